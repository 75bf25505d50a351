"""Groove curvature radii of Sec. 3.5.5 against the thesis statements and a direct numerical solution."""

import math

import numpy as np
import pytest
from numba import njit

from twin.physics.groove import (
    groove_curvature_radius_numerical,
    groove_radius,
    nut_curvature_radius,
    nut_curvature_radius_iso,
    screw_curvature_radius,
    screw_curvature_radius_iso,
)

# Table 7.5 (bench screw)
R_M = 8.0e-3
R_B = 1.5875e-3
H = 0.0629e-3
L = 0.0505e-3
F_CONF = 0.528
ALPHA_E = math.atan(5.0e-3 / (2.0 * math.pi * R_M))  # lead 5 mm; Table 7.5 lists 5.679 deg

# Figs. 3.16-3.21 screw (r_m = 20 mm, r_b = 3.175 mm); the printed H, L "x 1e-3 mm" read as mm
FIG_R_M = 20.0e-3
FIG_R_B = 3.175e-3
FIG_H = 0.078e-3
FIG_L = 0.055e-3

ANGLES_DEG = (10.0, 30.0, 45.13, 60.0, 70.0)  # fitted range of Eqs. 3.20/3.27: 10-70 deg


def test_helix_angle_of_table_7_5():
    assert math.degrees(ALPHA_E) == pytest.approx(5.679, abs=2e-3)


def test_groove_radius_is_conformity_times_ball_diameter():
    # Sec. 3.5.3: r = f D_b
    assert groove_radius(F_CONF, R_B) == pytest.approx(0.528 * 3.175e-3, rel=1e-15)


@pytest.mark.parametrize("member", ["screw", "nut"])
@pytest.mark.parametrize("alpha_deg", [10.0, 45.0, 70.0])
def test_numerical_reference_reproduces_the_bearing_torus(member, alpha_deg):
    # alpha_e = H = L = 0 makes the groove a torus whose normal section along the
    # parallel has radius (distance of the point from the axis)/cos(alpha), the
    # ISO formula with r_b -> r_groove; 1e-5 covers the finite-difference step.
    r_groove = 3.3e-3
    alpha = math.radians(alpha_deg)
    radius = groove_curvature_radius_numerical(FIG_R_M, r_groove, alpha, 0.0, 0.0, 0.0, member)
    if member == "screw":
        expected = screw_curvature_radius_iso(FIG_R_M, r_groove, alpha)
    else:
        expected = nut_curvature_radius_iso(FIG_R_M, r_groove, alpha)
    assert radius == pytest.approx(expected, rel=1e-5)


@pytest.mark.parametrize("r_m", [6.0e-3, 8.0e-3, 20.0e-3, 50.0e-3])
def test_fitted_formulas_converge_to_iso_for_vanishing_helix(r_m):
    # Thesis: "for alpha_e -> 0 the proposed new formula converges to the literature
    # formula". With alpha_e = L = 0 the ISO radius is the bearing value, so the gap is
    # the fit's own error: the thesis claims < 2 % against its data; measured here
    # <= 2.9 % (screw, near 65 deg) and <= 1.5 % (nut) over 10-70 deg.
    r_b = 0.2 * r_m
    for alpha in np.radians(np.linspace(10.0, 70.0, 25)):
        assert screw_curvature_radius(r_m, r_b, alpha, 0.0, 0.0) == pytest.approx(
            screw_curvature_radius_iso(r_m, r_b, alpha), rel=0.03
        )
        assert nut_curvature_radius(r_m, r_b, alpha, 0.0, 0.0) == pytest.approx(
            nut_curvature_radius_iso(r_m, r_b, alpha), rel=0.015
        )


