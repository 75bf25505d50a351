"""Correlations of a feature with the sampled values: Pearson and Spearman with percentile-bootstrap intervals, and
the partial rank correlation coefficient (PRCC)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from scipy import stats
from threadpoolctl import threadpool_limits

from campaigns.statistics.defaults import CONFIDENCE
from numerics.jit import KERNEL

#: Residual sum of squares of ranks, relative to n^3, below which a PRCC regression counts as exact (round-off only).
_EXPLAINED = 1e-18
#: Runs up to which a resample's rank sums are exact in 64-bit integers and doubles (:func:`_centred_ranks`: four
#: times the sum of squares is at most 4 n**3 < 2**53).
_EXACT_RANKS = 100_000
#: numpy's pairwise-summation block (``PW_BLOCKSIZE``): below it a sum is eight interleaved partial sums.
_PAIRWISE_BLOCK = 128


def _pearson(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Pearson correlation along the last axis (NaN where a variance is zero)."""
    xc = x - x.mean(axis=-1, keepdims=True)
    yc = y - y.mean(axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = (xc * yc).sum(axis=-1) / np.sqrt((xc * xc).sum(axis=-1) * (yc * yc).sum(axis=-1))
    return np.clip(r, -1.0, 1.0)


def bootstrap_correlation(x, y, method: str = "spearman", *, n_boot: int = 1000, confidence: float = CONFIDENCE,
                          seed=None):
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
    estimate, lower, upper = bootstrap_correlations(x[None, :], y, idx, method, confidence)
    return float(estimate[0]), float(lower[0]), float(upper[0])


def _pairwise_plan(n: int) -> np.ndarray:
    """How numpy sums ``n`` numbers (``pairwise_sum`` in numpy/_core/src/umath/loops_utils.h.src), in postfix order:
    rows ``(first, length)`` are blocks of at most :data:`_PAIRWISE_BLOCK` (:func:`_block_sum`), rows ``(0, -1)``
    add the two sums above them; a longer range is halved at a multiple of 8. A plan, not recursion: numba's cache
    cannot reload a recursive function (the reloaded caller crashed)."""
    plan: list[tuple[int, int]] = []

    def split(first: int, length: int) -> None:
        if length <= _PAIRWISE_BLOCK:
            plan.append((first, length))
            return
        half = length // 2
        half -= half % 8
        split(first, half)
        split(first + half, length - half)
        plan.append((0, -1))

    split(0, n)
    return np.array(plan, dtype=np.int64)


@numba.njit(**KERNEL)
def _block_sum(a, first, n):
    """numpy's sum of at most :data:`_PAIRWISE_BLOCK` numbers ``a[first:first + n]``: in order below 8, else eight
    interleaved partial sums added as a tree, then the rest in order."""
    if n < 8:
        res = 0.0
        for i in range(first, first + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[first], a[first + 1], a[first + 2], a[first + 3]
    r4, r5, r6, r7 = a[first + 4], a[first + 5], a[first + 6], a[first + 7]
    i = 8
    while i < n - n % 8:
        k = first + i
        r0 += a[k]
        r1 += a[k + 1]
        r2 += a[k + 2]
        r3 += a[k + 3]
        r4 += a[k + 4]
        r5 += a[k + 5]
        r6 += a[k + 6]
        r7 += a[k + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[first + i]
        i += 1
    return res


@numba.njit(**KERNEL)
def _pairwise_sum(a, plan, partial):
    """``numpy.add.reduce(a)`` operation for operation, by the plan of :func:`_pairwise_plan` for ``len(a)``
    (``partial``: a stack as long as the plan), so a sum here has the bits of the same sum in numpy."""
    top = 0
    for p in range(plan.shape[0]):
        if plan[p, 1] < 0:
            top -= 1
            partial[top - 1] = partial[top - 1] + partial[top]
        else:
            partial[top] = _block_sum(a, plan[p, 0], plan[p, 1])
            top += 1
    return partial[0]


@numba.njit(**KERNEL)
def _resample_counts(resample, multiplicity):
    """How often each run appears in one resample (indices ``resample``)."""
    multiplicity[:] = 0
    for i in range(len(resample)):
        multiplicity[resample[i]] += 1


@numba.njit(**KERNEL)
def _centred_ranks(order, starts, n_values, multiplicity, counts, twice):
    """Each distinct value's count in a resample (``multiplicity`` per run; ``order``: the runs sorted by value,
    ``starts``: where each distinct value begins in it) and twice its average rank less the mean rank
    ``(n + 1) / 2``, into ``counts`` and ``twice``; returns ``sum(counts * twice**2)``, four times the ranks' sum of
    squares about their mean.

    A resample's average rank of a value is the number of resampled values below it plus half of (its own count
    + 1); ranks are whole or half numbers summing to ``n (n + 1) / 2``, so their mean is ``(n + 1) / 2`` and twice a
    centred rank is an integer. In integers these sums are exact, as the same sums of whole, half and quarter
    numbers are in floating point in any order (below 2**53: n**3 for n runs): numpy's bits, without a chain of
    dependent floating additions per value.
    """
    n = len(multiplicity)
    if n_values == n:  # no ties: one run per value
        for k in range(n):
            counts[k] = multiplicity[order[k]]
    else:
        for k in range(n_values):
            c = 0
            for s in range(starts[k], starts[k + 1]):
                c += multiplicity[order[s]]
            counts[k] = c
    below = 0
    for k in range(n_values):
        twice[k] = 2 * below + counts[k] - n
        below += counts[k]
    squares = 0
    for k in range(n_values):
        squares += counts[k] * twice[k] * twice[k]
    return squares


@numba.njit(**KERNEL)
def _standardized_ranks(order, starts, n_values, multiplicity, counts, twice, scaled, by_run):
    """Each run's rank in one resample, centred and scaled to unit norm, into ``by_run`` (NaN without variance): the
    ranks' ``c = r - mean(r); c / sqrt(sum(c * c))`` as numpy computes it, from :func:`_centred_ranks` (``counts``,
    ``twice``, ``scaled``: scratch per distinct value)."""
    norm = np.sqrt(_centred_ranks(order, starts, n_values, multiplicity, counts, twice) * 0.25)
    for k in range(n_values):
        scaled[k] = (0.5 * twice[k]) / norm
    if n_values == len(multiplicity):
        for k in range(n_values):
            by_run[order[k]] = scaled[k]
    else:
        for k in range(n_values):
            for s in range(starts[k], starts[k + 1]):
                by_run[order[s]] = scaled[k]


@numba.njit(**KERNEL)
def _centred_resample(values, resample, row, work, plan, partial):
    """One resample of ``values`` into ``row``, less its mean, as numpy computes ``c = v - mean(v)``; returns
    ``sqrt(sum(c * c))`` (:func:`_pairwise_sum`; ``work``: one row of scratch)."""
    n = len(resample)
    for i in range(n):
        row[i] = values[resample[i]]
    mean = _pairwise_sum(row, plan, partial) / n
    for i in range(n):
        row[i] = row[i] - mean
    for i in range(n):
        work[i] = row[i] * row[i]
    return np.sqrt(_pairwise_sum(work, plan, partial))


@numba.njit(nogil=True, **KERNEL)
def _bootstrap_rows(idx, standardized, values, order, starts, n_values, spearman, plan):
    """Every resample (row of ``idx``) of ``values`` (or, ``spearman``, of their ranks: ``order``, ``starts``,
    ``n_values`` from :func:`_numbered`) centred and scaled to unit norm into ``standardized``."""
    n = idx.shape[1]
    multiplicity, counts, twice = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
    scaled, by_run, work = np.empty(n), np.empty(n), np.empty(n)
    partial = np.empty(plan.shape[0])
    for b in range(idx.shape[0]):
        row = standardized[b]
        if spearman:
            _resample_counts(idx[b], multiplicity)
            _standardized_ranks(order, starts, n_values, multiplicity, counts, twice, scaled, by_run)
            for i in range(n):
                row[i] = by_run[idx[b, i]]
        else:
            norm = _centred_resample(values, idx[b], row, work, plan, partial)
            for i in range(n):
                row[i] = row[i] / norm


@numba.njit(nogil=True, **KERNEL)
def _bootstrap_dots(idx, yb, out, X, orders, starts, n_values, spearman, plan):
    """``out[b, j]``: the correlation of resample ``b`` of row ``j`` of ``X`` with the standardized resample
    ``yb[b]``, as numpy sums ``sum(standardized(x[b]) * yb[b])``; resample by resample, so that a resample's indices
    and ``yb[b]`` stay in cache for every row."""
    p, n = X.shape
    multiplicity, counts, twice = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
    scaled, by_run, row, work = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    partial = np.empty(plan.shape[0])
    for b in range(idx.shape[0]):
        resample, weights = idx[b], yb[b]
        if spearman:
            _resample_counts(resample, multiplicity)
        for j in range(p):
            if spearman:
                _standardized_ranks(orders[j], starts[j], n_values[j], multiplicity, counts, twice, scaled, by_run)
                for i in range(n):
                    work[i] = by_run[resample[i]] * weights[i]
            else:
                norm = _centred_resample(X[j], resample, row, work, plan, partial)
                for i in range(n):
                    work[i] = (row[i] / norm) * weights[i]
            out[b, j] = _pairwise_sum(work, plan, partial)


def _numbered(v: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """The runs of ``v`` sorted by value, the position in that order where each distinct value begins (then
    ``len(v)``), and the number of distinct values: what :func:`_centred_ranks` counts a resample by."""
    order = np.argsort(v, kind="stable")
    ordered = v[order]
    first = np.flatnonzero(np.concatenate([[True], ordered[1:] != ordered[:-1]]))
    return order.astype(np.int64), np.append(first, len(v)).astype(np.int64), len(first)


def bootstrap_correlations(X: np.ndarray, y: np.ndarray, idx: np.ndarray, method: str, confidence: float):
    """Estimates and percentile CIs for each row of ``X`` (shape (p, n)) against ``y``, shared resamples ``idx``.

    Each resample's correlation is the dot product of the two resampled rows centred and scaled to unit norm
    (Spearman: of their ranks, :func:`_centred_ranks`), in compiled loops that sum as numpy sums
    (:func:`_pairwise_sum`): numpy's numbers without an (n_boot, n) temporary per step. The loops release the GIL,
    so that callers may run several bootstraps on threads.
    """
    spearman = method == "spearman"
    estimate = _pearson(stats.rankdata(X, axis=-1), stats.rankdata(y)[None, :]) if spearman else _pearson(X, y[None, :])
    idx = np.ascontiguousarray(idx, dtype=np.int64)
    X, y = np.ascontiguousarray(X, dtype=float), np.ascontiguousarray(y, dtype=float)
    p, n = X.shape
    if spearman and n > _EXACT_RANKS:
        raise ValueError(f"bootstrap_correlations: {n} runs; Spearman takes at most {_EXACT_RANKS} (its rank sums "
                         "stay exact)")
    ranked = n if spearman else 0
    orders, starts = np.zeros((p, ranked), np.int64), np.zeros((p, ranked + 1), np.int64)
    n_values = np.zeros(p, np.int64)
    if spearman:
        for j, x in enumerate(X):
            orders[j], first, n_values[j] = _numbered(x)
            starts[j, :len(first)] = first
        y_numbered = _numbered(y)
    else:
        y_numbered = (orders[:0].ravel(), starts[:0].ravel(), 0)
    plan = _pairwise_plan(n)
    yb, boot = np.empty(idx.shape), np.empty((idx.shape[0], p))
    _bootstrap_rows(idx, yb, y, *y_numbered, spearman, plan)
    _bootstrap_dots(idx, yb, boot, X, orders, starts, n_values, spearman, plan)
    alpha = 0.5 * (1.0 - confidence)
    lower, upper = np.full(p, math.nan), np.full(p, math.nan)
    for j in range(p):
        finite = np.clip(boot[:, j], -1.0, 1.0)
        finite = finite[np.isfinite(finite)]  # resamples without variance have no correlation
        if len(finite):
            lower[j], upper[j] = np.quantile(finite, [alpha, 1.0 - alpha])
    return estimate, lower, upper


def prcc(X, y, design: RankDesign | None = None) -> np.ndarray:
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
    design : RankDesign, optional
        :func:`rank_design` of ``X``, when several features share the runs (the factorisation does not depend on
        ``y``); computed here otherwise.

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
    design = rank_design(X) if design is None else design
    if design.residuals_x is None:
        return out
    Q, R_inv, residuals_x = design.Q, design.R_inv, design.residuals_x
    ry = stats.rankdata(y)
    coefficients = Q.T @ ry
    beta = R_inv[1:] @ coefficients
    residuals_y = (ry - Q @ coefficients)[:, None] + beta * residuals_x
    explained = _EXPLAINED * n**3  # rank variance ~ n^3 / 12
    for k, j in enumerate(varying):
        rx, rr = residuals_x[:, k], residuals_y[:, k]
        if min(rx @ rx, rr @ rr) > explained:
            out[j] = _pearson(rx, rr)
    return out


@dataclass(frozen=True)
class RankDesign:
    """The factorisation :func:`prcc` regresses on, from the sampled values alone: ``A = [1, ranks of the varying
    columns] = Q R``, ``R^-1``, and each column's residual on the others (``A H e_k / H_kk``); ``residuals_x`` is
    None where ``A`` is rank deficient (every PRCC is then NaN)."""

    Q: np.ndarray | None
    R_inv: np.ndarray | None
    residuals_x: np.ndarray | None


def rank_design(X) -> RankDesign:
    """:class:`RankDesign` of the sampled values ``X`` (shape (n, p)) for :func:`prcc`.

    The factorisation runs on one BLAS thread: a 1000 x 49 QR takes ~8 ms on one core, and 0.2-1 s when OpenBLAS's
    threads wait for each other on cores other work holds (measured on the shared 2-core machine, load 7-11); the
    factors are the same bits either way (checked on a 7 x 1000 analysis, docs/performance.md)."""
    X = np.asarray(X, dtype=float)
    varying = np.flatnonzero(np.ptp(X, axis=0) > 0)
    n = X.shape[0]
    if len(varying) == 0 or n < len(varying) + 3:
        return RankDesign(None, None, None)
    with threadpool_limits(1, user_api="blas"):  # see the docstring
        Q, R = np.linalg.qr(np.column_stack([np.ones(n), stats.rankdata(X[:, varying], axis=0)]))
        if np.abs(np.diag(R)).min() <= 1e-9 * np.abs(np.diag(R)).max():
            return RankDesign(None, None, None)
        R_inv = np.linalg.solve(R, np.eye(R.shape[0]))
        H_diag = (R_inv * R_inv).sum(axis=1)  # diagonal of H = R^-1 R^-T
        return RankDesign(Q, R_inv, (Q @ R_inv.T[:, 1:]) / H_diag[1:])
