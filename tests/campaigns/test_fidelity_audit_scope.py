"""What the fidelity audit re-runs and in which unit it judges: a data set whose runs all took the full model's levels
is not re-run (identical, recorded as such), the audit's budget goes to the data sets the automatic choice
simplifies, a torque is judged against the torque tolerance and printed in mN·m, and settings the audit cannot
judge with are refused before any run."""

import re

import numpy as np
import pytest
import xarray as xr
from campaign_helpers import SYNTHETIC_CATALOG, write_spec

from campaigns.bench.campaign import load_spec, run_campaign
from campaigns.bench.fidelity_audit import (
    AUDIT_MIN_PAIRS,
    IDENTICAL,
    IDENTICAL_BASIS,
    audit_pairs,
    audit_problems,
    compare_fidelity,
    simplified_datasets,
    summary_attrs,
    with_identical,
)
from campaigns.bench.scene_audit import THESIS_SPEC
from campaigns.runner.spec import SpecError
from campaigns.runner.synthetic import synthetic_run
from campaigns.statistics.accuracy_rule import (
    MEAN_SHIFT_TOLERANCE,
    TORQUE_SHIFT_TOLERANCE,
    paired_verdict,
    tolerance_for,
)

SPECS = THESIS_SPEC.parent


def _full_levels(spec, name):
    import twin

    dataset = next(d for d in spec.datasets if d.name == name)
    scene = twin.load_scene(dataset.scene).with_conditions(dataset.conditions)
    return twin.fidelity.resolve_fidelity(scene, twin.load_parameters("bench"), "full", list(spec.features)).summary()


def test_a_data_set_whose_runs_took_the_full_levels_is_identical_and_the_others_are_simplified():
    """The decision rests on the levels each data set's runs recorded (results.nc fidelity_<data set>): the full
    levels of its scene on every run -> identical; any other level on any run -> simplified."""
    spec = load_spec(THESIS_SPEC)
    attrs = {f"fidelity_{d.name}": _full_levels(spec, d.name) for d in spec.datasets}
    attrs["fidelity_ds1"] = attrs["fidelity_ds1"].replace("current_loop=full", "current_loop=ideal")
    attrs["fidelity_ds5"] = attrs["fidelity_ds5"] + " | " + attrs["fidelity_ds5"].replace("nut_rotation=on",
                                                                                          "nut_rotation=off")
    found = simplified_datasets(spec, attrs)
    assert found == {d.name: d.name in ("ds1", "ds5") for d in spec.datasets}


def test_the_budget_goes_to_the_simplified_data_sets_up_to_all_their_runs():
    """fidelity_audit.runs per data set of the campaign, shared among the simplified ones, at most every run."""
    spec = load_spec(SPECS / "demo.toml")  # 13 data sets, 59 runs each, fidelity_audit.runs = 10
    assert (spec.fidelity_audit.runs, len(spec.datasets), spec.runs_per_dataset) == (10, 13, 59)
    assert audit_pairs(spec, 1) == 59      # 130 runs of budget, one data set: all its 59 runs
    assert audit_pairs(spec, 3) == 43      # 130 // 3
    assert audit_pairs(spec, 13) == 10     # every data set simplified: the old audit
    assert audit_pairs(spec, 0) == 0       # nothing to re-run


def _results(values, status="ok", wall=1.0, unit="m"):
    names = list(values)
    data = np.array([values[n] for n in names])
    return xr.Dataset({"f": (("dataset", "run"), data, {"units": unit}),
                       "status": (("dataset", "run"), np.full(data.shape, status, dtype=object)),
                       "wall_time": (("dataset", "run"), np.full(data.shape, wall))},
                      coords={"dataset": names, "run": np.arange(data.shape[1])})