@pytest.mark.parametrize("alpha_deg", ANGLES_DEG)
def test_fitted_formulas_match_numerical_solution_at_bench_geometry(alpha_deg):
    # The fit was trained on numerical solutions of Eqs. 3.18/3.26 with a maximum
    # relative error < 2 % (Sec. 3.5.5); against our independent solution we measure
    # <= 3.1 % for the screw (alpha = 60 deg) and <= 1.4 % for the nut, so 3.5 % / 2 %.
    alpha = math.radians(alpha_deg)
    r_groove = groove_radius(F_CONF, R_B)
    screw_ref = groove_curvature_radius_numerical(R_M, r_groove, alpha, ALPHA_E, H, L, "screw")
    nut_ref = groove_curvature_radius_numerical(R_M, r_groove, alpha, ALPHA_E, H, L, "nut")
    assert screw_curvature_radius(R_M, R_B, alpha, ALPHA_E, L) == pytest.approx(screw_ref, rel=0.035)
    assert nut_curvature_radius(R_M, R_B, alpha, ALPHA_E, L) == pytest.approx(nut_ref, rel=0.02)


@pytest.mark.parametrize("alpha_deg", [30.0, 45.0, 60.0])
def test_fitted_formulas_match_numerical_solution_for_figure_screw(alpha_deg):
    # Figs. 3.17/3.19 geometry, alpha_e = 9.043 deg: the thesis states < 2 % fit error;
    # measured 1.95 % (screw, 60 deg) and 1.0 % (nut), so 2.5 % / 2 %.
    alpha = math.radians(alpha_deg)
    alpha_e = math.radians(9.043)
    r_groove = groove_radius(F_CONF, FIG_R_B)
    screw_ref = groove_curvature_radius_numerical(FIG_R_M, r_groove, alpha, alpha_e, FIG_H, FIG_L, "screw")
    nut_ref = groove_curvature_radius_numerical(FIG_R_M, r_groove, alpha, alpha_e, FIG_H, FIG_L, "nut")
    assert screw_curvature_radius(FIG_R_M, FIG_R_B, alpha, alpha_e, FIG_L) == pytest.approx(screw_ref, rel=0.025)
    assert nut_curvature_radius(FIG_R_M, FIG_R_B, alpha, alpha_e, FIG_L) == pytest.approx(nut_ref, rel=0.02)


@pytest.mark.parametrize("alpha_deg", [30.0, 45.0, 60.0])
def test_iso_underestimates_by_10_to_15_percent_at_20_deg_helix(alpha_deg):
    # Thesis: for helix angles up to 20 deg the literature formula errs by 10-15 %;
    # the helix curvature cos^2(alpha_e)/r predicts 1/cos^2(20 deg) - 1 = 13 %.
    alpha = math.radians(alpha_deg)
    alpha_e = math.radians(20.0)
    r_groove = groove_radius(F_CONF, FIG_R_B)
    iso_s = screw_curvature_radius_iso(FIG_R_M, FIG_R_B, alpha)
    iso_n = nut_curvature_radius_iso(FIG_R_M, FIG_R_B, alpha)
    ratios = (
        groove_curvature_radius_numerical(FIG_R_M, r_groove, alpha, alpha_e, FIG_H, FIG_L, "screw") / iso_s,
        groove_curvature_radius_numerical(FIG_R_M, r_groove, alpha, alpha_e, FIG_H, FIG_L, "nut") / iso_n,
        screw_curvature_radius(FIG_R_M, FIG_R_B, alpha, alpha_e, FIG_L) / iso_s,
        nut_curvature_radius(FIG_R_M, FIG_R_B, alpha, alpha_e, FIG_L) / iso_n,
    )
    for ratio in ratios:
        assert 1.10 <= ratio <= 1.17


def test_signs_screw_convex_nut_concave():
    # Sec. 3.5.5: r_cs > 0, r_cn < 0 (centre outside the nut). The nut check guards the
    # sign correction of Eq. 3.27: as printed (+ b5 r_m ...) it is positive below ~55 deg.
    # Magnitudes: at least ~r_m - r_b (screw) and r_m + r_b (nut), the alpha -> 0 bearing values.
    for alpha_e in np.radians([0.0, 5.679, 20.0, 40.0]):
        for alpha in np.radians(np.linspace(10.0, 70.0, 13)):
            assert screw_curvature_radius(R_M, R_B, alpha, alpha_e, L) > 0.98 * (R_M - R_B)
            assert nut_curvature_radius(R_M, R_B, alpha, alpha_e, L) < -0.98 * (R_M + R_B)


