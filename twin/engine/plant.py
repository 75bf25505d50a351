"""Continuous-time right-hand side of the bench (Eqs. 9.1-9.11) for a group of lanes, compiled with numba.

A lane is one Monte Carlo sample; a group of lanes shares the scene and the model configuration (the fidelity
levels) and advances in lock-step (:mod:`twin.engine.loop`). Every array is ``[row, lane]``: the state ``x``
(layout :class:`twin.layout.S`), the constants ``c`` (:class:`twin.layout.K`), the held inputs ``u``
(:class:`twin.layout.U`), the derivatives ``dxdt`` and the work rows ``w`` (:class:`twin.layout.W`: the forces the
rest of the engine reads). The right-hand side is a sequence of *stages*, each one loop over the lanes whose body
calls a scalar physics law of :mod:`twin.physics` (branch-free, inlined), so LLVM vectorises it; a lane's numbers depend
only on its own row entries, never on its lane mates or on the lane count (tests/engine/test_lanes.py).
A stage takes the work rows through the ``w`` argument and never aliases it with another array argument (the
``noalias`` promise of :data:`numerics.jit.KERNEL`).

The digital controllers are outside: the speed loop's current demand and the valve command enter as held inputs
(zero-order hold between controller samples).
"""

import math
from functools import reduce

import numba
import numpy as np

from numerics.jit import KERNEL, SCALAR
from twin.components import DERIVATIVE_STAGES, FORCE_STAGES, guides, preload, seal
from twin.engine.codes import (
    BALL_GROOVE_FRICTION,
    BALL_GROOVE_FRICTION_CHAPTER5,
    CONTACT,
    CURRENT_LOOP,
    CURRENT_LOOP_FULL,
    MOTOR_THERMAL,
    NUT_ROTATION,
    NUT_ROTATION_ON,
    PNEUMATICS,
    PNEUMATICS_FULL,
    PNEUMATICS_IDEAL,
    SCREW_AXIAL,
    SCREW_AXIAL_DYNAMIC,
    THERMAL_DYNAMIC,
)
from twin.layout import N_WORK, NUT_CONSTANT_STRIDE, NUT_STATE_STRIDE, K, S, U, W
from twin.physics import pneumatics as pn
from twin.physics.ball_groove_friction import friction_generalised_forces, nut_friction_force, tangential_speed
from twin.physics.ball_screw import nut_axial_force, nut_elastic_force, travel_deviation
from twin.physics.friction import stribeck_friction
from twin.physics.motor import current_derivative, winding_resistance, winding_temperature_derivative
from twin.scenes.profiles import profile_value

#: Newton iterations the quasi-static screw-axial balance may take in one evaluation; warm-started from the last
#: solution it needs 1-3 (measured: docs/accuracy.md); a lane that runs out is flagged (``W.BALANCE_FAILED``).
BALANCE_ITERATIONS = 30
#: Newton correction [m] below which the quasi-static balance counts as solved: a femtometre, 1e-9 of the
#: micrometre features and far below any deflection the model resolves.
BALANCE_TOLERANCE = 1.0e-15
#: Groups of at most this many lanes take the fused form of the right-hand side (one lane's stages one after the
#: other), larger ones the split form (one loop over the lanes per stage, vectorised): benchmarks/single_run.py.
FUSED_LANES = 1


def work_rows(lanes: int) -> np.ndarray:
    """Zeroed work rows for a group of ``lanes`` lanes."""
    return np.zeros((N_WORK, lanes))


@numba.njit(**SCALAR)
def lead_deviation(c, lane, angle):
    """The screw's travel deviation ``e`` [m] and its rate ``e'`` [m/rad] at the screw angle ``angle`` relative to a
    nut, since the test's zero (:func:`twin.physics.ball_screw.travel_deviation`, ISO 3408-3)."""
    return travel_deviation(angle, c[K.LEAD_ARM_NOMINAL, lane], c[K.LEAD_SLOPE, lane], c[K.LEAD_WAVE_AMPLITUDE, lane],
                            c[K.LEAD_WAVE_NUMBER, lane], c[K.LEAD_WAVE_PHASE, lane], c[K.LEAD_WAVE_AT_ZERO, lane],
                            c[K.LEAD_REVOLUTION_AMPLITUDE, lane], c[K.LEAD_REVOLUTION_PHASE, lane],
                            c[K.LEAD_REVOLUTION_AT_ZERO, lane])


@numba.njit(**KERNEL)
def has_lead_error(c, lanes):
    """Whether any lane of the group has a lead error. A lane without one gets ``e = e' = 0`` exactly from
    :func:`lead_deviation`, and adding those zeros changes no bit of its kinematics: skipping the computation for a
    group without lead errors gives every lane the numbers it has in any group."""
    amplitude = 0.0
    for lane in range(lanes):
        amplitude += (abs(c[K.LEAD_SLOPE, lane]) + abs(c[K.LEAD_WAVE_AMPLITUDE, lane])
                      + abs(c[K.LEAD_REVOLUTION_AMPLITUDE, lane]))
    return amplitude > 0.0


# Each stage below is written once, for one lane (``*_at``, a SCALAR function), and composed two ways from that one
# source: split, one loop over the lanes per stage (the form LLVM vectorises, for groups), and fused, every stage of
# one lane after the other (:func:`rhs`, :func:`internal_forces` and :func:`measurands` for groups of at most
# ``FUSED_LANES`` lanes: one lane's state stays in registers, and the stage calls and loop set-ups of the split form
# are gone). A lane's operations and their order are the same in both, so are its bits (tests/engine/test_lanes.py).


# The components' stages (twin.components.FORCE_STAGES and DERIVATIVE_STAGES, one list each), composed the same two
# ways: a chain of closures, one per stage, each calling the rest of the chain and then its stage. numba reads a
# closure's free variables as compile-time constants, so every call is a direct call and SCALAR inlines it: the chain
# compiles to the stages' bodies one after the other, as if written out by hand, and adding a component to the table
# changes neither composition.


@numba.njit(**SCALAR)
def _no_forces(x, c, w, lanes, levels):
    pass


@numba.njit(**SCALAR)
def _no_derivatives(x, c, u, w, dxdt, lanes, levels):
    pass


