"""Wall time of one default-scene run after compilation (issue: bench twin core).

Prints the median of repeated 10 s nominal-scene runs per integrator and step, runs/s on one core,
and the real-time factor. Usage: python benchmarks/single_run.py [--repeats N] [--quick]
"""

import argparse
import statistics
import time

from machine import header

import twin


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--scene", default="nominal")
    parser.add_argument("--quick", action="store_true", help="one 1 s run per configuration (seconds)")
    args = parser.parse_args()
    scene = twin.load_scene(args.scene)
    if args.quick:
        scene, args.repeats = scene.with_duration(1.0), 1
    params = twin.load_parameters()
    header("single run: wall time of one scene after compilation", args.quick)
    print(f"# scene '{scene.name}', duration {scene.duration} s; median of {args.repeats} runs after compilation")
    print(f"{'integrator':22s} {'dt [s]':>10s} {'wall [s]':>9s} {'runs/s':>8s} {'x real time':>12s} {'f_b [um]':>10s}")
    for integrator, dt in (("rk4", 6.25e-5), ("rk4", 3.125e-5), ("semi_implicit_euler", 3.125e-5),
                           ("semi_implicit_euler", 1.5625e-5)):
        twin.simulate(scene, params, integrator=integrator, dt=dt, duration=0.01)  # compile
        times = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            ds = twin.simulate(scene, params, integrator=integrator, dt=dt)
            times.append(time.perf_counter() - start)
        wall = statistics.median(times)
        print(f"{integrator:22s} {dt:10.4g} {wall:9.3f} {1 / wall:8.2f} {scene.duration / wall:12.1f} "
              f"{float(ds.backlash_feature_true) * 1e6:10.4f}")


if __name__ == "__main__":
    main()
