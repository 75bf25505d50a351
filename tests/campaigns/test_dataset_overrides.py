"""A data set's fixed parameters and common random numbers (``parameters``, ``seeds_from``: campaigns/runner/spec.py):
what they change in the samples, the requests and the replay, and one clear error for each bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest
from campaign_helpers import SYNTHETIC_SPEC, load, write_spec

import campaigns
from campaigns.bench.replay import replay_run
from campaigns.runner.execution import build_request
from campaigns.runner.sampling import sample
from campaigns.runner.spec import SpecError
from campaigns.runner.synthetic import synthetic_run

# the synthetic spec's data sets are ds2, ds4, ds6, ds5 (indices 0-3); its table samples gain, offset, stiffness,
# inert, then two scene conditions
OFFSET, INERT = 1, 3
FIXED = """
[[datasets]]
name = "ds4__offset_fixed"
scene = "ds4"
conditions = { backlash = 0.0, preload = 0.0, external_force = 0.0 }
parameters = { "synthetic.offset" = 2e-6 }
seeds_from = "ds4"
"""


def _targets(spec):
    return [d.target for d in spec.distributions()]


def test_a_fixed_parameter_replaces_its_draw_and_leaves_every_other_draw_as_it_was(tmp_path):
    plain, spec = load(SYNTHETIC_SPEC), load(write_spec(tmp_path, FIXED, append=True))
    samples = sample(spec)
    assert spec.fixed_columns(4, _targets(spec)) == {OFFSET: 2e-6}
    assert (samples[4, :, OFFSET] == 2e-6).all()
    # seeds_from ds4: every other column draws what ds4 draws, run by run (the draws happen before the fixing)
    others = [k for k in range(samples.shape[-1]) if k != OFFSET]
    np.testing.assert_array_equal(samples[4][:, others], samples[1][:, others])
    # the data sets that existed keep their values: adding a data set changes no other data set's runs
    np.testing.assert_array_equal(samples[:4], sample(plain))
    request = build_request(spec, samples, 4, 7)
    assert request.parameter_values["synthetic.offset"] == 2e-6 and request.seed_index == 1


def test_common_random_numbers_give_the_named_data_set_s_noise_run_by_run(tmp_path):
    spec = load(write_spec(tmp_path, FIXED, append=True))
    samples = sample(spec)
    own, shared = build_request(spec, samples, 1, 3), build_request(spec, samples, 4, 3)
    np.testing.assert_array_equal(shared.noise_rng().normal(size=4), own.noise_rng().normal(size=4))
    assert build_request(spec, samples, 0, 3).seed_index == 0  # a data set without seeds_from keeps its own


def test_an_unsampled_fixed_parameter_reaches_the_run(tmp_path):
    gain_row = SYNTHETIC_SPEC.read_text().split("[[uncertainties]]")[1]
    assert '"synthetic.gain"' in gain_row
    path = tmp_path / "unsampled_gain.toml"
    path.write_text(SYNTHETIC_SPEC.read_text().replace("[[uncertainties]]" + gain_row, "")
                    + FIXED.replace('"synthetic.offset" = 2e-6', '"synthetic.gain" = 1.5'))
    spec = load(path)
    assert "synthetic.gain" not in _targets(spec)
    request = build_request(spec, sample(spec), 4, 0)
    assert request.parameter_values["synthetic.gain"] == 1.5


def test_specs_that_use_neither_keep_their_hash():
    spec = load(SYNTHETIC_SPEC)
    assert all("parameters" not in d and "seeds_from" not in d for d in spec.canonical()["spec"]["datasets"])


def test_a_campaign_with_fixed_parameters_replays_each_run_bit_for_bit(tmp_path):
    spec = load(write_spec(tmp_path, FIXED, append=True), runs=3)
    results = campaigns.run_campaign(spec, tmp_path / "out", workers=1, progress=False, run_function=synthetic_run)
    replayed = replay_run(results, "ds4__offset_fixed", 2, run_function=synthetic_run)
    assert replayed.attrs["identical_backlash_feature"] == "yes"
    assert json.loads(replayed.attrs["parameters"])["synthetic.offset"] == 2e-6


@pytest.mark.parametrize("text, problem", [
    ('parameters = { "synthetic.ofset" = 1e-6 }', "datasets[4].parameters.synthetic.ofset: unknown parameter "
                                                  "'synthetic.ofset'; did you mean 'synthetic.offset'"),
    ('parameters = { "scene.preload" = 10.0 }', "scene.preload is a scene condition: set it in the data set's "
                                                "conditions"),
    ('parameters = { "synthetic.offset" = "big" }', "must be a finite number in the parameter's SI unit, got 'big'"),
    ('parameters = { "synthetic.offset" = nan }', "must be a finite number in the parameter's SI unit, got nan"),
    ('seeds_from = "ds44"', "datasets[4].seeds_from: unknown data set 'ds44'; did you mean 'ds4'?"),
    ('seeds_from = "extra"', "datasets[4].seeds_from: names the data set itself"),
])
def test_bad_overrides_get_one_clear_error_before_any_run(tmp_path, text, problem):
    entry = f'\n[[datasets]]\nname = "extra"\nscene = "ds4"\n{text}\n'
    with pytest.raises(SpecError) as caught:
        load(write_spec(tmp_path, entry, append=True))
    assert problem in str(caught.value)
    assert len(caught.value.problems) == 1, caught.value.problems


def test_seeds_are_taken_from_a_data_set_with_its_own(tmp_path):
    chain = FIXED + '\n[[datasets]]\nname = "chained"\nscene = "ds4"\nseeds_from = "ds4__offset_fixed"\n'
    with pytest.raises(SpecError, match="'ds4__offset_fixed' itself uses the seeds of 'ds4'; name that data set"):
        load(write_spec(tmp_path, chain, append=True))


def test_a_bench_parameter_outside_its_range_is_refused_with_the_range(tmp_path):
    thesis = SYNTHETIC_SPEC.parents[3] / "campaigns" / "specs" / "thesis_backlash.toml"
    path = tmp_path / "bad.toml"
    path.write_text(f'extends = "{thesis}"\n[observability]\nsweep = []\n[[datasets]]\nname = "ds4"\nscene = "ds4"\n'
                    'conditions = { backlash = 0.0 }\nparameters = { "pneumatics.friction_static" = 5000.0 }\n')
    with pytest.raises(SpecError, match=r"datasets\[0\]\.parameters: pneumatics\.friction_static: value 5000 N is "
                                        r"out of range; allowed: >= 0 and <= 1200"):
        campaigns.load_spec(path)
