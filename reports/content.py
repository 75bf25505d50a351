"""The report's content: sections, tables, figures and captions from the stored data.

:func:`build` turns the loaded inputs (:mod:`reports.inputs`) into one
:class:`reports.model.Report`: the executive summary and the sections, one module each in
:mod:`reports.sections`, in the order and with the titles of :mod:`reports.outline` (shared state and chart
limits: :mod:`reports.builder`). Every number shown is read from
``results.nc`` or ``analysis.nc`` (or the accuracy data set); nothing is simulated. Figures
and tables are numbered in the order they appear, which both renderers keep.
"""

from __future__ import annotations

from reports.builder import Builder
from reports.inputs import Inputs
from reports.model import Report, Section
from reports.outline import SECTIONS
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

#: The function that builds each section of :data:`reports.outline.SECTIONS`, by key.
BUILDERS = {
    "comparison": comparison.build,
    "observability": observability.build,
    "measured": measured.build,
    "control_robustness": control_robustness.build,
    "distributions": distributions.build,
    "correlations": correlations.build,
    "scatter": scatter.build,
    "traces": traces.build,
    "failures": failures.build,
    "fidelity": fidelity.build,
    "model_form": model_form.build,
    "speed": speed.build,
    "summary": summary.build,
}
#: The titles of the sections every campaign report has, in their order.
SECTION_TITLES = {entry.key: entry.title for entry in SECTIONS if not entry.needs}


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
    names = ({"design_a": inputs.comparison.name_a, "design_b": inputs.comparison.name_b}
             if inputs.comparison is not None else {})
    sections = tuple(Section(entry.key, entry.title.format(**names), tuple(BUILDERS[entry.key](b)))
                     for entry in SECTIONS if not entry.needs or getattr(inputs, entry.needs))
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
