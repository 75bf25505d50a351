"""The report model: what a report says, independent of how it is rendered.

:mod:`reports.content` builds one :class:`Report` from the stored campaign
files; :mod:`reports.html` and :mod:`reports.pdf` render the same model, so the
two documents carry the same sections, tables, figures and numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Paragraph:
    """Plain text (no markup: renderers escape it)."""

    text: str


@dataclass(frozen=True)
class Callout:
    """A short verdict set apart from the text.

    ``tone`` is ``"good"`` (a requirement met), ``"bad"`` (not met, or failures),
    ``"info"`` (something missing or to keep in mind) or ``"muted"`` (insufficient data).
    ``link`` is the key of the section that holds the details (the executive summary
    points every finding to its section); empty for none.
    """

    text: str
    tone: str = "info"
    link: str = ""


@dataclass(frozen=True)
class Heading:
    """A subsection heading (the section is level 1)."""

    text: str


@dataclass(frozen=True)
class Code:
    """Preformatted text shown in a monospace font with its line breaks kept (a command, a spec file); no markup:
    renderers escape it."""

    text: str


@dataclass(frozen=True)
class Table:
    """A numbered table; every cell is already formatted text.

    ``muted`` flags rows whose statistics rest on too few runs: renderers grey them out
    (the row itself says why). ``widths`` are the columns' relative widths in the PDF (empty: the renderer's
    default), for a wide table whose long cells need the room.
    """

    number: int
    caption: str
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    muted: tuple[bool, ...] = ()
    widths: tuple[float, ...] = ()


@dataclass(frozen=True)
class Figure:
    """A numbered figure: PNG bytes and a caption that says what to look at."""

    number: int
    key: str
    caption: str
    png: bytes


Block = Paragraph | Callout | Heading | Code | Table | Figure


@dataclass(frozen=True)
class Section:
    """A top-level, numbered section; ``key`` is its stable anchor."""

    key: str
    title: str
    blocks: tuple[Block, ...]


@dataclass(frozen=True)
class Report:
    """A whole report.

    Attributes
    ----------
    title, subtitle : str
    generated_at : str
        ISO 8601 timestamp (UTC); the only part allowed to differ between two
        reports of the same input.
    facts : tuple of (str, str)
        Key facts of the title page.
    executive : tuple of Block
        The executive summary on page 1: the question, the verdicts, the data sets, the
        top influences, the failures and the fidelity audit, each linking to its section.
    sections : tuple of Section
    summary_title : str
        Heading of the page-1 blocks (``executive``).
    contents : bool
        Whether a table of contents follows page 1 (a short report goes without).
    landscape : bool
        Whether the PDF's pages are landscape A4 (a wide table on page 1).
    source : str
        What the report was generated from, in the footer's words.
    """

    title: str
    subtitle: str
    generated_at: str
    facts: tuple[tuple[str, str], ...]
    executive: tuple[Block, ...] = field(default=())
    sections: tuple[Section, ...] = field(default=())
    summary_title: str = "Executive summary"
    contents: bool = True
    landscape: bool = False
    source: str = "the stored campaign files"

    def link_text(self, key: str) -> str:
        """``§6 Observability``: how a link to the section ``key`` reads."""
        number = next(i for i, s in enumerate(self.sections, start=1) if s.key == key)
        return f"§{number} {self.sections[number - 1].title}"
