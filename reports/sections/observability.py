"""Section "Observability": the separation of the data sets, then each fault sweep (backlash, preload loss) and its
minimum detectable fault size against its requirement (Table 9.3's 1 µm backlash by default)."""

from __future__ import annotations

import math

import numpy as np

from campaigns.statistics.detection import RESOLUTIONS
from reports import figures
from reports.builder import Builder
from reports.detection import minimum_detectable, sweep_quantity, sweep_views, swept
from reports.model import Callout, Heading, Paragraph
from reports.phrases import NO_VERDICT, tone
from reports.units import number


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
        pairs = len(b.datasets) * (len(b.datasets) - 1)
        if len(blank) == len(b.datasets):
            yield Paragraph(f"Detection probability of {feature} between data sets: not computed, no data set has the "
                            f"runs for a threshold (fewer than {int(floor)} ok runs: {reason})." if floor is not None
                            else f"Detection probability of {feature} between data sets: not computed.")
        elif _says_only(detection, 1.0):
            yield Paragraph(f"Detection probability of {feature} between data sets: every one of the {pairs} pairs of "
                            "distinct data sets reads 1.00 (to two decimals): against each data set's threshold at a "
                            f"{fa:.0%} false-alarm rate, the runs of every other data set are flagged, so the bench "
                            "tells every pair of conditions apart (the matrix is not drawn: it would say nothing "
                            "more).")
        else:
            yield b.figure(
                f"separation-{feature}",
                f"Detection probability of {feature}: runs of the row data set flagged by a threshold set on the "
                f"column data set at a {fa:.0%} false-alarm rate. Cells near 1 mean the bench tells the two "
                "conditions apart; compare the data sets with backlash (rows) against those without (columns)."
                + (f" Blank columns ({', '.join(blank)}): insufficient data for a threshold"
                   + (f", fewer than {int(floor)} ok runs: {reason}." if floor is not None else ".")
                   if blank else ""),
                figures.heatmap(detection, b.datasets, b.datasets, colorbar_label="detection probability [–]",
                                xlabel="reference data set (threshold)", ylabel="tested data set", vmin=0.0,
                                vmax=1.0, cmap="viridis"),
            )
        overlap = a["overlap"].sel(feature=feature).transpose("dataset", "reference").values
        if _says_only(overlap, 0.0):
            yield Paragraph(f"Overlap of the {feature} distributions: every one of the {pairs} pairs of distinct data "
                            "sets reads 0.00 (to two decimals): no two data sets' histograms share any area (the "
                            "matrix is not drawn: it would say nothing more).")
        else:
            yield b.figure(
                f"overlap-{feature}",
                f"Overlap coefficient of the {feature} distributions of each pair of data sets. Low values (dark) "
                "mean well-separated distributions; the diagonal is 1 by definition.",
                figures.heatmap(overlap, b.datasets, b.datasets, colorbar_label="overlap coefficient [–]",
                                xlabel="data set", ylabel="data set", vmin=0.0, vmax=1.0, cmap="magma"),
            )
    for key, view in sweep_views(a):
        yield from _sweep(b, view, key, power)


