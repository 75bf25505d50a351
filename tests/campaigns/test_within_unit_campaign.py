"""Within-unit campaigns (the spec's ``[units]``, issue 29): the same units tested repeatedly at every fault level.

Known answers on the synthetic model (campaigns/runner/synthetic.py): its measured feature is ``gain * backlash +
offset + TEMPERATURE_SLOPE * (room_temperature - 298.15 K) + noise``. With gain and offset drawn once per unit, a unit's
tests differ by the room temperature (uniform 15-35 degC: sd 5.77 K, times 0.05 µm/K = 0.289 µm) and the noise
(0.2 µm), a test-to-test sigma of 0.351 µm. The median unit then detects a growth of about
``(z_0.95 sqrt(1 + 1/R) + z_0.95) sigma = 1.24 µm`` (R = 3 baseline repeats; campaigns/analysis/within_unit.py), which
lies between the 1 and 2 µm levels of the sweep; between units the offsets (uniform ±1 µm) add to the scatter, so one
test per unit detects no less than that.
"""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest
import xarray as xr
from campaign_helpers import SYNTHETIC_SPEC, data_variables, load, write_spec
from scipy import stats

import campaigns
from campaigns.analysis.campaign_analysis import analysis_dataset, summary
from campaigns.analysis.within_unit import unit_values, within_unit_dataset
from campaigns.bench.fidelity_audit import full_fidelity_variant
from campaigns.bench.replay import replay_run
from campaigns.runner.execution import build_request
from campaigns.runner.sampling import UNIT_STREAM, draw, sample
from campaigns.runner.spec import SpecError
from campaigns.runner.synthetic import NOISE_SIGMA, TEMPERATURE_SLOPE, SyntheticModel, synthetic_run
from campaigns.statistics.within_unit_floors import MIN_REPEATS, MIN_UNITS
from campaigns.workflows.export import runs_table

UNITS, REPEATS = MIN_UNITS, MIN_REPEATS
LEVELS = (0.0, 1e-6, 2e-6, 5e-6)
WITHIN_UNIT = f"""
name = "synthetic_within_unit"
runs_per_dataset = {UNITS * REPEATS}

[execution]
isolation = "none"

[traces]
runs_per_dataset = 0

[observability]
sweep = ["b0", "b1", "b2", "b5"]
""" + "".join(f"""
[[datasets]]
name = "b{level * 1e6:g}"
scene = "ds2"
conditions = {{ backlash = {level!r}, preload = 0.0, external_force = 0.0 }}
""" for level in LEVELS) + f"""
[units]  # last: a test appends its fields to this table
count = {UNITS}
repeats = {REPEATS}
"""
# the synthetic table samples gain, offset, stiffness, inert, then the scene's room temperature and supply pressure
PER_UNIT, PER_TEST = [0, 1, 2, 3], [4, 5]


@pytest.fixture(scope="module")
def within_unit_spec(tmp_path_factory):
    return load(write_spec(tmp_path_factory.mktemp("spec"), WITHIN_UNIT))


@pytest.fixture(scope="module")
def within_unit_results(within_unit_spec, tmp_path_factory):
    out = tmp_path_factory.mktemp("within_unit") / "out"
    return campaigns.run_campaign(within_unit_spec, out, workers=1, progress=False, run_function=synthetic_run)