def _forces_then(rest, stage):
    """The chain ``rest``, then ``stage`` (``(active, forces_at)``), of the forces phase; ``lanes``: a range of lanes
    (split: one loop per stage over the group; fused: ``range(lane, lane + 1)``)."""
    active, forces_at = stage

    @numba.njit(**SCALAR)
    def forces(x, c, w, lanes, levels):
        rest(x, c, w, lanes, levels)
        if active(levels):
            for lane in lanes:
                forces_at(x, c, w, lane)
    return forces


def _derivatives_then(rest, stage):
    """:func:`_forces_then` for the derivatives phase."""
    active, derivatives_at = stage

    @numba.njit(**SCALAR)
    def derivatives(x, c, u, w, dxdt, lanes, levels):
        rest(x, c, u, w, dxdt, lanes, levels)
        if active(levels):
            for lane in lanes:
                derivatives_at(x, c, u, w, dxdt, lane, levels)
    return derivatives


#: The components' forces phase: their work rows (``component_forces(x, c, w, lanes, levels)``, lanes a range).
component_forces = reduce(_forces_then, FORCE_STAGES, _no_forces)
#: The components' derivatives phase (``component_derivatives(x, c, u, w, dxdt, lanes, levels)``).
component_derivatives = reduce(_derivatives_then, DERIVATIVE_STAGES, _no_derivatives)


@numba.njit(**SCALAR)
def _nut_kinematics_at(x, c, w, lane, nut, rows, errors):
    """``dx_i`` and its rate without the screw's axial motion (Eq. 9.5 with the lead error,
    :mod:`twin.physics.ball_screw`): ``p(T) phi_i / 2 pi + e(phi_i) - x_ni`` with ``phi_i = theta_s - theta_ni``,
    into ``rows`` and ``rows + 2`` (:data:`W.NUT_KINEMATIC`, or directly :data:`W.NUT_DX` for the dynamic level),
    and ``e'(phi_i)`` into :data:`W.NUT_LEAD_SLOPE` for the reaction torques; ``errors``: the group has a lead error
    (:func:`has_lead_error`)."""
    position = S.NUT1_POSITION + NUT_STATE_STRIDE * nut
    arm = c[K.LEAD_ARM, lane]
    if errors:
        angle = x[S.SCREW_ANGLE, lane] - x[position + 2, lane]
        rate = x[S.SCREW_SPEED, lane] - x[position + 3, lane]
        deviation, slope = lead_deviation(c, lane, angle)
        w[rows + nut, lane] = (arm * angle + deviation) - x[position, lane]
        w[rows + 2 + nut, lane] = (arm * rate + slope * rate) - x[position + 1, lane]
        w[W.NUT_LEAD_SLOPE + nut, lane] = slope
    else:
        w[rows + nut, lane] = arm * (x[S.SCREW_ANGLE, lane] - x[position + 2, lane]) - x[position, lane]
        w[rows + 2 + nut, lane] = arm * (x[S.SCREW_SPEED, lane] - x[position + 3, lane]) - x[position + 1, lane]
        w[W.NUT_LEAD_SLOPE + nut, lane] = 0.0


@numba.njit(**KERNEL)
def _nut_kinematics(x, c, w, lanes, rows):
    """:func:`_nut_kinematics_at` in every lane (the lead-error branch decided once for the group)."""
    errors = has_lead_error(c, lanes)
    for nut in range(2):
        if errors:
            for lane in range(lanes):
                _nut_kinematics_at(x, c, w, lane, nut, rows, True)
        else:
            for lane in range(lanes):
                _nut_kinematics_at(x, c, w, lane, nut, rows, False)


@numba.njit(**SCALAR)
def _axial_stiffness_at(x, c, w, lane):
    """Axial stiffness of the screw seen by the nuts [N/m] and its energy-gradient push on the sled [N].

    The rear bearing in series with the shaft ``E A / (l0 + x_n1)`` (Sec. 9.3) and, at the ``static``
    ``screw_torsion`` fidelity, the shaft's torsion between the coupling and the nuts. The coupling
    sits at the rear-bearing end (assumption, docs/model.md), so the twisted length is the same
    ``l = l0 + x_n1``; the shaft carries the nuts' torque ``(p/2pi)(f_1 + f_2)``, whose twist
    ``(p/2pi)(f_1 + f_2) l / (G J_p)`` moves both nuts' relative position (Eq. 9.5) exactly as an axial
    compliance ``(p/2pi)^2 l / (G J_p)`` in series with the shaft's (a static compliance: the shaft's
    own inertia, 3 % of the screw-side inertia, stays with the coupling's). The stiffness depends on the
    sled position, so the spring energy ``k(x_n1) x_s^2 / 2`` also pushes the sled with
    ``-dE/dx_n1 = k^2 x_s^2 (1/(E A) + (p/2pi)^2/(G J_p)) / 2``: tiny, but it keeps the model conservative.
    """
    length = c[K.SHAFT_LENGTH_0, lane] + x[S.NUT1_POSITION, lane]
    twist = c[K.SHAFT_TWIST_COMPLIANCE, lane]
    w[W.AXIAL_STIFFNESS, lane] = 1.0 / (1.0 / c[K.BEARING_STIFFNESS, lane] + length / c[K.SHAFT_EA, lane]
                                        + length * twist)


@numba.njit(**SCALAR)
def _axial_gradient_at(x, c, w, lane):
    """The axial spring energy's push on the sled, ``k^2 x_s^2 (1/(E A) + (p/2pi)^2/(G J_p)) / 2`` [N]
    (:func:`_axial_stiffness_at`), at the screw's axial displacement of this evaluation."""
    stiffness = w[W.AXIAL_STIFFNESS, lane]
    half_squared = 0.5 * stiffness * stiffness * x[S.SCREW_AXIAL, lane] * x[S.SCREW_AXIAL, lane]
    twist = c[K.SHAFT_TWIST_COMPLIANCE, lane]
    w[W.AXIAL_GRADIENT, lane] = half_squared / c[K.SHAFT_EA, lane] + half_squared * twist


