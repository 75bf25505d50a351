"""Second baseline: python-control's ``input_output_response`` on the part of the model it can represent.

python-control cannot connect the continuous plant to the bench's discrete controllers in one
system ("incompatible timebases", see docs/accuracy.md), so the baseline is the continuous plant
alone (analog current loop, motor, torsional chain, ball screw, nuts) driven open-loop by a
current-demand step, wrapped as a ``control.nlsys`` around the same right-hand side. The same
open-loop problem is integrated by the compiled loop's integrators and by a tight ``scipy_radau``
solution, and all are timed and compared.
"""

from __future__ import annotations

import time

import control
import numba
import numpy as np
from scipy.integrate import solve_ivp

import twin
from twin.engine.integrators import INTEGRATORS, Workspace, step
from twin.engine.model import build_model
from twin.engine.plant import rhs, work_rows
from twin.engine.reference import absolute_tolerance
from twin.fidelity import full_plant, resolve_fidelity
from twin.layout import N_INPUTS, N_STATES, S, U

# The plant alone: full detail, no load system, no sensors in the way.
OPEN_LOOP_FIDELITY = full_plant("absent")

CURRENT_STEP = 0.5  # A of current demand: ~1.9 N m of motor torque, accelerating the unloaded screw
DURATION = 0.05     # s


@numba.njit(cache=True)
def _integrate(method, x, c, u, levels, force_table, active, pairs, dt, n_steps, record_every, out, vectors, w,
               matrices, cache, small):
    """``n_steps`` steps of one run as a one-lane group (``[row, 1]`` arrays), the master nut's position every
    ``record_every`` steps into ``out``."""
    for k in range(n_steps):
        if k % record_every == 0:
            out[k // record_every] = x[S.NUT1_POSITION, 0]
        step(method, k * dt, x, dt, c, u, levels, force_table, vectors, w, matrices, cache, small, k == 0, active,
             pairs)
    out[n_steps // record_every] = x[S.NUT1_POSITION, 0]


def compare(dt: float = 1.5625e-5, output_dt: float = 1e-3) -> list[dict]:
    """Wall time and max nut-position error of each way of solving the open-loop problem."""
    # The current step from rest at the preloaded equilibrium: the open-loop problem the baseline compares
    # solvers on. The thesis start (nuts unloaded at t = 0) would add the springs' loading transient to it.
    scene = twin.load_scene("ds5").with_conditions({"zero_procedure": "preloaded"}).with_duration(DURATION)
    params = twin.load_parameters()
    model = build_model(scene, params, resolve_fidelity(scene, params, OPEN_LOOP_FIDELITY))
    # one run as a one-lane group of the engine: every array [row, lane]
    c, levels, force_table = model.constants.reshape(-1, 1), model.levels, model.force_table
    inputs = np.zeros((N_INPUTS, 1))
    inputs[U.CURRENT_DEMAND] = CURRENT_STEP
    times = np.arange(0.0, DURATION + 0.5 * output_dt, output_dt)
    derivative = np.zeros((N_STATES, 1))
    w = work_rows(1)
    probe = model.initial_state.copy().reshape(-1, 1)
    active = model.active
    y0 = model.initial_state[active]
    nut_index = int(np.flatnonzero(active == S.NUT1_POSITION)[0])

    def f(t, y):
        probe[active, 0] = y
        rhs(t, probe, c, inputs, levels, force_table, derivative, w)
        return derivative[active, 0]

    start = time.perf_counter()
    reference = solve_ivp(f, (0.0, DURATION), y0, method="Radau", t_eval=times, rtol=1e-10,
                          atol=absolute_tolerance(1.0)[active])
    results = [{"method": "scipy_radau (reference)", "wall_time": time.perf_counter() - start, "error": 0.0}]
    nut = reference.y[nut_index]

    system = control.nlsys(lambda t, y, u, params: f(t, y), None, inputs=1, states=y0.size, outputs=y0.size,
                           name="bench_plant")
    start = time.perf_counter()
    response = control.input_output_response(system, times, np.zeros(times.size), X0=y0,
                                             solve_ivp_kwargs={"rtol": 1e-6})
    results.append({"method": "control.input_output_response (RK45, rtol 1e-6)",
                    "wall_time": time.perf_counter() - start,
                    "error": float(np.max(np.abs(response.states[nut_index] - nut)))})

    every = int(round(output_dt / dt))
    n_steps = int(round(DURATION / dt))
    for method in ("rk4", "semi_implicit_euler"):
        out = np.zeros(n_steps // every + 1)
        vectors, work, matrices, cache, small = Workspace(N_STATES, 1).arrays()
        arguments = (c, inputs, levels, force_table, active, model.pairs, dt)
        workspace = (vectors[:6], work, matrices, cache, small)
        _integrate(INTEGRATORS[method], model.initial_state.copy().reshape(-1, 1), *arguments, 1, every, out,
                   *workspace)
        start = time.perf_counter()
        _integrate(INTEGRATORS[method], model.initial_state.copy().reshape(-1, 1), *arguments, n_steps, every, out,
                   *workspace)
        results.append({"method": f"compiled {method} (dt {dt:g} s)", "wall_time": time.perf_counter() - start,
                        "error": float(np.max(np.abs(out - nut)))})
    return results
