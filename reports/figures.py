"""The report's figures, one function per kind, each returning PNG bytes.

Figures are drawn on :class:`matplotlib.figure.Figure` objects with the Agg
canvas (no pyplot state, no display) and saved without the ``Software`` PNG
chunk, so the same data give byte-identical files. Every function receives
values already in display units (:mod:`reports.units`) and the axis labels with
those units; the captions live in :mod:`reports.content`.
"""

from __future__ import annotations

import functools
import io
import math
import re
from typing import NamedTuple

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import TwoSlopeNorm
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, MaxNLocator, NullFormatter
from scipy import stats

#: Pixels per inch of the stored PNGs: sharp on a laptop screen and on paper at the page width.
DPI = 150
#: Figure width [in]: the text width of an A4 page, so PDF figures are shown at their drawn size.
WIDTH = 7.0
#: Tallest figure [in]: an A4 page's text height less room for a caption.
MAX_HEIGHT = 8.4
#: Most traces (curves or distributions) drawn over each other on one axes; more become small multiples.
MAX_TRACES = 4
#: Characters per line of a wrapped tick or axis label (a long parameter name breaks after "." or "_").
LABEL_WIDTH = 30
_STYLE = {
    "font.size": 9.0,
    "axes.titlesize": 9.5,
    "axes.labelsize": 9.0,
    "legend.fontsize": 8.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "axes.grid": True,
    "grid.alpha": 0.3,
}


class Group(NamedTuple):
    """Values of one data set (or one signal) with its legend label and colour."""

    label: str
    values: np.ndarray
    color: str


class Line(NamedTuple):
    """A curve or a set of points (time series, scatter, detection curve)."""

    label: str
    x: np.ndarray
    y: np.ndarray
    color: str
    style: str = "-"


class Panel(NamedTuple):
    """One axes: title, axis labels and what it draws (groups or lines)."""

    title: str
    xlabel: str
    ylabel: str
    items: tuple


def _new(nrows: int, ncols: int, height: float, **subplots) -> Figure:
    # drawn at the PNG's resolution, so text extents measured on the canvas are those of the stored image;
    # never taller than a page leaves for a figure and its caption
    fig = Figure(figsize=(WIDTH, min(height, MAX_HEIGHT)), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    fig.subplots(nrows, ncols, squeeze=False, **subplots)
    return fig


def wrap(text: str, width: int = LABEL_WIDTH) -> str:
    """Break a long identifier after ``.``, ``_`` or a space so that no line exceeds ``width`` characters (where it
    can).

    ``sensors.preload_load_cell_offset_tempco_range1`` becomes
    ``sensors.preload_load_cell_`` / ``offset_tempco_range1``: the whole name stays readable, so no key is needed.
    """
    lines, line = [], ""
    for token in re.split(r"(?<=[._ ])", text):
        if line and len(line) + len(token) > width:
            lines.append(line.rstrip())
            line = ""
        line += token
    return "\n".join(lines + [line.rstrip()]) if line else "\n".join(lines)


def _scaled(values: np.ndarray, label: str) -> tuple[np.ndarray, str]:
    """Values of a plain-number axis scaled by a power of ten written into the label (no offset text to collide)."""
    finite = np.abs(values[np.isfinite(values)])
    if finite.size == 0 or finite.max() == 0:
        return values, label
    exponent = int(math.floor(math.log10(finite.max())))
    if -2 <= exponent <= 3:
        return values, label
    return values / 10.0**exponent, f"{label} ×1e{exponent}"


def _legend_outside(fig: Figure, axes, ncols: int = 4, **options) -> None:
    """One legend for the whole figure below the axes, each label once, never over data."""
    handles = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=False):
            handles.setdefault(label, handle)
    if handles:
        fig.legend(handles.values(), handles.keys(), loc="outside lower center", ncols=min(len(handles), ncols),
                   frameon=False, **options)


def _png(fig: Figure) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=DPI, metadata={"Software": None})
    return buffer.getvalue()


