"""The compiled multi-rate time loop of a group of lanes: plant integration, digital loops, instruments, recording,
divergence guard.

Controller sample instants fall on integration-step boundaries (the step divides both sample periods). Between
samples the controller outputs are held (zero-order hold). No Python runs inside the loop. Every lane advances in
lock-step; a lane whose run fails (the guard trips) is recorded as such and *retired*: its state is reset to its
initial state, finite and benign, and nothing of it is recorded any more, so it neither slows nor touches its lane
mates, and its own numbers up to the failure are those it has alone.
"""

import math

import numba

from numerics.jit import KERNEL, SCALAR
from sensors.acquisition import convert
from twin.components import reducer
from twin.control.discrete import pi_step
from twin.engine import instrumentation as ins
from twin.engine.codes import PNEUMATICS, PNEUMATICS_FULL
from twin.engine.integrators import step
from twin.engine.plant import W, ball_screw_outputs, internal_forces, lead_deviation, measurands
from twin.features import MOTION_SPEED_THRESHOLD, N_ACCUMULATORS, accumulate
from twin.layout import STATUS_NONFINITE, STATUS_OK, STATUS_OUT_OF_BOUNDS, K, M, S, Signal, U
from twin.physics.ball_screw import contact_geometry
from twin.physics.pneumatics import hysteresis_play
from twin.scenes.profiles import profile_value

#: Relative margin under the approach limit within which :func:`guard` evaluates the exact contact geometry.
_APPROACH_MARGIN = 1e-9
#: Bound code of a quasi-static screw-axial balance that did not converge (twin.layout.BOUND_REASONS).
BOUND_BALANCE = 9
#: Bound code of a finite-but-wrong run (the local-error check).
BOUND_LOCAL_ERROR = 8

LOCAL_ERROR_EVERY = 4        # acquisition instants between local-error checks (4 ms: ~5 % of the run's cost)
LOCAL_ERROR_PERSISTENCE = 3  # checks in a row above tolerance before a run is declared wrong


@numba.njit(**SCALAR)
def _relative_position(x, c, lane, nut):
    """``dx_i = x_s + p(T) (theta_s - theta_ni) / 2 pi - x_ni`` of one lane at its stored screw-axial displacement,
    without the lead error (:func:`_lead_error_bound` bounds it)."""
    position = S.NUT1_POSITION + 4 * nut
    return (x[S.SCREW_AXIAL, lane] + c[K.LEAD_ARM, lane] * (x[S.SCREW_ANGLE, lane] - x[position + 2, lane])
            - x[position, lane])


@numba.njit(**SCALAR)
def _lead_error_bound(x, c, lane, nut):
    """An upper bound of the lead error's ``|e|`` at nut ``nut`` (:func:`twin.physics.ball_screw.travel_deviation`:
    each sine difference is at most 2)."""
    angle = x[S.SCREW_ANGLE, lane] - x[S.NUT1_ANGLE + 4 * nut, lane]
    return (abs(c[K.LEAD_SLOPE, lane] * c[K.LEAD_ARM_NOMINAL, lane] * angle)
            + 2.0 * abs(c[K.LEAD_WAVE_AMPLITUDE, lane]) + 2.0 * abs(c[K.LEAD_REVOLUTION_AMPLITUDE, lane]))


