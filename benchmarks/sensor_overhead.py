"""Wall-time share of the sensor models (issue: sensors and acquisition).

Times the same scene with every instrument ideal (true signals, no sensor model runs) and at
the quantized and full (edge-accurate with errors and noise) levels; prints the overhead.
The instruments' level is set through the fidelity request (``encoders`` and ``analog_sensors``);
the plant stays the same (the full plant at two fixed steps, and the campaigns' automatic plant at its default
step, RK4 at the drive period) so that only the sensor models differ.
Usage: python benchmarks/sensor_overhead.py [--scene ds2] [--repeats 5] [--quick]
"""

import argparse
import statistics
import time

from machine import header

import twin


def instruments(level: str, plant: str = "full") -> dict[str, str]:
    """The plant at ``plant`` ("full", or "auto": the automatic fidelity of the campaigns), every instrument at
    ``level`` (the torque meter's 1 kHz refresh only when modelled)."""
    return {"default": plant, "encoders": level, "analog_sensors": level,
            "torque_meter_refresh": "ideal" if level == "ideal" else "modelled"}


def median_wall(scene, repeats, **options):
    twin.simulate(scene, duration=0.01, **options)  # compile
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        twin.simulate(scene, **options)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--scene", default="ds2")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="one 1 s run per configuration (seconds)")
    args = parser.parse_args()
    scene = twin.load_scene(args.scene)
    if args.quick:
        scene, args.repeats = scene.with_duration(1.0), 1
    header("sensor overhead: the same scene with ideal, quantized and full instruments", args.quick)
    print(f"# scene '{scene.name}' ({scene.duration} s), median of {args.repeats} runs after compilation")
    # the full plant at two fixed steps, and the automatic plant at its default step (the quasi-static screw axial:
    # RK4 at the drive period), as a campaign runs it
    for integrator, dt, plant in (("rk4", 6.25e-5, "full"), ("semi_implicit_euler", 3.125e-5, "full"),
                                  ("rk4", None, "auto")):
        solver = twin.Solver(integrator, dt=dt)
        base = median_wall(scene, args.repeats, solver=solver, fidelity=instruments("ideal", plant))
        step = twin.simulate(scene, duration=0.01, solver=solver, fidelity=instruments("ideal", plant)).attrs["dt"]
        for level in ("quantized", "full"):
            wall = median_wall(scene, args.repeats, solver=solver, fidelity=instruments(level, plant))
            print(f"{integrator:20s} dt={step:.4g} {plant:4s} plant  ideal {base:.3f} s   {level:9s} {wall:.3f} s   "
                  f"overhead {100 * (wall / base - 1):5.1f} %")


if __name__ == "__main__":
    main()
