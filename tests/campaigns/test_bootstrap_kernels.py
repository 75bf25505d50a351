"""The compiled bootstrap loops of :mod:`campaigns.statistics.correlation` and :mod:`campaigns.statistics.sensitivity`
give numpy's numbers bit for bit, on one thread or several.

The analysis promises the same ``analysis.nc`` for the same results and seed (docs/campaigns.md, "The same numbers
everywhere"); the compiled loops replaced numpy array expressions, so they are checked here against those
expressions, exactly (no tolerance: a sum in another order is another number, and that is what would be caught).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr
from scipy import stats

from campaigns.statistics import correlation, sensitivity
from campaigns.statistics.correlation import bootstrap_correlations, prcc, rank_design


def _numpy_bootstrap(X, y, idx, method, confidence):
    """The array expressions the compiled loops replaced: every resample materialised, standardized and summed by
    numpy."""
    spearman = method == "spearman"

    def resampled(v):
        return stats.rankdata(v[idx], axis=-1) if spearman else v[idx]

    def standardized(v):
        centred = v - v.mean(axis=-1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            return centred / np.sqrt((centred * centred).sum(axis=-1, keepdims=True))

    yb = standardized(resampled(y))
    alpha = 0.5 * (1.0 - confidence)
    lower, upper = np.full(len(X), math.nan), np.full(len(X), math.nan)
    for j, x in enumerate(X):
        boot = np.clip((standardized(resampled(x)) * yb).sum(axis=-1), -1.0, 1.0)
        boot = boot[np.isfinite(boot)]
        if len(boot):
            lower[j], upper[j] = np.quantile(boot, [alpha, 1.0 - alpha])
    return lower, upper


@pytest.mark.parametrize("n", [*range(140), 255, 256, 257, 999, 1000, 1001, 4099])
def test_the_pairwise_sum_is_numpys(n):
    a = np.random.default_rng(n).standard_normal(n) * 10.0 ** np.random.default_rng(n + 1).uniform(-8, 8, n)
    plan = correlation._pairwise_plan(n)
    assert correlation._pairwise_sum(a, plan, np.empty(len(plan))) == np.add.reduce(a)
    assert correlation._pairwise_sum(a, plan, np.empty(len(plan))) == a[None, :].sum(axis=-1)[0]


@pytest.mark.parametrize(("n", "p", "n_boot"), [(25, 4, 60), (200, 5, 300), (1000, 6, 400), (333, 3, 17)])
@pytest.mark.parametrize("method", ["pearson", "spearman"])
def test_bootstrap_correlations_are_numpys_bit_for_bit(n, p, n_boot, method):
    rng = np.random.default_rng(n + p)
    X = rng.standard_normal((p, n))
    X[1] = np.round(X[1])  # ties
    X[2] = 1.0  # a constant column: no correlation in any resample
    y = 0.3 * X[0] + rng.standard_normal(n)
    idx = rng.integers(0, n, (n_boot, n))
    _, lower, upper = bootstrap_correlations(X, y, idx, method, 0.95)
    expected = _numpy_bootstrap(X, y, idx, method, 0.95)
    np.testing.assert_array_equal(lower, expected[0])
    np.testing.assert_array_equal(upper, expected[1])
    assert np.isnan(lower[2]) and np.isfinite(lower[[0, 1]]).all()


def test_a_shared_rank_design_gives_the_prcc_of_a_fresh_one():
    rng = np.random.default_rng(7)
    X = rng.standard_normal((300, 6))
    X[:, 4] = 2.0
    design = rank_design(X)
    for y in (X[:, 0] + 0.1 * rng.standard_normal(300), np.exp(X[:, 1]), rng.standard_normal(300)):
        np.testing.assert_array_equal(prcc(X, y, design), prcc(X, y))


def test_the_rank_design_on_one_blas_thread_is_the_design_on_several():
    """:func:`rank_design` pins BLAS to one thread (busy cores): the PRCCs are those of the threaded factorisation."""
    from threadpoolctl import threadpool_limits

    rng = np.random.default_rng(3)
    X, y = rng.standard_normal((1000, 49)), rng.standard_normal(1000)
    single = prcc(X, y, rank_design(X))
    with threadpool_limits(2, user_api="blas"):
        Q, R = np.linalg.qr(np.column_stack([np.ones(1000), stats.rankdata(X, axis=0)]))
        R_inv = np.linalg.solve(R, np.eye(R.shape[0]))
        threaded = correlation.RankDesign(Q, R_inv, (Q @ R_inv.T[:, 1:]) / (R_inv * R_inv).sum(axis=1)[1:])
        np.testing.assert_array_equal(prcc(X, y, threaded), single)


def _numpy_first_order_intervals(X, y, n_boot, confidence, seed):
    """The array expressions :func:`campaigns.statistics.sensitivity.first_order` replaced: each resample sorted
    along the input by ``repeat`` of the sorted runs, EASI-reordered by fancy indexing, and the periodogram ratio
    with numpy's temporaries."""
    from SALib.analyze import rbd_fast

    n = len(y)
    counts = np.random.default_rng(seed).multinomial(n, np.full(n, 1.0 / n), size=n_boot)
    reorder = sensitivity._easi_order(n)
    ci = np.full((X.shape[1], 2), math.nan)
    for j in range(X.shape[1]):
        if np.ptp(X[:, j]) == 0:
            continue
        order = np.argsort(X[:, j])
        runs = np.repeat(np.tile(order, n_boot), counts[:, order].ravel()).reshape(n_boot, n)
        signals = y[runs[:, reorder]]
        power = np.abs(np.fft.rfft(signals - signals.mean(axis=-1, keepdims=True), axis=-1)[:, 1:]) ** 2
        one_sided = np.full(power.shape[-1], 2.0)
        if n % 2 == 0:
            one_sided[-1] = 1.0
        index = rbd_fast.unskew_S1(2.0 * power[:, :10].sum(axis=-1) / (power * one_sided).sum(axis=-1), 10, n)
        alpha = 0.5 * (1.0 - confidence)
        ci[j] = np.quantile(index[np.isfinite(index)], [alpha, 1.0 - alpha])
    return ci


