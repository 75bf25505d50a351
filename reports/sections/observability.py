"""Section "Observability": the backlash sweep and the minimum detectable backlash (Table 9.3)."""

from __future__ import annotations

import math

import numpy as np

from reports import figures
from reports.builder import Builder
from reports.figures import Line
from reports.model import Callout, Heading, Paragraph
from reports.sections.executive import backlash_requirement, verdicts
from reports.units import axis_label, display_scale, number, quantity


def build(b: Builder):
    a = b.analysis
    fa = float(a.attrs.get("false_alarm_rate", 0.05))
    power = float(a.attrs.get("detection_power", 0.95))
    yield Paragraph(
        f"Separation between data sets: the detection probability is the fraction of a data set's runs beyond the "
        f"threshold that flags {fa:.0%} of a reference data set's runs (false alarms); the overlap coefficient is the "
        "shared area of the two feature histograms (1: indistinguishable, 0: disjoint)."
    )
    for feature in b.measured:
        detection = a["detection_probability"].sel(feature=feature).transpose("dataset", "reference").values
        yield b.figure(
            f"separation-{feature}",
            f"Detection probability of {feature}: runs of the row data set flagged by a threshold set on the column "
            f"data set at a {fa:.0%} false-alarm rate. Cells near 1 mean the bench tells the two conditions apart; "
            "compare the data sets with backlash (rows) against those without (columns).",
            figures.heatmap(detection, b.datasets, b.datasets, colorbar_label="detection probability [–]",
                            xlabel="reference data set (threshold)", ylabel="tested data set", vmin=0.0, vmax=1.0,
                            cmap="viridis"),
        )
        overlap = a["overlap"].sel(feature=feature).transpose("dataset", "reference").values
        yield b.figure(
            f"overlap-{feature}",
            f"Overlap coefficient of the {feature} distributions of each pair of data sets. Low values (dark) mean "
            "well-separated distributions; the diagonal is 1 by definition.",
            figures.heatmap(overlap, b.datasets, b.datasets, colorbar_label="overlap coefficient [–]",
                            xlabel="data set", ylabel="data set", vmin=0.0, vmax=1.0, cmap="magma"),
        )
    yield Heading("Minimum detectable backlash")
    # the verdict is the analysis's sentence, verbatim (with its bounds and n); the report adds only facts of the curve
    yield from verdicts(b, "")
    if "sweep_backlash" not in a or "minimum_detectable_backlash" not in a:
        yield Callout("Not available: the campaign spec has no observability sweep ([observability] sweep), so the "
                      "minimum detectable backlash cannot be compared with the 1 µm requirement.")
        return
    sweep = [str(s) for s in a["sweep_point"].values]
    backlash = a["sweep_backlash"].values
    requirement, source = backlash_requirement(a)
    factor, unit = display_scale("m", [requirement])
    yield Paragraph(
        f"Along the sweep {', '.join(sweep)} (data sets differing only in backlash: "
        f"{', '.join(quantity(x, 'm') for x in backlash)}), the detection probability against the zero-backlash "
        f"data set is interpolated linearly to where it reaches {power:.0%}: the minimum detectable backlash."
    )
    minimum = {f: float(a["minimum_detectable_backlash"].sel(feature=f)) for f in b.features}
    probability = {f: a["sweep_detection_probability"].sel(feature=f).values for f in b.features}
    for feature in b.features:
        if not math.isfinite(minimum[feature]):
            yield Callout(f"{feature}: the detection probability never reaches {power:.0%} along the sweep.", "info")
    if (backlash > 0).any():
        smallest = int(np.flatnonzero(backlash == backlash[backlash > 0].min())[0])
        bounded = [f for f in b.features if probability[f][smallest] >= power]
        if bounded:
            yield Paragraph(
                f"For {', '.join(bounded)} the smallest non-zero level of the sweep "
                f"({quantity(backlash[smallest], 'm')}) is already detected, so the minimum detectable backlash is an "
                "upper bound from the interpolation between 0 and that level. Add data sets with backlash near the "
                "requirement to resolve it."
            )
    curves = [Line(f, backlash * factor, probability[f], f"C{k}", "-" if k == 0 else "--")
              for k, f in enumerate(b.features)]
    minima = [(f"{f}: minimum detectable {number(minimum[f] * factor)} {unit}", minimum[f] * factor, f"C{k}")
              for k, f in enumerate(b.features)]
    yield b.figure(
        "detection-sweep",
        "Detection probability against backlash along the sweep, per feature. Where a curve crosses the "
        f"{power:.0%} line (star) is the minimum detectable backlash, the green line the requirement; the verdict "
        f"above also weighs the bootstrap bounds of the star's position.",
        figures.detection(curves, power=power, false_alarm_rate=fa,
                          requirement=(f"requirement {number(requirement * factor)} {unit} ({source.split(':')[0]})",
                                       requirement * factor),
                          minima=minima, xlabel=axis_label("backlash", unit)),
    )
    for feature in b.measured:
        yield b.figure(
            f"sweep-distribution-{feature}",
            f"{feature} for the sweep data sets (Fig. 9.10 style). The smallest backlash whose distribution clears the "
            "zero-backlash one is what the bench can observe.",
            figures.distributions(b.distribution_panels(feature, sweep)),
        )
