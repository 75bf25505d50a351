"""Reduced ball screw: per-sphere double-sided elasto-backlash Hertzian contact (Sec. 9.3).

Sign convention (documented choice between Eqs. 9.5 and 9.12)
-------------------------------------------------------------
A positive screw rotation ``theta_s`` advances the nuts along ``+x``, so the
screw's *equivalent linear position* is ``x_eq = p theta_s / (2 pi)``: the
sign of Eq. 9.12. Eq. 9.5 writes ``-p theta_s/(2 pi)``, i.e. the opposite
angle sign (its right-hand screw turns negatively for a positive stroke,
Fig. 9.12c); flipping the angle sign maps one onto the other. The relative
axial position of nut ``i`` (Eq. 9.5 in this convention) is

    dx_i = x_s + p (theta_s - theta_ni) / (2 pi) - x_ni

where ``x_s`` is the screw axial displacement, ``theta_ni`` the nut rotation
allowed by the guides and ``x_ni`` the nut translation (each from its
assembled, centred position). ``dx_i > b/2`` loads the flanks that push the
nut towards ``+x``; ``|dx_i| < b/2`` is the open backlash gap.

Contact law
-----------
The axial interference, projected on the plane normal to the thread, is
``delta_a = (|dx| - b/2) cos(alpha_e)``. The ball centre moves along the line
of the two groove curvature centres, distant ``A0 = (r_s - r_b) + (r_n - r_b)``,
so the contact angle and the normal approach are (Eq. 9.4, in the exact
angular-contact-bearing form of Harris & Kotzalas, *Rolling Bearing Analysis*,
2007, Sec. 2.4; the printed Eq. 9.4 is its first-order form)

    tan(alpha) = tan(alpha_0) + delta_a / (A0 cos(alpha_0)),
    delta_n    = A0 cos(alpha_0) / cos(alpha) - A0.

The normal load per sphere is Hertzian (Eq. 7.28) with the stiffness of the
sphere-screw and sphere-nut contacts in series, ``K(alpha)`` (Sec. 7.3 with the
groove curvatures of Sec. 3.5.5, fitted by a polynomial in ``sin(alpha)``), plus the
saturated damping of Eq. 7.29 with ``C_H = b_h sqrt(K)`` (Eq. 7.54). Its axial
component is ``P sin(alpha) cos(alpha_e)`` (Eq. 9.6) and ``Z_eff`` spheres carry
it (Eq. 5.5). Because ``d(delta_n)/d(delta_a) = sin(alpha)`` exactly, the
axial force is the derivative of the stored elastic energy: the undamped
contact is conservative.

Lead (travel) error and thermal expansion
-----------------------------------------
A real screw's groove is not at ``p phi / (2 pi)`` along it: ISO 3408-3 (ball screws, acceptance tests)
bounds its travel deviation by a mean deviation over the useful travel (the slope of the "mean travel"
line), a variation about that line over the travel, and a variation within one revolution
(:func:`travel_deviation`). The nut follows the groove, so the kinematics of Eq. 9.5 become

    dx_i = x_s + p(T) (theta_s - theta_ni) / (2 pi) + e(theta_s - theta_ni) - x_ni,

and the reaction torques on screw and nut take the local lead ``p(T)/(2 pi) + e'`` (the contact force
is the gradient of the same elastic energy). ``p(T) = p (1 + alpha (T - 20 degC))`` is the steel's
thermal expansion (Sec. 7.7, Eq. 7.72 in its dimensionally consistent form). Both nuts ride the same
groove a whole number of leads apart, so the per-revolution term is the same for both; their spacing's
share of the long-wave term (a few um over the test, against a 1e6 N/m disc-spring set) is neglected.
"""

import math

import numba

from numerics.elementary import cos, sin
from numerics.jit import SCALAR
from twin.physics.hertz import damping_coefficient, saturated_damping_force

