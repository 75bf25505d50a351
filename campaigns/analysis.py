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
  data set, compared with the 1 µm requirement of Table 9.3.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import xarray as xr
from scipy import stats

from campaigns import sensitivity
from campaigns.files import atomic_write
from campaigns.margins_analysis import control_robustness

#: Table 9.3: minimum detectable linear backlash [m].
BACKLASH_REQUIREMENT = 1e-6
REQUIREMENT_SOURCE = "Bertolino (2020) Table 9.3: minimum detectable linear backlash 1 µm"
#: Ok runs a data set needs before any statistic of it is computed. The detection threshold is the 95 %
#: quantile of the reference (false-alarm rate 5 %) and the minimum detectable backlash is where the detection
#: probability reaches 95 %: both are resolved only when one run is at most 5 % of the sample, i.e. n >= 20.
#: Below that the bootstrap has too few distinct resamples for a 95 % interval (docs/campaigns.md, Analysis).
MIN_OK_RUNS = 20
_VERDICT_ATTRS = {"long_name": "verdict on the Table 9.3 requirement: met / not met / undetermined / insufficient data"}
_STATEMENT_ATTRS = {
    "long_name": "the verdict on the Table 9.3 requirement with the estimate, its bounds and the sample size, "
                 "in one sentence"}