@numba.njit(**SCALAR)
def guard(x, c, w, lane, levels):
    """Divergence guard of one lane: 0 if its state is finite and physical, else a bound code
    (twin.layout.BOUND_REASONS)."""
    total = 0.0
    for j in range(x.shape[0]):
        total += x[j, lane]
    if not math.isfinite(total):
        return 1
    if abs(x[S.NUT1_POSITION, lane]) > c[K.STROKE_LIMIT, lane]:
        return 2
    if abs(reducer.motor_speed_at(x, c, lane)) > c[K.MAX_MOTOR_SPEED, lane]:
        return 3
    if abs(x[S.CURRENT, lane]) > 5.0 * c[K.MAX_CURRENT, lane]:
        return 4
    if x[S.WINDING_TEMP, lane] > c[K.MAX_TEMPERATURE, lane]:
        return 5
    for nut in range(2):
        relative = _relative_position(x, c, lane, nut)
        reach = abs(relative) + _lead_error_bound(x, c, lane, nut) - 0.5 * c[K.BACKLASH, lane]
        # The normal approach never exceeds the axial interference (the triangle inequality on
        # Eq. 9.4's exact form), so the geometry (and the lead error) is needed only near the limit.
        if reach > 0.0 and reach * c[K.COS_HELIX, lane] > (1.0 - _APPROACH_MARGIN) * c[K.MAX_NORMAL_APPROACH, lane]:
            deviation, _ = lead_deviation(c, lane, x[S.SCREW_ANGLE, lane] - x[S.NUT1_ANGLE + 4 * nut, lane])
            gap = abs(relative + deviation) - 0.5 * c[K.BACKLASH, lane]
            if gap > 0.0:
                approach, _ = contact_geometry(gap * c[K.COS_HELIX, lane], c[K.CENTRE_DISTANCE, lane],
                                               c[K.CONTACT_RADIAL_0, lane], c[K.CONTACT_AXIAL_0, lane])
                if approach > c[K.MAX_NORMAL_APPROACH, lane]:
                    return 6
    if levels[PNEUMATICS] == PNEUMATICS_FULL:
        for chamber in (S.CHAMBER1_PRESSURE, S.CHAMBER2_PRESSURE):
            if x[chamber, lane] <= 0.0 or x[chamber, lane] > 2.0 * c[K.P_SUPPLY, lane]:
                return 7
    if w[W.BALANCE_FAILED, lane] > 0.0:
        return BOUND_BALANCE
    return 0


@numba.njit(**SCALAR)
def record(row, t, x, c, u, w, lane, memory, levels, force_table):
    """Write one output row of one lane: true signals from its state and the work rows of :func:`internal_forces`
    (evaluated at this state), measured ones from its last acquisition."""
    row[Signal.POSITION_DEMAND] = memory[M.DEMAND, lane]
    row[Signal.NUT1_POSITION] = x[S.NUT1_POSITION, lane] - c[K.NUT1_ZERO, lane]
    row[Signal.NUT2_POSITION] = x[S.NUT2_POSITION, lane] - c[K.NUT1_ZERO, lane]
    row[Signal.SCREW_ANGLE] = x[S.SCREW_ANGLE, lane]
    row[Signal.SCREW_EQUIVALENT_POSITION] = c[K.LEAD_ARM_NOMINAL, lane] * (
        x[S.SCREW_ANGLE, lane] - c[K.SCREW_ANGLE_ZERO, lane])
    (row[Signal.BALL_GROOVE_FRICTION_TORQUE], row[Signal.BALL_SCREW_EFFICIENCY], row[Signal.SCREW_TWIST],
     row[Signal.SCREW_AXIAL_POSITION]) = ball_screw_outputs(x, c, w, lane)
    row[Signal.MOTOR_CURRENT] = x[S.CURRENT, lane]
    row[Signal.MOTOR_TORQUE] = c[K.TORQUE_CONSTANT, lane] * x[S.CURRENT, lane]
    row[Signal.MOTOR_SPEED] = reducer.motor_speed_at(x, c, lane)
    row[Signal.WINDING_TEMPERATURE] = x[S.WINDING_TEMP, lane]
    row[Signal.PRELOAD_FORCE] = w[W.PRELOAD, lane]
    row[Signal.EXTERNAL_FORCE] = w[W.EXTERNAL, lane]
    row[Signal.TRANSMITTED_TORQUE] = w[W.TORQUE, lane]
    row[Signal.NUT1_CONTACT_FORCE] = w[W.NUT_FORCE, lane]
    row[Signal.NUT2_CONTACT_FORCE] = w[W.NUT_FORCE + 1, lane]
    row[Signal.SPEED_COMMAND] = memory[M.SPEED_COMMAND, lane]
    row[Signal.CURRENT_DEMAND] = u[U.CURRENT_DEMAND, lane]
    row[Signal.NUT1_SPEED] = x[S.NUT1_SPEED, lane]
    row[Signal.FORCE_DEMAND] = profile_value(force_table, t)
    if levels[PNEUMATICS] == PNEUMATICS_FULL:
        row[Signal.CHAMBER1_PRESSURE] = x[S.CHAMBER1_PRESSURE, lane]
        row[Signal.CHAMBER2_PRESSURE] = x[S.CHAMBER2_PRESSURE, lane]
        row[Signal.VALVE_COMMAND] = u[U.VALVE_COMMAND, lane]
        row[Signal.PISTON_POSITION] = x[S.PISTON_POSITION, lane]
    for j in range(ins.N_MEASURED):
        row[Signal.LINEAR_ENCODER_POSITION + j] = memory[M.SLED + j, lane]


