"""The report of a test-procedure search (``search.nc`` of ``twin procedure search``): HTML, PDF and the chart.

Entry point::

    reports.build_search_report(search_path, out_dir, *, generated_at=None)

Page 1 gives the search's question (the fault and its requirement), its statement, verbatim, in the tone of its
verdict, and the ranked table of the candidate procedures; then the screening estimate against test duration (the
Pareto front) and what re-runs each candidate. Every number is read from ``search.nc``; nothing is simulated or
recomputed. The document is a :class:`reports.model.Report`, rendered by :mod:`reports.html` and :mod:`reports.pdf`
like a campaign report (the file's text is escaped in HTML and passed to typst as data).
"""

from __future__ import annotations

import json
import math
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from campaigns.analysis.vocabulary import SWEEP_QUANTITIES
from reports.errors import ReportError
from reports.model import Callout, Code, Figure, Heading, Paragraph, Report, Section, Table
from reports.phrases import decision, tone
from reports.units import display_scale, estimate_with_interval, quantity, quantity_range

__all__ = ["build_search_report"]

#: What ``search.nc`` must hold (the contract of ``twin procedure search``), besides one ``knob_<name>`` per knob.
REQUIRED_VARIABLES = (
    "test_duration", "reference", "screening_estimate", "screening_low", "screening_high", "screening_note",
    "best_feature", "score", "score_low", "score_high", "round_reached", "finalist", "within_unit_low",
    "within_unit_high", "within_unit_verdict", "within_unit_statement", "pareto", "rank", "difference_to_best",
    "difference_low", "difference_high", "evidence", "rerun",
)
REQUIRED_ATTRIBUTES = ("name", "fault", "fault_unit", "requirement", "statement", "verdict", "best", "knobs",
                       "search_spec", "plan")
#: The faults a search minimises, in words.
FAULT_WORDS = {"backlash": "backlash growth", "preload_loss": "preload loss"}
#: Display unit of each fault unit (factor from SI, symbol): backlash in µm, preload loss in N, the same in every row
#: of a column and on the chart, so the candidates compare at a glance; the sweeps' own table
#: (campaigns.analysis.campaign_analysis).
FAULT_DISPLAY = {unit: (scale, shown) for _, unit, scale, shown in SWEEP_QUANTITIES.values()}
#: The reference procedure in words, when search.nc does not say it (attribute ``reference_procedure``).
REFERENCE_WORDS = "the base scene's own procedure"
#: Ratio of the largest to the smallest value above which the chart's value axis is logarithmic.
LOG_SPAN = 30.0
#: Shown for a value the file does not resolve (NaN) or a cell that does not apply.
NONE = "—"

CHART_NAME = "pareto.png"


def build_search_report(search_path: str | Path, out_dir: str | Path, *,
                        generated_at: datetime | None = None) -> dict[str, Path]:
    """Write ``search_report.html``, ``search_report.pdf`` and ``pareto.png`` of a procedure search.

    Parameters
    ----------
    search_path : str or Path
        The search's ``search.nc`` (``twin procedure search``).
    out_dir : str or Path
        Output directory (created if needed).
    generated_at : datetime, optional
        Timestamp recorded in the report; default now (UTC). The same file and timestamp give byte-identical HTML.

    Returns
    -------
    dict
        ``{"html": Path, "pdf": Path, "chart": Path}``.

    Raises
    ------
    ReportError
        If the file is missing, unreadable or lacks what the report needs (naming the file and what is missing),
        the output directory cannot be written, or the PDF cannot be compiled.
    """
    # lazy: start-up cost (matplotlib, typst and Jinja2 load only when a report is built)
    from reports.html import render_html
    from reports.pdf import render_pdf

    generated_at = (generated_at or datetime.now(UTC)).astimezone(UTC)
    search_path = Path(search_path)
    search = load_search(search_path)
    out_dir = Path(out_dir)
    html = out_dir / "search_report.html"
    try:  # before the chart is drawn, so an unwritable destination fails at once
        out_dir.mkdir(parents=True, exist_ok=True)
        html.touch()
    except OSError as exc:
        raise ReportError(out_dir, f"cannot write the report there ({exc.strerror or exc})") from exc
    report = build(search, search_path, generated_at.isoformat(timespec="seconds"))
    chart = out_dir / CHART_NAME
    chart.write_bytes(next(b for s in report.sections for b in s.blocks if isinstance(b, Figure)).png)
    html.write_text(render_html(report), encoding="utf-8")
    pdf = render_pdf(report, out_dir / "search_report.pdf", generated_at)
    return {"html": html, "pdf": pdf, "chart": chart}


