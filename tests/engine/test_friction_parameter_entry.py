"""Bad friction parameters are refused at the entry a user meets (`twin simulate --set`, twin.simulate), before any
run, naming the field (issue 41): a seal whose presliding stiffness or regularisation speed puts an eigenvalue beyond
RK4's reach at the run's step (twin.physics.bristle_friction.rk4_step_problems), and guides whose breakaway level is
below their sliding level (twin.physics.friction.level_problems; the seal's pair is checked by validate_pneumatics)."""

import pytest

import twin
from twin.errors import OptionError, ParameterError

SHORT = 0.01  # s: the checks run before the solve, so any duration shows them


def test_a_presliding_stiffness_beyond_rk4s_reach_is_refused_naming_the_field_and_the_largest_stable_step():
    # the stiffest seal the parameter's range allows on a light (0.05 kg) piston: a presliding mode RK4 at 125 us
    # cannot follow (a stiffness beyond the range is refused by the range itself)
    light = twin.load_parameters().with_values({"pneumatics.friction_presliding_stiffness": 4.0e7,
                                                "pneumatics.piston_mass": 0.05})
    with pytest.raises(OptionError) as refused:
        twin.simulate("ds4", light, duration=SHORT, solver=twin.Solver(dt=125e-6),
                      fidelity={"seal_friction": "elasto_plastic"})
    text = str(refused.value)
    assert "pneumatics.friction_presliding_stiffness: 4e+07" in text and "presliding mode" in text
    largest = float(text.rsplit("dt <= ", 1)[1].split()[0])
    twin.simulate("ds4", light, duration=SHORT, solver=twin.Solver(dt=125e-6 / 8), save="features",
                  fidelity={"seal_friction": "elasto_plastic"})  # 15.6 us < the largest stable step it named
    assert 125e-6 / 8 <= largest


def test_a_regularisation_speed_too_small_for_the_step_is_refused_and_a_smaller_step_accepts_it():
    sharp = twin.load_parameters().with_values({"pneumatics.friction_velocity_threshold": 1.0e-5})
    regularised = {"seal_friction": "regularised"}  # the level whose smoothing speed it is (the default has none)
    with pytest.raises(OptionError, match="pneumatics.friction_velocity_threshold"):
        twin.simulate("ds4", sharp, duration=SHORT, fidelity=regularised)
    # RK4's limit is 2.785 m v_th / F_s = 2.785 * 7.5 kg * 1e-5 m/s / 400 N = 5.2e-7 s (the test's closed form)
    ok = twin.simulate("ds4", sharp, duration=SHORT, solver=twin.Solver(dt=125e-6 / 256), save="features",
                       fidelity=regularised)
    assert ok.status != "" and ok.dt == pytest.approx(125e-6 / 256)


def test_the_nominal_seal_passes_at_every_default_step():
    for scene in ("ds1", "ds4", "nominal"):
        twin.simulate(scene, duration=SHORT, save="features")
        twin.simulate(scene, duration=SHORT, save="features", fidelity={"seal_friction": "regularised"})


def test_guides_with_breakaway_below_sliding_friction_are_refused_naming_the_field():
    backwards = twin.load_parameters().with_values({"sled.guide_friction_static": 10.0,
                                                    "sled.guide_friction_dynamic": 20.0})
    with pytest.raises(ParameterError, match="sled.guide_friction_static: the breakaway"):
        twin.simulate("ds4", backwards, duration=SHORT)
