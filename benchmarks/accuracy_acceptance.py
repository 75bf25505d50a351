"""Acceptance of the default configuration: the accuracy rule (issue 32, decision 1) on the thesis study.

Runs the thesis spec (Table 9.5 uncertainties, thesis seed, data sets 1-7) under the tight reference (full fidelity,
RK4 at 15.625 us) and under each candidate (the default; the previous default, RK4 at 62.5 us with the dynamic screw
axial) over the same sampled runs, analyses each campaign and judges each candidate (campaigns.bench.solver_accuracy,
campaigns.statistics.accuracy_rule). Prints every verdict statement and each configuration's mean wall time per run,
and writes campaign_accuracy.nc, campaign_accuracy.md (the table for docs/accuracy.md) and campaign_accuracy.png/.svg
into --out. Every line is stamped with the seconds since the start, so the stages' costs can be read off. Without
--quick it also prints the cost of one paired run (the reference and every candidate, from the runs' own wall times)
and what the full study (7 data sets x 200 runs) costs at that rate on --workers cores.

    python benchmarks/accuracy_acceptance.py --out out/accuracy_acceptance            # 7 x 200 runs per configuration
    python benchmarks/accuracy_acceptance.py --out out/accuracy_acceptance --resume   # continue after an interruption
    python benchmarks/accuracy_acceptance.py --out out/acceptance_16 --runs 16        # the cost at small n
    python benchmarks/accuracy_acceptance.py --quick   # ds2 and ds5, 3 runs of 1 s: the pipeline; "insufficient data"
"""

from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import time
from pathlib import Path

from machine import header

from app.studies.charts import campaign_accuracy_chart
from campaigns.bench.solver_accuracy import THESIS_SPEC, campaign_accuracy
from campaigns.statistics.accuracy_rule import MIN_PAIRED_RUNS

#: --quick: two data sets (one free nut, one preloaded), 1 s runs in which the screw moves one way only, so only the
#: Eq. 9.12 features are defined (the hysteresis needs both directions), and 3 runs (the fewest an sd ratio's
#: jackknife takes): far below the rule's 200, so every verdict must say "insufficient data".
QUICK_DATASETS = ("ds2", "ds5")
QUICK_FEATURES = ("backlash_feature", "backlash_feature_true")
QUICK_RUNS = 3
QUICK_DURATION = 1.0
#: The thesis study's data sets (ds1-ds7): what the full acceptance runs.
FULL_DATASETS = 7


def short_scenes(names, duration: float, directory: Path) -> dict[str, str]:
    """Scene files that shorten the named built-in scenes to ``duration`` (everything else inherited)."""
    directory.mkdir(parents=True, exist_ok=True)
    scenes = {}
    for name in names:
        path = directory / f"{name}_{duration:g}s.toml"
        path.write_text(f'base = "{name}"\nname = "{name}_{duration:g}s"\nduration = {duration}\n')
        scenes[name] = str(path)
    return scenes


def cpu_seconds() -> float:
    """CPU time of this process and of its waited-for children (the campaigns' worker processes) [s]."""
    return sum(resource.getrusage(who).ru_utime + resource.getrusage(who).ru_stime
               for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))


def print_cost(judged, runs: int, workers: int, elapsed: float) -> None:
    """The cost of one paired run and the full study's at that rate: the sum over configurations of the mean wall
    time of an ok run (each run holds one worker; on a loaded machine a worker gets less than a core, so this is an
    upper bound of the CPU), times 7 x 200 pairs over ``workers`` workers, plus the other stages as measured here
    (compile, cluster start, margins, assembly, analysis; the margins and the assembly grow with n, so this part is
    a lower bound)."""
    per_pair = float(judged.configuration_wall_time.sum())
    datasets = judged.sizes["dataset"]
    in_runs = per_pair * runs * datasets / workers
    full = per_pair * MIN_PAIRED_RUNS * FULL_DATASETS / workers
    fixed = max(elapsed - in_runs, 0.0)
    print(f"cost of one paired run ({judged.sizes['configuration']} configurations): {per_pair:.2f} worker-s "
          f"(mean run wall times at n = {runs}); runs here {in_runs:.0f} s of {elapsed:.0f} s on {workers} workers, "
          f"other stages {fixed:.0f} s")
    print(f"estimated full study ({FULL_DATASETS} data sets x {MIN_PAIRED_RUNS} runs): "
          f"{(full + fixed) / 60:.0f} min on {workers} workers ({per_pair * MIN_PAIRED_RUNS * FULL_DATASETS / 60:.0f} "
          f"worker-min of runs + {fixed / 60:.1f} min of other stages), at this machine's load")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out/accuracy_acceptance"))
    parser.add_argument("--runs", type=int, default=MIN_PAIRED_RUNS, help="runs per data set (the rule needs 200)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--resume", action="store_true", help="continue the campaigns of an interrupted study")
    parser.add_argument("--force", action="store_true", help="overwrite the study files of an earlier study in --out")
    parser.add_argument("--quick", action="store_true",
                        help=f"{', '.join(QUICK_DATASETS)}, {QUICK_RUNS} runs of {QUICK_DURATION:g} s into a temporary "
                             "directory (checks the pipeline; too few runs for any verdict)")
    args = parser.parse_args()
    if (args.out / "campaign_accuracy.nc").exists() and not (args.force or args.resume):
        sys.exit(f"{args.out} holds an earlier study: --resume to continue it, --force to overwrite its files")
    header("acceptance of the default: the accuracy rule against the tight reference", args.quick)
    options = {}
    if args.quick:
        args.out = Path(tempfile.mkdtemp(prefix="accuracy_acceptance_quick_"))
        options = {"datasets": QUICK_DATASETS, "features": QUICK_FEATURES,
                   "scenes": short_scenes(QUICK_DATASETS, QUICK_DURATION, args.out / "scenes")}
        args.runs = QUICK_RUNS
    start, cpu_start = time.perf_counter(), cpu_seconds()
    judged = campaign_accuracy(args.out, THESIS_SPEC, runs=args.runs, workers=args.workers, resume=args.resume,
                               progress=lambda line: print(f"[{time.perf_counter() - start:5.0f} s] {line}",
                                                           flush=True), **options)
    campaign_accuracy_chart(judged, args.out / "campaign_accuracy.png")
    for name in judged.configuration.values:
        row = judged.sel(configuration=name)
        print(f"{name}: {row.configuration_solvers.item()}; mean wall time per ok run "
              f"{float(row.configuration_wall_time):.3f} s (results.nc wall_time, this machine's load)")
    elapsed = time.perf_counter() - start
    print(f"wrote {args.out / 'campaign_accuracy.nc'}, campaign_accuracy.md, campaign_accuracy.png/.svg "
          f"({elapsed:.0f} s in all, {cpu_seconds() - cpu_start:.0f} s CPU of this process and its workers)")
    if args.quick:
        print(f"no cost estimate in --quick ({QUICK_DURATION:g} s runs): run with --runs 16 for it")
    else:
        print_cost(judged, args.runs, args.workers, elapsed)


if __name__ == "__main__":
    main()
