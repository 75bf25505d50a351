"""Per-step cost of everything in the compiled loop that is not the right-hand side, part by part, for a lane group.

A compiled harness records the state of a group of lanes after every step of a run (the nominal scene at full
fidelity, the ds1 data set at the thesis campaign's automatic fidelity; each lane its own noise), then calls each
part of :func:`twin.engine.loop.run_loop` over that trajectory, in compiled loops: the integrator step, the
divergence guard, the instruments' advance, the acquisition and speed-loop instants, the recording of a row and the
local-error check. Each figure is the median of ``--repeats`` passes less an empty pass over the same trajectory,
per call and per integration step (calls per run / steps), for the whole group and per lane. ``run_loop`` itself
is timed on the same group (:func:`twin.engine.group.solve_group`); the parts' sum against it shows what the
harness misses (the loop's own bookkeeping). CPU time (``time.process_time``); print the load average with it: on
a shared machine use the shares.

Usage: python benchmarks/step_costs.py [--repeats N] [--lanes L] [--quick]
"""

from __future__ import annotations

import argparse
import statistics
import time
from types import SimpleNamespace

import numba
import numpy as np
from machine import header
from single_run import THESIS_OUTPUTS

from twin import simulation
from twin.engine import instrumentation as ins
from twin.engine import loop
from twin.engine.group import solve_group
from twin.engine.integrators import INTEGRATORS, Workspace, step
from twin.engine.plant import internal_forces, measurands
from twin.layout import N_INPUTS, N_MEMORY, N_SIGNALS, N_STATES, M
from twin.parameters import load_parameters
from twin.solver import DEFAULT_LANES, DEFAULT_SOLVER, Solver

DRIVE_PERIOD = load_parameters().value("drive.speed_loop_sample_time")
#: The cases profiled: (scene, integrator, step; None: the default step). The nominal scene as `twin.simulate` runs
#: it by default (every output: full fidelity, RK4 at 62.5 us), a thesis data set as a thesis campaign runs it (its
#: outputs set the automatic fidelity: the quasi-static screw axial, RK4 at the drive period), and the nominal scene
#: with the linearly implicit step at the drive period (it integrates the full model's screw-axial mode).
CASES = (("nominal", DEFAULT_SOLVER.integrator, None), ("ds1", DEFAULT_SOLVER.integrator, None),
         ("nominal", "imex_euler", DRIVE_PERIOD))
OUTPUTS = {"nominal": None}
FIDELITY = {"nominal": "full"}


@numba.njit
def record_trajectory(method, x, c, levels, position_table, force_table, active, pairs, dt, speed_every,
                      position_every, parameters, states, noise, memory, vectors, w, matrices, cache, small,
                      trajectory, inputs):
    """run_loop's sequence of samples, steps and instrument advances (no output, no checks), recording the group's
    state after every step (``trajectory[k]`` is the state at ``(k + 1) dt``) and the held inputs of that step."""
    lanes = x.shape[1]
    u = np.zeros((N_INPUTS, lanes))
    alive = np.ones(lanes, dtype=np.bool_)
    loop.controller_init(0.0, x, c, u, w, levels, memory, parameters, states, force_table)
    to_acquisition = to_speed = 0
    for k in range(trajectory.shape[0]):
        t = k * dt
        if to_acquisition == 0:
            internal_forces(t, x, c, w, lanes, levels, force_table)
            loop.acquisition_sample(t, x, c, u, w, levels, memory, parameters, states, noise, position_table,
                                    force_table, position_every * dt, alive)
            to_acquisition = position_every
        if to_speed == 0:
            loop.speed_sample(x, c, u, levels, memory, parameters, speed_every * dt, alive)
            to_speed = speed_every
        step(method, t, x, dt, c, u, levels, force_table, vectors[:6], w, matrices, cache, small,
             to_acquisition == position_every, active, pairs)
        trajectory[k] = x
        inputs[k] = u
        to_acquisition -= 1
        to_speed -= 1
        measurands(t + dt, x, c, w, lanes, levels, force_table)
        ins.instruments_advance(t + dt, dt, x, c, w, levels, parameters, states, to_acquisition)


