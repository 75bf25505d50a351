"""Section "Failed runs": every run that did not finish, with its reason."""

from __future__ import annotations

import json

import numpy as np

from campaigns.runner.runs import STATUS_MEANINGS
from reports.builder import LISTED_RUNS, Builder
from reports.model import Callout


def status_meanings(attrs) -> dict[str, str]:
    """What each status means, as the results file states it: ``comment`` (one ``"status: meaning"`` per line), or a
    JSON ``flag_meanings`` in files written before the CF flag variable ``status_flag``; else the runner's own."""
    try:
        return json.loads(attrs["flag_meanings"])
    except (KeyError, TypeError, ValueError):
        pass
    meanings = dict(STATUS_MEANINGS)
    for item in str(attrs.get("comment", "")).splitlines():
        key, sep, text = item.partition(": ")
        if sep and key in meanings:
            meanings[key] = text
    return meanings


def build(b: Builder):
    results = b.results
    status = results["status"].values
    failed = np.argwhere(status != "ok")
    if len(failed) == 0:
        yield Callout("Every run succeeded: no failed runs.", "good")
        return
    yield Callout(f"{len(failed)} of {status.size} runs failed. They are left out of every statistic above.", "bad")
    groups: dict[tuple[str, str, str], list[int]] = {}
    for d, r in failed:
        key = (b.datasets[d], str(status[d, r]), str(results["failure_reason"].values[d, r]))
        groups.setdefault(key, []).append(int(results["run"].values[r]))
    rows = []
    for (name, st, reason), runs in groups.items():
        listed = (", ".join(map(str, runs[:LISTED_RUNS]))
                  + (f" and {len(runs) - LISTED_RUNS} more" if len(runs) > LISTED_RUNS else ""))
        rows.append((name, st, str(len(runs)), listed, reason or "–"))
    yield b.table("Failed runs grouped by data set, status and reason (run indices within the data set).",
                  ("Data set", "Status", "Count", "Runs", "Reason"), rows)
    meanings = status_meanings(results["status"].attrs)
    present = sorted({str(s) for s in status.ravel()} - {"ok"})
    yield b.table("What each status means.", ("Status", "Meaning"), [(s, meanings.get(s, "–")) for s in present])
