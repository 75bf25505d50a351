"""Known answers of the campaign statistics on small constructed samples (campaigns.analysis.campaign_analysis,
campaigns.statistics.sensitivity).

Each test computes the expected value independently (by hand, with scipy, or with a plain loop over the same
bootstrap resamples) so that a slip in the vectorised code (an index, a default, a boundary, a random stream)
changes the answer. Sample sizes are small: the whole module runs in about a second.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import xarray as xr
from scipy import stats

from campaigns.analysis import settings as analysis_settings
from campaigns.analysis.campaign_analysis import analysis_dataset, analyze, summary
from campaigns.analysis.observability import observability_sweep, requirement_statement
from campaigns.analysis.vocabulary import BACKLASH_REQUIREMENT
from campaigns.statistics import detection, sensitivity
from campaigns.statistics.correlation import bootstrap_correlation, prcc
from campaigns.statistics.detection import (
    bootstrap_minimum_detectable,
    detection_probability,
    minimum_detectable,
    overlap_coefficient,
)
from campaigns.statistics.order_statistics import MIN_DETECTION_RUNS
from campaigns.statistics.sensitivity import HARMONICS, _easi_order, _first_order_of_signals, first_order

AGAINST = "against the 1 µm requirement of Table 9.3"
#: Runs per data set of the constructed sweeps: one more than the detection floor (59 at the default settings).
RUNS = 60


def _quantile_order_statistic(values, q):
    """The ``inverted_cdf`` quantile written out: the smallest sorted value whose rank reaches ``q n``."""
    ordered = np.sort(np.asarray(values, dtype=float))
    return float(ordered[max(math.ceil(q * len(ordered)) - 1, 0)])


def _loop_bootstrap(x, y, idx, method, confidence):
    """The percentile bootstrap of a correlation over the resamples ``idx``: scipy's estimate, and the textbook
    formula on every resample (ranked with scipy for Spearman); resamples without variance dropped."""
    correlate = stats.pearsonr if method == "pearson" else stats.spearmanr
    xb, yb = x[idx], y[idx]
    if method == "spearman":
        xb, yb = stats.rankdata(xb, axis=1), stats.rankdata(yb, axis=1)
    xc, yc = xb - xb.mean(axis=1)[:, None], yb - yb.mean(axis=1)[:, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        boot = np.einsum("ij,ij->i", xc, yc) / np.sqrt(np.einsum("ij,ij->i", xc, xc) * np.einsum("ij,ij->i", yc, yc))
    alpha = (1 - confidence) / 2
    lower, upper = np.quantile(boot[np.isfinite(boot)], [alpha, 1 - alpha])
    return correlate(x, y)[0], lower, upper


def results_dataset(features: dict, parameters: dict, *, levels=None, status=None, sweep=None) -> xr.Dataset:
    """A results.nc-like dataset: features and parameters as (dataset, run) arrays, all runs ok unless told."""
    shape = next(iter(features.values())).shape
    names = [f"d{k}" for k in range(shape[0])]
    data = {
        f: (("dataset", "run"), np.asarray(v, dtype=float), {"role": "feature", "units": "m"})
        for f, v in features.items()
    }
    data |= {
        p: (("dataset", "run"), np.asarray(v, dtype=float), {"role": "sampled", "units": "1"})
        for p, v in parameters.items()
    }
    data["status"] = (("dataset", "run"), np.full(shape, "ok", dtype=object) if status is None else status)
    data["condition_backlash"] = ("dataset", np.zeros(shape[0]) if levels is None else np.asarray(levels, dtype=float))
    spec = {"spec": {"observability": {"sweep": [] if sweep is None else sweep}}}
    return xr.Dataset(
        data, coords={"dataset": names, "run": np.arange(shape[1])}, attrs={"spec_json": json.dumps(spec)}
    )


# --- correlations ----------------------------------------------------------------------------------


@pytest.mark.parametrize("method", ["pearson", "spearman"])
def test_bootstrap_correlation_is_the_percentile_bootstrap_with_its_defaults(method):
    rng = np.random.default_rng(30)
    x = rng.normal(size=25)
    y = 0.6 * x + rng.normal(size=25)
    idx = np.random.default_rng(4).integers(0, 25, (1000, 25))  # the documented defaults: 1000 resamples, 95 %
    np.testing.assert_allclose(
        bootstrap_correlation(x, y, method, seed=4), _loop_bootstrap(x, y, idx, method, 0.95), rtol=1e-12
    )


def test_a_perfect_anticorrelation_is_minus_one_and_a_constant_sample_has_none():
    # exact linear relations: round-off puts the raw estimate and many resamples a few ulps beyond +-1 (this sample
    # was chosen so that it does); a correlation and its bounds never leave [-1, 1]
    x = np.random.default_rng(3).normal(size=17)
    for slope in (3.0, -3.0):
        estimate, lower, upper = bootstrap_correlation(x, slope * x + 1, "pearson", n_boot=200, seed=1)
        assert -1.0 <= lower <= upper <= 1.0 and -1.0 <= estimate <= 1.0
        assert estimate == pytest.approx(np.sign(slope), abs=1e-15) and upper - lower < 1e-15
    with np.errstate(invalid="ignore"):
        found = bootstrap_correlation(np.ones(17), x, "spearman", n_boot=50, seed=1)
    assert all(math.isnan(v) for v in found)  # no variance: no correlation, no interval (not an error)


def test_the_analysis_intervals_are_the_bootstrap_of_each_data_set_and_feature_stream():
    """Per (data set d, feature f): pairs resampled with the stream SeedSequence(seed, spawn_key=(d, f)), shared by
    every parameter; Pearson and Spearman estimates and both percentile bounds, for each of three parameters."""
    rng = np.random.default_rng(31)
    X = rng.normal(size=(3, 2, 30))  # parameter, data set, run
    f = X[0] + 0.5 * X[1] ** 3 + rng.normal(size=(2, 30))
    g = -X[2] + rng.normal(size=(2, 30))
    results = results_dataset({"f": f, "g": g}, {"p0": X[0], "p1": X[1], "p2": X[2]})
    a = analysis_dataset(results, n_boot=150, confidence=0.9, seed=8, min_ok_runs=20, sensitivity_boot=20)
    for d in range(2):
        for k, y in enumerate((f[d], g[d])):
            idx = np.random.default_rng(np.random.SeedSequence(8, spawn_key=(d, k))).integers(0, 30, (150, 30))
            for j in range(3):
                for method in ("pearson", "spearman"):
                    expected = _loop_bootstrap(X[j, d], y, idx, method, 0.9)
                    cell = dict(dataset=f"d{d}", feature=("f", "g")[k], parameter=f"p{j}")
                    found = (float(a[method].sel(cell)), *a[f"{method}_ci"].sel(cell).values)
                    np.testing.assert_allclose(found, expected, rtol=1e-10, err_msg=f"{method} {cell}")
            np.testing.assert_allclose(a["prcc"].sel(dataset=f"d{d}", feature=("f", "g")[k]), prcc(X[:, d].T, y))
            found = sensitivity.first_order(
                X[:, d].T,
                y,
                n_boot=20,
                confidence=0.9,
                seed=np.random.SeedSequence(8, spawn_key=(analysis_settings.SENSITIVITY_STREAM, d, k)),
            )
            # 30 runs, below sensitivity.MIN_RUNS: every index flagged (outputs print the intervals only)
            cell = a.sel(dataset=f"d{d}", feature=("f", "g")[k])
            np.testing.assert_array_equal(cell["first_order_index"], found["index"])
            np.testing.assert_array_equal(cell["effect_size"], found["effect_size"])
            np.testing.assert_array_equal(cell["first_order_index_flag"],
                                          sensitivity.unresolved(found["index"], found["ci"], 30))
            assert (cell["first_order_index_flag"] & sensitivity.BELOW_MIN_RUNS).all()
            np.testing.assert_array_equal(
                a["first_order_index_ci"].sel(dataset=f"d{d}", feature=("f", "g")[k]), found["ci"]
            )
            np.testing.assert_array_equal(
                a["effect_size_ci"].sel(dataset=f"d{d}", feature=("f", "g")[k]), found["effect_size_ci"]
            )


def test_prcc_needs_three_more_runs_than_varying_columns_and_independent_columns():
    rng = np.random.default_rng(32)
    X = np.array([[1.0, 5.0], [2.0, 3.0], [3.0, 4.0], [4.0, 1.0], [5.0, 2.0]])
    y = np.array([2.0, 1.0, 5.0, 3.0, 4.0])
    assert np.isfinite(prcc(X, y)).all()  # n = 5 = 2 columns + 3: enough
    assert np.isnan(prcc(X[:4], y[:4])).all()  # n = 4: too few
    assert np.isnan(prcc(np.ones((10, 2)), rng.normal(size=10))).all()  # nothing varies
    assert np.isnan(prcc(rng.normal(size=(10, 2)), np.ones(10))).all()  # the output does not vary
    duplicated = rng.normal(size=(12, 2))
    duplicated = np.column_stack([duplicated, duplicated[:, 0]])  # ranks linearly dependent
    assert np.isnan(prcc(duplicated, rng.normal(size=12))).all()
    assert prcc(X, y).shape == (2,) and prcc(rng.normal(size=(9, 4)), rng.normal(size=9)).shape == (4,)


# --- separation --------------------------------------------------------------------------------------


def test_overlap_uses_max_10_sqrt_n_bins_over_the_pooled_range():
    rng = np.random.default_rng(33)
    for n_a, n_b in ((3, 4), (150, 250)):  # 10 bins, then sqrt(400) = 20 bins
        a, b = rng.normal(0, 1, n_a), rng.normal(0.7, 1.3, n_b)
        bins = max(10, int(math.sqrt(n_a + n_b)))
        pooled = np.concatenate([a, b])
        pa = np.histogram(a, bins, range=(pooled.min(), pooled.max()))[0] / n_a
        pb = np.histogram(b, bins, range=(pooled.min(), pooled.max()))[0] / n_b
        assert overlap_coefficient(a, b) == pytest.approx(np.minimum(pa, pb).sum(), abs=1e-15)
        assert overlap_coefficient(b, a) == overlap_coefficient(a, b)
    # two bins by request: [0, 1.5) and [1.5, 3]: a puts 1/2, b 1/4 in the first bin; 1/2 and 3/4 in the second
    assert overlap_coefficient([0, 3], [0, 2, 2, 3], bins=2) == pytest.approx(0.25 + 0.5)
    assert math.isnan(overlap_coefficient([], [1.0, 2.0])) and math.isnan(overlap_coefficient([1.0, 2.0], []))


def test_detection_thresholds_are_strict_quantiles_on_the_side_of_the_shift():
    reference = np.arange(21.0)  # 95 % quantile exactly 19, 5 % quantile exactly 1
    # a run at the threshold itself is not flagged (the false-alarm rate counts values beyond it)
    assert detection_probability(reference, [19.0] * 10 + [20.0] * 10) == 0.5
    assert detection_probability(reference, [1.0] * 10 + [0.0] * 10) == 0.5  # below the reference: lower threshold
    # equal medians count as upward: skewed sample, 95 % quantile 9.05 (1 run beyond), 5 % quantile 0 (none below)
    skewed = np.array([0.0] * 10 + list(range(1, 11)), dtype=float)
    assert detection_probability(skewed, skewed) == 0.05
    assert detection_probability(skewed, skewed, false_alarm_rate=0.2) == 0.2  # 80 % quantile 6.2: 4 runs beyond
    assert math.isnan(detection_probability([], [1.0])) and math.isnan(detection_probability([1.0], []))


# --- minimum detectable level ------------------------------------------------------------------------


def test_minimum_detectable_known_answers():
    # default power 0.95: crossing between 0.94 (level 1) and 0.96 (level 2), halfway
    assert minimum_detectable([0.0, 1.0, 2.0], [0.05, 0.94, 0.96]) == (pytest.approx(1.5), 1.0, 2.0)
    # exactly at the power counts as reached
    assert minimum_detectable([0.0, 1.0, 2.0], [0.05, 0.95, 1.0]) == (pytest.approx(1.0), 0.0, 1.0)
    # the smallest level already detected: that level, bracket of zero width (levels sorted first)
    assert minimum_detectable([2.0, 1.0, 3.0], [1.0, 1.0, 1.0]) == (1.0, 1.0, 1.0)
    # never reached: NaN, the largest level of the sweep and no upper bound
    estimate, lower, upper = minimum_detectable([5.0, 0.0, 2.0], [0.5, 0.05, 0.3])
    assert math.isnan(estimate) and (lower, upper) == (5.0, math.inf)
    assert all(math.isnan(v) for v in minimum_detectable([0.0, 1.0], [0.05, math.nan]))


def _sweep_samples(seed=34):
    rng = np.random.default_rng(seed)
    levels = np.array([2.0, 0.0, 1.0, 3.0, 4.0])  # the reference (0) second, to be found by index
    return levels, [level + rng.normal(0.0, 0.8, RUNS) for level in levels]


def test_bootstrap_minimum_detectable_is_the_loop_over_resampled_sweeps():
    """Defaults (false-alarm 5 %, power 95 %, 95 %): every data set resampled per replicate in turn, the replicate's
    bracket found; bounds = order statistics of the brackets, widened to hold the estimate's bracket."""
    levels, samples = _sweep_samples()
    assert len(bootstrap_minimum_detectable(levels, samples, 1, seed=5)["replicates"]) == 1000  # the default n_boot
    found = bootstrap_minimum_detectable(levels, samples, 1, n_boot=200, seed=5)
    probability = [detection_probability(samples[1], s, 0.05) for s in samples]
    np.testing.assert_array_equal(found["probability"], probability)
    estimate, lower, upper = minimum_detectable(levels, probability, 0.95)
    assert found["bracket"] == (lower, upper) and found["estimate"] == pytest.approx(estimate)
    rng = np.random.default_rng(5)
    draws = [rng.integers(0, len(s), (200, len(s))) for s in samples]
    brackets = []
    for b in range(200):
        resampled = [s[draw[b]] for s, draw in zip(samples, draws, strict=True)]
        brackets.append(minimum_detectable(levels, [detection_probability(resampled[1], r) for r in resampled]))
    brackets = np.array(brackets)
    expected = (
        min(_quantile_order_statistic(brackets[:, 1], 0.025), lower),
        max(_quantile_order_statistic(brackets[:, 2], 0.975), upper),
    )
    assert found["bounds"] == expected
    assert expected[0] < expected[1]  # a real interval, not a degenerate case
    np.testing.assert_array_equal(found["replicates"], np.where(np.isnan(brackets[:, 0]), math.inf, brackets[:, 0]))
    # a narrower confidence cannot widen the bounds
    narrow = bootstrap_minimum_detectable(levels, samples, 1, n_boot=200, seed=5, confidence=0.5)["bounds"]
    assert expected[0] <= narrow[0] and narrow[1] <= expected[1]