@numba.njit
def empty_pass(trajectory):
    total = 0.0
    for k in range(trajectory.shape[0]):
        total += trajectory[k, 0, 0]
    return total


@numba.njit
def step_pass(method, trajectory, c, u, levels, force_table, active, pairs, dt, vectors, w, matrices, cache, small):
    x = np.zeros(trajectory.shape[1:])
    for k in range(trajectory.shape[0]):
        x[:] = trajectory[k]
        step(method, k * dt, x, dt, c, u, levels, force_table, vectors[:6], w, matrices, cache, small, False,
             active, pairs)
    return x


@numba.njit
def guard_pass(trajectory, c, w, levels):
    codes = 0
    for k in range(trajectory.shape[0]):
        for lane in range(trajectory.shape[2]):
            codes += loop.guard(trajectory[k], c, w, lane, levels)
    return codes


@numba.njit
def instruments_pass(trajectory, x0, c, levels, force_table, dt, position_every, parameters, states, w):
    """The measurands and the instruments' advance after every step (as run_loop: the analog channels when due)."""
    lanes = x0.shape[1]
    memory = np.zeros((N_MEMORY, lanes))
    u = np.zeros((N_INPUTS, lanes))
    loop.controller_init(0.0, x0, c, u, w, levels, memory, parameters, states, force_table)
    for k in range(trajectory.shape[0]):
        x = trajectory[k]
        measurands((k + 1) * dt, x, c, w, lanes, levels, force_table)
        ins.instruments_advance((k + 1) * dt, dt, x, c, w, levels, parameters, states,
                                (position_every - (k + 1) % position_every) % position_every)
    return states


@numba.njit
def samples_pass(trajectory, x0, c, levels, position_table, force_table, dt, every, parameters, states, noise, w,
                 output, part):
    """Part 0: acquisition instants, 1: speed-loop instants, 2: output rows, each at every ``every``-th state (the
    acquisition and the recording with the contact forces they read, :func:`internal_forces`)."""
    lanes = x0.shape[1]
    memory = np.zeros((N_MEMORY, lanes))
    u = np.zeros((N_INPUTS, lanes))
    alive = np.ones(lanes, dtype=np.bool_)
    loop.controller_init(0.0, x0, c, u, w, levels, memory, parameters, states, force_table)
    n = 0
    x = np.zeros(x0.shape)
    for k in range(0, trajectory.shape[0], every):
        x[:] = trajectory[k]  # the quasi-static balance writes its rows: work on a copy
        if part == 0:
            for lane in range(lanes):
                memory[M.SAMPLES, lane] = 0.0  # the same noise row each time: the cost does not depend on it
            internal_forces(k * dt, x, c, w, lanes, levels, force_table)
            loop.acquisition_sample(k * dt, x, c, u, w, levels, memory, parameters, states, noise, position_table,
                                    force_table, every * dt, alive)
        elif part == 1:
            loop.speed_sample(x, c, u, levels, memory, parameters, every * dt, alive)
        else:
            internal_forces(k * dt, x, c, w, lanes, levels, force_table)
            for lane in range(lanes):
                loop.record(output[n, :, lane], k * dt, x, c, u, w, lane, memory, levels, force_table)
        n += 1
    return n


@numba.njit
def local_error_pass(method, trajectory, c, u, levels, force_table, active, pairs, dt, every, tolerance, vectors, w,
                     matrices, cache, small):
    estimate = np.zeros(trajectory.shape[2])
    worst = 0.0
    for k in range(0, trajectory.shape[0], every):
        loop.local_error(method, k * dt, trajectory[k], dt, c, u, levels, force_table, vectors, w, matrices, cache,
                         small, tolerance, active, pairs, estimate)
        worst = max(worst, estimate.max())
    return worst


