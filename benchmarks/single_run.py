"""One run: CPU time of the 10 s nominal scene, every solution path side by side, feature errors per data set.

Three tables, all measured in this one process (ratios hold on a loaded machine; absolute CPU seconds
do not, so the load average is printed with them):

1. the single-run target: the nominal scene at the default settings, CPU seconds (``time.process_time``,
   model build and result packaging included), median of ``--repeats`` runs after compilation;
2. the solution paths on the same scene: the default, the other compiled integrators, the scipy
   reference path and python-control's ``input_output_response`` (on the open-loop plant, the part of
   the model it can represent: ``app.studies.control_baseline``), as CPU per simulated second, the
   ratio to the default and the error of the Eq. 9.12 feature against a tight reference (RK4 at
   7.8125 us, converged to ~1e-4 um: docs/accuracy.md);
3. the Eq. 9.12 feature error of the default on every thesis data set (ds1-ds7, at the thesis
   campaign's fidelity) against the same reference, with the 0.1 um target.

Usage: python benchmarks/single_run.py [--repeats N] [--quick]
"""

from __future__ import annotations

import argparse
import statistics
import time

from machine import header

import twin
from twin.simulation import DEFAULT_DT, DEFAULT_INTEGRATOR

SINGLE_RUN_TARGET = 0.1        # s of CPU for the 10 s nominal scene (issue 16)
FEATURE_TARGET = 0.1e-6        # m: the feature within 0.1 um of the tight reference on every data set
REFERENCE = ("rk4", 7.8125e-6)  # tight reference (docs/accuracy.md: converged far below the target)
PATHS = ((DEFAULT_INTEGRATOR, DEFAULT_DT), ("imex_euler", 1.25e-4), ("rk4", 3.125e-5),
         ("semi_implicit_euler", 3.125e-5), ("rosenbrock_w2", 6.25e-5))
SCIPY_PATH = ("scipy_lsoda", 1e-8)  # the reference path at the tolerance that matches the default's accuracy
FEATURES = ("backlash_feature", "backlash_feature_true")
THESIS_DATASETS = ("ds1", "ds2", "ds3", "ds4", "ds5", "ds6", "ds7")
#: What a thesis-campaign run computes (campaigns/specs/thesis_backlash.toml): it sets the automatic fidelity.
THESIS_OUTPUTS = ["backlash_feature", "backlash_feature_true", "backlash_hysteresis", "backlash_hysteresis_true",
                  "position_demand", "nut1_position", "screw_equivalent_position", "linear_encoder_position",
                  "preload_force", "external_force"]


def cpu_run(scene, params, **options):
    """``(CPU seconds, Dataset)`` of one ``twin.simulate`` call."""
    start = time.process_time()
    ds = twin.simulate(scene, params, throw=False, **options)
    return time.process_time() - start, ds


