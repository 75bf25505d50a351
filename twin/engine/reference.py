"""Reference path: the same right-hand side and sampled-data logic, integrated by scipy's ``solve_ivp``.

It serves two purposes (docs/accuracy.md): it is the accuracy reference of the
work-precision study, and it is the baseline a user of the scipy stack would
write. The integration restarts at every drive (speed-loop) sample instant,
where the digital loops update their held outputs exactly as in the compiled
loop (:func:`twin.engine.loop.acquisition_sample`, :func:`twin.engine.loop.speed_sample`).

Instruments are stepped at the sample instants only. That is exact for what the
controllers read at the ``quantized`` level of the encoders and the resolver
(their counts are functions of position, not of path) and for every ``ideal``
instrument; analog channels at the ``quantized``/``full`` levels and the
encoders' period-method speed depend on the stepping grid, so compare those
against the compiled loop with care. The analog conditioners' lag coefficients were computed for the instruments'
integration step: pass instruments built for the drive period.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from twin.components import COMPONENTS
from twin.engine.instrumentation import N_INSTRUMENTS, STATE_ROW, instruments_advance
from twin.engine.loop import acquisition_sample, controller_init, guard, record, speed_sample
from twin.engine.plant import internal_forces, measurands, rhs, work_rows
from twin.layout import N_INPUTS, STATUS_NONFINITE, STATUS_OK, STATUS_OUT_OF_BOUNDS, STATUS_SOLVER_FAILED, S

METHODS = {"scipy_radau": "Radau", "scipy_lsoda": "LSODA", "scipy_bdf": "BDF", "scipy_rk45": "RK45"}

# Absolute tolerance per state (a component's of twin.components from its module), relative to the size of what each
# state resolves:
# positions to 1e-13 m (1e-7 of a micrometre feature), angles to 1e-12 rad, speeds to 1e-10,
# currents to 1e-10 A, temperature to 1e-8 K, spool to 1e-12, pressures to 1e-4 Pa.
_ATOL_BY_STATE = {
    S.CURRENT: 1e-10, S.WINDING_TEMP: 1e-8, S.SCREW_ANGLE: 1e-12,
    S.SCREW_SPEED: 1e-10, S.SCREW_AXIAL: 1e-13, S.SCREW_AXIAL_SPEED: 1e-10, S.NUT1_POSITION: 1e-13,
    S.NUT1_SPEED: 1e-10, S.NUT1_ANGLE: 1e-12, S.NUT1_ANGULAR_SPEED: 1e-10, S.NUT2_POSITION: 1e-13,
    S.NUT2_SPEED: 1e-10, S.NUT2_ANGLE: 1e-12, S.NUT2_ANGULAR_SPEED: 1e-10, S.HALL_CURRENT: 1e-10,
    S.CURRENT_PI: 1e-8, S.SPOOL_POSITION: 1e-12, S.SPOOL_SPEED: 1e-9, S.CHAMBER1_PRESSURE: 1e-4,
    S.CHAMBER2_PRESSURE: 1e-4, S.PISTON_POSITION: 1e-13, S.PISTON_SPEED: 1e-10,
    **{state: tolerance for component in COMPONENTS for state, tolerance in component.ABSOLUTE_TOLERANCES.items()},
}


def absolute_tolerance(scale: float) -> np.ndarray:
    """Absolute tolerances of every state (layout ``S``), multiplied by ``scale`` (1 at ``rtol`` = 1e-10)."""
    return np.array([_ATOL_BY_STATE[state] for state in S]) * scale


LOCAL_ERROR_SCALE = 1e8  # guard tolerance = reference atol x 1e8: 10 um, 1e-4 rad, 1e-2 m/s, 1e-2 A, 1e4 Pa


def local_error_tolerance() -> np.ndarray:
    """Absolute tolerances of the compiled loop's finite-but-wrong guard (:func:`twin.engine.loop.local_error`)."""
    return absolute_tolerance(LOCAL_ERROR_SCALE)


