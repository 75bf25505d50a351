"""The requirement verdict: known answers on synthetic sweeps, bootstrap bounds, insufficient data (analysis.nc and
CLI).

The synthetic sweeps have a Gaussian feature ``f = backlash + N(0, sigma)``. Detection at false-alarm rate
alpha = 5 % with power 95 % then needs a shift of ``(z_0.95 + z_0.95) sigma = 3.29 sigma``: that is the true
minimum detectable backlash of each sweep. Where the bootstrap bounds are two adjacent sweep levels, the sweep
does not resolve the value: the statement gives the bracket and analysis.nc no number.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr
from scipy import stats

from campaigns.analysis.campaign_analysis import analysis_dataset
from campaigns.analysis.settings import MIN_OK_RUNS
from campaigns.statistics.detection import RESOLUTIONS, bootstrap_minimum_detectable, printed_estimate, sweep_resolution
from campaigns.statistics.order_statistics import MIN_DETECTION_RUNS

#: The observability spec's sweep levels [m].
LEVELS = (0.0, 0.5e-6, 1e-6, 1.5e-6, 2e-6, 3e-6, 5e-6)
#: Shift detected with probability 95 % at false-alarm rate 5 %, in standard deviations of the feature.
DETECTABLE_SHIFT = 2 * stats.norm.ppf(0.95)


def sweep_results(sigma: float, levels=LEVELS, *, runs: int = 100, ok_runs: int | None = None,
                  seed: int = 0) -> xr.Dataset:
    """A results dataset of a backlash sweep with feature ``f = backlash + N(0, sigma)`` and one inert parameter."""
    rng = np.random.default_rng(seed)
    names = [f"b{k}" for k in range(len(levels))]
    feature = np.asarray(levels)[:, None] + rng.normal(0.0, sigma, (len(levels), runs))
    status = np.full(feature.shape, "ok", dtype=object)
    if ok_runs is not None:
        status[:, ok_runs:], feature[:, ok_runs:] = "error", math.nan
    return xr.Dataset(
        {
            "f": (("dataset", "run"), feature, {"role": "feature", "units": "m"}),
            "p.inert": (("dataset", "run"), rng.uniform(size=feature.shape), {"role": "sampled", "units": "1"}),
            "status": (("dataset", "run"), status),
            "condition_backlash": ("dataset", np.asarray(levels, dtype=float), {"units": "m"}),
        },
        coords={"dataset": names, "run": np.arange(runs)},
        attrs={"spec_json": json.dumps({"spec": {"observability": {"sweep": names}}})},
    )


def verdict_of(analysis: xr.Dataset) -> tuple[str, str, np.ndarray, float]:
    a = analysis.sel(feature="f")
    return (str(a["requirement_verdict"].item()), str(a["requirement_statement"].item()),
            a["minimum_detectable_backlash_ci"].values, float(a["minimum_detectable_backlash"]))


def resolution_of(analysis: xr.Dataset) -> str:
    return RESOLUTIONS[int(analysis["minimum_detectable_status"].sel(feature="f"))]


def test_clearly_met_between_two_adjacent_levels_is_a_bracket():
    # truth 3.29 * 0.1 um = 0.33 um: the 0.5 um data set is detected in every resample, the 0 um one never
    a = analysis_dataset(sweep_results(0.1e-6), n_boot=300)
    verdict, statement, (lower, upper), estimate = verdict_of(a)
    assert verdict == "met" and (lower, upper) == (0.0, 0.5e-6) and math.isnan(estimate)
    assert resolution_of(a) == "between_adjacent_levels"
    assert statement == (
        "met: minimum detectable backlash between the adjacent sweep levels 0 µm (b0) and 0.5 µm (b1) (95 % bootstrap "
        "bounds: above 0 µm (b0), at most 0.5 µm (b1); 100 ok runs per sweep data set, 7 data sets) against the 1 µm "
        "requirement of Table 9.3")


def test_clearly_not_met():
    # truth 3.29 um: detection is far below 95 % at 1.5 um (about 42 %)
    verdict, statement, (lower, upper), estimate = verdict_of(analysis_dataset(sweep_results(1e-6), n_boot=300))
    assert verdict == "not met" and lower >= 1.5e-6 and lower <= 3.29e-6 <= upper and lower <= estimate <= upper
    assert statement.startswith("not met: ")


def test_never_detected_along_the_sweep_is_not_met_with_an_infinite_upper_bound(tmp_path):
    a = analysis_dataset(sweep_results(5e-6), n_boot=300)
    verdict, statement, (lower, upper), estimate = verdict_of(a)
    assert verdict == "not met" and math.isnan(estimate) and lower >= 1e-6 and upper == math.inf
    assert resolution_of(a) == "beyond_sweep"
    assert statement.startswith("not met: minimum detectable backlash above 5 µm (b6), the largest sweep level: "
                                "detection probability below 95 % along the whole sweep (95 % bootstrap bounds: above ")
    assert "possibly beyond the sweep; 100 ok runs" in statement
    path = tmp_path / "analysis.nc"
    analysis_dataset(sweep_results(5e-6), n_boot=50).to_netcdf(path, engine="netcdf4")
    with xr.open_dataset(path, engine="netcdf4") as stored:  # inf and NaN survive the file
        assert stored["minimum_detectable_backlash_ci"].sel(feature="f", bound="upper") == math.inf


def test_a_bracket_straddling_the_requirement_is_undetermined():
    # truth 3.29 * 0.35 um = 1.15 um lies in the gap 0.5-2 um of this coarse sweep: the data cannot say which side
    # of 1 um
    for seed in range(3):
        results = sweep_results(0.35e-6, (0.0, 0.5e-6, 2e-6, 5e-6), seed=seed)
        verdict, statement, (lower, upper), _ = verdict_of(analysis_dataset(results, n_boot=300))
        assert verdict == "undetermined" and (lower, upper) == (0.5e-6, 2e-6)
        assert statement.startswith("undetermined: ")


def test_the_interpolated_estimate_is_neither_a_verdict_nor_printed():
    """0 and 5 um only (the old demo sweep): the interpolation gives 4.7 um, the truth may be anywhere in 0-5 um, so
    the statement and analysis.nc give the bracket, never 4.7 (the replay of "minimum detectable backlash 4.74 µm")."""
    results = sweep_results(0.1e-6, (0.0, 5e-6))
    a = analysis_dataset(results, n_boot=300)
    verdict, statement, (lower, upper), estimate = verdict_of(a)
    assert (lower, upper) == (0.0, 5e-6) and verdict == "undetermined" and math.isnan(estimate)
    assert resolution_of(a) == "between_adjacent_levels"
    assert statement.startswith("undetermined: minimum detectable backlash between the adjacent sweep levels 0 µm (b0) "
                                "and 5 µm (b1) (")
    assert "4.7" not in statement
    np.testing.assert_array_equal(a["minimum_detectable_bracket"].sel(feature="f"), [0.0, 5e-6])
    samples = [results["f"].sel(dataset=n).values for n in results["dataset"].values]
    found = bootstrap_minimum_detectable((0.0, 5e-6), samples, 0, n_boot=300, seed=1)
    assert found["estimate"] == pytest.approx(5e-6 * 0.90 / 0.95) and math.isnan(found["printed"])


def test_a_value_is_printed_where_the_bounds_span_more_than_one_sweep_step():
    """Levels every 0.25 um, sigma 0.5 um (truth 1.64 um), 100 runs: the bootstrap bounds hold several levels, so the
    sweep resolves the value: analysis.nc holds it, the statement prints it rounded at the leading digit of the
    bounds' half-width, and the bounds hold the truth."""
    sigma, levels = 0.5e-6, np.arange(0, 13) * 0.25e-6
    a = analysis_dataset(sweep_results(sigma, levels, seed=5), n_boot=300)
    verdict, statement, (lower, upper), estimate = verdict_of(a)
    inside = levels[(levels > lower) & (levels < upper)]
    assert resolution_of(a) == "resolved" and len(inside) >= 1
    assert lower < DETECTABLE_SHIFT * sigma <= upper and lower <= estimate <= upper and verdict == "not met"
    step = 10.0 ** math.floor(math.log10((upper - lower) / 2))  # the statement rounds at the bounds' leading digit
    printed = round(estimate / step) * step
    assert printed == pytest.approx(printed_estimate(estimate, (lower, upper)), abs=1e-15)
    assert statement.startswith(f"not met: minimum detectable backlash {printed * 1e6:.3g} µm (95 % bootstrap bounds")


