"""The test-procedure designer (campaigns.workflows.procedure_search) on the synthetic model, whose answer to a
procedure is known (campaigns.runner.synthetic.procedure_effect: a preload hides the backlash, a force adds noise,
cycles average it).

Behaviour: the plan and the budget, the design, the screening estimate's closed form, the ranking against the
known answer, the statement, the evidence re-run to the same numbers, the files, and every bad input refused
before any run.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from campaign_helpers import SYNTHETIC_SPEC
from scipy import stats

import campaigns
from campaigns.analysis.within_unit import extrapolated_detectable
from campaigns.runner.files import CONVENTIONS
from campaigns.runner.spec import SpecError
from campaigns.runner.synthetic import SYNTHETIC_CATALOG, procedure_effect, synthetic_run
from campaigns.statistics.defaults import FALSE_ALARM_RATE, POWER
from campaigns.workflows.procedure_search import (
    describe_plan,
    design,
    final_seed,
    load_search,
    pareto_front,
    plan_runs,
    run_search,
    screening_scores,
)

SEARCH_FILE = SYNTHETIC_SPEC.parent / "synthetic_search.toml"
SEARCH = SEARCH_FILE.read_text().replace('campaign = "synthetic_search_campaign.toml"',
                                         f'campaign = "{SEARCH_FILE.parent / "synthetic_search_campaign.toml"}"')


def write(tmp_path, search: str = SEARCH):
    path = tmp_path / "search.toml"
    path.write_text(search)
    return path


def load(path, **options):
    return load_search(path, catalog=SYNTHETIC_CATALOG, **options)


@pytest.fixture(scope="module")
def searched(tmp_path_factory):
    root = tmp_path_factory.mktemp("search")
    spec = load(write(root))
    path = run_search(spec, root / "out", workers=1, progress=False, run_function=synthetic_run,
                      catalog=SYNTHETIC_CATALOG)
    with xr.open_dataset(path, engine="netcdf4") as handle:
        return spec, handle.load(), root / "out"


def noise_over_sensitivity(knobs: dict) -> float:
    sensitivity, noise = procedure_effect(knobs)
    return noise / sensitivity


def test_the_plan_counts_every_run_and_the_files_hold_them(searched):
    spec, ds, out = searched
    assert describe_plan(spec).endswith(f"total {plan_runs(spec)} runs")
    files = [xr.open_dataset(p, engine="netcdf4") for p in out.glob("candidates/*/*/results.nc")]
    ran = sum(f.sizes["dataset"] * f.sizes["run"] for f in files)
    assert ran == plan_runs(spec) == 4 * 177 * 2 + 1 * 177 * 4


def test_each_further_round_halves_the_candidates_and_doubles_the_repeats(tmp_path):
    spec = load(write(tmp_path, SEARCH.replace("finalists = 1", "finalists = 1\nrounds = 3")))
    assert describe_plan(spec) == (
        "round0: 4 candidates x 59 units x 3 repeats x 2 levels = 1416 runs; "
        "round1: 2 candidates x 59 units x 6 repeats x 2 levels = 1416 runs; "
        "final: the best 1 x 59 units x 3 repeats x 4 levels = 708 runs; total 3540 runs")


def test_the_design_is_the_reference_the_anchors_then_a_seeded_latin_hypercube(searched):
    spec = searched[0]
    candidates = design(spec)
    assert [c.name for c in candidates] == ["p00", "p01", "p02", "p03"]
    assert candidates[0].reference and candidates[1].knobs["cycles"] == 8
    assert design(spec) == candidates  # the same seed, the same design
    for c in candidates[2:]:
        assert 100.0 <= c.knobs["preload"] <= 1000.0 and 500.0 <= c.knobs["external_force"] <= 2000.0
        assert isinstance(c.knobs["cycles"], int) and 1 <= c.knobs["cycles"] <= 8
    # a Latin hypercube of 2 points puts one in each half of every range
    assert sorted(c.knobs["preload"] < 550.0 for c in candidates[2:]) == [False, True]


def test_the_search_finds_the_known_best_and_ranks_by_the_known_answer(searched):
    spec, ds, _ = searched
    ratio = {c.name: noise_over_sensitivity(c.knobs) for c in design(spec)}
    best = min(ratio, key=ratio.get)
    assert ds.attrs["best"] == best == "p01"
    assert int(ds["rank"].sel(candidate=best)) == 1 and int(ds["finalist"].sel(candidate=best)) == 1
    # round 0 (the same units and repeats for all): the screening estimate grows with noise/sensitivity
    score = ds["score"].to_series()
    rho = stats.spearmanr([ratio[c] for c in score.index], score.fillna(np.inf).values).statistic
    assert rho > 0.7, (ratio, score.to_dict())
    # the paired bounds separate the best from the worst candidate
    worst = max(ratio, key=ratio.get)
    assert float(ds["difference_low"].sel(candidate=worst)) > 0.0


def test_the_statement_is_the_best_finalists_verdict_and_names_what_it_beats(searched):
    _, ds, _ = searched
    verdict = str(ds["within_unit_verdict"].sel(candidate=ds.attrs["best"]).item())
    assert verdict in ("met", "not met", "undetermined", "insufficient data") and ds.attrs["verdict"] == verdict
    statement = ds.attrs["statement"]
    assert statement.startswith(f"{verdict}: the best of 4 procedures is p01")
    assert "reference" in statement and "paired bootstrap" in statement and "59 units x 3 tests" in statement


def test_the_finalists_figure_is_the_within_unit_analysis(searched):
    """The finalist's bounds are its full campaign's analysis.nc figures for the 95th-percentile unit."""
    _, ds, out = searched
    best = ds.attrs["best"]
    analysis = xr.open_dataset(out / "candidates" / best / "final" / "analysis.nc", engine="netcdf4")
    ci = analysis["within_unit_minimum_detectable_backlash_ci"].sel(unit_quantile=0.95, feature="backlash_feature")
    assert float(ds["within_unit_low"].sel(candidate=best)) == float(ci.sel(bound="lower"))
    assert float(ds["within_unit_high"].sel(candidate=best)) == float(ci.sel(bound="upper"))


def test_each_candidates_evidence_runs_again_to_the_same_numbers(searched, tmp_path):
    """The rerun command's spec file, loaded as `twin campaign run` loads it, is the campaign that ran (same hash)
    and runs to the same features; the finalists' campaigns draw fresh units (their own root seed)."""
    spec, ds, out = searched
    for candidate in ds["candidate"].values:
        evidence = out / str(ds["evidence"].sel(candidate=candidate).item())
        spec_file = evidence.parent / f"{evidence.name}.toml"
        assert str(ds["rerun"].sel(candidate=candidate).item()).startswith(
            f"twin campaign run candidates/{candidate}/{evidence.name}.toml")
        stored = xr.open_dataset(evidence / "results.nc", engine="netcdf4")
        assert campaigns.load_spec(spec_file, catalog=SYNTHETIC_CATALOG).spec_hash() == stored.attrs["spec_hash"]
    final = (out / "candidates" / ds.attrs["best"] / "final.toml").read_text()
    assert f"root_seed = {final_seed(spec)}" in final and final_seed(spec) != 12345  # fresh units for the verdict
    again = campaigns.run_campaign(campaigns.load_spec(spec_file, catalog=SYNTHETIC_CATALOG), tmp_path / "again",
                                   workers=1, progress=False, run_function=synthetic_run)
    np.testing.assert_array_equal(xr.open_dataset(again)["backlash_feature"].values, stored["backlash_feature"].values)


