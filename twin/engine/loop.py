"""The compiled multi-rate time loop: plant integration, digital loops, recording, divergence guard.

Controller sample instants fall on integration-step boundaries (the step
divides both sample periods). Between samples the controller outputs are held
(zero-order hold). No Python runs inside the loop.
"""

import math

import numba
import numpy as np

from sensors.acquisition import convert
from sensors.analog import AN_REFRESH_PERIOD, AN_TAU, AS_NEXT_REFRESH, analog_step
from sensors.encoder import encoder_step
from sensors.lanes import one_lane
from twin.control.discrete import pi_step
from twin.engine import instrumentation as ins
from twin.engine.integrators import WORK_VECTORS, step
from twin.engine.plant import (
    ball_screw_outputs,
    external_force,
    internal_forces,
    nut_interference,
    preload_between_nuts,
    sensed_current,
    transmitted_torque,
)
from twin.features import MOTION_SPEED_THRESHOLD, N_ACCUMULATORS, accumulate
from twin.layout import (
    BOUND_CONTACT_RELEASED,
    N_INPUTS,
    N_MEASURED,
    PNEUMATICS_FULL,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_OUT_OF_BOUNDS,
    K,
    M,
    S,
    Signal,
    U,
)
from twin.physics.ball_screw import contact_geometry
from twin.physics.pneumatics import hysteresis_play
from twin.scenes.profiles import profile_value

#: Largest biased binary exponent of a state below which the sum in :func:`guard` cannot overflow
#: (|x_j| < 2**977, so even 2**40 such terms sum to a finite number).
_SAFE_EXPONENT = 2000
#: Relative margin under the approach limit within which :func:`guard` evaluates the exact contact geometry.
_APPROACH_MARGIN = 1e-9


@numba.njit(cache=True)
def _sum_is_finite(x):
    """``math.isfinite(sum(x))``, the sum taken only when an element is large or not finite.

    The exponent fields are compared as integers, which vectorise (a float sum does not:
    its order is fixed), so the common case costs a fraction of the serial sum.
    """
    bits = x.view(np.int64)
    largest = 0
    for j in range(bits.shape[0]):
        largest = max(largest, (bits[j] >> 52) & 0x7FF)
    if largest < _SAFE_EXPONENT:
        return True
    total = 0.0
    for j in range(x.shape[0]):
        total += x[j]
    return math.isfinite(total)


@numba.njit(cache=True)
def guard(x, c):
    """Divergence guard: 0 if the state is finite and physical, else a bound code (layout.BOUND_REASONS)."""
    if not _sum_is_finite(x):
        return 1
    if abs(x[S.NUT1_POSITION]) > c[K.STROKE_LIMIT]:
        return 2
    if abs(x[S.REDUCER_SPEED] * c[K.RATIO]) > c[K.MAX_MOTOR_SPEED]:
        return 3
    if abs(x[S.CURRENT]) > 5.0 * c[K.MAX_CURRENT]:
        return 4
    if x[S.WINDING_TEMP] > c[K.MAX_TEMPERATURE]:
        return 5
    for nut in (0, 1):
        gap = nut_interference(x, c, nut)
        # The normal approach never exceeds the axial interference (the triangle inequality on
        # Eq. 9.4's exact form), so the geometry is needed only near the limit.
        if gap > 0.0 and gap * c[K.COS_HELIX] > (1.0 - _APPROACH_MARGIN) * c[K.MAX_NORMAL_APPROACH]:
            approach, _ = contact_geometry(gap * c[K.COS_HELIX], c[K.CENTRE_DISTANCE], c[K.CONTACT_ANGLE_0])
            if approach > c[K.MAX_NORMAL_APPROACH]:
                return 6
    if int(c[K.PNEUMATICS]) == PNEUMATICS_FULL:
        for chamber in (S.CHAMBER1_PRESSURE, S.CHAMBER2_PRESSURE):
            if x[chamber] <= 0.0 or x[chamber] > 2.0 * c[K.P_SUPPLY]:
                return 7
    return 0


