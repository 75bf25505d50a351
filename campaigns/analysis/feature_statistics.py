"""The distribution of each feature per data set: runs used and excluded, runs per status, and the mean, standard
deviation and quantiles with the interval each method allows at the data set's number of runs (at any n: a few runs
already separate data sets whose means differ by many spreads, issue 42)."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from campaigns.analysis.settings import AnalysisSettings
from campaigns.analysis.vocabulary import features_of, used
from campaigns.statistics.intervals import (
    MEAN_INTERVAL_METHOD,
    QUANTILE_INTERVAL_METHOD,
    STD_INTERVAL_METHOD,
    mean_interval,
    quantile_interval,
    std_interval,
)
from campaigns.statistics.order_statistics import quantile_interval_min_runs
from campaigns.units import feature_units

#: Probabilities of the quantiles stored per data set (``feature_quantile``): the median and the two tails that the
#: detection rule reads (a 5 % false-alarm threshold on either side of a reference).
QUANTILE_PROBABILITIES = (0.05, 0.5, 0.95)


def feature_statistics(results: xr.Dataset, settings: AnalysisSettings) -> xr.Dataset:
    """``n_used``, ``n_excluded``, ``n_status``, ``data_sufficient`` (at least ``settings.min_ok_runs`` used runs)
    and ``feature_mean``, ``feature_std``, ``feature_quantile`` with their intervals, per data set and feature."""
    features = features_of(results)
    names = [str(n) for n in results["dataset"].values]
    confidence, min_ok_runs = settings.confidence, settings.min_ok_runs
    n_used = np.zeros((len(names), len(features)), dtype=np.int64)
    mean, std = np.full(n_used.shape, math.nan), np.full(n_used.shape, math.nan)
    mean_ci, std_ci = np.full(n_used.shape + (2,), math.nan), np.full(n_used.shape + (2,), math.nan)
    quantiles = np.full(n_used.shape + (len(QUANTILE_PROBABILITIES),), math.nan)
    quantiles_ci = np.full(quantiles.shape + (2,), math.nan)
    for d, name in enumerate(names):
        row = results.sel(dataset=name)
        for f, feature in enumerate(features):
            y = row[feature].values[used(results, feature).sel(dataset=name).values]
            n_used[d, f] = len(y)
            mean[d, f], *mean_ci[d, f] = mean_interval(y, confidence)
            std[d, f], *std_ci[d, f] = std_interval(y, confidence)
            for k, q in enumerate(QUANTILE_PROBABILITIES):
                quantiles[d, f, k], *quantiles_ci[d, f, k] = quantile_interval(y, q, confidence)
    statuses = sorted(set(results["status"].values.ravel().tolist()))
    n_status = np.array([[int((results["status"].sel(dataset=n) == s).sum()) for s in statuses] for n in names])
    n_runs = results.sizes["run"]
    units = [str(results[f].attrs.get("units", "1")) for f in features]
    in_feature_units = feature_units(units)
    data_vars = {
        "n_used": (("dataset", "feature"), n_used.astype(np.int32),
                   {"units": "1", "long_name": "runs used (status ok, finite feature)"}),
        "n_excluded": (("dataset", "feature"), (n_runs - n_used).astype(np.int32),
                       {"units": "1", "long_name": "runs excluded from the statistics"}),
        "n_status": (("dataset", "status"), n_status.astype(np.int32), {"units": "1", "long_name": "runs per status"}),
        "data_sufficient": (
            ("dataset", "feature"),
            (n_used >= min_ok_runs).astype(np.int8),
            {
                "long_name": f"at least {min_ok_runs} used runs (else the data set's correlations, indices and "
                             "detection probabilities are NaN; its mean, standard deviation and quantiles are given "
                             "with their intervals at any n, which below this floor rest on a shape so few runs "
                             "cannot check)",
                "flag_values": np.array([0, 1], dtype=np.int8),
                "flag_meanings": "insufficient_data sufficient_data",
                "min_ok_runs": min_ok_runs,
            },
        ),
        "feature_mean": (("dataset", "feature"), mean,
                         {"long_name": "mean of the feature over used runs (from 1 run)", **in_feature_units}),
        "feature_mean_ci": (("dataset", "feature", "bound"), mean_ci,
                            {"long_name": f"{confidence:g} interval of feature_mean (below min_ok_runs, "
                                          "data_sufficient = 0: flagged, read as indicative)",
                             "method": MEAN_INTERVAL_METHOD, **in_feature_units}),
        "feature_std": (("dataset", "feature"), std,
                        {"long_name": "standard deviation of the feature over used runs (from 2 runs)",
                         **in_feature_units}),
        "feature_std_ci": (("dataset", "feature", "bound"), std_ci,
                           {"long_name": f"{confidence:g} interval of feature_std (below min_ok_runs, "
                                          "data_sufficient = 0: flagged, read as indicative)",
                            "method": STD_INTERVAL_METHOD, **in_feature_units}),
        "feature_quantile": (("dataset", "feature", "quantile_probability"), quantiles,
                             {"long_name": "quantile of the feature over used runs (linear interpolation between "
                                           "order statistics)", **in_feature_units}),
        "feature_quantile_ci": (("dataset", "feature", "quantile_probability", "bound"), quantiles_ci,
                                {"long_name": f"{confidence:g} interval of feature_quantile (NaN: n too small for a "
                                              "bound, below feature_quantile_min_runs)",
                                 "method": QUANTILE_INTERVAL_METHOD, **in_feature_units}),
        "feature_quantile_min_runs": (
            "quantile_probability",
            np.array([quantile_interval_min_runs(q, confidence) for q in QUANTILE_PROBABILITIES], dtype=np.int32),
            {"units": "1", "long_name": "fewest used runs with which order statistics bound the quantile on both "
                                        f"sides at {confidence:g}"}),
    }
    coords = {
        "dataset": ("dataset", np.array(names, dtype=object)),
        "feature": ("feature", np.array(features, dtype=object)),
        "feature_units": ("feature", np.array(units, dtype=object), {"long_name": "units of each feature"}),
        "bound": ("bound", np.array(["lower", "upper"], dtype=object)),
        "quantile_probability": ("quantile_probability", np.array(QUANTILE_PROBABILITIES),
                                 {"units": "1", "long_name": "probability of the quantile"}),
        "status": ("status", np.array(statuses, dtype=object)),
    }
    return xr.Dataset(data_vars, coords=coords)
