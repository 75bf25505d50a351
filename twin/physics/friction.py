"""Coulomb-Stribeck-viscous friction of supports (Eqs. 7.63 and 7.64)."""

import numba

from numerics import elementary
from numerics.jit import SCALAR


@numba.njit(**SCALAR)
def stribeck_friction(v, static, dynamic, stribeck_rate, viscous, v_threshold):
    """Support friction force (Eq. 7.63) or torque (Eq. 7.64).

    ``[F_d + (F_s - F_d) exp(-a |v|)] sign(v) + b v``, with ``sign(v)``
    regularised as ``tanh(v / v_threshold)``: the discontinuous Coulomb term
    would otherwise make any fixed-step integrator chatter at velocity
    reversals. The same regularisation as the thesis's friction laws, which
    "require an always present little amount of sliding" (Sec. 7.4.1).

    Parameters
    ----------
    v : float
        Sliding velocity [m/s or rad/s].
    static, dynamic : float
        Breakaway ``F_s`` and Coulomb ``F_d`` levels [N or N m].
    stribeck_rate : float
        ``a`` [s/m or s/rad].
    viscous : float
        ``b`` [N s/m or N m s/rad].
    v_threshold : float
        Regularisation velocity [m/s or rad/s], > 0.

    Returns
    -------
    float
        Friction force/torque, opposing ``v`` (positive for ``v > 0``).
    """
    return stribeck_level(v, static, dynamic, stribeck_rate) * elementary.tanh(v / v_threshold) + viscous * v


@numba.njit(**SCALAR)
def stribeck_level(v, static, dynamic, stribeck_rate):
    """Steady sliding friction level ``F_d + (F_s - F_d) exp(-a |v|)`` of Eq. 7.63 [N or N m] (the Coulomb and
    Stribeck part, without its sign): shared with the bristle laws of :mod:`twin.physics.bristle_friction`."""
    return dynamic + (static - dynamic) * elementary.exp(-stribeck_rate * abs(v))


@numba.njit(**SCALAR)
def stribeck_slope(v, static, dynamic, viscous, v_threshold):
    """Dissipative part of ``d/dv`` of :func:`stribeck_friction` [N s/m or N m s/rad], >= 0.

    ``F_c(v) (1 - tanh^2(v / v_th)) / v_th + b`` with ``F_c`` the Stribeck level ``F_s`` at rest, taken
    here as ``max(F_s, F_d)``: the regularised Coulomb slope, the stiffest term near a velocity reversal.
    The Stribeck decay (a negative slope) is left out: the linearly implicit integrators use this only
    to keep sticking friction stable (a W-method is consistent for any matrix, Hairer & Wanner,
    *Solving ODEs II*, Sec. IV.7), and a negative damping would weaken that.
    """
    return max(static, dynamic) * sech_squared(v / v_threshold) / v_threshold + viscous


@numba.njit(**SCALAR)
def sech_squared(z):
    """``1 - tanh(z)^2``, the slope of the ``tanh`` regularisation; exactly 0 for ``|z|`` above ~19.1, where
    ``tanh`` rounds to 1 (the sliding speeds of most steps)."""
    t = elementary.tanh(z)
    return 1.0 - t * t


def level_problems(static_name: str, static: float, dynamic_name: str, dynamic: float) -> list[str]:
    """The problems of an Eq. 7.63 pair of levels, one line each naming the field: both finite and >= 0, and the
    breakaway ``F_s`` at least the Coulomb level ``F_d`` (the Stribeck curve falls from breakaway to sliding; a
    rising one is not the law Eq. 7.63 states, and the bristle laws' purely elastic range ``z_ba < F_d / sigma_0``
    is set below breakaway by it). A parameter check, not for the compiled loop."""
    problems = [f"{name}: must be a finite number >= 0, got {value!r}"
                for name, value in ((static_name, static), (dynamic_name, dynamic))
                if not (value == value and 0.0 <= value < float("inf"))]
    if not problems and static < dynamic:
        problems.append(f"{static_name}: the breakaway (static) friction must not be below the dynamic one "
                        f"({static_name} = {static!r}, {dynamic_name} = {dynamic!r})")
    return problems
