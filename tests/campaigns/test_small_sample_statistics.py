"""Known answers of the small-sample rules of the analysis (issue 33): the order-statistic floor of the detection
threshold, the first-order index's chance level against the number of runs, and analysis.nc in CF form.

Coverage tolerances are binomial: a count K of R seeded repetitions whose true probability is p lies below the
0.1 % quantile of Binomial(R, p) with probability 0.001, so a test that asks K to reach that quantile of the
nominal rate fails by chance once in a thousand seeds (and, seeded, never from one run to the next).
"""

from __future__ import annotations

import json
import math

import netCDF4
import numpy as np
import pytest
import xarray as xr
from scipy import stats

from campaigns.analysis.campaign_analysis import analysis_dataset, analyze, summary
from campaigns.analysis.settings import MIN_OK_RUNS
from campaigns.runner.files import CONVENTIONS
from campaigns.statistics import sensitivity
from campaigns.statistics.intervals import mean_interval, quantile_interval, std_interval
from campaigns.statistics.order_statistics import (
    MIN_DETECTION_RUNS,
    detection_run_floor,
    min_runs_for_quantile_bound,
    quantile_bound_rank,
    quantile_interval_min_runs,
    quantile_interval_ranks,
)

# --- the detection threshold's floor ------------------------------------------------------------------------------


def test_the_detection_floor_is_the_closed_form_of_the_order_statistics():
    """P(X_(r) >= xi_q) = P(Binomial(n, q) <= r - 1), written out with math.comb; the sample maximum bounds the 95 %
    quantile at 95 % from 59 runs on (1 - 0.95^59 = 0.9515, 1 - 0.95^58 = 0.9490)."""

    def coverage(n, r, q):
        return sum(math.comb(n, k) * q**k * (1 - q) ** (n - k) for k in range(r))

    assert min_runs_for_quantile_bound(0.95, 0.95) == 59 == MIN_DETECTION_RUNS == detection_run_floor()
    assert 1 - 0.95**59 >= 0.95 > 1 - 0.95**58
    assert min_runs_for_quantile_bound(0.9, 0.9) == 22 and min_runs_for_quantile_bound(0.99, 0.95) == 299
    assert detection_run_floor(0.1, 0.8, 0.9) == 22 and detection_run_floor(0.05, 0.99, 0.95) == 299
    for n in (59, 60, 100, 200, 1000):
        r = quantile_bound_rank(n, 0.95, 0.95)
        assert coverage(n, r, 0.95) >= 0.95 > coverage(n, r - 1, 0.95), n
    assert quantile_bound_rank(59, 0.95, 0.95) == 59 and quantile_bound_rank(58, 0.95, 0.95) is None
    assert quantile_bound_rank(200, 0.95, 0.95) == 196


@pytest.mark.parametrize("n", [59, 200])
def test_the_order_statistic_bound_covers_the_quantile_at_its_nominal_rate(n):
    """R = 20000 seeded normal references of n runs: X_(r) (rank from quantile_bound_rank) lies above the true 95 %
    quantile (1.645) in a fraction K/R whose expectation is P(Binomial(n, 0.95) <= r - 1) >= 0.95 (0.9515 at 59 runs,
    0.9740 at 200). K must reach the 0.1 % quantile of Binomial(R, 0.95) and stay within the 0.1-99.9 % band of its
    exact rate (the bound is neither short nor looser than the closed form)."""
    repetitions, rng = 20_000, np.random.default_rng(n)
    r = quantile_bound_rank(n, 0.95, 0.95)
    bound = np.sort(rng.standard_normal((repetitions, n)), axis=1)[:, r - 1]
    covered = int((bound >= stats.norm.ppf(0.95)).sum())
    exact = stats.binom.cdf(r - 1, n, 0.95)
    assert covered >= stats.binom.ppf(0.001, repetitions, 0.95)
    assert stats.binom.ppf(0.001, repetitions, exact) <= covered <= stats.binom.ppf(0.999, repetitions, exact)