def load_search(path: Path):
    """``search.nc`` loaded into memory and checked against the contract.

    Raises
    ------
    ReportError
        Naming the file and every variable or attribute that is missing or malformed.
    """
    from reports.inputs import open_netcdf  # lazy: xarray loads only when a report is built

    search = open_netcdf(path, "procedure-search")
    problems = []
    if "candidate" not in search.dims:
        problems.append("dimension 'candidate' missing")
    knobs = []
    try:
        knobs = json.loads(search.attrs["knobs"])
        if not isinstance(knobs, list) or not all(isinstance(k, str) for k in knobs):
            problems.append("attribute 'knobs' is not a JSON list of knob names")
            knobs = []
    except KeyError:
        pass  # reported with the other attributes
    except (TypeError, json.JSONDecodeError) as exc:
        problems.append(f"attribute 'knobs' is not valid JSON ({exc})")
    missing = [n for n in REQUIRED_VARIABLES + tuple(f"knob_{k}" for k in knobs) if n not in search.variables]
    if missing:
        problems.append(f"variable(s) {', '.join(repr(n) for n in missing)} missing")
    absent = [a for a in REQUIRED_ATTRIBUTES if a not in search.attrs]
    if absent:
        problems.append(f"attribute(s) {', '.join(repr(a) for a in absent)} missing")
    if not missing and "candidate" in search.dims:
        if "feature" not in search.dims:
            problems.append("dimension 'feature' missing")
        wrong = [n for n in REQUIRED_VARIABLES + tuple(f"knob_{k}" for k in knobs)
                 if search[n].dims[:1] != ("candidate",)]
        if wrong:
            problems.append(f"variable(s) {', '.join(repr(n) for n in wrong)} not along 'candidate'")
    if not absent and search.attrs.get("fault_unit") not in FAULT_DISPLAY:
        problems.append(f"attribute 'fault_unit' is {search.attrs['fault_unit']!r}, not 'm' or 'N'")
    if not absent and not problems and str(search.attrs["best"]) not in [str(c) for c in search["candidate"].values]:
        problems.append(f"attribute 'best' names {search.attrs['best']!r}, which is not a candidate")
    if problems:
        raise ReportError(path, "not a procedure-search file (search.nc of `twin procedure search`): "
                                + "; ".join(problems))
    return search


# --- formatting ---

def _finite(*values) -> bool:
    return all(v is not None and math.isfinite(float(v)) for v in values)


def plain(value: float, digits: int = 3) -> str:
    """``value`` to ``digits`` significant digits without an exponent (``3600``, ``0.25``); NaN as an em dash."""
    if not _finite(value):
        return NONE
    value = float(value)
    if value == 0:
        return "0"
    rounded = round(value, digits - 1 - math.floor(math.log10(abs(value))))
    return f"{rounded + 0.0:.12g}"


def _display(unit: str) -> tuple[float, str]:
    """The fault's display factor and unit; the unit is passed on to :mod:`reports.units` with values already scaled
    (``µm`` takes no further prefix there)."""
    return FAULT_DISPLAY.get(unit, (1.0, unit))


def interval(estimate: float, low: float, high: float, unit: str, signed: bool = False) -> str:
    """An estimate with its 95 % bounds at the precision they resolve (:func:`campaigns.units.estimate_with_interval`)
    in the fault's display unit; ``—`` when any of the three is not resolved. A size (``signed`` false) reads without
    a ``+``."""
    if not _finite(estimate, low, high):
        return NONE
    factor, shown = _display(unit)
    text = estimate_with_interval(float(estimate) * factor, float(low) * factor, float(high) * factor, shown)
    return text if signed else text.removeprefix("+")