@numba.njit(cache=True)
def record(row, t, x, c, u, memory, force_table, stiffness_poly):
    """Write one output row: true signals from the state, measured ones from the last acquisition."""
    torque, f1, f2, preload, external, p1, p2 = internal_forces(t, x, c, force_table, stiffness_poly)
    row[Signal.POSITION_DEMAND] = memory[M.DEMAND]
    row[Signal.NUT1_POSITION] = x[S.NUT1_POSITION] - c[K.NUT1_ZERO]
    row[Signal.NUT2_POSITION] = x[S.NUT2_POSITION] - c[K.NUT1_ZERO]
    row[Signal.SCREW_ANGLE] = x[S.SCREW_ANGLE]
    row[Signal.SCREW_EQUIVALENT_POSITION] = c[K.LEAD_ARM] * (x[S.SCREW_ANGLE] - c[K.SCREW_ANGLE_ZERO])
    (row[Signal.BALL_GROOVE_FRICTION_TORQUE], row[Signal.BALL_SCREW_EFFICIENCY], row[Signal.SCREW_TWIST],
     row[Signal.SCREW_AXIAL_POSITION]) = ball_screw_outputs(x, c, f1, f2, p1, p2)
    row[Signal.MOTOR_CURRENT] = x[S.CURRENT]
    row[Signal.MOTOR_TORQUE] = c[K.TORQUE_CONSTANT] * x[S.CURRENT]
    row[Signal.MOTOR_SPEED] = c[K.RATIO] * x[S.REDUCER_SPEED]
    row[Signal.WINDING_TEMPERATURE] = x[S.WINDING_TEMP]
    row[Signal.PRELOAD_FORCE] = preload
    row[Signal.EXTERNAL_FORCE] = external
    row[Signal.TRANSMITTED_TORQUE] = torque
    row[Signal.NUT1_CONTACT_FORCE] = f1
    row[Signal.NUT2_CONTACT_FORCE] = f2
    row[Signal.SPEED_COMMAND] = memory[M.SPEED_COMMAND]
    row[Signal.CURRENT_DEMAND] = u[U.CURRENT_DEMAND]
    row[Signal.NUT1_SPEED] = x[S.NUT1_SPEED]
    row[Signal.FORCE_DEMAND] = profile_value(force_table, t)
    if int(c[K.PNEUMATICS]) == PNEUMATICS_FULL:
        row[Signal.CHAMBER1_PRESSURE] = x[S.CHAMBER1_PRESSURE]
        row[Signal.CHAMBER2_PRESSURE] = x[S.CHAMBER2_PRESSURE]
        row[Signal.VALVE_COMMAND] = u[U.VALVE_COMMAND]
        row[Signal.PISTON_POSITION] = x[S.PISTON_POSITION]
    for j in range(N_MEASURED):
        row[Signal.LINEAR_ENCODER_POSITION + j] = memory[M.SLED + j]


@numba.njit(cache=True)
def force_loop(t, c, u, memory, sample_time, force_table):
    """Digital PI force loop of the cRIO (Sec. 9.3): load-cell reading -> valve command.

    The PI output is a deviation from the valve's mid position, limited to the
    command range; it goes through the output D/A and the valve's hysteresis.
    """
    half_span = 0.5 * (c[K.VALVE_MAX] - c[K.VALVE_MIN])
    deviation, memory[M.FORCE_INTEGRAL] = pi_step(profile_value(force_table, t) - memory[M.EXTERNAL],
                                                  memory[M.FORCE_INTEGRAL], c[K.FORCE_KP], c[K.FORCE_KI],
                                                  sample_time, half_span)
    if c[K.VALVE_COMMAND_BITS] > 0.0:
        deviation = convert(deviation, half_span, c[K.VALVE_COMMAND_BITS])
    u[U.VALVE_COMMAND] = hysteresis_play(deviation + c[K.VALVE_MID], u[U.VALVE_COMMAND], c[K.VALVE_HYSTERESIS],
                                         c[K.VALVE_MIN], c[K.VALVE_MAX])


@numba.njit(cache=True)
def controller_init(memory, u, instrument_state, rows, levels, x, c, force_table, stiffness_poly):
    """Reset the loops' memory and zero/settle the instruments on the initial state."""
    memory[:] = 0.0
    u[:] = 0.0
    u[U.VALVE_COMMAND] = c[K.VALVE_MID]
    torque, _, _, preload, external, _, _ = internal_forces(0.0, x, c, force_table, stiffness_poly)
    ins.instruments_init(instrument_state, rows, x, c, 0.0, torque, preload, external)
    memory[M.PREVIOUS_ANGLE] = ins.motor_angle_measured(rows, levels, x, c)


