"""Statistics: PRCC against references, ranking recovery, bootstrap coverage, separation, observability."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr
from campaign_helpers import SYNTHETIC_SPEC, load
from scipy import stats

import campaigns
from campaigns.analysis.campaign_analysis import analysis_dataset
from campaigns.analysis.vocabulary import BACKLASH_REQUIREMENT
from campaigns.runner.execution import build_request
from campaigns.runner.files import CONVENTIONS
from campaigns.runner.runs import execute
from campaigns.runner.sampling import sample
from campaigns.runner.synthetic import synthetic_run
from campaigns.statistics.correlation import bootstrap_correlation, prcc
from campaigns.statistics.detection import (
    detection_probability,
    minimum_detectable,
    overlap_coefficient,
    requirement_verdict,
)


def _prcc_by_precision_matrix(X, y):
    """Reference PRCC, independent of the residual regressions: from the inverse P of the rank
    correlation matrix, -P[j, y] / sqrt(P[j, j] P[y, y]) (the partial-correlation identity)."""
    P = np.linalg.inv(np.corrcoef(stats.rankdata(np.column_stack([X, y]), axis=0), rowvar=False))
    return -P[:-1, -1] / np.sqrt(np.diag(P)[:-1] * P[-1, -1])


def test_prcc_matches_the_precision_matrix_identity():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(300, 5))
    y = np.exp(X[:, 0]) + X[:, 1] ** 3 - 0.5 * X[:, 2] + 0.3 * rng.normal(size=300)
    np.testing.assert_allclose(prcc(X, y), _prcc_by_precision_matrix(X, y), atol=1e-10)


def test_prcc_closed_forms():
    rng = np.random.default_rng(2)
    X = rng.normal(size=(500, 3))
    # y strictly monotone in x0 alone: rank(y) = rank(x0), so the residuals coincide and PRCC = 1;
    # the other columns' PRCC is undefined (y's ranks are fully explained): NaN
    result = prcc(X, np.exp(X[:, 0]))
    assert result[0] == pytest.approx(1.0, abs=1e-12) and np.isnan(result[1:]).all()
    # Gaussian y = x0 + x1 + e: population PRCC of x0 is s / sqrt(1 - s^2) with the Spearman
    # correlation s = (6/pi) asin(r/2), r = 1/sqrt(3), and corr(x0, x1) = 0. n = 20000: sd ~ 0.005.
    X = rng.normal(size=(20000, 2))
    y = X.sum(axis=1) + rng.normal(size=20000)
    s = 6 / math.pi * math.asin(1 / (2 * math.sqrt(3)))
    assert prcc(X, y)[0] == pytest.approx(s / math.sqrt(1 - s * s), abs=0.02)
    # a constant column is left out and gets NaN
    X[:, 1] = 1.0
    result = prcc(X, y)
    assert np.isnan(result[1]) and np.isfinite(result[0])


def test_ranking_of_known_monotone_dependences_is_recovered():
    """Synthetic model, 300 runs. Effect spreads (standard deviation of each term of the feature):
    ds2 (80 um, no load): gain 2.7 um > offset 0.58 um > temperature 0.29 um; stiffness acts only under load.
    ds5 (1000 N preload): offset 0.58 um > stiffness 0.33 um > temperature 0.29 um > gain 0.17 um.
    PRCC must rank them exactly and leave the ineffective ones below 0.2; Spearman (marginal, diluted by
    the other terms) must at least find the dominant one."""
    spec = load(SYNTHETIC_SPEC, runs=300)
    samples = sample(spec)
    names = [d.target for d in spec.distributions()]
    cases = {
        0: (["synthetic.gain", "synthetic.offset", "scene.room_temperature"],
            ["synthetic.stiffness", "synthetic.inert", "scene.supply_pressure"]),
        3: (["synthetic.offset", "synthetic.stiffness", "scene.room_temperature", "synthetic.gain"],
            ["synthetic.inert", "scene.supply_pressure"]),
    }
    for d, (effects, inert) in cases.items():
        records = [execute(synthetic_run, build_request(spec, samples, d, i)) for i in range(300)]
        y = np.array([r["features"]["backlash_feature"] for r in records])
        partial = dict(zip(names, prcc(samples[d], y), strict=False))
        marginal = {n: stats.spearmanr(samples[d][:, j], y)[0] for j, n in enumerate(names)}
        assert sorted(effects + inert, key=lambda n: -abs(partial[n]))[: len(effects)] == effects
        assert max(abs(partial[n]) for n in inert) < 0.2
        assert max(effects + inert, key=lambda n: abs(marginal[n])) == effects[0]


def test_bootstrap_intervals_cover_the_truth_at_the_stated_rate():
    """200 seeded trials of n = 100 bivariate normals (rho = 0.5), 95 % percentile intervals.

    The covering count K is Binomial(200, p). The percentile bootstrap of a correlation is known to
    under-cover slightly at this n, so we accept p >= 0.92: K must exceed the 0.1 % quantile of
    Binomial(200, 0.92), and must not exceed the 99.9 % quantile of Binomial(200, 0.99) (not vacuous).
    """
    rho, trials, n = 0.5, 200, 100
    truth = {"pearson": rho, "spearman": 6 / math.pi * math.asin(rho / 2)}
    covered = {"pearson": 0, "spearman": 0}
    rng = np.random.default_rng(2024)
    for trial in range(trials):
        xy = rng.multivariate_normal([0, 0], [[1, rho], [rho, 1]], size=n)
        for method in covered:
            _, lower, upper = bootstrap_correlation(xy[:, 0], xy[:, 1], method, n_boot=500, seed=trial)
            covered[method] += lower <= truth[method] <= upper
    low, high = stats.binom.ppf(0.001, trials, 0.92), stats.binom.ppf(0.999, trials, 0.99)
    for method, k in covered.items():
        assert low < k <= high, f"{method}: {k}/{trials} intervals cover the truth"


def test_bootstrap_estimate_matches_scipy():
    rng = np.random.default_rng(3)
    x, y = rng.normal(size=50), rng.normal(size=50)
    assert bootstrap_correlation(x, y, "pearson", seed=0)[0] == pytest.approx(stats.pearsonr(x, y)[0])
    assert bootstrap_correlation(x, y, "spearman", seed=0)[0] == pytest.approx(stats.spearmanr(x, y)[0])
    assert bootstrap_correlation(x, y, seed=5) == bootstrap_correlation(x, y, seed=5)


def test_separation_measures_against_normal_closed_forms():
    rng = np.random.default_rng(4)
    a, b = rng.normal(0, 1, 40000), rng.normal(1, 1, 40000)
    assert overlap_coefficient(a, b) == pytest.approx(2 * stats.norm.cdf(-0.5), abs=0.03)
    assert overlap_coefficient(a, a) == 1.0
    assert overlap_coefficient(a, a + 100) == 0.0
    # detection at false-alarm rate 5 %: P(N(1,1) > z_0.95) = 1 - Phi(z_0.95 - 1)
    assert detection_probability(a, b, 0.05) == pytest.approx(1 - stats.norm.cdf(stats.norm.ppf(0.95) - 1), abs=0.01)
    assert detection_probability(a, a, 0.05) == pytest.approx(0.05, abs=0.005)
    assert detection_probability(a, -b, 0.05) == pytest.approx(1 - stats.norm.cdf(stats.norm.ppf(0.95) - 1), abs=0.01)


def test_minimum_detectable_interpolates_the_sweep():
    estimate, lower, upper = minimum_detectable([0.0, 5e-6, 40e-6], [0.05, 0.5, 1.0], 0.95)
    assert (estimate, lower, upper) == (pytest.approx(5e-6 + 35e-6 * 0.45 / 0.5), 5e-6, 40e-6)
    # order-free
    assert minimum_detectable([40e-6, 0.0, 5e-6], [1.0, 0.05, 0.95], 0.95) == (pytest.approx(5e-6), 0.0, 5e-6)
    estimate, lower, upper = minimum_detectable([0.0, 5e-6], [0.05, 0.5], 0.95)
    assert math.isnan(estimate) and (lower, upper) == (5e-6, math.inf)
    assert requirement_verdict(0.5e-6, 0.8e-6, BACKLASH_REQUIREMENT) == "met"
    assert requirement_verdict(0.5e-6, 1e-6, BACKLASH_REQUIREMENT) == "met"  # 1 um itself detected
    assert requirement_verdict(5e-6, 40e-6, BACKLASH_REQUIREMENT) == "not met"
    # 1 um not detected: the minimum lies above it
    assert requirement_verdict(1e-6, 1.5e-6, BACKLASH_REQUIREMENT) == "not met"
    assert requirement_verdict(0.0, 5e-6, BACKLASH_REQUIREMENT) == "undetermined"
    assert requirement_verdict(5e-6, math.inf, BACKLASH_REQUIREMENT) == "not met"
    unknown = minimum_detectable([0.0, 5e-6], [0.05, math.nan])[1:]
    assert requirement_verdict(*unknown, BACKLASH_REQUIREMENT) == "undetermined"


def test_analysis_of_the_synthetic_campaign(reference_results, tmp_path):
    """40 runs per data set: enough for the moments and correlations, too few for a detection threshold (59) at the
    default settings; the sweep statistics are checked with the floor lowered to 40."""
    path = campaigns.analyze(reference_results, tmp_path / "default.nc", n_boot=20, sensitivity_boot=10)
    with xr.open_dataset(path) as a:
        assert (a["requirement_verdict"] == "insufficient data").all() and a.attrs["min_detection_runs"] == 59
        assert "each of the 3 sweep data sets has 40 ok runs; at least 59 per sweep data set are needed" in str(
            a["requirement_statement"].sel(feature="backlash_feature").item())
        assert np.isnan(a["detection_probability"]).all() and (a["data_sufficient"] == 1).all()
    path = campaigns.analyze(reference_results, tmp_path / "analysis.nc", n_boot=200, min_detection_runs=40)
    with xr.open_dataset(path) as a:
        assert a.attrs["Conventions"] == CONVENTIONS  # the one CF version of every data file
        assert (a["n_excluded"] == 0).all() and (a["n_used"] == 40).all()
        top = a["prcc"].sel(dataset="ds2", feature="backlash_feature").to_pandas().abs().idxmax()
        assert top == "synthetic.gain"
        ci = a["spearman_ci"].sel(dataset="ds2", feature="backlash_feature", parameter="synthetic.gain")
        assert (ci.sel(bound="lower")
                <= a["spearman"].sel(dataset="ds2", feature="backlash_feature", parameter="synthetic.gain")
                <= ci.sel(bound="upper"))
        assert list(a["sweep_point"].values) == ["ds4", "ds6", "ds2"]
        # 80 um and 5 um are far above the ~1 um spread of the synthetic feature: both detected
        p = a["sweep_detection_probability"].sel(feature="backlash_feature")
        assert float(p.sel(sweep_point="ds2")) == 1.0 and float(p.sel(sweep_point="ds6")) == 1.0
        minimum = a["minimum_detectable_backlash"].sel(feature="backlash_feature")
        # 5 um already detected, 0 um not: the minimum lies between those two adjacent levels and no number is given
        assert math.isnan(float(minimum)) and minimum.attrs["requirement"] == 1e-6
        bracket = a["minimum_detectable_bracket"].sel(feature="backlash_feature")
        assert list(bracket.values) == [0.0, 5e-6]  # the 1 um verdict needs a finer sweep
        assert str(a["requirement_statement"].sel(feature="backlash_feature").item()).startswith(
            "undetermined: minimum detectable backlash between the adjacent sweep levels 0 µm (ds4) and 5 µm (ds6) (")
        # the bootstrap bounds are the same sweep levels (5 um is detected in every resample): no verdict on 1 um
        assert list(a["minimum_detectable_backlash_ci"].sel(feature="backlash_feature").values) == [0.0, 5e-6]
        assert a["requirement_verdict"].sel(feature="backlash_feature") == "undetermined"
        assert (a["data_sufficient"] == 1).all() and (a.attrs["min_ok_runs"], a.attrs["min_detection_runs"]) == (20, 40)
        # the given-data sensitivity: the gain dominates data set 2, its effect in metres of feature
        effect = a["effect_size"].sel(dataset="ds2", feature="backlash_feature")
        assert effect.to_pandas().idxmax() == "synthetic.gain" and a["effect_size"].attrs["units"] == "m"
        assert "rbd_fast" in a["first_order_index"].attrs["method"]
        # 40 runs, below sensitivity.MIN_RUNS (200): the index is flagged (outputs print its interval only); the gain's
        # effect is large enough for the interval to exclude 0, and the estimate lies inside it
        cell = a.sel(dataset="ds2", feature="backlash_feature", parameter="synthetic.gain")
        assert int(cell["first_order_index_flag"]) == 1 and float(cell["first_order_index_ci"].sel(bound="lower")) > 0
        index_ci = cell["first_order_index_ci"]
        assert index_ci.sel(bound="lower") <= cell["first_order_index"] <= index_ci.sel(bound="upper")
        assert float(a["overlap"].sel(feature="backlash_feature", dataset="ds2", reference="ds4")) == 0.0


def test_analysis_reports_exclusions_by_status():
    spec = load(SYNTHETIC_SPEC, runs=10)
    samples = sample(spec)
    from campaigns.runner.storage import build_results
    from campaigns.runner.synthetic import SyntheticModel

    faults = {("ds2", 0): "raise", ("ds2", 1): "nan"} | {("ds6", i): "diverge" for i in range(10)}
    model = SyntheticModel(faults=faults)
    chunks = []
    for d in range(len(spec.datasets)):
        records = [execute(model, build_request(spec, samples, d, i)) for i in range(10)]
        chunks.append(
            {
                "dataset_index": d,
                "run": np.arange(10),
                "status": np.array([r["status"] for r in records]),
                "failure_reason": np.array([r["failure_reason"] for r in records]),
                "t_reached": np.array([r["t_reached"] for r in records]),
                "wall_time": np.array([r["wall_time"] for r in records]),
                **{f"feature/{f}": np.array([r["features"][f] for r in records]) for f in spec.features},
            }
        )
    a = analysis_dataset(build_results(spec, samples, chunks), n_boot=50, min_ok_runs=5)
    assert int(a["n_used"].sel(dataset="ds2", feature="backlash_feature")) == 8
    assert int(a["n_excluded"].sel(dataset="ds2", feature="backlash_feature_true")) == 2  # whole run excluded
    assert int(a["n_status"].sel(dataset="ds2", status="error")) == 1
    assert int(a["n_status"].sel(dataset="ds2", status="failed")) == 1
    # a data set without any successful run: NaN statistics, and no verdict on the requirement
    assert int(a["n_used"].sel(dataset="ds6", feature="backlash_feature")) == 0
    assert (a["data_sufficient"].sel(dataset="ds6") == 0).all() and (a["data_sufficient"].sel(dataset="ds2") == 1).all()
    assert np.isnan(a["spearman"].sel(dataset="ds6")).all()
    assert (a["requirement_verdict"] == "insufficient data").all()
    assert "ds6 has 0 ok runs" in str(a["requirement_statement"].sel(feature="backlash_feature").item())


def test_resampled_ranks_are_scipys_average_ranks():
    """The bootstrap ranks each resample from its counts of each distinct value (twice the centred rank, in
    integers); ties (repeated runs, discrete values) included."""
    from campaigns.statistics import correlation

    rng = np.random.default_rng(5)
    for v in (rng.normal(size=200), rng.integers(0, 4, 200).astype(float), np.full(200, 2.0)):
        order, starts, n_values = correlation._numbered(v)
        multiplicity, counts, twice = (np.empty(200, dtype=np.int64) for _ in range(3))
        for resample in rng.integers(0, 200, (30, 200)):
            correlation._resample_counts(resample, multiplicity)
            squares = correlation._centred_ranks(order, starts, n_values, multiplicity, counts, twice)
            value_of_run = np.empty(200, dtype=np.int64)
            for k in range(n_values):
                value_of_run[order[starts[k]:starts[k + 1]]] = k
            ranks = 0.5 * twice[value_of_run[resample]] + 100.5
            np.testing.assert_array_equal(ranks, stats.rankdata(v[resample]))
            assert squares == 4 * ((ranks - ranks.mean()) ** 2).sum()