def run_reference(model, instruments, n_speed_samples: int, speed_ts: float, position_ratio: int, output_ratio: int,
                  output: np.ndarray, memory: np.ndarray, method: str, rtol: float, x: np.ndarray):
    """Integrate sample interval by sample interval with ``solve_ivp`` from state ``x`` (updated in place); one
    run, as a one-lane group of the compiled loop's functions.

    Returns
    -------
    (status, bound_code, t_reached, rows_written, reason, stats)
        ``stats``: ``nfev``, ``njev``, ``nlu``, ``steps`` and ``min_step`` [s] over the run.
    """
    c = model.constants.reshape(-1, 1)
    levels, force_table = model.levels, model.force_table
    lane_x = x.reshape(-1, 1)  # the same memory: x is updated through it
    lane_memory = memory.reshape(-1, 1)
    u = np.zeros((N_INPUTS, 1))
    w = work_rows(1)
    parameters = np.ascontiguousarray(instruments.parameters[:, :, None])
    noise = np.ascontiguousarray(instruments.noise[:, :, None])
    states = np.zeros((N_INSTRUMENTS, STATE_ROW, 1))
    alive = np.ones(1, dtype=np.bool_)
    controller_init(0.0, lane_x, c, u, w, levels, lane_memory, parameters, states, force_table)
    derivative = np.zeros_like(lane_x)
    active = model.active
    probe = lane_x.copy()  # the states the fidelity removed keep their values here

    def f(t, y):
        probe[active, 0] = y
        rhs(t, probe, c, u, levels, force_table, derivative, w)
        return derivative[active, 0]

    atol = absolute_tolerance(rtol / 1e-10)[active]
    stats = {"nfev": 0, "njev": 0, "nlu": 0, "steps": 0, "min_step": np.inf}
    rows = 0
    for j in range(n_speed_samples + 1):
        t = j * speed_ts
        if j % position_ratio == 0 or j % output_ratio == 0:
            internal_forces(t, lane_x, c, w, 1, levels, force_table)
        if j % position_ratio == 0:
            acquisition_sample(t, lane_x, c, u, w, levels, lane_memory, parameters, states, noise,
                               model.position_table, force_table, position_ratio * speed_ts, alive)
        speed_sample(lane_x, c, u, levels, lane_memory, parameters, speed_ts, alive)
        if j % output_ratio == 0:
            record(output[rows], t, lane_x, c, u, w, 0, lane_memory, levels, force_table)
            rows += 1
        if j == n_speed_samples:
            break
        solution = solve_ivp(f, (t, t + speed_ts), x[active], method=method, rtol=rtol, atol=atol)
        stats["nfev"] += int(solution.nfev)
        stats["njev"] += int(solution.njev)
        stats["nlu"] += int(solution.nlu)
        stats["steps"] += solution.t.size - 1
        if solution.t.size > 1:
            stats["min_step"] = min(stats["min_step"], float(np.min(np.diff(solution.t))))
        if not solution.success:
            return STATUS_SOLVER_FAILED, 0, t, rows, f"solve_ivp ({method}): {solution.message}", stats
        x[active] = solution.y[:, -1]
        x[S.SCREW_AXIAL:S.SCREW_AXIAL_SPEED + 1] = probe[S.SCREW_AXIAL:S.SCREW_AXIAL_SPEED + 1, 0]
        code = guard(lane_x, c, w, 0, levels)
        if code != 0:
            status = STATUS_NONFINITE if code == 1 else STATUS_OUT_OF_BOUNDS
            return status, code, t + speed_ts, rows, "", stats
        measurands(t + speed_ts, lane_x, c, w, 1, levels, force_table)
        instruments_advance(t + speed_ts, speed_ts, lane_x, c, w, levels, parameters, states,
                            (position_ratio - (j + 1) % position_ratio) % position_ratio)
    return STATUS_OK, 0, n_speed_samples * speed_ts, rows, "", stats