def test_replicates_that_never_reach_the_power_are_infinite():
    rng = np.random.default_rng(43)
    samples = [level + rng.normal(0.0, 5.0, 30) for level in (0.0, 1.0)]  # 1 is far below 3.29 sigma
    found = bootstrap_minimum_detectable([0.0, 1.0], samples, 0, n_boot=50, seed=2)
    assert math.isnan(found["estimate"]) and found["bounds"][1] == math.inf
    assert (found["replicates"] == math.inf).all()


def test_the_bootstrap_bounds_move_with_the_confidence_on_a_fine_sweep():
    """Levels every 0.25 (sigma 0.8, 25 runs): the replicates' brackets spread over several levels, so the order
    statistics of each confidence differ (95 %: 1.25-2.75, 50 %: 1.75-2.25 around the bracket 1.75-2); each equals
    the loop's."""
    rng = np.random.default_rng(44)
    levels = np.arange(17) * 0.25
    samples = [level + rng.normal(0.0, 0.8, 25) for level in levels]
    rng = np.random.default_rng(9)
    draws = [rng.integers(0, 25, (100, 25)) for _ in samples]
    brackets = np.array(
        [
            minimum_detectable(
                levels,
                [detection_probability(samples[0][draws[0][b]], s[d[b]]) for s, d in zip(samples, draws, strict=True)],
            )
            for b in range(100)
        ]
    )
    _, lower, upper = minimum_detectable(levels, [detection_probability(samples[0], s) for s in samples])
    found = {}
    for confidence in (0.95, 0.5):
        alpha = (1 - confidence) / 2
        found[confidence] = bootstrap_minimum_detectable(levels, samples, 0, n_boot=100, seed=9, confidence=confidence)[
            "bounds"
        ]
        assert found[confidence] == (
            min(_quantile_order_statistic(brackets[:, 1], alpha), lower),
            max(_quantile_order_statistic(brackets[:, 2], 1 - alpha), upper),
        ), confidence
    assert found[0.5] != found[0.95]


