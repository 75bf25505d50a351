"""Execution: worker-count invariance, failure isolation, the chunk-size rule."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import xarray as xr
from campaign_helpers import SYNTHETIC_SPEC, data_variables, load, write_spec

import campaigns
from campaigns.runner import execution
from campaigns.runner.execution import (
    BALANCE_CHUNKS,
    OVERHEAD_TARGET,
    TASK_OVERHEAD,
    Cluster,
    build_request,
    chunk_size,
    run_chunk,
)
from campaigns.runner.runs import execute, kill_grace
from campaigns.runner.sampling import sample
from campaigns.runner.sandbox import Sandbox
from campaigns.runner.storage import CampaignError
from campaigns.runner.synthetic import SyntheticModel, synthetic_run

FAULTS = {("ds2", 3): "raise", ("ds4", 1): "nan", ("ds6", 2): "hang", ("ds5", 0): "diverge"}


def test_results_do_not_depend_on_the_worker_count(reference_results, single_worker_results):
    with xr.open_dataset(reference_results) as two, xr.open_dataset(single_worker_results) as single:
        assert (two["status"] == "ok").all()
        xr.testing.assert_identical(data_variables(single), data_variables(two))


def test_failed_runs_are_recorded_and_the_campaign_goes_on(tmp_path):
    """A healthy synthetic run takes milliseconds; the 3 s budget leaves a margin of 100x or more even on a
    saturated machine (a fresh sandbox's start-up is not charged to its run), so only the hang times out."""
    spec = load(write_spec(tmp_path, "runs_per_dataset = 8\n[execution]\ntimeout = 3.0\n"))
    path = campaigns.run_campaign(spec, tmp_path / "out", workers=2, progress=False,
                                  run_function=SyntheticModel(faults=FAULTS))
    with xr.open_dataset(path) as ds:
        status = ds["status"].to_pandas()
        reason = ds["failure_reason"].to_pandas()
        assert status.size == 4 * 8  # every run has a record
        assert status.loc["ds2", 3] == "error" and "RuntimeError: injected failure" in reason.loc["ds2", 3]
        assert status.loc["ds4", 1] == "failed" and "backlash_feature is not finite" in reason.loc["ds4", 1]
        assert status.loc["ds6", 2] == "timeout" and "killed after" in reason.loc["ds6", 2]
        assert status.loc["ds5", 0] == "diverged" and reason.loc["ds5", 0] == "injected divergence"
        assert float(ds["t_reached"].sel(dataset="ds5", run=0)) == 0.5
        assert math.isnan(float(ds["t_reached"].sel(dataset="ds6", run=2)))
        assert (status == "ok").sum().sum() == 4 * 8 - len(FAULTS)
        assert (reason.values[status.values == "ok"] == "").all()
        ok = ds["backlash_feature"].where(ds["status"] == "ok")

    analysis = xr.open_dataset(campaigns.analyze(path, min_ok_runs=3))  # 7 ok runs per data set: below MIN_OK_RUNS
    with analysis:
        excluded = analysis["n_excluded"].sel(feature="backlash_feature").to_pandas()
        assert excluded.to_dict() == {"ds2": 1, "ds4": 1, "ds6": 1, "ds5": 1}
        assert int(analysis["n_status"].sel(dataset="ds6", status="timeout")) == 1
        np.testing.assert_allclose(analysis["feature_mean"].sel(feature="backlash_feature"), ok.mean("run"), rtol=1e-12)
        assert "status 'ok'" in analysis.attrs["selection"]


def test_in_process_isolation_records_failures_too(tmp_path):
    """``isolation = "none"``: exceptions and NaN are still records (no kill fallback there)."""
    spec = load(write_spec(tmp_path, "runs_per_dataset = 4\n"))
    samples = sample(spec)
    requests = [build_request(spec, samples, 0, i) for i in range(4)]
    records = run_chunk(SyntheticModel(faults={("ds2", 1): "raise", ("ds2", 2): "nan"}), requests, "none")
    assert [r["status"] for r in records] == ["ok", "error", "failed", "ok"]
    assert [r["run_index"] for r in records] == [0, 1, 2, 3]
    malformed = execute(lambda request: None, requests[0])  # a broken run function is a record too
    assert malformed["status"] == "error" and malformed["failure_reason"].startswith("AttributeError")


def test_sandbox_survives_a_crash_and_a_hang(tmp_path):
    """The child process dies or is killed; the records say why and the next run gets a fresh child.

    The 2 s budget is ~1000x a healthy run; the run after the kill starts in a cold child, whose start-up
    is not charged to it, so it is ok however loaded the machine is."""
    spec = load(write_spec(tmp_path, "runs_per_dataset = 3\n[execution]\ntimeout = 2.0\n"))
    samples = sample(spec)
    model = SyntheticModel(faults={("ds2", 0): "crash", ("ds2", 1): "hang"})
    sandbox = Sandbox()
    try:
        records = [sandbox.run(model, build_request(spec, samples, 0, i)) for i in range(3)]
    finally:
        sandbox.close()
    assert [r["status"] for r in records] == ["error", "timeout", "ok"]
    assert records[0]["failure_reason"] == "run process died (exit code 3)"
    assert records[1]["wall_time"] >= 2.0 + kill_grace(2.0)  # a lower bound: the kill never comes early


def test_chunk_size_rule():
    assert chunk_size(None, 1000, 2) == 1  # pilot
    slow = 10.0  # s per run: overhead is negligible, one run per chunk
    assert chunk_size(slow, 1000, 2) == 1
    fast = 1e-3
    c = chunk_size(fast, 10**6, 2)
    assert TASK_OVERHEAD / (c * fast) <= OVERHEAD_TARGET  # overhead bound met
    assert chunk_size(fast, 80, 2) == math.ceil(80 / (BALANCE_CHUNKS * 2))  # load balance wins at the tail
    assert chunk_size(1e-9, 10**12, 1) * 1e-9 <= 60.0


def test_a_subset_of_data_sets_runs_with_the_streams_of_its_place_in_the_spec(tmp_path, reference_results):
    """``datasets``: only those run, each with the parameters and noise it has in the whole campaign (the fidelity
    audit re-runs the data sets it needs this way), on a cluster the caller owns and keeps open."""
    spec = load(SYNTHETIC_SPEC)
    names = [d.name for d in spec.datasets]
    kept = names[1:3]
    announced = []
    with Cluster(1, announce=lambda stage, message: announced.append(stage)) as cluster:
        path = execution.run_campaign(spec, tmp_path / "subset", run_function=synthetic_run, cluster=cluster,
                                      datasets=kept, progress=False)
        assert cluster.started  # left open for its owner
        again = execution.run_campaign(spec, tmp_path / "again", run_function=synthetic_run, cluster=cluster,
                                       datasets=kept[:1], progress=False)
    assert announced.count("cluster start") == 1 and announced.count("cluster stop") == 1
    with xr.open_dataset(path) as subset, xr.open_dataset(reference_results) as whole, xr.open_dataset(again) as one:
        assert list(subset.dataset.values) == kept
        for feature in spec.features:
            np.testing.assert_array_equal(subset[feature].values, whole[feature].sel(dataset=kept).values)
            np.testing.assert_array_equal(one[feature].values, whole[feature].sel(dataset=kept[:1]).values)
        assert json.loads(subset.attrs["dataset_seed_indices"]) == {n: names.index(n) for n in kept}
    with pytest.raises(CampaignError, match="datasets: nope: name one or more of the spec's data sets"):
        execution.run_campaign(spec, tmp_path / "bad", run_function=synthetic_run, datasets=["nope"])