@numba.njit(**SCALAR)
def _balance_step_at(x, c, w, lane, contact_model):
    """One Newton step of the quasi-static screw-axial balance in one lane (a no-op once it is solved).

    ``k(x_n1) x_s + f_1^el(x_s + a_1) + f_2^el(x_s + a_2) = 0``: the rear bearing and shaft against the two
    contacts' elastic forces (:func:`twin.physics.ball_screw.nut_elastic_force`), with ``a_i`` the kinematic part of
    ``dx_i``. Its left side grows with ``x_s`` (every term does), so the root is unique. The axial speed is the
    balance's time derivative, ``v_s = -(k_1 b_1 + k_2 b_2 + x_s v_n1 dk/dx_n1) / (k + k_1 + k_2)`` with ``k_i`` the
    contacts' tangent stiffnesses and ``b_i`` the rates of ``a_i``.
    """
    position = x[S.SCREW_AXIAL, lane]
    f1, k1 = nut_elastic_force(
        position + w[W.NUT_KINEMATIC, lane], c[K.BACKLASH, lane], c[K.COS_HELIX, lane],
        c[K.CENTRE_DISTANCE, lane], c[K.CONTACT_RADIAL_0, lane], c[K.CONTACT_AXIAL_0, lane],
        c[K.SIN_ALPHA_0, lane], _stiffness(c, lane), c[K.SIN_ALPHA_MIN, lane], c[K.SIN_ALPHA_SPAN, lane],
        c[K.LOADED_BALLS, lane], contact_model, c[K.LINEAR_CONTACT_STIFFNESS, lane])
    f2, k2 = nut_elastic_force(
        position + w[W.NUT_KINEMATIC + 1, lane], c[K.BACKLASH, lane], c[K.COS_HELIX, lane],
        c[K.CENTRE_DISTANCE, lane], c[K.CONTACT_RADIAL_0, lane], c[K.CONTACT_AXIAL_0, lane],
        c[K.SIN_ALPHA_0, lane], _stiffness(c, lane), c[K.SIN_ALPHA_MIN, lane], c[K.SIN_ALPHA_SPAN, lane],
        c[K.LOADED_BALLS, lane], contact_model, c[K.LINEAR_CONTACT_STIFFNESS, lane])
    stiffness = w[W.AXIAL_STIFFNESS, lane]
    slope = stiffness + k1 + k2
    correction = (stiffness * position + f1 + f2) / slope
    done = w[W.BALANCE_DONE, lane] > 0.0
    x[S.SCREW_AXIAL, lane] = position if done else position - correction
    # the rate of the balance, from the tangents at the last iterate (dk/dx_n1 = -k^2 (1/EA + twist))
    gradient = -stiffness * stiffness * (1.0 / c[K.SHAFT_EA, lane] + c[K.SHAFT_TWIST_COMPLIANCE, lane])
    rate = -(k1 * w[W.NUT_RATE, lane] + k2 * w[W.NUT_RATE + 1, lane]
             + position * gradient * x[S.NUT1_SPEED, lane]) / slope
    x[S.SCREW_AXIAL_SPEED, lane] = x[S.SCREW_AXIAL_SPEED, lane] if done else rate
    w[W.BALANCE_DONE, lane] = 1.0 if done or abs(correction) <= BALANCE_TOLERANCE else 0.0


@numba.njit(**SCALAR)
def _stiffness(c, lane):
    """The stiffness fit's coefficients of one lane, as a tuple (:func:`twin.physics.ball_screw.stiffness_at`)."""
    return (c[K.STIFFNESS_C0, lane], c[K.STIFFNESS_C1, lane], c[K.STIFFNESS_C2, lane], c[K.STIFFNESS_C3, lane],
            c[K.STIFFNESS_C4, lane], c[K.STIFFNESS_C5, lane], c[K.STIFFNESS_C6, lane])


@numba.njit(**KERNEL)
def _unsolved(w, lanes):
    """Whether any lane's quasi-static balance is still unsolved."""
    remaining = 0.0
    for lane in range(lanes):
        remaining += 1.0 - w[W.BALANCE_DONE, lane]
    return remaining > 0.0


@numba.njit(**SCALAR)
def _balance_failed_at(w, lane):
    """Flag a lane whose balance is still unsolved after :data:`BALANCE_ITERATIONS` (the guard reads it)."""
    w[W.BALANCE_FAILED, lane] = 1.0 if w[W.BALANCE_DONE, lane] == 0.0 else w[W.BALANCE_FAILED, lane]


@numba.njit(**KERNEL)
def screw_axial_balance(x, c, w, lanes, contact_model):
    """The quasi-static screw-axial level: solve the balance (:func:`_balance_step_at`, Newton from the last
    solution, warm-started by the lane's own ``S.SCREW_AXIAL`` row) in every lane, writing ``S.SCREW_AXIAL`` and
    ``S.SCREW_AXIAL_SPEED`` of ``x``; a lane still unsolved after :data:`BALANCE_ITERATIONS` is flagged in
    ``W.BALANCE_FAILED``. Each lane iterates until its own correction is below :data:`BALANCE_TOLERANCE` (a solved
    lane's step changes nothing), so its result does not depend on how long its lane mates need."""
    for lane in range(lanes):
        w[W.BALANCE_DONE, lane] = 0.0
    for _ in range(BALANCE_ITERATIONS):
        for lane in range(lanes):
            _balance_step_at(x, c, w, lane, contact_model)
        if not _unsolved(w, lanes):
            return
    for lane in range(lanes):
        _balance_failed_at(w, lane)


@numba.njit(**SCALAR)
def _screw_axial_balance_at(x, c, w, lane, contact_model):
    """:func:`screw_axial_balance` in one lane: the same Newton steps, stopped when this lane is solved."""
    w[W.BALANCE_DONE, lane] = 0.0
    for _ in range(BALANCE_ITERATIONS):
        _balance_step_at(x, c, w, lane, contact_model)
        if w[W.BALANCE_DONE, lane] > 0.0:
            return
    _balance_failed_at(w, lane)


@numba.njit(**SCALAR)
def _relative_motion_at(x, w, lane, nut):
    """``dx_i`` and its rate with the screw's axial displacement (quasi-static level)."""
    w[W.NUT_DX + nut, lane] = x[S.SCREW_AXIAL, lane] + w[W.NUT_KINEMATIC + nut, lane]
    w[W.NUT_DV + nut, lane] = x[S.SCREW_AXIAL_SPEED, lane] + w[W.NUT_RATE + nut, lane]


@numba.njit(**SCALAR)
def _dynamic_relative_motion_at(x, w, lane, nut):
    """Add the screw's axial displacement and speed (dynamic level) to the kinematic ``dx_i`` rows."""
    w[W.NUT_DX + nut, lane] += x[S.SCREW_AXIAL, lane]
    w[W.NUT_DV + nut, lane] += x[S.SCREW_AXIAL_SPEED, lane]


