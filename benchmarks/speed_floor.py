"""The least CPU a run can take with this model at the default accuracy: what limits the step, and at what cost.

Per scene (the nominal scene at the default settings; with ``--datasets`` also the thesis data sets at the thesis
campaign's fidelity), a lane group of runs at the default method and step (RK4; 62.5 us at full fidelity, the 125 us
drive period at the campaign's automatic fidelity: ``twin.Solver.step``) is recorded step by step
(``step_costs.recorded_group``). Measured on it, per lane (per Monte Carlo sample):

* ``t_rhs``: CPU of one right-hand side (``twin.engine.plant.rhs``) over the recorded states and inputs, in a compiled
  loop, less an empty pass (median of ``--repeats``), divided by the lanes;
* ``outside``: ``run_loop``'s CPU per step and lane less four right-hand sides (stage updates, instruments, guard,
  sample instants, local-error check);
* the eigenvalues of the Jacobian (``twin.engine.linearize``) of the first lane at ``--instants`` states spread
  over the run: RK4's largest stable step at each (``linearize.largest_stable_step``), the mode that sets it and its
  damping ratio.

From these, per 10 s of simulated time (the target's unit), three floors per sample:

* **A** RK4 at the largest step that divides the drive period and is stable at every instant, with the work
  outside the right-hand side per step as measured at the recorded step (at a longer step this undercounts the
  work done per second of simulated time, such as the sample instants: still a floor);
* **B** the same steps, the right-hand sides alone;
* **C** any explicit Runge-Kutta method, the right-hand sides alone: an s-stage method reaches at most ``s - 1``
  along the imaginary axis (Vichnevetsky 1983; Kinnmark & Gray 1984), so it needs at least ``|Im lambda|``
  right-hand sides per second of simulated time for a mode on that axis. The limiting modes here are lightly
  damped (damping ratio printed), so C is indicative, not a strict bound.

and the right-hand-side cost at which A would meet the 40 ms per sample target (issue 32). With ``--datasets``:
the thesis campaign's ceiling on 2 workers from floor A per data set, and the cores a 7 x 1000 study needs for
5 min at the measured CPU per sample.

    python benchmarks/speed_floor.py [--datasets] [--instants 200] [--repeats 5] [--lanes 8]
    python benchmarks/speed_floor.py --quick     # nominal scene, 0.5 s, 10 instants (seconds)
"""

from __future__ import annotations

import argparse
import os

import numba
import numpy as np
from machine import header
from single_run import TARGET, THESIS_DATASETS, THESIS_OUTPUTS
from step_costs import FIDELITY, OUTPUTS, empty_pass, median_cpu, recorded_group, run_loop_cpu

import twin
from twin.engine.linearize import RK4_STABILITY, jacobian, largest_stable_step
from twin.engine.plant import rhs, work_rows
from twin.solver import DEFAULT_LANES, DEFAULT_SOLVER

TARGET_DURATION = 10.0          # s of simulated time the single-run target is stated for (issue 16)
CAMPAIGN_TARGET = 25.0          # runs/s on 2 workers (issue 32)
STUDY_RUNS, STUDY_MINUTES = 7000, 5.0
WORKERS = 2
RK4_STAGES = 4


@numba.njit
def rhs_pass(trajectory, inputs, c, levels, force_table, dt, w):
    """One right-hand side of the group at every recorded state, with the inputs held in its step."""
    out = np.zeros(trajectory.shape[1:])
    x = np.zeros(trajectory.shape[1:])
    total = 0.0
    for k in range(trajectory.shape[0]):
        x[:] = trajectory[k]
        rhs((k + 1) * dt, x, c, inputs[k], levels, force_table, out, w)
        total += out[0, 0]
    return total


def limiting_modes(recorded, instants: int):
    """Per sampled instant of the first lane: (time, RK4's largest stable step, the eigenvalue that sets it, largest
    |Im lambda|)."""
    model, dt = recorded.model, recorded.run.dt
    rows = np.unique(np.linspace(0, recorded.n - 1, instants).astype(int))
    found = []
    for k in rows:
        y = recorded.trajectory[k][model.active, 0]
        eigenvalues = np.linalg.eigvals(jacobian(model, y, t=(k + 1) * dt, u=recorded.inputs[k][:, 0]))
        limits = [largest_stable_step([lam]) for lam in eigenvalues]  # one ray each, to name the limiting mode
        worst = int(np.argmin(limits))
        limiting = eigenvalues[np.isfinite(limits)]  # the modes that set a step limit at all (largest_stable_step)
        found.append(((k + 1) * dt, limits[worst], eigenvalues[worst],
                      float(np.max(np.abs(limiting.imag), initial=0.0))))
    return found


