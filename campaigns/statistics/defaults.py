"""The settings every statistic of a campaign defaults to: one confidence for every interval and bound, and the
detection rule's false-alarm rate and power (docs/campaigns.md, Analysis); and the threads a resampling runs on."""

import os

#: Detection settings of the verdict: the threshold flags this fraction of the reference's runs ...
FALSE_ALARM_RATE = 0.05
#: ... and the minimum detectable level is where this fraction of a data set's runs is flagged.
POWER = 0.95
#: Confidence of the bootstrap bounds and of the order-statistic floor.
CONFIDENCE = 0.95


def threads() -> int:
    """Threads an estimator's resampling may run on: the cores this process may use. Every resample is computed
    alone whichever thread computes it, so the numbers do not depend on it."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
