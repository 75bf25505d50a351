"""Statistics of a campaign: correlations, separation of data sets, observability.

All statistics use successful runs only (status ``"ok"`` and a finite feature);
``n_used`` and ``n_excluded`` record how many runs entered and were left out,
``n_status`` how many runs ended with each status.

* Correlation of each feature with each sampled value, per data set: Pearson and
  Spearman with seeded percentile-bootstrap confidence intervals, and the partial
  rank correlation coefficient (PRCC, rank-transformed partial correlation).
* Separation of the feature distributions of two data sets: overlap coefficient
  and detection probability at a fixed false-alarm rate.
* Observability: along the spec's backlash sweep (data sets that differ only in
  their backlash), the smallest backlash detectable against the zero-backlash
  data set, compared with the 1 µm requirement of Table 9.3. The sweep levels
  bracketing it are the finding; a value between them is printed only where the
  sweep resolves it (:func:`sweep_resolution`).

Sample-size floors, each from the statistic's own confidence: :data:`MIN_OK_RUNS`
for moments and correlations (which carry their own intervals),
:data:`MIN_DETECTION_RUNS` for the quantile that sets the detection threshold
(order statistics, :func:`min_runs_for_quantile_bound`), and
:data:`campaigns.statistics.sensitivity.MIN_RUNS` for the first-order index.
"""

from __future__ import annotations

import json
import math
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import xarray as xr
from scipy import stats

from campaigns.analysis.margins import control_robustness
from campaigns.runner.files import CONVENTIONS, atomic_write
from campaigns.statistics import sensitivity
from campaigns.units import estimate_with_interval
from campaigns.units import quantity as quantity_text

#: Table 9.3: minimum detectable linear backlash [m].
BACKLASH_REQUIREMENT = 1e-6
REQUIREMENT_SOURCE = "Bertolino (2020) Table 9.3: minimum detectable linear backlash 1 µm"
#: Ok runs a data set needs before any statistic of it is computed (``data_sufficient``). A floor against printing
#: noise, not a confidence statement: below 20 runs a rank correlation must exceed ±0.45 (1.96/sqrt(n - 1)) to be
#: told from independence, and the first-order index cannot be computed at all (it needs more than 2 x 10 harmonics
#: of runs). Every statistic above it carries its own interval. The detection threshold carries none: it has its
#: own floor, :data:`MIN_DETECTION_RUNS` (docs/campaigns.md, Analysis).
MIN_OK_RUNS = 20
#: Detection settings of the verdict: the threshold flags this fraction of the reference's runs ...
FALSE_ALARM_RATE = 0.05
#: ... and the minimum detectable level is where this fraction of a data set's runs is flagged.
POWER = 0.95
#: Confidence of the bootstrap bounds and of the order-statistic floor.
CONFIDENCE = 0.95
#: Flag values of ``minimum_detectable_status``: how far the sweep resolves the minimum detectable level.
RESOLUTIONS = ("insufficient_data", "resolved", "between_adjacent_levels", "beyond_sweep")
_VERDICT_ATTRS = {"long_name": "verdict on the Table 9.3 requirement: met / not met / undetermined / insufficient data"}
_STATEMENT_ATTRS = {
    "long_name": "the verdict on the Table 9.3 requirement with the estimate, its bounds and the sample size, "
                 "in one sentence"}
_RESOLUTION_ATTRS = {
    "long_name": "how far the sweep resolves the minimum detectable level: resolved (a sweep level lies strictly "
                 "inside the bootstrap bounds: the value is printed), between_adjacent_levels (the bracket of two "
                 "adjacent sweep levels is the finding), beyond_sweep (no level detected with the power), "
                 "insufficient_data",
    "flag_values": np.arange(len(RESOLUTIONS), dtype=np.int8),
    "flag_meanings": " ".join(RESOLUTIONS),
}
#: What a sweep's condition measures: condition -> (fault quantity, unit, display scale, display unit). The
#: fault size of a data set is ``|condition - condition of the reference|`` (the backlash itself; the loss of
#: preload from the healthy reference).
SWEEP_QUANTITIES = {"backlash": ("backlash", "m", 1e6, "µm"), "preload": ("preload loss", "N", 1.0, "N")}
#: Spawn-key tag of the observability bootstrap's random stream (the correlation bootstraps use (dataset, feature)).
_OBSERVABILITY_STREAM = 1_000_003
#: Spawn-key tag of the first-order index bootstrap's random stream.
_SENSITIVITY_STREAM = 1_000_033
#: Spawn-key tag of the within-unit bootstrap's random stream (:mod:`campaigns.analysis.within_unit`).
_WITHIN_UNIT_STREAM = 1_000_037
#: Residual sum of squares of ranks, relative to n^3, below which a PRCC regression counts as exact (round-off only).
_EXPLAINED = 1e-18


def quantile_bound_rank(n: int, quantile: float, confidence: float) -> int | None:
    """Rank ``r`` (1-based) of the smallest order statistic of ``n`` runs that is a one-sided upper confidence bound,
    at ``confidence``, of the distribution's ``quantile``; None when not even the sample maximum is.

    Distribution-free (any continuous distribution): ``X_(r) >= xi_q`` exactly when fewer than ``r`` runs fall below
    ``xi_q``, so ``P(X_(r) >= xi_q) = P(Binomial(n, q) <= r - 1)`` (David & Nagaraja 2003, *Order Statistics*,
    3rd ed., Sec. 7.1). By symmetry ``n + 1 - r`` is the rank of the largest order statistic that is a lower bound of
    the ``1 - quantile`` quantile at the same confidence.
    """
    k = int(stats.binom.ppf(confidence, n, quantile))  # the smallest k with P(Binomial(n, q) <= k) >= confidence
    while k > 0 and stats.binom.cdf(k - 1, n, quantile) >= confidence:  # round-off guards of the inverse
        k -= 1
    while k < n and stats.binom.cdf(k, n, quantile) < confidence:
        k += 1
    return k + 1 if k + 1 <= n else None


def min_runs_for_quantile_bound(quantile: float, confidence: float) -> int:
    """The fewest runs for which some order statistic bounds the ``quantile`` from above at ``confidence``.

    The sample maximum is the most likely bound: ``P(X_(n) >= xi_q) = 1 - q^n`` (:func:`quantile_bound_rank`), so
    ``n = ceil(log(1 - confidence) / log(quantile))``: 59 for the 95 % quantile at 95 % (1 - 0.95^59 = 0.952,
    1 - 0.95^58 = 0.949; David & Nagaraja 2003, Sec. 7.2, the distribution-free tolerance limit of Wilks 1941).
    """
    n = max(1, math.ceil(math.log1p(-confidence) / math.log(quantile)))
    while 1.0 - quantile**n < confidence:  # round-off guards of the logarithms
        n += 1
    while n > 1 and 1.0 - quantile ** (n - 1) >= confidence:
        n -= 1
    return n


def detection_run_floor(false_alarm_rate: float = FALSE_ALARM_RATE, power: float = POWER,
                       confidence: float = CONFIDENCE) -> int:
    """Ok runs every data set of a detection statement needs: :data:`MIN_DETECTION_RUNS` for the default settings.

    The detection threshold is the ``1 - false_alarm_rate`` quantile of the reference, and a data set is detected
    with probability ``power`` when its ``1 - power`` quantile lies beyond that threshold. Each quantile has a
    distribution-free confidence bound among its sample's order statistics only from
    :func:`min_runs_for_quantile_bound` runs on (the largest run bounds the upper quantile from above, the smallest
    the lower one from below); below it, no threshold taken from the runs can be shown to keep the false-alarm rate
    (or the power) at its nominal value with ``confidence``, whatever order statistic is used.
    """
    return max(min_runs_for_quantile_bound(1.0 - false_alarm_rate, confidence),
               min_runs_for_quantile_bound(power, confidence))


#: Ok runs every data set needs before a detection probability against its threshold (or of its runs, for the
#: verdict) is computed: 59 at a 5 % false-alarm rate, 95 % power and 95 % confidence (:func:`detection_run_floor`).
#: At the previous floor, 20, even the largest run bounds the 95 % quantile with only 64 % confidence (1 - 0.95^20),
#: and the threshold used (interpolated between the two largest runs) with 26-64 %.
MIN_DETECTION_RUNS = detection_run_floor()