def test_a_resumed_search_reads_its_finished_campaigns_and_finds_the_same(searched):
    spec, ds, out = searched
    stamps = {p: p.stat().st_mtime_ns for p in out.glob("candidates/*/*/results.nc")}
    path = run_search(spec, out, workers=1, progress=False, resume=True, run_function=synthetic_run,
                      catalog=SYNTHETIC_CATALOG)
    assert {p: p.stat().st_mtime_ns for p in out.glob("candidates/*/*/results.nc")} == stamps  # nothing re-ran
    with xr.open_dataset(path, engine="netcdf4") as again:
        assert again.attrs["statement"] == ds.attrs["statement"]
        xr.testing.assert_identical(again.drop_attrs(), ds.drop_attrs())


def test_search_nc_is_cf_and_the_ranking_table_is_in_rank_order(searched):
    _, ds, out = searched
    assert ds.attrs["Conventions"] == CONVENTIONS and ds["score"].attrs["units"] == "m"
    assert ds["knob_preload"].attrs["units"] == "N" and ds["test_duration"].attrs["units"] == "s"
    table = pd.read_csv(out / "ranking.csv")
    assert table["rank"].tolist() == sorted(table["rank"]) and table["candidate"].iloc[0] == ds.attrs["best"]
    assert "score [um]" in table.columns and "preload [N]" in table.columns