@numba.njit(**SCALAR)
def _contact_at(c, w, lane, nut, contact_model):
    """Axial force and per-sphere normal load of nut ``nut`` (Eqs. 9.4-9.6, 7.28, 7.29)."""
    force, normal, _ = nut_axial_force(
        w[W.NUT_DX + nut, lane], w[W.NUT_DV + nut, lane], c[K.BACKLASH, lane], c[K.COS_HELIX, lane],
        c[K.CENTRE_DISTANCE, lane], c[K.CONTACT_RADIAL_0, lane], c[K.CONTACT_AXIAL_0, lane],
        c[K.SIN_ALPHA_0, lane], _stiffness(c, lane), c[K.SIN_ALPHA_MIN, lane], c[K.SIN_ALPHA_SPAN, lane],
        c[K.CONTACT_DAMPING, lane], c[K.LOADED_BALLS, lane], contact_model,
        c[K.LINEAR_CONTACT_STIFFNESS, lane])
    w[W.NUT_FORCE + nut, lane] = force
    w[W.NUT_NORMAL + nut, lane] = normal


@numba.njit(**SCALAR)
def _force_demand(t, pneumatics, force_table):
    """The scene's force demand at ``t`` where the ideal load source applies it, else 0 (shared by a group)."""
    return profile_value(force_table, t) if pneumatics == PNEUMATICS_IDEAL else 0.0


@numba.njit(**SCALAR)
def _external_force_at(x, c, w, lane, pneumatics, demand):
    """External force on the master nut [N, +x]: the load cell's spring force (full pneumatics), the scene's
    force demand ``demand`` (ideal source, :func:`_force_demand`) or nothing (absent)."""
    if pneumatics == PNEUMATICS_FULL:
        w[W.EXTERNAL, lane] = pn.load_cell_spring_force(
            x[S.PISTON_POSITION, lane] - c[K.LINK_OFFSET, lane], x[S.NUT1_POSITION, lane],
            x[S.PISTON_SPEED, lane], x[S.NUT1_SPEED, lane], c[K.LOAD_CELL_STIFFNESS, lane],
            c[K.LOAD_CELL_DAMPING, lane])
    else:
        w[W.EXTERNAL, lane] = demand


@numba.njit(**SCALAR)
def _groove_friction_at(x, c, w, lane, nut, chapter5):
    """Helix friction force of nut ``nut`` along ``v_t`` [N] (reduced Ch. 5, Eqs. 5.16-5.24) at the ``chapter5``
    level, else 0."""
    if not chapter5:
        w[W.NUT_FRICTION + nut, lane] = 0.0
        return
    position = S.NUT1_POSITION + NUT_STATE_STRIDE * nut
    speed = tangential_speed(x[S.SCREW_SPEED, lane], x[position + 3, lane], x[S.SCREW_AXIAL_SPEED, lane],
                             x[position + 1, lane], c[K.PITCH_RADIUS, lane], c[K.COS_HELIX, lane],
                             c[K.SIN_HELIX, lane])
    w[W.NUT_FRICTION + nut, lane] = nut_friction_force(
        w[W.NUT_NORMAL + nut, lane], speed, c[K.LOADED_BALLS, lane], c[K.BALL_RADIUS, lane],
        c[K.FRICTION_G1, lane], c[K.FRICTION_G2, lane], c[K.FRICTION_G3, lane], c[K.FRICTION_G4, lane],
        c[K.FRICTION_G5, lane], c[K.FRICTION_G6, lane], c[K.ROLLING_K_GC, lane], c[K.ROLLING_K_RF, lane],
        c[K.ROLLING_F_V1, lane], c[K.ROLLING_THRESHOLD, lane])


@numba.njit(**KERNEL)
def _internal_forces_at(x, c, w, lane, levels, demand, errors):
    """:func:`internal_forces` of one lane, fused (``demand``: :func:`_force_demand`; ``errors``:
    :func:`has_lead_error` of its group). Not inlined: :func:`internal_forces` and :func:`rhs_at` call the one
    compiled copy (inlining it twice costs compile time and gains nothing measurable)."""
    contact_model = levels[CONTACT]
    _axial_stiffness_at(x, c, w, lane)
    if levels[SCREW_AXIAL] == SCREW_AXIAL_DYNAMIC:
        for nut in range(2):
            _nut_kinematics_at(x, c, w, lane, nut, W.NUT_DX, errors)
        for nut in range(2):
            _dynamic_relative_motion_at(x, w, lane, nut)
    else:
        for nut in range(2):
            _nut_kinematics_at(x, c, w, lane, nut, W.NUT_KINEMATIC, errors)
        _screw_axial_balance_at(x, c, w, lane, contact_model)
        for nut in range(2):
            _relative_motion_at(x, w, lane, nut)
    _axial_gradient_at(x, c, w, lane)
    for nut in range(2):
        _contact_at(c, w, lane, nut, contact_model)
    component_forces(x, c, w, range(lane, lane + 1), levels)
    _external_force_at(x, c, w, lane, levels[PNEUMATICS], demand)
    chapter5 = levels[BALL_GROOVE_FRICTION] == BALL_GROOVE_FRICTION_CHAPTER5
    for nut in range(2):
        _groove_friction_at(x, c, w, lane, nut, chapter5)