def _styled(draw):
    """Run a figure function inside the report's matplotlib style (fonts, grid)."""

    @functools.wraps(draw)
    def wrapper(*args, **kwargs):
        with matplotlib.rc_context(_STYLE):
            return draw(*args, **kwargs)

    return wrapper


def literal(text: str) -> str:
    """Text of the user's (a spec's requirement source) drawn as written: matplotlib reads what stands between two $
    as mathtext, and fails on some of it."""
    return text.replace("$", r"\$")


def _tidy_x(ax) -> None:
    """Few x ticks without an offset text (values come scaled by :func:`_scaled`), so tick labels never collide."""
    ax.xaxis.set_major_locator(MaxNLocator(5))
    ax.ticklabel_format(axis="x", style="plain", useOffset=False)


def _density(ax, group: Group) -> bool:
    """Draw one group's histogram and kernel density; return whether a density was drawn."""
    values = group.values[np.isfinite(group.values)]
    if len(values) == 0:
        ax.plot([], [], color=group.color, label=f"{group.label} (no successful run)")
        return False
    spread = np.ptp(values)
    if spread == 0 or len(values) < 3:
        # no spread to estimate a density from: mark where every run landed, away from the axes' edge
        ax.axvline(values[0], color=group.color, lw=2.0, label=f"{group.label} (all {len(values)} runs)")
        pad = max(0.05 * abs(values[0]), 1.0)
        ax.update_datalim([(values[0] - pad, 0.0), (values[0] + pad, 0.0)], updatey=False)
        ax.autoscale_view(scaley=False)
        return False
    bins = max(8, min(40, int(math.sqrt(len(values)) * 1.5)))
    ax.hist(values, bins=bins, density=True, color=group.color, alpha=0.3, edgecolor=group.color, linewidth=0.5)
    grid = np.linspace(values.min() - 0.15 * spread, values.max() + 0.15 * spread, 300)
    try:
        ax.plot(grid, stats.gaussian_kde(values)(grid), color=group.color, lw=1.6,
                label=f"{group.label} (n = {len(values)})")
    except np.linalg.LinAlgError:  # (near-)singular data: the histogram alone says it
        ax.plot([], [], color=group.color, label=f"{group.label} (n = {len(values)})")
    return True


@_styled
def distributions(panels: list[Panel]) -> bytes:
    """Histograms (probability density) with a Gaussian kernel density per group, panels side by side.

    Up to :data:`MAX_TRACES` groups are drawn over each other with one legend below the
    panels; more groups become small multiples, one row per group sharing the value axis
    (each row scaled to its own density, so narrow and wide distributions both show).
    A group without spread is a vertical line.
    """
    n_groups = max(len(panel.items) for panel in panels)
    stacked = n_groups > MAX_TRACES
    rows = n_groups if stacked else 1
    fig = _new(rows, len(panels), 0.9 + 0.62 * rows if stacked else 2.9, sharex="col")
    grid = np.array(fig.axes).reshape(rows, len(panels))
    for column, panel in enumerate(panels):
        cells = [[group] for group in panel.items] if stacked else [list(panel.items)]
        for row, (ax, groups) in enumerate(zip(grid[:, column], cells, strict=False)):
            drawn = [_density(ax, group) for group in groups]
            if not any(np.isfinite(group.values).any() for group in groups):
                ax.text(0.5, 0.5, "no successful run", transform=ax.transAxes, ha="center", va="center", color="grey")
            ax.set_ylim(bottom=0.0)
            if stacked:
                ax.set_yticks([])
                used = int(np.isfinite(groups[0].values).sum())
                ax.set_ylabel(f"{groups[0].label}\nn = {used}", rotation=0, ha="right", va="center")
                if row < rows - 1:
                    ax.tick_params(labelbottom=False)
            else:
                ax.set_ylabel(panel.ylabel)
                if not any(drawn):
                    ax.set_yticks([])
            _tidy_x(ax)
        grid[0, column].set_title(panel.title)
        grid[-1, column].set_xlabel(panel.xlabel)
    if not stacked:  # the rows of small multiples name their data set and n themselves
        _legend_outside(fig, fig.axes, ncols=3)
    return _png(fig)


