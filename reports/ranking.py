"""Orders of the parameters by strength: the tornado charts, the scatter plots and page 1's influences rank alike."""

from __future__ import annotations

import numpy as np


def rank_order(values: np.ndarray) -> np.ndarray:
    """Indices of the finite entries, strongest magnitude first (ties in parameter order)."""
    finite = np.flatnonzero(np.isfinite(values))
    return finite[np.argsort(-np.abs(values[finite]), kind="stable")]


def largest_first(values: np.ndarray) -> np.ndarray:
    """Indices of the finite entries, largest (signed) first (ties in parameter order)."""
    finite = np.flatnonzero(np.isfinite(values))
    return finite[np.argsort(-values[finite], kind="stable")]


def ranked_over_datasets(analysis, feature: str) -> np.ndarray:
    """Parameter indices by their largest |Spearman ρ| in any data set (parameters without one left out)."""
    rho = np.abs(analysis["spearman"].sel(feature=feature).transpose("parameter", "dataset").values)
    strongest = np.array([row[np.isfinite(row)].max() if np.isfinite(row).any() else np.nan for row in rho])
    return rank_order(strongest)