# --- the verdict's sentence --------------------------------------------------------------------------


def test_requirement_statement_known_sentences():
    """A resolved value with its bounds; a bracket of adjacent levels, named by their data sets; a sweep never
    detected; every level the sentence gives named by its data set when the levels are given."""
    levels = {"b0": 0.0, "b1": 0.5e-6, "b2": 1e-6, "b3": 5e-6}
    assert requirement_statement("met", 0.4e-6, (0.0, 0.5e-6), {"a": 60, "b": 65}) == (
        "met: minimum detectable backlash 0.4 µm (95 % bootstrap bounds: above 0 µm, at most 0.5 µm; "
        f"60–65 ok runs per sweep data set, 2 data sets) {AGAINST}"
    )
    assert requirement_statement(
        "undetermined", math.nan, (0.5e-6, 5e-6), {"b0": 70, "b1": 70}, resolution="between_adjacent_levels",
        bracket=(1e-6, 5e-6), levels=levels,
    ) == (
        "undetermined: minimum detectable backlash between the adjacent sweep levels 1 µm (b2) and 5 µm (b3) "
        f"(95 % bootstrap bounds: above 0.5 µm (b1), at most 5 µm (b3); 70 ok runs per sweep data set, 2 data sets) "
        f"{AGAINST}"
    )
    assert requirement_statement(
        "not met", math.nan, (1e-6, math.inf), {"a": 30, "b": 30, "c": 30}, resolution="beyond_sweep",
        bracket=(5e-6, math.inf), levels=levels, confidence=0.9, power=0.8, min_runs=22,
    ) == (
        "not met: minimum detectable backlash above 5 µm (b3), the largest sweep level: detection probability below "
        "80 % along the whole sweep (90 % bootstrap bounds: above 1 µm (b2), possibly beyond the sweep; 30 ok runs "
        f"per sweep data set, 3 data sets) {AGAINST}"
    )
    # exactly the floor is enough
    assert requirement_statement("undetermined", 1.2e-6, (0.5e-6, 2e-6), {"a": 59}).startswith(
        "undetermined: minimum detectable backlash 1.2 µm (95 % bootstrap bounds: above 0.5 µm, at most 2 µm; "
        "59 ok runs"
    )


