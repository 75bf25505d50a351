"""Does the automatic fidelity pay? Lane-engine CPU time of each built-in scene at "full" and at the rules' levels.

Per built-in scene, one ``twin.simulate_batch`` group of ``--lanes`` runs (16: a campaign's group) at fidelity
``"full"`` and one at the levels the rules of ``twin/fidelity/rules.toml`` choose alone (``resolve_fidelity(...,
speed_file=None)``, passed as an explicit request, so the stored measurement does not gate what it measures), for the
scene's own outputs, interleaved full / auto within each repeat so that both see the same load; the figure is the
median over the repeats of the paired ratio full / auto of CPU time (``time.process_time``: the run's Python side,
model build, instruments and features included, as in a campaign's worker). Compilation is done before any clock
starts. The scenes are those of ``twin.scenes.list_scenes()``: the thesis data sets ds1..ds7, ``nominal`` (a
campaign's default base scene) and the chapter 7 scenes.

``--write`` stores the ratios in ``twin/fidelity/speed.toml``, the measurement the gate of ``resolve_fidelity`` reads
(``min_lane_speedup``; docs/fidelity.md, "Fidelity that pays"). ``--quick`` (CI) runs 0.5 s scenes, one repeat, and
never writes.

Usage: python benchmarks/fidelity_speed.py [--repeats N] [--lanes N] [--scenes ds1,ds2] [--quick | --write]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from datetime import UTC, datetime

from machine import cpu_model, header, vector_extension

import twin
from twin.fidelity.rules import MEASUREMENT_FIELDS, SPEED_FILE, resolve_fidelity

QUICK_DURATION = 0.5  # s of each scene simulated in --quick


def automatic_levels(scene: twin.Scene, params) -> dict[str, str]:
    """The levels the rules alone choose for the scene and its own outputs (no gate)."""
    return dict(resolve_fidelity(scene, params, "auto", speed_file=None).levels)


def group_cpu(scene: twin.Scene, params, fidelity, lanes: int, duration: float | None, seed: int) -> float:
    """CPU seconds of one group of ``lanes`` runs of ``scene`` (each its own noise seed)."""
    runs = [(scene, params, seed + k) for k in range(lanes)]
    solver = twin.Solver(lanes=lanes)
    start = time.process_time()
    twin.simulate_batch(runs, solver=solver, duration=duration, fidelity=fidelity, throw=False)
    return time.process_time() - start


def measure(names: list[str], lanes: int, repeats: int, duration: float | None) -> dict[str, dict]:
    """Per scene: the automatic levels, the median CPU time of a group at each fidelity and the median paired ratio."""
    params = twin.load_parameters("bench")
    scenes = {name: twin.load_scene(name) for name in names}
    levels = {name: automatic_levels(scene, params) for name, scene in scenes.items()}
    full_levels = {name: resolve_fidelity(scene, params, "full").levels for name, scene in scenes.items()}
    for name, scene in scenes.items():  # compile every configuration before a clock starts
        for fidelity in ("full", levels[name]):
            group_cpu(scene, params, fidelity, min(lanes, 2), 0.01, 0)
    results = {}
    for name, scene in scenes.items():
        full, auto = [], []
        for r in range(repeats):
            full.append(group_cpu(scene, params, "full", lanes, duration, 1000 * r))
            auto.append(group_cpu(scene, params, levels[name], lanes, duration, 1000 * r))
        ratios = [f / a for f, a in zip(full, auto, strict=True)]
        reduced = ", ".join(f"{k}={v}" for k, v in levels[name].items() if v != full_levels[name][k])
        results[name] = {"speedup": statistics.median(ratios), "ratio_min": min(ratios), "ratio_max": max(ratios),
                         "full_cpu": statistics.median(full), "auto_cpu": statistics.median(auto),
                         "auto_levels": reduced or "none reduced"}
        print(f"{name:26s} {results[name]['full_cpu']:8.2f} {results[name]['auto_cpu']:8.2f} "
              f"{results[name]['speedup']:7.2f}x  ({min(ratios):.2f}-{max(ratios):.2f})  {reduced}", flush=True)
    return results


def speed_file_text(results: dict[str, dict], measurement: dict) -> str:
    """``speed.toml``: the measurement's header, then one table per scene."""
    assert set(MEASUREMENT_FIELDS) <= set(measurement)
    lines = ["# Lane-engine speedup of the automatic fidelity: full / auto CPU time of one group per built-in",
             "# scene, written by `python benchmarks/fidelity_speed.py --write` (do not edit by hand; rerun it after",
             "# a change of the rules, the levels or the engine). twin/fidelity/rules.py reads `speedup` against",
             "# rules.toml's min_lane_speedup (docs/fidelity.md, \"Fidelity that pays\"); the rest is the record.",
             "", "[measurement]"]
    lines += [f"{key} = {_toml(value)}" for key, value in measurement.items()]
    for name, row in results.items():
        lines += ["", f"[scenes.{name}]",
                  f"speedup = {row['speedup']:.3f}  # median over the repeats of full / auto",
                  f"ratio_range = [{row['ratio_min']:.3f}, {row['ratio_max']:.3f}]  # least and largest repeat",
                  f"full_cpu = {row['full_cpu']:.3f}  # s of CPU per group, median",
                  f"auto_cpu = {row['auto_cpu']:.3f}",
                  f"auto_levels = {_toml(row['auto_levels'])}  # what the rules reduce (scene's own outputs)"]
    return "\n".join(lines) + "\n"


