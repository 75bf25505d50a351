"""The settings of a campaign's analysis (bootstrap size, confidence, detection rule, seed, run floors), checked once,
and the spawn-key tags that give each analysis its own random stream from the one seed."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

from campaigns.statistics.defaults import CONFIDENCE, FALSE_ALARM_RATE, POWER, threads
from campaigns.statistics.order_statistics import detection_run_floor

#: Ok runs a data set needs before any statistic of it is computed (``data_sufficient``). A floor against printing
#: noise, not a confidence statement: below 20 runs a rank correlation must exceed ±0.45 (1.96/sqrt(n - 1)) to be
#: told from independence, and the first-order index cannot be computed at all (it needs more than 2 x 10 harmonics
#: of runs). Every statistic above it carries its own interval. The detection threshold carries none: it has its
#: own floor, :data:`campaigns.statistics.order_statistics.MIN_DETECTION_RUNS` (docs/campaigns.md, Analysis).
MIN_OK_RUNS = 20
#: Spawn-key tag of the observability bootstrap's random stream (the correlation bootstraps use (dataset, feature)).
OBSERVABILITY_STREAM = 1_000_003
#: Spawn-key tag of the first-order index bootstrap's random stream.
SENSITIVITY_STREAM = 1_000_033
#: Spawn-key tag of the within-unit bootstrap's random stream (:mod:`campaigns.analysis.within_unit`).
WITHIN_UNIT_STREAM = 1_000_037
#: Spawn-key tag of the model-form study's paired bootstrap of the detection-probability shift
#: (:mod:`campaigns.analysis.model_form`).
MODEL_FORM_STREAM = 1_000_039


@dataclass(frozen=True)
class AnalysisSettings:
    """What every analysis of :func:`campaigns.analysis.campaign_analysis.analysis_dataset` takes besides the results.

    ``min_detection_runs`` defaults to :func:`campaigns.statistics.order_statistics.detection_run_floor` of the
    detection settings and is never below ``min_ok_runs`` (:attr:`detection_runs`); ``sensitivity_boot`` resamples
    give the interval of the first-order index.
    """

    n_boot: int = 1000
    confidence: float = CONFIDENCE
    false_alarm_rate: float = FALSE_ALARM_RATE
    power: float = POWER
    seed: int = 0
    min_ok_runs: int = MIN_OK_RUNS
    min_detection_runs: int | None = None
    sensitivity_boot: int = 200

    def __post_init__(self):
        if self.min_ok_runs < 3:
            raise ValueError(f"min_ok_runs = {self.min_ok_runs}: must be at least 3 (a standard deviation and a "
                             "correlation need 3 runs)")

    @property
    def detection_runs(self) -> int:
        """Ok runs a reference (and every sweep data set) needs before a detection probability is computed."""
        floor = self.min_detection_runs
        if floor is None:
            floor = detection_run_floor(self.false_alarm_rate, self.power, self.confidence)
        return max(floor, self.min_ok_runs)


def on_threads(work: Callable, tasks: Iterable) -> None:
    """``work(task)`` for every task, on as many threads as the process has cores
    (:func:`campaigns.statistics.defaults.threads`), the first error raised. For tasks that write disjoint cells of
    arrays and compute each cell alone: the bootstrap loops release the GIL, and a cell's numbers do not depend on
    the thread that computes it or on the order the tasks finish in."""
    tasks = list(tasks)
    count = max(1, min(threads(), len(tasks)))
    if count == 1:
        for task in tasks:
            work(task)
        return
    with ThreadPoolExecutor(count) as pool:
        for done in [pool.submit(work, task) for task in tasks]:
            done.result()