@numba.njit(**SCALAR)
def force_loop(t, c, u, memory, lane, sample_time, force_table):
    """Digital PI force loop of the cRIO (Sec. 9.3): load-cell reading (``M.FORCE_FEEDBACK``, with or without the
    electrical noise: the scene's ``noise_path``) -> valve command.

    The PI output is a deviation from the valve's mid position, limited to the
    command range; it goes through the output D/A and the valve's hysteresis.
    """
    half_span = 0.5 * (c[K.VALVE_MAX, lane] - c[K.VALVE_MIN, lane])
    deviation, memory[M.FORCE_INTEGRAL, lane] = pi_step(
        profile_value(force_table, t) - memory[M.FORCE_FEEDBACK, lane], memory[M.FORCE_INTEGRAL, lane],
        c[K.FORCE_KP, lane], c[K.FORCE_KI, lane], sample_time, half_span)
    if c[K.VALVE_COMMAND_BITS, lane] > 0.0:
        deviation = convert(deviation, half_span, c[K.VALVE_COMMAND_BITS, lane])
    u[U.VALVE_COMMAND, lane] = hysteresis_play(deviation + c[K.VALVE_MID, lane], u[U.VALVE_COMMAND, lane],
                                               c[K.VALVE_HYSTERESIS, lane], c[K.VALVE_MIN, lane],
                                               c[K.VALVE_MAX, lane])


@numba.njit(**KERNEL)
def acquisition_sample(t, x, c, u, w, levels, memory, parameters, states, noise, position_table, force_table,
                       sample_time, alive):
    """Acquisition instant of the cRIO in every live lane: read every channel, run the position and force loops,
    and accumulate the backlash features (:mod:`twin.features`) on true and on measured signals. ``w`` holds
    the measurands of :func:`twin.engine.plant.measurands` at this instant."""
    lanes = x.shape[1]
    threshold = MOTION_SPEED_THRESHOLD * sample_time
    demand = profile_value(position_table, t)
    for lane in range(lanes):
        if not alive[lane]:
            continue
        n = int(memory[M.SAMPLES, lane])
        ins.acquire(t, x, c, w, lane, levels, memory, parameters, states, noise, n)
        memory[M.DEMAND, lane] = demand
        command, memory[M.POSITION_INTEGRAL, lane] = pi_step(
            demand - memory[M.SLED, lane], memory[M.POSITION_INTEGRAL, lane], c[K.POSITION_KP, lane],
            c[K.POSITION_KI, lane], sample_time, c[K.SPEED_FULL_SCALE, lane])
        if c[K.SPEED_COMMAND_BITS, lane] > 0.0:
            command = convert(command, c[K.SPEED_FULL_SCALE, lane], c[K.SPEED_COMMAND_BITS, lane])
        memory[M.SPEED_COMMAND, lane] = command
        if levels[PNEUMATICS] == PNEUMATICS_FULL:
            force_loop(t, c, u, memory, lane, sample_time, force_table)
        # Eq. 9.12 takes the screw's nominal lead: the bench's engineer does not know the lead error or the expansion
        arm = c[K.LEAD_ARM_NOMINAL, lane]
        accumulate(memory[M.FEATURES_TRUE:M.FEATURES_TRUE + N_ACCUMULATORS, lane],
                   x[S.NUT1_POSITION, lane] - c[K.NUT1_ZERO, lane],
                   arm * (x[S.SCREW_ANGLE, lane] - c[K.SCREW_ANGLE_ZERO, lane]), w[W.TORQUE, lane], n == 0, threshold)
        accumulate(memory[M.FEATURES_MEASURED:M.FEATURES_MEASURED + N_ACCUMULATORS, lane], memory[M.SLED, lane],
                   arm * memory[M.SCREW_ANGLE, lane], memory[M.TORQUE, lane], n == 0, threshold)
        memory[M.SAMPLES, lane] = n + 1


@numba.njit(**KERNEL)
def speed_sample(x, c, u, levels, memory, parameters, sample_time, alive):
    """Drive speed-loop instant in every live lane: resolver speed by differencing, PI to the current demand."""
    for lane in range(x.shape[1]):
        if not alive[lane]:
            continue
        angle = ins.motor_angle_measured(x, c, lane, levels, parameters)
        measured_speed = (angle - memory[M.PREVIOUS_ANGLE, lane]) / sample_time
        memory[M.PREVIOUS_ANGLE, lane] = angle
        memory[M.MOTOR_SPEED, lane] = measured_speed
        u[U.CURRENT_DEMAND, lane], memory[M.SPEED_INTEGRAL, lane] = pi_step(
            memory[M.SPEED_COMMAND, lane] - measured_speed, memory[M.SPEED_INTEGRAL, lane], c[K.SPEED_KP, lane],
            c[K.SPEED_KI, lane], sample_time, c[K.MAX_CURRENT, lane])