@_styled
def tornado(labels, estimate, lower, upper, *, interval: str, marker=None, band: float | None, xlabel: str, title: str,
            muted: str | None = None) -> bytes:
    """Ranked horizontal bars with confidence intervals, the strongest at the top.

    Parameters
    ----------
    labels : list of str
        Parameter names; long ones are wrapped (:func:`wrap`).
    estimate, lower, upper : array_like
        Bar lengths and their interval (same order as ``labels``, already ranked).
    interval : str
        Legend label of the interval.
    marker : tuple of (str, array_like), optional
        A second coefficient drawn as diamonds (label, values).
    band : float, optional
        Half-width of the grey band around zero of coefficients indistinguishable from noise.
    muted : str, optional
        Why these statistics are not to be trusted (e.g. too few runs): the bars are drawn
        grey and the reason is written over the chart.
    """
    n = len(labels)
    wrapped = [wrap(label) for label in labels]
    lines = sum(label.count("\n") + 1 for label in wrapped)
    fig = _new(1, 1, 0.95 + 0.13 * max(lines, 4) + 0.06 * n)
    ax = fig.axes[0]
    y = np.arange(n)[::-1]
    estimate, lower, upper = (np.asarray(v, dtype=float) for v in (estimate, lower, upper))
    colors = np.where(estimate >= 0, "#c0504d", "#4f81bd") if muted is None else np.full(n, "#b0b0b0")
    ax.barh(y, estimate, color=colors, alpha=0.75, height=0.65, label="Spearman ρ")
    # drawn about the interval's midpoint: a percentile interval need not contain the estimate
    ax.errorbar((lower + upper) / 2, y, xerr=(upper - lower) / 2, fmt="none",
                ecolor="black" if muted is None else "#909090",
                capsize=2.5, lw=0.9, label=interval)
    if marker is not None:
        ax.plot(np.asarray(marker[1], dtype=float), y, "D", color="black" if muted is None else "#909090", ms=3.5,
                mfc="white",
                label=marker[0])
    if band:
        ax.axvspan(-band, band, color="grey", alpha=0.2, lw=0, label="|ρ| indistinguishable from 0")
    ax.axvline(0.0, color="black", lw=0.8)
    ax.set_yticks(y, wrapped, fontsize=7.5)
    ax.set_xlim(-1.05, 1.05)
    ax.set_ylim(-0.7, n - 0.3)
    ax.grid(axis="y", visible=False)
    ax.set(xlabel=xlabel, title=title + (f" — {muted}" if muted else ""))
    if muted:
        ax.title.set_color("#707070")
    _legend_outside(fig, [ax], ncols=4, fontsize=7.5)
    return _png(fig)


@_styled
def heatmap(matrix, row_labels, col_labels, *, colorbar_label: str, xlabel: str, ylabel: str,
            vmin: float, vmax: float, cmap: str, center: float | None = None) -> bytes:
    """A labelled colour matrix with each cell's value written in it (NaN cells blank, long row labels wrapped)."""
    matrix = np.asarray(matrix, dtype=float)
    rows, cols = matrix.shape
    row_labels = [wrap(label) for label in row_labels]
    lines = max((label.count("\n") + 1 for label in row_labels), default=1)
    fig = _new(1, 1, 1.4 + (0.1 + 0.11 * lines) * max(rows, 4))
    ax = fig.axes[0]
    norm = TwoSlopeNorm(center, vmin, vmax) if center is not None else None
    image = ax.imshow(np.ma.masked_invalid(matrix), cmap=cmap, aspect="auto", norm=norm,
                      vmin=None if norm else vmin, vmax=None if norm else vmax)
    for i in range(rows):
        for j in range(cols):
            if np.isfinite(matrix[i, j]):
                red, green, blue, _ = image.cmap(image.norm(matrix[i, j]))
                dark = 0.299 * red + 0.587 * green + 0.114 * blue < 0.5  # perceived luminance of the cell
                ax.text(j, i, f"{matrix[i, j]:.2f}", ha="center", va="center", fontsize=7,
                        color="white" if dark else "black")
    ax.set_xticks(range(cols), col_labels)
    ax.set_yticks(range(rows), row_labels, fontsize=7.5 if lines > 1 else 8.0)
    ax.grid(False)
    ax.set(xlabel=xlabel, ylabel=ylabel)
    fig.colorbar(image, ax=ax, label=colorbar_label, shrink=0.8)
    return _png(fig)