def test_sweep_resolution_and_the_printed_digits_known_answers():
    levels = np.array([0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0])
    assert sweep_resolution(levels, 1.19, (0.5, 1.5)) == "resolved"  # 1.0 lies inside
    assert sweep_resolution(levels, 0.96, (0.5, 1.0)) == "between_adjacent_levels"
    assert sweep_resolution(levels, 4.74, (0.0, 5.0)) == "resolved"  # 0.5 ... 3 lie inside
    assert sweep_resolution(np.array([0.0, 5.0]), 4.74, (0.0, 5.0)) == "between_adjacent_levels"
    # 5 lies inside, but the bounds are open above: not resolved
    assert sweep_resolution(np.array([0.0, 5.0]), 4.74, (0.0, math.inf)) == "between_adjacent_levels"
    assert sweep_resolution(levels, 0.5, (0.5, 0.5)) == "resolved"  # the estimate is a level
    assert sweep_resolution(levels, math.nan, (5.0, math.inf)) == "beyond_sweep"
    # GUM 7.2.6: to the leading digit of the uncertainty (half-width 0.5 -> 0.1, 300 -> 100, 0.25 -> 0.1, 0.025 -> 0.01)
    assert printed_estimate(1.19, (0.5, 1.5)) == pytest.approx(1.2)
    assert printed_estimate(371.0, (0.0, 600.0)) == pytest.approx(400.0)
    assert printed_estimate(1.834, (1.5, 2.0)) == pytest.approx(1.8)
    assert printed_estimate(1.834, (1.8, 1.85)) == pytest.approx(1.83)
    assert printed_estimate(2.0, (2.0, 2.0)) == 2.0
    # a rounding that would leave the bounds takes a finer digit (the demo's H: 4.3 within 2-40 µm read "0 µm")
    assert printed_estimate(4.3, (2.0, 40.0)) == pytest.approx(4.0)
    rng = np.random.default_rng(7)
    for lower, width in zip(rng.uniform(0, 50, 200), rng.uniform(0.01, 100, 200), strict=True):
        estimate = rng.uniform(lower, lower + width)
        assert lower <= printed_estimate(estimate, (lower, lower + width)) <= lower + width


