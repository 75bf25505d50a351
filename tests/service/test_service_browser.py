"""The web page in a real browser: Playwright drives the system's headless Chromium (never its own download)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from service_helpers import CAMPAIGN_BUDGET, SPEC, wait_until

playwright = pytest.importorskip("playwright.sync_api")
CHROMIUM = Path("/usr/bin/chromium") if Path("/usr/bin/chromium").exists() else shutil.which("chromium")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="Chromium not found (/usr/bin/chromium; CI installs "
                                                         "Debian's chromium package)")


def not_blank(png: Path) -> tuple[float, int]:
    """Grey-level standard deviation and number of distinct colours of a screenshot."""
    import matplotlib.image

    pixels = matplotlib.image.imread(png)[..., :3]
    colours = len(np.unique((pixels * 255).astype(np.uint8).reshape(-1, 3), axis=0))
    return float(pixels.mean(axis=2).std()), colours


def accessible(page) -> None:
    """axe-core finds no serious or critical violation on the page (issue 31)."""
    from axe_check import serious_violations

    violations = serious_violations(page)
    assert not violations, f"{page.url}:\n" + "\n".join(violations)


def _evaluate(page, script: str):
    """``script``'s value in the page, or ``None`` while the page is between two documents (it reloads when done)."""
    try:
        return page.evaluate(script)
    except playwright.Error:
        return None


def test_submit_through_the_form_watch_the_bar_open_the_report(service, tmp_path):
    budget_ms = CAMPAIGN_BUDGET * 1000
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=str(CHROMIUM), args=["--no-sandbox", "--disable-gpu"])
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        page.set_default_timeout(120_000)
        page.goto(f"{service.url}/")
        assert "/login" in page.url
        accessible(page)
        page.fill("#token", "bt_wrong")
        page.click("button[type=submit]")
        assert "unknown or revoked token" in page.inner_text("#login-error")
        accessible(page)
        page.fill("#token", service.tokens["submitter"])
        page.click("button[type=submit]")
        page.wait_for_url(f"{service.url}/")
        accessible(page)

        # a broken spec: the errors appear beside it, nothing is queued
        page.goto(f"{service.url}/submit")
        page.fill("#spec", SPEC.read_text().replace("runs_per_dataset = 2", "runs_per_dataset = -1"))
        page.click(".overrides button[type=submit]")
        assert "runs_per_dataset" in page.inner_text("#errors")
        accessible(page)
        page.screenshot(path=str(tmp_path / "submit-errors.png"), full_page=True)

        page.fill("#spec", SPEC.read_text())
        page.fill("input[name=runs]", "2")
        page.click(".overrides button[type=submit]")
        page.wait_for_url("**/campaigns/*")
        full = "() => { const b = document.querySelector('#progress'); return !!b && b.max > 0 && b.value === b.max; }"
        wait_until(lambda: _evaluate(page, full), what="a full progress bar")
        assert "(100.0 %)" in page.inner_text("[data-field=runs]")
        page.wait_for_selector("#report-link", timeout=budget_ms)  # the page reloads when the campaign is done
        assert page.inner_text("[data-field=state]") == "done"
        assert page.locator("#verdicts li").count() == 4  # one verdict line per feature of the spec
        # the report's page-1 figure, loaded by the browser as the page's own image (the login cookie, img-src 'self')
        drawn = ("() => { const i = document.querySelector('#answer img'); "
                 "return !!i && i.complete && i.naturalWidth > 0; }")
        wait_until(lambda: _evaluate(page, drawn), what="the page-1 figure drawn on the campaign page")
        accessible(page)
        page.screenshot(path=str(tmp_path / "campaign.png"), full_page=True)
        campaign_page = page.url
        page.goto(f"{service.url}/")  # the list with a finished campaign in it
        accessible(page)
        page.goto(f"{service.url}/campaigns/no-such-campaign")  # the message page
        accessible(page)
        page.goto(campaign_page)
        page.click("#report-link")
        page.wait_for_load_state("load")
        assert page.url.endswith("/files/report.html")
        shot = tmp_path / "report.png"
        page.screenshot(path=str(shot))
        browser.close()
    spread, colours = not_blank(shot)
    assert spread > 0.02 and colours > 50, f"the report screenshot looks blank (std {spread:.4f}, {colours} colours)"