def amount(value: float, unit: str) -> str:
    """One value of the fault in its display unit (``1 µm``, ``200 N``)."""
    factor, shown = _display(unit)
    return quantity(float(value) * factor, shown) if _finite(value) else NONE


def bracket(low: float, high: float, unit: str) -> str:
    """A within-unit bracket between two levels: ``1–2 µm``; ``> 4 µm`` above the largest level; ``—`` for none."""
    factor, shown = _display(unit)
    if _finite(low) and _finite(high):
        return quantity_range(float(low) * factor, float(high) * factor, shown)
    if _finite(low) and float(high) == math.inf:
        return f"> {amount(low, unit)}"
    if _finite(high) and not _finite(low):
        return f"< {amount(high, unit)}"
    return NONE


def _text(value) -> str:
    return "" if value is None else str(value.item() if hasattr(value, "item") else value)


class _Search:
    """The loaded file in the report's terms: per-candidate values in rank order."""

    def __init__(self, search, path: Path):
        self.ds, self.path = search, path
        self.attrs = search.attrs
        self.knobs = json.loads(search.attrs["knobs"])
        self.unit = str(search.attrs["fault_unit"])
        self.fault = FAULT_WORDS.get(str(search.attrs["fault"]), str(search.attrs["fault"]).replace("_", " "))
        self.requirement = float(search.attrs["requirement"])
        ranks = np.asarray(search["rank"].values, dtype=float)
        ids = [str(c) for c in search["candidate"].values]
        self.order = sorted(range(len(ids)), key=lambda i: (ranks[i] if math.isfinite(ranks[i]) else math.inf, ids[i]))
        self.ids = ids
        self.best = str(search.attrs["best"])
        self.reference_words = str(search.attrs.get("reference_procedure", REFERENCE_WORDS))

    def value(self, name: str, i: int):
        return self.ds[name].values[i]

    def is_reference(self, i: int) -> bool:
        return int(self.value("reference", i)) == 1

    def knob_columns(self) -> list[tuple[str, str, list[str]]]:
        """Per knob: its name in words, its display unit (``""`` for none) and its cells, one per candidate (file
        order), all in the one display unit of the column."""
        columns = []
        for knob in self.knobs:
            var = self.ds[f"knob_{knob}"]
            name = knob.replace("_", " ")
            if var.dtype.kind in "fiu":
                values = var.values.astype(float)
                factor, shown = display_scale(str(var.attrs.get("units", "")), values)
                columns.append((name, "" if shown == "–" else shown, [plain(v * factor) for v in values]))
            else:
                columns.append((name, "", [_text(v) or NONE for v in var.values]))
        return columns

    def score_note(self, i: int) -> str:
        """Why a candidate's score is not resolved: its best feature's screening note, else the first note given."""
        notes = self.ds["screening_note"].isel(candidate=i)
        feature = _text(self.value("best_feature", i))
        if feature and "feature" in notes.dims and feature in [str(f) for f in notes["feature"].values]:
            note = _text(notes.sel(feature=feature).values)
            if note:
                return note
        return next((n for n in (_text(v) for v in np.ravel(notes.values)) if n), "")