@numba.njit(**KERNEL)
def internal_forces(t, x, c, w, lanes, levels, force_table):
    """The coupling forces of the mechanical chain at state ``x`` into the work rows (:class:`W`): torque
    through the couplings, the screw-axial balance at the quasi-static level (which writes ``S.SCREW_AXIAL`` and
    ``S.SCREW_AXIAL_SPEED`` of ``x``), the contacts, the preload, the external force and, at the ``chapter5``
    level, the ball-groove friction. What the right-hand side, the recorder and the instruments read."""
    demand = _force_demand(t, levels[PNEUMATICS], force_table)
    if lanes <= FUSED_LANES:
        errors = has_lead_error(c, lanes)
        for lane in range(lanes):
            _internal_forces_at(x, c, w, lane, levels, demand, errors)
        return
    contact_model = levels[CONTACT]
    for lane in range(lanes):
        _axial_stiffness_at(x, c, w, lane)
    if levels[SCREW_AXIAL] == SCREW_AXIAL_DYNAMIC:
        _nut_kinematics(x, c, w, lanes, W.NUT_DX)
        for nut in range(2):
            for lane in range(lanes):
                _dynamic_relative_motion_at(x, w, lane, nut)
    else:
        _nut_kinematics(x, c, w, lanes, W.NUT_KINEMATIC)
        screw_axial_balance(x, c, w, lanes, contact_model)
        for nut in range(2):
            for lane in range(lanes):
                _relative_motion_at(x, w, lane, nut)
    for lane in range(lanes):
        _axial_gradient_at(x, c, w, lane)
    for nut in range(2):
        for lane in range(lanes):
            _contact_at(c, w, lane, nut, contact_model)
    component_forces(x, c, w, range(lanes), levels)
    pneumatics = levels[PNEUMATICS]
    for lane in range(lanes):
        _external_force_at(x, c, w, lane, pneumatics, demand)
    if levels[BALL_GROOVE_FRICTION] == BALL_GROOVE_FRICTION_CHAPTER5:
        for nut in range(2):
            for lane in range(lanes):
                _groove_friction_at(x, c, w, lane, nut, True)
    else:
        for nut in range(2):
            for lane in range(lanes):
                _groove_friction_at(x, c, w, lane, nut, False)


@numba.njit(**KERNEL)
def measurands(t, x, c, w, lanes, levels, force_table):
    """What the analog instruments measure after a step, without the contacts: the torque through the couplings,
    the preload and the external force into the work rows (the current is read off the state)."""
    demand = _force_demand(t, levels[PNEUMATICS], force_table)
    pneumatics = levels[PNEUMATICS]
    if lanes <= FUSED_LANES:
        for lane in range(lanes):
            component_forces(x, c, w, range(lane, lane + 1), levels)
            _external_force_at(x, c, w, lane, pneumatics, demand)
        return
    component_forces(x, c, w, range(lanes), levels)
    for lane in range(lanes):
        _external_force_at(x, c, w, lane, pneumatics, demand)


@numba.njit(**SCALAR)
def current_loop_voltage(x, c, u, lane):
    """The analog current PI's output (the demanded voltage) and the voltage the inverter applies to the equivalent
    circuit, limited to ``K.VOLTAGE_LIMIT`` (:func:`twin.physics.motor.equivalent_voltage_limit`) [V]."""
    demand_voltage = (c[K.CURRENT_KP, lane] * (u[U.CURRENT_DEMAND, lane] - x[S.HALL_CURRENT, lane])
                      + x[S.CURRENT_PI, lane])
    limit = c[K.VOLTAGE_LIMIT, lane]
    return min(max(demand_voltage, -limit), limit), demand_voltage


@numba.njit(**SCALAR)
def _drive_current_at(x, c, u, dxdt, lane, current_loop):
    """The drive's current: the full loop (winding current, Eq. 9.1, power-consistent: :mod:`twin.physics.motor`,
    Hall sensor and analog PI with back-calculation anti-windup) or the ideal lag at the loop's bandwidth."""
    if current_loop == CURRENT_LOOP_FULL:
        demand = u[U.CURRENT_DEMAND, lane]
        voltage, demand_voltage = current_loop_voltage(x, c, u, lane)
        resistance = winding_resistance(x[S.WINDING_TEMP, lane], c[K.R20, lane], c[K.R_TEMP_COEF, lane])
        dxdt[S.CURRENT, lane] = current_derivative(voltage, x[S.CURRENT, lane], x[S.REDUCER_SPEED, lane], resistance,
                                                   c[K.INDUCTANCE, lane], c[K.TORQUE_CONSTANT, lane], c[K.RATIO, lane])
        dxdt[S.CURRENT_PI, lane] = (c[K.CURRENT_KI, lane] * (demand - x[S.HALL_CURRENT, lane])
                                    + (voltage - demand_voltage) / c[K.CURRENT_AW_TIME, lane])
        dxdt[S.HALL_CURRENT, lane] = (x[S.CURRENT, lane] - x[S.HALL_CURRENT, lane]) / c[K.HALL_TAU, lane]
    else:
        dxdt[S.CURRENT, lane] = (u[U.CURRENT_DEMAND, lane] - x[S.CURRENT, lane]) / c[K.CURRENT_LOOP_TAU, lane]


@numba.njit(**SCALAR)
def _winding_thermal_at(x, c, dxdt, lane):
    """The winding temperature (Eq. 9.2) at the ``dynamic`` motor-thermal level."""
    temperature = x[S.WINDING_TEMP, lane]
    resistance = winding_resistance(temperature, c[K.R20, lane], c[K.R_TEMP_COEF, lane])
    dxdt[S.WINDING_TEMP, lane] = winding_temperature_derivative(
        temperature, c[K.AMBIENT, lane], resistance * x[S.CURRENT, lane] * x[S.CURRENT, lane],
        c[K.THERMAL_RESISTANCE, lane], c[K.THERMAL_TAU, lane], c[K.HEAT_TRANSFER, lane],
        c[K.MOTOR_AREA, lane], c[K.EMISSIVITY, lane])


@numba.njit(**SCALAR)
def _lead_error_torque(w, lane):
    """The lead error's share of the nuts' reaction torque on the screw, ``e'_1 f_1 + e'_2 f_2`` [N m]: the contact
    forces act through the local lead ``p/2pi + e'`` (:mod:`twin.physics.ball_screw`); 0 without a lead error."""
    return w[W.NUT_LEAD_SLOPE, lane] * w[W.NUT_FORCE, lane] + w[W.NUT_LEAD_SLOPE + 1, lane] * w[W.NUT_FORCE + 1, lane]


