"""Per-step cost of everything in the compiled loop that is not the right-hand side, part by part.

A compiled harness records the state after every step of a run (the nominal scene at full fidelity, and the
ds1 data set at the thesis campaign's automatic fidelity), then calls each part of
:func:`twin.engine.loop.run_loop` over that trajectory, in compiled loops: the integrator step, the divergence
guard, the instruments' advance, the acquisition and speed-loop instants, the recording of a row and the
local-error check. Each figure is the median of ``--repeats`` passes less an empty pass over the same
trajectory, per call and per integration step (calls per run / steps). ``run_loop`` itself is timed on the
same model; the parts' sum against it shows what the harness misses (the loop's own bookkeeping).
CPU time (``time.process_time``); print the load average with it: on a shared machine use the shares.

Usage: python benchmarks/step_costs.py [--repeats N] [--quick]
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
from twin.engine.instrumentation import build_instruments, instrument_levels
from twin.engine.integrators import INTEGRATORS, WORK_VECTORS, step
from twin.engine.model import build_model
from twin.engine.reference import local_error_tolerance
from twin.engine.solver_choice import IMPLICIT_METHOD
from twin.layout import N_INPUTS, N_MEMORY, N_SIGNALS, M
from twin.parameters import load_parameters

#: The nominal scene as `twin.simulate` runs it by default (every output: full fidelity); any other scene (the
#: thesis data sets) as a thesis campaign runs it (its outputs set the automatic fidelity).
OUTPUTS = {"nominal": None}
FIDELITY = {"nominal": "full"}
#: The methods profiled, each at its step: the default, and the implicit branch of the opt-in automatic integrator
#: (twin.engine.solver_choice) at the bench's drive period.
METHODS = ((simulation.DEFAULT_INTEGRATOR, simulation.DEFAULT_DT),
           (IMPLICIT_METHOD, load_parameters().value("drive.speed_loop_sample_time")))


@numba.njit
def record_trajectory(method, x, c, position_table, force_table, poly, active, pairs, dt, speed_every,
                      position_every, rows, levels, lookback, noise, trajectory, inputs):
    """run_loop's sequence of samples, steps and instrument advances (no output, no checks), recording the state
    after every step (row ``k`` is the state at ``(k + 1) dt``) and the held inputs of that step."""
    work = np.zeros((WORK_VECTORS + x.shape[0], x.shape[0]))
    u = np.zeros(N_INPUTS)
    memory = np.zeros(N_MEMORY)
    state = np.zeros((ins.N_INSTRUMENTS, ins.STATE_ROW))
    loop.controller_init(memory, u, state, rows, levels, x, c, force_table, poly)
    for k in range(trajectory.shape[0]):
        t = k * dt
        if k % position_every == 0:
            loop.acquisition_sample(t, x, c, u, memory, state, rows, levels, noise, position_table, force_table,
                                    poly, position_every * dt)
        if k % speed_every == 0:
            loop.speed_sample(x, c, u, memory, rows, levels, speed_every * dt)
        step(method, t, x, dt, c, u, force_table, poly, work, False, active, pairs)
        trajectory[k] = x
        inputs[k] = u
        loop.instruments_advance(t + dt, dt, x, c, state, rows, levels, lookback,
                                 (position_every - (k + 1) % position_every) % position_every, force_table)
    return u


@numba.njit
def empty_pass(trajectory):
    total = 0.0
    for k in range(trajectory.shape[0]):
        total += trajectory[k, 0]
    return total


@numba.njit
def step_pass(method, trajectory, c, u, force_table, poly, active, pairs, dt):
    work = np.zeros((WORK_VECTORS + trajectory.shape[1], trajectory.shape[1]))
    x = np.zeros(trajectory.shape[1])
    for k in range(trajectory.shape[0]):
        x[:] = trajectory[k]
        step(method, k * dt, x, dt, c, u, force_table, poly, work, False, active, pairs)
    return x


@numba.njit
def guard_pass(trajectory, c):
    codes = 0
    for k in range(trajectory.shape[0]):
        codes += loop.guard(trajectory[k], c)
    return codes


@numba.njit
def instruments_pass(trajectory, x0, c, force_table, poly, dt, position_every, rows, levels, lookback):
    state = np.zeros((ins.N_INSTRUMENTS, ins.STATE_ROW))
    memory = np.zeros(N_MEMORY)
    u = np.zeros(N_INPUTS)
    loop.controller_init(memory, u, state, rows, levels, x0, c, force_table, poly)
    for k in range(trajectory.shape[0]):
        loop.instruments_advance((k + 1) * dt, dt, trajectory[k], c, state, rows, levels, lookback,
                                 (position_every - (k + 1) % position_every) % position_every, force_table)
    return state


@numba.njit
def samples_pass(trajectory, x0, c, position_table, force_table, poly, dt, every, rows, levels, noise, output, part):
    """Part 0: acquisition instants, 1: speed-loop instants, 2: output rows, each at every ``every``-th state."""
    state = np.zeros((ins.N_INSTRUMENTS, ins.STATE_ROW))
    memory = np.zeros(N_MEMORY)
    u = np.zeros(N_INPUTS)
    loop.controller_init(memory, u, state, rows, levels, x0, c, force_table, poly)
    n = 0
    for k in range(0, trajectory.shape[0], every):
        x = trajectory[k]
        if part == 0:
            memory[M.SAMPLES] = 0.0  # the same noise row each time: the cost does not depend on it
            loop.acquisition_sample(k * dt, x, c, u, memory, state, rows, levels, noise, position_table,
                                    force_table, poly, every * dt)
        elif part == 1:
            loop.speed_sample(x, c, u, memory, rows, levels, every * dt)
        else:
            loop.record(output[n], k * dt, x, c, u, memory, force_table, poly)
        n += 1
    return n


@numba.njit
def local_error_pass(method, trajectory, c, u, force_table, poly, active, pairs, dt, every, tolerance):
    work = np.zeros((WORK_VECTORS + trajectory.shape[1], trajectory.shape[1]))
    scratch = np.zeros((2, trajectory.shape[1]))
    worst = 0.0
    for k in range(0, trajectory.shape[0], every):
        worst = max(worst, loop.local_error(method, k * dt, trajectory[k], dt, c, u, force_table, poly, work,
                                            scratch, tolerance, active, pairs))
    return worst


def median_cpu(function, args, repeats) -> float:
    function(*args)  # compile
    times = []
    for _ in range(repeats):
        start = time.process_time()
        function(*args)
        times.append(time.process_time() - start)
    return statistics.median(times)


def recorded_run(scene_name: str, duration: float, integrator: str, dt: float) -> SimpleNamespace:
    """One run of ``scene_name`` (fidelity and outputs as in :data:`FIDELITY`, :data:`OUTPUTS`), its model and
    instruments, and the state and held inputs after every step (``trajectory``, ``inputs``, one row per step)."""
    run = simulation._validated(scene_name, None, integrator, dt, simulation.DEFAULT_OUTPUT_DT, duration,
                                FIDELITY.get(scene_name, "auto"), OUTPUTS.get(scene_name, THESIS_OUTPUTS),
                                None, "thesis", 1e-10)
    model = build_model(run.scene, run.params, run.fidelity, curvature="thesis")
    n = int(round(run.scene.duration / run.dt))
    instruments = build_instruments(
        run.params.values(), run.scene.condition("room_temperature"), instrument_levels(run.fidelity),
        np.random.default_rng(0), n // run.position_every + 1, run.dt,
        torque_meter_refresh=run.fidelity.level("torque_meter_refresh") == "modelled")
    x0 = model.initial_state
    trajectory, inputs = np.zeros((n, x0.size)), np.zeros((n, N_INPUTS))
    record_trajectory(INTEGRATORS[integrator], x0.copy(), model.constants, model.position_table, model.force_table,
                      model.stiffness_poly, model.active, model.pairs, run.dt, run.speed_every, run.position_every,
                      instruments.parameters, instruments.levels, instruments.lookback, instruments.noise,
                      trajectory, inputs)
    return SimpleNamespace(run=run, model=model, instruments=instruments, trajectory=trajectory, inputs=inputs, n=n)


def run_loop_cpu(recorded: SimpleNamespace, integrator: str, repeats: int) -> float:
    """Median CPU seconds of :func:`twin.engine.loop.run_loop` over the recorded run's scene (after a warm-up)."""
    run, model, instruments = recorded.run, recorded.model, recorded.instruments

    def once():
        memory = np.zeros(N_MEMORY)
        out = np.full((recorded.n // run.output_every + 1, N_SIGNALS), np.nan)
        start = time.process_time()
        loop.run_loop(model.initial_state.copy(), model.constants, model.position_table, model.force_table,
                      model.stiffness_poly, model.active, model.pairs, recorded.n, run.dt, run.speed_every,
                      run.position_every, run.output_every, run.position_every, INTEGRATORS[integrator],
                      instruments.parameters, instruments.levels, instruments.lookback, instruments.noise, memory,
                      out, local_error_tolerance(), 0.0, 0)
        return time.process_time() - start

    once()
    return statistics.median(once() for _ in range(repeats))


def profile(scene_name: str, duration: float, repeats: int, integrator: str, dt: float) -> None:
    method = INTEGRATORS[integrator]
    recorded = recorded_run(scene_name, duration, integrator, dt)
    run, model, instruments, trajectory, n = (recorded.run, recorded.model, recorded.instruments,
                                              recorded.trajectory, recorded.n)
    c, ft, poly, x0 = model.constants, model.force_table, model.stiffness_poly, model.initial_state
    rows, levels, lookback, noise = (instruments.parameters, instruments.levels, instruments.lookback,
                                     instruments.noise)
    u = recorded.inputs[-1]
    output = np.zeros((n // run.output_every + 1, N_SIGNALS))
    tolerance = local_error_tolerance()
    check_every = loop.LOCAL_ERROR_EVERY * run.position_every
    empty = median_cpu(empty_pass, (trajectory,), repeats)
    total = run_loop_cpu(recorded, integrator, repeats)
    parts = [  # (name, function, args, calls per run)
        ("integrator step (all right-hand sides)", step_pass,
         (method, trajectory, c, u, ft, poly, model.active, model.pairs, run.dt), n),
        ("instruments advanced after every step", instruments_pass,
         (trajectory, x0, c, ft, poly, run.dt, run.position_every, rows, levels, lookback), n),
        ("divergence guard", guard_pass, (trajectory, c), n),
        ("local-error check (3 extra steps)", local_error_pass,
         (method, trajectory, c, u, ft, poly, model.active, model.pairs, run.dt, check_every, tolerance),
         n // check_every),
        ("acquisition instant", samples_pass,
         (trajectory, x0, c, model.position_table, ft, poly, run.dt, run.position_every, rows, levels, noise,
          output, 0), n // run.position_every),
        ("drive speed-loop instant", samples_pass,
         (trajectory, x0, c, model.position_table, ft, poly, run.dt, run.speed_every, rows, levels, noise, output,
          1), n // run.speed_every),
        ("recording one output row", samples_pass,
         (trajectory, x0, c, model.position_table, ft, poly, run.dt, run.output_every, rows, levels, noise,
          output, 2), n // run.output_every),
    ]
    print(f"\n'{scene_name}' ({run.fidelity.level('encoders')} encoders, {model.active.size} states), "
          f"{run.scene.duration:g} s = {n} steps of {integrator} at {run.dt * 1e6:g} us; run_loop {total:.3f} s CPU "
          f"({1e9 * total / n:.0f} ns per step)")
    print(f"{'part':42s} {'ns/call':>9s} {'calls':>8s} {'ns/step':>8s} {'share':>7s}")
    accounted = 0.0
    for name, function, args, calls in parts:
        cpu = max(median_cpu(function, args, repeats) - empty * calls / n, 0.0)
        accounted += cpu
        print(f"{name:42s} {1e9 * cpu / calls:9.0f} {calls:8d} {1e9 * cpu / n:8.1f} {100 * cpu / total:6.1f} %")
    rest = total - accounted
    print(f"{'rest of run_loop (bookkeeping, call overhead)':42s} {'':9s} {'':8s} {1e9 * rest / n:8.1f} "
          f"{100 * rest / total:6.1f} %")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="0.5 s of each scene, one pass (seconds)")
    args = parser.parse_args()
    duration, repeats = (0.5, 1) if args.quick else (10.0, args.repeats)
    header("step costs: the compiled loop's parts per integration step", args.quick)
    for integrator, dt in METHODS:
        for scene_name in ("nominal", "ds1"):
            profile(scene_name, duration, repeats, integrator, dt)


if __name__ == "__main__":
    main()