def _toml(value) -> str:
    return f'"{value}"' if isinstance(value, str) else repr(value)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="repeats per scene and fidelity (default 5)")
    parser.add_argument("--lanes", type=int, default=16, help="runs per group (default 16: a campaign's group)")
    parser.add_argument("--scenes", help="comma-separated scenes (default: every built-in scene)")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--quick", action="store_true", help=f"{QUICK_DURATION:g} s scenes, 1 repeat, thesis data "
                                                           "sets 1, 2 and 5; never writes")
    mode.add_argument("--write", action="store_true", help=f"store the ratios in {SPEED_FILE}")
    args = parser.parse_args()
    if args.repeats < 1 or args.lanes < 1:
        parser.error("--repeats and --lanes: must be at least 1")
    names = args.scenes.split(",") if args.scenes else twin.scenes.list_scenes()
    if args.write and args.scenes:
        parser.error("--write stores every built-in scene: leave out --scenes")
    unknown = sorted(set(names) - set(twin.scenes.list_scenes()))
    if unknown:
        parser.error(f"--scenes: {', '.join(unknown)} not built-in ({', '.join(twin.scenes.list_scenes())})")
    if args.quick:
        names, repeats, duration = [n for n in ("ds1", "ds2", "ds5") if n in names] or names[:1], 1, QUICK_DURATION
    else:
        repeats, duration = args.repeats, None
    header("Fidelity that pays: full / auto CPU time of a lane group per built-in scene", args.quick)
    print(f"# {args.lanes} lanes per group, {repeats} repeat(s), "
          f"{f'{duration:g} s runs' if duration else 'each scene its own duration'}")
    print(f"{'scene':26s} {'full [s]':>8s} {'auto [s]':>8s} {'speedup':>8s}  (repeat range)  automatic levels")
    before = os.getloadavg()
    results = measure(names, args.lanes, repeats, duration)
    after = os.getloadavg()
    load = f"{' '.join(f'{v:.2f}' for v in before)} before, {' '.join(f'{v:.2f}' for v in after)} after"
    print(f"# load average (1, 5, 15 min): {load}")
    if args.write:
        measurement = {"machine": f"{cpu_model()} ({vector_extension()}), {os.cpu_count()} cores",
                       "date": datetime.now(UTC).date().isoformat(), "load": load, "lanes": args.lanes,
                       "repeats": repeats, "clock": "time.process_time of one twin.simulate_batch group",
                       "outputs": "each scene's own"}
        SPEED_FILE.write_text(speed_file_text(results, measurement))
        print(f"# written: {SPEED_FILE}")


if __name__ == "__main__":
    main()
