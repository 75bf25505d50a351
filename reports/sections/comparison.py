"""Section "A against B": this campaign (design A) against another design's campaign (B), from
:mod:`campaigns.workflows.design_comparison` (nothing is computed here)."""

from __future__ import annotations

from campaigns.statistics.defaults import CONFIDENCE
from campaigns.workflows.design_comparison import MIN_RUNS, describe_shift, failure_text
from reports.builder import Builder
from reports.model import Callout, Paragraph
from reports.phrases import feature_words, plain_name, tone


def _feature(b: Builder, feature: str) -> str:
    """A feature in the words of page 1; its true-signal twin as the same feature with ideal sensors (glossary)."""
    measured = feature.removesuffix("_true")
    if measured != feature and measured in b.results:
        return f"{feature_words(b.results, measured)}, ideal sensors"
    return feature_words(b.results, feature)


def _requirement(b: Builder, what: str) -> str:
    """A compared verdict's subject with its feature in words (``backlash_feature: minimum detectable ...``)."""
    feature, sep, rest = what.partition(": ")
    return f"{_feature(b, feature)}: {rest}" if sep and feature in b.results else what


def build(b: Builder):
    c = b.inputs.comparison
    yield Callout(c.sentence, "info")
    yield Paragraph(
        f"Pairing: {'paired run by run (common random numbers)' if c.paired else 'unpaired'}: {c.pairing}. "
        + (f"The designs differ in: {', '.join(plain_name(p) for p in c.design_changes)}. " if c.design_changes
           else "The two specs resolve every tolerance alike. ")
        + f"Every difference is {c.name_b} − {c.name_a}, with its {CONFIDENCE * 100:g} % interval: the mean shift "
          "by Student's t (of the paired differences, or Welch's when unpaired), the shift of the standard deviation "
          "by a percentile bootstrap; a shift is resolved when its interval excludes 0 "
          "(campaigns.workflows.design_comparison).")
    yield Paragraph(f"Every difference of the two specs ({c.name_a} → {c.name_b}): " + "; ".join(c.spec_changes) + "."
                    if c.spec_changes else "The two specs differ in their name and description only.")
    if failures := failure_text(c, detail=True):
        yield Paragraph(f"{failures[0].upper()}{failures[1:]}. A shift with fewer than {MIN_RUNS} runs (pairs) ok on "
                        "a side has no interval: it could not be made (–).")
    rows = [(s.dataset, _feature(b, s.feature), describe_shift(s.mean, s.unit), describe_shift(s.sd, s.unit),
             f"{s.n_b} / {s.n_a}", "yes" if s.mean.resolved else "no" if s.made else "not made") for s in c.shifts]
    yield b.table(f"Each feature's distribution, {c.name_b} against {c.name_a}, per data set.",
                  ("Data set", "Feature", "Mean shift", "Standard-deviation shift", f"Runs {c.name_b} / {c.name_a}",
                   "Mean shift resolved"), rows, [not s.mean.resolved for s in c.shifts])
    if not c.verdicts:
        yield Paragraph("Verdicts: not compared (an analysis.nc is missing beside one of the results).")
        return
    yield b.table(f"Each verdict in {c.name_b} and in {c.name_a}, with the statements they rest on.",
                  ("Requirement", c.name_b, c.name_a, "Changed"),
                  [(_requirement(b, v.what), v.statement_b, v.statement_a, "yes" if v.changed else "no")
                   for v in c.verdicts],
                  [not v.changed for v in c.verdicts])
    for v in (v for v in c.verdicts if v.changed):
        yield Callout(f"{_requirement(b, v.what)}: {v.verdict_a} in {c.name_a}, {v.verdict_b} in {c.name_b}.",
                      tone(v.verdict_b))