def test_insufficient_data_sentences_name_the_short_data_sets_and_the_runs_needed():
    why = ("with fewer, not even the largest run bounds the 95 % quantile that sets the detection threshold from above "
           "with 95 % confidence")
    tail = f"so no minimum detectable backlash is estimated {AGAINST}"
    assert requirement_statement("insufficient data", math.nan, (math.nan, math.nan), {"a": 1, "b": 59}) == (
        f"insufficient data: a has 1 ok run; at least 59 per sweep data set are needed ({why}), {tail}"
    )
    assert requirement_statement(
        "insufficient data", math.nan, (math.nan, math.nan), {"a": 0, "b": 3, "c": 30}, min_runs=5
    ) == (f"insufficient data: a has 0 ok runs, b has 3 ok runs; at least 5 per sweep data set are needed ({why}), "
          + tail)
    assert requirement_statement("insufficient data", math.nan, (math.nan, math.nan), {"a": 50, "b": 50}).startswith(
        "insufficient data: each of the 2 sweep data sets has 50 ok runs; at least 59 per sweep data set"
    )
    # the power's quantile binds when it is the more extreme one: 99 % detection needs 299 runs at 95 % confidence
    assert requirement_statement(
        "insufficient data", math.nan, (math.nan, math.nan), {"a": 100}, power=0.99, min_runs=299
    ) == (
        "insufficient data: a has 100 ok runs; at least 299 per sweep data set are needed (with fewer, not even the "
        "smallest run bounds the 1 % quantile that 99 % detection rests on from below with 95 % confidence), " + tail
    )
    assert requirement_statement("insufficient data", math.nan, (math.nan, math.nan), {}) == (
        "insufficient data: the spec has no observability sweep, so no minimum detectable backlash is estimated "
        + AGAINST
    )


