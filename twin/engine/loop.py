"""The compiled multi-rate time loop: plant integration, digital loops, recording, divergence guard.

Controller sample instants fall on integration-step boundaries (the step
divides both sample periods). Between samples the controller outputs are held
(zero-order hold). No Python runs inside the loop.
"""

import math

import numba
import numpy as np

from twin.control.discrete import pi_step
from twin.engine.integrators import step
from twin.engine.layout import (
    N_INPUTS,
    PNEUMATICS_FULL,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_OUT_OF_BOUNDS,
    K,
    S,
    Signal,
    U,
)
from twin.engine.plant import internal_forces
from twin.physics.ball_screw import contact_geometry
from twin.physics.pneumatics import hysteresis_play
from twin.scenes.profiles import profile_value


@numba.njit(cache=True)
def quantize_floor(value, resolution):
    """Incremental-encoder reading: the count floor(x/res) times res; ``resolution <= 0`` is ideal."""
    if resolution <= 0.0:
        return value
    return math.floor(value / resolution) * resolution


@numba.njit(cache=True)
def quantize_round(value, lsb, full_scale):
    """Converter with mid-tread rounding and saturation at +/-full_scale; ``lsb <= 0`` is ideal."""
    value = min(max(value, -full_scale), full_scale)
    if lsb <= 0.0:
        return value
    return round(value / lsb) * lsb


@numba.njit(cache=True)
def guard(x, c):
    """Divergence guard: 0 if the state is finite and physical, else a bound code (layout.BOUND_REASONS)."""
    total = 0.0
    for j in range(x.shape[0]):
        total += x[j]
    if not math.isfinite(total):
        return 1
    if abs(x[S.NUT1_POSITION]) > c[K.STROKE_LIMIT]:
        return 2
    if abs(x[S.REDUCER_SPEED] * c[K.RATIO]) > c[K.MAX_MOTOR_SPEED]:
        return 3
    if abs(x[S.CURRENT]) > 5.0 * c[K.MAX_CURRENT]:
        return 4
    if x[S.WINDING_TEMP] > c[K.MAX_TEMPERATURE]:
        return 5
    arm = c[K.LEAD_ARM]
    for pos, ang in ((S.NUT1_POSITION, S.NUT1_ANGLE), (S.NUT2_POSITION, S.NUT2_ANGLE)):
        dx = x[S.SCREW_AXIAL] + arm * (x[S.SCREW_ANGLE] - x[ang]) - x[pos]
        gap = abs(dx) - 0.5 * c[K.BACKLASH]
        if gap > 0.0:
            approach, _ = contact_geometry(gap * c[K.COS_HELIX], c[K.CENTRE_DISTANCE], c[K.CONTACT_ANGLE_0])
            if approach > c[K.MAX_NORMAL_APPROACH]:
                return 6
    if int(c[K.PNEUMATICS]) == PNEUMATICS_FULL:
        for chamber in (S.CHAMBER1_PRESSURE, S.CHAMBER2_PRESSURE):
            if x[chamber] <= 0.0 or x[chamber] > 2.0 * c[K.P_SUPPLY]:
                return 7
    return 0


@numba.njit(cache=True)
def record(row, t, x, c, u, demand, speed_command, force_table, stiffness_poly):
    torque, f1, f2, preload, external, _, _ = internal_forces(t, x, c, force_table, stiffness_poly)
    row[Signal.POSITION_DEMAND] = demand
    row[Signal.NUT1_POSITION] = x[S.NUT1_POSITION] - c[K.NUT1_ZERO]
    row[Signal.NUT2_POSITION] = x[S.NUT2_POSITION] - c[K.NUT1_ZERO]
    row[Signal.SCREW_ANGLE] = x[S.SCREW_ANGLE]
    row[Signal.SCREW_EQUIVALENT_POSITION] = c[K.LEAD_ARM] * (x[S.SCREW_ANGLE] - c[K.SCREW_ANGLE_ZERO])
    row[Signal.SCREW_AXIAL_POSITION] = x[S.SCREW_AXIAL]
    row[Signal.MOTOR_CURRENT] = x[S.CURRENT]
    row[Signal.MOTOR_TORQUE] = c[K.TORQUE_CONSTANT] * x[S.CURRENT]
    row[Signal.MOTOR_SPEED] = c[K.RATIO] * x[S.REDUCER_SPEED]
    row[Signal.WINDING_TEMPERATURE] = x[S.WINDING_TEMP]
    row[Signal.PRELOAD_FORCE] = preload
    row[Signal.EXTERNAL_FORCE] = external
    row[Signal.TRANSMITTED_TORQUE] = torque
    row[Signal.NUT1_CONTACT_FORCE] = f1
    row[Signal.NUT2_CONTACT_FORCE] = f2
    row[Signal.SPEED_COMMAND] = speed_command
    row[Signal.CURRENT_DEMAND] = u[U.CURRENT_DEMAND]
    row[Signal.NUT1_SPEED] = x[S.NUT1_SPEED]
    row[Signal.FORCE_DEMAND] = profile_value(force_table, t)
    if int(c[K.PNEUMATICS]) == PNEUMATICS_FULL:
        row[Signal.CHAMBER1_PRESSURE] = x[S.CHAMBER1_PRESSURE]
        row[Signal.CHAMBER2_PRESSURE] = x[S.CHAMBER2_PRESSURE]
        row[Signal.VALVE_COMMAND] = u[U.VALVE_COMMAND]
        row[Signal.PISTON_POSITION] = x[S.PISTON_POSITION]