def test_the_old_floor_did_not_bound_the_threshold():
    """At 20 runs the sample maximum covers the 95 % quantile in 1 - 0.95^20 = 64 % of references, and the threshold
    the analysis uses (numpy's interpolated 95 % quantile, 0.05 of the way from X_(19) to X_(20)) in about 26 %
    (P(Binomial(20, 0.95) <= 18) = 0.264): far below 95 %."""
    repetitions, rng = 20_000, np.random.default_rng(20)
    samples = rng.standard_normal((repetitions, 20))
    xi = stats.norm.ppf(0.95)
    maximum = int((samples.max(axis=1) >= xi).sum())
    threshold = int((np.quantile(samples, 0.95, axis=1) >= xi).sum())
    assert stats.binom.ppf(0.001, repetitions, 1 - 0.95**20) <= maximum <= stats.binom.ppf(0.999, repetitions,
                                                                                         1 - 0.95**20)
    assert threshold < maximum < stats.binom.ppf(0.001, repetitions, 0.95)


# --- means, standard deviations and quantiles at any n (issue 42) -------------------------------------------------

#: Seeded repetitions of each coverage test: the binomial 0.1-99.9 % band of a 95 % rate is then about +-1 point.
REPETITIONS = 4000


def _within_band(covered: int, rate: float) -> bool:
    """K of REPETITIONS covered, with true rate ``rate``: inside the 0.1-99.9 % band of Binomial(R, rate)."""
    return stats.binom.ppf(0.001, REPETITIONS, rate) <= covered <= stats.binom.ppf(0.999, REPETITIONS, rate)


@pytest.mark.parametrize("n", [2, 3, 8, 20])
def test_the_mean_and_sd_intervals_cover_a_normal_truth_at_their_stated_rate(n):
    """Normal samples (mean 5, sd 2): the t interval holds the true mean, the chi-square interval the true sd, in
    95 % of seeded samples at every n from 2 on (both exact for a normal feature), within the binomial band."""
    rng = np.random.default_rng(1000 + n)
    samples = rng.normal(5.0, 2.0, (REPETITIONS, n))
    means = np.array([mean_interval(y) for y in samples])
    stds = np.array([std_interval(y) for y in samples])
    assert _within_band(int(((means[:, 1] <= 5.0) & (5.0 <= means[:, 2])).sum()), 0.95)
    assert _within_band(int(((stds[:, 1] <= 2.0) & (2.0 <= stds[:, 2])).sum()), 0.95)
    assert (means[:, 1] < means[:, 0]).all() and (stds[:, 1] < stds[:, 0]).all() and (stds[:, 0] < stds[:, 2]).all()


def test_the_mean_and_sd_intervals_closed_forms_and_edges():
    """n = 2, values 0 and 2: mean 1, s = sqrt(2); t(0.975, 1) = 12.706 gives 1 +- 12.706; the chi-square interval is
    s / sqrt(chi2(0.975, 1)) = s / 2.2414 and s / sqrt(chi2(0.025, 1)) = s / 0.031338. One value: its mean, no
    interval; none: NaN. A constant sample: an interval of zero width."""
    mean, low, high = mean_interval([0.0, 2.0])
    assert mean == 1.0 and high - mean == pytest.approx(12.7062, rel=1e-5) and mean - low == pytest.approx(12.7062,
                                                                                                            rel=1e-5)
    s, low, high = std_interval([0.0, 2.0])
    assert s == pytest.approx(math.sqrt(2.0)) and low == pytest.approx(math.sqrt(2.0) / 2.2414, rel=1e-4)
    assert high == pytest.approx(math.sqrt(2.0) / 0.031338, rel=1e-4)
    assert mean_interval([3.0])[0] == 3.0 and np.isnan(mean_interval([3.0])[1:]).all()
    assert np.isnan(mean_interval([])).all() and np.isnan(std_interval([3.0])).all()
    assert mean_interval([4.0] * 5) == (4.0, 4.0, 4.0) and std_interval([4.0] * 5) == (0.0, 0.0, 0.0)


