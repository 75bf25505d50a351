"""What the analyses say alike: the Table 9.3 requirement and its wording, the fault quantity of each sweep
condition, the attributes of the verdict variables, and which runs a statistic uses."""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from campaigns.statistics.detection import RESOLUTIONS

#: Table 9.3: minimum detectable linear backlash [m].
BACKLASH_REQUIREMENT = 1e-6
REQUIREMENT_SOURCE = "Bertolino (2020) Table 9.3: minimum detectable linear backlash 1 µm"
#: What a sweep's condition measures: condition -> (fault quantity, unit, display scale, display unit). The
#: fault size of a data set is ``|condition - condition of the reference|`` (the backlash itself; the loss of
#: preload from the healthy reference).
SWEEP_QUANTITIES = {"backlash": ("backlash", "m", 1e6, "µm"), "preload": ("preload loss", "N", 1.0, "N")}
VERDICT_ATTRS = {"long_name": "verdict on the Table 9.3 requirement: met / not met / undetermined / insufficient data"}
STATEMENT_ATTRS = {
    "long_name": "the verdict on the Table 9.3 requirement with the estimate, its bounds and the sample size, "
                 "in one sentence"}
#: The analysis's mark of the features a sweep's verdicts are about (``features`` of its ``[[observability]]``
#: table; every feature when it names none), with the sweep's :func:`sweep_key`: ``sweep_feature_preload``.
SWEEP_FEATURE = "sweep_feature"
SWEEP_FEATURE_ATTRS = {
    "long_name": "whether the sweep's verdict is about the feature (the features of its [[observability]] table; "
                 "every feature when it names none): page 1 and the printed summary give the marked ones",
    "flag_values": np.array([0, 1], dtype=np.int8),
    "flag_meanings": "other_feature sweep_feature",
}
RESOLUTION_ATTRS = {
    "long_name": "how far the sweep resolves the minimum detectable level: resolved (a sweep level lies strictly "
                 "inside the bootstrap bounds: the value is printed), between_adjacent_levels (the bracket of two "
                 "adjacent sweep levels is the finding), beyond_sweep (no level detected with the power), "
                 "insufficient_data",
    "flag_values": np.arange(len(RESOLUTIONS), dtype=np.int8),
    "flag_meanings": " ".join(RESOLUTIONS),
}


def requirement_of(observability: dict) -> tuple[float, str]:
    """The requirement [SI] on the swept fault size and its source: the spec's ``observability`` table's, else
    Table 9.3's."""
    return (observability.get("requirement") or BACKLASH_REQUIREMENT,
            observability.get("requirement_source") or REQUIREMENT_SOURCE)


def used(results: xr.Dataset, feature: str) -> xr.DataArray:
    """The runs a statistic of ``feature`` uses: status ok and a finite feature."""
    return (results["status"] == "ok") & np.isfinite(results[feature])


def runs_text(n: int) -> str:
    """``"1 ok run"``, ``"3 ok runs"``."""
    return f"{n} ok run{'s' if n != 1 else ''}"


def features_of(results: xr.Dataset) -> list[str]:
    """The feature variables of ``results.nc``, in their stored order."""
    return [v for v in results.data_vars if results[v].attrs.get("role") == "feature"]


def parameters_of(results: xr.Dataset) -> list[str]:
    """The sampled-value variables of ``results.nc``, in their stored order."""
    return [v for v in results.data_vars if results[v].attrs.get("role") == "sampled"]


def stored_spec(results: xr.Dataset) -> dict:
    """The spec the results were computed from, as ``results.nc`` stores it."""
    return json.loads(results.attrs["spec_json"])["spec"]


def sweep_key(index: int, condition: str) -> str:
    """What tells a spec's fault sweeps apart in the analysis's variable names: ``""`` for the first (its variables
    keep the names of a spec with one sweep, so older analysis files read the same), ``"_<condition>"`` for each
    further one (``requirement_verdict_preload``, along ``sweep_point_preload``); a spec sweeps each condition at most
    once (:func:`campaigns.runner.spec.cross_field_problems`)."""
    return "" if index == 0 else f"_{condition}"


def sweeps_of(spec: dict) -> list[tuple[str, dict]]:
    """Each fault sweep of a stored spec, the first first, with its :func:`sweep_key`: the ``observability`` table
    and the ``further_sweeps`` of a spec written with ``[[observability]]`` tables; empty without a sweep."""
    tables = [spec["observability"], *spec.get("further_sweeps", [])]
    return [(sweep_key(k, t.get("condition", "backlash")), t) for k, t in enumerate(tables) if t["sweep"]]


def sweep_features(table: dict, features: list[str]) -> list[str]:
    """The features a stored sweep table's verdicts are about, in the campaign's order: those its ``features`` names
    (left out of the stored spec when empty), else every one of ``features``."""
    named = table.get("features") or features
    return [f for f in features if f in named]


def marked_features(analysis: xr.Dataset, key: str = "") -> list[str]:
    """The features the analysis marks as the verdicts of the sweep with :func:`sweep_key` ``key`` are about
    (:data:`SWEEP_FEATURE`); every feature when it has no mark (an analysis written before sweeps named theirs)."""
    features = [str(f) for f in analysis["feature"].values]
    name = SWEEP_FEATURE + key
    if name not in analysis:
        return features
    return [f for f, marked in zip(features, analysis[name].values, strict=True) if marked]


def is_within_unit(spec: dict) -> bool:
    """Whether a stored spec is a within-unit campaign: units and a sweep (a fidelity audit's runs keep the units but
    no sweep)."""
    return spec.get("units") is not None and bool(spec["observability"]["sweep"])


def sweep_levels(results: xr.Dataset, datasets: list[str], condition: str = "backlash",
                 reference: str | None = None) -> tuple[np.ndarray, int]:
    """The fault size [SI] of each sweep data set, ``|condition - condition of the reference|``, and the index of the
    reference (``reference`` named, else the data set where the condition is zero)."""
    values = np.array([float(results[f"condition_{condition}"].sel(dataset=n)) for n in datasets])
    index = datasets.index(reference) if reference is not None else int(np.flatnonzero(values == 0.0)[0])
    return np.abs(values - values[index]), index