@_styled
def scatter(panels: list[Panel]) -> bytes:
    """Scatter panels on a two-column grid; ``items`` are :class:`Line` s drawn as points.

    The x label (a parameter name with its unit) is wrapped; plain-number axes carry
    their power of ten in the label, never as an offset text.
    """
    ncols = 2 if len(panels) > 1 else 1
    nrows = math.ceil(len(panels) / ncols)
    fig = _new(nrows, ncols, 0.7 + 2.7 * nrows)
    for ax, panel in zip(fig.axes, panels, strict=False):
        xlabel = panel.xlabel
        for item in panel.items:
            x, xlabel = _scaled(np.asarray(item.x, dtype=float), panel.xlabel)
            ax.plot(x, item.y, "o", ms=3.0, alpha=0.6, color=item.color, mec="none", label=item.label)
        ax.set_xlabel(wrap(xlabel, 44))
        ax.set_ylabel(wrap(panel.ylabel, 24))
        _tidy_x(ax)
    for ax in fig.axes[len(panels):]:
        ax.set_visible(False)
    _legend_outside(fig, fig.axes, ncols=7, markerscale=1.5)
    return _png(fig)


@_styled
def time_series(panels: list[Panel], *, sharey: bool = False) -> bytes:
    """Stacked time-series panels sharing the time axis; ``items`` are :class:`Line` s.

    Each panel has its legend to the right of the axes, never over the data (small
    multiples name their line in the title instead); callers keep at most :data:`MAX_TRACES` lines per panel (small
    multiples otherwise). ``sharey`` gives every panel the same value axis (small multiples of one quantity).
    """
    compact = sharey and len(panels) > 3
    fig = _new(len(panels), 1, (0.6 + 1.05 * len(panels)) if compact else (0.45 + 1.25 * len(panels)))
    for ax in fig.axes[1:]:
        ax.sharex(fig.axes[0])
        if sharey:
            ax.sharey(fig.axes[0])
    for ax, panel in zip(fig.axes, panels, strict=False):
        for line in panel.items:
            ax.plot(line.x, line.y, line.style, color=line.color, lw=1.0, label=line.label)
        ax.set_title(panel.title, fontsize=8.5 if compact else None)
        if not sharey:
            ax.set_ylabel(wrap(panel.ylabel, 22))
        ax.yaxis.set_major_locator(MaxNLocator(4 if compact else 5))
        if not compact:  # every signal named in the figure, beside its axes
            ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, fontsize=7.5)
    if sharey:  # one label for the shared value axis, along the whole column
        fig.supylabel(panels[0].ylabel, fontsize=9.0)
    for ax in fig.axes[:-1]:
        ax.tick_params(labelbottom=False)
    fig.axes[-1].set_xlabel(panels[-1].xlabel)
    return _png(fig)

class Points(NamedTuple):
    """Values at discrete levels with their interval (NaN: no bar), drawn as unjoined markers: between two levels
    there are no data, so nothing is drawn there."""

    label: str
    x: np.ndarray
    y: np.ndarray
    low: np.ndarray
    high: np.ndarray
    color: str
    filled: bool = True


