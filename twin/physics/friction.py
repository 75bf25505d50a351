"""Coulomb-Stribeck-viscous friction of supports (Eqs. 7.63 and 7.64)."""

import math

import numba


@numba.njit(cache=True)
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
    coulomb = dynamic + (static - dynamic) * math.exp(-stribeck_rate * abs(v))
    return coulomb * math.tanh(v / v_threshold) + viscous * v
