"""Paired comparison of two campaigns' feature distributions over the same sampled runs.

Two configurations of one spec (a solver against a finer reference, :mod:`campaigns.solver_accuracy`;
the automatic fidelity against the full model, :mod:`campaigns.fidelity_audit`) run with the same seeds,
so run i of a data set has the same parameters and the same noise under both. The shift of the mean and of
the standard deviation, the largest paired difference and the Kolmogorov-Smirnov distance are set against
the Monte Carlo sampling error of the mean, ``1.96 sigma / sqrt(N)``.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.stats import ks_2samp


def compare_features(candidate: xr.Dataset, reference: xr.Dataset, feature: str = "backlash_feature") -> xr.Dataset:
    """Per data set: mean and sigma shifts, KS distance and p-value, and 1.96 sigma / sqrt(N)."""
    rows = []
    for name in candidate.dataset.values:
        both = (candidate.status.sel(dataset=name) == "ok") & (reference.status.sel(dataset=name) == "ok")
        a = candidate[feature].sel(dataset=name).where(both, drop=True).values
        b = reference[feature].sel(dataset=name).where(both, drop=True).values
        ks = ks_2samp(a, b)
        rows.append({
            "n": a.size,
            "mean_shift": float(np.mean(a) - np.mean(b)),
            "sigma_shift": float(np.std(a, ddof=1) - np.std(b, ddof=1)),
            "max_paired_difference": float(np.max(np.abs(a - b))),
            "ks_distance": float(ks.statistic),
            "ks_pvalue": float(ks.pvalue),
            "sampling_error": float(1.96 * np.std(b, ddof=1) / np.sqrt(b.size)),
        })
    data = {key: ("dataset", [r[key] for r in rows]) for key in rows[0]}
    ds = xr.Dataset(data, coords={"dataset": candidate.dataset.values})
    for key in ("mean_shift", "sigma_shift", "max_paired_difference", "sampling_error"):
        ds[key].attrs["units"] = "m"
    return ds
