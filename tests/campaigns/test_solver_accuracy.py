"""Campaign-level comparison of solver configurations: shifts, KS distance and the sampling-error line."""

import numpy as np
import pytest
import xarray as xr

from app.studies.charts import campaign_accuracy_chart
from campaigns.comparison import compare_features


def _results(values):
    status = np.full(values.shape, "ok", dtype=object)
    return xr.Dataset({"backlash_feature": (("dataset", "run"), values), "status": (("dataset", "run"), status)},
                      coords={"dataset": ["ds2", "ds5"], "run": np.arange(values.shape[1])})


def test_compare_features_closed_form(tmp_path):
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
    chart = comparison.expand_dims(candidate=["test"])
    chart.attrs["reference"] = "fine"
    campaign_accuracy_chart(chart, tmp_path / "campaign_accuracy.png")
    assert (tmp_path / "campaign_accuracy.png").stat().st_size > 10_000


def test_failed_runs_are_left_out_of_both():
    reference = np.tile(np.linspace(1e-6, 2e-6, 50), (2, 1))
    candidate = _results(reference.copy())
    candidate["status"][0, :5] = "diverged"
    comparison = compare_features(candidate, _results(reference))
    assert int(comparison.n.sel(dataset="ds2")) == 45
    assert float(comparison.mean_shift.sel(dataset="ds2")) == pytest.approx(0.0, abs=1e-18)