def admissible_step(limit: float, drive_period: float) -> float:
    """The largest ``drive_period / k`` at or below ``limit`` (a step must divide the sample periods); the drive
    period itself when nothing limits the step."""
    return drive_period / max(1, int(np.ceil(drive_period / limit - 1e-9))) if limit < np.inf else drive_period


def explicit_cross_check(name: str, duration: float | None, step: float, default_step: float) -> None:
    """The linear analysis checked by the nonlinear run: RK4 at ``step`` against the default, same scene and noise."""
    options = {"duration": duration, "fidelity": FIDELITY.get(name, "auto"),
               "outputs": OUTPUTS.get(name, THESIS_OUTPUTS), "throw": False}
    default = twin.simulate(name, solver=DEFAULT_SOLVER, **options)
    coarse = twin.simulate(name, solver=twin.Solver(DEFAULT_SOLVER.integrator, dt=step), **options)
    change = (f"f_b true {1e6 * (float(coarse.backlash_feature_true) - float(default.backlash_feature_true)):+.4f} um "
              f"against {default_step * 1e6:g} us" if coarse.attrs["status"] == default.attrs["status"] == "ok" else
              coarse.attrs["failure_reason"] or default.attrs["failure_reason"])
    print(f"  cross-check, the nonlinear run at {1e6 * step:.2f} us: {coarse.attrs['status']}, largest local error "
          f"{coarse.attrs['max_local_error']:.2f} of its tolerance, {change}")


