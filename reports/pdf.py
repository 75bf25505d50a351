"""PDF rendering of a report with typst (a pip-installable engine, no system packages).

The report model is written as JSON next to the figure files in a temporary
directory; the fixed template ``templates/report.typ`` reads it and lays out a
title page, a table of contents and the numbered sections, figures and tables.
Passing data rather than generating typst markup means no text of the report
ever needs escaping.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from dataclasses import asdict
from datetime import datetime
from importlib import resources
from pathlib import Path

from reports.errors import ReportError
from reports.model import Callout, Figure, Report


def _document(report: Report, figure_names: dict[int, str]) -> dict:
    """The report as JSON-ready data; figures refer to their PNG files, links carry their text."""

    def block_data(block) -> dict:
        if isinstance(block, Figure):
            return {"type": "Figure", "number": block.number, "caption": block.caption,
                    "path": figure_names[block.number]}
        data = {"type": type(block).__name__, **asdict(block)}
        if isinstance(block, Callout) and block.link:
            data["link_text"] = report.link_text(block.link)
        return data

    return {
        "title": report.title,
        "summary_title": report.summary_title,
        "contents": report.contents,
        "landscape": report.landscape,
        "subtitle": report.subtitle,
        "generated_at": report.generated_at,
        "facts": [list(f) for f in report.facts],
        "executive": [block_data(b) for b in report.executive],
        "sections": [{"key": s.key, "title": s.title, "blocks": [block_data(b) for b in s.blocks]}
                     for s in report.sections],
    }


def render_pdf(report: Report, path: str | Path, timestamp: datetime) -> Path:
    """Compile the report to a PDF file.

    Parameters
    ----------
    report : Report
    path : str or Path
        The PDF to write.
    timestamp : datetime
        The document date recorded in the PDF (the report's generation time).

    Returns
    -------
    Path

    Raises
    ------
    ReportError
        If typst is not installed or the compilation fails.
    """
    try:
        import typst
    except ImportError as exc:
        raise ReportError(path, "cannot write the PDF: the typst package is not installed "
                                "(pip install 'benchtwin[report]')") from exc
    path = Path(path)
    with tempfile.TemporaryDirectory(prefix="benchtwin-report-") as tmp:
        root = Path(tmp)
        names = {}
        for blocks in [report.executive] + [section.blocks for section in report.sections]:
            for block in blocks:
                if isinstance(block, Figure):
                    names[block.number] = f"figure-{block.number}.png"
                    (root / names[block.number]).write_bytes(block.png)
        (root / "report.json").write_text(json.dumps(_document(report, names), ensure_ascii=False))
        with resources.as_file(resources.files("reports") / "templates" / "report.typ") as template:
            shutil.copyfile(template, root / "main.typ")
        try:
            pdf = typst.compile(str(root / "main.typ"), root=str(root), ignore_system_fonts=True,
                                timestamp=int(timestamp.timestamp()))
        except Exception as exc:  # typst raises its own error types with the template's diagnostics
            raise ReportError(path, f"typst could not compile the report: {exc}") from exc
    path.write_bytes(pdf)
    return path