# --- the analysis dataset ----------------------------------------------------------------------------


def test_sweep_statistics_are_those_of_the_sweep_functions_against_the_zero_backlash_data_set():
    levels, samples = _sweep_samples()
    features = np.array(samples) * 1e-6
    results = results_dataset(
        {"f": features, "g": features[::-1].copy()}, {}, levels=levels * 1e-6, sweep=["d0", "d1", "d2", "d3", "d4"]
    )
    a = analysis_dataset(results, n_boot=200, seed=6)
    for k, values in enumerate((features, features[::-1].copy())):
        found = bootstrap_minimum_detectable(
            levels * 1e-6,
            list(values),
            1,
            n_boot=200,
            seed=np.random.SeedSequence(6, spawn_key=(analysis_settings.OBSERVABILITY_STREAM, k)),
        )
        cell = a.isel(feature=k)
        np.testing.assert_array_equal(cell["sweep_detection_probability"], found["probability"])
        np.testing.assert_array_equal(cell["minimum_detectable_bracket"], found["bracket"])
        np.testing.assert_array_equal(cell["minimum_detectable_backlash_ci"], found["bounds"])
        resolved = found["resolution"] == "resolved"
        np.testing.assert_equal(float(cell["minimum_detectable_backlash"]), found["estimate"] if resolved else math.nan)
        assert detection.RESOLUTIONS[int(cell["minimum_detectable_status"])] == found["resolution"]
        verdict = detection.requirement_verdict(*found["bounds"], BACKLASH_REQUIREMENT)
        assert str(cell["requirement_verdict"].item()) == verdict
        assert str(cell["requirement_statement"].item()).startswith(f"{verdict}: ")
    np.testing.assert_array_equal(a["sweep_backlash"], levels * 1e-6)
    # the reversed feature sits below the reference: its thresholds are the lower ones
    assert str(a["requirement_statement"].sel(feature="f").item()).endswith(
        f"{RUNS} ok runs per sweep data set, 5 data sets) {AGAINST}"
    )


def test_observability_sweep_defaults_are_the_documented_ones():
    """False-alarm rate 5 %, power 95 %, 95 % bounds, MIN_DETECTION_RUNS: the same numbers as the sweep functions'
    defaults."""
    levels, samples = _sweep_samples()
    results = results_dataset({"f": np.array(samples)}, {}, levels=levels)
    found = observability_sweep(results, "f", ["d0", "d1", "d2", "d3", "d4"], n_boot=100, seed=3)
    expected = bootstrap_minimum_detectable(levels, samples, 1, n_boot=100, seed=3)
    np.testing.assert_equal(float(found["minimum_detectable_backlash"]),
                            expected["estimate"] if expected["resolution"] == "resolved" else math.nan)
    assert tuple(found["minimum_detectable_backlash_ci"].values) == expected["bounds"]
    assert "95 % bootstrap bounds" in str(found["requirement_statement"].item())