def scene_floor(name: str, duration: float | None, instants: int, repeats: int, lanes: int) -> dict:
    recorded = recorded_group(name, duration, DEFAULT_SOLVER.integrator, None, lanes)
    run, model, n = recorded.run, recorded.model, recorded.n
    args = (recorded.trajectory, recorded.inputs, recorded.c, model.levels, model.force_table, run.dt,
            work_rows(lanes))
    t_rhs = max(median_cpu(rhs_pass, args, repeats) - median_cpu(empty_pass, (recorded.trajectory,), repeats),
                0) / n / lanes
    per_step = run_loop_cpu(recorded, repeats) / n / lanes
    outside = per_step - RK4_STAGES * t_rhs
    modes = limiting_modes(recorded, instants)
    limits = np.array([m[1] for m in modes])
    worst = modes[int(np.argmin(limits))]
    drive_period = run.params.value("drive.speed_loop_sample_time")
    step = admissible_step(float(limits.min()), drive_period)
    scale = TARGET_DURATION / run.scene.duration
    steps = TARGET_DURATION / step
    imag_max = max(m[3] for m in modes)
    outside_total = steps * outside
    floor = {
        "name": name, "states": model.active.size, "duration": run.scene.duration, "t_rhs": t_rhs,
        "outside": outside, "per_run": per_step * n * scale, "limit_min": float(limits.min()),
        "limit_median": float(np.median(limits)), "worst_time": worst[0], "worst_mode": worst[2],
        "imag_max": imag_max, "step": step, "A": steps * (RK4_STAGES * t_rhs + outside),
        "B": steps * RK4_STAGES * t_rhs, "C": TARGET_DURATION * imag_max * t_rhs,
        "t_rhs_for_target": (TARGET - outside_total) / (steps * RK4_STAGES),
    }
    lam = floor["worst_mode"]
    print(f"\n'{name}' ({floor['states']} states, screw axial {run.fidelity.level('screw_axial')}, "
          f"{floor['duration']:g} s recorded at {DEFAULT_SOLVER.integrator} {run.dt * 1e6:g} us in {lanes} lanes; "
          f"figures per sample and {TARGET_DURATION:g} s)")
    print(f"  measured per lane: right-hand side {1e9 * t_rhs:.0f} ns; run_loop {1e9 * per_step:.0f} ns per step, of "
          f"which {1e9 * outside:.0f} ns outside the four right-hand sides; {floor['per_run']:.3f} s CPU per sample")
    print(f"  RK4 stable step over {len(modes)} instants: min {1e6 * floor['limit_min']:.1f} us (t = "
          f"{floor['worst_time']:.3f} s, lambda = {lam.real:.3g} {lam.imag:+.3g}i 1/s, damping ratio "
          f"{-lam.real / abs(lam):.2f}), median {1e6 * floor['limit_median']:.1f} us; largest |Im lambda| "
          f"{imag_max:.3g} 1/s")
    print(f"  largest step dividing the {1e6 * drive_period:g} us drive period under that: {1e6 * step:.2f} us")
    print(f"  floor A (RK4 at {1e6 * step:.2f} us, per-step work outside the right-hand side as at "
          f"{1e6 * run.dt:g} us) "
          f"{floor['A']:.3f} s; B (its right-hand sides alone) {floor['B']:.3f} s; "
          f"C (any explicit method, right-hand sides alone, indicative) {floor['C']:.3f} s")
    if step > run.dt * (1 + 1e-9):
        explicit_cross_check(name, duration, step, run.dt)
    needed = floor["t_rhs_for_target"]
    print(f"  for A to meet {TARGET:g} s per sample the right-hand side would have to cost "
          + (f"next to nothing: the work outside it takes {outside_total:.3f} s of the {TARGET:g} s" if needed <= 0 else
             f"{1e9 * needed:.0f} ns per lane ({t_rhs / needed:.1f}x less than now)" if needed < t_rhs else
             f"{1e9 * needed:.0f} ns per lane: met at today's {1e9 * t_rhs:.0f} ns"))
    return floor


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--datasets", action="store_true", help="also the seven thesis data sets (campaign fidelity)")
    parser.add_argument("--instants", type=int, default=200, help="states along the run whose eigenvalues are taken")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--lanes", type=int, default=DEFAULT_LANES, help="lanes of the recorded group")
    parser.add_argument("--quick", action="store_true", help="nominal scene, 0.5 s, 10 instants, one pass")
    args = parser.parse_args()
    header("speed floor: the least CPU per run that the model's stiffest mode and its right-hand side allow",
           args.quick)
    duration, instants, repeats = (0.5, 10, 1) if args.quick else (None, args.instants, args.repeats)
    print(f"# RK4 stability function R(z) = {RK4_STABILITY}; imaginary-axis reach "
          f"{largest_stable_step([1j]):.3f}, real-axis {largest_stable_step([-1.0]):.3f}")
    nominal = scene_floor("nominal", duration, instants, repeats, args.lanes)
    verdict = "not reachable" if nominal["A"] > TARGET else "reachable"
    print(f"\ntarget {TARGET:g} s per sample and {TARGET_DURATION:g} s (nominal, default settings, {args.lanes} "
          f"lanes) by RK4 at the default accuracy: {verdict} at today's right-hand side (floor A {nominal['A']:.3f} s);"
          f" any explicit method's right-hand sides alone: {nominal['C']:.3f} s (indicative)")
    if not args.datasets or args.quick:
        return
    floors = [scene_floor(name, None, instants, repeats, args.lanes) for name in THESIS_DATASETS]
    mean_a = float(np.mean([f["A"] for f in floors]))
    mean_run = float(np.mean([f["per_run"] for f in floors]))
    ceiling = WORKERS / mean_a
    cores = STUDY_RUNS * mean_run / (60.0 * STUDY_MINUTES)
    print(f"\nthesis campaign (mean over the data sets, {args.lanes} lanes): CPU per sample {mean_run:.3f} s "
          f"measured, floor A {mean_a:.3f} s")
    reach = "reachable" if ceiling >= CAMPAIGN_TARGET else "not reachable"
    print(f"  RK4 ceiling on {WORKERS} workers: {ceiling:.1f} runs/s; target {CAMPAIGN_TARGET:g} runs/s: {reach}")
    print(f"  cores for {STUDY_RUNS} runs in {STUDY_MINUTES:g} min at today's CPU per sample (no audit): "
          f"{cores:.1f} (this machine: {os.cpu_count()}); campaigns reach such a cluster with --scheduler")


if __name__ == "__main__":
    main()