def build(search, path: Path, generated_at: str) -> Report:
    """The report model of a procedure search."""
    s = _Search(search, path)
    requirement = amount(s.requirement, s.unit)
    source = _text(s.attrs.get("requirement_source", ""))
    verdict = _text(s.attrs["verdict"])
    best = s.ids.index(s.best) if s.best in s.ids else s.order[0]
    reference = [i for i in s.order if s.is_reference(i)]
    knob_columns = s.knob_columns()

    statement = _text(s.attrs["statement"])
    # the statement verbatim, after the decision (and the verdict, unless the statement starts with it)
    decided = decision(verdict) + ("" if statement.startswith(verdict) else f" ({verdict})")
    summary = [Callout(f"{decided} — {statement}", tone(verdict))]
    procedure = "; ".join(f"{name} {cells[best]}" + (f" {unit}" if unit and cells[best] != NONE else "")
                          for name, unit, cells in knob_columns)
    summary.append(Paragraph(
        f"Best procedure: {s.best} (rank {plain(s.value('rank', best))}): {procedure}; test duration "
        f"{plain(s.value('test_duration', best))} s. Its screening estimate ({_text(s.value('best_feature', best))}): "
        f"{interval(s.value('score', best), s.value('score_low', best), s.value('score_high', best), s.unit)}."))
    if reference:
        ref = reference[0]
        summary.append(Paragraph(
            f"Reference: {s.ids[ref]}, {s.reference_words} (marked “reference” in the table), rank "
            f"{plain(s.value('rank', ref))}."))
    summary.append(ranked_table(s, knob_columns))

    sections = (
        Section("chart", "Screening estimate against test duration", (chart_figure(s, best, reference),)),
        Section("reproduction", "Reproduction", tuple(reproduction(s))),
    )
    name = _text(s.attrs["name"])
    facts = (
        ("Search", f"{name}: {_text(s.attrs.get('description', '')) or '–'}"),
        ("Candidates", f"{len(s.ids)}; screened on {plain(s.attrs.get('units', math.nan))} unit(s) × "
                       f"{plain(s.attrs.get('repeats', math.nan))} repeat(s) at "
                       f"{amount(float(s.attrs.get('screening_level', math.nan)), s.unit)}, root seed "
                       f"{_text(s.attrs.get('root_seed', '–'))}"),
        ("Report generated", generated_at),
    )
    return Report(
        title=f"Test-procedure search: {name}",
        subtitle=f"Fault: {s.fault}; requirement {requirement}" + (f" ({source})" if source else "")
                 + ". BenchTwin, ball-screw test bench digital twin.",
        generated_at=generated_at,
        facts=facts,
        executive=tuple(summary),
        sections=sections,
        summary_title="Result",
        contents=False,
        landscape=True,
        source=f"the stored search file {path.name}",
    )


def ranked_table(s: _Search, knob_columns) -> Table:
    """Table 1: one row per candidate in rank order."""
    header = ("rank", "candidate", *(f"{name} [{unit}]" if unit else name for name, unit, _ in knob_columns),
              "test duration [s]", "best feature",
              "screening estimate (95 % interval)", "within-unit bracket", "within-unit verdict", "Pareto front",
              "difference to best (95 % interval)")
    rows = []
    for i in s.order:
        finalist = int(s.value("finalist", i)) == 1
        score = interval(s.value("score", i), s.value("score_low", i), s.value("score_high", i), s.unit)
        if score == NONE and (note := s.score_note(i)):
            score = f"{NONE} ({note})"
        rows.append((
            plain(s.value("rank", i)),
            s.ids[i] + (" (reference)" if s.is_reference(i) else ""),
            *(cells[i] for _, _, cells in knob_columns),
            plain(s.value("test_duration", i)),
            _text(s.value("best_feature", i)) or NONE,
            score,
            bracket(s.value("within_unit_low", i), s.value("within_unit_high", i), s.unit) if finalist else NONE,
            (_text(s.value("within_unit_verdict", i)) or NONE) if finalist else NONE,
            "yes" if int(s.value("pareto", i)) == 1 else "no",
            interval(s.value("difference_to_best", i), s.value("difference_low", i), s.value("difference_high", i),
                     s.unit, signed=True),
        ))
    caption = (f"The candidate procedures ranked by their screening estimate of the detectable {s.fault} (1 = best); "
               f"“(reference)”: {s.reference_words}. The within-unit bracket (the 95th-percentile unit's detectable "
               "growth between two levels of the finalist's full campaign) and its verdict are given for finalists "
               f"only ({NONE} otherwise). The difference to the best is paired over the same units; {NONE}: not "
               "resolved.")
    widths = (0.45, 1.0, *(1.0 for _ in knob_columns), 0.85, 1.25, 1.9, 1.0, 0.9, 0.6, 1.9)
    return Table(1, caption, header, tuple(rows), widths=widths)


