"""Principal curvature radii of the helical gothic-arch grooves (Bertolino 2020, Sec. 3.5.5).

A sphere touching a groove at contact angle ``alpha`` sees two groove curvatures:

* the *second* one, in the plane normal to the thread, is that of the groove
  profile, ``rho_22 = -1/r_s`` (screw, Eq. 3.12) or ``-1/r_n`` (nut, Eq. 3.22),
  with the groove radius ``r = f D_b`` from the conformity factor (Sec. 3.5.3);
* the *first* one, ``rho_21 = 1/r_c``, is the curvature of the curve cut from the
  groove by the plane containing the thread tangent and the contact normal
  (Fig. 3.15). The thesis gives a fitted formula that accounts for the helix angle
  (Eqs. 3.20, 3.27) and the ISO 3408-4 formula that ignores it (Eqs. 3.21, 3.28).

Sign convention (thesis, and :mod:`twin.physics.hertz`): a radius is positive when
the centre of curvature lies inside the body (convex), negative when it lies
outside (concave). The screw's first radius is positive, the nut's negative.

Units: SI (m, rad) at the interface. The fitted formulas were obtained with the
contact angle in degrees; the conversion is done inside.

Fitted-formula validity (Sec. 3.5.5): ``alpha_e`` 0-75 deg, ``alpha`` 10-70 deg,
``r_m`` 6-50 mm, ``L`` 0-0.39 mm, balls of commercial size for ``r_m``.

The scalar formulas are ``numba.njit`` kernels without input checks so that the
compiled simulation loop can call them; validate inputs at the Python level
(see :func:`twin.physics.hertz.ball_groove_stiffness`).
:func:`groove_curvature_radius_numerical` is a plain-Python reference that solves
the intersection problem behind Eqs. 3.18/3.26 directly.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.optimize import root

# Table 3.3: constants of Eq. 3.20.
_A1 = 1.0091
_A2 = 1.8975
_A3 = 7.1416e-6
_A4 = 2.8783
_A5 = 2.3380e-1
_A6 = 3.9180
_A7 = 4.1160e-1

# Table 3.4: constants of Eq. 3.27.
_B1 = -2.479e-5
_B2 = 2.860e-2
_B3 = 1.124e-4
_B4 = 6.937e-3
_B5 = 9.695e-1


@njit(cache=True)
def groove_radius(f, r_b):
    """Groove profile radius from the conformity factor, ``r = f D_b = 2 f r_b``.

    ISO 3408-1 definition quoted in Sec. 3.5.3: ``r_{s,n} = f_{s,n} D_b``.

    Parameters
    ----------
    f : float
        Conformity factor [-] (0.528 for the bench screw, Table 7.5).
    r_b : float
        Ball radius [m].

    Returns
    -------
    float
        Groove radius ``r_s`` or ``r_n`` [m].
    """
    return 2.0 * f * r_b


@njit(cache=True)
def screw_curvature_radius(r_m, r_b, alpha, alpha_e, L):
    """First principal curvature radius of the screw groove, thesis fit (Eq. 3.20).

    ``r_cs = a1 r_m exp(s1 - a7 sin^a2(a3 alpha_deg^a4)) - r_b - L a4^s1`` with
    ``s1 = alpha_e^a2 + a3 alpha_deg^a4 + alpha_e tan(a5 alpha_e^a6)`` and the
    constants of Table 3.3, as printed. The thesis evaluates it with lengths in m,
    ``alpha_e`` in rad and ``alpha`` in degrees; this function takes ``alpha`` in
    rad and converts.

    Checked against the thesis statements (see ``tests/physics/test_groove.py``):
    for ``alpha_e -> 0`` it approaches the ISO formula (Eq. 3.21) within ~3 % over
    10-70 deg; the helix raises the radius by ~1/cos^2(alpha_e) (the curvature of a
    helix is cos^2(alpha_e)/r), i.e. ~15 % at 20 deg; and it matches the direct
    numerical solution of the intersection problem
    (:func:`groove_curvature_radius_numerical`) within 3.1 % at the bench geometry
    (worst at 60 deg; the thesis states < 2 % over its own fitting data) and within
    2 % for the Fig. 3.17 screw (r_m = 20 mm, alpha_e = 9.043 deg, 30-60 deg).

    Parameters
    ----------
    r_m : float
        Pitch circle radius [m].
    r_b : float
        Ball radius [m].
    alpha : float
        Contact angle in the plane normal to the thread [rad].
    alpha_e : float
        Helix angle [rad].
    L : float
        Ogival offset [m].

    Returns
    -------
    float
        ``r_cs`` [m], positive (convex).
    """
    alpha_deg = math.degrees(alpha)
    s1 = alpha_e**_A2 + _A3 * alpha_deg**_A4 + alpha_e * math.tan(_A5 * alpha_e**_A6)
    shape = math.sin(_A3 * alpha_deg**_A4) ** _A2
    return _A1 * r_m * math.exp(s1 - _A7 * shape) - r_b - L * _A4**s1


@njit(cache=True)
def screw_curvature_radius_iso(r_m, r_b, alpha):
    """First principal curvature radius of the screw groove, ISO 3408-4 (Eq. 3.21).

    ``r_cs,ISO = (r_m - r_b cos(alpha)) / cos(alpha)``: the bearing formula, which
    ignores the helix angle.

    Parameters
    ----------
    r_m : float
        Pitch circle radius [m].
    r_b : float
        Ball radius [m].
    alpha : float
        Contact angle [rad].

    Returns
    -------
    float
        ``r_cs,ISO`` [m], positive (convex).
    """
    return (r_m - r_b * math.cos(alpha)) / math.cos(alpha)


@njit(cache=True)
def nut_curvature_radius(r_m, r_b, alpha, alpha_e, L):
    """First principal curvature radius of the nut groove, thesis fit (Eq. 3.27).

    Implemented as

    ``r_cn = b1 - r_b - s2 tan^2(alpha_e) asin(b3 + b4 alpha_deg r_m + L sqrt(s2))
    - b5 r_m (1 + tan^2(alpha_e)) - b4 r_m s2 alpha_deg``, ``s2 = (b2 alpha_deg)^(b2 alpha_deg)``

    with the constants of Table 3.4 (lengths in m, ``alpha_e`` in rad, ``alpha`` in
    degrees inside; this function takes ``alpha`` in rad).

    **Sign correction.** The source text prints ``+ b5 r_m (1 + tan^2(alpha_e))``.
    As printed the formula is unphysical: it gives a *positive* radius below
    ~55 deg although the thesis states r_cn < 0 (centre outside the nut, Fig. 3.19),
    e.g. +2.73 mm at the bench geometry (Table 7.5, alpha = 45 deg) where ISO
    (Eq. 3.28) gives -12.90 mm. With ``- b5`` the formula

    * reduces for ``alpha_e = 0`` to ``-r_m (b5 + b4 alpha_deg s2) - r_b``, which
      tracks the ISO ``-r_m / cos(alpha) - r_b`` within ~1.5 % over 10-70 deg
      (the thesis: "converges to the literature formula");
    * scales with the helix as ``(1 + tan^2 alpha_e) = 1/cos^2 alpha_e``, as the
      helix curvature does, the ``asin`` term supplying the same factor for the
      ``alpha``-dependent part (``asin x ~ x``);
    * matches the direct numerical solution of the intersection problem
      (:func:`groove_curvature_radius_numerical`, written from Eqs. 3.2-3.3, 3.23-3.24
      rather than from the long printed Eq. 3.26) within ~1.5 %, e.g. -12.94 mm vs
      -13.01 mm at the bench geometry (alpha = 45 deg), -31.94 mm vs -32.25 mm for the Fig. 3.21 screw
      (r_m = 20 mm, alpha_e = 9.043 deg, alpha = 45 deg),

    consistent with the stated fit error (< 2 %). We therefore read the printed
    ``+`` as a transcription error of ``-``; no other term was changed.

    Parameters
    ----------
    r_m : float
        Pitch circle radius [m].
    r_b : float
        Ball radius [m].
    alpha : float
        Contact angle [rad].
    alpha_e : float
        Helix angle [rad].
    L : float
        Ogival offset [m].

    Returns
    -------
    float
        ``r_cn`` [m], negative (concave).
    """
    alpha_deg = math.degrees(alpha)
    s2 = (_B2 * alpha_deg) ** (_B2 * alpha_deg)
    tan2 = math.tan(alpha_e) ** 2
    helix_term = s2 * tan2 * math.asin(_B3 + _B4 * alpha_deg * r_m + L * math.sqrt(s2))
    return _B1 - r_b - helix_term - _B5 * r_m * (1.0 + tan2) - _B4 * r_m * s2 * alpha_deg


@njit(cache=True)
def nut_curvature_radius_iso(r_m, r_b, alpha):
    """First principal curvature radius of the nut groove, ISO 3408-4 (Eq. 3.28).

    ``r_cn,ISO = -(r_m + r_b cos(alpha)) / cos(alpha)``.

    Parameters
    ----------
    r_m : float
        Pitch circle radius [m].
    r_b : float
        Ball radius [m].
    alpha : float
        Contact angle [rad].

    Returns
    -------
    float
        ``r_cn,ISO`` [m], negative (concave).
    """
    return -(r_m + r_b * math.cos(alpha)) / math.cos(alpha)


def _frenet_frame(theta, alpha_e):
    """Unit vectors t, n, b of the Frenet-Serret frame in Oxyz (columns of T_2, Eq. 3.2).

    ``b = t x n``; the printed first entry of the b column of T_2
    (``sin(alpha_e) cos(theta)``) is an OCR slip for ``sin(alpha_e) sin(theta)``,
    as the x component of Eq. 3.8 confirms.
    """
    t = np.array([-math.cos(alpha_e) * math.sin(theta), math.cos(alpha_e) * math.cos(theta), math.sin(alpha_e)])
    n = np.array([-math.cos(theta), -math.sin(theta), 0.0])
    return t, n, np.cross(t, n)


def _centre_and_direction(theta, alpha, r_m, alpha_e, H, L, member):
    """Profile centre C and unit vector from C to the groove point at (theta, alpha).

    Screw half groove S1: C_1s = B - H n + L b (Eq. 3.6), point = C + r_s (cos a n - sin a b)
    (Eqs. 3.7, 3.13). Nut half groove N1: C_1n = B + H n + L b (Eq. 3.23); N1 lies in
    the third quarter of the n-b plane (Sec. 3.5.3), so the point is
    C + r_n (-cos a n - sin a b).
    """
    t, n, b = _frenet_frame(theta, alpha_e)
    centre_b = r_m * np.array([math.cos(theta), math.sin(theta), theta * math.tan(alpha_e)])  # Eq. 3.3
    if member == "screw":
        return centre_b - H * n + L * b, math.cos(alpha) * n - math.sin(alpha) * b
    return centre_b + H * n + L * b, -math.cos(alpha) * n - math.sin(alpha) * b


def groove_curvature_radius_numerical(r_m, r_groove, alpha, alpha_e, H, L, member, step=None):
    """Reference first curvature radius from the groove/plane intersection (Eqs. 3.14-3.17).

    Builds the half groove S1 (``member="screw"``) or N1 (``member="nut"``) from
    Eqs. 3.2-3.3, 3.6-3.7 and 3.23, cuts it with the plane Pi through the profile
    centre spanned by the thread tangent t and the centre-to-contact direction
    (Eqs. 3.14, 3.24), and returns the signed radius of curvature of the cut at the
    contact point. For each in-plane abscissa ``l1`` the three scalar equations
    ``groove(theta_P + d_theta, alpha + d_alpha) = C + l1 t + l2 d`` (the content of
    Eqs. 3.18/3.26) are solved for ``(d_theta, d_alpha, l2)``; the curvature follows
    from a central second difference of ``l2(l1)`` (truncation error ~ (step/r_c)^2).

    Plain Python (scipy), for validating the fitted formulas; not for the run-time loop.

    Parameters
    ----------
    r_m : float
        Pitch circle radius [m].
    r_groove : float
        Groove profile radius ``r_s`` or ``r_n`` [m].
    alpha : float
        Contact angle [rad].
    alpha_e : float
        Helix angle [rad].
    H : float
        Centre radius offset [m].
    L : float
        Ogival offset [m].
    member : {"screw", "nut"}
        Which groove.
    step : float, optional
        Finite-difference step in ``l1`` [m]; default ``1e-3 r_m``.

    Returns
    -------
    float
        First curvature radius [m]: positive when the centre of curvature is inside
        the body (screw), negative when outside (nut).
    """
    if member not in ("screw", "nut"):
        raise ValueError(f"member must be 'screw' or 'nut', got {member!r}")
    h = 1e-3 * r_m if step is None else step
    centre0, d0 = _centre_and_direction(0.0, alpha, r_m, alpha_e, H, L, member)
    t0 = _frenet_frame(0.0, alpha_e)[0]

    def in_plane_ordinate(l1):
        # unknowns scaled to lengths so one tolerance fits all three
        def residual(x):
            centre, d = _centre_and_direction(x[0] / r_m, alpha + x[1] / r_groove, r_m, alpha_e, H, L, member)
            return (centre + r_groove * d - (centre0 + l1 * t0 + x[2] * d0)) / r_m

        sol = root(residual, [l1, 0.0, r_groove], method="hybr", options={"xtol": 1e-13})
        if not sol.success and np.max(np.abs(sol.fun)) > 1e-14:
            raise RuntimeError(f"groove/plane intersection did not converge at l1={l1}: {sol.message}")
        return sol.x[2]

    minus, mid, plus = (in_plane_ordinate(s * h) for s in (-1.0, 0.0, 1.0))
    slope = (plus - minus) / (2.0 * h)
    second = (plus - 2.0 * mid + minus) / h**2
    # d points from the profile centre into the body: bending towards +d means a centre inside
    return (1.0 + slope**2) ** 1.5 / second
