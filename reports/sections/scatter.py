"""Section "Feature against the top-ranked parameters": scatter plots."""

from __future__ import annotations

from reports import figures
from reports.builder import SCATTER_PARAMETERS, Builder
from reports.figures import Line, Panel
from reports.model import Callout, Paragraph
from reports.ranking import ranked_over_datasets
from reports.units import axis_label, display_scale


def build(b: Builder):
    a = b.analysis
    parameters = [str(p) for p in a["parameter"].values]
    yield Paragraph(
        "The feature against its top-ranked parameters (largest |Spearman ρ| in any data set). Each data set's mean is "
        "subtracted from its feature values, so data sets with different backlash share one axis and the dependence "
        "within a data set is visible."
    )
    for feature in b.measured:
        factor, unit = b.feature_scale(feature)
        top = [parameters[j] for j in ranked_over_datasets(a, feature)[:SCATTER_PARAMETERS]]
        if not top:
            yield Callout(f"{feature}: no parameter with a finite correlation, nothing to plot.")
            continue
        panels = []
        for parameter in top:
            values = b.results[parameter]
            p_factor, p_unit = display_scale(values.attrs.get("units", ""), values.values)
            points = []
            for name in b.datasets:
                mask = b.used_mask(feature, name)
                if mask.any():
                    y = b.results[feature].sel(dataset=name).values[mask]
                    x = b.results[parameter].sel(dataset=name).values[mask]
                    points.append(Line(name, x * p_factor, (y - y.mean()) * factor, b.color[name]))
            panels.append(Panel(parameter, axis_label(parameter, p_unit),
                                axis_label(f"{feature} − data-set mean", unit), tuple(points)))
        yield b.figure(
            f"scatter-{feature}",
            f"{feature} (minus its data-set mean) against its {len(top)} top-ranked parameters, "
            "one colour per data set. "
            "A clear slope means the tolerance moves the feature; compare the vertical spread it explains with the "
            "backlash to be detected.",
            figures.scatter(panels),
        )