def median_cpu(function, args, repeats) -> float:
    function(*args)  # compile
    times = []
    for _ in range(repeats):
        start = time.process_time()
        function(*args)
        times.append(time.process_time() - start)
    return statistics.median(times)


def recorded_group(scene_name: str, duration: float, integrator: str, dt: float | None, lanes: int):
    """A group of ``lanes`` runs of ``scene_name`` (fidelity and outputs as in :data:`FIDELITY`, :data:`OUTPUTS`;
    noise seeds 0 ... lanes - 1), prepared as :func:`twin.simulate_batch` prepares them, and the group's state and
    held inputs after every step (``trajectory``, ``inputs``: one ``[row, lane]`` block per step)."""
    prepared = []
    for seed in range(lanes):
        run = simulation._validated(scene_name, None, Solver(integrator, dt=dt), simulation.DEFAULT_OUTPUT_DT,
                                    duration, FIDELITY.get(scene_name, "auto"), OUTPUTS.get(scene_name, THESIS_OUTPUTS),
                                    seed, "thesis")
        prepared.append(simulation._prepared(run, seed, record=False))
    run, model = prepared[0].run, prepared[0].model
    x0 = np.ascontiguousarray(np.stack([p.model.initial_state for p in prepared], axis=1))
    c = np.ascontiguousarray(np.stack([p.model.constants for p in prepared], axis=1))
    parameters = np.ascontiguousarray(np.stack([p.instruments.parameters for p in prepared], axis=2))
    noise = np.ascontiguousarray(np.stack([p.instruments.noise for p in prepared], axis=2))
    n = run.n_steps
    trajectory, inputs = np.zeros((n, N_STATES, lanes)), np.zeros((n, N_INPUTS, lanes))
    workspace = Workspace(N_STATES, lanes)
    record_trajectory(INTEGRATORS[run.solver.integrator], x0.copy(), c, model.levels, model.position_table,
                      model.force_table, model.active, model.pairs, run.dt, run.speed_every, run.position_every,
                      parameters, np.zeros((ins.N_INSTRUMENTS, ins.STATE_ROW, lanes)), noise,
                      np.zeros((N_MEMORY, lanes)), *workspace.arrays(), trajectory, inputs)
    return SimpleNamespace(run=run, model=model, prepared=prepared, x0=x0, c=c, parameters=parameters, noise=noise,
                           trajectory=trajectory, inputs=inputs, n=n, lanes=lanes)


def run_loop_cpu(group: SimpleNamespace, repeats: int) -> float:
    """Median CPU seconds of the group through :func:`twin.engine.group.solve_group` (run_loop; after a warm-up)."""
    run = group.run

    def once():
        start = time.process_time()
        solve_group([p.model for p in group.prepared], [p.instruments for p in group.prepared], n_steps=group.n,
                    dt=run.dt, speed_every=run.speed_every, position_every=run.position_every, output_every=0,
                    jacobian_every=run.position_every, method=INTEGRATORS[run.solver.integrator],
                    tolerance=group.prepared[0].tolerance)
        return time.process_time() - start

    once()
    return statistics.median(once() for _ in range(repeats))