@numba.njit(**KERNEL)
def controller_init(t, x, c, u, w, levels, memory, parameters, states, force_table):
    """Reset the loops' memory and zero/settle the instruments on the initial state of every lane."""
    lanes = x.shape[1]
    for j in range(memory.shape[0]):
        for lane in range(lanes):
            memory[j, lane] = 0.0
    for lane in range(lanes):
        u[U.CURRENT_DEMAND, lane] = 0.0
        u[U.VALVE_COMMAND, lane] = c[K.VALVE_MID, lane]
    internal_forces(t, x, c, w, lanes, levels, force_table)
    ins.instruments_init(t, x, c, w, levels, parameters, states)
    for lane in range(lanes):
        memory[M.PREVIOUS_ANGLE, lane] = ins.motor_angle_measured(x, c, lane, levels, parameters)


@numba.njit(**KERNEL)
def local_error(method, t, x, h, c, u, levels, force_table, vectors, w, matrices, cache, small, tolerance, active,
                pairs, estimate):
    """Step-doubling estimate of the local error of one step in every lane, in units of ``tolerance``, into
    ``estimate``.

    One step of ``h`` against two of ``h/2`` from the same state (Richardson; Hairer,
    Norsett & Wanner, *Solving ODEs I*, Sec. II.4). Stable steps give estimates far
    below 1; a step beyond the method's stability limit gives a growing spurious
    mode, whose local error is of the order of the state itself, long before it
    reaches NaN or a physical bound: this is how "finite but wrong" runs are caught.
    ``x`` is left unchanged (the scratch states are ``vectors[6:8]``).
    """
    single, double = vectors[6], vectors[7]
    lanes = x.shape[1]
    for j in range(x.shape[0]):
        for lane in range(lanes):
            single[j, lane] = x[j, lane]
            double[j, lane] = x[j, lane]
    step(method, t, single, h, c, u, levels, force_table, vectors[:6], w, matrices, cache, small, False, active,
         pairs)
    step(method, t, double, 0.5 * h, c, u, levels, force_table, vectors[:6], w, matrices, cache, small, False,
         active, pairs)
    step(method, t + 0.5 * h, double, 0.5 * h, c, u, levels, force_table, vectors[:6], w, matrices, cache, small,
         False, active, pairs)
    for lane in range(lanes):
        worst = 0.0
        for j in active:
            scale = tolerance[j] + 1e-2 * abs(double[j, lane])
            worst = max(worst, abs(single[j, lane] - double[j, lane]) / scale)
        estimate[lane] = worst


@numba.njit(**KERNEL)
def _retire(x, x0, lane):
    """Put a failed lane back to its initial state (finite and benign) so that it costs no more than a live one."""
    for j in range(x.shape[0]):
        x[j, lane] = x0[j, lane]