@numba.njit(cache=True)
def acquisition_sample(t, x, c, u, memory, instrument_state, rows, levels, noise, position_table, force_table,
                       stiffness_poly, sample_time):
    """Acquisition instant of the cRIO: read every channel, run the position and force loops,
    and accumulate the backlash features (:mod:`twin.features`) on true and on measured signals."""
    torque, _, _, preload, external, _, _ = internal_forces(t, x, c, force_table, stiffness_poly)
    n = int(memory[M.SAMPLES])
    sled = ins.linear_encoder_position(instrument_state, rows, levels, x, c)
    screw_angle = ins.screw_angle_measured(instrument_state, rows, levels, x, c)
    memory[M.SLED] = sled
    memory[M.SCREW_ANGLE] = screw_angle
    memory[M.SLED_SPEED] = ins.sled_speed_measured(instrument_state, rows, levels, x, t)
    memory[M.CURRENT] = ins.analog_measured(instrument_state, rows, levels, ins.CURRENT_MONITOR, sensed_current(x, c),
                                            noise[n, ins.CURRENT_MONITOR])
    memory[M.TORQUE] = ins.analog_measured(instrument_state, rows, levels, ins.TORQUE_METER, torque,
                                           noise[n, ins.TORQUE_METER])
    memory[M.PRELOAD] = ins.analog_measured(instrument_state, rows, levels, ins.PRELOAD_CELL, preload,
                                            noise[n, ins.PRELOAD_CELL])
    memory[M.EXTERNAL] = ins.analog_measured(instrument_state, rows, levels, ins.LOAD_CELL, external,
                                             noise[n, ins.LOAD_CELL])
    memory[M.DEMAND] = profile_value(position_table, t)
    command, memory[M.POSITION_INTEGRAL] = pi_step(memory[M.DEMAND] - sled, memory[M.POSITION_INTEGRAL],
                                                   c[K.POSITION_KP], c[K.POSITION_KI], sample_time,
                                                   c[K.SPEED_FULL_SCALE])
    if c[K.SPEED_COMMAND_BITS] > 0.0:
        command = convert(command, c[K.SPEED_FULL_SCALE], c[K.SPEED_COMMAND_BITS])
    memory[M.SPEED_COMMAND] = command
    if int(c[K.PNEUMATICS]) == PNEUMATICS_FULL:
        force_loop(t, c, u, memory, sample_time, force_table)
    arm = c[K.LEAD_ARM]
    threshold = MOTION_SPEED_THRESHOLD * sample_time
    accumulate(memory[M.FEATURES_TRUE:M.FEATURES_TRUE + N_ACCUMULATORS], x[S.NUT1_POSITION] - c[K.NUT1_ZERO],
               arm * (x[S.SCREW_ANGLE] - c[K.SCREW_ANGLE_ZERO]), torque, n == 0, threshold)
    accumulate(memory[M.FEATURES_MEASURED:M.FEATURES_MEASURED + N_ACCUMULATORS], sled, arm * screw_angle,
               memory[M.TORQUE], n == 0, threshold)
    memory[M.SAMPLES] = n + 1


@numba.njit(cache=True)
def speed_sample(x, c, u, memory, rows, levels, sample_time):
    """Drive speed-loop instant: resolver speed by differencing, PI to the current demand."""
    angle = ins.motor_angle_measured(rows, levels, x, c)
    measured_speed = (angle - memory[M.PREVIOUS_ANGLE]) / sample_time
    memory[M.PREVIOUS_ANGLE] = angle
    memory[M.MOTOR_SPEED] = measured_speed
    u[U.CURRENT_DEMAND], memory[M.SPEED_INTEGRAL] = pi_step(memory[M.SPEED_COMMAND] - measured_speed,
                                                            memory[M.SPEED_INTEGRAL], c[K.SPEED_KP],
                                                            c[K.SPEED_KI], sample_time, c[K.MAX_CURRENT])


