"""Loop margins per run: stored for a small thesis campaign, analysed against design limits, limits validated."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import campaigns
from campaigns.analysis.margins import control_robustness
from campaigns.analysis.settings import AnalysisSettings
from campaigns.bench.adapter import MARGIN_NOTE, MARGIN_VARIABLES, margin_variables, run_margins
from campaigns.runner.execution import build_request
from campaigns.runner.sampling import sample
from campaigns.runner.spec import SpecError

SPECS = Path(campaigns.__file__).parent / "specs"


@pytest.fixture(scope="module")
def small_thesis():
    """The thesis study (7 data sets, every Table 9.5 tolerance) with 3 runs per data set."""
    spec = campaigns.load_spec(SPECS / "thesis_backlash.toml").model_copy(update={"runs_per_dataset": 3})
    samples = sample(spec)
    return spec, samples, margin_variables(spec, lambda d, i: build_request(spec, samples, d, i))


def test_small_thesis_campaign_margins_are_finite_and_vary(small_thesis):
    spec, _, variables = small_thesis
    assert set(variables) == {*MARGIN_VARIABLES, MARGIN_NOTE}
    for name, (dims, values, attrs) in variables.items():
        if name == MARGIN_NOTE:
            assert (values == "").all(), values  # every loop computed for every run (the cylinder is attached)
            continue
        assert dims == ("dataset", "run") and values.shape == (7, 3)
        assert attrs["role"] == "margin" and attrs["units"] and attrs["long_name"]
        if name == "current_loop_gain_margin":
            assert np.isinf(values).all()  # analog second-order loop: the phase never reaches -180 deg
            continue
        assert np.isfinite(values).all(), name
    for loop in ("current", "speed", "position", "force"):
        for metric in ("phase_margin", "peak_sensitivity"):
            values = variables[f"{loop}_loop_{metric}"][1]
            assert np.ptp(values) > 0, f"{loop} {metric} does not vary across the sampled runs"
    # the sampled motor tolerances (k_t, J, R: +/-10 %) move the speed loop more than the analog current loop's
    # pole-zero cancellation (R only) moves the current loop
    assert np.ptp(variables["speed_loop_crossover_frequency"][1]) / 57.7 > \
        np.ptp(variables["current_loop_crossover_frequency"][1]) / 981.3


def test_margins_of_a_run_are_nan_with_a_reason(small_thesis):
    spec, samples, _ = small_thesis
    request = build_request(spec, samples, 0, 0)
    broken = request.__class__(**{**request.__dict__, "parameter_values": {**request.parameter_values,
                                                                            "motor.inductance": -1.0}})
    values, note = run_margins(broken)
    assert all(math.isnan(v) for v in values.values())
    assert "motor.inductance" in note
    detached = request.__class__(**{**request.__dict__, "conditions": {**request.conditions, "cylinder": "detached"}})
    values, note = run_margins(detached)
    assert math.isnan(values["force_loop_phase_margin"]) and "cylinder detached" in note
    assert math.isfinite(values["speed_loop_phase_margin"])


def _synthetic_results(n: int, below: int, limits: dict | None = None, seed: int = 1) -> xr.Dataset:
    """One data set of ``n`` runs: the speed loop's phase margin rises with the feature; ``below`` runs under 30 deg."""
    rng = np.random.default_rng(seed)
    feature = rng.normal(0.0, 1.0, n)
    phase = 60.0 + 5.0 * feature
    order = np.argsort(phase)
    phase[order[:below]] = np.linspace(20.0, 29.0, below)
    gain = np.full(n, 20.0)
    spec = {"spec": {"control_limits": limits} if limits else {}}
    attrs = {"role": "margin", "loop": "speed"}
    return xr.Dataset(
        {
            "backlash_feature": (("dataset", "run"), feature[None], {"role": "feature", "units": "m"}),
            "speed_loop_phase_margin": (("dataset", "run"), phase[None], {**attrs, "metric": "phase_margin",
                                                                           "units": "degree"}),
            "speed_loop_gain_margin": (("dataset", "run"), gain[None], {**attrs, "metric": "gain_margin",
                                                                         "units": "dB"}),
            "status": (("dataset", "run"), np.full((1, n), "ok", dtype=object)),
        },
        coords={"dataset": ["ds"], "run": np.arange(n)},
        attrs={"spec_json": json.dumps(spec)},
    )


def _robustness(results, **options):
    return control_robustness(results, AnalysisSettings(n_boot=200, **options))


@pytest.mark.parametrize(("n", "below", "verdict"), [
    (400, 0, "met"),                 # exact upper bound 1 - 0.025**(1/400) = 0.92 % <= 1 %
    (300, 0, "undetermined"),        # upper bound 1.22 % > 1 % with no run below: more runs are needed
    (400, 12, "not met"),            # 3 %: exact lower bound 1.56 % >= 1 %
    (10, 0, "insufficient data"),    # fewer than min_ok_runs (20)
])
def test_limit_verdicts_are_known_answers(n, below, verdict):
    a = _robustness(_synthetic_results(n, below))
    check = a.sel(limit_check="speed_loop_phase_margin")
    assert str(check["margin_limit_verdict"].values) == verdict
    statement = str(check["margin_limit_statement"].values)
    assert statement.startswith(verdict + ":") and "speed loop PM ≥ 30°" in statement
    if verdict != "insufficient data":
        assert f"{below} of {n} runs" in statement
        assert int(check["margin_limit_counts"].sel(count="beyond")) == below