def test_bounds_contain_the_estimate_and_the_truth_on_a_fine_sweep():
    """Levels every 0.25 um, 1000 runs: the bounds hold the true 3.29 sigma, and the replicates' interpolated minima."""
    sigma, levels = 0.5e-6, np.arange(0, 21) * 0.25e-6
    results = sweep_results(sigma, levels, runs=1000, seed=4)
    samples = [results["f"].sel(dataset=n).values for n in results["dataset"].values]
    found = bootstrap_minimum_detectable(levels, samples, 0, n_boot=300, seed=1)
    lower, upper = found["bounds"]
    assert lower <= found["estimate"] <= upper and lower < DETECTABLE_SHIFT * sigma <= upper
    assert found["bracket"][0] >= lower and found["bracket"][1] <= upper
    assert lower <= np.quantile(found["replicates"], 0.025) and np.quantile(found["replicates"], 0.975) <= upper
    assert upper - lower <= 1e-6  # and they say something: at most four sweep steps apart


def test_the_bootstrap_is_deterministic_in_its_seed():
    results = sweep_results(0.3e-6)
    xr.testing.assert_identical(analysis_dataset(results, n_boot=100, seed=3),
                                analysis_dataset(results, n_boot=100, seed=3))
    samples = [results["f"].sel(dataset=n).values for n in results["dataset"].values]
    same = [bootstrap_minimum_detectable(LEVELS, samples, 0, n_boot=100, seed=s)["replicates"] for s in (7, 7, 8)]
    np.testing.assert_array_equal(same[0], same[1])
    assert not np.array_equal(same[0], same[2])