def test_the_extrapolated_detectable_growth_has_its_closed_form():
    """Repeats at +-sigma around each cell's mean (exact cell statistics): a unit whose feature moves by s at growth
    G detects g = G (margin + z_power sigma) / s, margin = t(1 - alpha, dof) sigma sqrt(1 + 1/R)."""
    units, sigma, growth = 6, 0.2, 1.0
    pattern = np.array([-1.0, 0.0, 1.0]) * sigma  # sample standard deviation (n - 1) = sigma
    shifts = np.linspace(0.5, 3.0, units)
    offsets = np.arange(units) * 10.0
    values = np.stack([offsets[:, None] + pattern, (offsets + shifts)[:, None] + pattern])
    dof = units * 2
    margin = stats.t.ppf(1 - FALSE_ALARM_RATE, dof) * sigma * math.sqrt(1 + 1 / 3)
    expected = growth * (margin + stats.norm.ppf(POWER) * sigma) / shifts
    np.testing.assert_allclose(extrapolated_detectable(values, growth), expected, rtol=1e-12)
    flat = values.copy()
    flat[1] = flat[0]
    assert np.isinf(extrapolated_detectable(flat, growth)).all()


def test_the_screening_estimate_is_the_design_review_units_order_statistic():
    rng = np.random.default_rng(5)
    values = rng.normal(0.0, 0.1, (2, 2, 100, 3)) + np.array([0.0, 1.0])[None, :, None, None]
    found = screening_scores(values, 1.0, seed=1, n_boot=200)
    per_unit = extrapolated_detectable(values[0], 1.0)
    assert found["estimate"][0] == np.sort(per_unit)[94]  # the 95th of 100 units, no interpolation
    assert found["low"][0] <= found["estimate"][0] <= found["high"][0]


def test_pareto_front():
    score = np.array([1.0, 2.0, 0.5, 3.0, math.inf])
    duration = np.array([5.0, 2.0, 10.0, 2.0, 1.0])
    assert pareto_front(score, duration).tolist() == [True, True, True, False, False]


@pytest.mark.parametrize("change, message", [
    (("cycles = [1, 8]", "cycle = [1, 8]"), "knobs.cycle: unknown knob; did you mean 'cycles'?"),
    (("preload = [100.0, 1000.0]", "preload = [0.0, 20000.0]"), "knobs.preload: 20000 N is outside the bench's range"),
    (("[knobs]\n", "[knobs]\namplitude = [0.1e-3, 0.2e-3]\nfrequency = [0.1, 0.2]\n"), "none within the bench's"),
    (("anchors = [{ preload = 0.0, external_force = 0.0, cycles = 8 }]", "anchors = [{ preload = -5.0 }]"),
     "anchors[0].preload"),
    (("[budget]", "[reference]\namplitude = 1e-3\n\n[budget]"),
     "reference.amplitude: not a condition of the reference"),
    (("runs = 4000", "runs = 100"), "budget.runs: 100 runs cannot rank anything: the smallest plan"),
    (("runs = 4000", "runs = 2000"), "budget.runs: the plan needs 2124 runs"),
    (("candidates = 4", "candidates = 1"), "budget.candidates"),
    (("finalists = 1", "finalists = 5"), "finalists = 5 is more than the 4 candidates"),
    (("levels = [0.5e-6, 1e-6, 2e-6]", "levels = [1e-6, 0.5e-6]"), "levels: must be positive growths in increasing"),
    (('features = ["backlash_feature"]', 'features = ["backlash_feature_true"]'), "cannot measure"),
    (('features = ["backlash_feature"]', 'features = ["drag"]'), "'drag' is not a feature of the campaign"),
    (('fault = "backlash"', 'fault = "wear"'), "fault"),
    (('name = "synthetic_search"', 'name = "synthetic_search"\ncolour = "red"'), "colour"),
    (("cycles = [1, 8]", "cycles = [1, 8]\nzero_procedure = []"), "knobs.zero_procedure: give at least one of"),
    (("candidates = 4", "candidates = 200"), "budget.candidates"),
    (("preload = [100.0, 1000.0]\nexternal_force = [500.0, 2000.0]\ncycles = [1, 8]", "cycles = 4"),
     "knobs: none has a range or a choice"),
    (('scene = "ds2"\n', ""), "scene"),
])
def test_bad_search_specs_are_one_clear_error_before_any_run(tmp_path, change, message):
    assert change[0] in SEARCH
    with pytest.raises(SpecError) as caught:
        load(write(tmp_path, SEARCH.replace(*change)))
    assert len(caught.value.problems) == 1 and message in caught.value.problems[0], caught.value.problems
    assert not (tmp_path / "out").exists()