#: Degree of the polynomial fit of the series Hertz stiffness in ``sin(alpha)`` (:func:`stiffness_at`).
STIFFNESS_FIT_DEGREE = 6
#: Contact laws (argument ``contact_model``): the codes of the ``contact`` levels in :data:`twin.levels.SUBSYSTEMS`
#: (their index, most detailed first; ``twin.engine.levels`` checks the two agree).
CONTACT_VARIABLE_ANGLE = 0  # Hertz with the Eq. 9.4 load-dependent angle
CONTACT_CONSTANT_ANGLE = 1  # Hertz at the design angle alpha_0
CONTACT_LINEAR = 2          # linear normal stiffness at the design angle (the elasto-backlash of Ch. 5)


@numba.njit(**SCALAR)
def contact_geometry(axial_interference, centre_distance, radial_0, axial_0):
    """Normal approach and ``sin(alpha)`` for an axial interference (Eq. 9.4, exact form).

    Parameters
    ----------
    axial_interference : float
        ``delta_a >= 0`` on the plane normal to the thread [m].
    centre_distance : float
        ``A0``, distance of the groove curvature centres at first contact [m].
    radial_0, axial_0 : float
        ``A0 cos(alpha_0)`` and ``A0 sin(alpha_0)`` [m], with ``alpha_0`` the design contact angle (constants of
        the screw, computed once).

    Returns
    -------
    (delta_n, sin_alpha)
    """
    axial = axial_0 + axial_interference
    distance = math.sqrt(radial_0 * radial_0 + axial * axial)
    return distance - centre_distance, axial / distance


@numba.njit(**SCALAR)
def stiffness_at(coefficients, sin_alpha_min, sin_alpha_span, sin_alpha):
    """Series Hertz stiffness ``K(alpha)`` from its polynomial fit in ``sin(alpha)`` (Horner, degree
    :data:`STIFFNESS_FIT_DEGREE`; ``coefficients`` an array or a tuple, lowest power first).

    The fit variable ``u = 2 (sin(alpha) - sin_min)/span - 1`` is clamped to [-1, 1]:
    the curvature formulas are only fitted up to 70 deg (Sec. 3.5.5). A polynomial,
    unlike a piecewise-linear table, keeps the force smooth, so the integrators
    keep their order (tests/engine/test_energy_convergence.py).
    """
    u = 2.0 * (sin_alpha - sin_alpha_min) / sin_alpha_span - 1.0
    u = min(max(u, -1.0), 1.0)
    value = coefficients[6]
    value = value * u + coefficients[5]
    value = value * u + coefficients[4]
    value = value * u + coefficients[3]
    value = value * u + coefficients[2]
    value = value * u + coefficients[1]
    return value * u + coefficients[0]


@numba.njit(**SCALAR)
def _contact_deflection(relative_position, backlash, cos_helix, centre_distance, radial_0, axial_0, sin_alpha_0,
                        stiffness_coefficients, sin_alpha_min, sin_alpha_span, contact_model, linear_stiffness):
    """The contact's state at a relative position (shared by :func:`nut_axial_force`, :func:`nut_elastic_force`
    and :func:`nut_axial_tangent`), branch-free in the data: in the backlash gap every quantity is that of an
    unloaded contact and ``closed`` is False.

    Returns
    -------
    (closed, side, sin_alpha, stiffness, elastic, normal_stiffness, geometric)
        Whether the flank is loaded, the sign of ``dx``, ``sin(alpha)``, ``K(alpha)`` [N/m^1.5], the elastic
        normal load per sphere ``P_el`` [N], ``dP_el/d(delta_n)`` [N/m], and ``d(sin alpha)/d(delta_a)`` [1/m]
        (the variable angle's geometric stiffening, 0 at a constant angle).
    """
    gap = abs(relative_position) - 0.5 * backlash
    closed = gap > 0.0
    side = 1.0 if relative_position > 0.0 else -1.0
    delta_a = max(gap, 0.0) * cos_helix
    if contact_model == CONTACT_VARIABLE_ANGLE:  # a group-invariant level: the same branch for every lane
        axial = axial_0 + delta_a
        distance = math.sqrt(radial_0 * radial_0 + axial * axial)
        delta_n = distance - centre_distance
        sin_alpha = axial / distance
        geometric = radial_0 * radial_0 / (distance * distance * distance)
    else:
        sin_alpha = sin_alpha_0
        delta_n = delta_a * sin_alpha
        geometric = 0.0
    delta_n = max(delta_n, 0.0)  # sqrt(r0^2 + a0^2) may round a few ulps below A0 at first contact
    stiffness = stiffness_at(stiffness_coefficients, sin_alpha_min, sin_alpha_span, sin_alpha)
    if contact_model == CONTACT_LINEAR:
        elastic = linear_stiffness * delta_n
        normal_stiffness = linear_stiffness
    else:
        root = math.sqrt(delta_n)
        elastic = stiffness * delta_n * root  # elastic_force without its clamp: delta_n >= 0 here
        normal_stiffness = 1.5 * stiffness * root
    return closed, side, sin_alpha, stiffness, elastic, normal_stiffness, geometric