def test_the_quantile_interval_ranks_are_the_binomial_closed_form():
    """P(X_(l) <= xi_q <= X_(u)) = P(l <= Binomial(n, q) <= u - 1), written out with math.comb: at least 95 %, with at
    most 2.5 % in each tail, and neither rank can move inwards. Floors: 6 runs for the median (1 - 2 0.5^6 = 0.969 with
    the extremes; at 5 runs a tail holds 3.1 %), 72 for the 5 % and 95 % quantiles (0.95^72 = 0.0249 <= 0.025 <
    0.95^71)."""

    def cdf(k, n, q):
        return sum(math.comb(n, j) * q**j * (1 - q) ** (n - j) for j in range(k + 1))

    assert [quantile_interval_min_runs(q) for q in (0.05, 0.5, 0.95)] == [72, 6, 72]
    assert quantile_interval_ranks(5, 0.5) is None and quantile_interval_ranks(6, 0.5) == (1, 6)
    assert quantile_interval_ranks(71, 0.95) is None and quantile_interval_ranks(72, 0.95) == (64, 72)
    for n, q in ((6, 0.5), (8, 0.5), (20, 0.5), (59, 0.5), (72, 0.95), (100, 0.05), (200, 0.95)):
        low, high = quantile_interval_ranks(n, q)
        below, above = cdf(low - 1, n, q), 1.0 - cdf(high - 1, n, q)  # the two tails: xi_q outside the interval
        assert below <= 0.025 and above <= 0.025, (n, q)
        assert cdf(low, n, q) > 0.025 and 1.0 - cdf(high - 2, n, q) > 0.025, (n, q)  # either rank moved in fails
    assert min(quantile_interval_min_runs(q) for q in (0.05, 0.5, 0.95)) == 6 < MIN_OK_RUNS


@pytest.mark.parametrize(("n", "q"), [(8, 0.5), (72, 0.95), (100, 0.05)])
def test_the_quantile_interval_covers_at_its_closed_form_rate(n, q):
    """Seeded normal samples: [X_(l), X_(u)] holds the true quantile in a fraction whose expectation is the binomial
    closed form P(l <= Binomial(n, q) <= u - 1) >= 0.95 (the ranks are discrete, so the rate exceeds 0.95: 0.992 for
    the median of 8); the count stays inside that rate's binomial band. Below the floor the bounds are NaN."""
    rng = np.random.default_rng(int(n / q))
    truth = stats.norm.ppf(q)
    found = np.array([quantile_interval(y, q) for y in rng.standard_normal((REPETITIONS, n))])
    low, high = quantile_interval_ranks(n, q)
    exact = stats.binom.cdf(high - 1, n, q) - stats.binom.cdf(low - 1, n, q)
    assert exact >= 0.95 and _within_band(int(((found[:, 1] <= truth) & (truth <= found[:, 2])).sum()), exact)
    assert np.isnan(quantile_interval(rng.standard_normal(quantile_interval_min_runs(q) - 1), q)[1:]).all()


def test_eight_runs_give_means_with_intervals_and_no_verdict():
    """The README's quicker look (--runs 8): the analysis gives every data set's mean, sd and median with their
    intervals (the two data sets' means, 10 noise sd apart, are told apart by disjoint intervals), the 5 % and 95 %
    quantiles without bounds (n too small), flags the data set (data_sufficient = 0), and withholds correlations,
    detection and the verdict; the summary prints the means with their intervals."""
    results = _results(8, 3, 11)
    results["f"] = results["f"] + xr.DataArray([0.0, 10e-6], dims="dataset")  # d1 10 µm above d0 (sd about 1.5 µm)
    a = analysis_dataset(results, n_boot=20, sensitivity_boot=10)
    assert (a["data_sufficient"] == 0).all() and np.isnan(a["spearman"]).all()
    assert np.isnan(a["detection_probability"]).all() and (a["requirement_verdict"] == "insufficient data").all()
    for name in ("feature_mean", "feature_std", "feature_mean_ci", "feature_std_ci"):
        assert np.isfinite(a[name]).all(), name
    mean = a["feature_mean_ci"].sel(feature="f")
    assert float(mean.sel(dataset="d0", bound="upper")) < float(mean.sel(dataset="d1", bound="lower"))
    median = a["feature_quantile_ci"].sel(feature="f", quantile_probability=0.5)
    assert np.isfinite(median).all() and np.isnan(a["feature_quantile_ci"].sel(quantile_probability=0.95)).all()
    assert a["feature_quantile_min_runs"].values.tolist() == [72, 6, 72]
    for d in ("d0", "d1"):
        values = results["f"].sel(dataset=d).values
        np.testing.assert_allclose(float(a["feature_mean"].sel(dataset=d, feature="f")), values.mean(), rtol=1e-12)
        np.testing.assert_allclose(float(a["feature_quantile"].sel(dataset=d, feature="f", quantile_probability=0.5)),
                                   np.median(values), rtol=1e-12)
    [warning] = summary(a)[1]
    assert warning.startswith("f: insufficient data in all 2 data sets (8 ok runs each): fewer than 20 ok runs")
    assert "their means (flagged): d0 " in warning and "(95 % interval " in warning and "n = 8)" in warning