def chart_figure(s: _Search, best: int, reference: list[int]) -> Figure:
    """Figure 1: screening estimate (95 % interval) against test duration, the Pareto front as a step line."""
    from reports import figures  # lazy: matplotlib loads only when a report is built

    factor, shown = _display(s.unit)
    values = {n: np.asarray(s.ds[n].values, dtype=float) for n in ("test_duration", "score", "score_low",
                                                                     "score_high")}
    drawn = np.concatenate([values[n] for n in ("score", "score_low", "score_high")] + [[s.requirement]]) * factor
    drawn = drawn[np.isfinite(drawn)]
    log = bool(drawn.size and drawn.min() > 0 and drawn.max() / drawn.min() > LOG_SPAN)
    durations = values["test_duration"][np.isfinite(values["test_duration"])]
    log_x = bool(durations.size and durations.min() > 0 and durations.max() / durations.min() > LOG_SPAN)
    labels: dict[int, str] = {}
    for i in reference:
        labels[i] = f"{s.ids[i]}: reference"
    labels[best] = f"{s.ids[best]}: best" if best not in labels else f"{s.ids[best]}: reference and best"
    front = [i for i in range(len(s.ids)) if int(s.value("pareto", i)) == 1]
    png = figures.duration_tradeoff(
        values["test_duration"], values["score"] * factor, values["score_low"] * factor,
        values["score_high"] * factor, front=front, labels=labels,
        requirement=(f"requirement {amount(s.requirement, s.unit)}", s.requirement * factor),
        xlabel="test duration [s]", ylabel=f"detectable {s.fault} [{shown}]", log=log, log_x=log_x)
    unresolved = [s.ids[i] for i in s.order if not _finite(values["test_duration"][i], values["score"][i])]
    caption = (f"Screening estimate of the detectable {s.fault} (point; bar: 95 % interval) against test duration, "
               "one point per candidate procedure; the Pareto-front candidates (none shorter and better) are joined "
               f"by a step line; dashed: the requirement ({amount(s.requirement, s.unit)})."
               + (" Logarithmic value axis (the values span more than 30×)." if log else "")
               + (" Logarithmic duration axis (the durations span more than 30×)." if log_x else "")
               + (f" Not drawn (no resolved estimate): {', '.join(unresolved)}." if unresolved else ""))
    return Figure(1, "chart", caption, png)


def reproduction(s: _Search):
    """What re-runs each candidate, the search spec and the plan, verbatim."""
    yield Paragraph("Each candidate's campaign directory (relative to the search directory) and the command that "
                    "re-runs it, in rank order:")
    lines = []
    for i in s.order:
        tags = [f"rank {plain(s.value('rank', i))}"] + (["reference"] if s.is_reference(i) else []) \
            + (["finalist"] if int(s.value("finalist", i)) == 1 else [])
        lines += [f"# {s.ids[i]} ({', '.join(tags)}): evidence {_text(s.value('evidence', i))}",
                  _text(s.value("rerun", i)), ""]
    yield Code("\n".join(lines).rstrip("\n"))
    yield Heading("Knobs")
    yield Table(2, "The knobs of the search in the order of the ranked table, with the unit the file stores them in.",
                ("knob", "meaning", "unit"),
                tuple((k, _text(s.ds[f"knob_{k}"].attrs.get("long_name", "")) or NONE,
                       _text(s.ds[f"knob_{k}"].attrs.get("units", "")) or NONE) for k in s.knobs))
    yield Heading("Search spec")
    yield Code(_text(s.attrs["search_spec"]).rstrip("\n"))
    yield Heading("Plan")
    yield Code(_text(s.attrs["plan"]).rstrip("\n"))
    yield Heading("Provenance")
    yield Table(3, "The search's global attributes.", ("attribute", "value"),
                tuple((key, amount(float(s.attrs[key]), s.unit) if key in ("requirement", "screening_level")
                       else _text(s.attrs[key]))
                      for key in ("root_seed", "units", "repeats", "requirement", "requirement_source",
                                  "screening_level", "Conventions", "history") if key in s.attrs))