@numba.njit(**SCALAR)
def _rotation_at(x, c, w, dxdt, lane):
    """Screw rotation (Eq. 9.7) against the transmitted torque (:func:`twin.components.reducer.forces_at`)."""
    torque = w[W.TORQUE, lane]
    # the nuts' reaction on the screw is -(p/2pi) times the sum of their axial forces, plus the helix friction
    w_s = x[S.SCREW_SPEED, lane]
    friction_s = stribeck_friction(w_s, c[K.SCREW_FRICTION_STATIC, lane], c[K.SCREW_FRICTION_DYNAMIC, lane],
                                   c[K.SCREW_FRICTION_RATE, lane], c[K.SCREW_FRICTION_VISCOUS, lane],
                                   c[K.ANGULAR_V_THRESHOLD, lane])
    screw_1, _, _, _ = friction_generalised_forces(w[W.NUT_FRICTION, lane], c[K.PITCH_RADIUS, lane],
                                                   c[K.COS_HELIX, lane], c[K.SIN_HELIX, lane])
    screw_2, _, _, _ = friction_generalised_forces(w[W.NUT_FRICTION + 1, lane], c[K.PITCH_RADIUS, lane],
                                                   c[K.COS_HELIX, lane], c[K.SIN_HELIX, lane])
    dxdt[S.SCREW_ANGLE, lane] = w_s
    dxdt[S.SCREW_SPEED, lane] = (torque - c[K.SCREW_DAMPING, lane] * w_s - friction_s
                                 - c[K.LEAD_ARM, lane] * (w[W.NUT_FORCE, lane] + w[W.NUT_FORCE + 1, lane])
                                 - _lead_error_torque(w, lane) + screw_1 + screw_2) / c[K.J_SCREW_SIDE, lane]


@numba.njit(**SCALAR)
def _screw_axial_at(x, c, w, dxdt, lane):
    """Screw axial motion at the dynamic level: rear bearing in series with the shaft (and its twist) to the
    contacts (Sec. 9.3)."""
    _, _, axial_1, _ = friction_generalised_forces(w[W.NUT_FRICTION, lane], c[K.PITCH_RADIUS, lane],
                                                   c[K.COS_HELIX, lane], c[K.SIN_HELIX, lane])
    _, _, axial_2, _ = friction_generalised_forces(w[W.NUT_FRICTION + 1, lane], c[K.PITCH_RADIUS, lane],
                                                   c[K.COS_HELIX, lane], c[K.SIN_HELIX, lane])
    dxdt[S.SCREW_AXIAL, lane] = x[S.SCREW_AXIAL_SPEED, lane]
    dxdt[S.SCREW_AXIAL_SPEED, lane] = (
        -(w[W.NUT_FORCE, lane] + w[W.NUT_FORCE + 1, lane])
        - w[W.AXIAL_STIFFNESS, lane] * x[S.SCREW_AXIAL, lane] + axial_1 + axial_2
        - c[K.SCREW_AXIAL_DAMPING, lane] * x[S.SCREW_AXIAL_SPEED, lane]) / c[K.SCREW_MASS, lane]


@numba.njit(**SCALAR)
def _nut_at(x, c, w, dxdt, lane, nut, rotation):
    """Nut ``nut`` (Eq. 9.8): the master carries the external force, the preload acts between them, the guides'
    friction on each (:func:`twin.components.guides.friction_at`); its roll on the linear guides against the contact
    torque ``(p/2pi) f_i`` (Sec. 9.3) where the fidelity keeps it."""
    position = S.NUT1_POSITION + NUT_STATE_STRIDE * nut
    master = 1.0 if nut == 0 else 0.0
    _, nut_torque, _, nut_axial = friction_generalised_forces(
        w[W.NUT_FRICTION + nut, lane], c[K.PITCH_RADIUS, lane], c[K.COS_HELIX, lane], c[K.SIN_HELIX, lane])
    guide = guides.friction_at(x, c, lane, nut)
    preload_share = preload.nut_share_at(c, w[W.PRELOAD, lane], lane, master)
    master_loads = master * (w[W.EXTERNAL, lane] + w[W.AXIAL_GRADIENT, lane])
    dxdt[position, lane] = x[position + 1, lane]
    dxdt[position + 1, lane] = (w[W.NUT_FORCE + nut, lane] + nut_axial - guide + preload_share + master_loads
                                ) / c[K.NUT1_MASS + NUT_CONSTANT_STRIDE * nut, lane]
    if rotation == NUT_ROTATION_ON:
        dxdt[position + 2, lane] = x[position + 3, lane]
        dxdt[position + 3, lane] = (c[K.LEAD_ARM, lane] * w[W.NUT_FORCE + nut, lane]
                                    + w[W.NUT_LEAD_SLOPE + nut, lane] * w[W.NUT_FORCE + nut, lane] + nut_torque
                                    - c[K.GUIDE_ROLL_STIFFNESS, lane] * x[position + 2, lane]
                                    - c[K.GUIDE_ROLL_DAMPING, lane] * x[position + 3, lane]) / c[K.J_NUT, lane]


@numba.njit(**SCALAR)
def _pneumatics_at(x, c, u, w, dxdt, lane, seal_level):
    """Valve spool, chamber pressures and piston of the load system (Eqs. 9.9-9.11) of one lane: the one home of the
    load system's dynamics (the force-loop design linearises these same laws, twin.control.force_loop_design).
    ``seal_level`` is the seal-friction level's code, for the seals' law
    (:func:`twin.components.seal.friction_at`)."""
    dxdt[S.SPOOL_POSITION, lane], dxdt[S.SPOOL_SPEED, lane] = pn.spool_derivative(
        x[S.SPOOL_POSITION, lane], x[S.SPOOL_SPEED, lane], u[U.VALVE_COMMAND, lane], c[K.VALVE_MID, lane],
        c[K.VALVE_MIN, lane], c[K.VALVE_MAX, lane], c[K.VALVE_FREQUENCY, lane], c[K.VALVE_DAMPING, lane])
    p1 = x[S.CHAMBER1_PRESSURE, lane]
    p2 = x[S.CHAMBER2_PRESSURE, lane]
    temperature = c[K.AIR_TEMPERATURE, lane]
    g1, g2 = pn.chamber_mass_flows(
        x[S.SPOOL_POSITION, lane], p1, p2, c[K.P_SUPPLY, lane], c[K.P_ATMOSPHERE, lane],
        c[K.MAX_CONDUCTANCE, lane], c[K.LEAKAGE_FRACTION, lane], c[K.CRITICAL_RATIO, lane],
        c[K.REFERENCE_DENSITY, lane], c[K.REFERENCE_TEMPERATURE, lane], temperature, temperature,
        c[K.LAMINAR_RATIO, lane])
    v1, dv1, v2, dv2 = pn.chamber_volumes(x[S.PISTON_POSITION, lane], x[S.PISTON_SPEED, lane], c[K.AREA1, lane],
                                          c[K.AREA2, lane], c[K.DEAD_VOLUME1, lane], c[K.DEAD_VOLUME2, lane],
                                          c[K.STROKE, lane])
    dxdt[S.CHAMBER1_PRESSURE, lane] = pn.chamber_pressure_derivative(
        p1, g1, v1, dv1, temperature, c[K.GAS_CONSTANT, lane], c[K.POLYTROPIC_EXPONENT, lane])
    dxdt[S.CHAMBER2_PRESSURE, lane] = pn.chamber_pressure_derivative(
        p2, g2, v2, dv2, temperature, c[K.GAS_CONSTANT, lane], c[K.POLYTROPIC_EXPONENT, lane])
    dxdt[S.PISTON_POSITION, lane] = x[S.PISTON_SPEED, lane]
    friction = seal.friction_at(x, c, dxdt, lane, seal_level)
    dxdt[S.PISTON_SPEED, lane] = pn.piston_acceleration_under_friction(
        p1, p2, x[S.PISTON_POSITION, lane], x[S.PISTON_SPEED, lane], w[W.EXTERNAL, lane], c[K.AREA1, lane],
        c[K.AREA2, lane], c[K.P_ATMOSPHERE, lane], c[K.PISTON_MASS, lane], c[K.PISTON_DAMPING, lane],
        friction, c[K.STROKE, lane], c[K.DAMPER_TRAVEL, lane], c[K.DAMPER_STIFFNESS, lane],
        c[K.DAMPER_DAMPING, lane], c[K.END_STOP_STIFFNESS, lane])


