"""Distribution-free bounds from order statistics: which ranked run bounds a quantile, how many runs a bound needs,
and the run floor of a detection statement that follows from it."""

from __future__ import annotations

import math

from scipy import stats

from campaigns.statistics.defaults import CONFIDENCE, FALSE_ALARM_RATE, POWER


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


def floor_reason(false_alarm_rate: float, power: float, confidence: float) -> str:
    """Why a sweep data set needs :func:`detection_run_floor` runs, in words (the quantile that binds)."""
    threshold = min_runs_for_quantile_bound(1.0 - false_alarm_rate, confidence)
    if threshold >= min_runs_for_quantile_bound(power, confidence):
        return (f"with fewer, not even the largest run bounds the {(1 - false_alarm_rate) * 100:g} % quantile that "
                f"sets the detection threshold from above with {confidence * 100:g} % confidence")
    return (f"with fewer, not even the smallest run bounds the {(1 - power) * 100:g} % quantile that "
            f"{power * 100:g} % detection rests on from below with {confidence * 100:g} % confidence")
