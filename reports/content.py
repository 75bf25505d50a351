"""The report's content: sections, tables, figures and captions from the stored data.

:func:`build` turns the loaded inputs (:mod:`reports.inputs`) into one
:class:`reports.model.Report`: the executive summary and the sections, one module each in
:mod:`reports.sections` (shared state and chart limits: :mod:`reports.builder`). Every number shown is read from
``results.nc`` or ``analysis.nc`` (or the accuracy data set); nothing is simulated. Figures
and tables are numbered in the order they appear, which both renderers keep.
"""

from __future__ import annotations

from reports.builder import Builder
from reports.inputs import Inputs
from reports.model import Report, Section
from reports.sections import (
    comparison,
    control_robustness,
    correlations,
    distributions,
    executive,
    failures,
    fidelity,
    measured,
    model_form,
    observability,
    scatter,
    speed,
    summary,
    traces,
)

#: The sections in their order: the results first (the answer, then what it rests on), provenance and the long
#: tables of the campaign's configuration last (issue 42).
SECTION_TITLES = {
    "observability": "Observability",
    "control_robustness": control_robustness.TITLE,
    "distributions": "Feature distributions",
    "correlations": "Correlations",
    "scatter": "Feature against the top-ranked parameters",
    "traces": "Representative traces",
    "failures": "Failed runs",
    "fidelity": "Fidelity",
    "model_form": model_form.TITLE,
    "speed": "Speed and accuracy",
    "summary": "Campaign and provenance",
}


def build(inputs: Inputs, generated_at: str) -> Report:
    """The report model of a campaign.

    Parameters
    ----------
    inputs : Inputs
        The loaded results, analysis and optional accuracy data.
    generated_at : str
        Timestamp recorded in the report.

    Returns
    -------
    Report
    """
    b = Builder(inputs)
    page_one = model_form.page_one(b, executive.build(b))  # first, so its data-set table is Table 1
    # a comparison report opens with the comparison; measured tests follow the observability they are judged by
    optional_first = [("comparison", comparison.build)] if inputs.comparison is not None else []
    optional_measured = [("measured", measured.build)] if inputs.measured else []
    titles = {**SECTION_TITLES, "measured": measured.TITLE,
              **({"comparison": comparison.title(b)} if inputs.comparison is not None else {})}
    sections = tuple(
        Section(key, titles[key], tuple(make(b)))
        for key, make in (
            *optional_first,
            ("observability", observability.build),
            *optional_measured,
            ("control_robustness", control_robustness.build),
            ("distributions", distributions.build),
            ("correlations", correlations.build),
            ("scatter", scatter.build),
            ("traces", traces.build),
            ("failures", failures.build),
            ("fidelity", fidelity.build),
            ("model_form", model_form.build),
            ("speed", speed.build),
            ("summary", summary.build),
        )
    )
    status = b.results["status"].values
    facts = (
        ("Campaign", f"{b.spec['name']}: {b.spec.get('description') or '–'}"),
        ("Runs", f"{status.size} ({int((status == 'ok').sum())} succeeded, {int((status != 'ok').sum())} failed)"),
        ("Spec hash", b.results.attrs.get("spec_hash", "–")),
        ("Results created", b.results.attrs.get("date_created", "–")),
        ("Report generated", generated_at),
    )
    return Report(
        title=f"Monte Carlo campaign report: {b.spec['name']}",
        subtitle="BenchTwin, ball-screw test bench digital twin (Bertolino 2020, Sec. 9.4)",
        generated_at=generated_at,
        facts=facts,
        executive=page_one,
        sections=sections,
    )
