"""Small-sample intervals of a feature's mean, standard deviation and quantiles, and of the shift of a mean between
two samples (paired or independent), each with its method in words for ``analysis.nc``."""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from campaigns.statistics.defaults import CONFIDENCE
from campaigns.statistics.order_statistics import quantile_interval_ranks

#: How each small-sample interval is computed, in words (analysis.nc attributes, docs/campaigns.md, Analysis).
MEAN_INTERVAL_METHOD = ("Student t interval, mean +- t((1 + c)/2, n - 1) s / sqrt(n): exact for a normal feature, "
                        "approximate for others (central limit); from 2 runs")
STD_INTERVAL_METHOD = ("chi-square interval, s sqrt((n - 1) / chi2((1 +- c)/2, n - 1)): exact for a normal feature "
                       "only, its coverage depends on the feature's kurtosis at any n (Box 1953); from 2 runs")
QUANTILE_INTERVAL_METHOD = ("distribution-free order-statistic interval [X_(l), X_(u)], ranks from Binomial(n, q) "
                            "with (1 - c)/2 in each tail (Hahn & Meeker 1991, Sec. 5.2); NaN below "
                            "feature_quantile_min_runs: n too small for a bound")


def mean_interval(values, confidence: float = CONFIDENCE) -> tuple[float, float, float]:
    """``(mean, lower, upper)``: the Student t interval of the mean (:data:`MEAN_INTERVAL_METHOD`); NaN bounds below 2
    values, all NaN for none. Values without spread give an interval of zero width."""
    y = np.asarray(values, dtype=float)
    if y.size == 0:
        return math.nan, math.nan, math.nan
    mean = float(y.mean())
    if y.size < 2:
        return mean, math.nan, math.nan
    half = float(stats.t.ppf(0.5 + 0.5 * confidence, y.size - 1) * y.std(ddof=1) / math.sqrt(y.size))
    return mean, mean - half, mean + half


def std_interval(values, confidence: float = CONFIDENCE) -> tuple[float, float, float]:
    """``(s, lower, upper)``: the sample standard deviation with its chi-square interval (:data:`STD_INTERVAL_METHOD`:
    ``(n - 1) s^2 / sigma^2`` is chi-square with ``n - 1`` degrees of freedom for a normal feature); NaN below 2
    values."""
    y = np.asarray(values, dtype=float)
    if y.size < 2:
        return math.nan, math.nan, math.nan
    s, dof = float(y.std(ddof=1)), y.size - 1
    alpha = 1.0 - confidence
    return (s, s * math.sqrt(dof / stats.chi2.ppf(1.0 - 0.5 * alpha, dof)),
            s * math.sqrt(dof / stats.chi2.ppf(0.5 * alpha, dof)))


def quantile_interval(values, quantile: float, confidence: float = CONFIDENCE) -> tuple[float, float, float]:
    """``(estimate, lower, upper)``: the sample quantile (numpy's linear interpolation) with its order-statistic
    interval (:func:`quantile_interval_ranks`); NaN bounds where the runs are too few for a bound."""
    y = np.sort(np.asarray(values, dtype=float))
    if y.size == 0:
        return math.nan, math.nan, math.nan
    estimate = float(np.quantile(y, quantile))
    ranks = quantile_interval_ranks(y.size, quantile, confidence)
    if ranks is None:
        return estimate, math.nan, math.nan
    return estimate, float(y[ranks[0] - 1]), float(y[ranks[1] - 1])


def mean_shift(new, old, *, paired: bool, confidence: float = CONFIDENCE,
               min_runs: int = 2) -> tuple[float, float, float]:
    """Shift of the mean ``mean(new) - mean(old)`` with its Student t interval at ``confidence``: of the run-by-run
    differences when ``paired`` (the two samples share their seeds run by run, common random numbers: ``new[i]`` and
    ``old[i]`` are one run under two configurations), else Welch's for independent samples (Welch 1947, Biometrika
    34, 28-35; the Welch-Satterthwaite degrees of freedom).

    Non-finite values are left out (a pair when either is). NaN throughout when a side has fewer than
    ``max(min_runs, 2)`` values (a variance needs two). Samples without spread give an interval of zero width.

    Returns
    -------
    tuple of float
        ``(shift, lower, upper)``.
    """
    a, b = np.asarray(new, dtype=float), np.asarray(old, dtype=float)
    if paired:
        if a.shape != b.shape:
            raise ValueError(f"a paired shift needs one value per run on both sides, got {a.size} and {b.size}")
        kept = np.isfinite(a) & np.isfinite(b)
        a, b = a[kept], b[kept]
    else:
        a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    if min(a.size, b.size) < max(min_runs, 2):
        return math.nan, math.nan, math.nan
    if paired:
        d = a - b
        shift, variance, dof = float(d.mean()), d.var(ddof=1) / d.size, d.size - 1
    else:
        shift = float(a.mean() - b.mean())
        va, vb = a.var(ddof=1) / a.size, b.var(ddof=1) / b.size
        variance = va + vb
        dof = variance**2 / (va**2 / (a.size - 1) + vb**2 / (b.size - 1)) if variance > 0.0 else 1.0
    if variance == 0.0:
        return shift, shift, shift
    half = float(stats.t.ppf(0.5 + confidence / 2, dof) * math.sqrt(variance))
    return shift, shift - half, shift + half