def test_worst_case_flags_and_correlation():
    results = _synthetic_results(400, 12)
    a = _robustness(results)
    phase = results["speed_loop_phase_margin"].values[0]
    worst = a["speed_loop_phase_margin_worst"].sel(dataset="ds")
    assert float(worst) == phase.min() == 20.0 and worst.attrs["units"] == "degree"  # one unit per variable (CF)
    assert int(a["margin_worst_run"].sel(dataset="ds", margin="speed_loop_phase_margin")) == int(np.argmin(phase))
    flagged = a["margin_runs_beyond_limits"].values[0] > 0
    np.testing.assert_array_equal(flagged, phase < 30.0)
    assert all("speed PM" in t for t in a["margin_limits_violated"].values[0][flagged])
    rho = a["margin_spearman"].sel(dataset="ds", margin="speed_loop_phase_margin", feature="backlash_feature")
    lower, upper = a["margin_spearman_ci"].sel(dataset="ds", margin="speed_loop_phase_margin",
                                               feature="backlash_feature").values
    assert float(rho) > 0.9 and lower <= float(rho) <= upper  # the margin was built to rise with the feature
    assert int(a["margin_spearman_n"].sel(dataset="ds", margin="speed_loop_phase_margin",
                                          feature="backlash_feature")) == 400
    # a constant margin has no rank correlation (NaN), not a spurious one
    assert np.isnan(a["margin_spearman"].sel(dataset="ds", margin="speed_loop_gain_margin").values).all()
    q = a["speed_loop_phase_margin_quantile"].sel(dataset="ds")
    assert float(q.sel(margin_probability=0.0)) == 20.0 and float(q.sel(margin_probability=1.0)) == phase.max()
    assert a["speed_loop_gain_margin_quantile"].attrs["units"] == "1"  # amplitude ratios, whatever the file held


def test_gain_margins_stored_as_ratios_keep_the_limits_meaning():
    """Gain margins are stored as amplitude ratios (units "1", issue 31); the limit stays in dB, so 3.5 dB (ratio
    1.5) is beyond the 6 dB limit and 20 dB (ratio 10) is not, exactly as when the file held dB."""
    in_db = _synthetic_results(400, 0)
    gain_db = np.where(np.arange(400) < 3, 3.5, 20.0)
    in_db["speed_loop_gain_margin"] = in_db["speed_loop_gain_margin"].copy(data=gain_db[None])
    as_ratio = in_db.copy()
    as_ratio["speed_loop_gain_margin"] = in_db["speed_loop_gain_margin"].copy(data=10 ** (gain_db[None] / 20))
    as_ratio["speed_loop_gain_margin"].attrs["units"] = "1"
    for results in (in_db, as_ratio):
        a = _robustness(results)
        statement = str(a["margin_limit_statement"].sel(limit_check="speed_loop_gain_margin").values)
        assert statement.startswith("undetermined: speed loop GM ≥ 6 dB: 3 of 400 runs beyond the limit"), statement
        assert "worst 3.5 dB (ds run 0)" in statement
        assert "speed GM 3.5 dB" in str(a["margin_limits_violated"].values[0, 0])
        assert float(a["speed_loop_gain_margin_worst"].sel(dataset="ds")) == pytest.approx(10 ** (3.5 / 20))


def test_an_infinite_gain_margin_says_why():
    """A loop whose phase never reaches -180 deg (the analog current loop) has GM = inf: the statement says "no
    phase crossover" rather than a bare "inf", and no run is beyond the GM limit."""
    results = _synthetic_results(400, 0)
    results["speed_loop_gain_margin"] = results["speed_loop_gain_margin"].copy(data=np.full((1, 400), np.inf))
    statement = str(_robustness(results)["margin_limit_statement"].sel(limit_check="speed_loop_gain_margin").values)
    assert statement.startswith("met: speed loop GM ≥ 6 dB: 0 of 400 runs beyond the limit")
    assert statement.endswith("worst ∞ dB, no phase crossover (ds run 0)")


def test_spec_limits_override_the_defaults():
    results = _synthetic_results(400, 0, limits={"phase_margin_min": 65.0})
    a = _robustness(results)
    assert str(a["margin_limit_verdict"].sel(limit_check="speed_loop_phase_margin").values) == "not met"
    assert "PM ≥ 65°" in str(a["margin_limit_statement"].sel(limit_check="speed_loop_phase_margin").values)


def test_control_limits_errors_name_the_field(tmp_path):
    path = tmp_path / "limits.toml"
    path.write_text(f'extends = "{SPECS / "demo.toml"}"\n[control_limits]\nphase_margin_min = -3\n'
                    'peak_sensitivity_max = 0.5\nmax_fraction_beyond = 1.5\nphase_margin = 30\n')
    with pytest.raises(SpecError) as info:
        campaigns.load_spec(path)
    text = str(info.value)
    for field in ("control_limits.phase_margin_min", "control_limits.peak_sensitivity_max",
                  "control_limits.max_fraction_beyond", "control_limits.phase_margin"):
        assert field in text, text


def test_default_limits_keep_the_spec_hash(tmp_path):
    """Specs written before [control_limits] existed keep their hash (and results directories); a set table counts."""
    base = campaigns.load_spec(SPECS / "demo.toml")
    assert "control_limits" not in base.canonical()["spec"]
    path = tmp_path / "limits.toml"
    path.write_text(f'extends = "{SPECS / "demo.toml"}"\n[control_limits]\ngain_margin_min = 8.0\n')
    changed = campaigns.load_spec(path)
    assert changed.control_limits.gain_margin_min == 8.0 and changed.control_limits.phase_margin_min == 30.0
    assert changed.spec_hash() != base.spec_hash()
