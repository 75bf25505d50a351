"""Reduced ball-screw contact (Eqs. 9.4-9.6): geometry, conservativeness, backlash, symmetry."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from twin.physics.ball_screw import (
    CONTACT_CONSTANT_ANGLE,
    CONTACT_LINEAR,
    CONTACT_VARIABLE_ANGLE,
    contact_geometry,
    effective_loaded_balls,
    groove_centre_distance,
    helix_angle,
    nut_axial_force,
    stiffness_at,
)

A0 = groove_centre_distance(1.5875e-3, 0.528)
ALPHA0 = math.radians(45.13)
RADIAL0, AXIAL0, SIN0 = A0 * math.cos(ALPHA0), A0 * math.sin(ALPHA0), math.sin(ALPHA0)
COS_HELIX = math.cos(helix_angle(5e-3, 8e-3))
K_CONST = np.array([5.27e9, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # constant stiffness polynomial (degree 6)
Z = 22.0


def force(dx, dv=0.0, backlash=0.0, variable=True, damping=0.0, linear_stiffness=None):
    """Axial nut force at the contact level: variable or constant angle Hertz, or linear if a stiffness is given."""
    model = (CONTACT_LINEAR if linear_stiffness is not None
             else (CONTACT_VARIABLE_ANGLE if variable else CONTACT_CONSTANT_ANGLE))
    return nut_axial_force(dx, dv, backlash, COS_HELIX, A0, RADIAL0, AXIAL0, SIN0, K_CONST, SIN0, 0.2, damping, Z,
                           model, linear_stiffness or 0.0)


def test_helix_angle_matches_table_7_5():
    assert math.degrees(helix_angle(5e-3, 8e-3)) == pytest.approx(5.679, abs=5e-3)


def test_contact_angle_first_order_matches_eq_9_4():
    """For small deformation the exact geometry reduces to Eq. 9.4: tan(a) = tan(a0) + d/(2(r_s - r_b) cos a0)."""
    delta = 1e-7
    _, sin_alpha = contact_geometry(delta, A0, RADIAL0, AXIAL0)
    alpha = math.asin(sin_alpha)
    assert math.tan(alpha) == pytest.approx(math.tan(ALPHA0) + delta / (A0 * math.cos(ALPHA0)), rel=1e-9)


def test_contact_angle_grows_with_load():
    angles = [math.asin(contact_geometry(d, A0, RADIAL0, AXIAL0)[1]) for d in (0.0, 5e-6, 2e-5)]
    assert angles[0] == pytest.approx(ALPHA0, abs=1e-12)
    assert angles[0] < angles[1] < angles[2]


@pytest.mark.parametrize("variable", [True, False])
def test_force_is_gradient_of_energy(variable):
    """dF/dx integrated numerically equals the Hertz energy Z * K * (2/5) delta_n^2.5 (conservative contact)."""
    dx = 8e-6
    energy, _ = quad(lambda d: force(d, variable=variable)[0], 0.0, dx, epsabs=1e-15, epsrel=1e-12)
    delta_n = contact_geometry(dx * COS_HELIX, A0, RADIAL0, AXIAL0)[0] if variable else dx * COS_HELIX * SIN0
    assert energy == pytest.approx(Z * K_CONST[0] * 0.4 * delta_n**2.5, rel=1e-9)


def test_hertz_three_halves_law_constant_angle():
    f1, f2 = force(2e-6, variable=False)[0], force(4e-6, variable=False)[0]
    assert f2 / f1 == pytest.approx(2**1.5, rel=1e-12)


def test_linear_contact_is_an_elasto_backlash_spring():
    """The linear level is proportional to the interference beyond the half gap (Ch. 5 elasto-backlash), and its
    secant stiffness K delta^0.5 reproduces the Hertz force at that deflection exactly."""
    backlash, dx = 20e-6, 14e-6
    delta_n = (dx - 0.5 * backlash) * COS_HELIX * math.sin(ALPHA0)
    secant = K_CONST[0] * delta_n**0.5
    linear = force(dx, backlash=backlash, linear_stiffness=secant)[0]
    assert linear == pytest.approx(force(dx, backlash=backlash, variable=False)[0], rel=1e-12)
    assert force(0.5 * backlash + 2 * (dx - 0.5 * backlash), backlash=backlash,
                 linear_stiffness=secant)[0] == pytest.approx(2 * linear, rel=1e-12)
    assert force(9e-6, backlash=backlash, linear_stiffness=secant)[0] == 0.0


def test_backlash_gap_transmits_nothing_and_is_symmetric():
    backlash = 20e-6
    for dx in np.linspace(-9.99e-6, 9.99e-6, 21):
        assert force(dx, backlash=backlash)[0] == 0.0
    assert force(12e-6, backlash=backlash)[0] == pytest.approx(-force(-12e-6, backlash=backlash)[0], rel=1e-14)
    assert force(12e-6, backlash=backlash)[0] == pytest.approx(force(2e-6)[0], rel=1e-14)


def test_saturated_damping_never_pulls():
    """Eq. 7.29: a fast separation cannot make the normal load negative (no attraction)."""
    f, normal, _ = force(3e-6, dv=-10.0, damping=1.0)
    assert normal == 0.0 and f == 0.0
    f_slow, normal_slow, _ = force(3e-6, dv=1e-6, damping=1.0)
    assert normal_slow > force(3e-6)[1]


def test_stiffness_polynomial_is_evaluated_in_the_fitted_range_and_clamped_outside():
    """Horner evaluation of sum c_k u^k with u = 2 (s - s_min) / span - 1, clamped to [-1, 1]: beyond the fitted
    angles (Sec. 3.5.5) the stiffness stays at its end values instead of following the polynomial."""
    coefficients = np.array([1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 0.0])  # 1 + 2u + 3u^2, as a degree-6 fit
    s_min, span = 0.7, 0.2
    assert stiffness_at(coefficients, s_min, span, 0.8) == pytest.approx(1.0, rel=1e-12)  # u = 0
    assert stiffness_at(coefficients, s_min, span, 0.85) == pytest.approx(1.0 + 1.0 + 0.75, rel=1e-12)  # u = 0.5
    assert stiffness_at(coefficients, s_min, span, 0.7) == pytest.approx(2.0, rel=1e-12)  # u = -1
    assert stiffness_at(coefficients, s_min, span, 0.5) == pytest.approx(2.0, rel=1e-12)  # u = -3, clamped to -1
    assert stiffness_at(coefficients, s_min, span, 1.2) == pytest.approx(6.0, rel=1e-12)  # u = 4, clamped to 1


def test_effective_loaded_balls_is_the_floor_of_the_loaded_fraction():
    """Eq. 5.5, Z_eff = floor(0.65 Z_tot), robust to a product that lands a rounding error below an integer."""
    assert effective_loaded_balls(20, 0.65) == 13
    assert effective_loaded_balls(21, 0.65) == 13  # 13.65
    assert effective_loaded_balls(10, 0.5) == 5
    assert 0.29 * 100 < 29 and effective_loaded_balls(100, 0.29) == 29  # 28.999999999999996 in binary


def test_groove_centre_distance_is_the_sum_of_the_profile_radii_less_the_ball():
    """Eq. 9.4: A0 = r_s + r_n - 2 r_b with r_s = r_n = 2 f r_b."""
    r_b, f = 1.5875e-3, 0.528
    assert groove_centre_distance(r_b, f) == pytest.approx(2 * (2 * f * r_b) - 2 * r_b, rel=1e-12)
    assert groove_centre_distance(r_b, 0.5) == 0.0  # a conforming groove: no play of the centres
