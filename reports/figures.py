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
from typing import NamedTuple

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import TwoSlopeNorm
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from scipy import stats

#: Pixels per inch of the stored PNGs: sharp on a laptop screen and on paper at the page width.
DPI = 150
#: Figure width [in]: the text width of an A4 page, so PDF figures are shown at their drawn size.
WIDTH = 7.0
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


def _new(nrows: int, ncols: int, height: float) -> Figure:
    fig = Figure(figsize=(WIDTH, height), layout="constrained")
    FigureCanvasAgg(fig)
    fig.subplots(nrows, ncols, squeeze=False)
    return fig


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


def _tidy_x(ax) -> None:
    """Few x ticks, and scientific notation for tiny or huge values, so tick labels never collide."""
    ax.xaxis.set_major_locator(MaxNLocator(5))
    ax.ticklabel_format(axis="x", style="sci", scilimits=(-3, 4), useOffset=True)


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
        ax.plot(grid, stats.gaussian_kde(values)(grid), color=group.color, lw=1.6, label=f"{group.label} (n = {len(values)})")
    except np.linalg.LinAlgError:  # (near-)singular data: the histogram alone says it
        ax.plot([], [], color=group.color, label=f"{group.label} (n = {len(values)})")
    return True


@_styled
def distributions(panels: list[Panel]) -> bytes:
    """Histograms (probability density) with a Gaussian kernel density per group, panels side by side.

    Each panel's ``items`` are :class:`Group` s drawn over each other, each
    with its own bins so that narrow and wide distributions both show. A group
    without spread is a vertical line; a panel of such groups has no density scale.
    """
    fig = _new(1, len(panels), 3.0)
    for ax, panel in zip(fig.axes, panels):
        densities = [_density(ax, group) for group in panel.items]
        if not any(np.isfinite(group.values).any() for group in panel.items):
            ax.text(0.5, 0.5, "no successful run", transform=ax.transAxes, ha="center", va="center", color="grey")
        if not any(densities):
            ax.set_yticks([])
        ax.set_ylim(bottom=0.0)
        ax.set(title=panel.title, xlabel=panel.xlabel, ylabel=panel.ylabel)
        _tidy_x(ax)
        ax.legend(loc="best")
    return _png(fig)


@_styled
def tornado(labels, estimate, lower, upper, *, interval: str, marker=None, band: float | None, xlabel: str, title: str) -> bytes:
    """Ranked horizontal bars with confidence intervals, the strongest at the top.

    Parameters
    ----------
    labels : list of str
    estimate, lower, upper : array_like
        Bar lengths and their interval (same order as ``labels``, already ranked).
    interval : str
        Legend label of the interval.
    marker : tuple of (str, array_like), optional
        A second coefficient drawn as diamonds (label, values).
    band : float, optional
        Half-width of the grey band around zero of coefficients indistinguishable from noise.
    """
    n = len(labels)
    fig = _new(1, 1, 1.3 + 0.27 * max(n, 3))
    ax = fig.axes[0]
    y = np.arange(n)[::-1]
    estimate, lower, upper = (np.asarray(v, dtype=float) for v in (estimate, lower, upper))
    colors = np.where(estimate >= 0, "#c0504d", "#4f81bd")
    ax.barh(y, estimate, color=colors, alpha=0.75, height=0.65, label="Spearman ρ")
    # drawn about the interval's midpoint: a percentile interval need not contain the estimate
    ax.errorbar((lower + upper) / 2, y, xerr=(upper - lower) / 2, fmt="none", ecolor="black", capsize=2.5, lw=0.9,
                label=interval)
    if marker is not None:
        ax.plot(np.asarray(marker[1], dtype=float), y, "D", color="black", ms=3.5, mfc="white", label=marker[0])
    if band:
        ax.axvspan(-band, band, color="grey", alpha=0.2, lw=0, label="|ρ| indistinguishable from 0")
    ax.axvline(0.0, color="black", lw=0.8)
    ax.set_yticks(y, labels)
    ax.set_xlim(-1.05, 1.05)
    ax.set_ylim(-0.7, n - 0.3)
    ax.grid(axis="y", visible=False)
    ax.set(xlabel=xlabel, title=title)
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncols=4, fontsize=7.5, frameon=False)
    return _png(fig)