# --- the first-order index at small n -----------------------------------------------------------------------------

#: Tolerances of Table 9.5 that the thesis specs sample (the count the chance level is measured for).
TOLERANCES = 38


def _additive_sample(n: int, rng: np.random.Generator):
    """y = 2 x1 + x2 + e with 38 inert inputs beside them, truncated-Gaussian inputs (like Table 9.5's) and unit
    noise: S1 = b^2 var(x) / (5 var(x) + 1), i.e. 0.664 and 0.166, and 0 for the inert ones."""
    X = stats.truncnorm.rvs(-3, 3, size=(n, 2 + TOLERANCES), random_state=rng)
    return X, 2.0 * X[:, 0] + X[:, 1] + rng.normal(size=n)


def test_the_first_order_index_of_inert_inputs_against_n_sets_the_minimum_runs():
    """The measurement behind sensitivity.MIN_RUNS, on an additive model with known indices (300 seeded repetitions
    per n). The estimator's bias for an inert input is small (mean within 0.005 of 0 at 150 and 200 runs; standard
    error 0.0003), but the largest of 38 inert indices, which a table of the largest indices shows, averages 0.109 at
    150 runs and 0.083 at 200 (standard error 0.0016): 200 is the first multiple of 50 where it stays below
    0.1. The active inputs are recovered on average (0.664, 0.166; standard error 0.003)."""
    var_x = stats.truncnorm.var(-3, 3)
    truth = np.array([4.0, 1.0]) * var_x / (5.0 * var_x + 1.0)
    largest, bias = {}, {}
    for n in (150, sensitivity.MIN_RUNS):
        rng = np.random.default_rng(n)
        indices = np.array([sensitivity.first_order_index(*_additive_sample(n, rng)) for _ in range(300)])
        largest[n] = indices[:, 2:].max(axis=1).mean()
        bias[n] = indices[:, 2:].mean()
        np.testing.assert_allclose(indices[:, :2].mean(axis=0), truth, atol=0.02)
    assert sensitivity.MIN_RUNS == 200
    assert largest[150] > 0.1 + 0.005 and largest[200] < 0.1 - 0.01
    assert abs(bias[150]) < 0.005 and abs(bias[200]) < 0.005


def test_below_50_runs_the_bias_itself_appears():
    """At 30 runs the Tissot-Prieur correction (lambda = 2M/n = 0.67) no longer centres an inert index on 0: its mean
    is about +0.07 (permutation null, 4000 seeded permutations; standard error 0.005)."""
    rng = np.random.default_rng(30)
    y = rng.normal(size=30)
    signals = np.array([y[rng.permutation(30)][sensitivity._easi_order(30)] for _ in range(4000)])
    assert sensitivity._first_order_of_signals(signals).mean() > 0.04


def test_unresolved_flags_known_answers():
    index = np.array([0.52, 0.10, math.nan, 0.30])
    ci = np.array([[-0.30, 0.51], [0.0, 0.2], [math.nan, math.nan], [0.35, 0.6]])
    assert sensitivity.unresolved(index, ci, 250).tolist() == [2, 0, 0, 2]  # the ds6 row of issue 33, and one below
    assert sensitivity.unresolved(index, ci, 199).tolist() == [3, 1, 1, 3]
    assert sensitivity.unresolved(index[1:2], ci[1:2], sensitivity.MIN_RUNS).tolist() == [0]


