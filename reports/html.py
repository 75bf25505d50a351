"""HTML rendering of a report: one self-contained file (inline CSS, figures as base64 PNG)."""

from __future__ import annotations

import base64

import jinja2
import markupsafe

from reports.model import Report

_ENVIRONMENT = jinja2.Environment(
    loader=jinja2.PackageLoader("reports", "templates"),
    autoescape=True,
    trim_blocks=True,
    lstrip_blocks=True,
    keep_trailing_newline=True,
)
_ENVIRONMENT.filters["base64"] = lambda data: base64.b64encode(data).decode("ascii")
# identifiers such as sensors.load_cell_offset_tempco may break after an underscore
_ENVIRONMENT.filters["breakable"] = lambda text: markupsafe.escape(text).replace("_", markupsafe.Markup("_<wbr>"))
_ENVIRONMENT.tests["kind"] = lambda block, name: type(block).__name__ == name


def render_html(report: Report) -> str:
    """The report as one HTML document that needs no network access.

    Parameters
    ----------
    report : Report

    Returns
    -------
    str
    """
    return _ENVIRONMENT.get_template("report.html.j2").render(report=report)