@numba.njit(**SCALAR)
def nut_axial_force(relative_position, relative_velocity, backlash, cos_helix, centre_distance, radial_0, axial_0,
                    sin_alpha_0, stiffness_coefficients, sin_alpha_min, sin_alpha_span, damping_b_h, loaded_balls,
                    contact_model, linear_stiffness):
    """Axial force of the screw on one nut (Eqs. 9.4-9.6, 7.28, 7.29, 7.54, 5.5).

    Parameters
    ----------
    relative_position, relative_velocity : float
        ``dx_i`` and its rate (module docstring) [m, m/s].
    backlash : float
        Total axial play ``b`` of the nut [m].
    cos_helix : float
        ``cos(alpha_e)``.
    centre_distance : float
        ``A0`` [m].
    radial_0, axial_0, sin_alpha_0 : float
        ``A0 cos(alpha_0)``, ``A0 sin(alpha_0)`` [m] and ``sin(alpha_0)`` of the design contact angle.
    stiffness_coefficients : array or tuple
        Polynomial fit of the series Hertz stiffness ``K`` [N/m^1.5] (:func:`stiffness_at`).
    sin_alpha_min, sin_alpha_span : float
        Range of ``sin(alpha)`` covered by the fit.
    damping_b_h : float
        ``b_h`` of Eq. 7.54.
    loaded_balls : float
        ``Z_eff``.
    contact_model : int
        :data:`CONTACT_VARIABLE_ANGLE` (Hertz with the variable angle of Eq. 9.4), :data:`CONTACT_CONSTANT_ANGLE`
        (Hertz at ``alpha_0``) or :data:`CONTACT_LINEAR` (linear normal stiffness ``linear_stiffness`` at
        ``alpha_0``: the elasto-backlash law of Sec. 5).
    linear_stiffness : float
        Normal stiffness per sphere of the linear law [N/m].

    Returns
    -------
    (force, normal_load, sin_alpha)
        ``force`` acts on the nut along ``+x`` (and its reaction on the screw);
        ``normal_load`` is ``P`` per sphere [N]; all zero but ``sin(alpha_0)`` in the gap.
    """
    closed, side, sin_alpha, stiffness, elastic, _, _ = _contact_deflection(
        relative_position, backlash, cos_helix, centre_distance, radial_0, axial_0, sin_alpha_0,
        stiffness_coefficients, sin_alpha_min, sin_alpha_span, contact_model, linear_stiffness)
    approach_rate = side * relative_velocity * cos_helix * sin_alpha
    normal = elastic + saturated_damping_force(elastic, damping_coefficient(damping_b_h, stiffness), approach_rate)
    force = side * loaded_balls * normal * sin_alpha * cos_helix
    return (force if closed else 0.0), (normal if closed else 0.0), (sin_alpha if closed else sin_alpha_0)


