"""A data set's test procedure (``procedure``: campaigns/runner/spec.py, twin/scenes/procedure.py): it reaches the run,
the bench builds its scene from it, replay repeats it, a spec without it keeps its hash, and a bad knob is one error."""

from __future__ import annotations

import json

import pytest
from campaign_helpers import SYNTHETIC_SPEC, load, write_spec

import campaigns
import twin
from campaigns.bench.adapter import run_scene
from campaigns.bench.replay import replay_run
from campaigns.runner.execution import build_request
from campaigns.runner.sampling import sample
from campaigns.runner.spec import SpecError
from campaigns.runner.synthetic import procedure_effect, synthetic_run

KNOBS = '{ preload = 200.0, external_force = 500.0, cycles = 2, frequency = 2.0, amplitude = 2e-3 }'
PROCEDURE = f"""
[[datasets]]
name = "ds4__procedure"
scene = "ds4"
conditions = {{ backlash = 1e-6, preload = 0.0 }}
procedure = {KNOBS}
"""


def test_the_procedure_reaches_the_run_and_the_bench_builds_its_scene(tmp_path):
    spec = load(write_spec(tmp_path, PROCEDURE, append=True))
    request = build_request(spec, sample(spec), 4, 0)
    assert request.procedure["cycles"] == 2 and build_request(spec, sample(spec), 0, 0).procedure == {}
    scene = run_scene(request)
    # the procedure's profiles and duration, then the data set's conditions over the procedure's preload
    assert scene.duration == pytest.approx(0.5 + 2 / 2.0 + 0.5) and scene.position_demand[1]["amplitude"] == 2e-3
    assert scene.condition("preload") == 0.0 and scene.condition("backlash") == 1e-6
    assert scene.outputs == twin.load_scene("ds4").outputs


def test_a_spec_without_a_procedure_keeps_its_hash_and_a_procedure_changes_it(tmp_path):
    plain = load(SYNTHETIC_SPEC)
    assert "procedure" not in plain.to_json()
    with_procedure = load(write_spec(tmp_path, PROCEDURE, append=True))
    assert '"procedure":' in with_procedure.to_json() and with_procedure.spec_hash() != plain.spec_hash()


def test_a_procedure_run_replays_bit_identically(tmp_path):
    spec = load(write_spec(tmp_path, PROCEDURE.replace("ds4__procedure", "proc"), append=True), runs=3)
    results = campaigns.run_campaign(spec, tmp_path / "out", workers=1, progress=False, run_function=synthetic_run)
    replayed = replay_run(results, "proc", 2, run_function=synthetic_run)
    assert replayed.attrs["identical_backlash_feature"] == "yes"
    # the synthetic model saw the procedure: its preload hides the backlash, its force loads the chain (the data
    # set's preload condition, 0, is applied after the procedure's)
    sensitivity, _ = procedure_effect({"preload": 200.0})
    stiffness = json.loads(replayed.attrs["parameters"])["synthetic.stiffness"]
    assert float(replayed["backlash_feature_true"]) == pytest.approx(sensitivity * 1e-6 + 500.0 / stiffness, rel=1e-12)


@pytest.mark.parametrize("knobs, problem", [
    ("{ cycle = 2 }", "datasets[4].procedure: cycle: unknown knob; did you mean 'cycles'?"),
    ("{ amplitude = 0.5 }", "datasets[4].procedure: amplitude: 0.5 m is outside the bench's range"),
    ("{ amplitude = 10e-3, frequency = 2.0 }", "above the bench's 70 mm/s"),
])
def test_a_bad_knob_is_one_error_naming_the_data_set_and_the_knob(tmp_path, knobs, problem):
    with pytest.raises(SpecError) as caught:
        load(write_spec(tmp_path, PROCEDURE.replace(KNOBS, knobs), append=True))
    assert len(caught.value.problems) == 1 and problem in caught.value.problems[0], caught.value.problems