def test_identical_data_sets_are_met_with_their_own_statement_in_the_file_and_the_attributes():
    rng = np.random.default_rng(3)
    full_values = rng.normal(30e-6, 0.4e-6, 20)
    auto = _results({"ds1": full_values + 0.001e-6 * rng.standard_normal(20), "ds2": full_values, "ds3": full_values})
    auto = auto.assign_coords(scene=("dataset", ["ds1", "ds2", "ds3"]))
    full = _results({"ds1": full_values}, wall=1.7).assign_coords(scene=("dataset", ["ds1"]))  # as results.nc
    audit = compare_fidelity(auto, full, ["f"])
    merged = with_identical(audit, ["ds2", "ds3"], ["f"], {"f": "m"}, ["ds1", "ds2", "ds3"])
    assert list(merged.dataset.values) == ["ds1", "ds2", "ds3"]
    assert list(merged.basis.values) == ["20 paired runs", IDENTICAL_BASIS, IDENTICAL_BASIS]
    assert merged.verdict.sel(dataset="ds2", feature="f").item() == "met"
    assert merged.statement.sel(dataset="ds3", feature="f").item() == IDENTICAL
    assert int(merged.n.sel(dataset="ds2", feature="f")) == 0
    assert np.isnan(float(merged.mean_shift.sel(dataset="ds2", feature="f")))
    assert merged.attrs["verdict"] == ("met: auto is within the tolerances of full fidelity (mean shift, standard "
                                       "deviation) on ds1 (20 paired runs each) and identical on the other 2 data "
                                       "set(s), whose automatic choice is the full model (not re-run)")
    attrs = summary_attrs(merged)
    assert attrs["fidelity_audit_ds2"] == IDENTICAL and attrs["fidelity_audit_ds1"].startswith("speedup x1.70; f: met")
    # no data set simplified: nothing re-run, every one identical, still a file and a verdict
    none = with_identical(None, ["ds2", "ds3"], ["f"], {"f": "m"}, ["ds2", "ds3"])
    assert none.attrs["verdict"] == ("met: the automatic choice is the full model on every data set (identical: "
                                     "nothing re-run)")
    assert (none.basis.values == IDENTICAL_BASIS).all() and none.attrs["runs"] == 0


def test_a_torque_is_judged_against_the_torque_tolerance_and_printed_in_millinewton_metres():
    """A drag-torque shift of 3.8 mN·m (the quasi-static screw axial on ds1) is far beyond a length's ±0.05 µm read as
    metres and far beyond the torque tolerance: not met, stated in mN·m; 0.3 mN·m with a tight spread is met."""
    assert tolerance_for("N m").value == TORQUE_SHIFT_TOLERANCE == 1.43e-3
    assert tolerance_for("m").value == MEAN_SHIFT_TOLERANCE
    rng = np.random.default_rng(5)
    reference = rng.normal(0.18, 0.004, 59)
    shifted = paired_verdict(reference + 3.8e-3 + 1e-4 * rng.standard_normal(59), reference, unit="N m",
                             min_pairs=AUDIT_MIN_PAIRS)
    assert shifted.verdict == "not met"
    assert re.match(r"not met: mean shift \+3\.\d{4} mN·m \(95 % t interval \+3\.\d{4} mN·m to \+3\.\d{4} mN·m",
                    shifted.statement) and "µm" not in shifted.statement
    assert "tolerance ±1.4300 mN·m" in shifted.statement
    close = paired_verdict(reference + 0.3e-3 + 1e-5 * rng.standard_normal(59), reference, unit="N m",
                           min_pairs=AUDIT_MIN_PAIRS)
    assert close.mean.verdict == "met", close.statement
    # the audit reads each feature's unit from the results: the same numbers in metres would be judged as a length
    auto, full = _results({"ds1": reference + 3.8e-3}, unit="N m"), _results({"ds1": reference}, unit="N m")
    audit = compare_fidelity(auto, full, ["f"])
    assert audit.feature_unit.sel(feature="f").item() == "N m"
    assert float(audit.mean_shift_tolerance.sel(feature="f")) == TORQUE_SHIFT_TOLERANCE
    assert re.search(r"max paired 3\.\d{4} mN·m, MC error \d\.\d{4} mN·m", summary_attrs(audit)["fidelity_audit_ds1"])
    with pytest.raises(ValueError, match="no mean-shift tolerance for features in 'rad'"):
        tolerance_for("rad")