def test_a_short_sweep_data_set_withholds_the_verdict_but_not_the_others_detection():
    levels, samples = _sweep_samples()
    status = np.full((5, RUNS), "ok", dtype=object)
    status[3, 58:] = "error"  # d3: 58 ok runs, one below the detection floor
    results = results_dataset(
        {"f": np.array(samples)}, {}, levels=levels, status=status, sweep=["d0", "d1", "d2", "d3", "d4"]
    )
    a = analysis_dataset(results, n_boot=50).sel(feature="f")
    expected = [detection_probability(samples[1], s) for s in samples]
    expected[3] = math.nan
    np.testing.assert_array_equal(a["sweep_detection_probability"], expected)
    assert str(a["requirement_verdict"].item()) == "insufficient data" and math.isnan(
        float(a["minimum_detectable_backlash"])
    )
    assert np.isnan(a["minimum_detectable_backlash_ci"]).all() and np.isnan(a["minimum_detectable_bracket"]).all()
    assert "d3 has 58 ok runs; at least 59 per sweep data set are needed" in str(a["requirement_statement"].item())
    assert int(a["minimum_detectable_status"]) == detection.RESOLUTIONS.index("insufficient_data")
    status[1, 58:] = "error"  # the reference short too: no data set has a detection probability
    a = analysis_dataset(results.assign(status=(("dataset", "run"), status)), n_boot=50).sel(feature="f")
    assert np.isnan(a["sweep_detection_probability"]).all()


def test_per_data_set_counts_means_and_the_separation_matrices():
    rng = np.random.default_rng(35)
    f = rng.normal(size=(3, 8)) + np.array([[0.0], [1.0], [3.0]])
    status = np.full((3, 8), "ok", dtype=object)
    status[0, 0], status[0, 1], status[2, :6] = "error", "timeout", "failed"
    f[1, 2] = math.nan  # an ok run without a finite feature is excluded too
    results = results_dataset({"f": f}, {"p": rng.normal(size=(3, 8))}, status=status)
    with pytest.raises(ValueError, match="min_ok_runs = 2: must be at least 3"):
        analysis_dataset(results, min_ok_runs=2)
    a = analysis_dataset(results, n_boot=20, min_ok_runs=3, min_detection_runs=3, sensitivity_boot=10).sel(feature="f")
    assert list(a["n_used"].values) == [6, 7, 2] and list(a["n_excluded"].values) == [2, 1, 6]
    assert list(a["data_sufficient"].values) == [1, 1, 0]
    assert a["status"].values.tolist() == ["error", "failed", "ok", "timeout"]
    assert a["n_status"].values.tolist() == [[1, 0, 6, 1], [0, 0, 8, 0], [0, 6, 2, 0]]
    used = [f[0, 2:], np.delete(f[1], 2)]
    np.testing.assert_allclose(a["feature_mean"][:2], [u.mean() for u in used], rtol=1e-14)
    np.testing.assert_allclose(a["feature_std"][:2], [u.std(ddof=1) for u in used], rtol=1e-14)
    # below min_ok_runs the mean is still given (flagged by data_sufficient), correlations are not (issue 42)
    assert float(a["feature_mean"][2]) == pytest.approx(f[2, 6:].mean(), rel=1e-14) and np.isnan(a["spearman"][2]).all()
    # detection_probability(dataset=i, reference=j) flags runs of i against the threshold of j
    assert float(a["detection_probability"].sel(dataset="d1", reference="d0")) == detection_probability(
        used[0], used[1]
    )
    assert float(a["detection_probability"].sel(dataset="d0", reference="d1")) == detection_probability(
        used[1], used[0]
    )
    assert float(a["overlap"].sel(dataset="d0", reference="d1")) == overlap_coefficient(used[0], used[1])
    assert (
        np.isnan(a["overlap"].sel(dataset="d2")).all()
        and np.isnan(a["detection_probability"].sel(reference="d2")).all()
    )
    # at the default detection floor (59) no data set here sets a threshold: no detection probability, the overlap
    # (a histogram, no quantile) stays
    default = analysis_dataset(results, n_boot=20, min_ok_runs=3, sensitivity_boot=10).sel(feature="f")
    assert np.isnan(default["detection_probability"]).all() and default.attrs["min_detection_runs"] == 59
    np.testing.assert_array_equal(default["overlap"], a["overlap"])
    assert a["effect_size"].attrs["units"] == "m"
    # exactly min_ok_runs used runs is enough: flagged sufficient, and its statistics computed
    exact = analysis_dataset(results, n_boot=20, min_ok_runs=6, sensitivity_boot=10).sel(dataset="d0", feature="f")
    assert int(exact["data_sufficient"]) == 1 and float(exact["feature_mean"]) == pytest.approx(used[0].mean())
    assert np.isfinite(exact["spearman"]).all()