#: Ratio of the largest to the smallest non-zero level above which a level axis is logarithmic.
LOG_LEVELS = 10.0


def level_axis(levels) -> str:
    """``"log"`` when the non-zero levels span more than :data:`LOG_LEVELS` (0.5 ... 80 µm: a linear axis would
    crowd the levels near the requirement into its first percent), else ``"linear"``."""
    positive = np.asarray(levels, dtype=float)
    positive = positive[np.isfinite(positive) & (positive > 0)]
    return "log" if positive.size > 1 and positive.max() / positive.min() > LOG_LEVELS else "linear"


@_styled
def detection(series: list[Points], *, power: float, false_alarm_rate: float, requirement: tuple[str, float],
              bounds: list[tuple[str, float, float, str]], xlabel: str, ylabel: str = "detection probability [–]",
              bands: tuple[tuple[str, float, float, str], ...] = ()) -> bytes:
    """Detection probability against fault size: each series' points with their intervals at the sweep levels
    (side by side when several series share a level), the power target, the false-alarm rate and the requirement.

    A ``power`` of NaN draws other values (feature means below the detection floor): no target lines, the value axis
    scaled to the data (logarithmic when the values are positive and span more than :data:`LOG_LEVELS`), and
    ``bands``, ``(label, low, high, colour)``, bands across the axes (each series' reference interval).
    ``requirement`` is
    ``(label, value)``; ``bounds`` are ``(label, lower, upper, colour)``: the 95 % bounds of a minimum detectable size,
    drawn as a bar above the points (``lower`` 0 or ``upper`` inf: to the axis' edge). All in the x axis' units.
    The axis is linear or logarithmic (:func:`level_axis`), its ticks at the levels themselves, written as plain
    numbers; a logarithmic axis cannot show the level 0, and leaves it out (the caller says so).
    """
    levels = np.unique(np.concatenate([np.asarray(s.x, dtype=float) for s in series] + [[requirement[1]]]))
    scale = level_axis(levels)
    shown = levels[levels > 0] if scale == "log" else levels
    fig = _new(1, 1, 3.5)  # page 1 holds it below the decisions
    ax = fig.axes[0]
    if scale == "log":
        ax.set_xscale("log")
    span = np.log10(shown.max() / shown.min()) if scale == "log" else float(np.ptp(shown)) or 1.0
    step = 0.012 * span  # side by side: a hundredth of the axis between series at one level
    for k, item in enumerate(series):
        offset = (k - 0.5 * (len(series) - 1)) * step
        x = np.asarray(item.x, dtype=float)
        keep = x > 0 if scale == "log" else np.isfinite(x)
        x_drawn = x[keep] * 10.0**offset if scale == "log" else x[keep] + offset
        y, low, high = (np.asarray(v, dtype=float)[keep] for v in (item.y, item.low, item.high))
        bars = np.isfinite(low) & np.isfinite(high) & np.isfinite(y)
        ax.errorbar(x_drawn[bars], y[bars], yerr=[y[bars] - low[bars], high[bars] - y[bars]], fmt="none",
                    ecolor=item.color, elinewidth=1.0, capsize=3.0)
        ax.plot(x_drawn, y, "o" if item.filled else "s", ls="none", color=item.color, ms=5.5,
                mfc=item.color if item.filled else "white", label=item.label, zorder=3)
    probability = math.isfinite(power)  # else the values are not probabilities (means below the detection floor)
    if probability:
        ax.axhline(power, color="black", ls="--", lw=0.9, label=f"target detection probability {power:.0%}")
        ax.axhline(false_alarm_rate, color="grey", ls=":", lw=0.9, label=f"false-alarm rate {false_alarm_rate:.0%}")
    ax.axvline(requirement[1], color="#2e7d32", lw=1.6, label=requirement[0])
    margin = 0.06 * span
    left, right = ((shown.min() / 10.0**margin, shown.max() * 10.0**margin) if scale == "log"
                   else (shown.min() - margin, shown.max() + margin))
    ax.set_xlim(left, right)
    for k, (label, lower, upper, color) in enumerate(bounds):
        low = lower if math.isfinite(lower) and (scale == "linear" or lower > 0) else left
        high = upper if math.isfinite(upper) else right
        if math.isfinite(lower) or math.isfinite(upper):
            y = 1.04 + 0.04 * k  # above the points, which reach 1
            ax.plot([low, high], [y, y], "-", color=color, lw=4.0, alpha=0.45, solid_capstyle="butt", label=label)
    ax.set_xticks(shown, [f"{value:g}" for value in shown])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.tick_params(axis="x", which="minor", bottom=False)
    for label, low, high, color in bands:
        if math.isfinite(low) and math.isfinite(high):
            ax.axhspan(low, high, color=color, alpha=0.18, lw=0, label=label)
    if probability:
        ax.set_ylim(-0.03, 1.06 + 0.04 * len(bounds))
    else:
        values = np.concatenate([np.asarray(v, dtype=float) for s in series for v in (s.y, s.low, s.high)]
                                + [np.asarray(band[1:3], dtype=float) for band in bands])
        values = values[np.isfinite(values)]
        if values.size and values.min() > 0 and values.max() / values.min() > LOG_LEVELS:
            ax.set_yscale("log")
            ax.yaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
            ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set(xlabel=xlabel, ylabel=ylabel)
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncols=2, fontsize=7.5, frameon=False)
    return _png(fig)