def _results(n: int, parameters: int, seed: int) -> xr.Dataset:
    """A results.nc-like dataset of two data sets: feature f = 2 p0 + noise [m], the other parameters inert."""
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1, 1, (parameters, 2, n))
    f = 2e-6 * X[0] + 1e-6 * rng.normal(size=(2, n))
    data = {"f": (("dataset", "run"), f, {"role": "feature", "units": "m"}),
            "status": (("dataset", "run"), np.full((2, n), "ok", dtype=object)),
            "condition_backlash": ("dataset", np.array([0.0, 5e-6]), {"units": "m"})}
    data |= {f"p{j}": (("dataset", "run"), X[j], {"role": "sampled", "units": "1"}) for j in range(parameters)}
    spec = {"spec": {"observability": {"sweep": ["d0", "d1"]}}}
    return xr.Dataset(data, coords={"dataset": ["d0", "d1"], "run": np.arange(n)},
                      attrs={"spec_json": json.dumps(spec), "title": "test campaign", "history": "made by a test"})


def test_no_printed_index_lies_outside_its_interval_and_the_flags_say_why():
    """200 runs, 40 parameters (39 inert): at the minimum the indices are resolved, except where the estimate fell
    outside its own percentile interval (1-6 % of inert inputs): flag 2 there. Every unflagged index lies inside its
    interval. At 100 runs every index is flagged (1), the intervals still given."""
    a = analysis_dataset(_results(200, 40, 7), n_boot=20, sensitivity_boot=100)
    flag = a["first_order_index_flag"].values
    index, ci = a["first_order_index"].values, a["first_order_index_ci"].values
    outside = (flag & sensitivity.OUTSIDE_INTERVAL) > 0
    assert outside.sum() >= 1 and not (flag & sensitivity.BELOW_MIN_RUNS).any()
    assert ((index[outside] < ci[..., 0][outside]) | (index[outside] > ci[..., 1][outside])).all()
    given = flag == 0
    assert ((ci[..., 0][given] <= index[given]) & (index[given] <= ci[..., 1][given])).all()
    assert index[..., 0].min() > 0.5  # the active parameter: S1 = (4/3)/(4/3 + 1) = 0.57
    small = analysis_dataset(_results(100, 5, 8), n_boot=20, sensitivity_boot=50)
    assert (small["first_order_index_flag"] & sensitivity.BELOW_MIN_RUNS).all()
    assert np.isfinite(small["first_order_index_ci"]).all()


# --- analysis.nc in CF form ---------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def analysis_file(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cf")
    results = _results(60, 3, 9)
    results["g"] = (("dataset", "run"), results["f"].values * 1e6, {"role": "feature", "units": "N m"})
    results.to_netcdf(folder / "results.nc", engine="netcdf4")
    return analyze(folder / "results.nc", n_boot=20, sensitivity_boot=10)


def test_every_numeric_variable_has_units_or_is_a_flag(analysis_file):
    """Units on every numeric variable; features of several units (m and N m here) are named per feature by the
    feature_units coordinate; flags carry numeric flag_values or flag_masks of their own type and one
    space-separated meaning each."""
    with xr.open_dataset(analysis_file, engine="netcdf4") as a:
        for name, variable in a.data_vars.items():
            if variable.dtype.kind not in "iuf":
                continue
            attrs = variable.attrs
            flags = attrs.get("flag_values", attrs.get("flag_masks"))
            if flags is not None:
                assert np.asarray(flags).dtype == variable.dtype, name
                assert len(attrs["flag_meanings"].split(" ")) == len(np.atleast_1d(flags)), name
                continue
            assert "units" in attrs or "feature_units" in attrs.get("comment", ""), name
        assert a["feature_units"].values.tolist() == ["m", "N m"]
        assert a["first_order_index_flag"].attrs["flag_meanings"] == "below_minimum_runs estimate_outside_interval"
        assert a["minimum_detectable_status"].attrs["flag_meanings"] == (
            "insufficient_data resolved between_adjacent_levels beyond_sweep")