@_styled
def heatmap(matrix, row_labels, col_labels, *, colorbar_label: str, xlabel: str, ylabel: str,
            vmin: float, vmax: float, cmap: str, center: float | None = None) -> bytes:
    """A labelled colour matrix with each cell's value written in it (NaN cells blank)."""
    matrix = np.asarray(matrix, dtype=float)
    rows, cols = matrix.shape
    fig = _new(1, 1, 1.4 + 0.26 * max(rows, 4))
    ax = fig.axes[0]
    norm = TwoSlopeNorm(center, vmin, vmax) if center is not None else None
    image = ax.imshow(np.ma.masked_invalid(matrix), cmap=cmap, aspect="auto", norm=norm,
                      vmin=None if norm else vmin, vmax=None if norm else vmax)
    for i in range(rows):
        for j in range(cols):
            if np.isfinite(matrix[i, j]):
                red, green, blue, _ = image.cmap(image.norm(matrix[i, j]))
                dark = 0.299 * red + 0.587 * green + 0.114 * blue < 0.5  # perceived luminance of the cell
                ax.text(j, i, f"{matrix[i, j]:.2f}", ha="center", va="center", fontsize=7, color="white" if dark else "black")
    ax.set_xticks(range(cols), col_labels)
    ax.set_yticks(range(rows), row_labels)
    ax.grid(False)
    ax.set(xlabel=xlabel, ylabel=ylabel)
    fig.colorbar(image, ax=ax, label=colorbar_label, shrink=0.8)
    return _png(fig)


@_styled
def scatter(panels: list[Panel]) -> bytes:
    """Scatter panels on a two-column grid; ``items`` are :class:`Line` s drawn as points."""
    ncols = 2 if len(panels) > 1 else 1
    nrows = math.ceil(len(panels) / ncols)
    fig = _new(nrows, ncols, 0.6 + 2.6 * nrows)
    for ax, panel in zip(fig.axes, panels):
        for item in panel.items:
            ax.plot(item.x, item.y, "o", ms=3.0, alpha=0.6, color=item.color, mec="none", label=item.label)
        ax.set(xlabel=panel.xlabel, ylabel=panel.ylabel)
        ax.set_title(panel.title, fontsize=8)
        _tidy_x(ax)
    for ax in fig.axes[len(panels):]:
        ax.set_visible(False)
    handles, labels = fig.axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 7), markerscale=1.5)
    return _png(fig)


@_styled
def time_series(panels: list[Panel]) -> bytes:
    """Stacked time-series panels sharing the time axis; ``items`` are :class:`Line` s."""
    fig = _new(len(panels), 1, 0.5 + 1.9 * len(panels))
    for ax in fig.axes[1:]:
        ax.sharex(fig.axes[0])
    for ax, panel in zip(fig.axes, panels):
        for line in panel.items:
            ax.plot(line.x, line.y, line.style, color=line.color, lw=1.0, label=line.label)
        ax.set(title=panel.title, ylabel=panel.ylabel)
        if len(panel.items) > 1:
            ax.legend(loc="best")
    for ax in fig.axes[:-1]:
        ax.tick_params(labelbottom=False)
    fig.axes[-1].set_xlabel(panels[-1].xlabel)
    return _png(fig)


@_styled
def detection(curves: list[Line], *, power: float, false_alarm_rate: float, requirement: tuple[str, float],
              minima: list[tuple[str, float, str]], xlabel: str) -> bytes:
    """Detection probability along the backlash sweep, with the power target and the requirement.

    ``requirement`` is ``(label, value)``; ``minima`` are ``(label, value, colour)`` of the
    minimum detectable backlash per feature (NaN: not reached), in the units of the x axis.
    """
    fig = _new(1, 1, 4.0)
    ax = fig.axes[0]
    for line in curves:
        ax.plot(line.x, line.y, "o" + line.style, color=line.color, lw=1.4, label=line.label)
    ax.axhline(power, color="black", ls="--", lw=0.9, label=f"target detection probability {power:.0%}")
    ax.axhline(false_alarm_rate, color="grey", ls=":", lw=0.9, label=f"false-alarm rate {false_alarm_rate:.0%}")
    ax.axvline(requirement[1], color="#2e7d32", lw=1.6, label=requirement[0])
    for label, value, color in minima:
        if math.isfinite(value):
            ax.plot([value], [power], "*", ms=12, color=color, mec="black", label=label)
    ax.set_xscale("symlog", linthresh=1.0)
    ax.set_ylim(-0.03, 1.03)
    ax.set(xlabel=xlabel, ylabel="detection probability [–]")
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncols=2, fontsize=7.5, frameon=False)
    return _png(fig)


@_styled
def work_precision(panels: list[Panel]) -> bytes:
    """Log error against log wall time, one line per solver method, panels side by side with a shared error axis."""
    fig = _new(1, len(panels), 3.6)
    for ax in fig.axes[1:]:
        ax.sharey(fig.axes[0])
    for ax, panel in zip(fig.axes, panels):
        for line in panel.items:
            ax.loglog(line.x, line.y, "o" + line.style, color=line.color, ms=3.5, lw=1.1, label=line.label)
        ax.set(title=panel.title, xlabel=panel.xlabel, ylabel=panel.ylabel)
        ax.grid(True, which="both", alpha=0.25)
    handles = {label: handle for ax in fig.axes for handle, label in zip(*ax.get_legend_handles_labels())}
    fig.legend(handles.values(), handles.keys(), loc="outside lower center", ncols=min(len(handles), 4), frameon=False)
    return _png(fig)
