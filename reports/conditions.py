"""Data-set labels from the conditions of each data set's effective scene.

The campaign driver stores every condition of each data set's effective scene in
``results.attrs["dataset_conditions"]`` (JSON ``{dataset: {condition: {"value", "unit"}}}``,
including ``external_force_peak``, the largest |force demand|; CONTRACT.md) and the base
scene's in ``results.attrs["base_scene_conditions"]``. A label shows every condition that
differs between the data sets or from the base scene, each quantity in one SI-prefixed unit
chosen over all data sets (80 µm beside 0 µm, never beside 0 m). Results written before the
driver stored the conditions fall back to the spec's overrides (the scene's own values,
such as its external force, are then unknown, and the label says so).

Nothing here imports simulation code: the conditions are read from the results file.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np

from reports.units import display_scale, number

#: Conditions listed first, in the order of Table 9.4; the others follow in the order the scene gives them.
_FIRST = ("backlash", "preload", "external_force_peak", "external_force", "cylinder", "zero_procedure")
#: How a condition reads in a label (default: its name with spaces).
_NAMES = {"external_force_peak": "external force", "preload_configuration": "preload configuration"}


@dataclass(frozen=True)
class DatasetConditions:
    """The conditions of every data set, and which of them a label shows.

    Attributes
    ----------
    values : dict
        ``{dataset: {condition: (value, unit)}}``; ``value`` is a float (SI) or a string.
    shown : tuple of str
        Conditions that differ between data sets or from the base scene, in label order.
    common : tuple of str
        Conditions every data set shares (stated once, not in every label).
    from_scene : bool
        True when read from the stored effective scenes; False for the spec-override fallback.
    """

    values: dict
    shown: tuple[str, ...]
    common: tuple[str, ...]
    from_scene: bool

    def scale(self, condition: str) -> tuple[float, str]:
        """One display unit per quantity, chosen from its largest magnitude over the data sets."""
        numbers = [v for v, _ in (d[condition] for d in self.values.values() if condition in d)
                   if isinstance(v, (int, float))]
        unit = next((u for d in self.values.values() if condition in d for _, u in [d[condition]]), "")
        return display_scale(unit, numbers)

    def text(self, dataset: str, condition: str) -> str:
        """``backlash 80 µm``, ``external force 4 kN`` or ``zero procedure encoder index``."""
        name = _NAMES.get(condition, condition.replace("_", " "))
        if condition not in self.values.get(dataset, {}):
            return f"{name} (scene's own)"
        value, _ = self.values[dataset][condition]
        if not isinstance(value, (int, float)):
            return f"{name} {value}"
        factor, unit = self.scale(condition)
        return f"{name} {number(value * factor)}" + (f" {unit}" if unit not in ("", "–") else "")

    def label(self, dataset: str) -> str:
        """Every shown condition of a data set, comma separated (empty when none differs)."""
        return ", ".join(self.text(dataset, c) for c in self.shown)

    def common_text(self) -> str:
        """The conditions all data sets share, e.g. ``room temperature 298 K, supply pressure 7 bar``."""
        first = next(iter(self.values), None)
        return ", ".join(self.text(first, c) for c in self.common) if first is not None else ""


def dataset_conditions(results, spec: dict) -> DatasetConditions:
    """The data sets' conditions from ``results.nc`` (stored effective scenes, else the spec's overrides)."""
    datasets = [str(d) for d in results["dataset"].values]
    stored = results.attrs.get("dataset_conditions")
    if stored:
        raw = json.loads(stored)
        values = {d: {k: (c["value"], c.get("unit", "")) for k, c in raw.get(d, {}).items()} for d in datasets}
        base_raw = json.loads(results.attrs.get("base_scene_conditions", "{}") or "{}")
        base = {k: (c["value"], c.get("unit", "")) for k, c in base_raw.items()}
        from_scene = True
    else:
        entries = {d["name"]: d for d in spec["datasets"]}
        values = {d: {k: (v, _condition_unit(results, k)) for k, v in entries[d].get("conditions", {}).items()}
                  for d in datasets}
        base, from_scene = {}, False
    names = list(dict.fromkeys(k for d in datasets for k in values[d]))
    names.sort(key=lambda k: _FIRST.index(k) if k in _FIRST else len(_FIRST))

    def differs(condition: str) -> bool:
        seen = [values[d].get(condition, (None, ""))[0] for d in datasets]
        if condition in base:
            seen.append(base[condition][0])
        return any(not _same(seen[0], v) for v in seen[1:])

    shown = tuple(k for k in names if differs(k))
    common = tuple(k for k in names if k not in shown)
    return DatasetConditions(values, shown, common, from_scene)


def _same(a, b) -> bool:
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return math.isclose(a, b, rel_tol=1e-12, abs_tol=0.0) or (np.isnan(a) and np.isnan(b))
    return a == b


def _condition_unit(results, key: str) -> str:
    variable = f"condition_{key}"
    return results[variable].attrs.get("units", "") if variable in results else ""