@_styled
def work_precision(panels: list[Panel]) -> bytes:
    """Log error against log wall time, one line per solver method, panels side by side with a shared error axis."""
    fig = _new(1, len(panels), 3.6)
    for ax in fig.axes[1:]:
        ax.sharey(fig.axes[0])
    for ax, panel in zip(fig.axes, panels, strict=False):
        for line in panel.items:
            ax.loglog(line.x, line.y, "o" + line.style, color=line.color, ms=3.5, lw=1.1, label=line.label)
        ax.set(title=panel.title, xlabel=panel.xlabel, ylabel=panel.ylabel)
        ax.grid(True, which="both", alpha=0.25)
    handles = {label: handle for ax in fig.axes for handle, label in zip(*ax.get_legend_handles_labels(), strict=False)}
    fig.legend(handles.values(), handles.keys(), loc="outside lower center", ncols=min(len(handles), 4), frameon=False)
    return _png(fig)


@_styled
def limit_strips(grid: list[list[tuple]], categories: list[str], *, row_labels: list[str],
                 col_titles: list[str]) -> bytes:
    """Strips of values per category against a limit, on a grid of panels.

    ``grid[row][col]`` is ``(values, limit, side, note)``: ``values`` of shape ``(categories, n)`` (NaN: none),
    the limit drawn as a dashed red line with the ``side`` ("below" or "above") that is beyond it shaded,
    and ``note`` written in a panel without a finite value. Each category's median is a black bar.
    """
    fig = _new(len(grid), len(grid[0]), 0.6 + 1.9 * len(grid))
    x = np.arange(len(categories))
    for row, panels in enumerate(grid):
        for col, (values, limit, side, note) in enumerate(panels):
            ax = fig.axes[row * len(panels) + col]
            finite = np.isfinite(values)
            jitter = np.linspace(-0.25, 0.25, values.shape[1]) if values.shape[1] > 1 else np.zeros(1)
            for d in range(len(categories)):
                ax.plot(x[d] + jitter[finite[d]], values[d][finite[d]], "o", ms=2.5, alpha=0.6, color=f"C{d % 10}",
                        mec="none")
                if finite[d].any():
                    ax.plot([x[d] - 0.3, x[d] + 0.3], [np.median(values[d][finite[d]])] * 2, "-", color="k", lw=1.0)
            if finite.any():
                low, high = float(np.min(values[finite])), float(np.max(values[finite]))
                span = max(high - low, abs(high - limit), 1e-9)
                bottom, top = min(low, limit) - 0.15 * span, max(high, limit) + 0.15 * span
                ax.set_ylim(bottom, top)
                ax.axhspan(*((bottom, limit) if side == "below" else (limit, top)), color="tab:red", alpha=0.08, lw=0)
            else:
                # clear of the limit
                ax.text(0.5, 0.75, note, transform=ax.transAxes, ha="center", va="center", fontsize=8)
            ax.axhline(limit, color="tab:red", ls="--", lw=1.0)
            ax.set_xticks(x, categories, rotation=90 if len(categories) > 4 else 0)
            ax.grid(False, axis="x")
            if row == 0:
                ax.set_title(col_titles[col])
            if col == 0:
                ax.set_ylabel(row_labels[row])
    return _png(fig)


