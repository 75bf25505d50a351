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


def resampled_ranks(v: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """``scipy.stats.rankdata(v[idx], axis=-1)`` (average ranks) without sorting every resample.

    A resample's rank of a value is the number of resampled values below it plus half of
    (its own count + 1): cumulative bootstrap counts over the values sorted once.
    """
    values, group = np.unique(v, return_inverse=True)
    out = np.empty(idx.shape)
    counts, rank = np.empty(len(values)), np.empty(len(values))
    for b in range(idx.shape[0]):
        _ranks_of_resample(group, idx[b], counts, rank)
        out[b] = rank[group[idx[b]]]
    return out


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
def _ranks_of_resample(group, resample, counts, rank):
    """Each distinct value's count in one resample (indices ``resample`` into values numbered by ``group``) and its
    average rank there: whole and half numbers, exact in any order of summation."""
    counts[:] = 0.0
    for i in range(len(resample)):
        counts[group[resample[i]]] += 1.0
    below = 0.0
    for k in range(len(counts)):
        below += counts[k]
        rank[k] = below - 0.5 * (counts[k] - 1.0)


@numba.njit(**KERNEL)
def _standardized_resample(values, group, resample, spearman, weights, weighted, counts, rank, row, work, plan,
                           partial):
    """One resample of ``values`` (or, ``spearman``, of their ranks) into ``row``, centred and scaled to unit norm
    (NaN without variance) as numpy computes ``c = v - mean(v); c / sqrt(sum(c * c))`` (:func:`_pairwise_sum`;
    ``work``: one row of scratch), times ``weights`` where ``weighted`` (the other resample of a correlation).

    Ranks take a shorter way to the same bits: a resample's ranks are whole or half numbers summing to
    ``n (n + 1) / 2``, so its mean, centred ranks and sum of squares are exact in any order of summation and come
    from the counts of each distinct value (``rank`` then holds each value's standardized rank).
    """
    n = len(resample)
    if spearman:
        _ranks_of_resample(group, resample, counts, rank)
        total = 0.0
        for k in range(len(counts)):
            total += counts[k] * rank[k]
        mean = total / n
        squares = 0.0
        for k in range(len(counts)):
            rank[k] = rank[k] - mean
            squares += counts[k] * (rank[k] * rank[k])
        norm = np.sqrt(squares)
        for k in range(len(counts)):
            rank[k] = rank[k] / norm
        for i in range(n):
            row[i] = rank[group[resample[i]]] * weights[i] if weighted else rank[group[resample[i]]]
        return
    for i in range(n):
        row[i] = values[resample[i]]
    mean = _pairwise_sum(row, plan, partial) / n
    for i in range(n):
        row[i] = row[i] - mean
        work[i] = row[i] * row[i]
    norm = np.sqrt(_pairwise_sum(work, plan, partial))
    for i in range(n):
        row[i] = (row[i] / norm) * weights[i] if weighted else row[i] / norm


@numba.njit(**KERNEL)
def _bootstrap_rows(values, group, n_values, idx, spearman, plan, standardized):
    """Every resample (row of ``idx``) standardized (:func:`_standardized_resample`) into ``standardized``."""
    counts, rank, work, unweighted = np.empty(n_values), np.empty(n_values), np.empty(idx.shape[1]), np.empty(0)
    partial = np.empty(plan.shape[0])
    for b in range(idx.shape[0]):
        _standardized_resample(values, group, idx[b], spearman, unweighted, False, counts, rank, standardized[b], work,
                               plan, partial)


@numba.njit(**KERNEL)
def _bootstrap_dots(values, group, n_values, idx, spearman, plan, yb, out):
    """``out[b]``: the correlation of resample ``b`` of ``values`` with the standardized resample ``yb[b]``, as numpy
    sums ``sum(standardized(x[b]) * yb[b])``; one row at a time, in cache."""
    n = idx.shape[1]
    counts, rank, row, work = np.empty(n_values), np.empty(n_values), np.empty(n), np.empty(n)
    partial = np.empty(plan.shape[0])
    for b in range(idx.shape[0]):
        _standardized_resample(values, group, idx[b], spearman, yb[b], True, counts, rank, row, work, plan, partial)
        out[b] = _pairwise_sum(row, plan, partial)


def bootstrap_correlations(X: np.ndarray, y: np.ndarray, idx: np.ndarray, method: str, confidence: float):
    """Estimates and percentile CIs for each row of ``X`` (shape (p, n)) against ``y``, shared resamples ``idx``.

    Each resample's correlation is the dot product of the two resampled rows centred and scaled to unit norm
    (Spearman: of their ranks, :func:`resampled_ranks`), in compiled loops that sum as numpy sums
    (:func:`_pairwise_sum`): numpy's numbers without an (n_boot, n) temporary per step.
    """
    spearman = method == "spearman"
    estimate = _pearson(stats.rankdata(X, axis=-1), stats.rankdata(y)[None, :]) if spearman else _pearson(X, y[None, :])
    idx = np.ascontiguousarray(idx, dtype=np.int64)

    def numbered(v: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
        v = np.ascontiguousarray(v, dtype=float)
        if not spearman:
            return v, np.zeros(1, dtype=np.int64), 1
        values, group = np.unique(v, return_inverse=True)
        return v, group.astype(np.int64), len(values)

    yb = np.empty(idx.shape)
    plan = _pairwise_plan(idx.shape[1])
    _bootstrap_rows(*numbered(y), idx, spearman, plan, yb)  # once, shared by every parameter
    alpha = 0.5 * (1.0 - confidence)
    lower, upper = np.full(len(X), math.nan), np.full(len(X), math.nan)
    boot = np.empty(idx.shape[0])
    for j, x in enumerate(X):
        _bootstrap_dots(*numbered(x), idx, spearman, plan, yb, boot)
        finite = np.clip(boot, -1.0, 1.0)
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