@numba.njit(**SCALAR)
def nut_elastic_force(relative_position, backlash, cos_helix, centre_distance, radial_0, axial_0, sin_alpha_0,
                      stiffness_coefficients, sin_alpha_min, sin_alpha_span, loaded_balls, contact_model,
                      linear_stiffness):
    """The elastic part of :func:`nut_axial_force` (no damping) and its tangent ``dF_el/d(dx)`` [N, N/m]
    (same arguments): what the quasi-static screw-axial balance solves with (:mod:`twin.engine.plant`).

    ``dF_el/d(dx) = Z cos(alpha_e)^2 [dP/d(delta_n) sin(alpha)^2 + P d(sin alpha)/d(delta_a)]`` with the angle's
    effect on ``K(alpha)`` left out (as in :func:`nut_axial_tangent`): Newton's iteration converges with any
    positive slope, only more slowly with an approximate one. Zero in the gap.
    """
    closed, side, sin_alpha, _, elastic, normal_stiffness, geometric = _contact_deflection(
        relative_position, backlash, cos_helix, centre_distance, radial_0, axial_0, sin_alpha_0,
        stiffness_coefficients, sin_alpha_min, sin_alpha_span, contact_model, linear_stiffness)
    force = side * loaded_balls * elastic * sin_alpha * cos_helix
    scale = loaded_balls * cos_helix * cos_helix
    slope = scale * (normal_stiffness * sin_alpha * sin_alpha + elastic * geometric)
    return (force if closed else 0.0), (slope if closed else 0.0)


def effective_loaded_balls(total_balls: float, loaded_fraction: float) -> int:
    """Eq. 5.5: ``Z_eff = floor(0.65 Z_tot)`` (the fraction is a parameter)."""
    return int(math.floor(loaded_fraction * total_balls + 1e-9))


def groove_centre_distance(ball_radius: float, conformity: float) -> float:
    """``A0 = r_s + r_n - 2 r_b = 2 (2 f - 1) r_b`` for equal screw/nut conformity ``f`` [m] (Eq. 9.4)."""
    return 2.0 * (2.0 * conformity - 1.0) * ball_radius


def helix_angle(lead: float, pitch_radius: float) -> float:
    """Helix angle ``alpha_e = atan(p / (2 pi r_m))`` [rad] (5.68 deg for Table 7.5, as listed there)."""
    return math.atan(lead / (2.0 * math.pi * pitch_radius))


def ball_angular_pitch(ball_radius: float, pitch_radius: float, lead: float) -> float:
    """Screw angle between neighbouring balls of a circuit, ``d = 2 pi (2 r_b) / sqrt((2 pi r_m)^2 + p^2)`` [rad]:
    touching balls (no spacers), one ball diameter apart along the helix, whose turn is ``sqrt((2 pi r_m)^2 + p^2)``
    long (0.395 rad for Table 7.5)."""
    return 2.0 * math.pi * (2.0 * ball_radius) / math.hypot(2.0 * math.pi * pitch_radius, lead)


def ball_averaging_factor(balls: int, angular_pitch: float) -> float:
    """Factor on a travel variation sinusoidal in screw angle once the nut averages it over ``balls`` balls
    ``angular_pitch`` apart: ``sin(N d / 2) / (N sin(d / 2))``, the mean of ``N`` equal sines a phase ``d`` apart
    about the middle ball (the Dirichlet kernel: Gradshteyn & Ryzhik, *Table of Integrals*, 7th ed., 1.341.1). Equal
    contact stiffnesses put the nut at the mean of its balls' groove positions. Exactly 1 for one ball (``x / x``);
    negative where the balls span between one and two periods (-0.216 for 22 balls 0.395 rad apart)."""
    return math.sin(balls * angular_pitch / 2.0) / (balls * math.sin(angular_pitch / 2.0))


