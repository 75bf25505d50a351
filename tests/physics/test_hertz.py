"""Hertzian point contact of Sec. 7.3: approximations against exact solutions and closed forms."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk, ellipkm1

from twin.physics.groove import groove_radius, nut_curvature_radius, screw_curvature_radius
from twin.physics.hertz import (
    FORMULA_ISO,
    FORMULA_THESIS,
    ball_groove_stiffness,
    contact_deflection,
    contact_semi_axes,
    curvature_difference,
    curvature_sum,
    damping_coefficient,
    elastic_force,
    elliptic_e,
    elliptic_k,
    ellipticity,
    equivalent_modulus,
    exact_ellipticity,
    hertz_contact,
    hertz_contact_exact,
    max_pressure,
    mean_pressure,
    relative_curvatures,
    saturated_damping_force,
    series_stiffness,
    stiffness_table,
)

# Table 7.5 (bench screw, steel on steel)
E_STEEL = 210.0e9
NU_STEEL = 0.29
R_M = 8.0e-3
R_B = 1.5875e-3
L = 0.0505e-3
R_S = groove_radius(0.528, R_B)
ALPHA_E = math.atan(5.0e-3 / (2.0 * math.pi * R_M))
ALPHA_0 = math.radians(45.13)
E_STAR = equivalent_modulus(E_STEEL, NU_STEEL, E_STEEL, NU_STEEL)


def _exact_k(kappa):
    # Eq. 7.37 in scipy's parameter m = 1 - kappa^-2; ellipkm1 avoids the cancellation in 1 - m
    return ellipkm1(kappa**-2) if kappa >= 1.0 else ellipk(1.0 - kappa**-2)


def _bench_curvatures():
    rho_b = 1.0 / R_B
    r_cs = screw_curvature_radius(R_M, R_B, ALPHA_0, ALPHA_E, L)
    r_cn = nut_curvature_radius(R_M, R_B, ALPHA_0, ALPHA_E, L)
    return {
        "screw": (rho_b, rho_b, 1.0 / r_cs, -1.0 / R_S),
        "nut": (rho_b, rho_b, 1.0 / r_cn, -1.0 / R_S),
        "ellipsoids": (1.0 / 0.01, 1.0 / 0.002, 1.0 / 0.05, 1.0 / 0.3),
        "crossed cylinders": (1.0 / 0.004, 0.0, 0.0, 1.0 / 0.012),
    }


CONTACTS = _bench_curvatures()


def test_equivalent_modulus_is_the_johnson_sum():
    # Johnson (1985) Eq. 4.22: identical bodies give E / (2 (1 - nu^2)); a rigid partner E / (1 - nu^2)
    assert E_STAR == pytest.approx(E_STEEL / (2.0 * (1.0 - NU_STEEL**2)), rel=1e-14)
    assert equivalent_modulus(E_STEEL, NU_STEEL, 1e300, 0.0) == pytest.approx(E_STEEL / (1.0 - NU_STEEL**2), rel=1e-14)
    assert equivalent_modulus(70e9, 0.33, E_STEEL, NU_STEEL) == equivalent_modulus(E_STEEL, NU_STEEL, 70e9, 0.33)


@pytest.mark.parametrize("kappa", np.concatenate([np.logspace(0.0, 6.0, 61), [1.0 + 1e-9, 2.0]]))
def test_elliptic_integrals_within_stated_error_for_kappa_ge_1(kappa):
    # Eqs. 7.39-7.40 (Abramowitz & Stegun 17.3.34/36): absolute error < 2e-8
    assert abs(elliptic_k(kappa) - _exact_k(kappa)) < 2e-8
    assert abs(elliptic_e(kappa) - ellipe(1.0 - kappa**-2)) < 2e-8


@pytest.mark.parametrize("kappa", np.logspace(-3.0, -1e-3, 31))
def test_elliptic_integrals_continuation_below_one(kappa):
    # Eqs. 7.41-7.42 scale the kappa >= 1 forms by kappa and 1/kappa, and the error bound with them
    assert abs(elliptic_k(kappa) - _exact_k(kappa)) < 2e-8 * kappa
    assert abs(elliptic_e(kappa) - ellipe(1.0 - kappa**-2)) < 2e-8 / kappa


def test_ellipticity_approximation_against_exact_root():
    # Eq. 7.43 is stated for 1 <= B/A < 1e10; the thesis gives no accuracy. Measured against
    # the exact root of Eq. 7.36: max relative error 5.9e-6 (B/A ~ 280), so 1e-5.
    for b_over_a in np.logspace(0.0, 10.0, 401)[1:]:
        f_rho = -(b_over_a - 1.0) / (b_over_a + 1.0)  # Eqs. 7.34-7.35 inverted
        assert ellipticity(b_over_a) == pytest.approx(exact_ellipticity(f_rho), rel=1e-5)
    assert ellipticity(1.0) == 1.0
    assert ellipticity(1.0 / 37.0) == pytest.approx(1.0 / ellipticity(37.0), rel=1e-14)


def test_exact_ellipticity_solves_eq_7_36():
    f_abs = 0.9
    kappa = exact_ellipticity(-f_abs)
    m = 1.0 - kappa**-2
    residual = ((kappa**2 + 1.0) * ellipe(m) - 2.0 * ellipk(m)) / ((kappa**2 - 1.0) * ellipe(m))
    assert residual == pytest.approx(f_abs, rel=1e-13)
    assert exact_ellipticity(0.0) == 1.0


@pytest.mark.parametrize("name", sorted(CONTACTS))
def test_approximate_contact_matches_exact(name):
    # The only approximation errors are kappa (< 1e-5 relative) and K, E (< 2e-8 absolute);
    # a*, b*, delta* depend on kappa with sensitivities below 1, so 1e-5 relative throughout.
    approx = hertz_contact(*CONTACTS[name], E_STAR)
    exact = hertz_contact_exact(*CONTACTS[name], E_STAR)
    assert approx == pytest.approx(exact, rel=1e-5)


def test_relative_curvatures_ordered_and_summing():
    rho = CONTACTS["screw"]
    sum_rho = curvature_sum(*rho)
    f_rho = curvature_difference(*rho, 0.0)
    a_rel, b_rel = relative_curvatures(sum_rho, f_rho)
    assert -1.0 < f_rho <= 0.0
    assert 0.0 < a_rel <= b_rel
    assert a_rel + b_rel == pytest.approx(sum_rho, rel=1e-15)
    # Sphere in a groove: A and B are the sums of the curvatures in the two principal planes
    assert sorted([a_rel, b_rel]) == pytest.approx(sorted([rho[0] + rho[3], rho[1] + rho[2]]), rel=1e-12)


@pytest.mark.parametrize("r1, r2", [(0.01, math.inf), (0.01, 0.03), (1.5875e-3, 1.5875e-3)])
def test_circular_contact_closed_form(r1, r2):
    # Sphere on flat / sphere on sphere (Johnson 1985, Eqs. 4.22-4.23):
    # F = 4/3 E* sqrt(R) delta^1.5, a = (3 F R / (4 E*))^(1/3), delta = a^2 / R, p0 = 3F/(2 pi a^2).
    # At kappa = 1 the approximations are exact to ~1e-11 (sum of Table 7.1 a_i = pi/2), so 1e-9.
    rho2 = 0.0 if math.isinf(r2) else 1.0 / r2
    r_eff = 1.0 / (1.0 / r1 + rho2)
    force = 50.0
    for contact in (hertz_contact, hertz_contact_exact):
        k_h, kappa, a_star, b_star, delta_star = contact(1.0 / r1, 1.0 / r1, rho2, rho2, E_STAR)
        assert kappa == pytest.approx(1.0, abs=1e-12)
        assert k_h == pytest.approx(4.0 / 3.0 * E_STAR * math.sqrt(r_eff), rel=1e-9)
        a, b = contact_semi_axes(force, a_star, b_star, 2.0 / r_eff, E_STAR)
        assert a == pytest.approx((3.0 * force * r_eff / (4.0 * E_STAR)) ** (1.0 / 3.0), rel=1e-9)
        assert b == pytest.approx(a, rel=1e-9)
        assert contact_deflection(force, k_h) == pytest.approx(a**2 / r_eff, rel=1e-9)
        assert max_pressure(force, a, b) == pytest.approx(3.0 * force / (2.0 * math.pi * a**2), rel=1e-9)


@pytest.mark.parametrize("name", ["screw", "nut", "ellipsoids"])
def test_stiffness_consistent_with_body_deflections_eq_7_53(name):
    # Eqs. 7.52-7.53: delta = sum_j 3 (1 - nu_j^2) F K / (2 pi a E_j) = 3 F K / (2 pi a E*),
    # with a from Eq. 7.45. This pins the 2^(5/2) of our Eq. 7.47 (the printed 2^(3/2) is off
    # by a factor 2). Exact integrals, so only rounding remains: 1e-12.
    rho = CONTACTS[name]
    force = 64.0
    k_h, kappa, a_star, b_star, _ = hertz_contact_exact(*rho, E_STAR)
    a, _ = contact_semi_axes(force, a_star, b_star, curvature_sum(*rho), E_STAR)
    delta_bodies = 2.0 * 3.0 * (1.0 - NU_STEEL**2) * force * _exact_k(kappa) / (2.0 * math.pi * a * E_STEEL)
    assert contact_deflection(force, k_h) == pytest.approx(delta_bodies, rel=1e-12)


def test_semi_axes_and_pressure_at_bench_load_match_exact():
    # 64 N on the bench sphere-screw contact; approximations within 1e-5 (see above).
    # The ellipse is slender and transverse: a > b.
    rho = CONTACTS["screw"]
    force = 64.0
    sum_rho = curvature_sum(*rho)
    axes = {}
    for contact in (hertz_contact, hertz_contact_exact):
        _, _, a_star, b_star, _ = contact(*rho, E_STAR)
        axes[contact] = contact_semi_axes(force, a_star, b_star, sum_rho, E_STAR)
    a, b = axes[hertz_contact]
    assert (a, b) == pytest.approx(axes[hertz_contact_exact], rel=1e-5)
    assert a > 5.0 * b
    assert mean_pressure(force, a, b) == pytest.approx(force / (math.pi * a * b), rel=1e-15)
    assert max_pressure(force, a, b) == pytest.approx(1.5 * force / (math.pi * a * b), rel=1e-15)


def test_force_proportional_to_deflection_power_1_5():
    k_h = hertz_contact(*CONTACTS["screw"], E_STAR)[0]
    deltas = np.array([1e-8, 1e-7, 1e-6, 1e-5])
    forces = np.array([elastic_force(k_h, d) for d in deltas])
    slopes = np.diff(np.log(forces)) / np.diff(np.log(deltas))
    assert slopes == pytest.approx(1.5, rel=1e-12)
    assert contact_deflection(elastic_force(k_h, 3e-6), k_h) == pytest.approx(3e-6, rel=1e-12)
    # Eq. 7.30: no interpenetration, no force
    assert elastic_force(k_h, 0.0) == 0.0
    assert elastic_force(k_h, -1e-6) == 0.0


@pytest.mark.parametrize("name", sorted(CONTACTS))
def test_swapping_bodies_changes_nothing(name):
    rho11, rho12, rho21, rho22 = CONTACTS[name]
    assert hertz_contact(rho21, rho22, rho11, rho12, E_STAR) == pytest.approx(
        hertz_contact(rho11, rho12, rho21, rho22, E_STAR), rel=1e-14
    )
    assert hertz_contact_exact(rho21, rho22, rho11, rho12, E_STAR) == pytest.approx(
        hertz_contact_exact(rho11, rho12, rho21, rho22, E_STAR), rel=1e-12
    )


def test_saturated_damping_force_eq_7_29():
    f_el, c = 100.0, 2.0e5
    assert saturated_damping_force(f_el, c, 1e-4) == pytest.approx(20.0)
    assert saturated_damping_force(f_el, c, -1e-4) == pytest.approx(-20.0)
    assert saturated_damping_force(f_el, c, 1.0) == f_el
    assert saturated_damping_force(f_el, c, -1.0) == -f_el  # total force F_nk + F_nd never < 0
    assert saturated_damping_force(0.0, c, 1.0) == 0.0  # no force jump at first touch


def test_damping_coefficient_eq_7_54():
    assert damping_coefficient(2.0, 1.0e10) == pytest.approx(2.0e5, rel=1e-15)


def test_series_stiffness_adds_deflections():
    k1, k2, force = 1.4e10, 1.6e10, 64.0
    k_eq = series_stiffness(k1, k2)
    assert contact_deflection(force, k_eq) == pytest.approx(
        contact_deflection(force, k1) + contact_deflection(force, k2), rel=1e-13
    )
    assert series_stiffness(k1, k1) == pytest.approx(k1 * 2.0**-1.5, rel=1e-14)


def test_ball_groove_stiffness_at_bench_geometry():
    # Independent route: exact Hertz on the groove curvatures. The nut contact is stiffer
    # than the screw contact (concave first curvature, larger footprint).
    k_s, k_n, k_eq = ball_groove_stiffness(ALPHA_0, R_M, R_B, R_S, R_S, ALPHA_E, L, E_STAR, FORMULA_THESIS)
    assert k_s == pytest.approx(hertz_contact_exact(*CONTACTS["screw"], E_STAR)[0], rel=1e-5)
    assert k_n == pytest.approx(hertz_contact_exact(*CONTACTS["nut"], E_STAR)[0], rel=1e-5)
    assert k_eq == pytest.approx(series_stiffness(k_s, k_n), rel=1e-15)
    assert k_n > k_s
    # The bench figure from an independent route: Harris & Kotzalas's textbook closed form on the ISO 3408-4
    # curvatures, computed here without the module (5.2726e9 N/m^1.5; 5.28 um at 64 N per ball).
    independent = _harris_series_stiffness(ALPHA_0)
    iso = ball_groove_stiffness(ALPHA_0, R_M, R_B, R_S, R_S, ALPHA_E, L, E_STAR, FORMULA_ISO)
    # the module's approximation of the ellipticity (Eqs. 7.32-7.50) is good to ~1e-6 here
    assert iso[2] == pytest.approx(independent, rel=1e-5)
    assert contact_deflection(64.0, iso[2]) == pytest.approx((64.0 / independent) ** (2.0 / 3.0), rel=1e-5)
    # At a 5.7 deg helix the thesis fits of the first curvature (Eqs. 3.20, 3.27) move it by 4e-5 only
    # against the 1.68 mm profile radius: a difference, not zero (test_simulate_api checks it reaches the model)
    assert k_eq == pytest.approx(independent, rel=1e-4) and k_eq != pytest.approx(independent, rel=1e-5)
    assert iso == pytest.approx((k_s, k_n, k_eq), rel=1e-3)


def _harris_contact_stiffness(rho_11, rho_12, rho_21, rho_22):
    """Point-contact load-deflection constant Q = K delta^1.5 of Harris & Kotzalas, Rolling Bearing Analysis
    (5th ed., 2007), Ch. 6: F(rho) = ((kappa^2 + 1) E - 2 K) / ((kappa^2 - 1) E), solved for the ellipticity
    kappa with scipy's complete elliptic integrals (parameter m = 1 - 1/kappa^2), then
    K = pi kappa E' sqrt(2 E / (9 sum_rho K^3)), E' = E / (1 - nu^2) for two equal materials."""
    total = rho_11 + rho_12 + rho_21 + rho_22
    f_rho = abs(rho_11 - rho_12 + rho_21 - rho_22) / total

    def mismatch(kappa):
        m = 1.0 - kappa**-2
        return ((kappa**2 + 1.0) * ellipe(m) - 2.0 * ellipk(m)) / ((kappa**2 - 1.0) * ellipe(m)) - f_rho

    kappa = brentq(mismatch, 1.0 + 1e-9, 1e3, xtol=1e-14, rtol=1e-15)
    m = 1.0 - kappa**-2
    e_prime = E_STEEL / (1.0 - NU_STEEL**2)
    return math.pi * kappa * e_prime * math.sqrt(2.0 * ellipe(m) / (9.0 * total * ellipk(m) ** 3))


def _harris_series_stiffness(alpha):
    """Ball against screw and nut grooves in series, ISO 3408-4 first curvature radii (r_m -/+ r_b cos a)/cos a."""
    r_screw = (R_M - R_B * math.cos(alpha)) / math.cos(alpha)
    r_nut = -(R_M + R_B * math.cos(alpha)) / math.cos(alpha)
    k_screw = _harris_contact_stiffness(1 / R_B, 1 / R_B, 1 / r_screw, -1 / R_S)
    k_nut = _harris_contact_stiffness(1 / R_B, 1 / R_B, 1 / r_nut, -1 / R_S)
    return (k_screw ** (-2.0 / 3.0) + k_nut ** (-2.0 / 3.0)) ** -1.5


def test_stiffness_table_matches_pointwise_and_keeps_shape():
    grid = np.radians(np.linspace(20.0, 70.0, 11))
    table = stiffness_table(grid, R_M, R_B, R_S, R_S, ALPHA_E, L, E_STAR)
    pointwise = [ball_groove_stiffness(a, R_M, R_B, R_S, R_S, ALPHA_E, L, E_STAR)[2] for a in grid]
    assert table == pytest.approx(pointwise, rel=1e-15)
    assert stiffness_table(grid.reshape(1, -1), R_M, R_B, R_S, R_S, ALPHA_E, L, E_STAR).shape == (1, 11)
    assert np.all(np.isfinite(table)) and np.all(table > 0.0)


@pytest.mark.parametrize(
    "override, argument",
    [
        ({"r_b": -1.0e-3}, "r_b"),
        ({"r_m": 0.0}, "r_m"),
        ({"r_s": 1.5e-3}, "r_s"),
        ({"r_n": -1.7e-3}, "r_n"),
        ({"alpha": 0.0}, "alpha"),
        ({"alpha": 0.5 * math.pi}, "alpha"),
        ({"alpha": -0.3}, "alpha"),
        ({"alpha_e": -0.1}, "alpha_e"),
        ({"L": -1e-6}, "L"),
        ({"e_star": -1.0}, "e_star"),
        ({"formula": 2}, "formula"),
    ],
)
def test_ball_groove_stiffness_rejects_bad_input(override, argument):
    kwargs = dict(alpha=ALPHA_0, r_m=R_M, r_b=R_B, r_s=R_S, r_n=R_S, alpha_e=ALPHA_E, L=L, e_star=E_STAR, formula=0)
    kwargs.update(override)
    with pytest.raises(ValueError, match=rf"\b{argument}\b"):
        ball_groove_stiffness(**kwargs)


def test_stiffness_table_rejects_bad_angle_and_lists_all_problems():
    grid = np.radians([30.0, 45.0, 95.0])
    with pytest.raises(ValueError, match="alpha_grid") as info:
        stiffness_table(grid, R_M, -R_B, R_S, R_S, ALPHA_E, L, E_STAR)
    assert "r_b" in str(info.value)


def test_exact_contact_rejects_bad_input():
    with pytest.raises(ValueError, match="e_star"):
        hertz_contact_exact(*CONTACTS["screw"], -1.0)
    # a sphere in a tighter concave seat is conforming, not Hertzian
    with pytest.raises(ValueError, match="rho11"):
        hertz_contact_exact(1.0 / R_B, 1.0 / R_B, -1.0 / R_B, -2.0 / R_B, E_STAR)
    # the limit: a sphere in a seat of its own radius has A = B = 0, a contact area without Hertz pressure
    with pytest.raises(ValueError, match="rho11"):
        hertz_contact_exact(1.0 / R_B, 1.0 / R_B, -1.0 / R_B, -1.0 / R_B, E_STAR)
