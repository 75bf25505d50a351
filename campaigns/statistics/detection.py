"""Detection of a fault against a reference: separation of two samples, the detection probability at a fixed
false-alarm rate, the minimum detectable level along a sweep with its bootstrap bounds, how far the sweep resolves
it, the verdict on a requirement and the runs that would decide an undetermined one."""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from campaigns.statistics.defaults import CONFIDENCE, FALSE_ALARM_RATE, POWER

#: Flag values of ``minimum_detectable_status``: how far the sweep resolves the minimum detectable level.
RESOLUTIONS = ("insufficient_data", "resolved", "between_adjacent_levels", "beyond_sweep")


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


def detection_probabilities(reference: np.ndarray, test: np.ndarray, false_alarm_rate: float) -> np.ndarray:
    """:func:`detection_probability` of each row of ``test`` (shape (B, n_t)) against the same row of ``reference``
    (B, n_r)."""
    upward = np.median(test, axis=-1) >= np.median(reference, axis=-1)
    high = np.quantile(reference, 1.0 - false_alarm_rate, axis=-1)
    low = np.quantile(reference, false_alarm_rate, axis=-1)
    return np.where(upward, np.mean(test > high[:, None], axis=-1), np.mean(test < low[:, None], axis=-1))


def detection_probability(reference, test, false_alarm_rate: float = FALSE_ALARM_RATE) -> float:
    """Probability that a ``test`` run is flagged by a threshold with the given false-alarm rate.

    The threshold is the ``1 - false_alarm_rate`` quantile of ``reference``
    (or the ``false_alarm_rate`` quantile when ``test`` lies below ``reference``,
    judged by the medians), so a fraction ``false_alarm_rate`` of reference runs
    would be flagged.
    """
    reference, test = np.asarray(reference, dtype=float), np.asarray(test, dtype=float)
    if len(reference) == 0 or len(test) == 0:
        return math.nan
    return float(detection_probabilities(reference[None, :], test[None, :], false_alarm_rate)[0])


def minimum_detectable(levels, probabilities, power: float = POWER) -> tuple[float, float, float]:
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
    false_alarm_rate: float = FALSE_ALARM_RATE,
    power: float = POWER,
    n_boot: int = 1000,
    confidence: float = CONFIDENCE,
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
    boot = np.stack([detection_probabilities(resampled[reference], r, false_alarm_rate) for r in resampled], axis=1)
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
    400 N. Bounds of zero width (the estimate is a sweep level) leave it as it is. A rounding that would leave the
    bounds (4.3 µm within 2-40 µm is not 0 µm) takes the next finer digit until it is inside them."""
    lower, upper = bounds
    half_width = 0.5 * (upper - lower)
    if not (math.isfinite(estimate) and math.isfinite(half_width) and half_width > 0):
        return estimate
    step = 10.0 ** math.floor(math.log10(half_width))
    while not lower <= round(estimate / step) * step <= upper and step > half_width * 1e-6:
        step /= 10.0
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
    needed = math.ceil(n * (z * probability_se[i] / gap) ** 2)
    if needed <= n:  # the normal scaling says decided already; the percentile bounds, which decide, do not
        return math.nan, (
            f"no estimate from the normal scaling: the detection probability of the "
            f"{labels[i] if labels is not None else f'{levels[i]:.3g}'} level, {probability[i] * 100:.3g} %, already "
            f"lies {gap / probability_se[i]:.2f} bootstrap standard errors ({probability_se[i] * 100:.2g} points at "
            f"{n} runs) from {power * 100:g} %, yet the percentile bounds straddle the requirement (a skewed "
            f"replicate distribution): more runs per sweep data set, or a level search (`twin campaign bracket`), "
            f"will tell")
    if needed > MAX_RUNS_TO_DECIDE:
        return math.inf, f"more than {MAX_RUNS_TO_DECIDE} runs per sweep data set"
    return float(needed), (
        f"{decides} would be decided at about {needed} ok runs per sweep data set if the estimate holds: the "
        f"detection probability of the {labels[i] if labels is not None else f'{levels[i]:.3g}'} level, "
        f"{probability[i] * 100:.3g} % (bootstrap standard "
        f"error {probability_se[i] * 100:.2g} points at {n} runs, falling as 1/sqrt(runs)), would then lie "
        f"{z:.2f} standard errors from {power * 100:g} %")


def requirement_verdict(lower: float, upper: float, requirement: float) -> str:
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
