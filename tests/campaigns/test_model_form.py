"""The model-form table (campaigns/analysis/model_form.py): known answers on synthetic results, and the spec end to
end."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import campaigns
import twin
from campaigns.analysis import model_form
from campaigns.analysis.observability import observability_sweep
from campaigns.analysis.settings import OBSERVABILITY_STREAM
from campaigns.bench.adapter import BenchCatalog
from campaigns.runner.spec import read_spec, validate_spec
from campaigns.statistics.intervals import mean_shift
from campaigns.statistics.paired_comparison import VERDICTS

SPEC = Path(__file__).parents[2] / "campaigns" / "specs" / "model_form.toml"
#: The sweep of the synthetic study [m]: ds4 is the reference, ds6 the one level below the 1 µm requirement.
LEVELS = {"ds4": 0.0, "ds6": 0.5e-6, "ds7": 5e-6, "ds2": 40e-6}
RUNS = 200


def _dataset(name, backlash, condition=None):
    conditions = {"backlash": backlash, "noise_path": "feedback", "cylinder": "attached"}
    if condition is not None:
        conditions.update(condition)
    return {"name": name, "scene": name.split("__")[0], "conditions": conditions}


def _results(variants: dict[str, tuple[dict, float, float]], runs: int = RUNS, seed: int = 1) -> xr.Dataset:
    """Results of a model-form study whose feature is the backlash plus an offset and Gaussian noise.

    ``variants``: label -> (changed condition, offset [m], noise sigma [m]); the baseline has offset 0 and
    sigma 0.01 µm, so it detects the 0.5 µm level (verdict met).
    """
    rng = np.random.default_rng(seed)
    rows = [(name, level, 0.0, 0.01e-6, None) for name, level in LEVELS.items()]
    for label, (condition, offset, sigma) in variants.items():
        rows += [(f"{name}__{label}", level, offset, sigma, condition) for name, level in LEVELS.items()]
    names = [r[0] for r in rows]
    feature = np.array([level + offset + sigma * rng.standard_normal(runs) for _, level, offset, sigma, _ in rows])
    spec = {"datasets": [_dataset(n, level, c) for n, level, _, _, c in rows],
            "observability": {"sweep": list(LEVELS), "condition": "backlash"}}
    return xr.Dataset(
        {"f": (("dataset", "run"), feature, {"role": "feature", "units": "m"}),
         "status": (("dataset", "run"), np.full(feature.shape, "ok", dtype=object)),
         "condition_backlash": ("dataset", np.array([r[1] for r in rows]), {"units": "m"})},
        coords={"dataset": np.array(names, dtype=object), "run": np.arange(runs)},
        attrs={"spec_json": json.dumps({"spec": spec}), "title": "synthetic model-form study"},
    )


def test_a_paired_variant_resolves_a_shift_independent_samples_cannot():
    # every data set has a 1 µm run-to-run spread shared with its variants run by run (common random numbers); the
    # variant adds 0.1 µm. Independent samples of 200 runs: standard error of the difference 0.1 µm, not resolved.
    # Paired: the differences are 0.1 µm exactly (to rounding), so the interval is 0.1 µm wide at most 1e-15 m.
    results = _results({"damping_x10": (None, 0.0, 0.0)})
    rng = np.random.default_rng(7)
    base = results["f"].values[: len(LEVELS)] + 1e-6 * rng.standard_normal((len(LEVELS), RUNS))
    results["f"].values[: len(LEVELS)] = base
    results["f"].values[len(LEVELS):] = base + 0.1e-6
    spec = json.loads(results.attrs["spec_json"])
    for entry in spec["spec"]["datasets"][len(LEVELS):]:
        entry["parameters"] = {"ball_screw.contact_damping_coefficient": 0.05}
    unpaired = model_form.model_form_dataset(results.assign_attrs(spec_json=json.dumps(spec)), _analysis(results))
    for entry in spec["spec"]["datasets"][len(LEVELS):]:
        entry["seeds_from"] = entry["name"].split("__")[0]
    paired = model_form.model_form_dataset(results.assign_attrs(spec_json=json.dumps(spec)), _analysis(results))
    assert str(unpaired["pairing"].item()) == "independent" and str(paired["pairing"].item()) == "paired"
    assert (paired["shift_status"].values == model_form.SHIFT_STATUS.index("resolved")).all()
    assert paired["mean_shift_ci"].values == pytest.approx(0.1e-6, abs=1e-15)
    assert (unpaired["shift_status"].values == model_form.SHIFT_STATUS.index("not_resolved")).sum() >= 3
    assert json.loads(str(paired["variant_parameters"].item())) == {"ball_screw.contact_damping_coefficient": 0.05}


def _analysis(results: xr.Dataset) -> xr.Dataset:
    """The attributes and the baseline verdict an analysis.nc carries (its own settings of the sweep)."""
    attrs = {"bootstrap": json.dumps({"n_boot": 200, "confidence": 0.95, "seed": 0}), "false_alarm_rate": 0.05,
             "detection_power": 0.95, "min_detection_runs": 59, "observability_condition": "backlash",
             "requirement": 1e-6, "requirement_source": "Table 9.3", "min_ok_runs": 20}
    settings = model_form._settings(xr.Dataset(attrs=attrs))
    found = observability_sweep(
        results, "f", list(LEVELS), false_alarm_rate=0.05, power=0.95, n_boot=200, confidence=0.95, min_runs=59,
        seed=np.random.SeedSequence(0, spawn_key=(OBSERVABILITY_STREAM, 0)),
        requirement=settings["requirement"], requirement_source=settings["requirement_source"])
    return xr.Dataset({"requirement_verdict": ("feature", [str(found["requirement_verdict"].item())])},
                      coords={"feature": ["f"]}, attrs=attrs)


def test_welch_interval_known_answer():
    # a = 1, 2, 3 against a constant 0: shift 2, variance of the mean 1/3 with 2 degrees of freedom,
    # t_0.975(2) = 4.302653: half-width 4.302653 * sqrt(1/3) = 2.484138
    shift, lower, upper = mean_shift([1.0, 2.0, 3.0], [0.0, 0.0, 0.0], paired=False)
    assert shift == pytest.approx(2.0)
    assert (lower, upper) == pytest.approx((2.0 - 2.484138, 2.0 + 2.484138), abs=1e-6)


def test_paired_interval_known_answer_is_that_of_the_differences():
    # differences 1, 2, 3 (and a pair with a NaN, left out): the same numbers as above, whatever the common part
    common = np.array([5.0, -7.0, 100.0, 1.0])
    shift, lower, upper = mean_shift(common + [1.0, 2.0, 3.0, np.nan], common, paired=True)
    assert (shift, lower, upper) == pytest.approx((2.0, 2.0 - 2.484138, 2.0 + 2.484138), abs=1e-6)
    with pytest.raises(ValueError, match="one value per run on both sides"):
        mean_shift([1.0, 2.0], [1.0, 2.0, 3.0], paired=True)


def test_welch_interval_matches_the_pooled_one_for_equal_samples_and_needs_two_runs():
    rng = np.random.default_rng(3)
    a, b = rng.normal(1.0, 1.0, 50), rng.normal(0.0, 1.0, 50)
    a = (a - a.mean()) / a.std(ddof=1) + 1.0  # both sample sd 1: Welch's dof is 98, the pooled one's
    b = (b - b.mean()) / b.std(ddof=1)
    from scipy.stats import t
    half = t.ppf(0.975, 98) * math.sqrt(2 / 50)
    assert mean_shift(a, b, paired=False) == pytest.approx((1.0, 1.0 - half, 1.0 + half))
    assert all(math.isnan(x) for x in mean_shift([1.0], [1.0, 2.0], paired=False))
    assert all(math.isnan(x) for x in mean_shift(a[:5], b, paired=False, min_runs=20))
    assert mean_shift([2.0, 2.0], [1.0, 1.0], paired=False) == (1.0, 1.0, 1.0)


def test_variants_read_the_changed_condition_from_the_spec():
    spec = {"datasets": [_dataset("ds4", 0.0), _dataset("ds4__noise_path_recorded", 0.0, {"noise_path": "recorded"})]}
    (variant,) = model_form.variants(spec)
    assert (variant.baseline, variant.assumption, variant.value, variant.baseline_value) == (
        "ds4", "noise_path", "recorded", "feedback")


def test_a_parameter_variant_is_named_by_its_label_and_paired_by_its_seeds():
    fixed = {"ball_screw.contact_damping_coefficient": 0.05}
    spec = {"datasets": [_dataset("ds4", 0.0),
                         {**_dataset("ds4__contact_damping_x10", 0.0), "parameters": fixed, "seeds_from": "ds4"},
                         {**_dataset("ds4__phases_fixed", 0.0), "parameters": {"sensors.phase": 0.0}}],
            "uncertainties": [{"target": "sensors.phase"}]}
    damping, phases = model_form.variants(spec)
    assert (damping.assumption, damping.value, damping.baseline_value, damping.paired) == (
        "contact_damping", "x10", "nominal", True)
    assert json.loads(damping.parameters) == fixed
    assert (phases.label, phases.baseline_value, phases.paired) == ("phases=fixed", "sampled", False)


@pytest.mark.parametrize("entry, problem", [
    (_dataset("ds9__x", 0.0, {"noise_path": "recorded"}), "no baseline data set 'ds9'"),
    (_dataset("ds4__two", 0.0, {"noise_path": "recorded", "cylinder": "detached"}), "differs in: cylinder, noise_path"),
    (_dataset("ds4__none", 0.0), "differs in: none"),
    ({**_dataset("ds4__both", 0.0, {"noise_path": "recorded"}), "parameters": {"a.b": 1.0}},
     "differs in: noise_path, a.b"),
    ({**_dataset("ds4__unlabelled", 0.0), "parameters": {"a.b": 1.0}}, "named <baseline>__<assumption>_<value>"),
])
def test_a_variant_must_change_exactly_one_stated_condition_or_its_parameters_alone(entry, problem):
    with pytest.raises(ValueError, match=problem):
        model_form.variants({"datasets": [_dataset("ds4", 0.0), entry]})


def test_the_table_states_resolved_shifts_and_the_verdict_an_assumption_changes():
    results = _results({"noise_path_recorded": ({"noise_path": "recorded"}, 0.0, 20e-6),
                        "cylinder_detached": ({"cylinder": "detached"}, 3e-6, 0.01e-6)})
    analysis = _analysis(results)
    table = model_form.model_form_dataset(results, analysis)
    assert list(table["variant"].values) == ["noise_path=recorded", "cylinder=detached"]
    assert list(table["assumption"].values) == ["noise_path", "cylinder"]
    assert str(table["baseline_verdict"].sel(feature="f").item()) == "met"
    # a 3 µm offset with 0.01 µm noise: resolved in every data set; the difference of two means of 200 runs has a
    # standard error of 0.001 µm, so the shift is 3 µm to within 0.005 µm (5 standard errors)
    detached = table.sel(variant="cylinder=detached", feature="f")
    assert (detached["shift_status"].values == model_form.SHIFT_STATUS.index("resolved")).all()
    assert detached["mean_shift"].values == pytest.approx(3e-6, abs=5e-9)
    lower, upper = detached["mean_shift_ci"].values.T
    assert upper - lower == pytest.approx(2 * 1.96 * 1e-9, rel=0.2)
    assert str(detached["variant_verdict"].item()) == "met"  # the offset moves the reference too: still detected
    # 20 µm noise, no offset: no shift resolved where the true shift is 0 (95 % each; the seed is fixed), and the
    # 0.5 µm level is no longer detected: the verdict changes
    recorded = table.sel(variant="noise_path=recorded", feature="f")
    assert str(recorded["variant_verdict"].item()) == "not met"
    assert int(recorded["verdict_change"]) == model_form.VERDICT_CHANGE.index("changed")
    assert set(table["variant_verdict"].values.ravel()) <= set(VERDICTS)
    assert table.attrs["headline"] == ("Of the assumptions varied (noise_path, cylinder), noise_path moves the "
                                       "requirement verdicts most, changing 1 of its 1 compared verdicts: "
                                       "noise_path=recorded, f: met → not met.")
    # the command line's lines: one per compared verdict, the change read from the same table
    lines = model_form.variant_lines(table)
    assert len(lines) == 2 and lines[0].startswith("noise_path=recorded, f: ") and lines[0].endswith(": changed")
    assert "(baseline met; detection probability at the requirement" in lines[0]
    assert lines[1].startswith("cylinder=detached, f: ") and lines[1].endswith(": unchanged")


def test_without_a_verdict_change_the_headline_names_the_largest_resolved_shift():
    results = _results({"noise_path_recorded": ({"noise_path": "recorded"}, -2e-6, 0.01e-6),
                        "cylinder_detached": ({"cylinder": "detached"}, 7e-6, 0.01e-6)})
    table = model_form.model_form_dataset(results, _analysis(results))
    assert (table["verdict_change"].values == model_form.VERDICT_CHANGE.index("unchanged")).all()
    headline = table.attrs["headline"]
    assert headline.startswith("No assumption varied (noise_path, cylinder) changes a requirement verdict "
                               "(2 compared); cylinder moves the features most: with cylinder = detached instead of "
                               "attached, the mean of f in ")
    assert "shifts by +7 µm" in headline or "shifts by +7.00" in headline


def test_a_shift_the_interval_does_not_resolve_is_never_named():
    results = _results({"noise_path_recorded": ({"noise_path": "recorded"}, -2e-6, 0.01e-6),
                        "cylinder_detached": ({"cylinder": "detached"}, 0.5e-6, 0.01e-6)})
    table = model_form.model_form_dataset(results, _analysis(results))
    # a far larger cylinder shift in ds2 whose interval holds zero: the headline still names the resolved 2 µm
    cell = {"variant": "cylinder=detached", "dataset": "ds2", "feature": "f"}
    table["mean_shift"].loc[cell] = 50e-6
    table["mean_shift_ci"].loc[cell] = [-1e-3, 1e-3]
    table["shift_status"].loc[cell] = model_form.SHIFT_STATUS.index("not_resolved")
    headline = model_form.headline(table)
    assert "noise_path moves the features most" in headline and "shifts by -2" in headline
    assert "50 µm" not in headline


def test_too_few_runs_give_insufficient_data_and_no_shift():
    results = _results({"cylinder_detached": ({"cylinder": "detached"}, 3e-6, 0.01e-6)}, runs=10)
    table = model_form.model_form_dataset(results, _analysis(results))
    assert (table["shift_status"].values == model_form.SHIFT_STATUS.index("insufficient_data")).all()
    assert np.isnan(table["mean_shift"].values).all()
    assert str(table["variant_verdict"].item()) == "insufficient data"
    assert table.attrs["headline"] == ("No assumption varied (cylinder) changes a requirement verdict (0 compared, "
                                       "1 not compared: insufficient data); no shift of a feature's mean is "
                                       "resolved by its interval.")


def test_the_table_is_written_as_cf_netcdf(tmp_path):
    results = _results({"cylinder_detached": ({"cylinder": "detached"}, 3e-6, 0.01e-6)}, runs=60)
    path = model_form.write_model_form(results, _analysis(results), tmp_path / model_form.FILE_NAME)
    with xr.open_dataset(path, engine="netcdf4") as stored:
        assert stored.attrs["Conventions"].startswith("CF-")
        assert stored["mean_shift"].attrs["units"] == "m"
        assert stored.attrs["headline"] == model_form.model_form_dataset(results, _analysis(results)).attrs["headline"]


#: Every variant of the study (label: baseline value), each on the seven data sets but the cylinder's (not on ds3).
STUDY_VARIANTS = {"noise_path=recorded": "feedback", "cylinder=detached": "attached", "contact_damping=half": "nominal",
                  "contact_damping=x10": "nominal", "seal_friction=2pct": "nominal", "seal_friction=10pct": "nominal",
                  "groove_friction=half": "nominal", "groove_friction=double": "nominal",
                  "friction_split=25-75": "nominal", "friction_split=75-25": "nominal",
                  "mounting_phases=fixed": "sampled"}


def test_the_spec_pairs_every_variant_with_a_baseline_of_the_thesis_study():
    spec = campaigns.load_spec(SPEC)
    found = model_form.variants(spec.model_dump(mode="json"))
    assert {v.label: v.baseline_value for v in found} == STUDY_VARIANTS
    assert all(v.paired for v in found)  # every variant takes its baseline's seeds: shifts of run-by-run differences
    assert {v.baseline for v in found if v.assumption == "cylinder"} == {"ds1", "ds2", "ds4", "ds5", "ds6", "ds7"}
    assert all(len([v for v in found if v.label == label]) == 7 for label in STUDY_VARIANTS if "cylinder" not in label)
    thesis = campaigns.load_spec(SPEC.with_name("thesis_backlash.toml"))
    # baselines first and in the thesis order, same seed and table: run i of ds1-ds7 is the thesis study's run i
    assert [d.name for d in spec.datasets[:7]] == [d.name for d in thesis.datasets]
    assert spec.root_seed == thesis.root_seed and spec.distributions() == thesis.distributions()


def test_the_friction_split_variants_keep_the_calibrated_drag_and_the_friction_ones_scale_it():
    """The split moves drag between sliding (g1, g4, g6) and rolling (k_gc) at the same Eq. 7.85 total: at the
    calibration point (1 kN, 100 rpm) each carries half, so a sliding share s scales sliding by 2 s and rolling by
    2 (1 - s); the friction variants scale all four alike."""
    nominal = twin.load_parameters("bench")
    sliding = ("ball_screw.sliding_friction_g1", "ball_screw.sliding_friction_g4", "ball_screw.sliding_friction_g6")
    rolling = "ball_screw.rolling_friction_load_coefficient"
    expected = {"25-75": (0.5, 1.5), "75-25": (1.5, 0.5), "half": (0.5, 0.5), "double": (2.0, 2.0)}
    for v in model_form.variants(campaigns.load_spec(SPEC).model_dump(mode="json")):
        if v.assumption not in ("friction_split", "groove_friction"):
            continue
        fixed, (s, r) = json.loads(v.parameters), expected[v.value]
        assert {k: fixed[k] / nominal[k].value for k in sliding} == pytest.approx(dict.fromkeys(sliding, s), rel=1e-9)
        assert fixed[rolling] / nominal[rolling].value == pytest.approx(r, rel=1e-9)


@pytest.mark.slow
def test_the_spec_runs_end_to_end_and_writes_the_table(tmp_path):
    # one baseline and a condition and two parameter variants of it, 3 runs each: the whole path on the bench model
    data = read_spec(SPEC)
    data["datasets"] = [d for d in data["datasets"] if d["name"] in (
        "ds4", "ds4__noise_path_recorded", "ds4__contact_damping_x10", "ds4__mounting_phases_fixed")]
    data["observability"] = {"sweep": []}
    data["runs_per_dataset"] = 3
    spec = validate_spec(data, BenchCatalog())
    results = campaigns.run_campaign(spec, tmp_path, workers=1, progress=False)
    campaigns.analyze(results)
    with xr.open_dataset(tmp_path / model_form.FILE_NAME, engine="netcdf4") as table:
        assert list(table["variant"].values) == ["noise_path=recorded", "contact_damping=x10", "mounting_phases=fixed"]
        assert (table["pairing"].values == "paired").all()
        assert (table["verdict_change"].values == model_form.VERDICT_CHANGE.index("not_compared")).all()
    with xr.open_dataset(results, engine="netcdf4") as stored:
        # the fixed phases are stored as the values the runs used; every other draw is the baseline's, run by run
        phase = stored["sensors.linear_encoder_mounting_phase"]
        assert (phase.sel(dataset="ds4__mounting_phases_fixed") == 0.0).all()
        assert (phase.sel(dataset="ds4") > 0.0).all()
        gain = stored["sensors.torque_meter_sensitivity_error_range1"]
        assert (gain.sel(dataset="ds4__contact_damping_x10") == gain.sel(dataset="ds4")).all()
