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

#: Table 9.3: minimum detectable linear backlash [m].
BACKLASH_REQUIREMENT = 1e-6
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


def _correlations(X: np.ndarray, y: np.ndarray, idx: np.ndarray, method: str, confidence: float):
    """Estimates and percentile CIs for each row of ``X`` (shape (p, n)) against ``y``, shared resamples ``idx``."""
    transform = (lambda v: stats.rankdata(v, axis=-1)) if method == "spearman" else (lambda v: v)
    estimate = _pearson(transform(X), transform(y)[None, :])
    yb = transform(y[idx])  # ranked once, shared by every parameter
    alpha = 0.5 * (1.0 - confidence)
    lower, upper = np.full(len(X), math.nan), np.full(len(X), math.nan)
    for j, x in enumerate(X):
        boot = _pearson(transform(x[idx]), yb)
        boot = boot[np.isfinite(boot)]  # resamples without variance have no correlation
        if len(boot):
            lower[j], upper[j] = np.quantile(boot, [alpha, 1.0 - alpha])
    return estimate, lower, upper


def prcc(X, y) -> np.ndarray:
    """Partial rank correlation coefficient of each column of ``X`` with ``y``.

    The PRCC of column ``j`` is the Pearson correlation of the residuals of
    ``rank(x_j)`` and ``rank(y)`` after linear regression (with intercept) on
    the ranks of the other columns (Marino et al. 2008, J. Theor. Biol. 254,
    Sec. 2.4), computed here by that definition. Constant columns are left out
    of the regressions and get NaN; so does a column whose residual is zero
    (the other columns explain it, or ``y``, completely) and every column when
    there are too few rows.

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
    if len(varying) == 0 or np.ptp(y) == 0 or len(y) < len(varying) + 3:
        return out
    R, ry = stats.rankdata(X[:, varying], axis=0), stats.rankdata(y)
    for k, j in enumerate(varying):
        others = np.column_stack([np.ones(len(y)), np.delete(R, k, axis=1)])
        rx, rr = (v - others @ np.linalg.lstsq(others, v, rcond=None)[0] for v in (R[:, k], ry))
        if min(rx @ rx, rr @ rr) > _EXPLAINED * len(y) ** 3:  # rank variance ~ n^3 / 12
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
    if np.median(test) >= np.median(reference):
        return float(np.mean(test > np.quantile(reference, 1.0 - false_alarm_rate)))
    return float(np.mean(test < np.quantile(reference, false_alarm_rate)))


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


def requirement_verdict(lower: float, upper: float, requirement: float = BACKLASH_REQUIREMENT) -> str:
    """``"yes"`` if the bracket of the minimum detectable level lies at or below ``requirement``,
    ``"no"`` if at or above it (its lower level is not detected), else ``"undetermined"``."""
    if upper <= requirement:
        return "yes"
    if lower >= requirement:
        return "no"
    return "undetermined"


def _used(results: xr.Dataset, feature: str) -> xr.DataArray:
    return (results["status"] == "ok") & np.isfinite(results[feature])


def observability_sweep(
    results: xr.Dataset, feature: str, datasets: list[str], *, false_alarm_rate: float = 0.05, power: float = 0.95
) -> xr.Dataset:
    """Detection probability along a backlash sweep and the minimum detectable backlash.

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

    Returns
    -------
    xarray.Dataset
        ``sweep_backlash(sweep_point)``, ``sweep_detection_probability(sweep_point)``,
        the scalar ``minimum_detectable_backlash`` (the Table 9.3 requirement in its
        attributes), ``minimum_detectable_bracket(bound)`` (the sweep levels around
        it) and ``meets_requirement`` (``"yes"``, ``"no"`` or ``"undetermined"``:
        the requirement lies inside the bracket, refine the sweep).
    """
    backlash = np.array([float(results["condition_backlash"].sel(dataset=n)) for n in datasets])
    reference_name = datasets[int(np.flatnonzero(backlash == 0.0)[0])]

    def values(name: str) -> np.ndarray:
        sel = results[feature].sel(dataset=name)
        return sel.values[_used(results, feature).sel(dataset=name).values]

    reference = values(reference_name)
    probability = np.array([detection_probability(reference, values(n), false_alarm_rate) for n in datasets])
    minimum, lower, upper = minimum_detectable(backlash, probability, power)
    return xr.Dataset(
        {
            "sweep_backlash": ("sweep_point", backlash, {"units": "m", "long_name": "backlash of the sweep data set"}),
            "sweep_detection_probability": (
                "sweep_point",
                probability,
                {"units": "1", "long_name": f"detection probability at false-alarm rate {false_alarm_rate:g} against {reference_name}"},
            ),
            "minimum_detectable_backlash": (
                (),
                minimum,
                {
                    "units": "m",
                    "long_name": f"smallest backlash detected with probability {power:g} at false-alarm rate {false_alarm_rate:g} (linear interpolation along the sweep; NaN: not reached)",
                    "requirement": BACKLASH_REQUIREMENT,
                    "requirement_source": "Table 9.3: minimum detectable linear backlash 1 µm",
                },
            ),
            "minimum_detectable_bracket": (
                "bound",
                np.array([lower, upper]),
                {"units": "m", "long_name": "sweep levels bracketing minimum_detectable_backlash (inf: never detected)"},
            ),
            "meets_requirement": (
                (),
                requirement_verdict(lower, upper),
                {"long_name": "minimum detectable backlash within the Table 9.3 requirement (1 µm): yes / no / undetermined (the requirement lies inside the bracket: refine the sweep)"},
            ),
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
) -> xr.Dataset:
    """Compute every statistic of :func:`analyze` on an opened results dataset."""
    parameters = [v for v in results.data_vars if results[v].attrs.get("role") == "sampled"]
    features = [v for v in results.data_vars if results[v].attrs.get("role") == "feature"]
    names = [str(n) for n in results["dataset"].values]
    shape = (len(names), len(features), len(parameters))
    out = {k: np.full(shape, math.nan) for k in ("pearson", "spearman", "prcc")}
    ci = {k: np.full(shape + (2,), math.nan) for k in ("pearson", "spearman")}
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
            used_values[d, f] = y
            n_used[d, f] = len(y)
            if len(y) < 3:
                continue
            mean[d, f], std[d, f] = y.mean(), y.std(ddof=1)
            X = np.stack([row[p].values[mask] for p in parameters]) if parameters else np.empty((0, len(y)))
            rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(d, f)))
            idx = rng.integers(0, len(y), (n_boot, len(y)))
            for method in ("pearson", "spearman"):
                estimate, lower, upper = _correlations(X, y, idx, method, confidence)
                out[method][d, f] = estimate
                ci[method][d, f, :, 0], ci[method][d, f, :, 1] = lower, upper
            out["prcc"][d, f] = prcc(X.T, y)
    for f in range(len(features)):
        for a in range(len(names)):
            for b in range(len(names)):
                overlap[f, a, b] = overlap_coefficient(used_values[a, f], used_values[b, f])
                detection[f, a, b] = detection_probability(used_values[b, f], used_values[a, f], false_alarm_rate)
    statuses = sorted(set(results["status"].values.ravel().tolist()))
    n_status = np.array([[int((results["status"].sel(dataset=n) == s).sum()) for s in statuses] for n in names])
    n_runs = results.sizes["run"]

    corr_dims = ("dataset", "feature", "parameter")
    data_vars = {
        "n_used": (("dataset", "feature"), n_used, {"long_name": "runs used (status ok, finite feature)"}),
        "n_excluded": (("dataset", "feature"), n_runs - n_used, {"long_name": "runs excluded from the statistics"}),
        "n_status": (("dataset", "status"), n_status, {"long_name": "runs per status"}),
        "feature_mean": (("dataset", "feature"), mean, {"long_name": "mean of the feature over used runs"}),
        "feature_std": (("dataset", "feature"), std, {"long_name": "standard deviation of the feature over used runs"}),
        "pearson": (corr_dims, out["pearson"], {"units": "1", "long_name": "Pearson correlation"}),
        "pearson_ci": (corr_dims + ("bound",), ci["pearson"], {"units": "1", "long_name": f"{confidence:g} percentile-bootstrap interval of pearson"}),
        "spearman": (corr_dims, out["spearman"], {"units": "1", "long_name": "Spearman rank correlation"}),
        "spearman_ci": (corr_dims + ("bound",), ci["spearman"], {"units": "1", "long_name": f"{confidence:g} percentile-bootstrap interval of spearman"}),
        "prcc": (corr_dims, out["prcc"], {"units": "1", "long_name": "partial rank correlation coefficient"}),
        "overlap": (("feature", "dataset", "reference"), overlap, {"units": "1", "long_name": "overlap coefficient of the feature distributions"}),
        "detection_probability": (
            ("feature", "dataset", "reference"),
            detection,
            {"units": "1", "long_name": f"fraction of dataset runs beyond the reference's threshold at false-alarm rate {false_alarm_rate:g}"},
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
    sweep = json.loads(results.attrs["spec_json"])["spec"]["observability"]["sweep"]
    if sweep:
        per_feature = [
            observability_sweep(results, f, sweep, false_alarm_rate=false_alarm_rate, power=power) for f in features
        ]
        combined = xr.concat([s.drop_vars("sweep_backlash") for s in per_feature], dim="feature")
        analysis = analysis.merge(combined.assign_coords(feature=analysis["feature"]))
        analysis["sweep_backlash"] = per_feature[0]["sweep_backlash"]
    analysis.attrs = {
        "Conventions": "CF-1.8",
        "title": f"Analysis of {results.attrs.get('title', 'a BenchTwin campaign')}",
        "source_spec_hash": results.attrs.get("spec_hash", ""),
        "selection": "statistics use runs with status 'ok' and a finite feature; see n_used, n_excluded, n_status",
        "bootstrap": json.dumps({"method": "percentile, pairs resampled", "n_boot": n_boot, "confidence": confidence, "seed": seed}),
        "false_alarm_rate": false_alarm_rate,
        "detection_power": power,
        "backlash_sweep": json.dumps(sweep),
    }
    return analysis


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
    from campaigns.storage import atomic_write

    atomic_write(out_path, lambda tmp: analysis.to_netcdf(tmp, engine="netcdf4"))
    return out_path
