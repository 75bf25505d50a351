"""Dynamic friction laws with an internal state: stiction, presliding and Stribeck sliding without a smoothing speed.

The regularised law of :mod:`twin.physics.friction` replaces ``sign(v)`` by ``tanh(v / v_th)``: below ``v_th`` it is
a viscous damper of slope ``F_s / v_th``, so a force below breakaway does not hold a body, it makes it creep at
``v ~ F v_th / F_s``. The laws here carry the micro-displacement ``z`` of the contact's asperities (the "bristles")
as a state: for a force below breakaway ``z`` is elastic and the body stands still; the sliding friction is reached
through the presliding displacement, not through a speed band. Their one numerical property is the stiffness of the
bristles, a physical parameter (the presliding stiffness ``sigma_0``).

Both laws share the force (Canudas de Wit et al., "A new model for control of systems with friction", IEEE TAC
40(3), 1995, Eq. 2; the damping term made speed-dependent as in Olsson et al., "Friction models and friction
compensation", European Journal of Control 4, 1998, Sec. 5.6)::

    F = sigma_0 z + sigma_1 exp(-(v / v_d)^2) dz/dt + sigma_2 v

and the steady sliding level ``g(v) = F_d + (F_s - F_d) exp(-a |v|)`` of Eq. 7.63
(:func:`twin.physics.friction.stribeck_level`), so that
at constant speed both give ``F = g(v) sign(v) + sigma_2 v``, the thesis law without its regularisation.

* **LuGre** (Canudas de Wit et al. 1995, Eq. 1): ``dz/dt = v - sigma_0 |v| z / g(v)``. Sticking is approximate:
  under a force below breakaway the bristle still relaxes at a rate ``sigma_0 |v| |z| / g``, so an oscillating
  force makes the body drift (Dupont et al. 2002, Sec. II).
* **Elasto-plastic** (Dupont, Hayward, Armstrong & Altpeter, "Single state elastoplastic friction models", IEEE TAC
  47(5), 2002, Eqs. 6-9): ``dz/dt = v (1 - alpha(z, v) z / z_ss(v))`` with ``z_ss = sign(v) g(v) / sigma_0`` and
  ``alpha = 0`` for ``|z| <= z_ba`` (purely elastic: no drift under any force below breakaway), rising to 1 at
  ``|z| = |z_ss|``, and 0 whenever ``z`` and ``v`` have opposite signs (unloading is elastic). Dupont et al. give
  the rise as a half sine "for example"; a cubic smoothstep ``3 s^2 - 2 s^3`` is used here (same end values and
  zero end slopes, and no libm call in the compiled loop: :mod:`numerics.elementary`).

**Dissipation.** With the bristles' stored energy ``sigma_0 z^2 / 2``, the power the friction takes from the
motion minus the rate of stored energy is, writing ``w = z / z_ss`` and ``s_1 = sigma_1 exp(-(v / v_d)^2)``::

    D = alpha g |v| w^2 - alpha s_1 v^2 w + (s_1 + sigma_2) v^2          (alpha = 1 for LuGre)

a quadratic in ``w`` that is never negative when ``alpha s_1^2 |v| <= 4 g (s_1 + sigma_2)``; since
``max_v s_1 |v| = sigma_1 v_d / sqrt(2 e)`` and ``g >= F_d``, ``sigma_1 v_d / sqrt(2 e) <= 4 F_d`` is sufficient for
every state and speed (:func:`dissipation_bound_holds`). With a constant ``sigma_1`` (``v_d`` infinite) LuGre is
not dissipative at high speed (Barabanov & Ortega, "Necessary and sufficient conditions for passivity of the
LuGre friction model", IEEE TAC 45(4), 2000).

**The step these laws allow** (explicit RK4, :func:`rk4_step_problems`). On a body of mass ``m`` the laws add two
eigenvalues that a fixed explicit step must resolve: sticking (``alpha = 0``, ``dz/dt = v``) the presliding mode
``m s^2 + sigma_1 s + sigma_0 = 0``; sliding, the bristles' relaxation to ``z_ss``, ``d(dz/dt)/dz = -sigma_0 |v| /
g(v)`` at ``|z| = |z_ss|`` (``alpha = 1`` with zero slope there), largest at the largest sliding speed and ``g =
F_d``. The regularised law's slope ``F_s / v_th`` on the same mass adds ``-F_s / (m v_th)``. A step is stable where
RK4's stability polynomial ``|1 + h + h^2/2 + h^3/6 + h^4/24| <= 1`` for every ``h = lambda dt``. The coupling to
the load cell and the contacts is not in these figures: they bound from below what a step needs, and a run that
passes them can still fail on the coupled modes (docs/accuracy.md).

All functions but the parameter checks are ``numba.njit`` scalar functions (float arguments, SI units, selects
instead of branches), meant for the lanes of the compiled loop.
"""

import cmath
import math
from collections.abc import Mapping

import numba

from numerics import elementary
from numerics.jit import SCALAR


@numba.njit(**SCALAR)
def lugre_deflection_rate(v, z, level, stiffness):
    """LuGre bristle rate ``dz/dt = v - sigma_0 |v| z / g(v)`` [m/s] (Canudas de Wit et al. 1995, Eq. 1).

    Parameters
    ----------
    v : float
        Sliding velocity [m/s].
    z : float
        Bristle deflection [m].
    level : float
        ``g(v)``, :func:`twin.physics.friction.stribeck_level` [N], > 0.
    stiffness : float
        Presliding stiffness ``sigma_0`` [N/m], > 0.
    """
    return v - stiffness * abs(v) * z / level


@numba.njit(**SCALAR)
def _smoothstep(s):
    """``3 s^2 - 2 s^3`` on ``s`` clipped to [0, 1]: 0 and 1 at the ends with zero slope."""
    s = min(max(s, 0.0), 1.0)
    return s * s * (3.0 - 2.0 * s)