#: What a sweep's condition measures: condition -> (fault quantity, unit, display scale, display unit). The
#: fault size of a data set is ``|condition - condition of the reference|`` (the backlash itself; the loss of
#: preload from the healthy reference).
SWEEP_QUANTITIES = {"backlash": ("backlash", "m", 1e6, "µm"), "preload": ("preload loss", "N", 1.0, "N")}
#: Spawn-key tag of the observability bootstrap's random stream (the correlation bootstraps use (dataset, feature)).
_OBSERVABILITY_STREAM = 1_000_003
#: Spawn-key tag of the first-order index bootstrap's random stream.
_SENSITIVITY_STREAM = 1_000_033
#: Residual sum of squares of ranks, relative to n^3, below which a PRCC regression counts as exact (round-off only).
_EXPLAINED = 1e-18


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
        not reached).
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
    return {
        "probability": probability,
        "estimate": estimate,
        "bracket": (lower, upper),
        "bounds": bounds,
        "replicates": np.where(np.isnan(brackets[:, 0]), math.inf, brackets[:, 0]),
    }


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
    confidence: float = 0.95,
    power: float = 0.95,
    min_ok_runs: int = MIN_OK_RUNS,
    largest_level: float = math.nan,
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
        Interpolated minimum detectable backlash [m] (NaN: not reached along the sweep).
    bounds : tuple of float
        Bootstrap bounds [m] (lower: a level not detected, upper: a level detected).
    n_used : dict
        Ok runs of each sweep data set (empty: no sweep).
    confidence, power, min_ok_runs, largest_level
        As used for the numbers (``largest_level``: the largest backlash of the sweep).
    condition, requirement, requirement_source
        The swept condition (:data:`SWEEP_QUANTITIES`), the requirement on its fault size (SI) and its source.
    """
    quantity, _, scale, unit = SWEEP_QUANTITIES[condition]

    def fmt(value: float) -> str:  # in the display unit of the fault quantity (µm for the backlash)
        return f"{value * scale:.3g} {unit}"

    against = f"against the {fmt(requirement)} requirement of {requirement_source}"
    if not n_used:
        return (
            "insufficient data: the spec has no observability sweep, "
            f"so no minimum detectable {quantity} is estimated {against}")
    short = [f"{name} has {_runs(n)}" for name, n in n_used.items() if n < min_ok_runs]
    if len(short) == len(n_used) > 1 and len(set(n_used.values())) == 1:
        short = [f"each of the {len(n_used)} sweep data sets has {_runs(next(iter(n_used.values())))}"]
    if short:
        return (
            f"insufficient data: {', '.join(short)} (at least {min_ok_runs} per sweep data set are needed), "
            f"so no minimum detectable {quantity} is estimated {against}"
        )
    counts = sorted(set(n_used.values()))
    runs = f"{counts[0]}" if len(counts) == 1 else f"{counts[0]}–{counts[-1]}"
    lower, upper = bounds
    upper_text = (f"at most {fmt(upper)}" if math.isfinite(upper)
                  else f"possibly beyond the sweep ({fmt(largest_level)})")
    level = "" if math.isfinite(estimate) else f"not reached up to {fmt(largest_level)}: "
    value = fmt(estimate) if math.isfinite(estimate) else f"detection probability below {power * 100:g} %"
    return (
        f"{verdict}: minimum detectable {quantity} {level}{value} ({confidence * 100:g} % bootstrap bounds: above "
        f"{fmt(lower)}, {upper_text}; {runs} ok runs per sweep data set, {len(n_used)} data sets) {against}"
    )


def _used(results: xr.Dataset, feature: str) -> xr.DataArray:
    return (results["status"] == "ok") & np.isfinite(results[feature])


def observability_sweep(
    results: xr.Dataset,
    feature: str,
    datasets: list[str],
    *,
    false_alarm_rate: float = 0.05,
    power: float = 0.95,
    n_boot: int = 1000,
    confidence: float = 0.95,
    min_ok_runs: int = MIN_OK_RUNS,
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
    min_ok_runs : int
        Ok runs every sweep data set needs; below it the verdict is ``"insufficient data"``
        and the sweep statistics of that data set are NaN.
    condition, reference, requirement, requirement_source
        The swept scene condition (:data:`SWEEP_QUANTITIES`; ``observability.condition`` of the
        spec), the reference data set (default: the one where it is zero), the requirement on the
        fault size (SI) and its source.

    Returns
    -------
    xarray.Dataset
        ``sweep_<q>(sweep_point)``, ``sweep_detection_probability(sweep_point)``,
        the scalar ``minimum_detectable_<q>`` (the requirement in its attributes),
        ``minimum_detectable_bracket(bound)`` (the sweep levels around the estimate),
        ``minimum_detectable_<q>_ci(bound)``, ``requirement_verdict`` and ``requirement_statement``,
        where ``<q>`` is the fault quantity (``backlash``, ``preload_loss``).
    """
    quantity, unit, _, _ = SWEEP_QUANTITIES[condition]
    stem = quantity.replace(" ", "_")
    values = np.array([float(results[f"condition_{condition}"].sel(dataset=n)) for n in datasets])
    reference = datasets.index(reference) if reference is not None else int(np.flatnonzero(values == 0.0)[0])
    backlash = np.abs(values - values[reference])  # the fault size of each sweep data set
    used = _used(results, feature)
    samples = [results[feature].sel(dataset=n).values[used.sel(dataset=n).values] for n in datasets]
    n_used = {n: len(s) for n, s in zip(datasets, samples, strict=False)}
    nan2 = (math.nan, math.nan)
    if min(n_used.values()) < min_ok_runs:
        enough = [len(s) >= min_ok_runs and n_used[datasets[reference]] >= min_ok_runs for s in samples]
        probability = np.array([detection_probability(samples[reference], s, false_alarm_rate) if ok else math.nan
                                for s, ok in zip(samples, enough, strict=False)])
        estimate, bracket, bounds, verdict = math.nan, nan2, nan2, "insufficient data"
    else:
        found = bootstrap_minimum_detectable(
            backlash, samples, reference, false_alarm_rate=false_alarm_rate, power=power, n_boot=n_boot,
            confidence=confidence, seed=seed,
        )
        probability, estimate, bracket, bounds = (found["probability"], found["estimate"], found["bracket"],
                                                  found["bounds"])
        verdict = requirement_verdict(*bounds, requirement)
    statement = requirement_statement(
        verdict, estimate, bounds, n_used, confidence=confidence, power=power, min_ok_runs=min_ok_runs,
        largest_level=float(backlash.max()), condition=condition, requirement=requirement,
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
            f"minimum_detectable_{stem}": (
                (),
                estimate,
                {
                    "units": unit,
                    "long_name": f"smallest {quantity} detected with probability {power:g} at false-alarm rate "
                                 f"{false_alarm_rate:g} (linear interpolation along the sweep; NaN: "
                                 "not reached or insufficient data)",
                    "requirement": requirement,
                    "requirement_source": requirement_source,
                },
            ),
            "minimum_detectable_bracket": (
                "bound",
                np.array(bracket),
                {"units": unit,
                 "long_name": f"sweep levels bracketing minimum_detectable_{stem} (inf: never detected)"},
            ),
            f"minimum_detectable_{stem}_ci": (
                "bound",
                np.array(bounds),
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
    false_alarm_rate: float = 0.05,
    power: float = 0.95,
    seed: int = 0,
    min_ok_runs: int = MIN_OK_RUNS,
    sensitivity_boot: int = 200,
) -> xr.Dataset:
    """Compute every statistic of :func:`analyze` on an opened results dataset.

    A data set with fewer than ``min_ok_runs`` used runs of a feature is flagged
    in ``data_sufficient`` and gets NaN statistics for that feature.
    ``sensitivity_boot`` resamples give the interval of the first-order index
    (:func:`campaigns.sensitivity.first_order`).
    """
    if min_ok_runs < 3:
        raise ValueError(
            f"min_ok_runs = {min_ok_runs}: must be at least 3 (a standard deviation and a correlation need 3 runs)")
    parameters = [v for v in results.data_vars if results[v].attrs.get("role") == "sampled"]
    features = [v for v in results.data_vars if results[v].attrs.get("role") == "feature"]
    names = [str(n) for n in results["dataset"].values]
    shape = (len(names), len(features), len(parameters))
    out = {k: np.full(shape, math.nan) for k in ("pearson", "spearman", "prcc")}
    ci = {k: np.full(shape + (2,), math.nan) for k in ("pearson", "spearman", "first_order_index", "effect_size")}
    out["first_order_index"], effect_size = np.full(shape, math.nan), np.full(shape, math.nan)
    n_used = np.zeros((len(names), len(features)), dtype=np.int64)
    mean, std = np.full(n_used.shape, math.nan), np.full(n_used.shape, math.nan)
    overlap = np.full((len(features), len(names), len(names)), math.nan)
    detection = np.full_like(overlap, math.nan)
    used_values: dict[tuple[int, int], np.ndarray] = {}
    for d, name in enumerate(names):
        row = results.sel(dataset=name)
        for f, feature in enumerate(features):
            mask = _used(results, feature).sel(dataset=name).values
            y = row[feature].values[mask]
            n_used[d, f] = len(y)
            if len(y) < min_ok_runs:
                continue
            used_values[d, f] = y
            mean[d, f], std[d, f] = y.mean(), y.std(ddof=1)
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
            out["first_order_index"][d, f], ci["first_order_index"][d, f] = found["index"], found["ci"]
            effect_size[d, f], ci["effect_size"][d, f] = found["effect_size"], found["effect_size_ci"]
    for f in range(len(features)):
        for a, b in ((a, b) for a in range(len(names)) for b in range(len(names))):
            if (a, f) in used_values and (b, f) in used_values:
                overlap[f, a, b] = overlap_coefficient(used_values[a, f], used_values[b, f])
                detection[f, a, b] = detection_probability(used_values[b, f], used_values[a, f], false_alarm_rate)
    statuses = sorted(set(results["status"].values.ravel().tolist()))
    n_status = np.array([[int((results["status"].sel(dataset=n) == s).sum()) for s in statuses] for n in names])
    n_runs = results.sizes["run"]

    corr_dims = ("dataset", "feature", "parameter")
    units = {results[f].attrs.get("units", "") for f in features}
    feature_units = units.pop() if len(units) == 1 else "units of each feature"
    data_vars = {
        "n_used": (("dataset", "feature"), n_used, {"long_name": "runs used (status ok, finite feature)"}),
        "n_excluded": (("dataset", "feature"), n_runs - n_used, {"long_name": "runs excluded from the statistics"}),
        "n_status": (("dataset", "status"), n_status, {"long_name": "runs per status"}),
        "data_sufficient": (
            ("dataset", "feature"),
            (n_used >= min_ok_runs).astype(np.int8),
            {
                "long_name": f"at least {min_ok_runs} used runs (else every statistic of the data set is NaN)",
                "flag_values": np.array([0, 1], dtype=np.int8),
                "flag_meanings": "insufficient_data sufficient_data",
                "min_ok_runs": min_ok_runs,
            },
        ),
        "feature_mean": (("dataset", "feature"), mean, {"long_name": "mean of the feature over used runs"}),
        "feature_std": (("dataset", "feature"), std, {"long_name": "standard deviation of the feature over used runs"}),
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
                          "alone, any shape of dependence", "method": sensitivity.METHOD},
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
                "units": feature_units,
                "long_name": "standard deviation of the conditional mean E[feature | parameter] over the parameter's "
                             "distribution, sqrt(max(first_order_index, 0) var(feature)): "
                             "what the parameter alone moves the feature by",
                "method": sensitivity.METHOD,
            },
        ),
        "effect_size_ci": (
            corr_dims + ("bound",),
            ci["effect_size"],
            {"units": feature_units,
             "long_name": "effect_size at the bounds of first_order_index_ci (feature variance held fixed)"},
        ),
        "overlap": (("feature", "dataset", "reference"), overlap,
                    {"units": "1", "long_name": "overlap coefficient of the feature distributions"}),
        "detection_probability": (
            ("feature", "dataset", "reference"),
            detection,
            {"units": "1",
             "long_name": "fraction of dataset runs beyond the reference's threshold at false-alarm rate "
                          f"{false_alarm_rate:g}"},
        ),
    }
    coords = {
        "dataset": ("dataset", np.array(names, dtype=object)),
        "reference": ("reference", np.array(names, dtype=object)),
        "feature": ("feature", np.array(features, dtype=object)),
        "parameter": ("parameter", np.array(parameters, dtype=object)),
        "bound": ("bound", np.array(["lower", "upper"], dtype=object)),
        "status": ("status", np.array(statuses, dtype=object)),
    }
    analysis = xr.Dataset(data_vars, coords=coords)
    observability = json.loads(results.attrs["spec_json"])["spec"]["observability"]
    sweep = observability["sweep"]
    condition = observability.get("condition", "backlash")
    requirement = (observability.get("requirement") or BACKLASH_REQUIREMENT, observability.get("requirement_source")
                   or REQUIREMENT_SOURCE)
    if sweep:
        per_feature = [
            observability_sweep(
                results, feature, sweep, false_alarm_rate=false_alarm_rate, power=power, n_boot=n_boot,
                confidence=confidence, min_ok_runs=min_ok_runs,
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
    analysis.attrs = {
        "Conventions": "CF-1.8",
        "title": f"Analysis of {results.attrs.get('title', 'a BenchTwin campaign')}",
        "source_spec_hash": results.attrs.get("spec_hash", ""),
        "selection": "statistics use runs with status 'ok' and a finite feature; see n_used, n_excluded, n_status",
        "bootstrap": json.dumps({"method": "percentile, pairs resampled", "n_boot": n_boot, "confidence": confidence,
                                 "seed": seed}),
        "false_alarm_rate": false_alarm_rate,
        "detection_power": power,
        "backlash_sweep": json.dumps(sweep),
        "min_ok_runs": min_ok_runs,
        "observability_condition": condition,
        "requirement": requirement[0],
        "requirement_units": SWEEP_QUANTITIES[condition][1],
        "requirement_source": requirement[1],
    }
    robustness = control_robustness(results, correlate=bootstrap_correlation, verdict_rule=requirement_verdict,
                                    features=features, n_boot=n_boot, confidence=confidence, seed=seed,
                                    min_ok_runs=min_ok_runs)
    return analysis.merge(robustness, combine_attrs="override")


def summary(analysis: xr.Dataset) -> tuple[list[str], list[str]]:
    """What a user must see of an analysis: per feature, the requirement statement, and the insufficient data sets.

    Returns
    -------
    tuple of list of str
        ``(statements, warnings)``: ``"<feature>: <requirement_statement>"`` per feature, and one
        warning per feature with data sets below ``min_ok_runs`` ok runs.
    """
    statements, warnings = [], []
    min_ok_runs = int(analysis.attrs["min_ok_runs"])
    for feature in (str(f) for f in analysis["feature"].values):
        statements.append(f"{feature}: {analysis['requirement_statement'].sel(feature=feature).item()}")
        n_used = analysis["n_used"].sel(feature=feature)
        short = [f"{d} ({_runs(int(n))})" for d, n in zip(analysis["dataset"].values, n_used.values, strict=False)
                 if n < min_ok_runs]
        if len(short) == len(n_used) > 1 and len(set(n_used.values)) == 1:
            short = [f"all {len(short)} data sets ({_runs(int(n_used[0]))} each)"]
        if short:
            warnings.append(
                f"{feature}: insufficient data in {', '.join(short)}: fewer than {min_ok_runs} ok runs, "
                "their statistics are NaN"
            )
    return statements, warnings


def analyze(results_path: str | Path, out_path: str | Path | None = None, **options) -> Path:
    """Analyse a campaign's ``results.nc`` and write ``analysis.nc``.

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
    atomic_write(out_path, lambda tmp: analysis.to_netcdf(tmp, engine="netcdf4"))
    return out_path
