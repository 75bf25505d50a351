"""Separation of the feature distributions of two data sets: the overlap coefficient and the detection probability
of one against the other's threshold at the detection rule's false-alarm rate."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from campaigns.analysis.settings import AnalysisSettings
from campaigns.analysis.vocabulary import features_of, used
from campaigns.statistics.detection import detection_probability, overlap_coefficient


def separation(results: xr.Dataset, settings: AnalysisSettings) -> xr.Dataset:
    """``overlap`` and ``detection_probability`` along (feature, dataset, reference): for data sets with at least
    ``min_ok_runs`` used runs of the feature, the detection probability where the reference has
    ``settings.detection_runs`` (its quantile is the threshold)."""
    features = features_of(results)
    names = [str(n) for n in results["dataset"].values]
    false_alarm_rate = settings.false_alarm_rate
    overlap = np.full((len(features), len(names), len(names)), math.nan)
    detection = np.full_like(overlap, math.nan)
    for f, feature in enumerate(features):
        mask = used(results, feature)
        samples = [results[feature].sel(dataset=n).values[mask.sel(dataset=n).values] for n in names]
        enough = [len(y) >= settings.min_ok_runs for y in samples]
        for a, b in ((a, b) for a in range(len(names)) for b in range(len(names))):
            if enough[a] and enough[b]:
                overlap[f, a, b] = overlap_coefficient(samples[a], samples[b])
                if len(samples[b]) >= settings.detection_runs:  # b's quantile is the threshold
                    detection[f, a, b] = detection_probability(samples[b], samples[a], false_alarm_rate)
    data_vars = {
        "overlap": (("feature", "dataset", "reference"), overlap,
                    {"units": "1", "long_name": "overlap coefficient of the feature distributions"}),
        "detection_probability": (
            ("feature", "dataset", "reference"),
            detection,
            {"units": "1",
             "long_name": "fraction of dataset runs beyond the reference's threshold at false-alarm rate "
                          f"{false_alarm_rate:g} (NaN: fewer than min_detection_runs in the reference, or "
                          "min_ok_runs in the data set)"},
        ),
    }
    coords = {
        "dataset": ("dataset", np.array(names, dtype=object)),
        "reference": ("reference", np.array(names, dtype=object)),
        "feature": ("feature", np.array(features, dtype=object)),
    }
    return xr.Dataset(data_vars, coords=coords)
