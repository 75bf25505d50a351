"""Campaign reports: HTML and PDF documents generated from the stored campaign files.

Entry point (the ``twin report`` CLI calls it)::

    reports.build_report(results_path, analysis_path=None, out_dir=..., *, accuracy_path=None, generated_at=None)

and, for a test-procedure search (``twin procedure search``, :mod:`reports.procedure_search`)::

    reports.build_search_report(search_path, out_dir, *, generated_at=None)

Data flow: ``results.nc`` (+ ``analysis.nc``, + accuracy data) --:mod:`reports.inputs`-->
loaded data --:mod:`reports.content`--> one :class:`reports.model.Report` -->
:mod:`reports.html` and :mod:`reports.pdf`. See ``docs/reports.md``.
"""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

from reports.errors import ReportError
from reports.procedure_search import build_search_report

__all__ = ["build_report", "build_search_report", "ReportError"]


def build_report(
    results_path: str | Path,
    analysis_path: str | Path | None = None,
    out_dir: str | Path = "report",
    *,
    accuracy_path: str | Path | None = None,
    generated_at: datetime | None = None,
    measured_paths=(),
    against_path: str | Path | None = None,
) -> dict[str, Path]:
    """Write ``report.html`` and ``report.pdf`` of a campaign; no simulation is run.

    Parameters
    ----------
    results_path : str or Path
        The campaign's ``results.nc``.
    analysis_path : str or Path, optional
        Its ``analysis.nc``. Default: ``analysis.nc`` beside the results when it
        exists; otherwise the analysis is computed in memory (nothing is written
        next to the results).
    out_dir : str or Path, default "report"
        Output directory (created if needed).
    accuracy_path : str or Path, optional
        The speed-versus-accuracy study, ``work_precision.nc`` of ``twin accuracy``;
        without it the report says the section is not available.
    measured_paths : iterable of paths, optional
        Measured tests (``twin measure import``): placed in each data set on page 1 and in a section of their own.
    against_path : str or Path, optional
        Another design's ``results.nc``: the report compares this campaign against it (a section and a sentence on
        page 1).
    generated_at : datetime, optional
        Timestamp recorded in the report; default now (UTC). The same inputs and
        timestamp give byte-identical HTML.

    Returns
    -------
    dict
        ``{"html": Path, "pdf": Path}``.

    Raises
    ------
    ReportError
        If an input file is missing, unreadable or inconsistent, the output
        directory cannot be written, or the PDF cannot be compiled.
    """
    # lazy: start-up cost (matplotlib, typst and Jinja2 load only when a report is built)
    from reports.content import build
    from reports.html import render_html
    from reports.inputs import load_inputs
    from reports.pdf import render_pdf

    generated_at = (generated_at or datetime.now(UTC)).astimezone(UTC)
    inputs = load_inputs(results_path, analysis_path, accuracy_path, measured_paths=measured_paths,
                         against_path=against_path)
    out_dir, html = Path(out_dir), Path(out_dir) / "report.html"
    try:  # before the figures are drawn, so an unwritable destination fails at once
        out_dir.mkdir(parents=True, exist_ok=True)
        html.touch()
    except OSError as exc:
        raise ReportError(out_dir, f"cannot write the report there ({exc.strerror or exc})") from exc
    report = build(inputs, generated_at.isoformat(timespec="seconds"))
    html.write_text(render_html(report), encoding="utf-8")
    pdf = render_pdf(report, out_dir / "report.pdf", generated_at)
    return {"html": html, "pdf": pdf}