@numba.njit(**KERNEL)
def run_loop(x, c, levels, position_table, force_table, active, pairs, n_steps, dt, speed_every, position_every,
             output_every, jacobian_every, method, parameters, states, noise, memory, output, tolerance, vectors, w,
             matrices, cache, small, inputs, alive, guard_memory, initial, status, bound, steps_done, rows_written):
    """Integrate ``n_steps`` steps of size ``dt`` of every lane of ``x`` (modified in place).

    Parameters
    ----------
    x, c : 2-D arrays ``[row, lane]``
        States and constants of the group's lanes.
    levels, active, pairs : int arrays
        The group's level codes, integrated states and their (position, velocity) pairs
        (:class:`twin.engine.model.Model`).
    speed_every, position_every, output_every : int
        Speed-loop, position-loop (= acquisition) and output decimation, in steps; ``output_every = 0`` records
        nothing (a campaign's untraced runs need only the features).
    jacobian_every : int
        Steps between refreshes of the W-method's matrices (unused by the other methods).
    method : int
        Integrator code (:mod:`twin.engine.integrators`).
    parameters, states, noise : arrays
        Instruments of the group (:mod:`twin.engine.instrumentation`): ``[instrument, row, lane]`` parameters and
        state, and the pre-drawn electrical noise ``[sample, instrument, lane]``.
    memory : 2-D array
        Loop memory (layout :class:`twin.layout.M`) per lane; holds the feature accumulators at the end.
    output : 3-D array
        ``(rows, N_SIGNALS, lanes)`` buffer, filled row by row.
    tolerance : 1-D array
        Absolute local-error tolerance per state for the finite-but-wrong guard
        (:func:`local_error`, checked every ``LOCAL_ERROR_EVERY`` acquisition instants).
    vectors, w, matrices, cache, small : arrays
        The integrators' workspace (:meth:`twin.engine.integrators.Workspace.arrays`).
    inputs, alive, guard_memory, initial : arrays
        The loop's own scratch (:meth:`twin.engine.integrators.Workspace.loop_arrays`), filled here: the inputs the
        digital loops hold, the live lanes, the local-error streak and estimate, the initial states (a failed lane
        is put back to them). Passed in, not allocated: the loop also runs as a CUDA kernel.
    status, bound, steps_done, rows_written : 1-D arrays per lane (outputs)
        The run's status code (twin.layout.STATUS_*), the guard's bound code, the steps done and the output rows
        written.
    """
    lanes = x.shape[1]
    u, x0 = inputs, initial
    streak, estimate = guard_memory[0], guard_memory[1]
    for lane in range(lanes):
        for j in range(x.shape[0]):
            x0[j, lane] = x[j, lane]
        for j in range(u.shape[0]):
            u[j, lane] = 0.0
        alive[lane] = True
        streak[lane] = 0.0
        estimate[lane] = 0.0
        status[lane] = STATUS_OK
        bound[lane] = 0
        steps_done[lane] = n_steps
        rows_written[lane] = 0
    controller_init(0.0, x, c, u, w, levels, memory, parameters, states, force_table)
    # Steps to the next acquisition, speed-loop and output instant and W-matrix refresh: counters, not
    # ``k % every`` (an integer division per test and step).
    to_acquisition = to_speed = to_output = to_jacobian = 0
    acquisitions = 0
    for k in range(n_steps + 1):
        t = k * dt
        check_error = False
        sampled = to_acquisition == 0
        recorded = output_every > 0 and to_output == 0
        if sampled or recorded:
            internal_forces(t, x, c, w, lanes, levels, force_table)
        if sampled:
            acquisition_sample(t, x, c, u, w, levels, memory, parameters, states, noise, position_table,
                               force_table, position_every * dt, alive)
            check_error = acquisitions % LOCAL_ERROR_EVERY == 0
            acquisitions += 1
            to_acquisition = position_every
        if to_speed == 0:
            speed_sample(x, c, u, levels, memory, parameters, speed_every * dt, alive)
            to_speed = speed_every
        if recorded:
            row = k // output_every
            for lane in range(lanes):
                if alive[lane]:
                    record(output[row, :, lane], t, x, c, u, w, lane, memory, levels, force_table)
                    rows_written[lane] = row + 1
            to_output = output_every
        if k == n_steps:
            break
        refresh = to_jacobian == 0
        if refresh:
            to_jacobian = jacobian_every
        step(method, t, x, dt, c, u, levels, force_table, vectors[:6], w, matrices, cache, small, refresh, active,
             pairs)
        if check_error:
            local_error(method, t + dt, x, dt, c, u, levels, force_table, vectors, w, matrices, cache, small,
                        tolerance, active, pairs, estimate)
        for lane in range(lanes):
            if not alive[lane]:
                continue
            code = guard(x, c, w, lane, levels)
            if code == 0 and check_error:
                memory[M.LOCAL_ERROR, lane] = max(memory[M.LOCAL_ERROR, lane], estimate[lane])
                # A legitimate transient (a new held input, a contact closing) gives a large estimate
                # that decays within a sample or two; a step beyond stability keeps it up.
                streak[lane] = streak[lane] + 1.0 if estimate[lane] > 1.0 else 0.0
                if streak[lane] >= LOCAL_ERROR_PERSISTENCE:
                    code = BOUND_LOCAL_ERROR
            if code != 0:
                status[lane] = STATUS_NONFINITE if code == 1 else STATUS_OUT_OF_BOUNDS
                bound[lane] = code
                steps_done[lane] = k + 1
                alive[lane] = False
                _retire(x, x0, lane)
        to_acquisition -= 1
        to_speed -= 1
        to_output -= 1
        to_jacobian -= 1
        measurands(t + dt, x, c, w, lanes, levels, force_table)
        ins.instruments_advance(t + dt, dt, x, c, w, levels, parameters, states, to_acquisition)
