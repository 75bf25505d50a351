"""Campaign throughput: runs/s, scheduling overhead, 1 -> 2 worker scaling, driver peak memory.

Usage::

    python benchmarks/campaign_throughput.py --synthetic --runs 200 --delay 0.005
    python benchmarks/campaign_throughput.py --runs 10          # the real bench (demo spec)
    python benchmarks/campaign_throughput.py --quick            # synthetic model, 10 runs per data set
    python benchmarks/campaign_throughput.py --thesis 60        # the thesis study end to end, 7 x 60 runs
    python benchmarks/campaign_throughput.py --thesis 60 --configuration default previous   # both, in turn
    python benchmarks/campaign_throughput.py --stages results.nc --resample 1000   # fixed stages, before and after

``--thesis N`` times the thesis spec (campaigns/specs/thesis_backlash.toml, N runs per data set) end to
end on a fresh local cluster of 2 workers, stage by stage (compilation check, cluster start, runs with
storage, the loop margins of every run on the cluster, the assembly of results.nc, the fidelity audit on
the same cluster, the analysis), and prints runs/s over the whole and the estimate for the full 7 x 1000
study (the runs, margins and assembly stages scaled to 7000 runs, the other stages as measured: the audit
re-runs the same 10 runs per data set whatever N). The runs stage includes each worker's sandbox start-up (a few
seconds), so a small N overestimates the full study.

``--stages RESULTS`` times the stages after the runs that read only ``results.nc`` (:data:`FIXED_STAGES`: the analysis,
then the report from it) on that file, with this tree's code and with the code of ``--before`` (a git revision,
default :data:`BEFORE`, exported with ``git archive``), each in a fresh process, and says whether both wrote the same
``analysis.nc``. ``--resample N``
first grows the file to N runs per data set without running the bench (:func:`resampled_results`), so a small
real campaign (e.g. ``--thesis 3``'s) gives a results file of the 7 x 1000 study's shape. ``--thesis N`` does the
same on the results it produced.

For each worker count a local cluster is started first and warmed up (worker
and sandbox start-up are not campaign throughput); the campaign then runs on it
through ``scheduler=``. Figures:

* runs/s: all runs / campaign wall time;
* scheduling overhead: ``1 - sum(run wall times) / (workers x campaign wall time)``,
  i.e. the share of worker time not spent inside run functions (dask round trips,
  sandbox pipes, the driver's chunk writes, load imbalance at the tail);
* driver peak memory: Python allocations traced by :mod:`tracemalloc` during a
  second, untimed pass of the campaign (tracing slows the driver), and the
  process's peak resident set size (it includes the local scheduler).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np
import xarray as xr
from distributed import LocalCluster
from machine import header

import campaigns
from campaigns.bench.adapter import BenchCatalog
from campaigns.runner.files import cf_encoding
from campaigns.runner.sampling import sample
from campaigns.runner.spec import validate_spec
from campaigns.runner.synthetic import SYNTHETIC_CATALOG, SyntheticModel

SPECS = Path(campaigns.__file__).parent / "specs"
ROOT = Path(__file__).resolve().parents[1]
#: The code the fixed stages are compared with: main before session 13's stage-cost work (issue 42, item 7; session
#: 12's started from dbe49a67e27e, docs/performance.md).
BEFORE = "d386b80532f9b8715f37a4b12b12c07676a6ce6a"

SYNTHETIC_SPEC = """
name = "throughput"
root_seed = 1
runs_per_dataset = {runs}
features = ["backlash_feature", "backlash_feature_true"]
[execution]
timeout = 60.0
{datasets}
[[uncertainties]]
target = "synthetic.gain"
distribution = "gaussian"
relative = true
half_range = 10.0
[[uncertainties]]
target = "synthetic.offset"
distribution = "uniform"
low = -1.0
high = 1.0
unit = "um"
[[uncertainties]]
target = "scene.room_temperature"
distribution = "uniform"
low = 15.0
high = 35.0
unit = "degC"
"""


def _spec(args, tmp: Path, runs: int) -> campaigns.CampaignSpec:
    if not args.synthetic:
        return campaigns.load_spec(SPECS / "demo.toml", runs=runs)
    datasets = "".join(
        f'[[datasets]]\nname = "ds{k}"\nconditions = {{ backlash = {b}, preload = 0.0 }}\n'
        for k, b in enumerate((0.0, 5e-6, 40e-6, 80e-6), start=1)
    )
    path = tmp / f"spec-{runs}.toml"
    path.write_text(SYNTHETIC_SPEC.format(runs=runs, datasets=datasets))
    return campaigns.load_spec(path, catalog=SYNTHETIC_CATALOG)


def measure(args, workers: int, tmp: Path) -> dict:
    """Run the campaign on a warmed-up local cluster of ``workers`` processes."""
    run_function = SyntheticModel(delay=args.delay) if args.synthetic else None
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        address = cluster.scheduler_address
        warm = _spec(args, tmp, workers)  # one run per worker thread starts every sandbox
        campaigns.run_campaign(warm, tmp / f"warm-{workers}", scheduler=address, progress=False,
                               run_function=run_function)
        spec = _spec(args, tmp, args.runs)
        start = time.perf_counter()
        results = campaigns.run_campaign(spec, tmp / f"run-{workers}", scheduler=address, progress=False,
                                         run_function=run_function)
        elapsed = time.perf_counter() - start
        # tracing slows the driver, so memory is measured on a second, untimed pass
        tracemalloc.start()
        campaigns.run_campaign(spec, tmp / f"memory-{workers}", scheduler=address, progress=False,
                               run_function=run_function)
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    with xr.open_dataset(results) as ds:
        n = ds.sizes["dataset"] * ds.sizes["run"]
        compute = float(ds["wall_time"].sum())
        ok = int((ds["status"] == "ok").sum())
    return {
        "workers": workers,
        "runs": n,
        "ok": ok,
        "elapsed": elapsed,
        "runs_per_s": n / elapsed,
        "mean_run_s": compute / n,
        "overhead_pct": 100.0 * (1.0 - compute / (workers * elapsed)),
        "traced_peak_mb": peak / 2**20,
    }


#: The fixed stages :func:`fixed_stages` times, in the order a campaign runs them after its runs.
FIXED_STAGES = ("analysis", "report")
THESIS_TARGET = 25.0  # runs/s end to end on 2 workers (issue 32)
#: Solver settings of the configurations timed: the default (the lane engine at its own choice of level and step)
#: and the previous default (RK4 at 62.5 us with the screw's axial mass), on the same engine.
CONFIGURATIONS = {"default": {}, "previous": {"dt": 6.25e-5, "fidelity": {"screw_axial": "dynamic"}}}


def thesis_end_to_end(runs: int, workers: int, tmp: Path, configuration: str = "default",
                      before: str | None = None, stages=FIXED_STAGES) -> None:
    """Run the thesis spec with ``runs`` runs per data set in one of :data:`CONFIGURATIONS`, end to end, and print
    the stages and the rates; with ``before``, the fixed stages on its results before and after
    (:func:`fixed_stages`)."""
    spec = campaigns.load_spec(SPECS / "thesis_backlash.toml", runs=runs)
    if CONFIGURATIONS[configuration]:
        spec = spec.model_copy(update={"solver": spec.solver.model_copy(update=CONFIGURATIONS[configuration])})
    marks: list[tuple[str, float]] = []
    start = time.perf_counter()
    results = campaigns.run_campaign(spec, tmp / "thesis", workers=workers, progress=False,
                                     announce=lambda stage, message: marks.append((stage, time.perf_counter())))
    marks.append(("analysis", time.perf_counter()))
    campaigns.analyze(results)
    end = time.perf_counter()
    marks.append(("end", end))
    # the stages the audit announces after its own (its runs, on the same cluster) are counted under "fidelity audit: "
    stages = {"start-up before the first stage": marks[0][1] - start}
    prefix = ""
    for k, (stage, at) in enumerate(marks[:-1]):
        if stage == "fidelity audit":
            prefix = "fidelity audit: "
        name = stage if stage in ("fidelity audit", "analysis") else prefix + stage
        stages[name] = stages.get(name, 0.0) + marks[k + 1][1] - at
    n = runs * len(spec.datasets)
    with xr.open_dataset(results) as ds:
        ok = int((ds["status"] == "ok").sum())
        compute = float(ds["wall_time"].sum())
        audit = ds.attrs.get("fidelity_audit", "not run")
        methods, counts = np.unique(ds["integrator"].values.astype(str), return_counts=True)
    solved_by = ", ".join(f"{m}: {c}" for m, c in zip(methods, counts, strict=True))
    total = end - start
    print(f"thesis spec, {len(spec.datasets)} x {runs} = {n} runs ({ok} ok) on {workers} workers, {configuration} "
          f"configuration (runs solved by {solved_by}), end to end {total:.1f} s:")
    for stage, seconds in stages.items():
        print(f"  {stage:32s} {seconds:8.1f} s  {100 * seconds / total:5.1f} %")
    print(f"  mean run {1e3 * compute / n:.0f} ms wall inside the workers; fidelity audit: {audit}")
    rate = n / total
    verdict = "met" if rate >= THESIS_TARGET else "not met"
    print(f"end to end: {rate:.2f} runs/s; target >= {THESIS_TARGET:g} runs/s: {verdict}")
    # the stages whose work grows with the number of runs; the audit's runs, start-up and the analysis do not
    per_run_stages = sum(stages.get(stage, 0.0) for stage in ("runs", "margins", "assembly"))
    full = 7 * 1000
    estimate = total - per_run_stages + per_run_stages * full / n
    print(f"estimate for 7 x 1000: {estimate / 60:.1f} min ({full / estimate:.2f} runs/s; the runs, margins and "
          "assembly stages scaled, the other stages as measured)")
    if before:
        fixed_stages(results, before, tmp, stages)


def resampled_results(path: Path, runs: int, out: Path) -> Path:
    """A results file of ``runs`` runs per data set grown from a small real one at ``path``, without running the
    bench: the sampled values drawn by the campaign's own sampling (its stored spec at ``runs`` runs, against the
    bench's catalog), every other
    per-run variable (status, features, margins, times) drawn with replacement from the real runs of its data set,
    the features jittered by 0.3 of their spread so that resampled runs do not tie. What the fixed stages cost
    depends on the shape (data sets, runs, sampled values, features, margins), not on the physics in the numbers;
    the numbers are not a campaign's."""
    with xr.open_dataset(path) as real:
        real = real.load()
    stored = json.loads(real.attrs["spec_json"])
    stored["spec"]["runs_per_dataset"] = runs
    base = stored["spec"]["base"]
    spec = validate_spec(stored["spec"], BenchCatalog(base["parameters"], base["scene"]))
    targets = [d.target for d in spec.distributions()]
    drawn = sample(spec)
    rng = np.random.default_rng(1)
    pick = rng.integers(0, real.sizes["run"], (real.sizes["dataset"], runs))
    variables = {}
    for name, variable in real.data_vars.items():
        if variable.dims != ("dataset", "run"):
            variables[name] = variable
            continue
        if name in targets:
            values = drawn[:, :, targets.index(name)]
        else:
            values = np.take_along_axis(variable.values, pick, axis=1)
            if variable.attrs.get("role") == "feature":
                values = values + 0.3 * (np.nanstd(variable.values) + 1e-7) * rng.standard_normal(values.shape)
        variables[name] = xr.DataArray(values, dims=variable.dims, attrs=variable.attrs)
    coords = {name: real[name] for name in real.coords if name != "run"}
    coords["run"] = ("run", np.arange(runs, dtype=np.int32), real["run"].attrs)
    grown = xr.Dataset(variables, coords=coords, attrs={**real.attrs, "spec_json": json.dumps(stored)})
    grown.to_netcdf(out, engine="netcdf4", encoding=cf_encoding(grown))
    return out