def test_attributes_state_the_settings_and_a_spec_without_sweep_says_so():
    rng = np.random.default_rng(36)
    results = results_dataset(
        {"f": rng.normal(size=(2, 25)), "g": rng.normal(size=(2, 25))}, {"p": rng.normal(size=(2, 25))}
    )
    results["g"].attrs["units"] = "s"
    a = analysis_dataset(
        results, n_boot=30, confidence=0.9, false_alarm_rate=0.1, power=0.8, seed=2, sensitivity_boot=10
    )
    assert (a.attrs["false_alarm_rate"], a.attrs["detection_power"], a.attrs["min_ok_runs"]) == (0.1, 0.8, 20)
    # the detection floor follows the settings: 1 - 0.9^22 = 0.902 >= 0.9 > 1 - 0.9^21 (the 80 % power needs 11)
    assert a.attrs["min_detection_runs"] == 22 and "90 % quantile" in a.attrs["min_detection_runs_reason"]
    assert a.attrs["first_order_min_runs"] == sensitivity.MIN_RUNS
    assert a.attrs["requirement"] == BACKLASH_REQUIREMENT and a.attrs["requirement_units"] == "m"
    assert json.loads(a.attrs["bootstrap"]) == {
        "method": "percentile, pairs resampled",
        "n_boot": 30,
        "confidence": 0.9,
        "seed": 2,
    }
    # features in two units: no single unit along the feature axis, the feature_units coordinate gives each
    assert "units" not in a["effect_size"].attrs and "feature_units coordinate (m, s)" in a["effect_size"].attrs[
        "comment"]
    assert a["feature_units"].values.tolist() == ["m", "s"] and "units" not in a["feature_mean"].attrs
    assert list(a["requirement_verdict"].values) == ["insufficient data"] * 2
    assert all("no observability sweep" in s for s in a["requirement_statement"].values)
    assert (a["data_sufficient"] == 1).all()


def test_summary_prints_each_statement_and_warns_about_short_data_sets():
    rng = np.random.default_rng(37)
    status = np.full((3, 25), "ok", dtype=object)
    status[1, 5:] = "error"
    results = results_dataset({"f": rng.normal(size=(3, 25))}, {}, status=status)
    a = analysis_dataset(results, n_boot=20)
    statements, warnings = summary(a)
    assert statements == [f"f: {a['requirement_statement'].sel(feature='f').item()}"]
    withheld = "fewer than 20 ok runs, their correlations, indices and detection probabilities are NaN"
    [warning] = warnings
    assert warning.startswith(f"f: insufficient data in d1 (5 ok runs): {withheld}; their means (flagged): d1 ")
    assert warning.endswith(", n = 5)") and "(95 % interval " in warning
    status[:, 1:] = "error"
    statements, warnings = summary(analysis_dataset(results.assign(status=(("dataset", "run"), status)), n_boot=20))
    [warning] = warnings
    assert warning.startswith(f"f: insufficient data in all 3 data sets (1 ok run each): {withheld}; their means")
    assert warning.count("(1 ok run, no interval)") == 3
    status[0, 1] = "ok"  # 2, 1, 1 ok runs: each named
    _, warnings = summary(analysis_dataset(results.assign(status=(("dataset", "run"), status)), n_boot=20))
    assert warnings[0].startswith(
        f"f: insufficient data in d0 (2 ok runs), d1 (1 ok run), d2 (1 ok run): {withheld}; their means (flagged): d0 ")
    assert summary(analysis_dataset(results_dataset({"f": rng.normal(size=(2, 25))}, {}), n_boot=20))[1] == []


def test_analyze_writes_beside_the_results_unless_told(tmp_path):
    rng = np.random.default_rng(38)
    results_dataset({"f": rng.normal(size=(2, 25))}, {}).to_netcdf(tmp_path / "results.nc", engine="netcdf4")
    assert analyze(tmp_path / "results.nc", n_boot=20, sensitivity_boot=10) == tmp_path / "analysis.nc"
    assert (
        analyze(tmp_path / "results.nc", tmp_path / "other.nc", n_boot=20, sensitivity_boot=10) == tmp_path / "other.nc"
    )
    with xr.open_dataset(tmp_path / "other.nc", engine="netcdf4") as other:
        assert int(other["n_used"].sel(dataset="d0", feature="f")) == 25


# --- first-order indices -----------------------------------------------------------------------------


def test_easi_order_goes_up_the_even_positions_and_down_the_odd_ones():
    assert _easi_order(5).tolist() == [0, 2, 4, 3, 1]
    assert _easi_order(6).tolist() == [0, 2, 4, 5, 3, 1]


@pytest.mark.parametrize("n", [301, 300])
def test_the_index_of_a_signal_is_salibs_for_odd_and_even_lengths(n):
    """SALib's rbd_fast takes the periodogram (the Nyquist bin, present for even n only, counted once)."""
    from SALib.analyze import rbd_fast
    from scipy.signal import periodogram

    rng = np.random.default_rng(39)
    signal = np.sin(np.linspace(0, 6 * np.pi, n)) + rng.normal(0, 0.7, n) + 0.3 * (-1.0) ** np.arange(n)
    spectrum = periodogram(signal)[1]
    expected = rbd_fast.unskew_S1(spectrum[1 : HARMONICS + 1].sum() / spectrum[1:].sum(), HARMONICS, n)
    assert _first_order_of_signals(signal[None, :])[0] == pytest.approx(expected, rel=1e-12)