def _sweep(b: Builder, a, key: str, power: float):
    """One fault sweep (``a``: its view of the analysis, :func:`reports.detection.sweep_views`): the analysis's
    verdicts, the curve's facts and the feature distributions along it."""
    yield Heading(f"Minimum detectable {swept(a)[0]}")
    # the verdict is the analysis's sentence, verbatim (with its bounds and n); the report adds only facts of the curve
    yield from _verdicts(b, a)
    if "sweep_point" not in a.dims or "requirement_verdict" not in a:
        yield Callout("Not available: the campaign spec has no observability sweep ([observability] sweep), so the "
                      "minimum detectable fault size cannot be compared with a requirement.")
        return
    sweep = [str(s) for s in a["sweep_point"].values]
    quantity_name, levels, scale, shown = sweep_quantity(a)
    yield Paragraph(
        f"Along the sweep {', '.join(sweep)} (data sets differing only in {quantity_name}: "
        f"{', '.join(number(x * scale) for x in levels)} {shown}), the minimum detectable {quantity_name} is where "
        f"the detection probability against the reference reaches {power:.0%}. Between two sweep levels the runs say "
        "nothing, so the finding is the pair of adjacent levels around that crossing; a value between them is given "
        "only where the sweep resolves it (its bootstrap bounds hold a sweep level inside), rounded to the precision "
        "of those bounds. Each sentence above is the analysis's, verbatim; the detection probability along the sweep "
        "is the figure on page 1."
    )
    probability = {f: a["sweep_detection_probability"].sel(feature=f).values for f in b.features}
    minimum = minimum_detectable(quantity_name)
    for feature in b.features:
        if _resolution(a, feature, float(a[minimum].sel(feature=feature)) if minimum in a else math.nan) == (
                "beyond_sweep"):
            yield Callout(f"{feature}: the detection probability never reaches {power:.0%} along the sweep.", "info")
    if (levels > 0).any():
        smallest = int(np.flatnonzero(levels == levels[levels > 0].min())[0])
        bounded = [f for f in b.features if probability[f][smallest] >= power]
        if bounded:
            yield Paragraph(
                f"For {', '.join(bounded)} the smallest non-zero level of the sweep "
                f"({number(levels[smallest] * scale)} {shown}) is already detected, so the minimum detectable "
                f"{quantity_name} lies between 0 and that level, and no value inside is resolved. Add data sets with "
                f"{quantity_name} near the requirement to resolve it."
            )
    for feature in b.measured:
        yield b.figure(
            f"sweep-distribution-{feature}{key.replace('_', '-')}",
            f"{feature} for the sweep data sets (Fig. 9.10 style). The smallest {quantity_name} whose distribution "
            "clears the reference's is what the bench can observe.",
            figures.distributions(b.distribution_panels(feature, sweep)),
        )


def _verdicts(b: Builder, a):
    """One callout per feature with the analysis's requirement statement along the sweep ``a`` is the view of,
    verbatim."""
    if "requirement_statement" not in a or "requirement_verdict" not in a:
        yield Callout(NO_VERDICT, "info")
        return
    for feature in [str(f) for f in a["feature"].values]:
        statement = str(a["requirement_statement"].sel(feature=feature).item())
        verdict = str(a["requirement_verdict"].sel(feature=feature).item())
        yield Callout(f"{feature}: {statement}", tone(verdict))
        if "within_unit_requirement_statement" in a:  # a within-unit campaign: the unit's own verdict beside it
            statement = str(a["within_unit_requirement_statement"].sel(feature=feature).item())
            verdict = str(a["within_unit_requirement_verdict"].sel(feature=feature).item())
            yield Callout(f"{feature} within unit: {statement}", tone(verdict))


def _resolution(analysis, feature: str, minimum: float) -> str:
    """How far the sweep resolves the feature's minimum detectable backlash, as the analysis flagged it
    (``minimum_detectable_status``); an older analysis without the flag: resolved when it states a value."""
    if "minimum_detectable_status" in analysis:
        status = analysis["minimum_detectable_status"].sel(feature=feature)
        meanings = status.attrs.get("flag_meanings", " ".join(RESOLUTIONS)).split()
        return meanings[int(status)]
    return "resolved" if math.isfinite(minimum) else "beyond_sweep"


def _says_only(matrix: np.ndarray, value: float) -> bool:
    """Whether every cell off the diagonal is finite and shows ``value`` as the heat map writes it (two decimals): a
    matrix that says one number says it better in a sentence (issue 42: 7 x 7 cells of 1.00)."""
    off = matrix[~np.eye(len(matrix), dtype=bool)]
    return off.size > 0 and bool(np.isfinite(off).all()) and bool((np.round(off, 2) == value).all())