#: What a fresh process runs to time one fixed stage (argv 1: the stage, 2: results.nc, 3: analysis.nc, 4: the
#: report's folder): the analysis writes ``analysis.nc``, the report reads it (HTML and PDF at a fixed timestamp).
#: Prints the wall and CPU seconds (every thread's).
_TIME_STAGE = """
import sys, time
start, cpu = time.perf_counter(), time.process_time()
stage, results, analysis, report = sys.argv[1:5]
if stage == "analysis":
    from campaigns.analysis.campaign_analysis import analyze
    analyze(results, analysis)
else:
    from datetime import UTC, datetime
    import reports
    reports.build_report(results, analysis, report, generated_at=datetime(2026, 1, 1, tzinfo=UTC))
print(time.perf_counter() - start, time.process_time() - cpu)
"""


def _timed_stage(stage: str, code: Path, results: Path, label: str, tmp: Path) -> tuple[float, float]:
    """Wall and CPU seconds of ``stage`` on ``results`` by the code under ``code``, in a fresh process (its imports
    and compiled-code loads included, as a campaign's stage has them); the files go to ``tmp`` under ``label``."""
    done = subprocess.run([sys.executable, "-c", _TIME_STAGE, stage, str(results), str(tmp / f"analysis-{label}.nc"),
                           str(tmp / f"report-{label}")], check=True, capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(code)}, cwd=code)
    wall, cpu = (float(v) for v in done.stdout.split()[-2:])
    return wall, cpu


