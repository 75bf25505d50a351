"""Speed against accuracy at the default configuration (issue: speed versus accuracy).

Prints, for the nominal and data-set-2 scenes (10 s): the default configuration's wall time on one
core (median after compilation; ``twin.simulate``, one lane with its recorded signals), the scipy reference
path's wall time and the feature difference between them (timed side by side in this run), the python-control
baseline on the open-loop plant, and the estimated wall time of the thesis study (7 x 1000 runs) on this
machine's cores from a lane group of thesis runs (``twin.simulate_batch``, as a campaign runs them).
Usage: python benchmarks/speed_accuracy.py [--reference-duration 2.0] [--quick]
"""

import argparse
import os
import statistics
import time

from machine import header
from single_run import THESIS_DATASETS, THESIS_OUTPUTS

import twin
from app.studies.control_baseline import compare
from twin.fidelity import full_plant
from twin.solver import DEFAULT_DT, DEFAULT_LANES, DEFAULT_SOLVER


def median_wall(scene, repeats=5, **options):
    twin.simulate(scene, duration=0.01, **options)
    times, ds = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        ds = twin.simulate(scene, **options)
        times.append(time.perf_counter() - start)
    return statistics.median(times), ds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--reference-duration", type=float, default=2.0,
                        help="simulated seconds of the side-by-side comparison with the scipy path")
    parser.add_argument("--quick", action="store_true", help="1 s scenes, 0.2 s reference comparison, one repeat")
    args = parser.parse_args()
    repeats = 1 if args.quick else 5
    if args.quick:
        args.reference_duration = 0.2
    header("speed against accuracy at the default configuration", args.quick)
    drive_period = twin.load_parameters().value("drive.speed_loop_sample_time")
    print(f"# {os.cpu_count()} cores; default: {DEFAULT_SOLVER.integrator} at the {drive_period:g} s drive "
          f"period at the automatic fidelity (quasi-static screw axial, ideal current loop), "
          f"{DEFAULT_DT:g} s where a faster mode is modelled (twin.Solver.step)")
    for name in ("nominal", "ds2"):
        full_duration = twin.load_scene(name).duration
        scene = twin.load_scene(name).with_duration(1.0 if args.quick else full_duration)
        wall, ds = median_wall(scene, repeats)
        print(f"{name:8s} {scene.duration:4.1f} s scene: {wall:.3f} s per run "
              f"({scene.duration / wall:.0f}x real time, {ds.attrs['integrator']} at {ds.attrs['dt']:g} s), "
              f"f_b {float(ds.backlash_feature) * 1e6:.4f} um")
    for name in ("ds2", "nominal"):
        scene = twin.load_scene(name).with_duration(args.reference_duration)
        ideal = full_plant()  # the solvers are compared on the plant, seen through ideal instruments
        fast, ds_fast = median_wall(scene, repeats=min(3, repeats), fidelity=ideal)
        start = time.perf_counter()
        ds_ref = twin.simulate(scene, solver=twin.Solver("scipy_lsoda", rtol=1e-8), fidelity=ideal)
        slow = time.perf_counter() - start
        start = time.perf_counter()
        ds_radau = twin.simulate(scene, solver=twin.Solver("scipy_radau", rtol=1e-8), fidelity=ideal)
        radau = time.perf_counter() - start
        print(f"{name:8s} {args.reference_duration:.1f} s, ideal instruments: default {fast:.3f} s; "
              f"scipy LSODA rtol 1e-8 {slow:.2f} s ({slow / fast:.0f}x), Radau rtol 1e-8 {radau:.2f} s "
              f"({radau / fast:.0f}x); feature difference "
              f"{abs(float(ds_fast.backlash_feature - ds_ref.backlash_feature)) * 1e6:.2e} um (LSODA), "
              f"{abs(float(ds_fast.backlash_feature - ds_radau.backlash_feature)) * 1e6:.2e} um (Radau)")
    for row in compare():
        print(
            f"open-loop plant 0.05 s: {row['method']:50s} {row['wall_time']:.4f} s, max nut error {row['error']:.2e} m")
    # the thesis runs as a campaign runs them: a lane group per data set, the thesis outputs (automatic fidelity)
    lanes, duration = DEFAULT_LANES, 1.0 if args.quick else None
    walls = []
    for name in THESIS_DATASETS[:2] if args.quick else THESIS_DATASETS:
        runs = [(name, None, seed) for seed in range(lanes)]
        twin.simulate_batch(runs[:1], duration=0.01, outputs=THESIS_OUTPUTS)  # compile
        start = time.perf_counter()
        twin.simulate_batch(runs, solver=twin.Solver(lanes=lanes), duration=duration, outputs=THESIS_OUTPUTS,
                            throw=False)
        scale = twin.load_scene(name).duration / (duration or twin.load_scene(name).duration)
        walls.append((time.perf_counter() - start) / lanes * scale)  # per full-length run
    per_run = statistics.mean(walls)
    print(f"thesis study estimate: 7000 runs x {per_run:.3f} s ({lanes} lanes a group) / {os.cpu_count()} cores = "
          f"{7000 * per_run / os.cpu_count() / 60:.1f} min (plus scheduling, storage and the fidelity audit)")


if __name__ == "__main__":
    main()
