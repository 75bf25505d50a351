"""The compiled bootstrap loops of :mod:`campaigns.statistics.correlation` give numpy's numbers bit for bit.

The analysis promises the same ``analysis.nc`` for the same results and seed (docs/campaigns.md, "The same numbers
everywhere"); the compiled loops replaced numpy array expressions, so they are checked here against those
expressions, exactly (no tolerance: a sum in another order is another number, and that is what would be caught).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from campaigns.statistics import correlation
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
