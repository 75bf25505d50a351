"""Property and fuzz tests (Hypothesis): broken specs are rejected with every error and leave nothing
behind; valid specs validate the same way twice; quantizer and encoder outputs stay on their grids; a
simulated run is finite or carries a failure status.

Example counts are small and the generation is derandomized, so CI on 2 cores is fast and deterministic.
"""

from __future__ import annotations

import copy
import json
import math
import tomllib

import numpy as np
import pytest
from campaign_helpers import SYNTHETIC_SPEC
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import campaigns
from campaigns.runner.spec import MAX_RUNS_PER_DATASET, SpecError, validate_spec
from campaigns.runner.synthetic import SYNTHETIC_CATALOG, SyntheticModel

CI = settings(max_examples=25, deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.function_scoped_fixture])
BASE = tomllib.loads(SYNTHETIC_SPEC.read_text())


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return "nan" if isinstance(value, float) and math.isnan(value) else repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {_toml_value(v)}" for k, v in value.items()) + "}"


def to_toml(data: dict) -> str:
    """The spec as TOML (every value inline: enough for specs)."""
    return "".join(f"{json.dumps(k)} = {_toml_value(v)}\n" for k, v in data.items())


# Each mutation breaks one thing and names the problems it must produce (prefixes, in any order).
# They touch disjoint fields, so any combination must report the union, and nothing else.
def _root_seed(d):
    d["root_seed"] = -3
    return ["root_seed:"]


def _runs_too_many(d):
    d["runs_per_dataset"] = MAX_RUNS_PER_DATASET + 1
    return ["runs_per_dataset:"]


def _unknown_feature(d):
    d["features"] = d["features"] + ["no_such_feature"]
    return ["features: unknown feature(s) no_such_feature"]


def _nan_condition(d):
    d["datasets"][0]["conditions"]["backlash"] = math.nan
    return ["datasets[0].conditions.backlash:"]


def _duplicate_dataset(d):
    d["datasets"].append(copy.deepcopy(d["datasets"][3]))
    return ["datasets: duplicate name(s) ds5"]


def _unknown_sweep_entry(d):
    d["observability"]["sweep"] = d["observability"]["sweep"] + ["nope"]
    return ["observability.sweep: unknown data set(s) nope"]


def _bad_sigma_and_unknown_target(d):
    d["uncertainties"][0].update(target="synthetic.no_such_parameter", sigma=-0.1)
    return ["uncertainties[0].sigma:", "uncertainties[0]: unknown parameter 'synthetic.no_such_parameter'"]


def _low_above_high(d):
    d["uncertainties"][1]["low"] = 2.0
    return ["uncertainties[1]: low (2) > high (1)"]


def _negative_timeout(d):
    d["execution"]["timeout"] = -1.0
    return ["execution.timeout:"]


def _unknown_key(d):
    d["bogus_key"] = 1
    return ["bogus_key:"]


def _target_twice(d):
    d["uncertainties"].append(copy.deepcopy(d["uncertainties"][2]))
    return ["uncertainties: target(s) listed twice: synthetic.stiffness"]


def _set_and_sampled(d):
    d["datasets"][1]["conditions"]["room_temperature"] = 300.0
    return ["datasets[1].conditions: room_temperature also sampled in uncertainties"]


def _zero_decimation(d):
    d["traces"]["decimation"] = 0
    return ["traces.decimation:"]


def _unknown_scene(d):
    d["base"]["scene"] = "no_such_scene"
    return ["base.scene: unknown scene 'no_such_scene'"]


MUTATIONS = [_root_seed, _runs_too_many, _unknown_feature, _nan_condition, _duplicate_dataset, _unknown_sweep_entry,
             _bad_sigma_and_unknown_target, _low_above_high, _negative_timeout, _unknown_key, _target_twice,
             _set_and_sampled, _zero_decimation, _unknown_scene]


@CI
@given(st.lists(st.sampled_from(MUTATIONS), min_size=1, max_size=len(MUTATIONS), unique=True))
def test_a_broken_spec_is_rejected_with_all_its_errors_and_leaves_nothing(tmp_path_factory, mutations):
    data = copy.deepcopy(BASE)
    expected = [prefix for mutate in mutations for prefix in mutate(data)]
    tmp = tmp_path_factory.mktemp("broken")
    path = tmp / "spec.toml"
    path.write_text(to_toml(data))
    log = tmp / "log"
    log.mkdir()
    with pytest.raises(SpecError) as info:
        campaigns.run_campaign(path, tmp / "out", catalog=SYNTHETIC_CATALOG, progress=False,
                               run_function=SyntheticModel(log_dir=str(log)))
    problems = info.value.problems
    for prefix in expected:
        assert sum(p.startswith(prefix) for p in problems) == 1, f"{prefix!r} not reported once in {problems}"
    assert len(problems) == len(expected), problems  # nothing spurious either
    assert not (tmp / "out").exists() and not list(log.iterdir())


