"""What a campaign will cost before it starts: runs, wall time, disk; the free-space check.

The estimate is printed by ``twin campaign run`` before anything runs and again, for the runs still to do, as the
runs start (:mod:`campaigns.runner.execution`: one estimate, from this module), and the disk part is
checked against the free space of the output directory's file system
(:func:`shutil.disk_usage`): a campaign that cannot fit is refused before the cluster starts.

The run model (:class:`campaigns.runner.runs.RunModel`) says what a run costs: ``typical_run_seconds`` (the wall time
a worker spends per run of a campaign, at ``typical_step``: in the model's lane groups, with the per-run work around
them, so a spec's ``solver.dt`` scales the run time in proportion; None: the wall time is not estimated) and
``trace_samples`` (samples of a kept time series before decimation). A run
never costs more than its budget (``execution.timeout`` and the kill grace): the sandbox ends it there.

The disk estimate covers what a campaign writes, at its peak: the chunk files, ``results.nc`` twice (a
rewrite, e.g. the fidelity audit's attributes, writes a new copy beside the old one before replacing it), the
fidelity audit's own campaign, and ``analysis.nc``. The figures per run are measured on real files (docs/performance.md,
"The figures behind the campaign code's constants"); ``tests/campaigns/test_budget_analysis_variables.py`` checks the
count of ``analysis.nc``'s variables against what the analysis writes.
"""

from __future__ import annotations

import math
import shutil
from dataclasses import dataclass
from pathlib import Path

from campaigns.runner.files import size_text
from campaigns.runner.runs import RunModel, kill_grace
from campaigns.runner.spec import CampaignSpec
from campaigns.runner.storage import CampaignError