def test_too_few_ok_runs_is_insufficient_data_with_nan_statistics():
    a = analysis_dataset(sweep_results(0.1e-6, ok_runs=1), n_boot=50)
    verdict, statement, ci, estimate = verdict_of(a)
    assert verdict == "insufficient data" and np.isnan(ci).all() and math.isnan(estimate)
    assert statement.startswith("insufficient data: each of the 7 sweep data sets has 1 ok run; ")
    assert f"at least {MIN_DETECTION_RUNS} per sweep data set are needed" in statement
    assert (a["data_sufficient"] == 0).all() and (a["n_used"] == 1).all() and a.attrs["min_ok_runs"] == MIN_OK_RUNS
    for name in ("feature_std", "feature_mean_ci", "pearson", "spearman", "prcc", "overlap", "detection_probability",
                 "sweep_detection_probability"):
        assert np.isnan(a[name]).all(), name
    assert np.isfinite(a["feature_mean"]).all()  # one run has a mean, flagged, without an interval (issue 42)
    # one data set short is enough: the others keep their statistics, the verdict is withheld
    results = sweep_results(0.1e-6)
    results["status"][2, MIN_OK_RUNS - 1 :] = "error"
    a = analysis_dataset(results, n_boot=50)
    assert list(a["data_sufficient"].sel(feature="f").values) == [1, 1, 0, 1, 1, 1, 1]
    assert str(a["requirement_verdict"].sel(feature="f").item()) == "insufficient data"
    assert (np.isnan(a["spearman"].sel(dataset="b2")).all() and np.isfinite(a["feature_mean"].sel(dataset="b2")).all()
            and np.isfinite(a["spearman"].sel(dataset="b1", feature="f")).any())
    assert f"b2 has {MIN_OK_RUNS - 1} ok runs" in str(a["requirement_statement"].sel(feature="f").item())
    # enough runs for the moments and correlations (20) but not for the detection threshold (59): b2's statistics are
    # computed, no detection probability against it, and the verdict is withheld with the number needed
    results = sweep_results(0.1e-6)
    results["status"][2, MIN_DETECTION_RUNS - 1 :] = "error"
    a = analysis_dataset(results, n_boot=50).sel(feature="f")
    assert list(a["data_sufficient"].values) == [1] * 7 and np.isfinite(a["feature_mean"]).all()
    assert np.isnan(a["detection_probability"].sel(reference="b2")).all()
    assert np.isfinite(a["detection_probability"].sel(dataset="b2", reference="b0"))
    assert np.isnan(a["sweep_detection_probability"].sel(sweep_point="b2"))
    assert str(a["requirement_statement"].item()).startswith(
        f"insufficient data: b2 has {MIN_DETECTION_RUNS - 1} ok runs; at least {MIN_DETECTION_RUNS} per sweep data set "
        "are needed (with fewer, not even the largest run bounds the 95 % quantile that sets the detection threshold "
        "from above with 95 % confidence), so no minimum detectable backlash is estimated")


def test_every_feature_gets_its_own_verdict():
    """A second feature (like backlash_hysteresis beside backlash_feature) with ten times the noise."""
    results = sweep_results(0.1e-6)
    results["g"] = results["condition_backlash"] + 10 * (results["f"] - results["condition_backlash"])
    results["g"].attrs = {"role": "feature", "units": "m"}
    a = analysis_dataset(results, n_boot=100)
    assert list(a["requirement_verdict"].values) == ["met", "not met"]
    assert a["requirement_statement"].sel(feature="g").item().startswith("not met: ")
    assert a["first_order_index"].sizes == {"dataset": 7, "feature": 2, "parameter": 1}


def test_a_spec_without_sweep_has_no_verdict():
    results = sweep_results(0.1e-6)
    results.attrs["spec_json"] = json.dumps({"spec": {"observability": {"sweep": []}}})
    a = analysis_dataset(results, n_boot=50)
    assert str(a["requirement_verdict"].sel(feature="f").item()) == "insufficient data"
    assert "no observability sweep" in str(a["requirement_statement"].sel(feature="f").item())


def test_cli_prints_the_statement_and_the_insufficient_data_sets(tmp_path):
    sweep_results(0.1e-6, ok_runs=1).to_netcdf(tmp_path / "results.nc", engine="netcdf4")
    done = subprocess.run([sys.executable, "-m", "app.cli", "campaign", "analyze", str(tmp_path / "results.nc")],
                          capture_output=True, text=True, timeout=900)  # hang guard
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(tmp_path / "analysis.nc", engine="netcdf4") as a:
        statement = str(a["requirement_statement"].sel(feature="f").item())
        assert str(a["requirement_verdict"].sel(feature="f").item()) == "insufficient data"
    assert f"f: {statement}" in done.stdout.splitlines()
    assert "warning: f: insufficient data in all 7 data sets (1 ok run each)" in done.stderr