def test_a_preload_loss_search_needs_a_preload_campaign_and_losses_within_the_setting(tmp_path):
    search = SEARCH.replace('fault = "backlash"', 'fault = "preload_loss"').replace(
        "levels = [0.5e-6, 1e-6, 2e-6]", "levels = [50.0, 100.0]\nscreening_level = 200.0").replace(
        "anchors = [{ preload = 0.0, external_force = 0.0, cycles = 8 }]", "")
    with pytest.raises(SpecError) as caught:
        load(write(tmp_path, search))
    assert any("a loss of 200 N is more than the lowest preload setting 0 N" in p for p in caught.value.problems)
    assert any("campaign: its observability sweep is over 'backlash'" in p for p in caught.value.problems)


def test_quick_is_the_smallest_plan_that_still_ranks(tmp_path):
    spec = load(write(tmp_path), quick=True)
    assert (spec.budget.candidates, spec.budget.finalists, spec.budget.rounds) == (3, 1, 1)
    assert spec.budget.runs == plan_runs(spec) == 3 * 177 * 2 + 177 * 4


def test_a_candidate_spec_file_with_other_content_is_not_overwritten(tmp_path):
    spec = load(write(tmp_path))
    target = tmp_path / "out" / "candidates" / "p00"
    target.mkdir(parents=True)
    (target / "round0.toml").write_text("# mine\n")
    with pytest.raises(SpecError, match="exists with another campaign"):
        run_search(spec, tmp_path / "out", workers=1, progress=False, run_function=synthetic_run,
                   catalog=SYNTHETIC_CATALOG)
    assert (target / "round0.toml").read_text() == "# mine\n"


@pytest.mark.parametrize("name, runs", [("procedure_backlash", 5400), ("procedure_preload_loss", 5400),
                                        ("procedure_preload_loss_preloaded_zero", 5400)])
def test_the_shipped_searches_are_valid_and_their_plans_fit_their_budgets(name, runs):
    """Loaded against the bench (its catalog and scenes): the reference and one design point make valid campaigns."""
    spec = load_search(Path(campaigns.__file__).parent / "specs" / f"{name}.toml")
    assert plan_runs(spec) == runs <= spec.budget.runs
    assert design(spec)[0].reference and len(design(spec)) == spec.budget.candidates


def test_the_cli_prints_the_plan_and_refuses_bad_input_in_one_line(tmp_path):
    twin = [sys.executable, "-m", "app.cli", "procedure", "search"]
    shipped = str(Path(campaigns.__file__).parent / "specs" / "procedure_backlash.toml")
    plan = subprocess.run([*twin, shipped, "--plan"], capture_output=True, text=True, check=True)
    assert "total 5400 runs" in plan.stdout and "p00 (reference: the base scene's own procedure)" in plan.stdout
    bad = write(tmp_path, SEARCH.replace("cycles = [1, 8]", "cycle = [1, 8]"))
    refused = subprocess.run([*twin, str(bad), "--out", str(tmp_path / "out")], capture_output=True, text=True)
    assert refused.returncode == 2 and refused.stderr.startswith("twin: error:") and "did you mean 'cycles'" in \
        refused.stderr
    assert not (tmp_path / "out").exists()
