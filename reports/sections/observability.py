"""Section "Observability": the backlash sweep and the minimum detectable backlash (Table 9.3)."""

from __future__ import annotations

import math

import numpy as np

from campaigns.analysis.campaign_analysis import RESOLUTIONS, printed_estimate
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
    floor, reason = a.attrs.get("min_detection_runs"), a.attrs.get("min_detection_runs_reason", "")
    for feature in b.measured:
        detection = a["detection_probability"].sel(feature=feature).transpose("dataset", "reference").values
        blank = [d for d, column in zip(b.datasets, detection.T, strict=True) if not np.isfinite(column).any()]
        yield b.figure(
            f"separation-{feature}",
            f"Detection probability of {feature}: runs of the row data set flagged by a threshold set on the column "
            f"data set at a {fa:.0%} false-alarm rate. Cells near 1 mean the bench tells the two conditions apart; "
            "compare the data sets with backlash (rows) against those without (columns)."
            + (f" Blank columns ({', '.join(blank)}): insufficient data for a threshold"
               + (f", fewer than {int(floor)} ok runs: {reason}." if floor is not None else ".")
               if blank else ""),
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
        f"{', '.join(number(x * factor) for x in backlash)} {unit}), the minimum detectable backlash is where the "
        f"detection probability against the zero-backlash data set reaches {power:.0%}. Between two sweep levels "
        "the runs say nothing, so the finding is the pair of adjacent levels around that crossing; a value between "
        "them is given only where the sweep resolves it (its bootstrap bounds hold a sweep level inside), rounded to "
        "the precision of those bounds. Each sentence above is the analysis's, verbatim."
    )
    minimum = {f: float(a["minimum_detectable_backlash"].sel(feature=f)) for f in b.features}
    probability = {f: a["sweep_detection_probability"].sel(feature=f).values for f in b.features}
    resolution = {f: _resolution(a, f, minimum[f]) for f in b.features}
    for feature in b.features:
        if resolution[feature] == "beyond_sweep":
            yield Callout(f"{feature}: the detection probability never reaches {power:.0%} along the sweep.", "info")
    if (backlash > 0).any():
        smallest = int(np.flatnonzero(backlash == backlash[backlash > 0].min())[0])
        bounded = [f for f in b.features if probability[f][smallest] >= power]
        if bounded:
            yield Paragraph(
                f"For {', '.join(bounded)} the smallest non-zero level of the sweep "
                f"({quantity(backlash[smallest], 'm')}) is already detected, so the minimum detectable backlash lies "
                "between 0 and that level, and no value inside is resolved. Add data sets with backlash near the "
                "requirement to resolve it."
            )
    curves = [Line(f, backlash * factor, probability[f], f"C{k}", "-" if k == 0 else "--")
              for k, f in enumerate(b.features)]
    minima = [(f"{f}: minimum detectable {number(_printed(a, f, minimum[f]) * factor)} {unit}", minimum[f] * factor,
               f"C{k}") for k, f in enumerate(b.features)]
    bracketed = [f"{f} between {number(lo * factor)} and {number(hi * factor)} {unit}"
                 for f in b.features if resolution[f] == "between_adjacent_levels"
                 for lo, hi in [a["minimum_detectable_bracket"].sel(feature=f).values]]
    yield b.figure(
        "detection-sweep",
        "Detection probability against backlash along the sweep, per feature; the dashed line is the "
        f"{power:.0%} target, the green line the requirement. A star marks a minimum detectable backlash the sweep "
        "resolves; "
        + (f"where it does not, the minimum lies between two adjacent levels ({'; '.join(bracketed)}) and no star is "
           "drawn (the straight segments between the points are not data). " if bracketed else
           "the straight segments between the points are not data. ")
        + "The verdict above weighs the bootstrap bounds.",
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


def _resolution(analysis, feature: str, minimum: float) -> str:
    """How far the sweep resolves the feature's minimum detectable backlash, as the analysis flagged it
    (``minimum_detectable_status``); an older analysis without the flag: resolved when it states a value."""
    if "minimum_detectable_status" in analysis:
        status = analysis["minimum_detectable_status"].sel(feature=feature)
        meanings = status.attrs.get("flag_meanings", " ".join(RESOLUTIONS)).split()
        return meanings[int(status)]
    return "resolved" if math.isfinite(minimum) else "beyond_sweep"


def _printed(analysis, feature: str, minimum: float) -> float:
    """The minimum detectable backlash as the statement prints it: rounded at the leading digit of its bounds'
    half-width (:func:`campaigns.analysis.campaign_analysis.printed_estimate`)."""
    if "minimum_detectable_backlash_ci" not in analysis:
        return minimum
    lower, upper = (float(v) for v in analysis["minimum_detectable_backlash_ci"].sel(feature=feature).values)
    return printed_estimate(minimum, (lower, upper))