#: Bytes of one chunk file besides its runs: the zip and .npy headers of its ~15 arrays, the provenance (JSON as
#: 4-byte unicode) and the checksum. The measured sizes of this and the figures below: docs/performance.md, "The
#: figures behind the campaign code's constants"; each rounded up.
CHUNK_FILE_BYTES = 8_000
#: Bytes per run in a chunk file besides its numbers: status, failure reason, fidelity and integrator as
#: fixed-width 4-byte unicode (the bench's fidelity line is ~250 characters).
RUN_CHUNK_BYTES = 1_500
#: Bytes per run in results.nc besides its numbers: status, failure reason, integrator and loop-margin note as
#: variable-length strings (HDF5 heap entries), the status flag.
RUN_RESULTS_BYTES = 400
#: Bytes of a netCDF file besides its variables: the global attributes (the spec JSON, provenance, the fidelity
#: audit's statements) and the HDF5 superblock.
FILE_BYTES = 100_000
#: Bytes of HDF5 metadata per netCDF variable (headers, attributes, chunk index).
VARIABLE_BYTES = 7_000
#: Variables of results.nc besides the sampled values, features, margins, traces and conditions (status, its flag,
#: failure reason, integrator, t_reached, wall_time, the margin note, the coordinates).
RESULTS_VARIABLES = 12
#: Variables of analysis.nc of a spec with one fault sweep besides two per margin figure (quantiles, worst case): its
#: statistics, the sweep's verdicts and levels, the control-limit verdicts, the coordinates.
ANALYSIS_VARIABLES = 62
#: Variables each further fault sweep adds to analysis.nc (its verdicts, levels, feature mark and sweep coordinate:
#: ``campaigns.analysis.observability``).
SWEEP_VARIABLES = 13
#: Margin figures the bench stores per run (4 loops x 4 figures, ``campaigns.bench.adapter.margin_variables``): counted
#: for every run function, a few hundred bytes of slack for the others.
MARGIN_FIGURES = 16
#: Free space the campaign must leave beyond its estimate (the estimate is an upper bound of the measured sizes,
#: this covers what it cannot see: the file system's blocks, the report, other writers on the same disk).
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
        Bytes the campaign's files take at their peak (chunks, results.nc and its rewrite, the fidelity
        audit, analysis.nc).
    workers : int
        Workers the wall time assumes.
    run_seconds : float or None
        Wall time of one run (the run function's typical time, scaled by the spec's step, at most its budget).
    """

    runs: int
    wall_seconds: float | None
    disk_bytes: int
    workers: int = 1
    run_seconds: float | None = None

    def duration(self) -> str:
        """The wall time in words, e.g. ``about 70 min on 2 worker(s)``."""
        return (f"about {_duration(self.wall_seconds)} on {self.workers} worker(s)" if self.wall_seconds is not None
                else "wall time unknown")

    def describe(self) -> str:
        """One line for the user, e.g. ``7000 run(s), about 70 min on 2 worker(s), about 13 MB on disk``."""
        return f"{self.runs} run(s), {self.duration()}, about {_size(self.disk_bytes)} on disk"


def run_seconds(spec: CampaignSpec, run_function: RunModel) -> float | None:
    """Wall time of one run of ``spec`` (see the module docstring), or None when the run model gives none."""
    typical = run_function.typical_run_seconds
    if typical is None:
        return None
    if spec.solver.dt is not None and run_function.typical_step is not None:
        typical *= run_function.typical_step / spec.solver.dt
    return min(typical, spec.execution.timeout + kill_grace(spec.execution.timeout))


def _campaign_bytes(spec: CampaignSpec, runs_per_dataset: int, trace_samples: int,
                    traces: bool = True) -> tuple[int, int]:
    """Bytes of one campaign's chunk files and of its results.nc, at ``runs_per_dataset``."""
    total = len(spec.datasets) * runs_per_dataset
    numbers = 8 * (len(spec.uncertainties) + len(spec.features) + MARGIN_FIGURES + 4)
    # the bench's runs take ~1 s: the adaptive chunking gives one run per chunk, the worst case
    chunks = (total if spec.execution.chunk_size is None
              else len(spec.datasets) * math.ceil(runs_per_dataset / spec.execution.chunk_size))
    traced = len(spec.datasets) * min(spec.traces.runs_per_dataset, runs_per_dataset) if traces else 0
    trace_bytes = traced * len(spec.traces.variables) * (trace_samples // spec.traces.decimation + 1) * 8
    chunk_files = chunks * CHUNK_FILE_BYTES + total * (numbers + RUN_CHUNK_BYTES) + trace_bytes
    variables = (len(spec.uncertainties) + len(spec.features) + MARGIN_FIGURES + RESULTS_VARIABLES
                 + len(spec.traces.variables) + len(spec.condition_units()))
    results = FILE_BYTES + 2 * len(spec.to_json()) + variables * VARIABLE_BYTES + total * (numbers + RUN_RESULTS_BYTES)
    return chunk_files + 2 * len(spec.to_json()), results + trace_bytes  # spec.json (indented) beside the chunks


def analysis_variables(spec: CampaignSpec) -> int:
    """The netCDF variables of the spec's ``analysis.nc``: the statistics and a sweep's, two per margin figure, and
    those of each further fault sweep."""
    return ANALYSIS_VARIABLES + 2 * MARGIN_FIGURES + SWEEP_VARIABLES * len(spec.further_sweeps)


def estimate(spec: CampaignSpec, run_function: RunModel, *, workers: int = 2, runs: int | None = None) -> Estimate:
    """Estimate the cost of ``runs`` runs of ``spec`` (default: all of them)."""
    total = len(spec.datasets) * spec.runs_per_dataset
    runs = total if runs is None else runs
    samples = run_function.trace_samples
    chunks, results = _campaign_bytes(spec, spec.runs_per_dataset, samples)
    audit_runs = min(spec.fidelity_audit.runs, spec.runs_per_dataset)
    audit = sum(_campaign_bytes(spec, audit_runs, samples, traces=False)) + FILE_BYTES if audit_runs >= 2 else 0
    analysis = (FILE_BYTES + analysis_variables(spec) * VARIABLE_BYTES
                + total * RUN_RESULTS_BYTES)  # the statistics, the per-run margin verdicts and their texts
    per_run = run_seconds(spec, run_function)
    wall = per_run * runs / max(1, workers) if per_run is not None else None
    # results.nc twice: a rewrite (the fidelity audit's attributes) writes the new copy before replacing the old
    return Estimate(runs, wall, chunks + 2 * results + audit + analysis, max(1, workers), per_run)


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
        raise CampaignError(f"{out_dir}: not enough free disk space ({_size(free)} free on {existing}; the campaign "
                            f"writes up to {_size(cost.disk_bytes)}, {_size(need)} with a {DISK_MARGIN:g}x margin); "
                            "free space or choose another output directory")


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def _size(n: float) -> str:
    return size_text(n)
