"""Section "Failed runs": every run that did not finish, with its reason."""

from __future__ import annotations

import json

import numpy as np

from reports.builder import LISTED_RUNS, Builder
from reports.model import Callout


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
    meanings = json.loads(results["status"].attrs.get("flag_meanings", "{}") or "{}")
    present = sorted({str(s) for s in status.ravel()} - {"ok"})
    yield b.table("What each status means.", ("Status", "Meaning"), [(s, meanings.get(s, "–")) for s in present])
