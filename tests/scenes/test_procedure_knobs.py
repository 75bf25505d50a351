"""Test procedures as knobs (twin.scenes.procedure): the profiles they compile to, the bench's limits, and the
backlash physics under a procedure."""

import math

import numpy as np
import pytest

import twin
from twin.errors import SceneError
from twin.scenes.procedure import (
    FORCE_RISE_TIME,
    KNOBS,
    NOMINAL_SPEED,
    SETTLE_TIME,
    procedure_duration,
    procedure_problems,
)
from twin.scenes.profiles import profile_values

UM = 1e-6
KNOBS_SET = {"preload": 300.0, "external_force": -1500.0, "amplitude": 3e-3, "frequency": 2.0, "cycles": 3,
             "dwell": 0.4, "zero_procedure": "preloaded"}


def test_the_motion_is_the_thesis_raised_cosine_for_the_given_cycles():
    """0 at rest through the dwell, 2A at each half cycle, back to 0 at every cycle's end and after the motion;
    peak speed 2 pi f A (central differences on a 0.1 ms grid: error ~ (2 pi f dt)^2 / 6, 1e-7 relative)."""
    scene = twin.load_scene("ds2").with_procedure(KNOBS_SET)
    table, a, f, dwell = scene.position_table(), 3e-3, 2.0, 0.4
    assert profile_values(table, np.array([0.0, dwell]))[1] == 0.0
    crests = dwell + (np.arange(3) + 0.5) / f
    ends = dwell + (np.arange(3) + 1.0) / f
    np.testing.assert_allclose(profile_values(table, crests), 2 * a, rtol=1e-12)
    np.testing.assert_allclose(profile_values(table, ends), 0.0, atol=1e-15)
    assert profile_values(table, np.array([scene.duration]))[0] == pytest.approx(0.0, abs=1e-15)
    t = np.arange(dwell, dwell + 3 / f, 1e-4)
    speed = np.gradient(profile_values(table, t), t)
    assert speed.max() == pytest.approx(2 * math.pi * f * a, rel=1e-6)


def test_duration_force_and_conditions():
    scene = twin.load_scene("ds2").with_procedure(KNOBS_SET)
    assert scene.duration == pytest.approx(0.4 + 3 / 2.0 + SETTLE_TIME) == procedure_duration(KNOBS_SET)
    force = profile_values(scene.force_table(), np.array([0.0, FORCE_RISE_TIME, scene.duration]))
    assert force.tolist() == [0.0, -1500.0, -1500.0]
    assert scene.condition("preload") == 300.0 and scene.condition("zero_procedure") == "preloaded"
    # the scene keeps what the procedure does not set: its outputs, its backlash, the cylinder
    ds2 = twin.load_scene("ds2")
    assert scene.outputs == ds2.outputs and scene.condition("backlash") == ds2.condition("backlash")
    # no force: no force demand at all (a detached cylinder may then run it)
    quiet = ds2.with_procedure({"external_force": 0.0}).with_conditions({"cylinder": "detached"})
    assert not quiet.has_force_demand
    assert ds2.with_procedure({}) is ds2


@pytest.mark.parametrize("knobs, words", [
    ({"cycle": 3}, ["cycle: unknown knob", "cycles"]),
    ({"amplitude": 0.2}, ["amplitude", "outside the bench's range", "Table 9.3"]),
    ({"preload": -1.0}, ["preload", "outside"]),
    ({"cycles": 2.5}, ["cycles: must be a whole number"]),
    ({"zero_procedure": "edge"}, ["zero_procedure", "thesis, preloaded"]),
    ({"amplitude": 10e-3, "frequency": 2.0}, ["above the bench's 70 mm/s"]),
    ({"amplitude": 0.5e-3, "frequency": 1.0}, ["below 5 mm/s", "MOTION_SPEED_THRESHOLD"]),
    ({"dwell": float("nan")}, ["dwell: must be a finite number"]),
])
def test_bad_knobs_name_the_knob_and_what_is_allowed(knobs, words):
    problems = procedure_problems(knobs)
    assert len(problems) == 1 and all(w in problems[0] for w in words), problems
    with pytest.raises(SceneError, match="procedure"):
        twin.load_scene("ds2").with_procedure(knobs)


def test_every_knob_default_is_a_valid_procedure():
    assert procedure_problems({name: knob.default for name, knob in KNOBS.items()}) == []
    fastest = {"amplitude": 5e-3, "frequency": NOMINAL_SPEED / (2 * math.pi * 5e-3)}
    assert procedure_problems(fastest) == []


MOTION = {"amplitude": 2e-3, "frequency": 2.0, "cycles": 2, "dwell": 0.2}


def _hysteresis(backlash: float) -> float:
    scene = twin.load_scene("ds2").with_procedure(MOTION).with_conditions(
        {"backlash": backlash, "cylinder": "detached"})
    return float(twin.simulate(scene, save="features", outputs=["backlash_hysteresis_true"]).features[
        "backlash_hysteresis_true"])


def test_a_free_nut_under_a_procedure_shows_its_backlash():
    """The physics of tests/engine/test_backlash_features.py under a procedure's motion: no preload, no force, the
    screw drags the nut on its trailing flank, so H(b) - H(0) = b less the samples that cross the gap after each
    reversal. From rest at the reversal the sled accelerates at a = (2 pi f)^2 A, so it crosses b in
    t_c = sqrt(2 b / a); each crossing sample is off its flank by at most b, so each direction's mean is off by at
    most b t_c / (half a period), and H(b) - H(0) lies between b (1 - 2 share) and b (+2 % for the chain's
    friction deflection's change)."""
    b = 40 * UM
    a = (2 * math.pi * MOTION["frequency"]) ** 2 * MOTION["amplitude"]
    share = math.sqrt(2 * b / a) * 2 * MOTION["frequency"]
    width = _hysteresis(b) - _hysteresis(0.0)
    assert b * (1 - 2 * share) <= width <= 1.02 * b, (width, share)
