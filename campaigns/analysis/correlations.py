"""Correlations of each feature with each sampled value, per data set: Pearson and Spearman with seeded
percentile-bootstrap intervals, the partial rank correlation coefficient (PRCC), and the first-order (Sobol') index
with its effect size (:mod:`campaigns.statistics.sensitivity`). A data set below ``min_ok_runs`` used runs of a
feature gets NaN; an index below :data:`campaigns.statistics.sensitivity.MIN_RUNS` runs, or outside its own
interval, is flagged in ``first_order_index_flag``: every output prints its interval only."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from campaigns.analysis.settings import SENSITIVITY_STREAM, AnalysisSettings, on_threads
from campaigns.analysis.vocabulary import feature_units, features_of, parameters_of, used
from campaigns.statistics import sensitivity
from campaigns.statistics.correlation import RankDesign, bootstrap_correlations, prcc, rank_design


def correlations(results: xr.Dataset, settings: AnalysisSettings) -> xr.Dataset:
    """``pearson``, ``spearman`` (with ``_ci``), ``prcc``, ``first_order_index`` (with its flag and interval) and
    ``effect_size`` (with its interval) along (dataset, feature, parameter). The correlation bootstrap of data set
    ``d`` and feature ``f`` draws from ``SeedSequence(seed, spawn_key=(d, f))``, the index's from
    ``(SENSITIVITY_STREAM, d, f)``; each data set and feature is computed alone, on the cores' threads
    (:func:`campaigns.analysis.settings.on_threads`)."""
    parameters, features = parameters_of(results), features_of(results)
    names = [str(n) for n in results["dataset"].values]
    confidence, n_boot, seed = settings.confidence, settings.n_boot, settings.seed
    sensitivity_boot = settings.sensitivity_boot
    shape = (len(names), len(features), len(parameters))
    out = {k: np.full(shape, math.nan) for k in ("pearson", "spearman", "prcc")}
    ci = {k: np.full(shape + (2,), math.nan) for k in ("pearson", "spearman", "first_order_index", "effect_size")}
    out["first_order_index"], effect_size = np.full(shape, math.nan), np.full(shape, math.nan)
    first_order_flag = np.zeros(shape, dtype=np.int8)
    tasks = []  # (data set, feature, sampled values, feature values, PRCC factorisation) with enough used runs
    for d, name in enumerate(names):
        row = results.sel(dataset=name)
        sampled = np.stack([row[p].values for p in parameters]) if parameters else np.empty((0, row.sizes["run"]))
        designs: dict[bytes, RankDesign] = {}  # the PRCC factorisation per set of runs: features mostly share theirs
        for f, feature in enumerate(features):
            mask = used(results, feature).sel(dataset=name).values
            y = row[feature].values[mask]
            first_order_flag[d, f] = sensitivity.BELOW_MIN_RUNS if len(y) < sensitivity.MIN_RUNS else 0
            if len(y) < settings.min_ok_runs:
                continue
            X = np.ascontiguousarray(sampled[:, mask])  # row-major as stacked: numpy sums a row pairwise only so
            design = designs.get(mask.tobytes())
            if design is None:  # here, not on the threads: it pins BLAS to one thread, a setting of the process
                design = designs[mask.tobytes()] = rank_design(X.T)
            tasks.append((d, f, X, y, design))

    def one(task) -> None:
        """Every statistic of one data set and feature, into its cells of the arrays above."""
        d, f, X, y, design = task
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(d, f)))
        idx = rng.integers(0, len(y), (n_boot, len(y)))
        for method in ("pearson", "spearman"):
            estimate, lower, upper = bootstrap_correlations(X, y, idx, method, confidence)
            out[method][d, f] = estimate
            ci[method][d, f, :, 0], ci[method][d, f, :, 1] = lower, upper
        out["prcc"][d, f] = prcc(X.T, y, design)
        found = sensitivity.first_order(
            X.T, y, n_boot=sensitivity_boot, confidence=confidence,
            seed=np.random.SeedSequence(seed, spawn_key=(SENSITIVITY_STREAM, d, f)),
        )
        first_order_flag[d, f] = sensitivity.unresolved(found["index"], found["ci"], len(y))
        out["first_order_index"][d, f], effect_size[d, f] = found["index"], found["effect_size"]
        ci["first_order_index"][d, f], ci["effect_size"][d, f] = found["ci"], found["effect_size_ci"]

    on_threads(one, tasks)
    corr_dims = ("dataset", "feature", "parameter")
    in_feature_units = feature_units([str(results[f].attrs.get("units", "1")) for f in features])
    data_vars = {
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
                          "alone, any shape of dependence; not to be printed where first_order_index_flag is set "
                          f"(below {sensitivity.MIN_RUNS} used runs, or outside its own interval): print the interval",
             "method": sensitivity.METHOD, "min_runs": sensitivity.MIN_RUNS},
        ),
        "first_order_index_flag": (
            corr_dims,
            first_order_flag,
            {"long_name": "why first_order_index and effect_size are not resolved (0: they are): fewer used runs "
                          f"than {sensitivity.MIN_RUNS} (the chance level of inert parameters' indices is then above "
                          "0.1), or the estimate outside its own bootstrap interval; where set, only the intervals "
                          "are printed",
             "flag_masks": np.array([sensitivity.BELOW_MIN_RUNS, sensitivity.OUTSIDE_INTERVAL], dtype=np.int8),
             "flag_meanings": sensitivity.FLAG_MEANINGS, "min_runs": sensitivity.MIN_RUNS},
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
                "long_name": "standard deviation of the conditional mean E[feature | parameter] over the parameter's "
                             "distribution, sqrt(max(first_order_index, 0) var(feature)): "
                             "what the parameter alone moves the feature by (not resolved where "
                             "first_order_index_flag is set: print effect_size_ci)",
                "method": sensitivity.METHOD,
                **in_feature_units,
            },
        ),
        "effect_size_ci": (
            corr_dims + ("bound",),
            ci["effect_size"],
            {"long_name": "effect_size at the bounds of first_order_index_ci (feature variance held fixed)",
             **in_feature_units},
        ),
    }
    coords = {
        "dataset": ("dataset", np.array(names, dtype=object)),
        "feature": ("feature", np.array(features, dtype=object)),
        "parameter": ("parameter", np.array(parameters, dtype=object)),
        "bound": ("bound", np.array(["lower", "upper"], dtype=object)),
    }
    return xr.Dataset(data_vars, coords=coords)