@numba.njit(**SCALAR)
def elastoplastic_deflection_rate(v, z, level, stiffness, elastic_deflection):
    """Elasto-plastic bristle rate ``dz/dt = v (1 - alpha(z, v) z / z_ss(v))`` [m/s] (Dupont et al. 2002, Eq. 6).

    Parameters
    ----------
    v, z, level, stiffness : float
        As in :func:`lugre_deflection_rate`.
    elastic_deflection : float
        ``z_ba`` [m], below the smallest steady deflection ``F_d / sigma_0`` (so ``z_ba < |z_ss(v)|`` at every
        speed): up to it the contact is purely elastic.
    """
    steady = level / stiffness                      # |z_ss(v)|
    s = (abs(z) - elastic_deflection) / (steady - elastic_deflection)
    alpha = _smoothstep(s) if z * v > 0.0 else 0.0  # unloading (z against v) is elastic
    return v * (1.0 - alpha * abs(z) / steady)


@numba.njit(**SCALAR)
def bristle_force(v, z, deflection_rate, stiffness, damping, damping_speed, viscous):
    """Friction force ``sigma_0 z + sigma_1 exp(-(v / v_d)^2) dz/dt + sigma_2 v`` [N], opposing the motion.

    Parameters
    ----------
    v : float
        Sliding velocity [m/s].
    z, deflection_rate : float
        Bristle deflection [m] and its rate [m/s] (:func:`lugre_deflection_rate` or
        :func:`elastoplastic_deflection_rate`).
    stiffness, damping : float
        ``sigma_0`` [N/m] and ``sigma_1`` [N s/m].
    damping_speed : float
        ``v_d`` [m/s], > 0: the bristle damping fades above it (the dissipation condition, module docstring).
    viscous : float
        ``sigma_2`` [N s/m], the ``b`` of Eq. 7.63.
    """
    u = v / damping_speed
    return stiffness * z + damping * elementary.exp(-u * u) * deflection_rate + viscous * v


def dissipation_bound_holds(damping, damping_speed, dynamic):
    """``sigma_1 v_d / sqrt(2 e) <= 4 F_d``: the bristle law dissipates at every state and speed (module
    docstring). A parameter check, not for the compiled loop."""
    return damping * damping_speed / math.sqrt(2.0 * math.e) <= 4.0 * dynamic


def rk4_stable(h: complex) -> bool:
    """Is ``h = lambda dt`` inside RK4's region of absolute stability (its stability polynomial at most 1)?"""
    return abs(1.0 + h * (1.0 + h / 2.0 * (1.0 + h / 3.0 * (1.0 + h / 4.0)))) <= 1.0


def seal_eigenvalues(level: str, values: Mapping[str, float], speed: float) -> dict[str, complex]:
    """The eigenvalues [1/s] the seal-friction ``level`` (``"regularised"`` or ``"elasto_plastic"``) adds on the
    piston (module docstring, "The step"), from ``values`` (``{"pneumatics.<key>": value}``, SI) and the largest
    sliding ``speed`` [m/s]."""
    v = {key.removeprefix("pneumatics."): value for key, value in values.items()}
    mass = v["piston_mass"]
    if level == "regularised":
        return {"regularised Coulomb slope": -max(v["friction_static"], v["friction_dynamic"]) / (
            mass * v["friction_velocity_threshold"])}
    stiffness, damping = v["friction_presliding_stiffness"], v["friction_bristle_damping"]
    # the stiffer root (an underdamped pair's conjugate has the same stability: RK4's region is symmetric)
    presliding = (-damping - cmath.sqrt(damping * damping - 4.0 * mass * stiffness)) / (2.0 * mass)
    return {"presliding mode": presliding,
            "sliding relaxation": complex(-stiffness * abs(speed) / max(v["friction_dynamic"], 1e-300))}


def rk4_step_limit(eigenvalues, dt: float) -> float:
    """The largest step up to ``dt`` at which RK4 is stable on every one of ``eigenvalues`` (bisection along each
    ray: the region is star-shaped about the origin along the rays of damped modes)."""
    limit = dt
    for lam in eigenvalues:
        if rk4_stable(lam * limit):
            continue
        low, high = 0.0, limit
        for _ in range(60):
            mid = 0.5 * (low + high)
            low, high = (mid, high) if rk4_stable(lam * mid) else (low, mid)
        limit = low
    return limit


def rk4_step_problems(level: str, values: Mapping[str, float], dt: float, speed: float) -> list[str]:
    """One line per seal-friction eigenvalue that RK4 at ``dt`` cannot integrate (empty when it can), naming the
    parameter that sets it, its value, the seals' moving mass, and the largest stable step. ``values`` as in
    :func:`seal_eigenvalues`. A parameter check for the caller that knows the run's step and speed, not for the
    compiled loop."""
    field, remedy = (("pneumatics.friction_velocity_threshold", "a larger threshold") if level == "regularised"
                     else ("pneumatics.friction_presliding_stiffness", "a smaller stiffness"))
    shown = values[field]
    mass = values["pneumatics.piston_mass"]
    problems = []
    for what, lam in seal_eigenvalues(level, values, speed).items():
        if rk4_stable(lam * dt):
            continue
        problems.append(
            f"{field}: {shown:g} with the seals' moving mass pneumatics.piston_mass = {mass:g} kg puts the "
            f"{what} of the {level} seal friction at {abs(lam):.3g} 1/s, beyond RK4's stability at dt = {dt:g} s "
            f"(|lambda dt| = {abs(lam) * dt:.3g}); allowed: {remedy}, or dt <= "
            f"{rk4_step_limit([lam], dt):.3g} s")
    return problems
