"""CPU per sample of a 10 s thesis run: the lane engine at 1, 8 and 16 lanes against the previous default.

All figures are measured in this one process, one configuration after the other, and repeated (min / median of
``--repeats``), so their ratios hold on a loaded machine while their absolute values do not (the load average is
printed with them). CPU time (``time.process_time``) includes the Python side of every run (model build,
instruments and noise, features); the scene and the parameter files are read once, as a campaign's worker does,
and compilation is done before the clock starts.

* the default: RK4 at the 125 us drive period with the quasi-static screw axial (the automatic fidelity of the
  thesis campaign), as one lane (a replay, ``twin.simulate_features``) and in groups of 8 and 16 lanes
  (``twin.simulate_batch``: a campaign's runs); the target is at most 40 ms of CPU per sample in a group
  (issue 32);
* the previous default: RK4 at 62.5 us with the screw's axial mass (``screw_axial = "dynamic"``), one lane;
* ``twin simulate nominal``: the wall time of its 10 s run (the run's ``wall_time``, what the command prints) and its
  real-time factor, against the target of issue 40 (at least 24x real time on an idle machine). One lane takes the
  engine's fused form, a group the split form (``twin.engine.plant.FUSED_LANES``).

Every sample is a different run (its own noise seed), taken from the thesis data sets in turn.

Usage: python benchmarks/single_run.py [--repeats N] [--quick]   (--quick: 1 s runs, one repeat)
"""

from __future__ import annotations

import argparse
import functools
import statistics
import time

from machine import header

import twin
from twin.solver import split_solver

TARGET = 0.040  # s of CPU per sample of a 10 s thesis run in a lane group (issue 32)
REAL_TIME_TARGET = 24.0  # `twin simulate nominal` at least 24x real time on an idle machine (issue 40)
THESIS_DATASETS = ("ds1", "ds2", "ds3", "ds4", "ds5", "ds6", "ds7")
#: What a thesis-campaign run computes (campaigns/specs/thesis_backlash.toml): it sets the automatic fidelity.
THESIS_OUTPUTS = ["backlash_feature", "backlash_feature_true", "backlash_hysteresis", "backlash_hysteresis_true",
                  "position_demand", "nut1_position", "screw_equivalent_position", "linear_encoder_position",
                  "preload_force", "external_force"]
PREVIOUS_DEFAULT = {"dt": 6.25e-5, "fidelity": {"screw_axial": "dynamic"}}


@functools.cache
def _inputs(dataset: str) -> tuple:
    """The data set's scene and the bench parameters, loaded once (a campaign loads them once per worker)."""
    return twin.load_scene(dataset), twin.load_parameters("bench")


def cpu_per_sample(dataset: str, lanes: int, duration: float, seed: int, **options) -> float:
    """CPU seconds per sample of ``lanes`` runs of ``dataset`` (one group, or one run for one lane)."""
    scene, params = _inputs(dataset)
    runs = [(scene, params, seed + k) for k in range(lanes)]
    solver, options = split_solver({**options, "lanes": lanes})
    start = time.process_time()
    if lanes == 1:
        twin.simulate(scene, params, solver=solver, save="features", rng=seed, duration=duration,
                      outputs=THESIS_OUTPUTS, throw=False, **options)
    else:
        twin.simulate_batch(runs, solver=solver, duration=duration, outputs=THESIS_OUTPUTS, throw=False, **options)
    return (time.process_time() - start) / lanes


def nominal_wall_time(repeats: int) -> tuple[float, float]:
    """The least wall time [s] of ``twin simulate nominal``'s run over ``repeats`` and the scene's duration [s]."""
    scene, params = twin.load_scene("nominal"), twin.load_parameters("bench")
    return min(twin.simulate(scene, params, rng=0).attrs["wall_time"] for _ in range(repeats)), scene.duration


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="repeats of each configuration (default 3)")
    parser.add_argument("--quick", action="store_true", help="1 s runs, one repeat, two data sets")
    args = parser.parse_args()
    header("CPU per sample of a thesis run: the lane engine against the previous default", args.quick)
    duration = 1.0 if args.quick else 10.0
    repeats = 1 if args.quick else args.repeats
    datasets = THESIS_DATASETS[:2] if args.quick else THESIS_DATASETS
    configurations = [("default, 1 lane (a replay)", 1, {}), ("default, 8 lanes", 8, {}),
                      ("default, 16 lanes", 16, {}), ("previous default (RK4 62.5 us, dynamic axial), 1 lane", 1,
                                                      PREVIOUS_DEFAULT)]
    for dataset in datasets:  # compile every configuration and load the caches before any clock starts
        for _, lanes, options in configurations:
            cpu_per_sample(dataset, min(lanes, 2), 0.01, 0, **options)
    scale = 10.0 / duration
    print(f"# {len(datasets)} data sets x {repeats} repeat(s), {duration:g} s runs scaled to 10 s; CPU per sample [ms]")
    print(f"{'configuration':58s} {'min':>8s} {'median':>8s}   per data set (median)")
    results = {}
    for label, lanes, options in configurations:
        per_dataset = {d: [scale * cpu_per_sample(d, lanes, duration, 1000 * r, **options) for r in range(repeats)]
                       for d in datasets}
        values = [v for vs in per_dataset.values() for v in vs]
        results[label] = statistics.median(values)
        detail = " ".join(f"{d} {1e3 * statistics.median(v):.0f}" for d, v in per_dataset.items())
        print(f"{label:58s} {1e3 * min(values):8.1f} {1e3 * statistics.median(values):8.1f}   {detail}")
    previous = results[configurations[-1][0]]
    for label, _, _ in configurations[:-1]:
        print(f"ratio previous / {label:41s} {previous / results[label]:6.2f}x")
    best = min(results[configurations[1][0]], results[configurations[2][0]])
    verdict = "met" if best <= TARGET else "not met"
    print(f"target: <= {TARGET * 1e3:g} ms CPU per sample in a lane group: {best * 1e3:.1f} ms -> {verdict}")
    if not args.quick:
        wall, duration = nominal_wall_time(repeats)
        print(f"twin simulate nominal: {wall:.3f} s wall for its {duration:g} s run, {duration / wall:.1f}x real time "
              f"(target >= {REAL_TIME_TARGET:g}x on an idle machine; this one's load average is in the header)")


if __name__ == "__main__":
    main()