@numba.njit(**SCALAR)
def nut_axial_tangent(relative_position, relative_velocity, backlash, cos_helix, centre_distance, radial_0, axial_0,
                      sin_alpha_0, stiffness_coefficients, sin_alpha_min, sin_alpha_span, damping_b_h, loaded_balls,
                      contact_model, linear_stiffness):
    """Tangent stiffness ``dF/d(dx)`` [N/m] and damping ``dF/d(dx')`` [N s/m] of :func:`nut_axial_force`.

    Same arguments as :func:`nut_axial_force`. The linearly implicit integrators need these only for stability
    (a W-method is consistent for any matrix: Hairer & Wanner, *Solving ODEs II*, Sec. IV.7), so the variation
    of ``K(alpha)`` with the angle is left out. With ``F = Z P sin(alpha) cos(alpha_e)`` and
    ``delta_a = (|dx| - b/2) cos(alpha_e)``:

        dF/d(dx) = Z cos(alpha_e)^2 [dP/d(delta_a) sin(alpha) + P d(sin alpha)/d(delta_a)],

    with ``dP/d(delta_a) = 1.5 K sqrt(delta_n) sin(alpha)`` (Hertz, Eq. 7.28, and
    ``d(delta_n)/d(delta_a) = sin(alpha)``, module docstring) and, for the variable angle of Eq. 9.4,
    ``d(sin alpha)/d(delta_a) = cos(alpha)^2 / A`` where ``A`` is the current distance of the curvature
    centres (the geometric stiffening of the contact). The damping of Eq. 7.29 adds
    ``Z cos(alpha_e)^2 sin(alpha)^2 C_H`` while it is not saturated.

    Returns
    -------
    (stiffness, damping, elastic_load)
        All zero in the backlash gap; ``elastic_load`` is the elastic part of the per-sphere normal load ``P``.
    """
    closed, _, sin_alpha, stiffness, elastic, normal_stiffness, geometric = _contact_deflection(
        relative_position, backlash, cos_helix, centre_distance, radial_0, axial_0, sin_alpha_0,
        stiffness_coefficients, sin_alpha_min, sin_alpha_span, contact_model, linear_stiffness)
    scale = loaded_balls * cos_helix * cos_helix
    damping_coefficient_h = damping_coefficient(damping_b_h, stiffness)
    approach_rate = relative_velocity * cos_helix * sin_alpha
    damping = scale * sin_alpha * sin_alpha * damping_coefficient_h
    damping = damping if damping_coefficient_h * abs(approach_rate) < elastic else 0.0
    tangent = scale * (normal_stiffness * sin_alpha * sin_alpha + elastic * geometric)
    return (tangent if closed else 0.0), (damping if closed else 0.0), (elastic if closed else 0.0)


@numba.njit(**SCALAR)
def travel_deviation(angle, lead_arm, slope, wave_amplitude, wave_number, wave_phase, wave_at_zero,
                     revolution_amplitude, revolution_phase, revolution_at_zero):
    """Travel deviation of the nut from its nominal travel and its rate per screw angle (ISO 3408-3:2006).

    ``phi`` is the screw angle relative to the nut since the test's zero, ``X = p phi / (2 pi)`` the nominal
    travel (module docstring)::

        e(phi)  = s X + a_u [sin(k_u phi + phi_u) - sin(phi_u)] + a_2pi [sin(phi + phi_2pi) - sin(phi_2pi)]
        e'(phi) = s p / (2 pi) + a_u k_u cos(k_u phi + phi_u) + a_2pi cos(phi + phi_2pi)

    ``s`` is the mean travel deviation per unit travel (ISO 3408-3's ``e_p / l_u``), ``a_u`` the amplitude of
    the variation over the useful travel, one sine of wavelength ``lambda_u`` (``v_up / 2``), with
    ``k_u = p / lambda_u`` per rad of screw angle, and ``a_2pi`` the variation within one revolution
    (``v_2pi p / 2``); ``e(0) = 0``: the test is zeroed where it starts. ``sin`` and ``cos`` are
    :mod:`numerics.elementary`'s (the same bits in a vector loop); ``wave_at_zero`` and ``revolution_at_zero``
    are ``sin(phi_u)`` and ``sin(phi_2pi)`` computed with the same function, so ``e(0)`` is exactly 0.

    Returns
    -------
    (deviation, rate)
        ``e`` [m] and ``de/dphi`` [m/rad]; both exactly zero when ``s``, ``a_u`` and ``a_2pi`` are.
    """
    wave = wave_number * angle + wave_phase
    revolution = angle + revolution_phase
    deviation = (slope * (lead_arm * angle) + wave_amplitude * (sin(wave) - wave_at_zero)
                 + revolution_amplitude * (sin(revolution) - revolution_at_zero))
    rate = slope * lead_arm + wave_amplitude * wave_number * cos(wave) + revolution_amplitude * cos(revolution)
    return deviation, rate
