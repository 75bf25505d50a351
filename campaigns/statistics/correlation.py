"""Correlations of a feature with the sampled values: Pearson and Spearman with percentile-bootstrap intervals, and
the partial rank correlation coefficient (PRCC)."""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from campaigns.statistics.defaults import CONFIDENCE

#: Residual sum of squares of ranks, relative to n^3, below which a PRCC regression counts as exact (round-off only).
_EXPLAINED = 1e-18


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
    n_boot = idx.shape[0]
    values, group = np.unique(v, return_inverse=True)
    resampled = group[idx]
    counts = np.bincount((resampled + len(values) * np.arange(n_boot)[:, None]).ravel(), minlength=n_boot * len(values))
    counts = counts.reshape(n_boot, len(values)).astype(float)
    rank = np.cumsum(counts, axis=1) - 0.5 * (counts - 1.0)
    return np.take_along_axis(rank, resampled, axis=1)


def bootstrap_correlations(X: np.ndarray, y: np.ndarray, idx: np.ndarray, method: str, confidence: float):
    """Estimates and percentile CIs for each row of ``X`` (shape (p, n)) against ``y``, shared resamples ``idx``."""
    spearman = method == "spearman"
    estimate = _pearson(stats.rankdata(X, axis=-1), stats.rankdata(y)[None, :]) if spearman else _pearson(X, y[None, :])

    def resampled(v: np.ndarray) -> np.ndarray:
        return resampled_ranks(v, idx) if spearman else v[idx]

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