@_styled
def duration_tradeoff(duration, estimate, low, high, *, front, labels: dict[int, str], requirement: tuple[str, float],
                      xlabel: str, ylabel: str, log: bool, log_x: bool = False) -> bytes:
    """A screening estimate against test duration per candidate procedure, the Pareto front joined by a step line.

    ``duration``, ``estimate``, ``low`` and ``high`` are per candidate (NaN: not drawn), in display units; each point
    carries a vertical bar from ``low`` to ``high``. ``front`` are the indices of the Pareto-front candidates,
    ``labels`` the text written beside some candidates (index -> text), ``requirement`` ``(label, value)`` a
    horizontal line; ``log`` draws a logarithmic value axis, ``log_x`` a logarithmic duration axis (ticks in plain
    numbers).
    """
    duration, estimate, low, high = (np.asarray(v, dtype=float) for v in (duration, estimate, low, high))
    fig = _new(1, 1, 4.2)
    ax = fig.axes[0]
    shown = np.isfinite(duration) & np.isfinite(estimate)
    on_front = np.zeros(duration.size, bool)
    on_front[list(front)] = True
    for mask, color, label in ((shown & ~on_front, "#8a8f98", "candidate (95 % interval)"),
                               (shown & on_front, "#1f5aa6", "Pareto front (95 % interval)")):
        if mask.any():
            bars = np.isfinite(low) & np.isfinite(high) & mask
            ax.errorbar(duration[bars], (low[bars] + high[bars]) / 2, yerr=(high[bars] - low[bars]) / 2, fmt="none",
                        ecolor=color, elinewidth=1.0, capsize=2.5, alpha=0.8)
            ax.plot(duration[mask], estimate[mask], "o", color=color, ms=5, label=label, zorder=3)
    steps = [i for i in sorted(front, key=lambda i: duration[i]) if shown[i]]
    if len(steps) > 1:
        ax.step(duration[steps], estimate[steps], where="post", color="#1f5aa6", lw=1.2, zorder=2)
    ax.axhline(requirement[1], color="#2e7d32", ls="--", lw=1.4, label=requirement[0])
    for scaled, axis, set_scale in ((log, ax.yaxis, ax.set_yscale), (log_x, ax.xaxis, ax.set_xscale)):
        if scaled:
            set_scale("log")
            axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
            axis.set_minor_formatter(NullFormatter())
    ax.autoscale_view()
    to_axes = ax.transData + ax.transAxes.inverted()
    for index, text in labels.items():
        if shown[index]:
            # written towards the middle of the axes, so a label at either end stays inside them
            left = to_axes.transform((duration[index], estimate[index]))[0] > 0.6
            ax.annotate(text, (duration[index], estimate[index]), xytext=(-8 if left else 8, 8),
                        textcoords="offset points", ha="right" if left else "left",
                        fontsize=8, arrowprops={"arrowstyle": "-", "color": "black", "lw": 0.6},
                        bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.85})
    ax.set(xlabel=xlabel, ylabel=ylabel)
    _legend_outside(fig, [ax], ncols=3)
    return _png(fig)
