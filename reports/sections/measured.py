"""Section "Measured tests": each measured test given to the report, placed in every data set, and the fault size the
campaign's sweep gives it (:mod:`campaigns.workflows.diagnosis`; nothing is computed here)."""

from __future__ import annotations

from campaigns.statistics.defaults import CONFIDENCE
from campaigns.workflows.diagnosis import describe
from reports.builder import Builder
from reports.model import Callout, Paragraph
from reports.units import quantity


def build(b: Builder):
    yield Paragraph(
        "Each measured test was brought in with `twin measure import`: its channels mapped to the twin's signals with "
        "their units and calibration, held at the 1 ms acquisition instants, and every feature computed by the "
        "twin's own code (campaigns.workflows.measured). Here it is placed in each data set's runs (status ok, finite "
        "feature): "
        f"its percentile, and whether it lies inside the {CONFIDENCE * 100:g} % prediction interval of one more run "
        "(mean ± t s √(1 + 1/n), normal theory; p is its two-sided probability). The fault size comes from the "
        "observability sweep: the levels whose intervals lie wholly below or above the measured value bound it, so "
        "the bounds are sweep levels, never values between them (campaigns.workflows.diagnosis).")
    for found in b.inputs.measured:
        yield Callout(f"Measured test {found.test}: {found.verdict}.", "info")
        for note in found.notes:
            yield Paragraph(f"Note: {note}.")
        for feature in found.features:
            unit = b.results[feature].attrs.get("units", "")
            rows = [(p.dataset, describe(p, unit)) for p in found.placements[feature]]
            fault = found.fault.get(feature)
            yield b.table(f"Measured test {found.test}, {feature} = "
                          f"{quantity(found.placements[feature][0].value, unit, 4)}, in each data set"
                          + (f"; fault size: {fault.statement}." if fault is not None else "."),
                          ("Data set", "Where the test lies"), rows)