valid_specs = st.fixed_dictionaries({
    "root_seed": st.integers(0, 2**63),
    "runs_per_dataset": st.integers(1, MAX_RUNS_PER_DATASET),
    "timeout": st.floats(1e-3, 3600.0, allow_nan=False),  # campaigns.runner.spec.BOUNDS (issue 31)
    "datasets": st.lists(st.sampled_from(range(4)), min_size=1, max_size=4, unique=True),
    "uncertainties": st.lists(st.sampled_from(range(6)), max_size=6, unique=True),
})


@CI
@given(valid_specs)
def test_a_valid_spec_validates_the_same_way_twice(choice):
    data = copy.deepcopy(BASE)
    data.update(root_seed=choice["root_seed"], runs_per_dataset=choice["runs_per_dataset"])
    data["execution"]["timeout"] = choice["timeout"]
    data["datasets"] = [BASE["datasets"][k] for k in choice["datasets"]]
    data["uncertainties"] = [BASE["uncertainties"][k] for k in choice["uncertainties"]]
    names = {d["name"] for d in data["datasets"]}
    data["observability"]["sweep"] = [n for n in BASE["observability"]["sweep"] if n in names]
    if len(data["observability"]["sweep"]) < 2 or "ds4" not in data["observability"]["sweep"]:
        data["observability"]["sweep"] = []
    first, second = (validate_spec(copy.deepcopy(data), SYNTHETIC_CATALOG),
                     validate_spec(copy.deepcopy(data), SYNTHETIC_CATALOG))
    assert first.to_json() == second.to_json() and first.spec_hash() == second.spec_hash()
    assert [d.as_dict() for d in first.distributions()] == [d.as_dict() for d in second.distributions()]


# --- sensors: outputs on their grids -------------------------------------------------------------

finite = st.floats(-1e3, 1e3, allow_nan=False)


@CI
@given(finite, st.floats(1e-9, 1.0))
def test_quantizer_output_is_on_its_grid_within_half_a_step(value, lsb):
    from sensors.acquisition import quantize

    q = quantize(value, lsb)
    assert q == lsb * round(q / lsb)  # a reconstruction level: lsb times a whole number
    assert abs(q - value) <= 0.5 * lsb * (1 + 1e-9) + 1e-12 * abs(value)


@CI
@given(finite, st.sampled_from([1.0, 5.0, 10.0]), st.integers(2, 24))
def test_converter_output_is_a_code_of_its_range(value, full_scale, bits):
    from sensors.acquisition import convert

    lsb = full_scale / 2.0 ** (bits - 1)
    v = convert(value, full_scale, float(bits))
    assert -full_scale <= v <= full_scale - lsb
    assert v == lsb * round(v / lsb)


@CI
@given(st.floats(-0.5, 0.5, allow_nan=False), st.sampled_from([1, 2]), st.floats(-0.3, 0.3), st.floats(-0.3, 0.3))
def test_encoder_reading_is_a_whole_count(x, fidelity, phase_error, asymmetry):
    from sensors.encoder import encoder_count, encoder_parameters, encoder_position

    resolution = 1e-6
    p = encoder_parameters(resolution=resolution, phase_error=phase_error, asymmetry_a=asymmetry,
                           asymmetry_b=-asymmetry, timer_period=2.5e-8, fidelity=fidelity)
    count = encoder_count(x, p)
    assert count == math.floor(count)
    assert encoder_position(x, p) == count * resolution
    if fidelity == 1:
        assert count * resolution <= x + 1e-15 and x - count * resolution < resolution * (1 + 1e-9)


# --- the twin: finite, or a failure status -------------------------------------------------------

@settings(max_examples=6, deadline=None, derandomize=True, database=None)
@given(st.floats(0.0, 200e-6), st.floats(0.0, 3000.0), st.floats(263.15, 323.15), st.floats(0.5, 2.0))
def test_a_simulated_run_is_finite_or_says_why_not(backlash, preload, room_temperature, stiffness_scale):
    twin = pytest.importorskip("twin")
    scene = twin.load_scene("ds2").with_conditions({"backlash": backlash, "preload": preload,
                                                    "room_temperature": room_temperature})
    params = twin.load_parameters("bench")
    name = "ball_screw.rear_bearing_axial_stiffness"  # Table B.9; scaled x0.5..x2
    params = params.with_values({name: params[name].value * stiffness_scale})
    ds = twin.simulate(scene, params, duration=0.2, throw=False)
    if ds.attrs["status"] == "ok":
        signals = [v for v in ds.data_vars if "time" in ds[v].dims]
        assert all(np.isfinite(ds[v].values).all() for v in signals)
        assert np.isfinite(float(ds["backlash_feature_true"])) and np.isfinite(float(ds["backlash_feature"]))
    else:
        assert ds.attrs["failure_reason"], "a failed run must say why"
        assert 0.0 <= ds.attrs["t_reached"] < 0.2