def feature_errors(ds, reference) -> dict[str, float]:
    return {f: abs(float(ds[f]) - float(reference[f])) for f in FEATURES}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="1 s of the scene, 0.5 s per data set (seconds)")
    args = parser.parse_args()
    duration = 1.0 if args.quick else None
    dataset_duration = 0.5 if args.quick else None
    scipy_duration = 0.05 if args.quick else 0.25
    repeats = 1 if args.quick else args.repeats
    params = twin.load_parameters()
    scene = twin.load_scene("nominal")
    if duration:
        scene = scene.with_duration(duration)
    header("single run: CPU time of one scene after compilation; solution paths side by side", args.quick)

    for integrator, dt in (*PATHS, REFERENCE):  # compile (or load the cache) outside the timings
        twin.simulate(scene, params, integrator=integrator, dt=dt, duration=0.01)
    times = [cpu_run(scene, params)[0] for _ in range(repeats)]
    cpu = statistics.median(times)
    verdict = "met" if cpu <= SINGLE_RUN_TARGET * scene.duration / 10.0 else "not met"
    print(f"\n1. '{scene.name}' scene, {scene.duration:g} s, default {DEFAULT_INTEGRATOR} at {DEFAULT_DT * 1e6:g} us: "
          f"{cpu:.3f} s CPU (median of {repeats}; min {min(times):.3f}), {scene.duration / cpu:.0f}x real time; "
          f"target <= {SINGLE_RUN_TARGET * scene.duration / 10.0:g} s: {verdict}")

    print(f"\n2. solution paths on '{scene.name}' (CPU per simulated second; feature error against "
          f"{REFERENCE[0]} at {REFERENCE[1] * 1e6:g} us)")
    print(f"{'path':44s} {'CPU/sim s':>10s} {'x default':>10s} {'|err f_b| um':>13s} {'|err f_b,true| um':>18s}")
    _, reference = cpu_run(scene, params, integrator=REFERENCE[0], dt=REFERENCE[1])
    default_rate = None
    for integrator, dt in PATHS:
        cost, ds = cpu_run(scene, params, integrator=integrator, dt=dt)
        rate = cost / scene.duration
        default_rate = default_rate or rate
        errors = feature_errors(ds, reference) if ds.attrs["status"] == "ok" else {f: float("nan") for f in FEATURES}
        label = f"{integrator} {dt * 1e6:g} us" + (" (default)" if (integrator, dt) == PATHS[0] else "")
        print(f"{label:44s} {rate:10.4f} {rate / default_rate:10.2f} {errors[FEATURES[0]] * 1e6:13.5f} "
              f"{errors[FEATURES[1]] * 1e6:18.5f}")
    short = scene.with_duration(scipy_duration)
    cost, ds = cpu_run(short, params, integrator=SCIPY_PATH[0], rtol=SCIPY_PATH[1])
    _, short_reference = cpu_run(short, params, integrator=REFERENCE[0], dt=REFERENCE[1])
    errors = feature_errors(ds, short_reference)
    print(f"{f'{SCIPY_PATH[0]} rtol {SCIPY_PATH[1]:g} ({scipy_duration:g} s simulated)':44s} "
          f"{cost / scipy_duration:10.4f} {cost / scipy_duration / default_rate:10.2f} "
          f"{errors[FEATURES[0]] * 1e6:13.5f} {errors[FEATURES[1]] * 1e6:18.5f}")
    # lazy: python-control costs start-up time; only this baseline needs it
    from app.studies.control_baseline import DURATION, compare

    rows = compare()
    compiled = next(r for r in rows if r["method"].startswith("compiled rk4"))
    print(f"python-control on the open-loop plant ({DURATION:g} s current step; wall time, the same problem solved by "
          "each; error = max |nut position error|):")
    for row in rows:
        print(f"  {row['method']:52s} {row['wall_time']:9.4f} s  x{row['wall_time'] / compiled['wall_time']:8.1f} "
              f"vs compiled rk4; error {row['error'] * 1e6:.2e} um")

    print(f"\n3. Eq. 9.12 feature error of the default per thesis data set (thesis campaign fidelity"
          f"{f', {dataset_duration:g} s' if dataset_duration else ', 10 s'}) against {REFERENCE[0]} at "
          f"{REFERENCE[1] * 1e6:g} us; target < {FEATURE_TARGET * 1e6:g} um")
    print(f"{'data set':9s} {'CPU [s]':>8s} {'f_b [um]':>10s} {'|err f_b| um':>13s} {'|err f_b,true| um':>18s}")
    worst = 0.0
    for name in THESIS_DATASETS:
        options = {"outputs": THESIS_OUTPUTS, "duration": dataset_duration}
        cost, ds = cpu_run(name, params, **options)
        _, ref = cpu_run(name, params, integrator=REFERENCE[0], dt=REFERENCE[1], **options)
        errors = feature_errors(ds, ref)
        worst = max(worst, *errors.values())
        print(f"{name:9s} {cost:8.3f} {float(ds[FEATURES[0]]) * 1e6:10.4f} {errors[FEATURES[0]] * 1e6:13.5f} "
              f"{errors[FEATURES[1]] * 1e6:18.5f}")
    print(f"largest feature error {worst * 1e6:.4f} um: target {'met' if worst < FEATURE_TARGET else 'not met'}")


if __name__ == "__main__":
    main()
