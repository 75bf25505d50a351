"""Where the load cell's electrical noise enters: the scene condition ``noise_path`` (docs/model.md).

``feedback`` (the default): the force loop acts on the same noisy conversion the record keeps. ``recorded``: the
record keeps it, the force loop reads the conversion without the noise sample. The plant sees the load cell only
through the force loop (the position loop reads the linear encoder, the drive the resolver), so under ``recorded``
every true signal is the noise-free run's, to the last bit, while the recorded force still carries the noise.
"""

import numpy as np
import pytest

import twin
from twin.errors import SceneError
from twin.scenes import CONDITIONS, NOISE_PATHS

DURATION = 1.0  # s: the first hold and half a second of the sinusoid, with the cylinder's force loop running
SIGNALS = ("nut1_position", "screw_equivalent_position", "external_force", "linear_encoder_position")


def _run(params, noise_path, seed=3):
    scene = twin.load_scene("ds2").with_conditions({"noise_path": noise_path})
    return twin.simulate(scene, params, duration=DURATION, rng=seed,
                         outputs=(*SIGNALS, "external_force_measured", "backlash_feature", "backlash_feature_true"))


def test_noise_path_is_a_choice_condition_with_feedback_as_default():
    assert CONDITIONS["noise_path"].choices == tuple(NOISE_PATHS) == ("feedback", "recorded")
    assert CONDITIONS["noise_path"].default == "feedback"
    assert twin.load_scene("ds2").condition("noise_path") == "feedback"  # stated by the nominal scene, inherited


def test_a_bad_noise_path_is_one_clear_error_naming_the_field_and_the_choices():
    with pytest.raises(SceneError) as err:
        twin.load_scene("ds2").with_conditions({"noise_path": "controller"})
    assert err.value.problems == ["conditions.noise_path: 'controller' is not one of feedback, recorded"]


def test_recorded_noise_leaves_the_plant_as_without_noise_and_the_record_noisy(bench):
    quiet = bench.with_values({"sensors.electrical_noise_half_width": 0.0})
    recorded, silent = _run(bench, "recorded"), _run(quiet, "recorded")
    for name in SIGNALS:
        np.testing.assert_array_equal(recorded[name].values, silent[name].values, err_msg=name)
    assert float(recorded.backlash_feature_true) == float(silent.backlash_feature_true)
    # the record carries the noise: +/-2.5 % of 20 kN, uniform, ~289 N rms against a force that stays below ~1 kN
    assert np.std(recorded.external_force_measured.values - silent.external_force_measured.values) > 100.0


def test_feedback_noise_moves_the_nut_and_without_noise_both_paths_agree(bench):
    feedback, recorded = _run(bench, "feedback"), _run(bench, "recorded")
    assert not np.array_equal(feedback.nut1_position.values, recorded.nut1_position.values)
    quiet = bench.with_values({"sensors.electrical_noise_half_width": 0.0})
    for name in SIGNALS:
        np.testing.assert_array_equal(_run(quiet, "feedback")[name].values, _run(quiet, "recorded")[name].values,
                                      err_msg=name)
