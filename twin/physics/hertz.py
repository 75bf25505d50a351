"""Hertzian point contact between a sphere and a groove (Bertolino 2020, Sec. 7.3).

The normal force of one contact is ``F = K_H delta^1.5 + F_d`` (Eqs. 7.27-7.30).
``K_H`` follows from the principal curvatures of the two bodies through the
explicit approximations of Antoine et al. (2006) adopted by the thesis
(Eqs. 7.31-7.50); :func:`hertz_contact_exact` solves the Hertz ellipticity equation
(Eq. 7.36) with exact elliptic integrals as a reference.

Conventions
-----------
* Curvature ``rho = 1/r`` is positive for a convex surface (centre of curvature
  inside the body) and negative for a concave one. The sphere has
  ``rho_11 = rho_12 = 1/r_b``; a groove has ``rho_21 = 1/r_c`` (first curvature,
  :mod:`twin.physics.groove`, positive on the screw, negative in the nut) and
  ``rho_22 = -1/r_s`` or ``-1/r_n`` (profile, Eqs. 3.12, 3.22).
* ``rho_11``/``rho_21`` and ``rho_12``/``rho_22`` lie in the same planes
  (``omega_h = 0`` in Eq. 7.33), which holds for a sphere in a groove.
* ``A <= B`` (Eqs. 7.33-7.35 as printed) and the ellipticity ``kappa = a/b >= 1``;
  ``a`` is the semi-major axis (transverse to rolling), ``b`` the semi-minor one.
* ``E*`` is the Johnson (1985) contact modulus, Eq. 7.31 corrected.

The scalar kernels are ``numba.njit`` without input checks, callable from the
compiled simulation loop; the Python-level entry points
(:func:`hertz_contact_exact`, :func:`ball_groove_stiffness`, :func:`stiffness_table`)
validate their inputs and raise :class:`twin.errors.InputError` (a ``ValueError``)
naming every offending argument.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.optimize import brentq
from scipy.special import ellipe, ellipkm1

from numerics.jit import SCALAR
from twin.errors import InputError
from twin.physics.groove import (
    nut_curvature_radius,
    nut_curvature_radius_iso,
    screw_curvature_radius,
    screw_curvature_radius_iso,
)

# Table 7.1 (= Abramowitz & Stegun 17.3.34 and 17.3.36, |error| <= 2e-8).
_KA = (1.38629436112, 0.09666344259, 0.03590092383, 0.03742563713, 0.01451196212)
_KB = (0.5, 0.12498593597, 0.06880248576, 0.03328355346, 0.00441787012)
_EA = (1.0, 0.44325141463, 0.06260601220, 0.04757383546, 0.01736506451)
_EB = (0.0, 0.24998368310, 0.09200180037, 0.04069697526, 0.00526449639)

# Table 7.2: coefficients of Eq. 7.44.
_MU_NUM = (4.02274361e-1, 3.7491752e-2, 7.4855761e-4, 2.1667028e-6)
_MU_DEN = (4.2678878e-1, 4.2605401e-2, 9.0786922e-4, 2.7868927e-6)

FORMULA_THESIS = 0
"""``formula`` selector: fitted groove curvatures, Eqs. 3.20 and 3.27."""
FORMULA_ISO = 1
"""``formula`` selector: ISO 3408-4 groove curvatures, Eqs. 3.21 and 3.28."""


@njit(cache=True)
def equivalent_modulus(E1, nu1, E2, nu2):
    """Equivalent (contact) modulus ``E* = [(1-nu1^2)/E1 + (1-nu2^2)/E2]^-1``.

    Eq. 7.31 prints a *product* of the two compliances inside the bracket; that is
    a typo (it is not even dimensionally a modulus). The standard sum is used
    (Johnson, *Contact Mechanics*, 1985, Eq. 4.22).

    Parameters
    ----------
    E1, E2 : float
        Young's moduli of the two bodies [Pa].
    nu1, nu2 : float
        Poisson's ratios [-].

    Returns
    -------
    float
        ``E*`` [Pa].
    """
    return 1.0 / ((1.0 - nu1**2) / E1 + (1.0 - nu2**2) / E2)


@njit(cache=True)
def curvature_sum(rho11, rho12, rho21, rho22):
    """Curvature sum ``sum(rho) = rho11 + rho12 + rho21 + rho22`` (Eq. 7.32) [1/m]."""
    return rho11 + rho12 + rho21 + rho22


@njit(cache=True)
def curvature_difference(rho11, rho12, rho21, rho22, omega):
    """Curvature difference ``F_rho`` (Eq. 7.33, sign as printed: ``F_rho <= 0``).

    Parameters
    ----------
    rho11, rho12 : float
        Principal curvatures of body 1 [1/m].
    rho21, rho22 : float
        Principal curvatures of body 2 [1/m].
    omega : float
        Angle between the planes of ``rho11`` and ``rho21`` [rad].

    Returns
    -------
    float
        ``F_rho`` in [-1, 0]; with Eqs. 7.34-7.35 it makes ``A <= B``, the range in
        which Eq. 7.43 is stated.
    """
    d1 = rho11 - rho12
    d2 = rho21 - rho22
    return -math.sqrt(d1**2 + d2**2 + 2.0 * math.cos(2.0 * omega) * d1 * d2) / curvature_sum(
        rho11, rho12, rho21, rho22
    )


@njit(cache=True)
def relative_curvatures(sum_rho, f_rho):
    """Relative principal curvatures ``A``, ``B`` (Eqs. 7.34-7.35) [1/m]; ``A + B = sum(rho)``."""
    return 0.5 * sum_rho * (1.0 + f_rho), 0.5 * sum_rho * (1.0 - f_rho)


@njit(cache=True)
def _hastings(m1, a, b):
    # Eqs. 7.39-7.40 share this polynomial-plus-log form in m1 = 1 - m
    poly = a[0] + m1 * (a[1] + m1 * (a[2] + m1 * (a[3] + m1 * a[4])))
    log_poly = b[0] + m1 * (b[1] + m1 * (b[2] + m1 * (b[3] + m1 * b[4])))
    return poly - log_poly * math.log(m1)


@njit(cache=True)
def elliptic_k(kappa):
    """Complete elliptic integral of the first kind ``K(kappa)`` (Eqs. 7.37, 7.39, 7.41).

    Eq. 7.39 (Table 7.1) with ``m1 = kappa^-2`` for ``kappa >= 1``; for ``kappa < 1``
    the continuation ``K(kappa) = kappa K(m = 1 - kappa^2)`` of Eq. 7.41. Absolute
    error < 2e-8 for ``kappa >= 1`` (< ``kappa`` * 2e-8 below).

    Parameters
    ----------
    kappa : float
        Ellipticity parameter [-], > 0.

    Returns
    -------
    float
        ``K`` as defined by Eq. 7.37 (parameter ``m = 1 - kappa^-2``).
    """
    if kappa >= 1.0:
        return _hastings(1.0 / kappa**2, _KA, _KB)
    return kappa * _hastings(kappa**2, _KA, _KB)


@njit(cache=True)
def elliptic_e(kappa):
    """Complete elliptic integral of the second kind ``E(kappa)`` (Eqs. 7.38, 7.40, 7.42).

    Eq. 7.40 (Table 7.1) with ``m1 = kappa^-2`` for ``kappa >= 1``; for ``kappa < 1``
    ``E(kappa) = E(m = 1 - kappa^2) / kappa`` (Eq. 7.42). Absolute error < 2e-8 for
    ``kappa >= 1`` (< 2e-8 / ``kappa`` below).

    Parameters
    ----------
    kappa : float
        Ellipticity parameter [-], > 0.

    Returns
    -------
    float
        ``E`` as defined by Eq. 7.38 (parameter ``m = 1 - kappa^-2``).
    """
    if kappa >= 1.0:
        return _hastings(1.0 / kappa**2, _EA, _EB)
    return _hastings(kappa**2, _EA, _EB) / kappa


@njit(cache=True)
def ellipticity(b_over_a):
    """Ellipticity ``kappa = a/b`` from ``B/A`` without iteration (Eqs. 7.43-7.44).

    ``kappa = (B/A)^gamma``, ``gamma = 2/3 P(X)/Q(X)``, ``X = log10(B/A)``, Table 7.2.
    Stated for ``1 <= B/A < 1e10``; ``gamma`` is even in ``X``, so ``B/A < 1`` gives
    ``1/kappa`` of the swapped problem. The thesis quotes no accuracy; against the
    exact root of Eq. 7.36 the relative error is < 1e-5 (max 5.9e-6, near
    ``B/A`` ~ 280) over the stated range, as measured in ``tests/physics/test_hertz.py``.

    Parameters
    ----------
    b_over_a : float
        Ratio of relative curvatures ``B/A`` [-].

    Returns
    -------
    float
        ``kappa`` [-].
    """
    x2 = math.log10(b_over_a) ** 2
    num = 1.0 + x2 * (_MU_NUM[0] + x2 * (_MU_NUM[1] + x2 * (_MU_NUM[2] + x2 * _MU_NUM[3])))
    den = 1.0 + x2 * (_MU_DEN[0] + x2 * (_MU_DEN[1] + x2 * (_MU_DEN[2] + x2 * _MU_DEN[3])))
    return b_over_a ** (2.0 / 3.0 * num / den)


@njit(cache=True)
def dimensionless_from_integrals(kappa, k_int, e_int):
    """Dimensionless semi-axes and approach ``a*``, ``b*``, ``delta*`` (Eqs. 7.48-7.50).

    Parameters
    ----------
    kappa : float
        Ellipticity [-].
    k_int, e_int : float
        ``K(kappa)`` and ``E(kappa)`` (Eqs. 7.37-7.38), approximate or exact.

    Returns
    -------
    tuple of float
        ``(a*, b*, delta*)``; all equal 1 for a circular contact.
    """
    a_star = (2.0 * kappa**2 * e_int / math.pi) ** (1.0 / 3.0)
    b_star = (2.0 * e_int / (math.pi * kappa)) ** (1.0 / 3.0)
    delta_star = 2.0 * k_int / math.pi * (math.pi / (2.0 * kappa**2 * e_int)) ** (1.0 / 3.0)
    return a_star, b_star, delta_star


@njit(cache=True)
def dimensionless_contact(kappa):
    """``(a*, b*, delta*)`` of Eqs. 7.48-7.50 with the approximate integrals (Eqs. 7.39-7.42)."""
    return dimensionless_from_integrals(kappa, elliptic_k(kappa), elliptic_e(kappa))


@njit(cache=True)
def hertz_stiffness(e_star, sum_rho, delta_star):
    """Hertz stiffness ``K_H`` of ``F = K_H delta^1.5`` (Eqs. 7.28, 7.47).

    ``K_H = 2^(5/2) E* / (3 delta*^(3/2) (A+B)^(1/2))`` with ``A + B = sum(rho)``.

    Eq. 7.47 prints ``2^(3/2)``. With the Johnson modulus ``E*`` (Eq. 7.31 corrected)
    and ``A + B = sum(rho)`` (Eqs. 7.34-7.35) that is half the Hertz value: for a
    sphere of radius R on a flat (``sum(rho) = 2/R``, ``delta* = 1``) it gives
    ``(2/3) E* sqrt(R)`` instead of ``(4/3) E* sqrt(R)`` (Johnson 1985, Eq. 4.23).
    ``2^(3/2)`` is right only with the modulus ``E' = 2 E*`` of Harris/Hamrock, which
    would in turn break Eqs. 7.45-7.46 and 7.53. Eliminating ``F`` between Eq. 7.45
    and the approach of Eqs. 7.52-7.53,
    ``delta = delta* (sum(rho)/2) (3F / (2 sum(rho) E*))^(2/3)``, gives the
    ``2^(5/2)`` used here; the tests check both the circular closed form and the
    consistency with Eqs. 7.52-7.53 for elliptical contacts.

    Parameters
    ----------
    e_star : float
        Equivalent modulus [Pa].
    sum_rho : float
        Curvature sum ``A + B`` [1/m], > 0.
    delta_star : float
        Dimensionless approach [-].

    Returns
    -------
    float
        ``K_H`` [N/m^1.5].
    """
    return 2.0**2.5 * e_star / (3.0 * delta_star**1.5 * math.sqrt(sum_rho))


@njit(cache=True)
def contact_semi_axes(force, a_star, b_star, sum_rho, e_star):
    """Semi-axes of the contact ellipse (Eqs. 7.45-7.46).

    ``a, b = (a*, b*) (3F / (2 (A+B) E*))^(1/3)``.

    Parameters
    ----------
    force : float
        Normal force [N], >= 0.
    a_star, b_star : float
        Dimensionless semi-axes (Eqs. 7.48-7.49).
    sum_rho : float
        ``A + B`` [1/m].
    e_star : float
        Equivalent modulus [Pa].

    Returns
    -------
    tuple of float
        ``(a, b)`` [m]: semi-major (transverse) and semi-minor (rolling direction).
    """
    scale = (3.0 * force / (2.0 * sum_rho * e_star)) ** (1.0 / 3.0)
    return a_star * scale, b_star * scale


@njit(cache=True)
def mean_pressure(force, a, b):
    """Mean contact pressure ``p = F / (pi a b)`` (Eq. 7.51) [Pa]."""
    return force / (math.pi * a * b)


@njit(cache=True)
def max_pressure(force, a, b):
    """Maximum (central) Hertz pressure ``p_h = 3/2 p`` (text after Eq. 7.51) [Pa]."""
    return 1.5 * mean_pressure(force, a, b)


@njit(**SCALAR)
def elastic_force(k_h, delta):
    """Elastic normal force ``K_H delta^1.5`` (Eq. 7.28), zero without interpenetration (Eq. 7.30) [N]."""
    d = max(delta, 0.0)
    return k_h * d * math.sqrt(d)  # delta**1.5, without the slower pow(); branch-free (k * 0 * 0 == 0)


@njit(cache=True)
def contact_deflection(force, k_h):
    """Normal approach ``delta = (F / K_H)^(2/3)`` carrying ``force`` (inverse of Eq. 7.28) [m]."""
    return (force / k_h) ** (2.0 / 3.0)


@njit(**SCALAR)
def damping_coefficient(b_h, k_h):
    """Contact damping ``C_H = b_h sqrt(K_H)`` (Eq. 7.54) [N s/m].

    Scaling with ``sqrt(K_H)`` keeps the damping ratio steady while ``K_H`` changes
    with the contact angle.
    """
    return b_h * math.sqrt(k_h)


@njit(**SCALAR)
def saturated_damping_force(f_elastic, c, delta_dot):
    """Damping force ``C_H delta_dot`` saturated to ``+-F_nk`` (Eq. 7.29).

    The saturation avoids a force jump when contact starts at non-zero approach
    speed and keeps the total normal force ``F_nk + F_nd`` non-negative while the
    bodies separate.

    Parameters
    ----------
    f_elastic : float
        Elastic force ``F_nk`` [N], >= 0.
    c : float
        Damping coefficient ``C_H`` [N s/m].
    delta_dot : float
        Interpenetration rate [m/s], positive while approaching.

    Returns
    -------
    float
        ``F_nd`` [N], within ``[-F_nk, F_nk]``.
    """
    return min(max(c * delta_dot, -f_elastic), f_elastic)


@njit(cache=True)
def hertz_contact(rho11, rho12, rho21, rho22, e_star):
    """Hertz point contact by the explicit approximations (Eqs. 7.32-7.50).

    Parameters
    ----------
    rho11, rho12 : float
        Principal curvatures of body 1 [1/m] (convex positive).
    rho21, rho22 : float
        Principal curvatures of body 2 [1/m], in the planes of ``rho11``, ``rho12``.
    e_star : float
        Equivalent modulus (Eq. 7.31) [Pa].

    Returns
    -------
    tuple of float
        ``(K_H [N/m^1.5], kappa, a*, b*, delta*)``.

    Notes
    -----
    Requires a non-conforming contact, ``A > 0`` (not checked here; see
    :func:`hertz_contact_exact` for a checked reference).
    """
    sum_rho = curvature_sum(rho11, rho12, rho21, rho22)
    a_rel, b_rel = relative_curvatures(sum_rho, curvature_difference(rho11, rho12, rho21, rho22, 0.0))
    kappa = ellipticity(b_rel / a_rel)
    a_star, b_star, delta_star = dimensionless_contact(kappa)
    return hertz_stiffness(e_star, sum_rho, delta_star), kappa, a_star, b_star, delta_star


def _exact_integrals(kappa):
    # scipy takes the parameter m = k^2 = 1 - kappa^-2; ellipkm1 takes 1 - m = kappa^-2 and
    # so keeps full precision for slender ellipses, where 1 - m would cancel
    m1 = kappa**-2
    return ellipkm1(m1), ellipe(1.0 - m1)


def _ellipticity_residual(kappa, f_abs):
    # Eq. 7.36; its kappa -> 1 limit is 0
    if kappa == 1.0:
        return -f_abs
    k_int, e_int = _exact_integrals(kappa)
    return ((kappa**2 + 1.0) * e_int - 2.0 * k_int) / ((kappa**2 - 1.0) * e_int) - f_abs


def exact_ellipticity(f_rho):
    """Root ``kappa >= 1`` of the Hertz ellipticity equation (Eq. 7.36), exact integrals.

    Eq. 7.36 is odd under ``kappa -> 1/kappa`` once ``K``, ``E`` are continued by
    Eqs. 7.41-7.42, so the printed (non-positive) ``F_rho`` of Eq. 7.33 has the root
    ``1/kappa``. We solve for ``|F_rho|`` to get the ``kappa >= 1`` branch that
    Eq. 7.43 approximates; ``a*`` and ``b*`` merely swap between the two branches and
    ``delta*`` is invariant, so ``K_H`` does not depend on the choice.

    Parameters
    ----------
    f_rho : float
        Curvature difference (Eq. 7.33), ``|f_rho| < 1``.

    Returns
    -------
    float
        ``kappa`` to ~1e-15 relative (scipy ``ellipkm1``/``ellipe``, ``brentq``).
    """
    f_abs = abs(f_rho)
    if f_abs == 0.0:
        return 1.0
    upper = 2.0
    while _ellipticity_residual(upper, f_abs) < 0.0:
        upper *= 2.0
    return brentq(_ellipticity_residual, 1.0, upper, args=(f_abs,), xtol=1e-300, rtol=4.0 * np.finfo(float).eps)


def hertz_contact_exact(rho11, rho12, rho21, rho22, e_star):
    """Reference Hertz point contact: Eq. 7.36 solved exactly, then Eqs. 7.47-7.50.

    Same inputs, conventions and outputs as :func:`hertz_contact`, with
    ``kappa`` from :func:`exact_ellipticity` and exact ``K``, ``E``
    (``scipy.special.ellipkm1``/``ellipe``; scipy's parameter is ``m = k^2``,
    here ``m = 1 - kappa^-2``).

    Raises
    ------
    twin.errors.InputError
        If ``e_star <= 0`` or the curvatures do not form a non-conforming contact
        (``A <= 0``).
    """
    problems = []
    if not e_star > 0.0:
        problems.append(f"e_star must be > 0 Pa, got {e_star!r}")
    sum_rho = curvature_sum(rho11, rho12, rho21, rho22)
    f_rho = curvature_difference(rho11, rho12, rho21, rho22, 0.0) if sum_rho > 0.0 else 0.0
    a_rel, _ = relative_curvatures(sum_rho, f_rho)
    if not a_rel > 0.0:
        problems.append(
            "rho11, rho12, rho21, rho22 must give relative curvatures A, B > 0 (non-conforming contact), "
            f"got sum(rho)={sum_rho!r} 1/m, A={a_rel!r} 1/m"
        )
    if problems:
        raise InputError("Hertz contact input", problems)
    kappa = exact_ellipticity(f_rho)
    a_star, b_star, delta_star = dimensionless_from_integrals(kappa, *_exact_integrals(kappa))
    return hertz_stiffness(e_star, sum_rho, delta_star), kappa, a_star, b_star, delta_star


@njit(cache=True)
def series_stiffness(k1, k2):
    """Stiffness of two Hertz contacts in series under the same force [N/m^1.5].

    The approaches add, ``delta = (F/k1)^(2/3) + (F/k2)^(2/3)``, hence
    ``F = (k1^(-2/3) + k2^(-2/3))^(-3/2) delta^1.5``.
    """
    return (k1 ** (-2.0 / 3.0) + k2 ** (-2.0 / 3.0)) ** -1.5


@njit(cache=True)
def _ball_groove_stiffness(alpha, r_m, r_b, r_s, r_n, alpha_e, L, e_star, formula):
    if formula == FORMULA_ISO:
        r_cs = screw_curvature_radius_iso(r_m, r_b, alpha)
        r_cn = nut_curvature_radius_iso(r_m, r_b, alpha)
    else:
        r_cs = screw_curvature_radius(r_m, r_b, alpha, alpha_e, L)
        r_cn = nut_curvature_radius(r_m, r_b, alpha, alpha_e, L)
    rho_b = 1.0 / r_b
    k_s = hertz_contact(rho_b, rho_b, 1.0 / r_cs, -1.0 / r_s, e_star)[0]
    k_n = hertz_contact(rho_b, rho_b, 1.0 / r_cn, -1.0 / r_n, e_star)[0]
    return k_s, k_n, series_stiffness(k_s, k_n)


@njit(cache=True)
def _stiffness_table(alpha_grid, r_m, r_b, r_s, r_n, alpha_e, L, e_star, formula):
    table = np.empty(alpha_grid.size)
    for i in range(alpha_grid.size):
        table[i] = _ball_groove_stiffness(alpha_grid[i], r_m, r_b, r_s, r_n, alpha_e, L, e_star, formula)[2]
    return table


def _check_ball_groove(alpha_name, alpha, r_m, r_b, r_s, r_n, alpha_e, L, e_star, formula):
    problems = []
    alpha = np.asarray(alpha, dtype=float)
    if alpha.size == 0 or not np.all((alpha > 0.0) & (alpha < 0.5 * math.pi)):
        problems.append(f"{alpha_name} must lie in (0, pi/2) rad, got {alpha.tolist()!r}")
    for name, value in (("r_m", r_m), ("r_b", r_b), ("e_star", e_star)):
        if not value > 0.0:
            problems.append(f"{name} must be > 0, got {value!r}")
    for name, value in (("r_s", r_s), ("r_n", r_n)):
        if not value > r_b:
            problems.append(f"{name} must exceed r_b={r_b!r} m (conformity > 0.5), got {value!r}")
    if not 0.0 <= alpha_e < 0.5 * math.pi:
        problems.append(f"alpha_e must lie in [0, pi/2) rad, got {alpha_e!r}")
    if not L >= 0.0:
        problems.append(f"L must be >= 0 m, got {L!r}")
    if formula not in (FORMULA_THESIS, FORMULA_ISO):
        problems.append(f"formula must be {FORMULA_THESIS} (Eqs. 3.20/3.27) or {FORMULA_ISO} (ISO), got {formula!r}")
    if problems:
        raise InputError("ball-groove contact input", problems)


def _as_floats(*values):
    # one numba specialisation (float64) whatever numeric types the caller passes
    return tuple(float(v) for v in values)


def ball_groove_stiffness(alpha, r_m, r_b, r_s, r_n, alpha_e, L, e_star, formula=FORMULA_THESIS):
    """Hertz stiffnesses of one sphere against the screw and the nut grooves.

    Sphere curvatures ``1/r_b`` (Eq. 3.11); groove curvatures ``1/r_c`` (first,
    :mod:`twin.physics.groove`) and ``-1/r_s`` or ``-1/r_n`` (profile, Eqs. 3.12,
    3.22); each contact through :func:`hertz_contact` (Eqs. 7.32-7.50). The two
    contacts lie on the sphere's normal line and carry the same normal force, so
    they combine in series (:func:`series_stiffness`).

    Parameters
    ----------
    alpha : float
        Contact angle in the plane normal to the thread [rad], in (0, pi/2).
    r_m : float
        Pitch circle radius [m].
    r_b : float
        Ball radius [m].
    r_s, r_n : float
        Screw and nut groove profile radii [m] (:func:`twin.physics.groove.groove_radius`).
    alpha_e : float
        Helix angle [rad].
    L : float
        Ogival offset [m].
    e_star : float
        Equivalent modulus (:func:`equivalent_modulus`) [Pa].
    formula : int
        :data:`FORMULA_THESIS` (0, Eqs. 3.20/3.27) or :data:`FORMULA_ISO` (1, Eqs. 3.21/3.28).

    Returns
    -------
    tuple of float
        ``(K_s, K_n, K_eq)`` [N/m^1.5]: sphere-screw, sphere-nut, and in series.

    Raises
    ------
    twin.errors.InputError
        Naming every argument out of range.
    """
    _check_ball_groove("alpha", alpha, r_m, r_b, r_s, r_n, alpha_e, L, e_star, formula)
    return _ball_groove_stiffness(*_as_floats(alpha, r_m, r_b, r_s, r_n, alpha_e, L, e_star), int(formula))


def stiffness_table(alpha_grid, r_m, r_b, r_s, r_n, alpha_e, L, e_star, formula=FORMULA_THESIS):
    """Series ball-groove stiffness ``K_eq(alpha)`` on a grid, for run-time interpolation.

    The contact angle varies during a run and ``K_H`` with it (Sec. 7.3, Fig. 7.6);
    the compiled engine interpolates this table linearly instead of re-evaluating
    Eqs. 7.32-7.50.

    Parameters
    ----------
    alpha_grid : array_like
        Contact angles [rad], each in (0, pi/2).
    r_m, r_b, r_s, r_n, alpha_e, L, e_star, formula
        As for :func:`ball_groove_stiffness`.

    Returns
    -------
    numpy.ndarray
        ``K_eq`` [N/m^1.5] at each grid angle.

    Raises
    ------
    twin.errors.InputError
        Naming every argument out of range.
    """
    _check_ball_groove("alpha_grid", alpha_grid, r_m, r_b, r_s, r_n, alpha_e, L, e_star, formula)
    grid = np.asarray(alpha_grid, dtype=float)
    table = _stiffness_table(grid.ravel(), *_as_floats(r_m, r_b, r_s, r_n, alpha_e, L, e_star), int(formula))
    return table.reshape(grid.shape)
