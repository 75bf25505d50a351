"""The reducer between the motor and the screw, with the torsional chain it drives (Eq. 9.3, Sec. 9.3): the whole
component in one module.

What it holds, and who reads it:

* the derivation of its constants from its parameters (:func:`reflected_inertia`, :func:`derive_constants`):
  the engine's model (:func:`twin.engine.model.build_model`) and the loop design (:mod:`twin.control.design`) take
  the same motor-side inertia from here; the fidelity rules the motor speed of a demand (:func:`motor_speed`);
* its laws: Eq. 9.3 for the reducer output (:func:`reducer_rhs_at`) and the torsional elasto-backlash of reducer,
  couplings and torque meter (:func:`transmitted_torque_at`, the law of :mod:`twin.physics.coupling`);
* its lane stage, one lane at a time (``*_at``, :data:`numerics.jit.SCALAR`): the engine composes it split over
  the lanes or fused per sample (:mod:`twin.engine.plant`);
* its contribution to the linearly implicit step's tangent (:func:`torsion_tangent_at`, :func:`friction_slope_at`;
  :mod:`twin.engine.implicit` places them on its degree of freedom);
* its energy terms (:func:`energy`, :mod:`twin.engine.energy`) and the reference integrator's tolerances of its
  states (:data:`ABSOLUTE_TOLERANCES`, :mod:`twin.engine.reference`);
* its fidelity levels: none (:data:`LEVELS`; the chain is always modelled, :mod:`twin.levels`).

Its states, constants, signals and work row are declared in its leaf module, :mod:`twin.vocabulary.reducer`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numba
import numpy as np

from numerics.jit import SCALAR
from twin.components.conditions import Conditions
from twin.layout import K, S, W
from twin.physics.coupling import elasto_backlash, elasto_backlash_energy
from twin.physics.drivetrain import torsional_stiffness
from twin.physics.friction import stribeck_friction, stribeck_slope

NAME = "reducer"
#: The reducer's fidelity levels (subsystems of :mod:`twin.levels`): none.
LEVELS: tuple[str, ...] = ()
#: Absolute tolerances of its states on the reference path (:mod:`twin.engine.reference`): the angle to 1e-12 rad,
#: the speed to 1e-10 rad/s (the scale of the screw's, which the reducer drives).
ABSOLUTE_TOLERANCES = {S.REDUCER_ANGLE: 1e-12, S.REDUCER_SPEED: 1e-10}


def reflected_inertia(p: Mapping[str, float]) -> float:
    """Motor and reducer inertia about the reducer output, ``(J_m + J_r) tau_mr^2`` [kg m^2] (Eq. 9.3 written for the
    reducer output angle)."""
    return (p["motor.inertia"] + p["reducer.inertia"]) * p["reducer.ratio"] ** 2


def motor_speed(output_speed: float, p: Mapping[str, float]) -> float:
    """Motor shaft speed [rad/s] at the reducer output speed ``output_speed`` [rad/s] (the ratio ``tau_mr``)."""
    return output_speed * p["reducer.ratio"]


def derive_constants(c: np.ndarray, p: Mapping[str, float], scene: Conditions) -> None:
    """Fill the reducer's derived constants into ``c`` (layout :class:`twin.layout.K`): the reflected inertia and
    the series torsional stiffness of reducer, couplings and torque meter (:func:`twin.physics.drivetrain.
    torsional_stiffness`); the scene's conditions do not enter. Its other constants copy a parameter (their
    ``Entry.parameter``)."""
    c[K.J_MOTOR_SIDE] = reflected_inertia(p)
    c[K.TORSION_STIFFNESS] = torsional_stiffness(p)


@numba.njit(**SCALAR)
def motor_speed_at(x, c, lane):
    """Motor shaft speed ``tau_mr omega_r`` [rad/s] of lane ``lane``."""
    return c[K.RATIO, lane] * x[S.REDUCER_SPEED, lane]


@numba.njit(**SCALAR)
def motor_angle_at(x, c, lane):
    """Motor shaft angle ``tau_mr theta_r`` [rad] of lane ``lane`` (what the resolver reads)."""
    return c[K.RATIO, lane] * x[S.REDUCER_ANGLE, lane]


@numba.njit(**SCALAR)
def transmitted_torque_at(x, c, lane):
    """Torque through the couplings and the torque meter ``T_tm`` [N m]: the torsional elasto-backlash between the
    reducer output and the screw (Sec. 9.3)."""
    return elasto_backlash(
        x[S.REDUCER_ANGLE, lane] - x[S.SCREW_ANGLE, lane], x[S.REDUCER_SPEED, lane] - x[S.SCREW_SPEED, lane],
        c[K.TORSION_STIFFNESS, lane], c[K.TORSION_DAMPING, lane], c[K.REDUCER_BACKLASH, lane])


@numba.njit(**SCALAR)
def reducer_rhs_at(x, c, torque, dxdt, lane):
    """Eq. 9.3 written for the reducer output: the motor torque ``k_t i`` through the reducer's efficiency, the motor's
    viscous damping and the motor-reducer friction against the transmitted torque ``torque``
    (:func:`transmitted_torque_at`), into ``dxdt`` of lane ``lane``."""
    ratio = c[K.RATIO, lane]
    w_r = x[S.REDUCER_SPEED, lane]
    friction_mr = stribeck_friction(w_r, c[K.MR_FRICTION_STATIC, lane], c[K.MR_FRICTION_DYNAMIC, lane],
                                    c[K.MR_FRICTION_RATE, lane], 0.0, c[K.ANGULAR_V_THRESHOLD, lane])
    drive = (c[K.TORQUE_CONSTANT, lane] * x[S.CURRENT, lane] * c[K.EFFICIENCY, lane]
             - c[K.MOTOR_VISCOUS, lane] * ratio * w_r) * ratio
    dxdt[S.REDUCER_ANGLE, lane] = w_r
    dxdt[S.REDUCER_SPEED, lane] = (drive - friction_mr - torque) / c[K.J_MOTOR_SIDE, lane]


@numba.njit(**SCALAR)
def torsion_tangent_at(x, c, lane):
    """The torsional chain's contribution to the implicit step's tangent: ``(engaged, stiffness, damping)`` of the
    elasto-backlash between the reducer output (+1) and the screw (-1); not engaged inside the play, and without
    its damping where the damping torque would exceed the elastic one (the law then saturates it)."""
    deflection = x[S.REDUCER_ANGLE, lane] - x[S.SCREW_ANGLE, lane]
    if abs(deflection) > 0.5 * c[K.REDUCER_BACKLASH, lane]:
        elastic = c[K.TORSION_STIFFNESS, lane] * (abs(deflection) - 0.5 * c[K.REDUCER_BACKLASH, lane])
        rate = x[S.REDUCER_SPEED, lane] - x[S.SCREW_SPEED, lane]
        damping = c[K.TORSION_DAMPING, lane] if c[K.TORSION_DAMPING, lane] * abs(rate) < elastic else 0.0
        return True, c[K.TORSION_STIFFNESS, lane], damping
    return False, 0.0, 0.0


@numba.njit(**SCALAR)
def friction_slope_at(x, c, lane):
    """The slope ``d(damping + friction)/d(omega_r)`` of Eq. 9.3's dissipative torques [N m s/rad]: the motor's
    viscous damping reflected through the reducer and the regularised motor-reducer friction."""
    ratio = c[K.RATIO, lane]
    return c[K.MOTOR_VISCOUS, lane] * ratio * ratio + stribeck_slope(
        x[S.REDUCER_SPEED, lane], c[K.MR_FRICTION_STATIC, lane], c[K.MR_FRICTION_DYNAMIC, lane], 0.0,
        c[K.ANGULAR_V_THRESHOLD, lane])


def energy(x: np.ndarray, c: np.ndarray) -> tuple[float, float]:
    """Kinetic energy of the motor side and elastic energy of the torsional chain of one run ``(kinetic, elastic)``
    [J] (``x``, ``c``: the run's full state and constants)."""
    kinetic = 0.5 * c[K.J_MOTOR_SIDE] * x[S.REDUCER_SPEED] ** 2
    elastic = elasto_backlash_energy(x[S.REDUCER_ANGLE] - x[S.SCREW_ANGLE], c[K.TORSION_STIFFNESS],
                                     c[K.REDUCER_BACKLASH])
    return kinetic, elastic


@numba.njit(**SCALAR)
def active(levels):
    """The chain is always modelled (no fidelity levels)."""
    return True


@numba.njit(**SCALAR)
def forces_at(x, c, w, lane):
    """Its work row: the transmitted torque ``T_tm`` (:func:`transmitted_torque_at`) into ``W.TORQUE``."""
    w[W.TORQUE, lane] = transmitted_torque_at(x, c, lane)


@numba.njit(**SCALAR)
def derivatives_at(x, c, u, w, dxdt, lane, levels):
    """Its states' derivatives: Eq. 9.3 against the transmitted torque of the forces phase (:func:`reducer_rhs_at`)."""
    reducer_rhs_at(x, c, w[W.TORQUE, lane], dxdt, lane)
