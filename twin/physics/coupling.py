"""Torsional elasto-backlash joint: reducer backlash, couplings and torque meter (Sec. 9.3)."""

import numba

from numerics.jit import SCALAR
from twin.physics.hertz import saturated_damping_force


@numba.njit(**SCALAR)
def elasto_backlash(deflection, deflection_rate, stiffness, damping, backlash):
    """Torque (or force) of a linear spring-damper with a total play ``backlash`` (Eq. 5.9 form).

    Parameters
    ----------
    deflection : float
        Relative displacement across the joint (input minus output side).
    deflection_rate : float
        Its time derivative.
    stiffness, damping : float
        Spring stiffness and damping coefficient.
    backlash : float
        Total play (free travel is ``+/- backlash/2`` about zero).

    Returns
    -------
    float
        Transmitted torque/force, positive when the input side leads. Zero in the gap.
    """
    half = 0.5 * backlash
    elastic = stiffness * (deflection - half) if deflection > half else stiffness * (deflection + half)
    # damping saturated to the elastic force as in Eq. 7.29 (no force jump at re-engagement)
    torque = elastic + saturated_damping_force(abs(elastic), damping, deflection_rate)
    return torque if abs(deflection) > half else 0.0


@numba.njit(cache=True)
def elasto_backlash_energy(deflection, stiffness, backlash):
    """Elastic energy stored in :func:`elasto_backlash` (for energy-balance checks)."""
    gap = abs(deflection) - 0.5 * backlash
    return 0.5 * stiffness * gap * gap if gap > 0.0 else 0.0
