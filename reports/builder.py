"""Shared state and settings of the report builder: the inputs, the colours and numbering, the limits of
each chart. The sections (:mod:`reports.sections`) build on it; :mod:`reports.content` assembles them."""

from __future__ import annotations

import numpy as np

from reports.conditions import dataset_conditions
from reports.figures import Group, Panel
from reports.inputs import Inputs
from reports.model import Figure, Table
from reports.phrases import insufficient
from reports.units import axis_label, display_scale

#: Parameters shown in a tornado chart (the strongest by |Spearman ρ|): two charts fit on a page.
TORNADO_PARAMETERS = 10
#: Ok runs below which a data set's statistics are greyed out, when analysis.nc states no ``min_ok_runs``
#: (older analyses): fewer runs than this give correlations of ±1 by chance alone.
FALLBACK_MIN_OK_RUNS = 10
#: Influences per feature in the executive summary.
SUMMARY_INFLUENCES = 3
#: Parameter rows of a correlation heat map (with wrapped names, a page holds about this many).
HEATMAP_PARAMETERS = 20
#: Parameters in the scatter plots of a feature.
SCATTER_PARAMETERS = 4
#: Run indices listed per row of the failed-runs table before "and N more".
LISTED_RUNS = 12
#: Standard deviation, relative to the mean, below which a feature counts as constant (floating-point round-off).
ROUND_OFF = 1e-12
#: Two-sided normal quantile of the 95 % band of a correlation under independence.
Z95 = 1.96
#: Trace panels in the order of Figs. 9.6/9.7/9.12: title, quantity (axis label) and the stored variables each draws.
TRACE_PANELS = (
    ("Position demand and response", "position", ("position_demand", "nut1_position", "linear_encoder_position")),
    ("Motor current", "current", ("motor_current", "motor_current_measured", "current_demand")),
    ("Preload and external force", "force",
     ("preload_force", "preload_force_measured", "external_force", "external_force_measured", "force_demand")),
    ("Chamber pressures", "pressure (absolute)", ("chamber1_pressure", "chamber2_pressure")),
)
#: Variables of the nut-minus-screw signal of Eq. 9.12 (Fig. 9.11).
NUT, SCREW = "nut1_position", "screw_equivalent_position"