def test_first_order_needs_more_than_twice_the_harmonics_in_runs_and_a_varying_output():
    rng = np.random.default_rng(40)
    X = rng.uniform(size=(2 * HARMONICS + 1, 2))
    X[:, 1] = 0.5  # a constant column
    found = first_order(X, X[:, 0] ** 2 + 0.1 * rng.normal(size=len(X)), n_boot=20, seed=1)
    assert np.isfinite(found["index"][0]) and np.isfinite(found["ci"][0]).all() and np.isnan(found["index"][1])
    assert np.isnan(found["ci"][1]).all()
    short = first_order(X[:-1], X[:-1, 0], n_boot=20, seed=1)
    assert all(np.isnan(v).all() for v in short.values())
    flat = first_order(X, np.ones(len(X)), n_boot=20, seed=1)
    assert all(np.isnan(v).all() for v in flat.values())


def test_first_order_interval_is_the_loop_over_resampled_runs_and_the_effect_size_follows():
    """Defaults: 200 resamples (multinomial run counts), 95 % percentile bounds of the estimator re-applied."""
    rng = np.random.default_rng(41)
    n = 60
    X = rng.uniform(-1, 1, (n, 2))
    y = np.abs(X[:, 0]) + 0.2 * X[:, 1] + 0.2 * rng.normal(size=n)
    found = first_order(X, y, seed=3)
    counts = np.random.default_rng(3).multinomial(n, np.full(n, 1.0 / n), size=200)
    for j in range(2):
        replicates = []
        for c in counts:
            runs = np.repeat(np.arange(n), c)
            order = runs[np.argsort(X[runs, j], kind="stable")]
            replicates.append(_first_order_of_signals(y[order][_easi_order(n)][None, :])[0])
        np.testing.assert_allclose(found["ci"][j], np.quantile(replicates, [0.025, 0.975]), rtol=1e-12)
        index = _first_order_of_signals(y[np.argsort(X[:, j])][_easi_order(n)][None, :])[0]
        assert found["index"][j] == pytest.approx(index, rel=1e-12)
    effect = np.sqrt(np.clip(found["index"], 0, None) * y.var(ddof=1))
    np.testing.assert_allclose(found["effect_size"], effect, rtol=1e-12)
    np.testing.assert_allclose(
        found["effect_size_ci"], np.sqrt(np.clip(found["ci"], 0, None) * y.var(ddof=1)), rtol=1e-12
    )
    # |x0| carries most of the variance; x1's small share is lost in the noise: a negative index, a zero effect
    assert found["index"][0] > 0.3 and found["index"][1] < 0.0 and found["effect_size"][1] == 0.0


def test_defaults_of_the_analysis_and_of_the_sentence():
    """1000 correlation resamples and 200 for the first-order index by default; the data_sufficient flag in CF form;
    the never-reached sentence at the default power of 95 %; exactly MIN_DETECTION_RUNS ok runs per sweep data set is
    a verdict, and no warning."""
    rng = np.random.default_rng(44)
    results = results_dataset({"f": rng.normal(size=(2, 25))}, {"p": rng.normal(size=(2, 25))})
    a = analysis_dataset(results)
    assert json.loads(a.attrs["bootstrap"])["n_boot"] == 1000 and a["first_order_index_ci"].attrs["n_boot"] == 200
    assert a["data_sufficient"].attrs["flag_values"].tolist() == [0, 1]
    assert requirement_statement(
        "not met", math.nan, (2e-6, math.inf), {"a": 60}, resolution="beyond_sweep", bracket=(5e-6, math.inf)
    ).startswith("not met: minimum detectable backlash above 5 µm, the largest sweep level: detection probability "
                 "below 95 % along the whole sweep (")
    levels, samples = _sweep_samples()
    status = np.full((5, RUNS), "ok", dtype=object)
    status[:, MIN_DETECTION_RUNS:] = "error"  # exactly MIN_DETECTION_RUNS = 59 in every sweep data set
    results = results_dataset(
        {"f": np.array(samples)}, {}, levels=levels, status=status, sweep=["d0", "d1", "d2", "d3", "d4"]
    )
    a = analysis_dataset(results, n_boot=50, sensitivity_boot=10)
    assert str(a["requirement_verdict"].sel(feature="f").item()) != "insufficient data"
    assert summary(a)[1] == []


def test_a_sweep_level_of_a_thousand_or_more_is_written_without_an_exponent():
    """A preload-loss sweep reaches 1000 N: its sentence says "1000 N", not "1e+03 N" (three significant digits below
    1000, whole units from there)."""
    statement = requirement_statement(
        "not met", math.nan, (800.0, math.inf), {"p0": 100}, resolution="beyond_sweep", bracket=(1000.0, math.inf),
        levels={"p0": 1000.0, "p200": 800.0}, condition="preload", requirement=200.0,
        requirement_source="assumed target")
    assert "above 1000 N (p0), the largest sweep level" in statement and "above 800 N (p200)" in statement
    assert "e+0" not in statement