#: Probabilities of the quantiles stored per data set (``feature_quantile``): the median and the two tails that the
#: detection rule reads (a 5 % false-alarm threshold on either side of a reference).
QUANTILE_PROBABILITIES = (0.05, 0.5, 0.95)
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


def quantile_interval_ranks(n: int, quantile: float, confidence: float = CONFIDENCE) -> tuple[int, int] | None:
    """Ranks ``(l, u)`` (1-based) of the order statistics of ``n`` runs that bound the distribution's ``quantile``
    with ``confidence``, ``(1 - confidence) / 2`` in each tail; None when ``n`` is too small for either bound.

    Distribution-free: ``X_(u)`` is the one-sided upper bound of :func:`quantile_bound_rank` at ``(1 + c) / 2``, and
    ``X_(l)`` its mirror image (the upper bound of the ``1 - quantile`` quantile of ``-X``), so ``P(X_(l) <= xi_q <=
    X_(u)) >= confidence`` for any continuous distribution (Hahn & Meeker 1991, *Statistical Intervals*, Sec. 5.2).
    """
    tail = 0.5 + 0.5 * confidence
    upper = quantile_bound_rank(n, quantile, tail)
    mirrored = quantile_bound_rank(n, 1.0 - quantile, tail)
    if upper is None or mirrored is None:
        return None
    return n + 1 - mirrored, upper


def quantile_interval_min_runs(quantile: float, confidence: float = CONFIDENCE) -> int:
    """The fewest runs with which :func:`quantile_interval_ranks` bounds the ``quantile`` on both sides: the sample
    extremes must bound it with ``(1 + confidence) / 2`` each (:func:`min_runs_for_quantile_bound`): 6 for the median,
    72 for the 5 % and 95 % quantiles at 95 %."""
    return min_runs_for_quantile_bound(max(quantile, 1.0 - quantile), 0.5 + 0.5 * confidence)


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


