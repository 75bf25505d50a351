"""Torsional elasto-backlash joint: reducer backlash, couplings and torque meter (Sec. 9.3)."""

import numba

from twin.physics.hertz import saturated_damping_force


@numba.njit(cache=True)
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
    if deflection > half:
        elastic = stiffness * (deflection - half)
    elif deflection < -half:
        elastic = stiffness * (deflection + half)
    else:
        return 0.0
    # damping saturated to the elastic force as in Eq. 7.29 (no force jump at re-engagement)
    return elastic + saturated_damping_force(abs(elastic), damping, deflection_rate)


@numba.njit(cache=True)
def elasto_backlash_energy(deflection, stiffness, backlash):
    """Elastic energy stored in :func:`elasto_backlash` (for energy-balance checks)."""
    gap = abs(deflection) - 0.5 * backlash
    return 0.5 * stiffness * gap * gap if gap > 0.0 else 0.0
