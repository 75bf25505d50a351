"""The acceptance study (campaigns.bench.solver_accuracy) end to end on the synthetic model: the reference and the
candidates over the same sampled runs, their analyses, the judgement, its CF file, its markdown table and its chart;
and the descriptive figures of campaigns.statistics.paired_comparison."""

import numpy as np
import pytest
import xarray as xr
from campaign_helpers import SYNTHETIC_SPEC, load
from test_campaign_cf import high_priority_findings

from app.studies.charts import campaign_accuracy_chart
from campaigns.bench.campaign import load_spec
from campaigns.bench.solver_accuracy import (
    CANDIDATES,
    REFERENCE,
    THESIS_SPEC,
    campaign_accuracy,
    markdown_table,
    variant,
)
from campaigns.runner.synthetic import synthetic_run
from campaigns.statistics.paired_comparison import compare_features

RUNS = 24


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """The study on the synthetic model, which ignores the solver: every candidate equals the reference run for run,
    so with the minimum lowered to the runs at hand every check must be met."""
    out = tmp_path_factory.mktemp("acceptance")
    lines = []
    judged = campaign_accuracy(out, load(SYNTHETIC_SPEC), runs=RUNS, min_pairs=RUNS, workers=1,
                               run_function=synthetic_run, progress=lines.append)
    return out, judged, lines


def test_identical_configurations_meet_the_rule_and_every_output_says_so(study):
    out, judged, lines = study
    assert list(judged.candidate.values) == [c.name for c in CANDIDATES]
    assert set(judged.candidate_verdict.values) == {"met"}
    assert set(judged.verdict.values.ravel()) == {"met"} and int(judged.n.min()) == RUNS
    assert set(judged.ranking_verdict.values.ravel()) == set(judged.verdict_unchanged.values.ravel()) == {"met"}
    for name in judged.candidate.values:
        assert f"{name}: {judged.candidate_statement.sel(candidate=name).item()}" in lines
    statement = judged.statement.sel(candidate="new_default", dataset="ds2", feature="backlash_feature").item()
    assert f"  ds2 backlash_feature: {statement}" in lines
    table = (out / "campaign_accuracy.md").read_text()
    assert table == markdown_table(xr.load_dataset(out / "campaign_accuracy.nc"))
    assert "### new_default: met" in table
    assert "| ds2 | `backlash_feature` | 24 | +0.0000 (+0.0000 to +0.0000) | 1.000 (1.000 to 1.000) |" in table
    for name in ("reference", *judged.candidate.values):
        assert (out / name / "results.nc").exists() and (out / name / "analysis.nc").exists()


@pytest.mark.parametrize("version", ["cf:1.11", "cf:1.8"])
def test_the_study_file_is_cf(study, version, tmp_path):
    out, _, _ = study
    pytest.importorskip("compliance_checker")
    findings = high_priority_findings(out / "campaign_accuracy.nc", version, tmp_path)
    assert not findings, "\n".join(findings)


def test_the_chart_draws_intervals_and_leaves_out_what_the_data_do_not_resolve(study, tmp_path):
    _, judged, _ = study
    campaign_accuracy_chart(judged, tmp_path / "campaign_accuracy.png")
    assert (tmp_path / "campaign_accuracy.png").stat().st_size > 10_000
    assert (tmp_path / "campaign_accuracy.svg").exists()
    unresolved = judged.copy()
    unresolved["mean_shift_lower"][:] = np.nan  # insufficient data: no interval, nothing drawn
    campaign_accuracy_chart(unresolved, tmp_path / "unresolved.png")


def test_variants_share_the_sampling_and_differ_only_in_the_solver():
    spec = load_spec(THESIS_SPEC)
    reference, previous = (variant(spec, c, runs=200) for c in (REFERENCE, CANDIDATES[1]))
    assert (reference.solver.integrator, reference.solver.dt, reference.solver.fidelity) == ("rk4", 15.625e-6, "full")
    assert (previous.solver.dt, previous.solver.fidelity) == (6.25e-5, {"default": "auto", "screw_axial": "dynamic"})
    assert variant(spec, CANDIDATES[0], runs=200).solver.dt is None  # the twin's own default step
    for v in (reference, previous):
        assert (v.root_seed, v.uncertainties, v.runs_per_dataset) == (spec.root_seed, spec.uncertainties, 200)
        assert v.fidelity_audit.runs == 0 and v.traces.runs_per_dataset == 0
        assert v.observability == spec.observability  # all sweep data sets run: the requirement verdicts exist
    short = variant(spec, REFERENCE, runs=3, datasets=["ds2", "ds5"], scenes={"ds2": "/tmp/ds2_1s.toml"})
    assert [d.scene for d in short.datasets] == ["/tmp/ds2_1s.toml", "ds5"]
    assert short.observability.sweep == []  # the sweep's data sets are not all run


def _results(values):
    status = np.full(values.shape, "ok", dtype=object)
    return xr.Dataset({"backlash_feature": (("dataset", "run"), values), "status": (("dataset", "run"), status)},
                      coords={"dataset": ["ds2", "ds5"], "run": np.arange(values.shape[1])})


def test_compare_features_closed_form():
    rng = np.random.default_rng(3)
    reference = rng.normal(37.5e-6, 0.1e-6, size=(2, 400))
    shifted = reference + 2e-9  # a uniform 2 nm offset
    comparison = compare_features(_results(shifted), _results(reference))
    np.testing.assert_allclose(comparison.mean_shift, 2e-9, rtol=1e-6)
    np.testing.assert_allclose(comparison.sigma_shift, 0.0, atol=1e-15)
    np.testing.assert_allclose(comparison.max_paired_difference, 2e-9, rtol=1e-6)
    expected_error = 1.96 * reference.std(axis=1, ddof=1) / np.sqrt(400)
    np.testing.assert_allclose(comparison.sampling_error, expected_error, rtol=1e-12)
    assert np.all(comparison.ks_pvalue > 0.5)  # 2 nm on a 100 nm spread: the same distribution


def test_failed_runs_are_left_out_of_both():
    reference = np.tile(np.linspace(1e-6, 2e-6, 50), (2, 1))
    candidate = _results(reference.copy())
    candidate["status"][0, :5] = "diverged"
    comparison = compare_features(candidate, _results(reference))
    assert int(comparison.n.sel(dataset="ds2")) == 45
    assert float(comparison.mean_shift.sel(dataset="ds2")) == pytest.approx(0.0, abs=1e-18)
