"""The run model is one stated contract (campaigns.runner.runs.RunModel) that both models implement, and the
analysis is a composer of analyses that each own their variables (issue 40)."""

from __future__ import annotations

import inspect

import pytest
import xarray as xr

from campaigns.analysis.campaign_analysis import ANALYSES, analysis_dataset
from campaigns.analysis.settings import AnalysisSettings
from campaigns.runner.catalog import Catalog, StaticCatalog
from campaigns.runner.runs import RunModel
from campaigns.runner.synthetic import SYNTHETIC_CATALOG, SyntheticModel, synthetic_run


def _members(protocol) -> set[str]:
    """The attributes and methods a protocol states (not those every object has)."""
    methods = {name for name, value in vars(protocol).items() if inspect.isfunction(value)}
    return set(protocol.__annotations__) | methods


def test_both_run_models_implement_every_member_of_the_protocol():
    from campaigns.bench.adapter import simulate_run

    members = _members(RunModel)
    assert {"lanes", "typical_run_seconds", "compiles", "__call__", "run_group", "warm_up", "signals",
            "results_attributes", "margin_variables"} <= members
    for model in (simulate_run, synthetic_run, SyntheticModel(delay=0.1)):
        missing = [name for name in members if not hasattr(model, name)]
        assert not missing, (type(model).__name__, missing)
    assert simulate_run.lanes > 1 and simulate_run.compiles and simulate_run.typical_run_seconds > 0
    assert synthetic_run.lanes == 1 and not synthetic_run.compiles and synthetic_run.typical_run_seconds is None


def test_both_catalogs_implement_every_member_of_the_protocol():
    from campaigns.bench.adapter import BenchCatalog

    members = _members(Catalog)
    for catalog in (BenchCatalog(), SYNTHETIC_CATALOG):
        assert not [name for name in members if not hasattr(catalog, name)], type(catalog).__name__
    assert StaticCatalog(parameters={}, conditions={}, scene_names=()).support_checks(None) == ([], [])


def test_a_bad_setting_is_refused_before_any_analysis_runs():
    with pytest.raises(ValueError, match="min_ok_runs = 2: must be at least 3"):
        AnalysisSettings(min_ok_runs=2)
    assert AnalysisSettings(min_ok_runs=80).detection_runs == 80  # never below the floor of every statistic
    assert AnalysisSettings().detection_runs == 59  # the order-statistic floor at 5 % / 95 % / 95 %


def test_the_composer_keeps_every_variable_of_every_analysis_and_no_two_analyses_write_the_same(reference_results):
    with xr.open_dataset(reference_results) as handle:
        results = handle.load()
    settings = AnalysisSettings(n_boot=50, sensitivity_boot=20)
    parts = {analysis.__name__: analysis(results, settings) for analysis in ANALYSES}
    owners: dict[str, str] = {}
    for name, part in parts.items():
        for variable in part.data_vars:
            assert variable not in owners, f"{variable} written by {owners.get(variable)} and {name}"
            owners[variable] = name
    combined = analysis_dataset(results, n_boot=50, sensitivity_boot=20)
    assert set(combined.data_vars) == set(owners)
    for variable, name in owners.items():  # the composer changes nothing of what an analysis computed
        assert combined[variable].variable.identical(parts[name][variable].variable), variable