@numba.njit(**KERNEL)
def pneumatics_rhs(x, c, u, w, dxdt, lanes, seal_level):
    """:func:`_pneumatics_at` in every lane."""
    for lane in range(lanes):
        _pneumatics_at(x, c, u, w, dxdt, lane, seal_level)


@numba.njit(**SCALAR)
def _derivatives_at(x, c, u, w, dxdt, lane, levels):
    """The derivatives of one lane from its work rows (:func:`_internal_forces_at`), fused: the components'
    stages, then the engine's own."""
    component_derivatives(x, c, u, w, dxdt, range(lane, lane + 1), levels)
    _drive_current_at(x, c, u, dxdt, lane, levels[CURRENT_LOOP])
    if levels[MOTOR_THERMAL] == THERMAL_DYNAMIC:
        _winding_thermal_at(x, c, dxdt, lane)
    _rotation_at(x, c, w, dxdt, lane)
    if levels[SCREW_AXIAL] == SCREW_AXIAL_DYNAMIC:
        _screw_axial_at(x, c, w, dxdt, lane)
    for nut in range(2):
        _nut_at(x, c, w, dxdt, lane, nut, levels[NUT_ROTATION])
    if levels[PNEUMATICS] == PNEUMATICS_FULL:
        _pneumatics_at(x, c, u, w, dxdt, lane, levels[seal.SEAL_FRICTION])


@numba.njit(**KERNEL)
def rhs_at(t, x, c, u, levels, force_table, dxdt, w, lane, errors):
    """:func:`rhs` of lane ``lane`` alone, fused (``errors``: :func:`has_lead_error` of its group): the per-sample
    form a fused integrator step composes (:mod:`twin.engine.integrators`)."""
    _internal_forces_at(x, c, w, lane, levels, _force_demand(t, levels[PNEUMATICS], force_table), errors)
    _derivatives_at(x, c, u, w, dxdt, lane, levels)


@numba.njit(**KERNEL)
def rhs(t, x, c, u, levels, force_table, dxdt, w):
    """Write ``dx/dt`` of every lane of a group into ``dxdt``.

    Only the derivatives of the states the group's fidelity levels keep are written; the integrators advance only
    those (:attr:`twin.engine.model.Model.active`). At the quasi-static screw-axial level the balance writes
    ``S.SCREW_AXIAL`` and ``S.SCREW_AXIAL_SPEED`` of ``x`` (states it removes from integration; each lane's row
    is also its Newton warm start). A group of at most ``FUSED_LANES`` lanes takes the fused form, the others the
    split form (the same stages, the same bits).

    Parameters
    ----------
    t : float
        Time [s].
    x, c, u : 2-D arrays ``[row, lane]``
        State (layout :class:`twin.layout.S`), model constants (:class:`twin.layout.K`) and the inputs held by the
        digital loops (:class:`twin.layout.U`).
    levels : 1-D int array
        The group's level code of every subsystem (:func:`twin.levels.level_codes`).
    force_table : 2-D array
        The scene's compiled external-force profile.
    dxdt, w : 2-D arrays
        Outputs: the derivatives and the work rows (:class:`W`).
    """
    lanes = x.shape[1]
    if lanes <= FUSED_LANES:
        errors = has_lead_error(c, lanes)
        for lane in range(lanes):
            rhs_at(t, x, c, u, levels, force_table, dxdt, w, lane, errors)
        return
    internal_forces(t, x, c, w, lanes, levels, force_table)
    component_derivatives(x, c, u, w, dxdt, range(lanes), levels)
    current_loop = levels[CURRENT_LOOP]
    if current_loop == CURRENT_LOOP_FULL:
        for lane in range(lanes):
            _drive_current_at(x, c, u, dxdt, lane, CURRENT_LOOP_FULL)
    else:
        for lane in range(lanes):
            _drive_current_at(x, c, u, dxdt, lane, current_loop)
    if levels[MOTOR_THERMAL] == THERMAL_DYNAMIC:
        for lane in range(lanes):
            _winding_thermal_at(x, c, dxdt, lane)
    for lane in range(lanes):
        _rotation_at(x, c, w, dxdt, lane)
    if levels[SCREW_AXIAL] == SCREW_AXIAL_DYNAMIC:
        for lane in range(lanes):
            _screw_axial_at(x, c, w, dxdt, lane)
    rotation = levels[NUT_ROTATION]
    for nut in range(2):
        for lane in range(lanes):
            _nut_at(x, c, w, dxdt, lane, nut, rotation)
    if levels[PNEUMATICS] == PNEUMATICS_FULL:
        pneumatics_rhs(x, c, u, w, dxdt, lanes, levels[seal.SEAL_FRICTION])


EFFICIENCY_POWER_FLOOR = 1.0e-3  # W: below this input power the efficiency is reported as 0 (at rest)


