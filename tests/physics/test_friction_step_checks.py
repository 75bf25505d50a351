"""The friction laws' parameter checks (issue 41, item 3): the levels of Eq. 7.63 and the step RK4 needs for the
seal's eigenvalues (twin.physics.friction.level_problems, twin.physics.bristle_friction.rk4_step_problems)."""

import math

import pytest

from twin import load_parameters
from twin.physics import bristle_friction as bf
from twin.physics.friction import level_problems

SEAL = {k: v for k, v in load_parameters().values().items() if k.startswith("pneumatics.")}
NOMINAL_SPEED = 0.07    # m/s: Table 9.3's nominal bench speed


def test_rk4s_real_axis_reach_is_2_785():
    """The classical fourth-order region meets the negative real axis at -2.7853 (Hairer & Wanner, Solving ODEs
    II, Fig. IV.2.1), and the imaginary axis at +-2 sqrt(2)."""
    assert bf.rk4_stable(-2.78) and not bf.rk4_stable(-2.79)
    assert bf.rk4_stable(2.82j) and not bf.rk4_stable(2.84j)
    assert bf.rk4_step_limit([-1.0e4], 1.0) == pytest.approx(2.7853e-4, rel=1e-4)


def test_the_seal_eigenvalues_are_the_closed_forms():
    m, s0, s1 = SEAL["pneumatics.piston_mass"], SEAL["pneumatics.friction_presliding_stiffness"], SEAL[
        "pneumatics.friction_bristle_damping"]
    ep = bf.seal_eigenvalues("elasto_plastic", SEAL, NOMINAL_SPEED)
    lam = ep["presliding mode"]
    assert m * lam * lam + s1 * lam + s0 == pytest.approx(0.0, abs=1e-6 * s0)   # a root of m s^2 + s1 s + s0
    assert abs(lam) == pytest.approx(math.sqrt(s0 / m), rel=1e-12)              # underdamped: |lambda| = omega
    assert ep["sliding relaxation"] == pytest.approx(-s0 * NOMINAL_SPEED / SEAL["pneumatics.friction_dynamic"])
    reg = bf.seal_eigenvalues("regularised", SEAL, NOMINAL_SPEED)["regularised Coulomb slope"]
    assert reg == pytest.approx(-SEAL["pneumatics.friction_static"] / (m * SEAL[
        "pneumatics.friction_velocity_threshold"]))


@pytest.mark.parametrize("level", ["regularised", "elasto_plastic"])
@pytest.mark.parametrize("dt", [1.25e-4, 6.25e-5, 1.5625e-5])
def test_the_nominal_seal_passes_at_every_step_the_twin_offers(level, dt):
    assert bf.rk4_step_problems(level, SEAL, dt, NOMINAL_SPEED) == []


def test_a_light_piston_makes_the_presliding_mode_unstable_and_the_message_names_the_field():
    light = dict(SEAL, **{"pneumatics.piston_mass": 0.01})
    problems = bf.rk4_step_problems("elasto_plastic", light, 6.25e-5, NOMINAL_SPEED)
    assert len(problems) == 1
    assert problems[0].startswith("pneumatics.friction_presliding_stiffness:")
    assert "pneumatics.piston_mass = 0.01 kg" in problems[0] and "presliding mode" in problems[0]
    limit = float(problems[0].rsplit("dt <= ", 1)[1].split()[0])
    assert bf.rk4_step_problems("elasto_plastic", light, limit * 0.99, NOMINAL_SPEED) == []


def test_a_stiff_seal_on_a_low_sliding_level_makes_the_relaxation_unstable():
    stiff = dict(SEAL, **{"pneumatics.friction_presliding_stiffness": 4.0e7, "pneumatics.friction_dynamic": 5.0})
    problems = bf.rk4_step_problems("elasto_plastic", stiff, 6.25e-5, NOMINAL_SPEED)
    assert any("sliding relaxation" in p for p in problems)


def test_a_small_regularisation_speed_names_its_own_field():
    sharp = dict(SEAL, **{"pneumatics.friction_velocity_threshold": 1.0e-5})
    problems = bf.rk4_step_problems("regularised", sharp, 6.25e-5, NOMINAL_SPEED)
    assert len(problems) == 1 and problems[0].startswith("pneumatics.friction_velocity_threshold:")
    # the limit it states is the closed form 2.785 m v_th / F_s
    limit = float(problems[0].rsplit("dt <= ", 1)[1].split()[0])
    assert limit == pytest.approx(2.7853 * 7.5 * 1.0e-5 / 400.0, rel=1e-3)


def test_friction_levels_negative_or_static_below_dynamic_get_one_line_each():
    assert level_problems("sled.guide_friction_static", 12.0, "sled.guide_friction_dynamic", 9.0) == []
    assert level_problems("sled.guide_friction_static", 9.0, "sled.guide_friction_dynamic", 9.0) == []
    below = level_problems("sled.guide_friction_static", 5.0, "sled.guide_friction_dynamic", 9.0)
    assert len(below) == 1 and below[0].startswith("sled.guide_friction_static:") and "below" in below[0]
    bad = level_problems("sled.guide_friction_static", -1.0, "sled.guide_friction_dynamic", math.nan)
    assert [p.split(":")[0] for p in bad] == ["sled.guide_friction_static", "sled.guide_friction_dynamic"]