@numba.njit(cache=True, inline="always")
def instruments_advance(t, dt, x, c, instrument_state, rows, levels, lookback, steps_to_sample, force_table):
    """Advance the instruments to time ``t``, the end of an integration step of ``dt``.

    The encoders are stepped at every step (:func:`sensors.encoder.encoder_step`);
    an analog channel is stepped, and its measurand computed, only when a reading depends on the step
    (:func:`twin.engine.instrumentation.analog_due`). One flat function: this runs after every step,
    and every call that passes arrays costs more than the tests it would save.
    """
    for encoder in (ins.LINEAR_ENCODER, ins.TORQUE_METER_ENCODER):
        if levels[encoder] > 0:
            measurand = ins.sled_measurand(x, c) if encoder == ins.LINEAR_ENCODER else ins.screw_angle_measurand(x, c)
            encoder_step(one_lane(instrument_state[encoder]), one_lane(rows[encoder]), 0, measurand, t)
    for channel in ins.ANALOG:
        if ins.analog_due(levels[channel], lookback[channel], steps_to_sample, rows[channel, AN_TAU],
                          rows[channel, AN_REFRESH_PERIOD], instrument_state[channel, AS_NEXT_REFRESH], t, dt):
            # the analog channels need only these forces, not the ball-groove contacts
            if channel == ins.TORQUE_METER:
                measurand = transmitted_torque(x, c)
            elif channel == ins.PRELOAD_CELL:
                measurand = preload_between_nuts(x, c)
            elif channel == ins.LOAD_CELL:
                measurand = external_force(t, x, c, force_table)
            else:
                measurand = sensed_current(x, c)
            analog_step(one_lane(instrument_state[channel]), one_lane(rows[channel]), 0, measurand, t)


@numba.njit(cache=True)
def contacts_held(x, c, held_interference):
    """Whether both nuts press on a flank with at least ``held_interference`` of axial interference
    (the deflection of the held-contact load, :func:`twin.engine.solver_choice.held_interference`)."""
    for nut in (0, 1):
        if nut_interference(x, c, nut) < held_interference:
            return False
    return True


LOCAL_ERROR_EVERY = 4        # acquisition instants between local-error checks (4 ms: ~5 % of the run's cost)
LOCAL_ERROR_PERSISTENCE = 3  # checks in a row above tolerance before a run is declared wrong


@numba.njit(cache=True)
def local_error(method, t, x, h, c, u, force_table, stiffness_poly, work, scratch, tolerance, active, pairs):
    """Step-doubling estimate of the local error of one step, in units of ``tolerance``.

    One step of ``h`` against two of ``h/2`` from the same state (Richardson; Hairer,
    Norsett & Wanner, *Solving ODEs I*, Sec. II.4). Stable steps give estimates far
    below 1; a step beyond the method's stability limit gives a growing spurious
    mode, whose local error is of the order of the state itself, long before it
    reaches NaN or a physical bound: this is how "finite but wrong" runs are caught.
    ``x`` is left unchanged.
    """
    single = scratch[0]
    double = scratch[1]
    single[:] = x
    double[:] = x
    step(method, t, single, h, c, u, force_table, stiffness_poly, work, False, active, pairs)
    step(method, t, double, 0.5 * h, c, u, force_table, stiffness_poly, work, False, active, pairs)
    step(method, t + 0.5 * h, double, 0.5 * h, c, u, force_table, stiffness_poly, work, False, active, pairs)
    worst = 0.0
    for j in active:
        scale = tolerance[j] + 1e-2 * abs(double[j])
        worst = max(worst, abs(single[j] - double[j]) / scale)
    return worst


