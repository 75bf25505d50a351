"""Torsional elasto-backlash joint: reducer backlash, couplings and torque meter (Sec. 9.3)."""

import numba


@numba.njit(cache=True)
def saturated_damping(elastic, damping_force):
    """Damping force saturated to the elastic force (Eq. 7.29; the same device as Eq. 5.9).

    Avoids force jumps at contact onset with non-zero approach speed and any
    attractive (pulling) force while the contact separates.
    """
    bound = abs(elastic)
    if damping_force > bound:
        return bound
    if damping_force < -bound:
        return -bound
    return damping_force


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
    return elastic + saturated_damping(elastic, damping * deflection_rate)


@numba.njit(cache=True)
def elasto_backlash_energy(deflection, stiffness, backlash):
    """Elastic energy stored in :func:`elasto_backlash` (for energy-balance checks)."""
    gap = abs(deflection) - 0.5 * backlash
    return 0.5 * stiffness * gap * gap if gap > 0.0 else 0.0
