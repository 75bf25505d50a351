"""What a campaign will cost before it starts: runs, wall time, disk; the free-space check.

The estimate is printed by ``twin campaign run`` before anything runs, and the disk part is
checked against the free space of the output directory's file system
(:func:`shutil.disk_usage`): a campaign that cannot fit is refused before the cluster starts.

A run function may declare what a run costs through two optional attributes:
``typical_run_seconds`` (wall time of one run on one core) and ``trace_samples`` (samples of a
kept time series before decimation). Without them the wall time is not estimated and traces
are taken as :data:`DEFAULT_TRACE_SAMPLES` samples.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

from campaigns.spec import CampaignSpec
from campaigns.storage import CampaignError

#: Bytes stored per run besides the sampled values and features: status, failure reason, t_reached,
#: wall_time, fidelity (the strings as numpy unicode, a few tens of characters).
RUN_OVERHEAD_BYTES = 512
#: Copies of every number on disk: the chunk files and results.nc.
COPIES = 2
#: Samples of a kept time series when the run function does not say.
DEFAULT_TRACE_SAMPLES = 10_001
#: Free space the campaign must leave beyond its estimate (the estimate is rough; netCDF adds headers).
DISK_MARGIN = 1.5


@dataclass(frozen=True)
class Estimate:
    """The cost of the runs still to do.

    Attributes
    ----------
    runs : int
        Runs to execute.
    wall_seconds : float or None
        Wall time with ``workers`` busy workers; None when the run function gives no run time.
    disk_bytes : int
        Bytes the chunk files and results.nc will take.
    workers : int
        Workers the wall time assumes.
    """

    runs: int
    wall_seconds: float | None
    disk_bytes: int
    workers: int = 1

    def describe(self) -> str:
        """One line for the user, e.g. ``7000 run(s), about 70 min on 2 worker(s), about 13 MB on disk``."""
        wall = (f"about {_duration(self.wall_seconds)} on {self.workers} worker(s)" if self.wall_seconds is not None
                else "wall time unknown")
        return f"{self.runs} run(s), {wall}, about {_size(self.disk_bytes)} on disk"


def estimate(spec: CampaignSpec, run_function=None, *, workers: int = 2, runs: int | None = None) -> Estimate:
    """Estimate the cost of ``runs`` runs of ``spec`` (default: all of them)."""
    total = len(spec.datasets) * spec.runs_per_dataset
    runs = total if runs is None else runs
    per_run = 8 * (len(spec.uncertainties) + len(spec.features)) + RUN_OVERHEAD_BYTES
    traced = len(spec.datasets) * min(spec.traces.runs_per_dataset, spec.runs_per_dataset)
    samples = getattr(run_function, "trace_samples", DEFAULT_TRACE_SAMPLES) // spec.traces.decimation + 1
    trace_bytes = traced * len(spec.traces.variables) * samples * 8
    run_seconds = getattr(run_function, "typical_run_seconds", None)
    wall = run_seconds * runs / max(1, workers) if run_seconds is not None else None
    return Estimate(runs, wall, COPIES * (per_run * total + trace_bytes), max(1, workers))


def check_disk(out_dir: str | Path, cost: Estimate) -> None:
    """Refuse a campaign whose estimated size (with :data:`DISK_MARGIN`) exceeds the free space.

    Raises
    ------
    CampaignError
        Naming the directory, the free space and the need.
    """
    existing = Path(out_dir).absolute()
    while not existing.exists():
        existing = existing.parent
    free = shutil.disk_usage(existing).free
    need = int(cost.disk_bytes * DISK_MARGIN)
    if free < need:
        raise CampaignError(f"{out_dir}: not enough free disk space ({_size(free)} free on {existing}, the campaign "
                            f"needs about {_size(need)} including a {DISK_MARGIN:g}x margin); free space or choose "
                            "another output directory")


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def _size(n: float) -> str:
    for unit in ("B", "kB", "MB", "GB"):
        if n < 1000:
            return f"{n:.0f} {unit}"
        n /= 1000
    return f"{n:.1f} TB"
