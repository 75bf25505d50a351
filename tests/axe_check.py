"""Accessibility check of a page open in Playwright: axe-core's serious and critical violations.

axe-core comes from PyPI with ``axe-playwright-python`` (its ``axe.min.js`` is in the wheel: nothing is
downloaded at test time); the page is the system Chromium's, driven by Playwright. Used by the report's and the
service's browser tests.
"""

from __future__ import annotations

#: axe-core impacts that fail a test (the WCAG AA contrast rule is "serious").
FAILING = ("serious", "critical")


def serious_violations(page) -> list[str]:
    """One line per serious or critical axe-core violation of ``page`` (empty: none), with the offending nodes."""
    from axe_playwright_python.sync_playwright import Axe

    results = Axe().run(page)
    return [f"{v['id']} ({v['impact']}): {v['help']}: {[n['target'] for n in v['nodes']][:5]}"
            for v in results.response["violations"] if v.get("impact") in FAILING]
