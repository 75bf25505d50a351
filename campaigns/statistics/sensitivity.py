"""Given-data sensitivity: first-order indices and effect sizes from the plain Monte Carlo sample.

Correlations (Pearson, Spearman, PRCC) only see monotone dependence: a feature
that rises on both sides of a tolerance's nominal (``f = |x|``) has a rank
correlation of zero. The first-order (Sobol') index

    S1_i = Var(E[Y | X_i]) / Var(Y)

sees any shape of dependence. It is estimated here from the campaign's own
sample, without a dedicated design, by the RBD-FAST / EASI estimator of
SALib (``SALib.analyze.rbd_fast``; Plischke 2010, Reliab. Eng. Syst. Saf. 95,
354-360): the outputs are reordered along the sorted input so that E[Y | X_i]
becomes a periodic signal, whose power in the first ``HARMONICS`` harmonics,
relative to the total, estimates S1_i; the Tissot & Prieur (2012, Reliab. Eng.
Syst. Saf. 107, 205-213) correction removes the bias of the noise in those
harmonics, so an inert parameter scatters around 0 (and may go slightly below).

The confidence interval is a seeded percentile bootstrap over runs (pairs
resampled, the estimator re-applied). SALib's own interval (normal
approximation from half-size resamples, one loop per parameter) costs about
1.5 s per data set and feature for 38 parameters; the same estimator is applied
here to all resamples at once: a resample is sorted along ``X_i`` by repeating
the sorted original runs by their bootstrap counts, no sort per resample (a
compiled loop, :func:`_sorted_resamples`, which releases the GIL).

The effect size is in the feature's units: the standard deviation of the
conditional mean E[Y | X_i] over the parameter's distribution,
``sqrt(max(S1_i, 0) Var(Y))`` — what the parameter alone moves the feature by
(one standard deviation of that movement; for a linear effect ``b X_i`` it is
``|b| std(X_i)``).

Small samples. For an input that does nothing, the runs sorted along it are in
uniformly random order, so the index of an inert input has a distribution that
depends on ``n`` alone (a permutation null). Its mean (the estimator's bias) is
below 0.013 from 50 runs on, but its standard deviation is 0.16 at 50 runs,
0.070 at 100 and 0.033 at 200 (about ``2 sqrt(M) / (n - 2M)`` for large ``n``),
and the largest of 38 inert inputs' indices (Table 9.5's count; a report ranks
the largest) averages 0.35 at 50 runs, 0.111 at 150 and 0.083 at 200.
:data:`MIN_RUNS` is the first of those sample sizes (on a grid of 50) where
that chance maximum stays below 0.1, the smallest share the findings name as a
driver: below it an index is not printed (:func:`unresolved`), only its
interval, which keeps its coverage at any ``n`` above 2M (measured 0.92-1.00
at 30-500 runs). An estimate can also fall outside its own percentile interval
(the bootstrap's duplicated runs reshape the reordered signal; 1-6 % of inert
inputs at every ``n`` measured): the interval is then printed alone, never a
bias-shifted one (for a chance-high estimate of an inert input, a shift
towards the estimate would exclude the true zero; Efron & Tibshirani 1993,
*An Introduction to the Bootstrap*, Sec. 10.6, on the risk of bias correction).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from SALib.analyze import rbd_fast

from numerics.jit import KERNEL

#: Harmonics of the reordered signal counted as first-order power (SALib's default M).
HARMONICS = 10
#: Runs below which a first-order index is not printed, only its interval: the fewest runs (on a grid of 50) at
#: which the largest of 38 inert inputs' indices averages below 0.1 (measured by permutation: 0.111 at 150 runs,
#: 0.083 at 200; module docstring, tests/campaigns/test_small_sample_statistics.py).
MIN_RUNS = 200
#: Flag bits of an index that is not printed (CF ``flag_masks``), and their ``flag_meanings``.
BELOW_MIN_RUNS, OUTSIDE_INTERVAL = np.int8(1), np.int8(2)
FLAG_MEANINGS = "below_minimum_runs estimate_outside_interval"
METHOD = (
    f"RBD-FAST/EASI given-data estimator (SALib.analyze.rbd_fast, M = {HARMONICS} harmonics, "
    "Tissot-Prieur bias correction) on the Monte Carlo sample; percentile bootstrap over runs"
)


def _easi_order(n: int) -> np.ndarray:
    """EASI reordering of ``n`` sorted positions: odd ones up, even ones back down (a periodic signal)."""
    return np.concatenate([np.arange(0, n, 2), np.arange(1, n, 2)[::-1]])


def _spectral_work(rows: int, n: int) -> tuple[np.ndarray, ...]:
    """Scratch arrays of :func:`_first_order_of_signals` for ``rows`` signals of ``n`` samples, column-major: the
    signals' centred copy, their spectrum, its power and the one-sided power."""
    return (np.empty((rows, n), order="F"), np.empty((rows, n // 2 + 1), dtype=complex, order="F"),
            np.empty((rows, n // 2), order="F"), np.empty((rows, n // 2), order="F"))


def _first_order_of_signals(signals: np.ndarray, work: tuple[np.ndarray, ...] | None = None) -> np.ndarray:
    """Bias-corrected first-order index of each reordered signal (rows), as ``rbd_fast`` computes it.

    ``rbd_fast`` takes the ratio of sums of ``scipy.signal.periodogram`` (mean removed, one-sided):
    that is ``|rfft|^2`` with every bin but the Nyquist one counted twice; the scale cancels in the
    ratio. ``periodogram`` itself costs three times the FFT (its short-time-FFT machinery).
    ``work`` (:func:`_spectral_work`, column-major like the signals) holds the steps' arrays, so that a loop over
    parameters allocates none: the same operations on the same layouts, so the same bits.
    """
    rows, n = signals.shape
    centred, spectrum, power, one_sided_power = _spectral_work(rows, n) if work is None else work
    np.subtract(signals, signals.mean(axis=-1, keepdims=True), out=centred)
    np.fft.rfft(centred, axis=-1, out=spectrum)
    np.square(np.abs(spectrum[:, 1:], out=power), out=power)
    one_sided = np.full(power.shape[-1], 2.0)
    if n % 2 == 0:
        one_sided[-1] = 1.0  # the Nyquist bin has no mirror image
    np.multiply(power, one_sided, out=one_sided_power)
    index = 2.0 * power[:, :HARMONICS].sum(axis=-1) / one_sided_power.sum(axis=-1)
    return rbd_fast.unskew_S1(index, HARMONICS, n)


@numba.njit(nogil=True, **KERNEL)
def _sorted_resamples(y, order, counts, reorder, signals):
    """Each bootstrap resample (run counts ``counts[b]``) sorted along the input (``order``: the runs sorted by it),
    the sorted runs each repeated by its count, EASI-reordered (``reorder``: :func:`_easi_order`), as the feature's
    values ``y`` in ``signals[b]``: no sort per resample. A run is written four times whatever its count, then the
    position moves on by the count (a branch on counts of 0-3 mispredicts at every run)."""
    n_boot, n = counts.shape
    runs = np.empty(n + 4, np.int64)
    for b in range(n_boot):
        i = 0
        for k in range(n):
            run, count = order[k], counts[b, order[k]]
            runs[i], runs[i + 1], runs[i + 2], runs[i + 3] = run, run, run, run
            for extra in range(4, count):
                runs[i + extra] = run
            i += count
        for i in range(n):
            signals[b, i] = y[runs[reorder[i]]]


def unresolved(index, ci, n: int) -> np.ndarray:
    """Why each first-order index is not printed, as flag bits (0: printed): :data:`BELOW_MIN_RUNS` when ``n`` is
    below :data:`MIN_RUNS`, :data:`OUTSIDE_INTERVAL` when the estimate lies outside its own interval ``ci``
    (shape (p, 2)). NaN estimates or bounds flag nothing of the second kind."""
    index, ci = np.asarray(index, dtype=float), np.asarray(ci, dtype=float)
    flag = np.full(index.shape, BELOW_MIN_RUNS if n < MIN_RUNS else 0, dtype=np.int8)
    with np.errstate(invalid="ignore"):
        flag[(index < ci[..., 0]) | (index > ci[..., 1])] |= OUTSIDE_INTERVAL
    return flag


def first_order(X, y, *, n_boot: int = 200, confidence: float = 0.95, seed=None) -> dict[str, np.ndarray]:
    """First-order index, its bootstrap interval and the effect size of each column of ``X`` on ``y``.

    Parameters
    ----------
    X : array_like, shape (n, p)
        Sampled values (any distribution: given data).
    y : array_like, shape (n,)
        The feature.
    n_boot : int, default 200
        Bootstrap resamples (runs resampled with replacement, shared by every column).
    confidence : float, default 0.95
    seed : int, SeedSequence, Generator or None

    Returns
    -------
    dict
        ``index`` (p,), ``ci`` (p, 2) percentile bounds, ``effect_size`` (p,) in the units of
        ``y`` and ``effect_size_ci`` (p, 2) (the index's bounds through the same transform). NaN for a constant column,
        and for every column when ``y`` is constant or ``n <= 2 HARMONICS`` (too few runs to separate the harmonics from
        the rest).
    """
    X, y = np.asarray(X, dtype=float), np.asarray(y, dtype=float)
    n, p = X.shape
    index, ci = first_order_index(X, y), np.full((p, 2), math.nan)
    if not np.isfinite(index).any():
        return {"index": index, "ci": ci, "effect_size": np.full(p, math.nan), "effect_size_ci": ci.copy()}
    counts = np.random.default_rng(seed).multinomial(n, np.full(n, 1.0 / n), size=n_boot)  # (n_boot, n)
    reorder, alpha = _easi_order(n), 0.5 * (1.0 - confidence)
    # column-major, as numpy's fancy indexing laid the resamples out before: the FFT batches the rows by the layout,
    # and its last bits depend on the batching
    signals, work = np.empty((n_boot, n), order="F"), _spectral_work(n_boot, n)
    for j in np.flatnonzero(np.isfinite(index)):
        _sorted_resamples(y, np.argsort(X[:, j]), counts, reorder, signals)
        replicates = _first_order_of_signals(signals, work)
        ci[j] = np.quantile(replicates[np.isfinite(replicates)], [alpha, 1.0 - alpha])

    def effect(share: np.ndarray) -> np.ndarray:
        return np.sqrt(np.clip(share, 0.0, None) * y.var(ddof=1))

    return {"index": index, "ci": ci, "effect_size": effect(index), "effect_size_ci": effect(ci)}


def first_order_index(X, y) -> np.ndarray:
    """The first-order index of each column of ``X`` on ``y`` alone (the point estimate of :func:`first_order`,
    ``rbd_fast.analyze``'s S1; Plischke 2010): NaN for a constant column, and for every column when ``y`` is constant
    or ``n <= 2 HARMONICS``."""
    X, y = np.asarray(X, dtype=float), np.asarray(y, dtype=float)
    n, p = X.shape
    index = np.full(p, math.nan)
    if n <= 2 * HARMONICS or np.ptp(y) == 0:
        return index
    reorder = _easi_order(n)
    for j in np.flatnonzero(np.ptp(X, axis=0) > 0):
        index[j] = _first_order_of_signals(y[np.argsort(X[:, j])][reorder][None, :])[0]
    return index
