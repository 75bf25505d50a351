"""The compiled multi-rate time loop: plant integration, digital loops, recording, divergence guard.

Controller sample instants fall on integration-step boundaries (the step
divides both sample periods). Between samples the controller outputs are held
(zero-order hold). No Python runs inside the loop.
"""

import math

import numba
import numpy as np

from sensors.acquisition import convert
from twin.control.discrete import pi_step
from twin.engine import instrumentation as ins
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
from twin.engine.plant import external_force, internal_forces, preload_between_nuts, transmitted_torque
from twin.physics.ball_screw import contact_geometry
from twin.physics.pneumatics import hysteresis_play
from twin.scenes.profiles import profile_value


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
def record(row, t, x, c, u, demand, speed_command, measured, force_table, stiffness_poly):
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
    for j in range(measured.shape[0]):
        row[Signal.LINEAR_ENCODER_POSITION + j] = measured[j]


@numba.njit(cache=True)
def force_loop(t, c, u, measured_force, integral, sample_time, force_table):
    """Digital PI force loop of the cRIO (Sec. 9.3): load-cell reading -> valve command.

    The PI output is a deviation from the valve's mid position, limited to the
    command range; it goes through the output D/A and the valve's hysteresis.
    Returns the new PI integral; the effective command is written to ``u``.
    """
    half_span = 0.5 * (c[K.VALVE_MAX] - c[K.VALVE_MIN])
    deviation, integral = pi_step(profile_value(force_table, t) - measured_force, integral, c[K.FORCE_KP],
                                  c[K.FORCE_KI], sample_time, half_span)
    if c[K.VALVE_COMMAND_BITS] > 0.0:
        deviation = convert(deviation, half_span, c[K.VALVE_COMMAND_BITS])
    command = deviation + c[K.VALVE_MID]
    u[U.VALVE_COMMAND] = hysteresis_play(command, u[U.VALVE_COMMAND], c[K.VALVE_HYSTERESIS], c[K.VALVE_MIN],
                                         c[K.VALVE_MAX])
    return integral


@numba.njit(cache=True)
def run_loop(x, c, position_table, force_table, stiffness_poly, n_steps, dt, speed_every, position_every,
             output_every, method, instrument_rows, instrument_levels, noise, output):
    """Integrate ``n_steps`` steps of size ``dt`` from state ``x`` (modified in place).

    Parameters
    ----------
    speed_every, position_every, output_every : int
        Speed-loop, position-loop (= acquisition) and output decimation, in steps.
    method : int
        Integrator code (:mod:`twin.engine.integrators`).
    instrument_rows, instrument_levels, noise : arrays
        Instruments of the run (:class:`twin.engine.instrumentation.Instruments`).
    output : 2-D array
        ``(n_steps // output_every + 1, N_SIGNALS)`` buffer, filled row by row.

    Returns
    -------
    (status, bound_code, steps_done, rows_written, feature_sums, feature_samples)
        ``feature_sums`` holds the Eq. 9.12 sums on true and on measured signals at the
        acquisition (position-loop) instants: ``|x_n1 - p theta_s / 2 pi|``, both zeroed at t = 0.
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
    arm = c[K.LEAD_ARM]
    levels = instrument_levels
    state = np.zeros((7, 13))
    torque, _, _, preload, external, _, _ = internal_forces(0.0, x, c, force_table, stiffness_poly)
    ins.instruments_init(state, instrument_rows, x, c, 0.0, torque, preload, external)
    analog_stepping = levels[ins.TORQUE_METER] + levels[ins.PRELOAD_CELL] + levels[ins.LOAD_CELL] \
        + levels[ins.CURRENT_MONITOR] > 0
    previous_angle = ins.motor_angle_measured(instrument_rows, levels, x, c)
    measured = np.zeros(8)
    feature_sums = np.zeros(2)
    feature_samples = 0
    sample = 0
    rows = 0
    for k in range(n_steps + 1):
        t = k * dt
        if k % position_every == 0:
            # acquisition instant: controller reads its inputs, the DAQ samples every channel
            torque, _, _, preload, external, _, _ = internal_forces(t, x, c, force_table, stiffness_poly)
            sled = ins.linear_encoder_position(state, instrument_rows, levels, x, c)
            screw_angle = ins.screw_angle_measured(state, instrument_rows, levels, x, c)
            measured[0] = sled
            measured[1] = screw_angle
            measured[2] = ins.sled_speed_measured(state, instrument_rows, levels, x, t)
            measured[4] = ins.analog_measured(state, instrument_rows, levels, ins.CURRENT_MONITOR, x[S.HALL_CURRENT],
                                              noise[sample, ins.CURRENT_MONITOR])
            measured[5] = ins.analog_measured(state, instrument_rows, levels, ins.TORQUE_METER, torque,
                                              noise[sample, ins.TORQUE_METER])
            measured[6] = ins.analog_measured(state, instrument_rows, levels, ins.PRELOAD_CELL, preload,
                                              noise[sample, ins.PRELOAD_CELL])
            measured[7] = ins.analog_measured(state, instrument_rows, levels, ins.LOAD_CELL, external,
                                              noise[sample, ins.LOAD_CELL])
            sample += 1
            demand = profile_value(position_table, t)
            command, position_integral = pi_step(demand - sled, position_integral, c[K.POSITION_KP],
                                                 c[K.POSITION_KI], position_ts, c[K.SPEED_FULL_SCALE])
            if c[K.SPEED_COMMAND_BITS] > 0.0:
                command = convert(command, c[K.SPEED_FULL_SCALE], c[K.SPEED_COMMAND_BITS])
            speed_command = command
            if pneumatics:
                force_integral = force_loop(t, c, u, measured[7], force_integral, position_ts, force_table)
            feature_sums[0] += abs(x[S.NUT1_POSITION] - c[K.NUT1_ZERO] - arm * (x[S.SCREW_ANGLE] - c[K.SCREW_ANGLE_ZERO]))
            feature_sums[1] += abs(sled - arm * screw_angle)
            feature_samples += 1
        if k % speed_every == 0:
            angle = ins.motor_angle_measured(instrument_rows, levels, x, c)
            measured_speed = (angle - previous_angle) / speed_ts
            previous_angle = angle
            measured[3] = measured_speed
            u[U.CURRENT_DEMAND], speed_integral = pi_step(speed_command - measured_speed, speed_integral,
                                                          c[K.SPEED_KP], c[K.SPEED_KI], speed_ts, c[K.MAX_CURRENT])
        if k % output_every == 0:
            record(output[rows], t, x, c, u, demand, speed_command, measured, force_table, stiffness_poly)
            rows += 1
        if k == n_steps:
            break
        step(method, t, x, dt, c, u, force_table, stiffness_poly, work)
        code = guard(x, c)
        if code != 0:
            status = STATUS_NONFINITE if code == 1 else STATUS_OUT_OF_BOUNDS
            return status, code, k + 1, rows, feature_sums, feature_samples
        if analog_stepping:
            # the instruments need only these three forces, not the ball-groove contacts
            torque = transmitted_torque(x, c)
            preload = preload_between_nuts(x, c)
            external = external_force(t + dt, x, c, force_table)
        ins.instruments_step(state, instrument_rows, levels, x, c, t + dt, torque, preload, external)
    return STATUS_OK, 0, n_steps, rows, feature_sums, feature_samples