class Builder:
    """Shared state while building: the inputs, the colours of the data sets and the numbering."""

    def __init__(self, inputs: Inputs):
        self.inputs = inputs
        self.results, self.analysis, self.spec = inputs.results, inputs.analysis, inputs.spec["spec"]
        self.datasets = [str(d) for d in self.results["dataset"].values]
        self.color = {name: f"C{i % 10}" for i, name in enumerate(self.datasets)}
        self.features = [str(v) for v in self.results.data_vars if self.results[v].attrs.get("role") == "feature"]
        self.measured = [f for f in self.features
                         if not (f.endswith("_true") and f.removesuffix("_true") in self.features)]
        self.parameters = [str(v) for v in self.results.data_vars if self.results[v].attrs.get("role") == "sampled"]
        # one source for the parameter counts of every sentence and caption: sampled, and of those varying
        self.constant = [p for p in self.parameters if not np.ptp(np.nan_to_num(self.results[p].values.astype(float)))]
        self.varying = [p for p in self.parameters if p not in self.constant]
        self.conditions = dataset_conditions(self.results, self.spec)
        stated = self.analysis.attrs.get("min_ok_runs")
        self.min_ok_runs = int(stated) if stated is not None else FALLBACK_MIN_OK_RUNS
        self.min_ok_source = ("the analysis's minimum" if stated is not None
                              else "the report's default; this analysis.nc states no minimum")
        self._figures = 0
        self._tables = 0

    def figure(self, key: str, caption: str, png: bytes) -> Figure:
        self._figures += 1
        return Figure(self._figures, key, caption, png)

    def table(self, caption: str, header, rows, muted=()) -> Table:
        self._tables += 1
        return Table(self._tables, caption, tuple(header), tuple(tuple(r) for r in rows), tuple(muted))

    def parameter_counts(self, names: bool = True) -> str:
        """``38 sampled values, of which 36 vary from run to run (2 constant: a, b)``."""
        text = f"{len(self.parameters)} sampled value(s), of which {len(self.varying)} vary from run to run"
        if not self.constant:
            return text
        return text + (f" ({len(self.constant)} constant by their distribution: {', '.join(self.constant)})" if names
                       else f" ({len(self.constant)} constant)")

    def n_used(self, dataset: str, feature: str) -> int:
        return int(self.analysis["n_used"].sel(dataset=dataset, feature=feature))

    def insufficient(self, dataset: str, feature: str) -> str | None:
        """Why a data set's statistics of a feature rest on too few runs (None when they do not).

        The analysis decides (``data_sufficient``); an older analysis without it is judged
        against ``min_ok_runs`` or the report's stated default.
        """
        n = self.n_used(dataset, feature)
        if "data_sufficient" in self.analysis:
            if int(self.analysis["data_sufficient"].sel(dataset=dataset, feature=feature)):
                return None
        elif n >= self.min_ok_runs:
            return None
        return insufficient(n, self.min_ok_runs)

    def true_of(self, feature: str) -> str | None:
        """The true-signal counterpart of a measured feature, if the campaign stored one."""
        name = feature + "_true"
        return name if name in self.features else None

    def used_mask(self, feature: str, dataset: str) -> np.ndarray:
        """The runs of a data set that the statistics use (status ok, finite feature), as in
        :mod:`campaigns.analysis.campaign_analysis`."""
        row = self.results.sel(dataset=dataset)
        return (row["status"].values == "ok") & np.isfinite(row[feature].values.astype(float))

    def used(self, feature: str, dataset: str) -> np.ndarray:
        """Feature values of the runs the statistics use."""
        return self.results[feature].sel(dataset=dataset).values[self.used_mask(feature, dataset)]

    def pair(self, feature: str) -> list[str]:
        """A measured feature and, when stored, its true-signal counterpart."""
        true = self.true_of(feature)
        return [feature, true] if true else [feature]

    def feature_scale(self, feature: str) -> tuple[float, str]:
        """One display unit for a feature and its true counterpart, so their panels compare directly."""
        unit = self.results[feature].attrs.get("units", "")
        return display_scale(unit, np.concatenate([self.results[f].values.ravel() for f in self.pair(feature)]))

    def distribution_panels(self, feature: str, datasets: list[str]) -> list[Panel]:
        """Density panels of a feature (measured, then true signals) over the given data sets."""
        factor, unit = self.feature_scale(feature)
        pair = self.pair(feature)
        return [Panel(f"{f} ({kind})" if len(pair) > 1 else f, axis_label(f, unit), f"probability density [1/{unit}]",
                      tuple(Group(d, self.used(f, d) * factor, self.color[d]) for d in datasets))
                for f, kind in zip(pair, ("measured", "true signals"), strict=False)]

    def describe(self, dataset: str) -> str:
        """``ds3 (backlash 0 µm, preload 0 kN, external force 4 kN)``: every condition that tells the data sets
        apart."""
        entry = next(d for d in self.spec["datasets"] if d["name"] == dataset)
        scene = entry.get("scene") or self.spec["base"]["scene"]
        parts = ([f"scene {scene}"] if scene != dataset else []) + ([self.conditions.label(dataset)]
                                                                    if self.conditions.shown else [])
        return f"{dataset} ({'; '.join(parts)})" if parts else dataset

    def label(self, name: str) -> str:
        """The stored long name of a variable (its name when it has none)."""
        return self.results[name].attrs.get("long_name", name) if name in self.results else name


def solver_description(spec: dict) -> str:
    """The campaign's solver configuration in words (unset entries are the model's defaults)."""
    solver = spec.get("solver", {})
    return ", ".join(f"{k} = {'model default' if v is None else v}" for k, v in solver.items()) or "model defaults"
