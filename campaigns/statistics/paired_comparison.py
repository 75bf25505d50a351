"""Paired comparison of two campaigns' feature distributions over the same sampled runs, and the verdict vocabulary.

Two configurations of one spec (a solver against a finer reference, :mod:`campaigns.bench.solver_accuracy`;
the automatic fidelity against the full model, :mod:`campaigns.bench.fidelity_audit`) run with the same seeds,
so run i of a data set has the same parameters and the same noise under both. :func:`compare_features` gives the
descriptive figures: the shift of the mean and of the standard deviation, the largest paired difference and the
Kolmogorov-Smirnov distance beside the Monte Carlo sampling error of the mean, ``1.96 sigma / sqrt(N)``. The verdict
on them is the accuracy rule's (:mod:`campaigns.statistics.accuracy_rule`), in the words of :data:`VERDICTS`, each a
:class:`Verdict` with its bounds, n and the one sentence every output prints. :func:`ensemble_spread` is the spread of
an ensemble of tight runs (:mod:`campaigns.bench.reference_ensemble`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy.stats import chi2, ks_2samp


def _paired_figures(a: np.ndarray, b: np.ndarray) -> dict[str, float]:
    """The figures of one data set's paired runs; NaN where too few runs define them (no run: all; one: the spreads)."""
    nan = math.nan
    n = a.size
    with warnings.catch_warnings():
        # scipy's exact two-sample KS distribution fails for some small samples (e.g. 5 against 5, D = 0.2) and falls
        # back to the asymptotic one, saying so; the p-value is descriptive, no part of any verdict
        warnings.filterwarnings("ignore", "ks_2samp: Exact calculation unsuccessful", RuntimeWarning)
        ks = ks_2samp(a, b) if n else None
    return {
        "n": n,
        "mean_shift": float(np.mean(a) - np.mean(b)) if n else nan,
        "sigma_shift": float(np.std(a, ddof=1) - np.std(b, ddof=1)) if n > 1 else nan,
        "max_paired_difference": float(np.max(np.abs(a - b))) if n else nan,
        "ks_distance": float(ks.statistic) if n else nan,
        "ks_pvalue": float(ks.pvalue) if n else nan,
        "sampling_error": float(1.96 * np.std(b, ddof=1) / np.sqrt(n)) if n > 1 else nan,
    }


def compare_features(candidate: xr.Dataset, reference: xr.Dataset, feature: str = "backlash_feature") -> xr.Dataset:
    """Per data set: mean and sigma shifts, KS distance and p-value, and 1.96 sigma / sqrt(N)."""
    rows = []
    for name in candidate.dataset.values:
        both = (candidate.status.sel(dataset=name) == "ok") & (reference.status.sel(dataset=name) == "ok")
        a = candidate[feature].sel(dataset=name).where(both, drop=True).values
        b = reference[feature].sel(dataset=name).where(both, drop=True).values
        rows.append(_paired_figures(a, b))
    data = {key: ("dataset", [r[key] for r in rows]) for key in rows[0]}
    ds = xr.Dataset(data, coords={"dataset": candidate.dataset.values})
    for key in ("mean_shift", "sigma_shift", "max_paired_difference", "sampling_error"):
        ds[key].attrs["units"] = "m"
    return ds


#: The verdicts of every judgement (campaigns.statistics.accuracy_rule, the analysis), best first.
VERDICTS = ("met", "not met", "undetermined", "insufficient data")


def ensemble_spread(values, confidence: float = 0.95) -> dict[str, float]:
    """Spread of an ensemble of runs that should agree: ``n``, ``mean``, ``min``, ``max``, ``range`` (max - min),
    the sample standard deviation ``std`` and its chi-square interval ``std_lower``/``std_upper`` at
    ``confidence`` (exact for normal members; the range is the distribution-free figure). Non-finite values
    (failed runs) are left out."""
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    n = int(x.size)
    if n < 2:
        nan = math.nan
        return {"n": n, "mean": float(x.mean()) if n else nan, "min": float(x.min()) if n else nan,
                "max": float(x.max()) if n else nan, "range": nan, "std": nan, "std_lower": nan, "std_upper": nan}
    std = float(x.std(ddof=1))
    alpha = 1 - confidence
    return {"n": n, "mean": float(x.mean()), "min": float(x.min()), "max": float(x.max()),
            "range": float(x.max() - x.min()), "std": std,
            "std_lower": std * math.sqrt((n - 1) / chi2.ppf(1 - alpha / 2, n - 1)),
            "std_upper": std * math.sqrt((n - 1) / chi2.ppf(alpha / 2, n - 1))}


def worst_verdict(verdicts) -> str:
    """The verdict of several together: ``not met`` if any is, then ``undetermined``, then ``insufficient data``;
    ``met`` only if every one is (and there is at least one)."""
    found = set(verdicts)
    return next((v for v in ("not met", "undetermined", "insufficient data") if v in found),
                "met" if found else "insufficient data")


@dataclass(frozen=True)
class Verdict:
    """A verdict with the numbers it rests on; ``statement`` is the one sentence every output prints."""

    verdict: str
    estimate: float   # what is judged, e.g. a mean paired shift [m] or a ratio of standard deviations
    lower: float      # lower bound of what the estimate can be (its interval), same unit
    upper: float      # upper bound
    n: int
    statement: str
