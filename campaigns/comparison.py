"""Paired comparison of two campaigns' feature distributions over the same sampled runs.

Two configurations of one spec (a solver against a finer reference, :mod:`campaigns.solver_accuracy`;
the automatic fidelity against the full model, :mod:`campaigns.fidelity_audit`) run with the same seeds,
so run i of a data set has the same parameters and the same noise under both. The shift of the mean and of
the standard deviation, the largest paired difference and the Kolmogorov-Smirnov distance are set against
the Monte Carlo sampling error of the mean, ``1.96 sigma / sqrt(N)``.

The verdicts (met / not met / undetermined / insufficient data), each with its bounds, n and the one sentence
every output prints: :func:`paired_shift_verdict` (a paired mean shift against a tolerance and a scene's
numerical floor: the fidelity audit) and :func:`reference_verdict` (one run against an ensemble of tight
references: ``benchmarks/single_run.py``); :func:`ensemble_spread` is the spread of such an ensemble.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy.stats import chi2, ks_2samp, t

#: Fewest paired runs for a verdict on a mean shift: a sample standard deviation needs two.
MIN_PAIRS = 2


def _paired_figures(a: np.ndarray, b: np.ndarray) -> dict[str, float]:
    """The figures of one data set's paired runs; NaN where too few runs define them (no run: all; one: the spreads)."""
    nan = math.nan
    n = a.size
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


#: The verdicts of :func:`reference_verdict` and :func:`paired_shift_verdict`.
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
    estimate: float   # m: the error (reference_verdict) or the mean paired shift (paired_shift_verdict)
    lower: float      # m: lower bound of what the estimate can be
    upper: float      # m: upper bound
    n: int
    statement: str


def _um(value: float) -> str:
    return f"{value * 1e6:.4f} µm"


def reference_verdict(candidate: float, references, target: float) -> Verdict:
    """Is a candidate's feature within ``target`` of a reference that is itself an ensemble?

    The references are tight runs that differ only in what should not matter (:mod:`campaigns.reference_ensemble`);
    each is an equally valid reference, so the candidate's error lies between its distance to the nearest and
    to the farthest of them: ``|c - m| -/+ s`` with ``m`` the centre of the references' range and ``s`` its
    half-width (the references' own uncertainty, distribution-free). ``met`` when even the farthest reference is
    within the target, ``not met`` when even the nearest is beyond it, ``undetermined`` otherwise (e.g. when the
    references disagree by more than the target), ``insufficient data`` without a finite candidate or reference.

    Parameters
    ----------
    candidate : float
        The candidate's feature [m].
    references : array_like
        The ensemble's feature values [m]; non-finite ones (failed runs) are left out.
    target : float
        Largest acceptable error [m].
    """
    refs = np.asarray(references, dtype=float)
    refs = refs[np.isfinite(refs)]
    n = int(refs.size)
    if n == 0 or not np.isfinite(candidate):
        why = "no finite reference" if n == 0 else "the candidate has no finite feature"
        return Verdict("insufficient data", math.nan, math.nan, math.nan, n,
                       f"insufficient data: {why} ({n} reference{'s' if n != 1 else ''}); target {_um(target)}")
    centre, spread = (refs.max() + refs.min()) / 2, (refs.max() - refs.min()) / 2
    error = abs(candidate - centre)
    lower, upper = max(error - spread, 0.0), error + spread
    verdict = "met" if upper <= target else "not met" if lower > target else "undetermined"
    return Verdict(verdict, error, lower, upper, n,
                   f"{verdict}: error {_um(error)} (bounds {_um(lower)} to {_um(upper)}: nearest and farthest of "
                   f"{n} references, which spread over {_um(2 * spread)}); target {_um(target)}")


def paired_shift_verdict(differences, tolerance: float, floor: float = 0.0, *, confidence: float = 0.95,
                         min_pairs: int = MIN_PAIRS) -> Verdict:
    """Is the mean of paired differences (a candidate against a reference over the same runs) within tolerance?

    The Student-t interval of the mean paired difference at ``confidence``: ``met`` when it lies within
    ``±tolerance`` (equivalence shown), ``not met`` when it lies beyond ``±(tolerance + floor)``: a shift
    within the scene's numerical sensitivity floor (the spread of tight runs that differ only in what should
    not matter, :mod:`campaigns.reference_ensemble`) is not attributable to the candidate, so only what exceeds
    it counts against it; ``undetermined`` otherwise; ``insufficient data`` below ``min_pairs`` finite pairs.

    Parameters
    ----------
    differences : array_like
        Paired differences candidate - reference [m]; non-finite ones are left out.
    tolerance : float
        Largest acceptable mean shift [m].
    floor : float
        Numerical sensitivity floor of the scene [m] (0: not known).
    confidence : float
        Two-sided confidence of the interval.
    min_pairs : int
        Fewest finite pairs with which a verdict is given.
    """
    d = np.asarray(differences, dtype=float)
    d = d[np.isfinite(d)]
    n = int(d.size)
    if n < max(min_pairs, 2):
        return Verdict("insufficient data", math.nan, math.nan, math.nan, n,
                       f"insufficient data: {n} paired run{'s' if n != 1 else ''} (at least {max(min_pairs, 2)} "
                       f"needed); tolerance {_um(tolerance)}")
    mean = float(d.mean())
    half = float(t.ppf(0.5 + confidence / 2, n - 1) * d.std(ddof=1) / math.sqrt(n))
    lower, upper = mean - half, mean + half
    if max(abs(lower), abs(upper)) <= tolerance:
        verdict = "met"
    elif lower > tolerance + floor or upper < -(tolerance + floor):
        verdict = "not met"
    else:
        verdict = "undetermined"
    floor_text = f"numerical floor {_um(floor)}" if floor > 0 else "numerical floor not measured"
    return Verdict(verdict, mean, lower, upper, n,
                   f"{verdict}: mean shift {mean * 1e6:+.4f} µm ({confidence * 100:g} % t interval "
                   f"{lower * 1e6:+.4f} to {upper * 1e6:+.4f} µm, n = {n}); tolerance {_um(tolerance)}, "
                   f"{floor_text}")