def test_coordinates_are_labels_without_fill_values_and_the_file_says_what_it_is(analysis_file):
    with netCDF4.Dataset(analysis_file) as nc:
        for name in ("dataset", "feature", "parameter", "bound", "status", "sweep_point", "reference"):
            variable = nc[name]
            assert variable.dtype == np.dtype("S1") and len(variable.dimensions) == 2, name  # CF 6.1 labels
            assert "_FillValue" not in variable.ncattrs(), name
        assert nc.Conventions == CONVENTIONS and nc.title.startswith("Analysis of test campaign")
        lines = nc.history.splitlines()
        assert (
            lines[0] == "made by a "
                        "test" and lines[1].endswith(": campaigns.analysis.campaign_analysis.analyze(results.nc)")
        )
        assert nc.min_detection_runs == 59 and nc.first_order_min_runs == sensitivity.MIN_RUNS
    with xr.open_dataset(analysis_file, engine="netcdf4") as a:  # and xarray reads the labels back as coordinates
        assert a["dataset"].values.tolist() == ["d0", "d1"] and float(a["n_used"].sel(dataset="d1", feature="f")) == 60


def test_the_cf_compliance_checker_finds_no_high_priority_issue(analysis_file):
    """The IOOS compliance checker (CF 1.8): no failed high-priority check, and no check that crashes (string
    coordinate variables used to crash its monotonicity check)."""
    pytest.importorskip("compliance_checker")
    from compliance_checker.base import BaseCheck
    from compliance_checker.suite import CheckSuite

    suite = CheckSuite()
    suite.load_all_available_checkers()
    groups, errors = suite.run_all(suite.load_dataset(str(analysis_file)), ["cf:1.8"])["cf:1.8"]

    def failed(result) -> bool:
        value = result.value
        return value[0] < value[1] if isinstance(value, tuple) else value is False

    assert [(r.name, r.msgs) for r in groups if r.weight == BaseCheck.HIGH and failed(r)] == []
    assert errors == {}


# --- scripts/findings_tables.py prints what analysis.nc resolves ----------------------------------------------------


def _findings_tables():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).parents[2] / "scripts" / "findings_tables.py"
    spec = importlib.util.spec_from_file_location("findings_tables", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_findings_tables_print_the_interval_only_where_the_index_is_withheld(capsys):
    results = _results(100, 3, 10)
    a = analysis_dataset(results, n_boot=20, sensitivity_boot=50)
    _findings_tables().tolerance_table(results, a)
    lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| d0 | f | ")]
    assert len(lines) == 3 and lines[0].startswith("| d0 | f | p0 | – (")  # ranked by the lower bound: p0 first
    assert all(", interval only: 100 ok runs < 200" in line and line.split(" | ")[4].startswith("(") for line in lines)
    # p2's estimate also fell outside its own interval (this sample), and the line says so
    assert lines[1].startswith("| d0 | f | p2 | – (") and lines[1].endswith(
        "100 ok runs < 200; the estimate fell outside its own interval | (0.000 – 0.682) | -0.21 | -0.06 |")
    a["first_order_index_flag"][:] = 0
    a["first_order_index"].loc[dict(dataset="d0", feature="f", parameter="p0")] = 0.57
    _findings_tables().tolerance_table(results, a)
    [line] = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| d0 | f | p0 |")]
    assert line.startswith("| d0 | f | p0 | 0.57 (")


def test_a_preload_sweep_prints_its_levels_not_the_interval_variables(capsys):
    # the analysis of a preload-loss sweep holds two sweep_ variables over sweep_point besides the swept quantity
    # (the detection probability and its interval); the table must label the columns with the preload loss
    points = ["p1000", "p800", "p600"]
    analysis = xr.Dataset(
        {
            "sweep_detection_probability": (("feature", "sweep_point"), np.array([[0.05, 0.5, 1.0]])),
            "sweep_detection_probability_ci": (("feature", "sweep_point", "bound"), np.zeros((1, 3, 2))),
            "sweep_preload_loss": (("sweep_point",), np.array([0.0, 200.0, 400.0])),
            "requirement_statement": (("feature",), np.array(["not met: between 200 and 400 N"], dtype=object)),
        },
        coords={"feature": ["drag_torque_feature"], "sweep_point": points, "bound": ["lower", "upper"]},
        attrs={"requirement_units": "N"},
    )
    _findings_tables().observability(analysis)
    out = capsys.readouterr().out
    assert "| feature | p1000 (0 N) | p800 (200 N) | p600 (400 N) |" in out
    assert "| drag_torque_feature | 0.05 | 0.50 | 1.00 |" in out