@numba.njit(cache=True)
def force_loop(t, x, c, u, integral, sample_time, force_table, stiffness_poly):
    """Digital PI force loop of the cRIO (Sec. 9.3): load-cell reading -> valve command.

    The PI output is a deviation from the valve's mid position, limited to the
    command range; it goes through the output D/A and the valve's hysteresis.
    Returns the new PI integral; the effective command is written to ``u``.
    """
    measured = internal_forces(t, x, c, force_table, stiffness_poly)[4]
    half_span = 0.5 * (c[K.VALVE_MAX] - c[K.VALVE_MIN])
    deviation, integral = pi_step(profile_value(force_table, t) - measured, integral, c[K.FORCE_KP], c[K.FORCE_KI],
                                  sample_time, half_span)
    command = quantize_round(deviation, c[K.VALVE_COMMAND_LSB], half_span) + c[K.VALVE_MID]
    u[U.VALVE_COMMAND] = hysteresis_play(command, u[U.VALVE_COMMAND], c[K.VALVE_HYSTERESIS], c[K.VALVE_MIN],
                                         c[K.VALVE_MAX])
    return integral


@numba.njit(cache=True)
def run_loop(x, c, position_table, force_table, stiffness_poly, n_steps, dt, speed_every, position_every,
             output_every, method, output):
    """Integrate ``n_steps`` steps of size ``dt`` from state ``x`` (modified in place).

    Parameters
    ----------
    speed_every, position_every, output_every : int
        Speed-loop, position-loop (= acquisition) and output decimation, in steps.
    method : int
        Integrator code (:mod:`twin.engine.integrators`).
    output : 2-D array
        ``(n_steps // output_every + 1, N_SIGNALS)`` buffer, filled row by row.

    Returns
    -------
    (status, bound_code, steps_done, rows_written, feature_sum, feature_samples)
        The feature sums accumulate Eq. 9.12 on true signals at the position-loop
        (acquisition) instants: ``|x_n1 - x_n1(0) - p (theta_s - theta_s(0)) / 2 pi|``.
    """
    work = np.zeros((5, x.shape[0]))
    u = np.zeros(N_INPUTS)
    u[U.VALVE_COMMAND] = c[K.VALVE_MID]
    pneumatics = int(c[K.PNEUMATICS]) == PNEUMATICS_FULL
    speed_ts = speed_every * dt
    position_ts = position_every * dt
    position_integral = 0.0
    speed_integral = 0.0
    force_integral = 0.0
    speed_command = 0.0
    demand = profile_value(position_table, 0.0)
    lsb = c[K.SPEED_COMMAND_LSB]
    previous_angle = quantize_floor(c[K.RATIO] * x[S.REDUCER_ANGLE], c[K.RESOLVER_RESOLUTION])
    feature_sum = 0.0
    feature_samples = 0
    rows = 0
    for k in range(n_steps + 1):
        t = k * dt
        if k % position_every == 0:
            demand = profile_value(position_table, t)
            measured = quantize_floor(x[S.NUT1_POSITION] - c[K.NUT1_ZERO], c[K.ENCODER_RESOLUTION])
            command, position_integral = pi_step(demand - measured, position_integral, c[K.POSITION_KP],
                                                 c[K.POSITION_KI], position_ts, c[K.SPEED_FULL_SCALE])
            speed_command = quantize_round(command, lsb, c[K.SPEED_FULL_SCALE])
            if pneumatics:
                force_integral = force_loop(t, x, c, u, force_integral, position_ts, force_table, stiffness_poly)
            feature_sum += abs(x[S.NUT1_POSITION] - c[K.NUT1_ZERO]
                               - c[K.LEAD_ARM] * (x[S.SCREW_ANGLE] - c[K.SCREW_ANGLE_ZERO]))
            feature_samples += 1
        if k % speed_every == 0:
            angle = quantize_floor(c[K.RATIO] * x[S.REDUCER_ANGLE], c[K.RESOLVER_RESOLUTION])
            measured_speed = (angle - previous_angle) / speed_ts
            previous_angle = angle
            u[U.CURRENT_DEMAND], speed_integral = pi_step(speed_command - measured_speed, speed_integral,
                                                          c[K.SPEED_KP], c[K.SPEED_KI], speed_ts, c[K.MAX_CURRENT])
        if k % output_every == 0:
            record(output[rows], t, x, c, u, demand, speed_command, force_table, stiffness_poly)
            rows += 1
        if k == n_steps:
            break
        step(method, t, x, dt, c, u, force_table, stiffness_poly, work)
        code = guard(x, c)
        if code != 0:
            status = STATUS_NONFINITE if code == 1 else STATUS_OUT_OF_BOUNDS
            return status, code, k + 1, rows, feature_sum, feature_samples
    return STATUS_OK, 0, n_steps, rows, feature_sum, feature_samples


