"""The sections of a campaign report in their order, with their titles: the one list that the report's builder
(:mod:`reports.content`), its contents in HTML and PDF (read from the built report) and every pointer to a section
(``§6 Observability``, "listed in the Fidelity section") read.

The order puts the results first (the answer, then what it rests on) and the provenance and the long tables of the
campaign's configuration last (issue 42). A section marked ``needs`` appears only when the report was given that input.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Entry:
    """One section: its stable key (the anchor of the HTML and PDF), its title, and the input it needs.

    ``needs`` is the attribute of :class:`reports.inputs.Inputs` that must be given for the section to appear
    (``"comparison"``: ``--against``; ``"measured"``: ``--measured``), empty for a section every report has. A title
    may name the two designs of a comparison (``{design_a}``, ``{design_b}``).
    """

    key: str
    title: str
    needs: str = ""


SECTIONS = (
    Entry("comparison", "{design_b} against {design_a}", needs="comparison"),  # a comparison report opens with it
    Entry("observability", "Observability"),
    Entry("measured", "Measured tests", needs="measured"),  # after the observability its tests are judged by
    Entry("control_robustness", "Control robustness"),
    Entry("distributions", "Feature distributions"),
    Entry("correlations", "Correlations"),
    Entry("scatter", "Feature against the top-ranked parameters"),
    Entry("traces", "Representative traces"),
    Entry("failures", "Failed runs"),
    Entry("fidelity", "Fidelity"),
    Entry("model_form", "Model-form study"),
    Entry("speed", "Speed and accuracy"),
    Entry("summary", "Campaign and provenance"),
)


def title(key: str) -> str:
    """The title of the section ``key`` (a comparison's with its placeholders)."""
    return next(entry.title for entry in SECTIONS if entry.key == key)