def _same_analysis(a: Path, b: Path) -> bool:
    """Whether two ``analysis.nc`` files hold the same numbers and texts (the history attribute aside)."""
    with xr.open_dataset(a) as x, xr.open_dataset(b) as y:
        if set(x.variables) != set(y.variables):
            return False
        same = all(x[v].dtype == y[v].dtype and np.array_equal(x[v].values, y[v].values,
                                                               equal_nan=x[v].dtype.kind == "f")
                   for v in x.variables)
        return same and {k: v for k, v in x.attrs.items() if k != "history"} == \
            {k: v for k, v in y.attrs.items() if k != "history"}


def fixed_stages(results: Path, before: str, tmp: Path, stages=FIXED_STAGES) -> None:
    """Print each fixed stage's time on ``results`` with this tree's code and with the code at ``before``, their
    ratio, and whether both wrote the same ``analysis.nc`` (the refactors promise the same bits). Each tree's report
    reads its own analysis (whose history stamp, and so the report's list of input files, differ). The stages run one
    after the other, before and after alternately, each in a fresh process."""
    # the report reads the analysis each tree wrote: timing the report times the analysis too
    stages = [stage for stage in FIXED_STAGES if stage in stages or (stage == "analysis" and "report" in stages)]
    old = tmp / "before"
    old.mkdir()
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", before], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(old)], input=archive, check=True)
    with xr.open_dataset(results) as ds:
        shape = f"{ds.sizes['dataset']} x {ds.sizes['run']}"
    rows = {stage: {label: _timed_stage(stage, code, results, label, tmp)
                    for label, code in (("before", old), ("after", ROOT))} for stage in stages}
    print(f"fixed stages on {results.name} ({shape} runs); before: {before[:10]}, after: this tree; "
          "CPU: every thread's")
    print(f"  {'stage':12s} {'before':>20s} {'after':>20s} {'ratio':>7s}")
    for stage, row in rows.items():
        (wall_b, cpu_b), (wall_a, cpu_a) = row["before"], row["after"]
        print(f"  {stage:12s} {wall_b:7.1f} s ({cpu_b:5.1f} s CPU) {wall_a:7.1f} s ({cpu_a:5.1f} s CPU) "
              f"{wall_b / wall_a:6.2f}x")
    same = _same_analysis(tmp / "analysis-before.nc", tmp / "analysis-after.nc")
    print(f"  analysis.nc before and after: {'identical' if same else 'DIFFERENT (a refactor changed numbers)'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200, help="runs per data set (default 200)")
    parser.add_argument("--synthetic", action="store_true", help="use the synthetic model instead of the bench twin")
    parser.add_argument("--delay", type=float, default=0.005, help="synthetic compute time per run [s] (default 0.005)")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="worker counts to compare (default 1 2)")
    parser.add_argument("--quick", action="store_true", help="synthetic model, 10 runs per data set (seconds)")
    parser.add_argument("--thesis", type=int, metavar="N",
                        help="time the thesis spec end to end with N runs per data set")
    parser.add_argument("--configuration", nargs="+", default=["default"], choices=list(CONFIGURATIONS),
                        help="with --thesis: configurations to time one after the other (default: default)")
    parser.add_argument("--stages", type=Path, metavar="RESULTS",
                        help="time the fixed stages on this results.nc before and after (see --before)")
    parser.add_argument("--resample", type=int, metavar="N",
                        help="with --stages: grow the file to N runs per data set first (no bench runs)")
    parser.add_argument("--stage", nargs="+", choices=FIXED_STAGES, default=list(FIXED_STAGES),
                        help="with --stages or --thesis: the fixed stages to time (default: all; the report needs the "
                             "analysis, which is then timed too)")
    parser.add_argument("--before", default=BEFORE, help=f"git revision of the code compared (default {BEFORE[:10]})")
    args = parser.parse_args()
    header("campaign throughput", args.quick)
    if args.stages:
        with tempfile.TemporaryDirectory() as tmp:
            results = args.stages
            if args.resample:
                results = resampled_results(results, args.resample, Path(tmp) / "resampled.nc")
            fixed_stages(results, args.before, Path(tmp), args.stage)
        return
    if args.thesis:
        for configuration in args.configuration:
            with tempfile.TemporaryDirectory() as tmp:
                thesis_end_to_end(args.thesis, max(args.workers), Path(tmp), configuration, args.before,
                                  args.stage)
        return
    if args.quick:
        args.synthetic, args.runs = True, 10
    model = f"synthetic (delay {args.delay:g} s)" if args.synthetic else "bench twin (demo spec)"
    print(f"model: {model}; runs per data set: {args.runs}")
    with tempfile.TemporaryDirectory() as tmp:
        rows = [measure(args, w, Path(tmp)) for w in args.workers]
    for r in rows:
        print(
            f"workers={r['workers']}: {r['runs']} runs ({r['ok']} ok) in {r['elapsed']:.2f} s -> "
            f"{r['runs_per_s']:.1f} runs/s; "
            f"mean run {1e3 * r['mean_run_s']:.2f} ms; scheduling overhead {r['overhead_pct']:.1f} %; "
            f"driver traced peak {r['traced_peak_mb']:.1f} MiB"
        )
    if len(rows) > 1:
        print(
            f"scaling {rows[0]['workers']} -> {rows[-1]['workers']} workers: "
            f"x{rows[-1]['runs_per_s'] / rows[0]['runs_per_s']:.2f}")
    print(f"driver peak RSS: {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")
    if args.synthetic and any(r["ok"] < r["runs"] for r in rows):
        # the synthetic model has no failure of its own: a failed run is a broken benchmark, not a figure
        raise SystemExit("campaign throughput: synthetic runs failed; the figures above measure failures")


if __name__ == "__main__":
    main()