def _pearson(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Pearson correlation along the last axis (NaN where a variance is zero)."""
    xc = x - x.mean(axis=-1, keepdims=True)
    yc = y - y.mean(axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = (xc * yc).sum(axis=-1) / np.sqrt((xc * xc).sum(axis=-1) * (yc * yc).sum(axis=-1))
    return np.clip(r, -1.0, 1.0)


def bootstrap_correlation(x, y, method: str = "spearman", *, n_boot: int = 1000, confidence: float = 0.95, seed=None):
    """Correlation of ``x`` and ``y`` with a percentile-bootstrap confidence interval.

    Parameters
    ----------
    x, y : array_like, shape (n,)
    method : {"pearson", "spearman"}
    n_boot : int, default 1000
        Bootstrap resamples (pairs resampled with replacement).
    confidence : float, default 0.95
    seed : int, Generator or None

    Returns
    -------
    tuple of float
        ``(estimate, lower, upper)``.
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    idx = np.random.default_rng(seed).integers(0, len(x), (n_boot, len(x)))
    estimate, lower, upper = _correlations(x[None, :], y, idx, method, confidence)
    return float(estimate[0]), float(lower[0]), float(upper[0])


def _resampled_ranks(v: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """``scipy.stats.rankdata(v[idx], axis=-1)`` (average ranks) without sorting every resample.

    A resample's rank of a value is the number of resampled values below it plus half of
    (its own count + 1): cumulative bootstrap counts over the values sorted once.
    """
    n_boot = idx.shape[0]
    values, group = np.unique(v, return_inverse=True)
    resampled = group[idx]
    counts = np.bincount((resampled + len(values) * np.arange(n_boot)[:, None]).ravel(), minlength=n_boot * len(values))
    counts = counts.reshape(n_boot, len(values)).astype(float)
    rank = np.cumsum(counts, axis=1) - 0.5 * (counts - 1.0)
    return np.take_along_axis(rank, resampled, axis=1)


def _correlations(X: np.ndarray, y: np.ndarray, idx: np.ndarray, method: str, confidence: float):
    """Estimates and percentile CIs for each row of ``X`` (shape (p, n)) against ``y``, shared resamples ``idx``."""
    spearman = method == "spearman"
    estimate = _pearson(stats.rankdata(X, axis=-1), stats.rankdata(y)[None, :]) if spearman else _pearson(X, y[None, :])

    def resampled(v: np.ndarray) -> np.ndarray:
        return _resampled_ranks(v, idx) if spearman else v[idx]

    def standardized(v: np.ndarray) -> np.ndarray:
        """Rows centred and scaled to unit norm (NaN rows without variance): a Pearson correlation is then a dot
        product."""
        centred = v - v.mean(axis=-1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            return centred / np.sqrt((centred * centred).sum(axis=-1, keepdims=True))

    yb = standardized(resampled(y))  # once, shared by every parameter
    alpha = 0.5 * (1.0 - confidence)
    lower, upper = np.full(len(X), math.nan), np.full(len(X), math.nan)
    for j, x in enumerate(X):
        boot = np.clip((standardized(resampled(x)) * yb).sum(axis=-1), -1.0, 1.0)
        boot = boot[np.isfinite(boot)]  # resamples without variance have no correlation
        if len(boot):
            lower[j], upper[j] = np.quantile(boot, [alpha, 1.0 - alpha])
    return estimate, lower, upper


def prcc(X, y) -> np.ndarray:
    """Partial rank correlation coefficient of each column of ``X`` with ``y``.

    The PRCC of column ``j`` is the Pearson correlation of the residuals of
    ``rank(x_j)`` and ``rank(y)`` after linear regression (with intercept) on
    the ranks of the other columns (Marino et al. 2008, J. Theor. Biol. 254,
    Sec. 2.4). All those regressions come from one QR factorisation of the
    design ``A = [1, ranks]``: with ``H = (A^T A)^-1``, the residual of column
    ``k`` on the others is ``A H e_k / H_kk``, and that of ``rank(y)`` on the
    others is the full residual plus ``beta_k`` times it (one factorisation
    instead of two least-squares fits per column, which a BLAS shared by busy
    cores makes costly). Constant columns are left out of the regressions and
    get NaN; so does a column whose residual is zero (the other columns explain
    it, or ``y``, completely), and every column when there are too few rows or
    the ranks of the columns are linearly dependent.

    Parameters
    ----------
    X : array_like, shape (n, p)
    y : array_like, shape (n,)

    Returns
    -------
    numpy.ndarray, shape (p,)
    """
    X, y = np.asarray(X, dtype=float), np.asarray(y, dtype=float)
    out = np.full(X.shape[1], math.nan)
    varying = np.flatnonzero(np.ptp(X, axis=0) > 0)
    n = len(y)
    if len(varying) == 0 or np.ptp(y) == 0 or n < len(varying) + 3:
        return out
    ry = stats.rankdata(y)
    Q, R = np.linalg.qr(np.column_stack([np.ones(n), stats.rankdata(X[:, varying], axis=0)]))
    if np.abs(np.diag(R)).min() <= 1e-9 * np.abs(np.diag(R)).max():
        return out
    R_inv = np.linalg.solve(R, np.eye(R.shape[0]))
    H_diag = (R_inv * R_inv).sum(axis=1)  # diagonal of H = R^-1 R^-T
    residuals_x = (Q @ R_inv.T[:, 1:]) / H_diag[1:]  # A H e_k / H_kk, column k
    coefficients = Q.T @ ry
    beta = R_inv[1:] @ coefficients
    residuals_y = (ry - Q @ coefficients)[:, None] + beta * residuals_x
    explained = _EXPLAINED * n**3  # rank variance ~ n^3 / 12
    for k, j in enumerate(varying):
        rx, rr = residuals_x[:, k], residuals_y[:, k]
        if min(rx @ rx, rr @ rr) > explained:
            out[j] = _pearson(rx, rr)
    return out


def overlap_coefficient(a, b, bins: int | None = None) -> float:
    """Overlap coefficient ``sum(min(p_a, p_b))`` of two samples' histograms on common bins.

    1 for identical distributions, 0 for disjoint ones. Default bins:
    ``max(10, sqrt(n_a + n_b))`` over the pooled range.
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if len(a) == 0 or len(b) == 0:
        return math.nan
    bins = bins or max(10, int(math.sqrt(len(a) + len(b))))
    edges = np.histogram_bin_edges(np.concatenate([a, b]), bins=bins)
    pa = np.histogram(a, edges)[0] / len(a)
    pb = np.histogram(b, edges)[0] / len(b)
    return float(np.minimum(pa, pb).sum())


def mean_shift(new, old, *, paired: bool, confidence: float = 0.95, min_runs: int = 2) -> tuple[float, float, float]:
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


def _detection_probabilities(reference: np.ndarray, test: np.ndarray, false_alarm_rate: float) -> np.ndarray:
    """:func:`detection_probability` of each row of ``test`` (shape (B, n_t)) against the same row of ``reference``
    (B, n_r)."""
    upward = np.median(test, axis=-1) >= np.median(reference, axis=-1)
    high = np.quantile(reference, 1.0 - false_alarm_rate, axis=-1)
    low = np.quantile(reference, false_alarm_rate, axis=-1)
    return np.where(upward, np.mean(test > high[:, None], axis=-1), np.mean(test < low[:, None], axis=-1))


def detection_probability(reference, test, false_alarm_rate: float = 0.05) -> float:
    """Probability that a ``test`` run is flagged by a threshold with the given false-alarm rate.

    The threshold is the ``1 - false_alarm_rate`` quantile of ``reference``
    (or the ``false_alarm_rate`` quantile when ``test`` lies below ``reference``,
    judged by the medians), so a fraction ``false_alarm_rate`` of reference runs
    would be flagged.
    """
    reference, test = np.asarray(reference, dtype=float), np.asarray(test, dtype=float)
    if len(reference) == 0 or len(test) == 0:
        return math.nan
    return float(_detection_probabilities(reference[None, :], test[None, :], false_alarm_rate)[0])


def minimum_detectable(levels, probabilities, power: float = 0.95) -> tuple[float, float, float]:
    """Smallest level whose detection probability reaches ``power``, and the sweep levels bracketing it.

    ``levels`` are the swept condition values, the reference included (at its
    own detection probability, i.e. the false-alarm rate). The estimate
    interpolates linearly between the last level below ``power`` and the first
    one reaching it; the truth is only known to lie between those two levels.

    Returns
    -------
    tuple of float
        ``(estimate, lower, upper)``; when no level reaches ``power``:
        ``(nan, largest level, inf)``; all NaN when a probability is unknown
        (a data set without used runs).
    """
    order = np.argsort(levels)
    levels, probabilities = np.asarray(levels, dtype=float)[order], np.asarray(probabilities, dtype=float)[order]
    if np.isnan(probabilities).any():
        return math.nan, math.nan, math.nan
    reached = np.flatnonzero(probabilities >= power)
    if len(reached) == 0:
        return math.nan, float(levels[-1]), math.inf
    k = reached[0]
    if k == 0:
        return float(levels[0]), float(levels[0]), float(levels[0])
    estimate = float(np.interp(power, probabilities[k - 1 : k + 1], levels[k - 1 : k + 1]))
    return estimate, float(levels[k - 1]), float(levels[k])


def bootstrap_minimum_detectable(
    levels,
    samples: list,
    reference: int,
    *,
    false_alarm_rate: float = 0.05,
    power: float = 0.95,
    n_boot: int = 1000,
    confidence: float = 0.95,
    seed=None,
) -> dict:
    """Minimum detectable level along a sweep, with bootstrap confidence bounds.

    Each bootstrap replicate resamples the runs of every sweep data set with
    replacement (independently per data set, the reference included), recomputes
    the detection probabilities against the resampled reference and the sweep
    levels bracketing the crossing of ``power`` (:func:`minimum_detectable`).
    Between two sweep levels the data say nothing, so the bounds are sweep
    levels: the lower bound is the ``(1 - confidence) / 2`` quantile of the
    replicates' last level *not* detected (the minimum lies above it), the upper
    bound the ``(1 + confidence) / 2`` quantile of their first level detected
    (``inf`` where more than that fraction never reaches ``power``). Quantiles
    are order statistics (no interpolation, so ``inf`` is handled exactly), and
    the bounds are widened, if needed, to contain the bracket of the estimate.

    Parameters
    ----------
    levels : array_like, shape (s,)
        Swept condition value of each data set.
    samples : list of array_like
        Used feature values of each data set.
    reference : int
        Index of the reference data set (zero level) in ``levels``.
    false_alarm_rate, power : float
    n_boot : int, default 1000
    confidence : float, default 0.95
    seed : int, Generator or None

    Returns
    -------
    dict
        ``probability`` (per data set), ``estimate`` (interpolated, NaN when
        ``power`` is never reached), ``bracket`` and ``bounds`` (each ``(lower,
        upper)``), the replicates' interpolated minima ``replicates`` (``inf``:
        not reached), and ``resolution`` (:func:`sweep_resolution`) with the
        value that may be printed, ``printed`` (:func:`printed_estimate`; NaN
        unless the sweep resolves it).
    """
    levels = np.asarray(levels, dtype=float)
    samples = [np.asarray(s, dtype=float) for s in samples]
    probability = np.array([detection_probability(samples[reference], s, false_alarm_rate) for s in samples])
    estimate, lower, upper = minimum_detectable(levels, probability, power)
    rng = np.random.default_rng(seed)
    resampled = [s[rng.integers(0, len(s), (n_boot, len(s)))] for s in samples]
    boot = np.stack([_detection_probabilities(resampled[reference], r, false_alarm_rate) for r in resampled], axis=1)
    brackets = np.array([minimum_detectable(levels, p, power) for p in boot])
    alpha = 0.5 * (1.0 - confidence)
    bounds = (
        min(float(np.quantile(brackets[:, 1], alpha, method="inverted_cdf")), lower),
        max(float(np.quantile(brackets[:, 2], 1.0 - alpha, method="inverted_cdf")), upper),
    )
    resolution = sweep_resolution(levels, estimate, bounds)
    return {
        "probability": probability,
        "probability_se": boot.std(axis=0, ddof=1),
        "probability_ci": detection_probability_interval(probability, boot, [len(s) for s in samples], confidence),
        "estimate": estimate,
        "bracket": (lower, upper),
        "bounds": bounds,
        "replicates": np.where(np.isnan(brackets[:, 0]), math.inf, brackets[:, 0]),
        "resolution": resolution,
        "printed": printed_estimate(estimate, bounds) if resolution == "resolved" else math.nan,
    }


def detection_probability_interval(probability, replicates, n_runs, confidence: float = CONFIDENCE) -> np.ndarray:
    """Interval of each sweep level's detection probability, shape (levels, 2) (:data:`DETECTION_INTERVAL_METHOD`).

    The percentile interval of the bootstrap ``replicates`` (shape (n_boot, levels): the reference and the level's
    runs resampled, so the threshold's own scatter is in it), widened to contain the exact (Clopper-Pearson)
    interval of the level's count at the estimated threshold: a level whose every run is flagged has every replicate
    at 1, yet its runs bound the probability only to ``(1 - c/2)^(1/n)`` (0.94 at 59 runs), which a bar at 1 would
    hide.
    """
    alpha = 0.5 * (1.0 - confidence)
    boot_low, boot_high = np.quantile(np.asarray(replicates, dtype=float), [alpha, 1.0 - alpha], axis=0)
    out = np.full((len(n_runs), 2), math.nan)
    for i, (p, n) in enumerate(zip(probability, n_runs, strict=True)):
        if n and math.isfinite(p):
            exact = stats.binomtest(round(p * n), n).proportion_ci(confidence_level=confidence, method="exact")
            out[i] = min(boot_low[i], exact.low), max(boot_high[i], exact.high)
    return out


#: How :func:`detection_probability_interval` bounds a level's detection probability, in words (analysis.nc).
DETECTION_INTERVAL_METHOD = ("percentile bootstrap (every sweep data set's runs resampled, the reference's threshold "
                             "with them), widened to contain the exact Clopper-Pearson interval of the level's count "
                             "at the estimated threshold")


def sweep_resolution(levels, estimate: float, bounds: tuple[float, float]) -> str:
    """Whether the sweep resolves the minimum detectable level, or only brackets it (one of :data:`RESOLUTIONS`).

    Between two sweep levels the data say nothing: the linear interpolation of the estimate is not evidence. The
    value is ``"resolved"`` when the bootstrap bounds are finite and hold a sweep level strictly inside: the sampling
    uncertainty then spans more than one sweep step, so the interpolation's error (at most one step) is within the
    stated bounds (or the bounds are one level, the estimate itself). Otherwise the estimate lies
    ``"between_adjacent_levels"`` (the bracket is the finding), or ``"beyond_sweep"`` when no level reaches the
    power.
    """
    if not math.isfinite(estimate):
        return "beyond_sweep"
    lower, upper = bounds
    levels = np.asarray(levels, dtype=float)
    if math.isfinite(upper) and (lower == upper or ((levels > lower) & (levels < upper)).any()):
        return "resolved"
    return "between_adjacent_levels"


def printed_estimate(estimate: float, bounds: tuple[float, float]) -> float:
    """The estimate rounded at the leading digit of its bounds' half-width: a result is given to the precision of its
    uncertainty (JCGM 100:2008, GUM, Sec. 7.2.6), e.g. 1.19 µm within 0.5-1.5 µm is 1.2 µm; 371 N within 0-600 N is
    400 N. Bounds of zero width (the estimate is a sweep level) leave it as it is."""
    half_width = 0.5 * (bounds[1] - bounds[0])
    if not (math.isfinite(estimate) and math.isfinite(half_width) and half_width > 0):
        return estimate
    step = 10.0 ** math.floor(math.log10(half_width))
    return round(estimate / step) * step


#: The largest number of runs :func:`runs_to_decide` reports; beyond it the answer is "more than" this.
MAX_RUNS_TO_DECIDE = 1_000_000


def runs_to_decide(levels, probability, probability_se, n: int, requirement: float, *, power: float = POWER,
                   confidence: float = CONFIDENCE, labels=None) -> tuple[float, str]:
    """Runs per sweep data set at which an undetermined verdict would be decided if the estimate holds.

    The verdict is ``met`` once the upper bound is within the requirement: a sweep level ``l <= requirement`` is
    detected with probability ``power`` in all but ``(1 - confidence) / 2`` of the bootstrap replicates; ``not met``
    once the lower bound reaches it: the smallest level ``l >= requirement`` is not detected in as many. With the
    detection probability ``p`` of that level as estimated and its bootstrap standard error ``se`` at ``n`` runs
    falling as ``1/sqrt(runs)`` (every sweep data set growing alike: the threshold's quantile and the level's
    fraction are both sample statistics), a normal replicate distribution clears ``power`` once
    ``|p - power| >= z se sqrt(n / runs)`` with ``z`` the ``(1 + confidence) / 2`` normal quantile, so::

        runs = ceil(n (z se / (p - power))^2)

    for the level that decides (the largest level at or below the requirement with ``p >= power``, else the
    smallest at or above it with ``p < power``). No number of runs decides when the sweep has no level on the side
    the estimate points to (the crossing lies strictly between two levels around the requirement, or ``p`` equals
    ``power``): then a sweep level at the requirement is needed, and the reason says so.

    ``labels`` name the levels in the reason (default: the number).

    Returns
    -------
    tuple of (float, str)
        ``(runs, reason)``: runs per sweep data set (NaN when no number decides, or when the numbers do not allow
        the estimate) and one sentence saying how it was derived or why there is none.
    """
    levels = np.asarray(levels, dtype=float)
    probability, probability_se = np.asarray(probability, dtype=float), np.asarray(probability_se, dtype=float)
    z = float(stats.norm.ppf(0.5 + 0.5 * confidence))
    below = [i for i in np.argsort(levels) if levels[i] <= requirement and probability[i] >= power]
    above = [i for i in np.argsort(levels) if levels[i] >= requirement and probability[i] < power]
    if below:
        i, decides = below[-1], "met"
    elif above:
        i, decides = above[0], "not met"
    else:
        return math.nan, ("no number of runs decides it: the detection probability crosses "
                          f"{power * 100:g} % between two sweep levels on either side of the requirement; a sweep "
                          "level at the requirement is needed")
    gap = abs(probability[i] - power)
    if gap == 0.0 or not math.isfinite(probability_se[i]):
        return math.nan, (f"no number of runs decides it: the detection probability at the deciding level is "
                          f"{probability[i] * 100:.3g} %, on the {power * 100:g} % line")
    needed = max(n + 1, math.ceil(n * (z * probability_se[i] / gap) ** 2))
    if needed > MAX_RUNS_TO_DECIDE:
        return math.inf, f"more than {MAX_RUNS_TO_DECIDE} runs per sweep data set"
    return float(needed), (
        f"{decides} would be decided at about {needed} ok runs per sweep data set if the estimate holds: the "
        f"detection probability of the {labels[i] if labels is not None else f'{levels[i]:.3g}'} level, "
        f"{probability[i] * 100:.3g} % (bootstrap standard "
        f"error {probability_se[i] * 100:.2g} points at {n} runs, falling as 1/sqrt(runs)), would then lie "
        f"{z:.2f} standard errors from {power * 100:g} %")


def requirement_verdict(lower: float, upper: float, requirement: float = BACKLASH_REQUIREMENT) -> str:
    """Verdict on the requirement from the bounds of the minimum detectable level.

    ``"met"`` when the upper bound (a level detected) is within ``requirement``;
    ``"not met"`` when the lower bound (a level not detected: the minimum lies
    above it) is at or above it; ``"undetermined"`` otherwise, and when a bound
    is unknown (NaN).
    """
    if upper <= requirement:
        return "met"
    if lower >= requirement:
        return "not met"
    return "undetermined"


def _runs(n: int) -> str:
    return f"{n} ok run{'s' if n != 1 else ''}"


def requirement_statement(
    verdict: str,
    estimate: float,
    bounds: tuple[float, float],
    n_used: dict[str, int],
    *,
    resolution: str = "resolved",
    bracket: tuple[float, float] = (math.nan, math.nan),
    levels: dict[str, float] | None = None,
    confidence: float = CONFIDENCE,
    power: float = POWER,
    false_alarm_rate: float = FALSE_ALARM_RATE,
    min_runs: int = MIN_DETECTION_RUNS,
    condition: str = "backlash",
    requirement: float = BACKLASH_REQUIREMENT,
    requirement_source: str = "Table 9.3",
) -> str:
    """The one sentence that states the verdict on the requirement (Table 9.3's by default), from the numbers.

    Parameters
    ----------
    verdict : str
        From :func:`requirement_verdict`, or ``"insufficient data"``.
    estimate : float
        The value that may be printed [SI] (``printed`` of :func:`bootstrap_minimum_detectable`); used only when
        ``resolution`` is ``"resolved"``.
    bounds : tuple of float
        Bootstrap bounds [SI] (lower: a level not detected, upper: a level detected, ``inf``: possibly beyond the
        sweep).
    n_used : dict
        Ok runs of each sweep data set (empty: no sweep).
    resolution, bracket
        From :func:`sweep_resolution`; the sweep levels around the estimate (:func:`minimum_detectable`).
    levels : dict, optional
        Fault size of each sweep data set [SI]: every level the sentence gives is named by its data set.
    confidence, power, false_alarm_rate, min_runs
        As used for the numbers (``min_runs``: the floor of every sweep data set, :func:`detection_run_floor`).
    condition, requirement, requirement_source
        The swept condition (:data:`SWEEP_QUANTITIES`), the requirement on its fault size (SI) and its source.
    """
    quantity, _, scale, unit = SWEEP_QUANTITIES[condition]
    names = {}
    for name, value in (levels or {}).items():
        names.setdefault(float(value), name)

    def fmt(value: float) -> str:  # in the display unit of the fault quantity (µm for the backlash)
        return f"{value * scale:.3g} {unit}"

    def level(value: float) -> str:  # a sweep level, named by its data set
        return f"{fmt(value)} ({names[value]})" if value in names else fmt(value)

    against = f"against the {fmt(requirement)} requirement of {requirement_source}"
    if not n_used:
        return (
            "insufficient data: the spec has no observability sweep, "
            f"so no minimum detectable {quantity} is estimated {against}")
    short = [f"{name} has {_runs(n)}" for name, n in n_used.items() if n < min_runs]
    if len(short) == len(n_used) > 1 and len(set(n_used.values())) == 1:
        short = [f"each of the {len(n_used)} sweep data sets has {_runs(next(iter(n_used.values())))}"]
    if short:
        return (
            f"insufficient data: {', '.join(short)}; at least {min_runs} per sweep data set are needed "
            f"({_floor_reason(false_alarm_rate, power, confidence)}), "
            f"so no minimum detectable {quantity} is estimated {against}"
        )
    counts = sorted(set(n_used.values()))
    runs = f"{counts[0]}" if len(counts) == 1 else f"{counts[0]}–{counts[-1]}"
    lower, upper = bounds
    if resolution == "resolved":
        value = fmt(estimate)
    elif resolution == "between_adjacent_levels":
        value = f"between the adjacent sweep levels {level(bracket[0])} and {level(bracket[1])}"
    else:
        value = (f"above {level(bracket[0])}, the largest sweep level: detection probability below {power * 100:g} % "
                 "along the whole sweep")
    upper_text = f"at most {level(upper)}" if math.isfinite(upper) else "possibly beyond the sweep"
    return (
        f"{verdict}: minimum detectable {quantity} {value} ({confidence * 100:g} % bootstrap bounds: above "
        f"{level(lower)}, {upper_text}; {runs} ok runs per sweep data set, {len(n_used)} data sets) {against}"
    )


def _floor_reason(false_alarm_rate: float, power: float, confidence: float) -> str:
    """Why a sweep data set needs :func:`detection_run_floor` runs, in words (the quantile that binds)."""
    threshold = min_runs_for_quantile_bound(1.0 - false_alarm_rate, confidence)
    if threshold >= min_runs_for_quantile_bound(power, confidence):
        return (f"with fewer, not even the largest run bounds the {(1 - false_alarm_rate) * 100:g} % quantile that "
                f"sets the detection threshold from above with {confidence * 100:g} % confidence")
    return (f"with fewer, not even the smallest run bounds the {(1 - power) * 100:g} % quantile that "
            f"{power * 100:g} % detection rests on from below with {confidence * 100:g} % confidence")


def _used(results: xr.Dataset, feature: str) -> xr.DataArray:
    return (results["status"] == "ok") & np.isfinite(results[feature])


def sweep_levels(results: xr.Dataset, datasets: list[str], condition: str = "backlash",
                 reference: str | None = None) -> tuple[np.ndarray, int]:
    """The fault size [SI] of each sweep data set, ``|condition - condition of the reference|``, and the index of the
    reference (``reference`` named, else the data set where the condition is zero)."""
    values = np.array([float(results[f"condition_{condition}"].sel(dataset=n)) for n in datasets])
    index = datasets.index(reference) if reference is not None else int(np.flatnonzero(values == 0.0)[0])
    return np.abs(values - values[index]), index


def observability_sweep(
    results: xr.Dataset,
    feature: str,
    datasets: list[str],
    *,
    false_alarm_rate: float = FALSE_ALARM_RATE,
    power: float = POWER,
    n_boot: int = 1000,
    confidence: float = CONFIDENCE,
    min_runs: int | None = None,
    seed=None,
    condition: str = "backlash",
    reference: str | None = None,
    requirement: float = BACKLASH_REQUIREMENT,
    requirement_source: str = REQUIREMENT_SOURCE,
) -> xr.Dataset:
    """Detection probability along a fault sweep, the minimum detectable fault size and the verdict.

    Parameters
    ----------
    results : xarray.Dataset
        Campaign results (``results.nc``).
    feature : str
    datasets : list of str
        The sweep (data sets differing only in backlash, ``observability.sweep``
        of the spec); the data set with zero backlash is the reference.
    false_alarm_rate, power : float
        The detection threshold flags ``false_alarm_rate`` of the reference runs;
        the minimum detectable backlash is where the detection probability reaches ``power``.
    n_boot, confidence, seed
        Bootstrap of :func:`bootstrap_minimum_detectable`.
    min_runs : int, optional
        Ok runs every sweep data set needs (default :func:`detection_run_floor` of the settings); below it the
        verdict is ``"insufficient data"`` and the detection probability of that data set is NaN (of every data
        set, when the reference is short).
    condition, reference, requirement, requirement_source
        The swept scene condition (:data:`SWEEP_QUANTITIES`; ``observability.condition`` of the
        spec), the reference data set (default: the one where it is zero), the requirement on the
        fault size (SI) and its source.

    Returns
    -------
    xarray.Dataset
        ``sweep_<q>(sweep_point)``, ``sweep_detection_probability(sweep_point)``,
        the scalar ``minimum_detectable_<q>`` (the requirement in its attributes; NaN unless the sweep
        resolves it), ``minimum_detectable_status`` (:data:`RESOLUTIONS`, numeric flags),
        ``minimum_detectable_bracket(bound)`` (the sweep levels around the estimate),
        ``minimum_detectable_<q>_ci(bound)``, ``requirement_verdict`` and ``requirement_statement``,
        where ``<q>`` is the fault quantity (``backlash``, ``preload_loss``).
    """
    quantity, unit, _, _ = SWEEP_QUANTITIES[condition]
    stem = quantity.replace(" ", "_")
    backlash, reference = sweep_levels(results, datasets, condition, reference)
    used = _used(results, feature)
    samples = [results[feature].sel(dataset=n).values[used.sel(dataset=n).values] for n in datasets]
    n_used = {n: len(s) for n, s in zip(datasets, samples, strict=False)}
    if min_runs is None:
        min_runs = detection_run_floor(false_alarm_rate, power, confidence)
    nan2 = (math.nan, math.nan)
    needed, needed_reason = math.nan, "the verdict is decided"
    if min(n_used.values()) < min_runs:
        needed = float(min_runs)
        needed_reason = (f"{min_runs} ok runs per sweep data set are needed before any verdict "
                         f"({_floor_reason(false_alarm_rate, power, confidence)})")
        enough = [len(s) >= min_runs and n_used[datasets[reference]] >= min_runs for s in samples]
        probability = np.array([detection_probability(samples[reference], s, false_alarm_rate) if ok else math.nan
                                for s, ok in zip(samples, enough, strict=False)])
        found = {"estimate": math.nan, "printed": math.nan, "bracket": nan2, "bounds": nan2,
                 "resolution": "insufficient_data", "probability_ci": np.full((len(datasets), 2), math.nan)}
        verdict = "insufficient data"
    else:
        found = bootstrap_minimum_detectable(
            backlash, samples, reference, false_alarm_rate=false_alarm_rate, power=power, n_boot=n_boot,
            confidence=confidence, seed=seed,
        )
        probability = found["probability"]
        verdict = requirement_verdict(*found["bounds"], requirement)
        if verdict == "undetermined":
            _, _, scale, shown = SWEEP_QUANTITIES[condition]
            needed, needed_reason = runs_to_decide(
                backlash, probability, found["probability_se"], min(n_used.values()), requirement, power=power,
                confidence=confidence, labels=[f"{b * scale:.3g} {shown} ({n})" for b, n in zip(backlash, datasets,
                                                                                                  strict=True)])
    statement = requirement_statement(
        verdict, found["printed"], found["bounds"], n_used, resolution=found["resolution"], bracket=found["bracket"],
        levels=dict(zip(datasets, backlash, strict=True)), confidence=confidence, power=power,
        false_alarm_rate=false_alarm_rate, min_runs=min_runs, condition=condition, requirement=requirement,
        requirement_source=requirement_source.removeprefix("Bertolino (2020) ").split(":")[0],
    )
    return xr.Dataset(
        {
            f"sweep_{stem}": ("sweep_point", backlash,
                              {"units": unit, "long_name": f"{quantity} of the sweep data set"}),
            "sweep_detection_probability": (
                "sweep_point",
                probability,
                {"units": "1",
                 "long_name": f"detection probability at false-alarm rate {false_alarm_rate:g} against "
                              f"{datasets[reference]} (NaN: insufficient data)"},
            ),
            "sweep_detection_probability_ci": (
                ("sweep_point", "bound"),
                found["probability_ci"],
                {"units": "1", "long_name": f"{confidence:g} interval of sweep_detection_probability (NaN: "
                                            "insufficient data)", "method": DETECTION_INTERVAL_METHOD}),
            f"minimum_detectable_{stem}": (
                (),
                found["estimate"] if found["resolution"] == "resolved" else math.nan,
                {
                    "units": unit,
                    "long_name": f"smallest {quantity} detected with probability {power:g} at false-alarm rate "
                                 f"{false_alarm_rate:g}, interpolated along the sweep, only where the sweep "
                                 "resolves it (minimum_detectable_status = resolved), else NaN: read "
                                 "minimum_detectable_bracket; print it rounded at the leading digit of the "
                                 "half-width of its bounds (campaigns.analysis.campaign_analysis.printed_estimate)",
                    "requirement": requirement,
                    "requirement_source": requirement_source,
                },
            ),
            "minimum_detectable_status": ((), np.int8(RESOLUTIONS.index(found["resolution"])), _RESOLUTION_ATTRS),
            "minimum_detectable_bracket": (
                "bound",
                np.array(found["bracket"]),
                {"units": unit,
                 "long_name": f"sweep levels bracketing minimum_detectable_{stem} (inf: never detected)"},
            ),
            f"minimum_detectable_{stem}_ci": (
                "bound",
                np.array(found["bounds"]),
                {
                    "units": unit,
                    "long_name": f"bootstrap bounds of the minimum detectable {quantity}: "
                                 "lower = a sweep level not detected "
                    "(the minimum lies above it), upper = a sweep level detected (inf: not reached)",
                    "confidence": confidence,
                    "n_boot": n_boot,
                },
            ),
            "requirement_verdict": ((), verdict, _VERDICT_ATTRS),
            "requirement_statement": ((), statement, _STATEMENT_ATTRS),
            "runs_to_decide": ((), needed, {
                "units": "1",
                "long_name": "ok runs per sweep data set at which an undetermined (or insufficient-data) verdict "
                             "would be decided if the estimate holds "
                             "(campaigns.analysis.campaign_analysis.runs_to_decide); NaN: "
                             "decided, or no number of runs decides it (runs_to_decide_reason says which)"}),
            "runs_to_decide_reason": ((), needed_reason, {"long_name": "how runs_to_decide was derived, or why "
                                                                       "there is none"}),
        },
        coords={
            "sweep_point": ("sweep_point", np.array(datasets, dtype=object), {"long_name": "data set of the sweep"}),
            "bound": ("bound", np.array(["lower", "upper"], dtype=object)),
        },
    )


def analysis_dataset(
    results: xr.Dataset,
    *,
    n_boot: int = 1000,
    confidence: float = 0.95,
    false_alarm_rate: float = FALSE_ALARM_RATE,
    power: float = POWER,
    seed: int = 0,
    min_ok_runs: int = MIN_OK_RUNS,
    min_detection_runs: int | None = None,
    sensitivity_boot: int = 200,
) -> xr.Dataset:
    """Compute every statistic of :func:`analyze` on an opened results dataset.

    A data set with fewer than ``min_ok_runs`` used runs of a feature is flagged
    in ``data_sufficient`` and gets NaN correlations, indices and detection
    probabilities for that feature; its mean, standard deviation and quantiles
    are computed at any n, each with the interval its method allows there
    (:func:`mean_interval`, :func:`std_interval`, :func:`quantile_interval`). A detection
    probability needs ``min_detection_runs`` (default :func:`detection_run_floor`
    of ``false_alarm_rate``, ``power`` and ``confidence``) in its reference data
    set, and the verdict in every sweep data set. ``sensitivity_boot`` resamples
    give the interval of the first-order index
    (:func:`campaigns.statistics.sensitivity.first_order`); an index below
    :data:`campaigns.statistics.sensitivity.MIN_RUNS` runs, or outside its own interval, is
    flagged in ``first_order_index_flag``: every output prints its interval only.
    """
    if min_ok_runs < 3:
        raise ValueError(
            f"min_ok_runs = {min_ok_runs}: must be at least 3 (a standard deviation and a correlation need 3 runs)")
    if min_detection_runs is None:
        min_detection_runs = detection_run_floor(false_alarm_rate, power, confidence)
    min_detection_runs = max(min_detection_runs, min_ok_runs)
    parameters = [v for v in results.data_vars if results[v].attrs.get("role") == "sampled"]
    features = [v for v in results.data_vars if results[v].attrs.get("role") == "feature"]
    names = [str(n) for n in results["dataset"].values]
    shape = (len(names), len(features), len(parameters))
    out = {k: np.full(shape, math.nan) for k in ("pearson", "spearman", "prcc")}
    ci = {k: np.full(shape + (2,), math.nan) for k in ("pearson", "spearman", "first_order_index", "effect_size")}
    out["first_order_index"], effect_size = np.full(shape, math.nan), np.full(shape, math.nan)
    first_order_flag = np.zeros(shape, dtype=np.int8)
    n_used = np.zeros((len(names), len(features)), dtype=np.int64)
    mean, std = np.full(n_used.shape, math.nan), np.full(n_used.shape, math.nan)
    mean_ci, std_ci = np.full(n_used.shape + (2,), math.nan), np.full(n_used.shape + (2,), math.nan)
    quantiles = np.full(n_used.shape + (len(QUANTILE_PROBABILITIES),), math.nan)
    quantiles_ci = np.full(quantiles.shape + (2,), math.nan)
    overlap = np.full((len(features), len(names), len(names)), math.nan)
    detection = np.full_like(overlap, math.nan)
    used_values: dict[tuple[int, int], np.ndarray] = {}
    for d, name in enumerate(names):
        row = results.sel(dataset=name)
        for f, feature in enumerate(features):
            mask = _used(results, feature).sel(dataset=name).values
            y = row[feature].values[mask]
            n_used[d, f] = len(y)
            first_order_flag[d, f] = sensitivity.BELOW_MIN_RUNS if len(y) < sensitivity.MIN_RUNS else 0
            # moments and quantiles at any n, each with the interval its method allows there (issue 42): a few runs
            # already separate data sets whose means differ by many spreads
            mean[d, f], *mean_ci[d, f] = mean_interval(y, confidence)
            std[d, f], *std_ci[d, f] = std_interval(y, confidence)
            for k, q in enumerate(QUANTILE_PROBABILITIES):
                quantiles[d, f, k], *quantiles_ci[d, f, k] = quantile_interval(y, q, confidence)
            if len(y) < min_ok_runs:
                continue
            used_values[d, f] = y
            X = np.stack([row[p].values[mask] for p in parameters]) if parameters else np.empty((0, len(y)))
            rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(d, f)))
            idx = rng.integers(0, len(y), (n_boot, len(y)))
            for method in ("pearson", "spearman"):
                estimate, lower, upper = _correlations(X, y, idx, method, confidence)
                out[method][d, f] = estimate
                ci[method][d, f, :, 0], ci[method][d, f, :, 1] = lower, upper
            out["prcc"][d, f] = prcc(X.T, y)
            found = sensitivity.first_order(
                X.T, y, n_boot=sensitivity_boot, confidence=confidence,
                seed=np.random.SeedSequence(seed, spawn_key=(_SENSITIVITY_STREAM, d, f)),
            )
            first_order_flag[d, f] = sensitivity.unresolved(found["index"], found["ci"], len(y))
            out["first_order_index"][d, f], effect_size[d, f] = found["index"], found["effect_size"]
            ci["first_order_index"][d, f], ci["effect_size"][d, f] = found["ci"], found["effect_size_ci"]
    for f in range(len(features)):
        for a, b in ((a, b) for a in range(len(names)) for b in range(len(names))):
            if (a, f) in used_values and (b, f) in used_values:
                overlap[f, a, b] = overlap_coefficient(used_values[a, f], used_values[b, f])
                if n_used[b, f] >= min_detection_runs:  # b's quantile is the threshold
                    detection[f, a, b] = detection_probability(used_values[b, f], used_values[a, f],
                                                               false_alarm_rate)
    statuses = sorted(set(results["status"].values.ravel().tolist()))
    n_status = np.array([[int((results["status"].sel(dataset=n) == s).sum()) for s in statuses] for n in names])
    n_runs = results.sizes["run"]

    corr_dims = ("dataset", "feature", "parameter")
    in_feature_units = _feature_units([str(results[f].attrs.get("units", "1")) for f in features])
    data_vars = {
        "n_used": (("dataset", "feature"), n_used.astype(np.int32),
                   {"units": "1", "long_name": "runs used (status ok, finite feature)"}),
        "n_excluded": (("dataset", "feature"), (n_runs - n_used).astype(np.int32),
                       {"units": "1", "long_name": "runs excluded from the statistics"}),
        "n_status": (("dataset", "status"), n_status.astype(np.int32), {"units": "1", "long_name": "runs per status"}),
        "data_sufficient": (
            ("dataset", "feature"),
            (n_used >= min_ok_runs).astype(np.int8),
            {
                "long_name": f"at least {min_ok_runs} used runs (else the data set's correlations, indices and "
                             "detection probabilities are NaN; its mean, standard deviation and quantiles are given "
                             "with their intervals at any n, which below this floor rest on a shape so few runs "
                             "cannot check)",
                "flag_values": np.array([0, 1], dtype=np.int8),
                "flag_meanings": "insufficient_data sufficient_data",
                "min_ok_runs": min_ok_runs,
            },
        ),
        "feature_mean": (("dataset", "feature"), mean,
                         {"long_name": "mean of the feature over used runs (from 1 run)", **in_feature_units}),
        "feature_mean_ci": (("dataset", "feature", "bound"), mean_ci,
                            {"long_name": f"{confidence:g} interval of feature_mean (below min_ok_runs, "
                                          "data_sufficient = 0: flagged, read as indicative)",
                             "method": MEAN_INTERVAL_METHOD, **in_feature_units}),
        "feature_std": (("dataset", "feature"), std,
                        {"long_name": "standard deviation of the feature over used runs (from 2 runs)",
                         **in_feature_units}),
        "feature_std_ci": (("dataset", "feature", "bound"), std_ci,
                           {"long_name": f"{confidence:g} interval of feature_std (below min_ok_runs, "
                                          "data_sufficient = 0: flagged, read as indicative)",
                            "method": STD_INTERVAL_METHOD, **in_feature_units}),
        "feature_quantile": (("dataset", "feature", "quantile_probability"), quantiles,
                             {"long_name": "quantile of the feature over used runs (linear interpolation between "
                                           "order statistics)", **in_feature_units}),
        "feature_quantile_ci": (("dataset", "feature", "quantile_probability", "bound"), quantiles_ci,
                                {"long_name": f"{confidence:g} interval of feature_quantile (NaN: n too small for a "
                                              "bound, below feature_quantile_min_runs)",
                                 "method": QUANTILE_INTERVAL_METHOD, **in_feature_units}),
        "feature_quantile_min_runs": (
            "quantile_probability",
            np.array([quantile_interval_min_runs(q, confidence) for q in QUANTILE_PROBABILITIES], dtype=np.int32),
            {"units": "1", "long_name": "fewest used runs with which order statistics bound the quantile on both "
                                        f"sides at {confidence:g}"}),
        "pearson": (corr_dims, out["pearson"], {"units": "1", "long_name": "Pearson correlation"}),
        "pearson_ci": (corr_dims + ("bound",), ci["pearson"],
                       {"units": "1", "long_name": f"{confidence:g} percentile-bootstrap interval of pearson"}),
        "spearman": (corr_dims, out["spearman"], {"units": "1", "long_name": "Spearman rank correlation"}),
        "spearman_ci": (corr_dims + ("bound",), ci["spearman"],
                        {"units": "1", "long_name": f"{confidence:g} percentile-bootstrap interval of spearman"}),
        "prcc": (corr_dims, out["prcc"], {"units": "1", "long_name": "partial rank correlation coefficient"}),
        "first_order_index": (
            corr_dims,
            out["first_order_index"],
            {"units": "1",
             "long_name": "first-order (Sobol') index: share of the feature's variance explained by the parameter "
                          "alone, any shape of dependence; not to be printed where first_order_index_flag is set "
                          f"(below {sensitivity.MIN_RUNS} used runs, or outside its own interval): print the interval",
             "method": sensitivity.METHOD, "min_runs": sensitivity.MIN_RUNS},
        ),
        "first_order_index_flag": (
            corr_dims,
            first_order_flag,
            {"long_name": "why first_order_index and effect_size are not resolved (0: they are): fewer used runs "
                          f"than {sensitivity.MIN_RUNS} (the chance level of inert parameters' indices is then above "
                          "0.1), or the estimate outside its own bootstrap interval; where set, only the intervals "
                          "are printed",
             "flag_masks": np.array([sensitivity.BELOW_MIN_RUNS, sensitivity.OUTSIDE_INTERVAL], dtype=np.int8),
             "flag_meanings": sensitivity.FLAG_MEANINGS, "min_runs": sensitivity.MIN_RUNS},
        ),
        "first_order_index_ci": (
            corr_dims + ("bound",),
            ci["first_order_index"],
            {"units": "1", "long_name": f"{confidence:g} percentile-bootstrap interval of first_order_index",
             "n_boot": sensitivity_boot, "method": sensitivity.METHOD},
        ),
        "effect_size": (
            corr_dims,
            effect_size,
            {
                "long_name": "standard deviation of the conditional mean E[feature | parameter] over the parameter's "
                             "distribution, sqrt(max(first_order_index, 0) var(feature)): "
                             "what the parameter alone moves the feature by (not resolved where "
                             "first_order_index_flag is set: print effect_size_ci)",
                "method": sensitivity.METHOD,
                **in_feature_units,
            },
        ),
        "effect_size_ci": (
            corr_dims + ("bound",),
            ci["effect_size"],
            {"long_name": "effect_size at the bounds of first_order_index_ci (feature variance held fixed)",
             **in_feature_units},
        ),
        "overlap": (("feature", "dataset", "reference"), overlap,
                    {"units": "1", "long_name": "overlap coefficient of the feature distributions"}),
        "detection_probability": (
            ("feature", "dataset", "reference"),
            detection,
            {"units": "1",
             "long_name": "fraction of dataset runs beyond the reference's threshold at false-alarm rate "
                          f"{false_alarm_rate:g} (NaN: fewer than min_detection_runs in the reference, or "
                          "min_ok_runs in the data set)"},
        ),
    }
    coords = {
        "dataset": ("dataset", np.array(names, dtype=object)),
        "reference": ("reference", np.array(names, dtype=object)),
        "feature": ("feature", np.array(features, dtype=object)),
        "feature_units": ("feature", np.array([str(results[f].attrs.get("units", "1")) for f in features],
                                              dtype=object), {"long_name": "units of each feature"}),
        "parameter": ("parameter", np.array(parameters, dtype=object)),
        "bound": ("bound", np.array(["lower", "upper"], dtype=object)),
        "quantile_probability": ("quantile_probability", np.array(QUANTILE_PROBABILITIES),
                                 {"units": "1", "long_name": "probability of the quantile"}),
        "status": ("status", np.array(statuses, dtype=object)),
    }
    analysis = xr.Dataset(data_vars, coords=coords)
    stored_spec = json.loads(results.attrs["spec_json"])["spec"]
    observability = stored_spec["observability"]
    sweep = observability["sweep"]
    condition = observability.get("condition", "backlash")
    requirement = (observability.get("requirement") or BACKLASH_REQUIREMENT, observability.get("requirement_source")
                   or REQUIREMENT_SOURCE)
    within_unit = stored_spec.get("units") is not None and bool(sweep)  # a fidelity audit's runs keep units, no sweep
    # A unit's tests share its fixed errors: between units, one test per unit keeps the sweep's runs independent.
    between_units = results.isel(run=results["repeat"].values == 0) if within_unit else results
    if sweep:
        per_feature = [
            observability_sweep(
                between_units, feature, sweep, false_alarm_rate=false_alarm_rate, power=power, n_boot=n_boot,
                confidence=confidence, min_runs=min_detection_runs,
                seed=np.random.SeedSequence(seed, spawn_key=(_OBSERVABILITY_STREAM, f)), condition=condition,
                reference=observability.get("reference"), requirement=requirement[0], requirement_source=requirement[1],
            )
            for f, feature in enumerate(features)
        ]
        levels = f"sweep_{SWEEP_QUANTITIES[condition][0].replace(' ', '_')}"
        combined = xr.concat([s.drop_vars(levels) for s in per_feature], dim="feature")
        analysis = analysis.merge(combined.assign_coords(feature=analysis["feature"]))
        analysis[levels] = per_feature[0][levels]
    else:
        statement = requirement_statement("insufficient data", math.nan, (math.nan, math.nan), {})
        analysis["requirement_verdict"] = ("feature", np.full(len(features), "insufficient data", dtype=object),
                                           _VERDICT_ATTRS)
        analysis["requirement_statement"] = ("feature", np.full(len(features), statement, dtype=object),
                                             _STATEMENT_ATTRS)
        analysis["runs_to_decide"] = ("feature", np.full(len(features), math.nan), {"units": "1"})
        analysis["runs_to_decide_reason"] = ("feature", np.full(len(features), "no observability sweep",
                                                                dtype=object))
    within_unit_settings = {}
    if within_unit:
        from campaigns.analysis.within_unit import within_unit_analysis  # here: within_unit builds on this module

        analysis["requirement_statement"] = ("feature", np.array(
            [f"{statement}; between units: one test per unit (repeat 0 of each of the "
             f"{between_units.sizes['run']} units), since a unit's tests share its fixed errors and are not "
             "independent draws" for statement in analysis["requirement_statement"].values], dtype=object),
            _STATEMENT_ATTRS)
        found = within_unit_analysis(results, features, observability, seed=seed, stream=_WITHIN_UNIT_STREAM,
                                     false_alarm_rate=false_alarm_rate, power=power, n_boot=n_boot,
                                     confidence=confidence)
        within_unit_settings = found.attrs
        analysis = analysis.merge(found.drop_attrs(deep=False), combine_attrs="override")
    analysis.attrs = {
        "Conventions": CONVENTIONS,
        "title": f"Analysis of {results.attrs.get('title', 'a BenchTwin campaign')}",
        "source_spec_hash": results.attrs.get("spec_hash", ""),
        "selection": "statistics use runs with status 'ok' and a finite feature; see n_used, n_excluded, n_status",
        "bootstrap": json.dumps({"method": "percentile, pairs resampled", "n_boot": n_boot, "confidence": confidence,
                                 "seed": seed}),
        "false_alarm_rate": false_alarm_rate,
        "detection_power": power,
        "backlash_sweep": json.dumps(sweep),
        "min_ok_runs": min_ok_runs,
        "min_detection_runs": min_detection_runs,
        "min_detection_runs_reason": _floor_reason(false_alarm_rate, power, confidence),
        "first_order_min_runs": sensitivity.MIN_RUNS,
        "observability_condition": condition,
        "requirement": requirement[0],
        "requirement_units": SWEEP_QUANTITIES[condition][1],
        "requirement_source": requirement[1],
        **within_unit_settings,
    }
    robustness = control_robustness(results, correlate=bootstrap_correlation, verdict_rule=requirement_verdict,
                                    features=features, n_boot=n_boot, confidence=confidence, seed=seed,
                                    min_ok_runs=min_ok_runs)
    return analysis.merge(robustness, combine_attrs="override")


def _feature_units(units: list[str]) -> dict[str, str]:
    """The ``units`` attribute of a variable along the feature axis: the features' common unit, or (features in
    several units; CF gives one unit per variable) a comment that points at the ``feature_units`` coordinate."""
    if len(set(units)) == 1:
        return {"units": units[0]}
    return {"comment": "in the units of each feature, given by the feature_units coordinate (" + ", ".join(
        sorted(set(units))) + ")"}


def summary(analysis: xr.Dataset) -> tuple[list[str], list[str]]:
    """What a user must see of an analysis: per feature, the requirement statement, and the insufficient data sets.

    Returns
    -------
    tuple of list of str
        ``(statements, warnings)``: ``"<feature>: <requirement_statement>"`` per feature (a within-unit campaign's
        ``"<feature> within unit: <within_unit_requirement_statement>"`` after it), and one warning per feature
        with data sets below ``min_ok_runs`` ok runs.
    """
    statements, warnings = [], []
    min_ok_runs = int(analysis.attrs["min_ok_runs"])
    for feature in (str(f) for f in analysis["feature"].values):
        statements.append(f"{feature}: {analysis['requirement_statement'].sel(feature=feature).item()}")
        if "within_unit_requirement_statement" in analysis:
            statements.append(f"{feature} within unit: "
                              f"{analysis['within_unit_requirement_statement'].sel(feature=feature).item()}")
        n_used = analysis["n_used"].sel(feature=feature)
        short = [f"{d} ({_runs(int(n))})" for d, n in zip(analysis["dataset"].values, n_used.values, strict=False)
                 if n < min_ok_runs]
        if len(short) == len(n_used) > 1 and len(set(n_used.values)) == 1:
            short = [f"all {len(short)} data sets ({_runs(int(n_used[0]))} each)"]
        if short:
            means = [f"{d} {mean_text(analysis, str(d), feature)}" for d, n in zip(
                analysis["dataset"].values, n_used.values, strict=True) if 0 < n < min_ok_runs]
            warnings.append(
                f"{feature}: insufficient data in {', '.join(short)}: fewer than {min_ok_runs} ok runs, "
                "their correlations, indices and detection probabilities are NaN"
                + (f"; their means (flagged): {', '.join(means)}" if means else ""))
    return statements, warnings


def mean_text(analysis: xr.Dataset, dataset: str, feature: str) -> str:
    """A data set's mean of a feature with its t interval, at the precision the interval resolves: ``1.23 µm (95 %
    interval 1.1 … 1.4 µm, n = 8)``; one run has no interval, and says so."""
    cell = analysis.sel(dataset=dataset, feature=feature)
    n, mean = int(cell["n_used"]), float(cell["feature_mean"])
    unit = str(analysis["feature_units"].sel(feature=feature).item()) if "feature_units" in analysis.coords else "1"
    if "feature_mean_ci" not in analysis or n < 2:
        return f"{quantity_text(mean, unit)} ({_runs(n)}, no interval)" if n else "– (no ok run)"
    low, high = (float(v) for v in cell["feature_mean_ci"].values)
    confidence = float(json.loads(analysis.attrs.get("bootstrap", "{}")).get("confidence", CONFIDENCE))
    return estimate_with_interval(mean, low, high, unit, confidence).removeprefix("+").replace(")", f", n = {n})", 1)


def analyze(results_path: str | Path, out_path: str | Path | None = None, **options) -> Path:
    """Analyse a campaign's ``results.nc`` and write ``analysis.nc`` (and, for a model-form study, its table
    ``model_form.nc`` beside it: :mod:`campaigns.analysis.model_form`).

    Parameters
    ----------
    results_path : str or Path
    out_path : str or Path, optional
        Default: ``analysis.nc`` next to the results.
    **options
        ``n_boot``, ``confidence``, ``false_alarm_rate``, ``power``, ``seed``
        (see :func:`analysis_dataset`).

    Returns
    -------
    Path
        The written file.
    """
    results_path = Path(results_path)
    out_path = Path(out_path) if out_path is not None else results_path.with_name("analysis.nc")
    with xr.open_dataset(results_path, engine="netcdf4") as results:
        analysis = analysis_dataset(results.load(), **options)
        history = str(results.attrs.get("history", "")).strip()
    stamp = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    analysis.attrs["history"] = "\n".join(
        [line for line in (history, f"{stamp}: "
                                    f"campaigns.analysis.campaign_analysis.analyze({results_path.name})") if line])
    atomic_write(out_path, lambda tmp: analysis.to_netcdf(tmp, engine="netcdf4", encoding=cf_encoding(analysis)))
    from campaigns.analysis import model_form  # here, not at the top: model_form builds on this module

    if model_form.is_model_form(results):  # a model-form study: its table beside the analysis (issue 33)
        model_form.write_model_form(results, analysis, out_path.with_name(model_form.FILE_NAME))
    return out_path


def cf_encoding(ds: xr.Dataset) -> dict[str, dict]:
    """netCDF encoding that keeps a dataset's coordinates CF-clean: text labels (``dataset``, ``feature``,
    ``parameter``, ...) as character arrays (CF 1.8, Sec. 6.1 labels: tools that check the monotonicity of numeric
    coordinate variables skip them, and xarray reads them back as string coordinates), and no ``_FillValue`` on any
    coordinate (CF 1.8, Sec. 2.5.1: coordinates have no missing values)."""
    encoding = {}
    for name, coordinate in ds.coords.items():
        text = coordinate.dtype.kind in "OUS"
        encoding[name] = {"dtype": "S1"} if text else {"_FillValue": None}
    return encoding