def profile(scene_name: str, duration: float, repeats: int, integrator: str, dt: float | None, lanes: int) -> None:
    group = recorded_group(scene_name, duration, integrator, dt, lanes)
    run, model, trajectory, n = group.run, group.model, group.trajectory, group.n
    method = INTEGRATORS[run.solver.integrator]
    c, ft, levels, x0 = group.c, model.force_table, model.levels, group.x0
    u = np.ascontiguousarray(group.inputs[-1])
    output = np.zeros((n // run.output_every + 1, N_SIGNALS, lanes))
    tolerance = group.prepared[0].tolerance
    check_every = loop.LOCAL_ERROR_EVERY * run.position_every

    def fresh():
        """A new workspace and instrument state for each part (the parts must not share them)."""
        vectors, w, matrices, cache, small = Workspace(N_STATES, lanes).arrays()
        return SimpleNamespace(vectors=vectors, w=w, matrices=matrices, cache=cache, small=small,
                               states=np.zeros((ins.N_INSTRUMENTS, ins.STATE_ROW, lanes)))

    a, b, d, e, f = fresh(), fresh(), fresh(), fresh(), fresh()
    empty = median_cpu(empty_pass, (trajectory,), repeats)
    total = run_loop_cpu(group, repeats)
    parts = [  # (name, function, args, calls per run)
        ("integrator step (all right-hand sides)", step_pass,
         (method, trajectory, c, u, levels, ft, model.active, model.pairs, run.dt, a.vectors, a.w, a.matrices,
          a.cache, a.small), n),
        ("instruments advanced after every step", instruments_pass,
         (trajectory, x0.copy(), c, levels, ft, run.dt, run.position_every, group.parameters, b.states, b.w), n),
        ("divergence guard", guard_pass, (trajectory, c, d.w, levels), n),
        ("local-error check (3 extra steps)", local_error_pass,
         (method, trajectory, c, u, levels, ft, model.active, model.pairs, run.dt, check_every, tolerance, e.vectors,
          e.w, e.matrices, e.cache, e.small), n // check_every),
        ("acquisition instant", samples_pass,
         (trajectory, x0.copy(), c, levels, model.position_table, ft, run.dt, run.position_every, group.parameters,
          f.states, group.noise, f.w, output, 0), n // run.position_every),
        ("drive speed-loop instant", samples_pass,
         (trajectory, x0.copy(), c, levels, model.position_table, ft, run.dt, run.speed_every, group.parameters,
          f.states, group.noise, f.w, output, 1), n // run.speed_every),
        ("recording one output row", samples_pass,
         (trajectory, x0.copy(), c, levels, model.position_table, ft, run.dt, run.output_every, group.parameters,
          f.states, group.noise, f.w, output, 2), n // run.output_every),
    ]
    print(f"\n'{scene_name}' ({run.fidelity.level('encoders')} encoders, screw axial "
          f"{run.fidelity.level('screw_axial')}, {model.active.size} states), {lanes} lanes, {run.scene.duration:g} s "
          f"= {n} steps of {run.solver.integrator} at {run.dt * 1e6:g} us; run_loop {total:.3f} s CPU "
          f"({1e9 * total / n:.0f} ns per step, {1e9 * total / n / lanes:.0f} per lane)")
    print(f"{'part':42s} {'ns/call':>9s} {'calls':>8s} {'ns/step':>8s} {'/lane':>7s} {'share':>7s}")
    accounted = 0.0
    for name, function, args, calls in parts:
        cpu = max(median_cpu(function, args, repeats) - empty * calls / n, 0.0)
        accounted += cpu
        print(f"{name:42s} {1e9 * cpu / calls:9.0f} {calls:8d} {1e9 * cpu / n:8.1f} {1e9 * cpu / n / lanes:7.1f} "
              f"{100 * cpu / total:6.1f} %")
    rest = total - accounted
    print(f"{'rest of run_loop (bookkeeping, call overhead)':42s} {'':9s} {'':8s} {1e9 * rest / n:8.1f} "
          f"{1e9 * rest / n / lanes:7.1f} {100 * rest / total:6.1f} %")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--lanes", type=int, default=DEFAULT_LANES)
    parser.add_argument("--quick", action="store_true", help="0.5 s of each scene, one pass (seconds)")
    args = parser.parse_args()
    duration, repeats = (0.5, 1) if args.quick else (10.0, args.repeats)
    header("step costs: the compiled loop's parts per integration step, for a lane group", args.quick)
    for scene_name, integrator, dt in CASES:
        profile(scene_name, duration, repeats, integrator, dt, args.lanes)


if __name__ == "__main__":
    main()