@numba.njit(cache=True)
def run_loop(x, c, position_table, force_table, stiffness_poly, active, pairs, n_steps, dt, speed_every,
             position_every, output_every, jacobian_every, method, rows, levels, lookback, noise, memory, output,
             tolerance, held_interference, release_budget):
    """Integrate ``n_steps`` steps of size ``dt`` from state ``x`` (modified in place).

    Parameters
    ----------
    active, pairs : int arrays
        Integrated states and their (position, velocity) pairs (:class:`twin.engine.model.Model`).
    speed_every, position_every, output_every : int
        Speed-loop, position-loop (= acquisition) and output decimation, in steps.
    jacobian_every : int
        Steps between refreshes of the W-method's matrix (unused by explicit methods).
    method : int
        Integrator code (:mod:`twin.engine.integrators`).
    rows, levels, lookback, noise : arrays
        Instruments of the run (:class:`twin.engine.instrumentation.Instruments`).
    memory : 1-D array
        Loop memory (layout :class:`twin.layout.M`), holds the feature accumulators at the end.
    output : 2-D array
        ``(n_steps // output_every + 1, N_SIGNALS)`` buffer, filled row by row.
    tolerance : 1-D array
        Absolute local-error tolerance per state for the finite-but-wrong guard
        (:func:`local_error`, checked every ``LOCAL_ERROR_EVERY`` acquisition instants).
    held_interference, release_budget : float, int
        If ``held_interference`` is positive, the run stops with bound code ``BOUND_CONTACT_RELEASED`` at the
        step that ends more than ``release_budget`` steps with a nut's axial interference below it
        (:func:`contacts_held`; the premise of the automatic integrator's implicit step,
        :mod:`twin.engine.solver_choice`); 0 checks nothing.

    Returns
    -------
    (status, bound_code, steps_done, rows_written)
    """
    work = np.zeros((WORK_VECTORS + x.shape[0], x.shape[0]))
    u = np.zeros(N_INPUTS)
    instrument_state = np.zeros((ins.N_INSTRUMENTS, ins.STATE_ROW))
    controller_init(memory, u, instrument_state, rows, levels, x, c, force_table, stiffness_poly)
    scratch = np.zeros((2, x.shape[0]))
    written = 0
    # Steps to the next acquisition, speed-loop and output instant and W-matrix refresh: counters, not
    # ``k % every`` (an integer division per test and step).
    to_acquisition = to_speed = to_output = to_jacobian = 0
    acquisitions = 0
    released = 0
    for k in range(n_steps + 1):
        t = k * dt
        check_error = False
        if to_acquisition == 0:
            acquisition_sample(t, x, c, u, memory, instrument_state, rows, levels, noise, position_table,
                               force_table, stiffness_poly, position_every * dt)
            check_error = acquisitions % LOCAL_ERROR_EVERY == 0
            acquisitions += 1
            to_acquisition = position_every
        if to_speed == 0:
            speed_sample(x, c, u, memory, rows, levels, speed_every * dt)
            to_speed = speed_every
        if to_output == 0:
            record(output[written], t, x, c, u, memory, force_table, stiffness_poly)
            written += 1
            to_output = output_every
        if k == n_steps:
            break
        refresh = to_jacobian == 0
        if refresh:
            to_jacobian = jacobian_every
        step(method, t, x, dt, c, u, force_table, stiffness_poly, work, refresh, active, pairs)
        code = guard(x, c)
        if held_interference > 0.0 and not contacts_held(x, c, held_interference):
            released += 1
            if code == 0 and released > release_budget:
                code = BOUND_CONTACT_RELEASED
        if code == 0 and check_error:
            estimate = local_error(method, t + dt, x, dt, c, u, force_table, stiffness_poly, work, scratch, tolerance,
                                   active, pairs)
            memory[M.LOCAL_ERROR] = max(memory[M.LOCAL_ERROR], estimate)
            # A legitimate transient (a new held input, a contact closing) gives a large estimate
            # that decays within a sample or two; a step beyond stability keeps it up.
            memory[M.LOCAL_ERROR_STREAK] = memory[M.LOCAL_ERROR_STREAK] + 1.0 if estimate > 1.0 else 0.0
            if memory[M.LOCAL_ERROR_STREAK] >= LOCAL_ERROR_PERSISTENCE:
                code = 8
        if code != 0:
            status = STATUS_NONFINITE if code == 1 else STATUS_OUT_OF_BOUNDS
            return status, code, k + 1, written
        to_acquisition -= 1
        to_speed -= 1
        to_output -= 1
        to_jacobian -= 1
        instruments_advance(t + dt, dt, x, c, instrument_state, rows, levels, lookback, to_acquisition, force_table)
    return STATUS_OK, 0, n_steps, written