def test_the_per_test_rows_default_to_the_scene_conditions(within_unit_spec):
    targets = [d.target for d in within_unit_spec.distributions()]
    assert within_unit_spec.per_test_targets() == [targets[k] for k in PER_TEST]
    assert within_unit_spec.unit_draws(7, targets) == {"unit": 7 // REPEATS, "per_unit": PER_UNIT}
    # stored as sampled: the hash changes with the rows, not with how they were written
    assert within_unit_spec.canonical()["spec"]["units"]["per_test"] == [targets[k] for k in PER_TEST]


def test_a_units_fixed_errors_are_shared_by_all_its_tests_and_the_per_test_rows_are_redrawn(within_unit_spec):
    samples = sample(within_unit_spec)
    by_unit = samples.reshape(len(LEVELS), UNITS, REPEATS, -1)
    # per unit: the same value in every repeat at every level (common random numbers across the unit's tests) ...
    assert (by_unit[..., PER_UNIT] == by_unit[:1, :, :1, PER_UNIT]).all()
    # ... and a value of its own: every unit draws other values
    assert all(len(np.unique(by_unit[0, :, 0, k])) == UNITS for k in PER_UNIT)
    # per test: every test of every unit at every level draws its own
    assert all(len(np.unique(samples[..., k])) == samples[..., k].size for k in PER_TEST)
    # the unit's stream is (root_seed, UNIT_STREAM, unit): the table drawn in order, its per-unit columns kept
    rng = np.random.default_rng(np.random.SeedSequence(within_unit_spec.root_seed, spawn_key=(UNIT_STREAM, 5)))
    expected = [draw(d, rng) for d in within_unit_spec.distributions()]
    np.testing.assert_array_equal(by_unit[2, 5, 1, PER_UNIT], np.array(expected)[PER_UNIT])


def test_each_test_has_its_own_noise(within_unit_spec):
    samples = sample(within_unit_spec)
    first, second = (build_request(within_unit_spec, samples, 1, run).noise_rng().normal() for run in (0, 1))
    other_level = build_request(within_unit_spec, samples, 2, 0).noise_rng().normal()
    assert len({first, second, other_level}) == 3


def test_the_fidelity_audit_reruns_the_same_tests_of_the_same_units(within_unit_spec):
    audit = full_fidelity_variant(within_unit_spec, 10)
    np.testing.assert_array_equal(sample(audit), sample(within_unit_spec)[:, :10])


def test_a_per_unit_row_made_per_test_changes_that_row_only(tmp_path, within_unit_spec):
    spec = load(write_spec(tmp_path, WITHIN_UNIT + 'per_test = ["scene.room_temperature", "scene.supply_pressure", '
                                                   '"synthetic.inert"]\n'))
    before, after = sample(within_unit_spec), sample(spec)
    np.testing.assert_array_equal(after[..., [0, 1, 2, 4, 5]], before[..., [0, 1, 2, 4, 5]])
    assert len(np.unique(after[..., 3])) == after[..., 3].size


def test_specs_without_units_keep_their_canonical_form_and_samples(tmp_path):
    spec = load(SYNTHETIC_SPEC)
    assert "units" not in spec.canonical()["spec"] and spec.unit_draws(3, []) == {}
    # the units change nothing but the per-unit rows: the per-test rows are the run's own draws, as without units
    within = load(write_spec(tmp_path, "runs_per_dataset = 177\n[units]\ncount = 59\nrepeats = 3\n"))
    plain = load(write_spec(tmp_path, "runs_per_dataset = 177\n"))
    np.testing.assert_array_equal(sample(within)[..., PER_TEST], sample(plain)[..., PER_TEST])


def test_results_name_the_unit_and_the_repeat_of_every_run(within_unit_results):
    with xr.open_dataset(within_unit_results) as results:
        np.testing.assert_array_equal(results["unit"].values, np.arange(UNITS * REPEATS) // REPEATS)
        np.testing.assert_array_equal(results["repeat"].values, np.arange(UNITS * REPEATS) % REPEATS)
        assert results["unit"].dims == ("run",) and results["unit"].attrs["units"] == "1"
        assert "long_name" in results["repeat"].attrs
        assert f"spawn_key=({UNIT_STREAM}, u)" in results.attrs["seeding"]
        offsets = results["synthetic.offset"].values.reshape(len(LEVELS), UNITS, REPEATS)
        assert (offsets == offsets[:1, :, :1]).all()


def test_the_runs_table_of_an_export_names_the_unit_and_the_repeat(within_unit_results):
    with xr.open_dataset(within_unit_results) as results:
        table = runs_table(results)
    row = table[(table["dataset"] == "b2") & (table["run"] == 100)].iloc[0]
    assert (row["unit"], row["repeat"]) == (100 // REPEATS, 100 % REPEATS)


def test_a_within_unit_run_replays_bit_for_bit(within_unit_results):
    for dataset, run in (("b0", 0), ("b2", 100)):
        replayed = replay_run(within_unit_results, dataset, run, run_function=synthetic_run)
        assert replayed.attrs["identical_backlash_feature"] == "yes"


def test_a_within_unit_campaign_resumes_to_the_same_results(within_unit_spec, within_unit_results, tmp_path):
    out = tmp_path / "out"
    shutil.copytree(within_unit_results.parent, out)
    (out / "results.nc").unlink()
    chunks = sorted((out / "chunks").rglob("*.npz"))
    removed = chunks[::3]
    for chunk in removed:
        chunk.unlink()
    log = tmp_path / "log"
    log.mkdir()
    path = campaigns.run_campaign(within_unit_spec, out, workers=1, resume=True, progress=False,
                                  run_function=SyntheticModel(log_dir=str(log)))
    executed = sum(len(f.read_text().splitlines()) for f in log.glob("runs-*.log"))
    assert 0 < executed < UNITS * REPEATS * len(LEVELS)
    with xr.open_dataset(path) as resumed, xr.open_dataset(within_unit_results) as whole:
        xr.testing.assert_identical(data_variables(resumed), data_variables(whole))


@pytest.fixture(scope="module")
def within_unit_analysis(within_unit_results):
    with xr.open_dataset(within_unit_results) as results:
        return results.load(), analysis_dataset(results.load(), n_boot=200)


def test_the_analysis_holds_the_within_unit_verdict_and_the_summary_prints_it(within_unit_analysis):
    _, analysis = within_unit_analysis
    assert set(analysis["within_unit_requirement_verdict"].dims) == {"feature"}
    assert list(analysis["level_dataset"].values) == ["b0", "b1", "b2", "b5"]
    np.testing.assert_array_equal(analysis["within_unit_backlash"].values, LEVELS)
    assert int(analysis["within_unit_n_units_used"].sel(feature="backlash_feature")) == UNITS
    statements, _ = summary(analysis)
    within = [s for s in statements if s.startswith("backlash_feature within unit: ")]
    assert within == ["backlash_feature within unit: "
                      + analysis["within_unit_requirement_statement"].sel(feature="backlash_feature").item()]
    assert analysis.attrs["within_unit_min_repeats"] == MIN_REPEATS


def test_the_within_unit_figures_are_those_of_the_module_on_the_runs_values(within_unit_analysis):
    results, analysis = within_unit_analysis
    levels, values, names = unit_values(results, "backlash_feature", ["b0", "b1", "b2", "b5"])
    assert values.shape == (len(LEVELS), UNITS, REPEATS) and names == ["b0", "b1", "b2", "b5"]
    direct = within_unit_dataset(levels, values, feature_units="m")
    stored = analysis.sel(feature="backlash_feature")
    np.testing.assert_array_equal(stored["within_unit_threshold_high"], direct["within_unit_threshold_high"])
    np.testing.assert_array_equal(stored["within_unit_detectable_bracket"], direct["within_unit_detectable_bracket"])


def test_the_median_unit_detects_the_analytic_growth_and_one_test_per_unit_sets_the_between_unit_sweep(
        within_unit_analysis):
    _, analysis = within_unit_analysis
    sigma = math.hypot(TEMPERATURE_SLOPE * 20.0 / math.sqrt(12.0), NOISE_SIGMA)
    z = stats.norm.ppf(0.95)
    expected = (z * math.sqrt(1.0 + 1.0 / REPEATS) + z) * sigma
    assert 1e-6 < expected < 2e-6
    stored = analysis.sel(feature="backlash_feature")
    median = stored["within_unit_minimum_detectable_bracket"].sel(unit_quantile=0.5).values
    np.testing.assert_array_equal(median, [1e-6, 2e-6])
    between = stored["minimum_detectable_bracket"].values
    assert between[0] >= median[0]
    statement = stored["requirement_statement"].item()
    assert f"{UNITS} ok runs per sweep data set" in statement
    assert f"one test per unit (repeat 0 of each of the {UNITS} units)" in statement


def test_a_feature_without_test_to_test_scatter_is_detected_at_the_first_level_that_moves_it(within_unit_analysis):
    _, analysis = within_unit_analysis
    stored = analysis.sel(feature="backlash_feature_true")  # the true feature: gain and stiffness, per unit only
    assert (stored["within_unit_scatter"] == 0.0).all()
    np.testing.assert_array_equal(stored["within_unit_minimum_detectable_bracket"].sel(unit_quantile=0.95),
                                  [0.0, 1e-6])
    assert "does not vary from test to test" in stored["within_unit_requirement_statement"].item()


@pytest.mark.parametrize("changes, problem", [
    ({"repeats = 3": 'repeats = 3\nper_test = ["scene.room_temperatur"]'},
     "units.per_test: 'scene.room_temperatur' is not a row of the uncertainty table; did you mean "
     "'scene.room_temperature'?"),
    ({"count = 59": "count = 30", "runs_per_dataset = 177": "runs_per_dataset = 90"},
     "units.count: 30 units is below the floor of 59: with fewer, not even the largest unit bounds the 95th-percentile "
     "unit"),
    ({"repeats = 3": "repeats = 2", "runs_per_dataset = 177": "runs_per_dataset = 118"},
     "units.repeats: 2 repeats is below the floor of 3: the check that the units share one test-to-test scatter"),
    ({"repeats = 3": "repeats = 3\ncolour = 1"}, "units.colour: unknown field"),
])
def test_bad_units_get_one_clear_error_before_any_run(tmp_path, changes, problem):
    text = WITHIN_UNIT
    for old, new in changes.items():
        assert old in text
        text = text.replace(old, new)
    with pytest.raises(SpecError) as caught:
        load(write_spec(tmp_path, text))
    assert problem in str(caught.value)
    assert len(caught.value.problems) == 1, caught.value.problems


def test_runs_per_dataset_must_be_units_times_repeats(tmp_path):
    with pytest.raises(SpecError) as caught:
        load(write_spec(tmp_path, WITHIN_UNIT), runs=100)
    assert caught.value.problems == [f"runs_per_dataset: 100 runs, but [units] tests {UNITS} units {REPEATS} times "
                                     f"each: set runs_per_dataset = {UNITS * REPEATS} (run i of a data set is test "
                                     f"i % {REPEATS} of unit i // {REPEATS})"]


def test_units_need_an_observability_sweep_with_one_level_per_data_set(tmp_path):
    with pytest.raises(SpecError, match=r"units: a within-unit campaign needs observability.sweep"):
        load(write_spec(tmp_path, WITHIN_UNIT.replace('sweep = ["b0", "b1", "b2", "b5"]', "sweep = []")))
    twice = WITHIN_UNIT.replace('name = "b5"', 'name = "b1again"').replace("5e-06", "1e-06").replace(
        '"b5"]', '"b1again"]')
    with pytest.raises(SpecError, match="units: the sweep's data sets must each set a different backlash"):
        load(write_spec(tmp_path, twice))


@pytest.mark.parametrize("name, sweep", [
    ("backlash_within_unit.toml", ["ds4", "b0_5", "b1", "b2", "ds6"]),
    ("preload_loss_within_unit.toml", ["p1000", "p950", "p900", "p800", "p600"]),
])
def test_the_shipped_within_unit_specs_validate_with_the_default_per_test_rows(name, sweep):
    spec = campaigns.load_spec(SYNTHETIC_SPEC.parents[3] / "campaigns" / "specs" / name)
    assert (spec.units.count, spec.units.repeats, spec.runs_per_dataset) == (60, 5, 300)
    assert [d.name for d in spec.datasets] == spec.observability.sweep == sweep
    assert spec.per_test_targets() == [
        "scene.room_temperature", "scene.supply_pressure", "sensors.load_cell_repeatability_error",
        "sensors.linear_encoder_mounting_phase", "sensors.torque_meter_encoder_mounting_phase"]
    assert len(spec.distributions()) - len(spec.per_test_targets()) > 40  # every other row: a fixed error of the unit


def test_the_homed_start_variant_fixes_the_encoders_mounting_phases_per_unit_and_changes_nothing_else():
    specs = SYNTHETIC_SPEC.parents[3] / "campaigns" / "specs"
    default = campaigns.load_spec(specs / "backlash_within_unit.toml")
    homed = campaigns.load_spec(specs / "backlash_within_unit_phases_per_unit.toml")
    assert set(default.per_test_targets()) - set(homed.per_test_targets()) == {
        "sensors.linear_encoder_mounting_phase", "sensors.torque_meter_encoder_mounting_phase"}
    assert homed.datasets == default.datasets and homed.distributions() == default.distributions()
    assert (homed.root_seed, homed.units.count, homed.units.repeats) == (default.root_seed, 60, 5)


def test_twin_campaign_analyze_prints_the_within_unit_statement_after_the_between_unit_one(
        within_unit_results, tmp_path, capsys):
    from app.cli import main  # the CLI on the library's results, as a user runs it

    assert main(["campaign", "analyze", str(within_unit_results), "--out", str(tmp_path / "analysis.nc")]) == 0
    lines = capsys.readouterr().out.splitlines()
    between = next(k for k, line in enumerate(lines) if line.startswith("backlash_feature: "))
    assert lines[between + 1].startswith("backlash_feature within unit: ")
    with xr.open_dataset(tmp_path / "analysis.nc") as analysis:
        assert lines[between + 1].endswith(
            analysis["within_unit_requirement_statement"].sel(feature="backlash_feature").item())


def test_the_cf_compliance_checker_finds_no_high_priority_issue_in_the_within_unit_files(within_unit_results, tmp_path):
    """results.nc with its unit and repeat coordinates, analysis.nc with the within-unit variables (CF 1.8: no
    failed high-priority check, no crashed check; the 64-bit integers CF has no type for are 32-bit)."""
    pytest.importorskip("compliance_checker")
    from compliance_checker.base import BaseCheck
    from compliance_checker.suite import CheckSuite

    suite = CheckSuite()
    suite.load_all_available_checkers()
    analysis = campaigns.analyze(within_unit_results, tmp_path / "analysis.nc", n_boot=100)

    def failed(result) -> bool:
        value = result.value
        return value[0] < value[1] if isinstance(value, tuple) else value is False

    for path in (within_unit_results, analysis):
        groups, errors = suite.run_all(suite.load_dataset(str(path)), ["cf:1.8"])["cf:1.8"]
        assert [(r.name, r.msgs) for r in groups if r.weight == BaseCheck.HIGH and failed(r)] == [], path.name
        assert errors == {}, path.name