@numba.njit(**SCALAR)
def ball_screw_outputs(x, c, w, lane):
    """Ball-screw output signals of one lane from the work rows of :func:`internal_forces`.

    Returns
    -------
    (friction_torque, efficiency, twist, axial_displacement)
        Ball-groove friction torque opposing the screw rotation, both nuts [N m] (Eqs. 5.17-5.18 in the
        reduced form; without external force, the drag torque of Eq. 7.85); the efficiency of Eq. 5.25
        (below); the shaft twist between the coupling and the nuts [rad]; the screw's axial
        displacement without the twist's share of ``x_s`` [m] (:func:`_axial_stiffness`).

    Notes
    -----
    Eq. 5.25 excludes the inertial terms: the input is the torque the screw puts into the ball-groove
    contacts (the nuts' reaction ``(p/2pi)(f_1+f_2)`` plus the friction torque) times the screw speed, the
    output the axial force of the contacts on the nuts (friction included) times the nuts' speeds.
    Driving (both powers positive), ``eta = P_out / P_in`` in (0, 1). Back-driving (the load drives the
    screw, both negative), ``eta = -P_in / P_out``: the magnitude is the inverse efficiency, the negative
    sign the reversed power flow ("when the motor brakes the action of the external force, it assumes a
    negative sign", Sec. 5.5). Powers of opposite signs (both enter the screw: a reversal, a gap
    crossing) or an input below ``EFFICIENCY_POWER_FLOOR`` give 0, where Fig. 5.18 drops to zero.
    """
    screw_1, _, _, nut_axial_1 = friction_generalised_forces(w[W.NUT_FRICTION, lane], c[K.PITCH_RADIUS, lane],
                                                             c[K.COS_HELIX, lane], c[K.SIN_HELIX, lane])
    screw_2, _, _, nut_axial_2 = friction_generalised_forces(w[W.NUT_FRICTION + 1, lane], c[K.PITCH_RADIUS, lane],
                                                             c[K.COS_HELIX, lane], c[K.SIN_HELIX, lane])
    f1, f2 = w[W.NUT_FORCE, lane], w[W.NUT_FORCE + 1, lane]
    friction_torque = -(screw_1 + screw_2)
    power_in = ((c[K.LEAD_ARM, lane] * (f1 + f2) + _lead_error_torque(w, lane) + friction_torque)
                * x[S.SCREW_SPEED, lane])
    power_out = (f1 + nut_axial_1) * x[S.NUT1_SPEED, lane] + (f2 + nut_axial_2) * x[S.NUT2_SPEED, lane]
    efficiency = 0.0
    if power_in > EFFICIENCY_POWER_FLOOR and power_out >= 0.0:
        efficiency = power_out / power_in
    elif power_in < -EFFICIENCY_POWER_FLOOR and power_out < 0.0:
        efficiency = -power_in / power_out
    stiffness = w[W.AXIAL_STIFFNESS, lane]
    length = c[K.SHAFT_LENGTH_0, lane] + x[S.NUT1_POSITION, lane]
    # series springs carry the same force -k x_s: each share of x_s is its compliance times that force
    twist = -stiffness * x[S.SCREW_AXIAL, lane] * length * c[K.SHAFT_TWIST_COMPLIANCE, lane] / c[K.LEAD_ARM, lane]
    axial = stiffness * x[S.SCREW_AXIAL, lane] * (1.0 / c[K.BEARING_STIFFNESS, lane] + length / c[K.SHAFT_EA, lane])
    return friction_torque, efficiency, twist, axial


@numba.njit(**SCALAR)
def sensed_current(x, c, lane, current_loop):
    """Current seen by the Hall sensor [A]: its filter state, or the current itself when the ideal
    current loop has no sensor dynamics."""
    return x[S.HALL_CURRENT, lane] if current_loop == CURRENT_LOOP_FULL else x[S.CURRENT, lane]


@numba.njit(**SCALAR)
def held_input_propagators(c, h, lane, cache):
    """Exact one-step propagators of the two linear blocks driven by a held input: the valve spool
    (second order, Table B.12: ``x'' = w^2 (s - x) - 2 zeta w x'``) and the ideal current loop's lag, for lane
    ``lane`` into ``cache[:, lane]``.

    ``cache[:8]`` holds ``(h, w, zeta, tau, Phi00, Phi01, Phi10, Phi11)`` and is refreshed only when a key
    changes: the matrix exponential ``Phi = exp(A h)`` of the spool (Moler & Van Loan, SIAM Review 45, 2003,
    Method 1 (Lagrange/Sylvester form) for a 2 x 2 matrix, with the double-eigenvalue limit at ``zeta = 1``)
    and ``cache[8] = 1 - exp(-h / tau)``. Exact under the zero-order hold because the steps divide both
    controllers' periods; the exponential Euler of Hochbruck & Ostermann (Acta Numerica 19, 2010, Sec. 2.1).
    """
    omega = 2.0 * math.pi * c[K.VALVE_FREQUENCY, lane]
    zeta = c[K.VALVE_DAMPING, lane]
    tau = c[K.CURRENT_LOOP_TAU, lane]
    if cache[0, lane] == h and cache[1, lane] == omega and cache[2, lane] == zeta and cache[3, lane] == tau:
        return
    cache[0, lane], cache[1, lane], cache[2, lane], cache[3, lane] = h, omega, zeta, tau
    discriminant = zeta * zeta - 1.0
    if 2.0 * math.sqrt(abs(discriminant)) > 1e-9:  # distinct eigenvalues, else the double-eigenvalue limit
        if discriminant > 0.0:  # over-damped: two real poles
            root = math.sqrt(discriminant) * omega
            first, second = -zeta * omega + root, -zeta * omega - root
            e1, e2 = math.exp(first * h), math.exp(second * h)
            identity_part = (first * e2 - second * e1) / (first - second)
            a_part = (e1 - e2) / (first - second)
        else:  # under-damped: complex pair -zeta w +- j w_d
            damped = math.sqrt(-discriminant) * omega
            decay = math.exp(-zeta * omega * h)
            cosine, sine = math.cos(damped * h), math.sin(damped * h)
            identity_part = decay * (cosine + zeta * omega * sine / damped)
            a_part = decay * sine / damped
    else:
        decay = math.exp(-omega * h)
        identity_part = decay * (1.0 + omega * h)
        a_part = decay * h
    # Phi = identity_part I + a_part A, A = [[0, 1], [-w^2, -2 zeta w]]
    cache[4, lane] = identity_part
    cache[5, lane] = a_part
    cache[6, lane] = -a_part * omega * omega
    cache[7, lane] = identity_part - 2.0 * zeta * omega * a_part
    cache[8, lane] = -math.expm1(-h / tau)