@pytest.mark.parametrize(("n", "p", "n_boot"), [(1000, 4, 200), (999, 3, 50), (60, 3, 31), (201, 2, 7)])
def test_the_first_order_intervals_are_numpys_bit_for_bit(n, p, n_boot):
    """The compiled resampling (a run written four times, moved on by its count) and the spectral steps into
    preallocated column-major arrays give the numbers of the numpy expressions (whose fancy indexing laid the
    resamples out column-major: the FFT's bits depend on the layout)."""
    rng = np.random.default_rng(n)
    X = rng.standard_normal((n, p))
    X[:, 1] = np.round(X[:, 1])  # ties
    X[:, -1] = 3.0  # a constant column: no index
    y = X[:, 0] ** 2 + rng.standard_normal(n)
    y[::7] = np.round(y[::7])
    found = sensitivity.first_order(X, y, n_boot=n_boot, seed=11)
    np.testing.assert_array_equal(found["ci"], _numpy_first_order_intervals(X, y, n_boot, 0.95, 11))


def test_the_sorted_resamples_repeat_runs_by_counts_of_any_size():
    """Counts of 0 to 9 (the branch-free writes cover 4 copies of a run; more are written one by one)."""
    n = 40
    counts = np.zeros((3, n), dtype=np.int64)
    counts[0] = 1
    counts[1, :4] = (9, 0, 26, 5)
    counts[2, ::8] = 8
    order, reorder, y = np.arange(n)[::-1].copy(), sensitivity._easi_order(n), np.arange(n, dtype=float)
    signals = np.empty((3, n), order="F")
    sensitivity._sorted_resamples(y, order, counts, reorder, signals)
    for b in range(3):
        np.testing.assert_array_equal(signals[b], y[np.repeat(order, counts[b, order])][reorder])


def test_the_analysis_on_one_thread_is_the_analysis_on_several(monkeypatch):
    """The correlations and the margins' bootstraps run on the cores' threads, each cell alone: one thread gives
    the same numbers."""
    from campaigns.analysis import settings
    from campaigns.analysis.correlations import correlations
    from campaigns.analysis.margins import control_robustness

    rng = np.random.default_rng(2)
    n, names = 240, ["d0", "d1", "d2"]
    X = rng.uniform(-1, 1, (5, 3, n))
    feature = 2e-6 * X[0] + 1e-6 * rng.normal(size=(3, n))
    margin = {"role": "margin", "loop": "speed", "metric": "phase_margin", "units": "degree"}
    data = {"f": (("dataset", "run"), feature, {"role": "feature", "units": "m"}),
            "g": (("dataset", "run"), feature ** 2 + 1e-12 * X[1], {"role": "feature", "units": "m2"}),
            "speed_loop_phase_margin": (("dataset", "run"), 60.0 + 5e6 * feature, margin),
            "status": (("dataset", "run"), np.full((3, n), "ok", dtype=object))}
    data |= {f"p{j}": (("dataset", "run"), X[j], {"role": "sampled", "units": "1"}) for j in range(5)}
    results = xr.Dataset(data, coords={"dataset": names, "run": np.arange(n)}, attrs={"spec_json": '{"spec": {}}'})
    options = settings.AnalysisSettings(n_boot=300, sensitivity_boot=40)
    monkeypatch.setattr(settings, "threads", lambda: 3)
    several = xr.merge([correlations(results, options), control_robustness(results, options)])
    monkeypatch.setattr(settings, "threads", lambda: 1)
    one = xr.merge([correlations(results, options), control_robustness(results, options)])
    xr.testing.assert_identical(several, one)
    assert np.isfinite(several["spearman_ci"]).all() and np.isfinite(several["margin_spearman_ci"]).all()