def test_radii_grow_with_contact_and_helix_angle():
    # Figs. 3.18a/3.21a: |r_c| increases with both alpha and alpha_e
    alphas = np.radians(np.linspace(10.0, 70.0, 13))
    for alpha_e in np.radians([0.0, 10.0, 30.0]):
        screw = [screw_curvature_radius(FIG_R_M, FIG_R_B, a, alpha_e, FIG_L) for a in alphas]
        nut = [nut_curvature_radius(FIG_R_M, FIG_R_B, a, alpha_e, FIG_L) for a in alphas]
        assert np.all(np.diff(screw) > 0.0)
        assert np.all(np.diff(nut) < 0.0)
    alpha = math.radians(45.0)
    helix = np.radians([0.0, 10.0, 20.0, 40.0])
    assert np.all(np.diff([screw_curvature_radius(FIG_R_M, FIG_R_B, alpha, ae, FIG_L) for ae in helix]) > 0.0)
    assert np.all(np.diff([nut_curvature_radius(FIG_R_M, FIG_R_B, alpha, ae, FIG_L) for ae in helix]) < 0.0)


def test_callable_from_compiled_code():
    @njit
    def first_curvatures(alpha):
        return (
            1.0 / screw_curvature_radius(R_M, R_B, alpha, ALPHA_E, L),
            1.0 / nut_curvature_radius(R_M, R_B, alpha, ALPHA_E, L),
        )

    rho_s, rho_n = first_curvatures(math.radians(45.13))
    assert rho_s == pytest.approx(1.0 / screw_curvature_radius(R_M, R_B, math.radians(45.13), ALPHA_E, L))
    assert rho_n < 0.0


def test_numerical_reference_rejects_unknown_member():
    with pytest.raises(ValueError, match="member"):
        groove_curvature_radius_numerical(R_M, 1.7e-3, 0.8, ALPHA_E, H, L, "ball")


# Table 3.3, typed from the thesis (not from the module): the constants of Eq. 3.20.
TABLE_3_3 = {"a1": 1.0091, "a2": 1.8975, "a3": 7.1416e-6, "a4": 2.8783, "a5": 2.3380e-1, "a6": 3.9180, "a7": 4.1160e-1}


@pytest.mark.parametrize("r_m, r_b, alpha_deg, alpha_e_deg, L", [
    (8.0e-3, 1.5875e-3, 45.0, 5.7, 0.0505e-3),     # the bench screw (Table 7.5)
    (20.0e-3, 3.175e-3, 30.0, 9.043, 0.055e-3),    # the Fig. 3.17 screw
    (20.0e-3, 3.175e-3, 60.0, 60.0, 0.2e-3),       # a steep helix: the tan(a5 alpha_e^a6) term matters
])
def test_screw_fit_is_eq_3_20_as_printed(r_m, r_b, alpha_deg, alpha_e_deg, L):
    """Eq. 3.20 with lengths in m, alpha_e in rad and alpha in degrees, evaluated here independently of the module:
    a transcription check of every constant and operation (the 2-3 % fit-error tests cannot see a slip in a5)."""
    a = TABLE_3_3
    alpha_e = math.radians(alpha_e_deg)
    sigma_1 = alpha_e ** a["a2"] + a["a3"] * alpha_deg ** a["a4"] + alpha_e * math.tan(a["a5"] * alpha_e ** a["a6"])
    expected = (a["a1"] * r_m * math.exp(sigma_1 - a["a7"] * math.sin(a["a3"] * alpha_deg ** a["a4"]) ** a["a2"])
                - r_b - L * a["a4"] ** sigma_1)
    assert screw_curvature_radius(r_m, r_b, math.radians(alpha_deg), alpha_e, L) == pytest.approx(expected, rel=1e-12)