@pytest.mark.parametrize("runs", [1, AUDIT_MIN_PAIRS - 1])
def test_an_audit_runs_count_below_the_fewest_pairs_is_refused_before_any_run(tmp_path, runs):
    path = tmp_path / "few.toml"
    path.write_text(f'extends = "{SPECS / "demo.toml"}"\n[fidelity_audit]\nruns = {runs}\n')
    with pytest.raises(SpecError) as refused:
        load_spec(path)
    assert refused.value.problems == [
        f"fidelity_audit.runs: {runs} is below the {AUDIT_MIN_PAIRS} paired runs an audit verdict needs "
        "(campaigns.bench.fidelity_audit.AUDIT_MIN_PAIRS); give 5 or more, or 0 to turn the audit off"]
    # a spec made in code is refused by run_campaign itself, before its output directory exists
    spec = load_spec(write_spec(tmp_path, "runs_per_dataset = 8\n[fidelity_audit]\nruns = 0\n"),
                     catalog=SYNTHETIC_CATALOG)
    bad = spec.model_copy(update={"fidelity_audit": spec.fidelity_audit.model_copy(update={"runs": runs})})
    with pytest.raises(SpecError, match="fidelity_audit.runs"):
        run_campaign(bad, tmp_path / "out", workers=1, progress=False, run_function=synthetic_run)
    assert not (tmp_path / "out").exists()
    assert audit_problems(bad.model_copy(update={"solver": bad.solver.model_copy(update={"fidelity": "full"})})) == []


@pytest.mark.parametrize("name", ["demo", "thesis_backlash", "observability", "preload_loss", "model_form"])
def test_the_shipped_specs_pass_the_audit_check(name):
    """Their features are lengths and torques, and their audits run with 5 or more pairs or not at all."""
    assert audit_problems(load_spec(SPECS / f"{name}.toml")) == []


def test_levels_no_speed_measurement_covers_run_the_full_model():
    """measured_fidelity: the demo asks data set 1 for the drag torque, so its automatic levels (the torque meter's
    refresh modelled) are not those speed.toml timed for the scene's own outputs (refresh ideal): it runs the full
    model. The thesis study asks for its scenes' own outputs: unchanged, the same object (results and hash kept)."""
    from campaigns.bench.campaign import measured_fidelity
    from twin.fidelity import SUBSYSTEMS

    demo = load_spec(SPECS / "demo.toml")
    moved = measured_fidelity(demo)
    ds1 = next(d for d in moved.datasets if d.name == "ds1")
    assert ds1.fidelity == {name: SUBSYSTEMS[name].full for name in SUBSYSTEMS}
    assert next(d for d in moved.datasets if d.name == "ds2").fidelity is None  # already the full model by the gate
    thesis = load_spec(THESIS_SPEC)
    assert measured_fidelity(thesis) is thesis


def test_a_campaign_on_the_full_model_re_runs_nothing(tmp_path):
    """ds2 runs the full model under auto (the gate of twin/fidelity/speed.toml): the audit stage runs no campaign of
    its own and records ds2 as identical, in results.nc and in fidelity_audit.nc."""
    path = tmp_path / "full_by_gate.toml"
    path.write_text(f'extends = "{THESIS_SPEC}"\nname = "gate"\nruns_per_dataset = 5\n[observability]\nsweep = []\n'
                    '[fidelity_audit]\nruns = 5\n'
                    '[[datasets]]\nname = "ds2"\nscene = "ds2"\nconditions = { backlash = 80e-6, preload = 0.0 }\n')
    said = []
    results = run_campaign(load_spec(path), tmp_path / "out", workers=1, progress=False,
                           announce=lambda stage, message: said.append((stage, message)))
    assert not (tmp_path / "out" / "fidelity_audit" / "results.nc").exists()  # no full-fidelity run
    assert [stage for stage, _ in said].count("runs") == 1
    assert ("fidelity audit", "gate: 1 data set(s) run the full model already (identical, not re-run)") in said
    audit_file = tmp_path / "out" / "fidelity_audit" / "fidelity_audit.nc"
    with xr.open_dataset(results) as ds, xr.open_dataset(audit_file) as a:
        assert ds.attrs["fidelity_audit_ds2"] == IDENTICAL
        assert ds.attrs["fidelity_audit"] == a.attrs["verdict"] == (
            "met: the automatic choice is the full model on every data set (identical: nothing re-run)")
        assert a.basis.sel(dataset="ds2").item() == IDENTICAL_BASIS
