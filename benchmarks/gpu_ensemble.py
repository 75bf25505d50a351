"""The thesis study on the GPU beside the CPU lane engine, on the same host (issue 43).

Usage::

    python benchmarks/gpu_ensemble.py --runs 1000            # 7 x 1000 on the GPU, 7 x 16 on the CPU: runs/s of each
    python benchmarks/gpu_ensemble.py --runs 200 --cpu-runs 40
    python benchmarks/gpu_ensemble.py --quick                # CI: 7 x 2 runs of 4 ms, the GPU side under numba's
                                                             # CUDA simulator (seconds), compared bit for bit

Every run is the thesis campaign's (campaigns/specs/thesis_backlash.toml): its sampled parameters and conditions,
its noise streams (:func:`campaigns.runner.execution.build_request`), untraced (the features only), end to end
through :func:`twin.simulate_batch` (model building, instruments, the compiled loop, the features). The GPU takes
each data set's runs as one group (one thread per run, ``Solver(engine="cuda")``); the CPU lane engine takes them in
groups of :data:`twin.solver.DEFAULT_LANES` in this one process (one core: a campaign's workers scale it). Each
engine runs one short warm-up group first, so its compile (the CPU's numba cache, the GPU's NVVM and ptxas) is
timed apart from its runs.

Printed: per engine the runs, wall time, runs per second and the 7 x 1000 study's wall time at that rate; then the
agreement on the runs both solved: equal statuses, bit-identical features, and the largest difference of each
feature against the scene's numerical floor (campaigns/bench/numerical_floor.toml). The rule (docs/gpu.md): the
same bits while no libm function is reached (the thesis scenes' sinusoid starts at 0.5 s), within the floor after.

``--quick`` runs the GPU side in a child process under ``NUMBA_ENABLE_CUDASIM=1 NUMBA_DISABLE_JIT=1`` (the engine's
plain Python functions, ~10 ms per thread and step) and fails unless every feature and status is bit-identical: the
plumbing of the full path, not a speed (nothing here is a GPU timing unless a GPU ran it; the header says which).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from machine import header

import campaigns
import twin
from campaigns.bench.adapter import run_scene
from campaigns.bench.fidelity_audit import numerical_floors
from campaigns.runner.execution import build_request
from campaigns.runner.sampling import sample
from twin.engine.cuda import unavailable
from twin.solver import DEFAULT_LANES, split_solver

SPEC = Path(campaigns.__file__).parent / "specs" / "thesis_backlash.toml"
#: Runs per data set of the full thesis study (7 x 1000).
FULL_STUDY = 1000
#: ``--quick``: runs per data set and their duration [s] (32 RK4 steps at 125 us: seconds under the simulator).
QUICK_RUNS, QUICK_DURATION = 2, 0.004
#: Duration of the warm-up group that compiles each engine [s].
WARM_UP = 0.002


def thesis_requests(runs: int) -> tuple[campaigns.CampaignSpec, list[list]]:
    """The thesis spec with ``runs`` runs per data set, untraced, and its requests per data set."""
    spec = campaigns.load_spec(SPEC, runs=runs)
    spec = spec.model_copy(update={"traces": spec.traces.model_copy(update={"runs_per_dataset": 0})})
    samples = sample(spec)
    return spec, [[build_request(spec, samples, d, r) for r in range(runs)] for d in range(len(spec.datasets))]


def solve(requests: list[list], engine: str, duration: float | None) -> tuple[np.ndarray, np.ndarray, float]:
    """Every request on ``engine``: the features ``[data set, run, feature]``, the statuses and the wall time."""
    features, statuses = [], []
    start = time.perf_counter()
    for group in requests:
        first = requests[0][0] if not group else group[0]
        lanes = len(group) if engine == "cuda" else DEFAULT_LANES
        solver, options = split_solver({k: v for k, v in first.solver.items() if v is not None}
                                       | {"lanes": lanes, "engine": engine})
        params = twin.load_parameters(first.parameters)
        runs = [(run_scene(r), params.with_values(r.parameter_values), r.noise_rng()) for r in group]
        summaries = twin.simulate_batch(runs, solver=solver, duration=duration, outputs=list(first.outputs),
                                        throw=False, **options)
        features.append([[s.features[f] for f in first.features] for s in summaries])
        statuses.append([s.status for s in summaries])
    return np.array(features), np.array(statuses), time.perf_counter() - start


def measured(requests: list[list], engine: str, duration: float | None) -> dict:
    """:func:`solve` after a warm-up group of one run per data set (the compile, timed apart)."""
    start = time.perf_counter()
    solve([group[:1] for group in requests], engine, WARM_UP)
    compile_time = time.perf_counter() - start
    features, statuses, wall = solve(requests, engine, duration)
    return {"features": features, "statuses": statuses, "wall": wall, "compile": compile_time}


def _report(engine: str, result: dict, duration: float, scene_duration: float) -> None:
    """Runs per second and, for runs of the scenes' full length, the full study's wall time at that rate (a shorter
    run's fixed costs, model and instruments, would not scale with the simulated time)."""
    runs = result["features"].shape[0] * result["features"].shape[1]
    rate = runs / result["wall"]
    full = len(result["features"]) * FULL_STUDY
    study = (f"the {len(result['features'])} x {FULL_STUDY} study at this rate: {full / rate:.0f} s"
             if duration == scene_duration else f"runs shorter than the scenes' {scene_duration:g} s: no study figure")
    print(f"{engine}: {runs} runs of {duration:g} s in {result['wall']:.1f} s ({rate:.2f} runs/s; warm-up and compile "
          f"{result['compile']:.1f} s); {study}")


def _agreement(spec, cpu: dict, gpu: dict) -> bool:
    """Print how the engines agree on the runs both solved; True if every feature and status is bit-identical."""
    n = cpu["features"].shape[1]
    a, b = cpu["features"], gpu["features"][:, :n]
    same_status = cpu["statuses"] == gpu["statuses"][:, :n]
    identical = a.tobytes() == b.tobytes() and bool(same_status.all())
    print(f"agreement on {a.shape[0]} x {n} runs: statuses equal {int(same_status.sum())}/{same_status.size}, "
          f"features bit-identical {int((a.view(np.int64) == b.view(np.int64)).sum())}/{a.size}")
    floors = numerical_floors(spec, list(spec.features))
    for d, dataset in enumerate(spec.datasets):
        cells = []
        for f, feature in enumerate(spec.features):
            worst = float(np.nanmax(np.abs(a[d, :, f] - b[d, :, f]), initial=0.0))
            floor = floors.get((dataset.name, feature))
            cells.append(f"{feature} {worst:.2e}" + (f" ({worst / floor:.2f} floor)" if floor else ""))
        print(f"  {dataset.name}: largest |cpu - gpu| [m]: " + ", ".join(cells))
    return identical


def _child(args) -> None:
    """The GPU side of ``--quick`` (a process under the CUDA simulator): its results into ``args.child``."""
    import warnings

    warnings.simplefilter("ignore", RuntimeWarning)  # the plain Python engine divides as compiled: inf/nan
    _, requests = thesis_requests(args.runs)
    result = measured(requests, "cuda", args.duration)
    np.savez(args.child, **result)


def _simulated(args) -> dict:
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "cuda.npz"
        env = {**os.environ, "NUMBA_ENABLE_CUDASIM": "1", "NUMBA_DISABLE_JIT": "1"}
        subprocess.run([sys.executable, __file__, "--runs", str(args.runs), "--duration", str(args.duration),
                        "--child", str(out)], env=env, check=True)
        with np.load(out) as stored:
            return {name: stored[name] for name in stored.files} | {"compile": float(stored["compile"]),
                                                                    "wall": float(stored["wall"])}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100, help="runs per data set on the GPU (default 100)")
    parser.add_argument("--cpu-runs", type=int, default=16, help="runs per data set on the CPU (default 16)")
    parser.add_argument("--duration", type=float, help="simulated time of each run [s] (default: the scenes', 10 s)")
    parser.add_argument("--quick", action="store_true", help="CI: the GPU side under the CUDA simulator, short runs")
    parser.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child is not None:
        _child(args)
        return 0
    if args.quick:
        args.runs, args.cpu_runs, args.duration = QUICK_RUNS, QUICK_RUNS, QUICK_DURATION
    header("GPU ensemble: the thesis study on the CUDA engine beside the CPU lane engine", quick=args.quick)
    reason = "" if args.quick else unavailable()
    if reason:
        print(f"twin: error: engine 'cuda': {reason}", file=sys.stderr)
        return 2
    print("# GPU: numba's CUDA simulator (no GPU timing)" if args.quick else f"# GPU: {_device()}")
    spec, requests = thesis_requests(max(args.runs, args.cpu_runs))
    scene_duration = max(twin.load_scene(d.scene or spec.base.scene).duration for d in spec.datasets)
    duration = args.duration or scene_duration
    cpu = measured([group[:args.cpu_runs] for group in requests], "cpu", args.duration)
    _report("cpu (one process)", cpu, duration, scene_duration)
    gpu = _simulated(args) if args.quick else measured([group[:args.runs] for group in requests], "cuda",
                                                       args.duration)
    _report("cuda (simulator)" if args.quick else "cuda", gpu, duration, scene_duration)
    identical = _agreement(spec, cpu, gpu)
    if args.quick and not identical:
        print("twin: error: under the simulator the CUDA engine must give the CPU's bits", file=sys.stderr)
        return 1
    return 0


def _device() -> str:
    from numba import cuda

    device = cuda.get_current_device()
    free, total = cuda.current_context().get_memory_info()
    return (f"{device.name.decode() if isinstance(device.name, bytes) else device.name}, compute capability "
            f"{device.compute_capability}, {total / 2**30:.0f} GiB ({free / 2**30:.0f} free)")


if __name__ == "__main__":
    sys.exit(main())
