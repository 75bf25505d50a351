"""Figures of one run, in the layout of Figs. 9.6/9.7 (used by the CLI and the reports)."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (backend must be chosen first)
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from twin.features import MOTION_SPEED_THRESHOLD  # noqa: E402

_MICRO = 1e6
_MILLI = 1e3
_KELVIN_OFFSET = 273.15
#: Colours of the screw's direction of motion in the hysteresis loop (as Fig. 5.12 tells the two branches apart).
_DIRECTION_COLOURS = {"moving +": "tab:blue", "moving −": "tab:orange", "hold/reversal": "0.7"}


def _nut_minus_screw(ds: xr.Dataset) -> list[tuple[str, np.ndarray]]:
    """Eq. 9.12's d = x_n1 - p theta_s / 2 pi [m] on true signals and, where the run has them, on the encoders."""
    series = [("true", (ds["nut1_position"] - ds["screw_equivalent_position"]).values)]
    if {"screw_angle_measured", "linear_encoder_position"} <= set(ds.data_vars):
        lead_arm = ds.attrs["screw_lead"] / (2 * np.pi)
        series.append(("encoders", (ds["linear_encoder_position"] - lead_arm * ds["screw_angle_measured"]).values))
    return series


def _panels(ds: xr.Dataset) -> list[tuple[str, str, list[tuple[str, np.ndarray, dict]]]]:
    """The time panels the run's signals allow: (title, y label, [(legend label, values, line style)]).

    A signal the run did not produce (a subsystem at a reduced fidelity, an output not
    requested) gives no panel, so no panel is ever drawn empty.
    """
    panels = []
    lines = [(label, ds[name].values * _MILLI, style) for label, name, style in (
        ("demand", "position_demand", {"lw": 1.0}),
        ("sled (true)", "nut1_position", {"lw": 1.0, "ls": "--"}),
        ("linear encoder", "linear_encoder_position", {"lw": 0.8})) if name in ds]
    panels.append(("position demand and response", "position [mm]", lines))
    # Eq. 9.12 as it accumulates: d itself swings across the gap many times a second (a solid band over a whole
    # test), while the running mean of |d| shows what the feature is made of and where it settles
    lines = []
    for (label, d), style in zip(_nut_minus_screw(ds), ({"lw": 1.2}, {"lw": 1.0, "ls": "--"}), strict=False):
        running = np.cumsum(np.abs(d)) / np.arange(1, d.size + 1)
        lines.append((f"running mean, {label} → {running[-1] * _MICRO:.1f} µm", running * _MICRO, style))
    lines.append(("|d|, true (averaged)", np.abs(_nut_minus_screw(ds)[0][1]) * _MICRO,
                  {"lw": 0.3, "color": "0.82", "zorder": 0}))
    panels.append(("backlash feature f_b (Eq. 9.12) as it accumulates", "mean of |x_n1 − p·θ_s/2π| [µm]", lines))
    lines = [(label, ds[name].values, style) for label, name, style in (
        ("true", "motor_current", {"lw": 0.6}), ("measured", "motor_current_measured", {"lw": 0.5, "alpha": 0.7}))
        if name in ds]
    if lines:
        panels.append(("motor current", "motor current [A]", lines))
    lines = [(label, ds[name].values / _MILLI, style) for label, name, style in (
        ("preload", "preload_force", {"lw": 1.0}), ("external force", "external_force", {"lw": 1.0}),
        ("force demand", "force_demand", {"lw": 0.8, "ls": ":"})) if name in ds]
    if lines:
        panels.append(("preload and external force", "force [kN]", lines))
    if "speed_command" in ds:
        panels.append(("motor speed command (after the 11-bit input)", "speed command [rad/s]",
                       [("command", ds["speed_command"].values, {"lw": 0.6})]))
    if "winding_temperature" in ds:
        panels.append(("winding temperature", "temperature [°C]",
                       [("winding", ds["winding_temperature"].values - _KELVIN_OFFSET, {"lw": 1.0})]))
    return panels


def _hysteresis(ax: plt.Axes, ds: xr.Dataset, title: str) -> None:
    """The hysteresis loop (Fig. 5.12): d on true signals against the screw equivalent position, each sample coloured
    by the screw's direction of motion as ``backlash_hysteresis`` classifies it (moving by more than
    :data:`twin.features.MOTION_SPEED_THRESHOLD` per sample), with the mean of d on each branch: their difference
    is the hysteresis width H."""
    screw = ds["screw_equivalent_position"].values
    d = _nut_minus_screw(ds)[0][1]
    step = np.diff(screw, prepend=screw[0])
    threshold = MOTION_SPEED_THRESHOLD * float(np.median(np.diff(ds["time"].values))) if screw.size > 1 else np.inf
    direction = np.where(step > threshold, "moving +", np.where(step < -threshold, "moving −", "hold/reversal"))
    for label, colour in _DIRECTION_COLOURS.items():
        chosen = direction == label
        if chosen.any():
            ax.scatter(screw[chosen] * _MILLI, d[chosen] * _MICRO, s=1.5, color=colour, alpha=0.5, linewidths=0,
                       rasterized=True, label=f"{label} ({int(chosen.sum())} samples)")
    for label in ("moving −", "moving +"):
        chosen = direction == label
        if chosen.any():
            ax.axhline(float(d[chosen].mean()) * _MICRO, color=_DIRECTION_COLOURS[label], lw=1.4,
                       label=f"mean of d {label}")
    width = float(ds["backlash_hysteresis_true"]) if "backlash_hysteresis_true" in ds else np.nan
    backlash = json.loads(ds.attrs.get("scene_conditions", "{}")).get("backlash")
    if backlash and ds.attrs.get("zero_procedure") == "thesis":  # zeroed with the nuts centred: flanks at d = ±b/2
        for sign in (1, -1):
            ax.axhline(sign * backlash / 2 * _MICRO, color="k", lw=0.8, ls=":",
                       label="gap flanks ±b/2 (zeroed centred)" if sign > 0 else None)
    said = (f"H = mean(d | −) − mean(d | +) = {width * _MICRO:.1f} µm (true signals)" if np.isfinite(width)
            else "H undefined: the screw did not move both ways")
    if backlash is not None:
        said += f"\nscene backlash {backlash * _MICRO:g} µm, zero procedure {ds.attrs.get('zero_procedure', '?')}"
    ax.set_title("\n".join([*textwrap.wrap(title, 64), said]), fontsize=9)
    ax.set_xlabel("screw equivalent position p·θ_s/2π [mm]")
    ax.set_ylabel("d = x_n1 − p·θ_s/2π [µm]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, markerscale=4)


def plot_run(ds: xr.Dataset, path: str | Path | None = None) -> plt.Figure:
    """Overview of a run on a two-column grid: position, the Eq. 9.12 feature as it accumulates, current, forces,
    speed command, temperature against time, and the hysteresis loop of nut minus screw against the screw position.

    Only the panels of signals the run produced are drawn (the winding temperature, for
    instance, exists only when the thermal model runs); each legend sits right of its axes.

    Parameters
    ----------
    ds : xarray.Dataset
        Output of :func:`twin.simulate`.
    path : str or Path, optional
        If given, the figure is saved there (format from the suffix) and closed.
    """
    t = ds["time"].values
    panels = _panels(ds)
    rows = (len(panels) + 2) // 2  # the time panels and the hysteresis loop
    fig, axes = plt.subplots(rows, 2, figsize=(12, 0.9 + 2.5 * rows), constrained_layout=True, squeeze=False)
    time_axes = list(axes.flat[:len(panels)])
    letters = "abcdefgh"
    for k, (ax, (title, ylabel, lines)) in enumerate(zip(time_axes, panels, strict=True)):
        for label, values, style in lines:
            ax.plot(t, values, label=label, **style)
        ax.set_title(f"({letters[k]}) {title}", fontsize=10)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        if k:
            ax.sharex(time_axes[0])
        if len(lines) > 1:
            ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    for k, ax in enumerate(time_axes):  # time labels under the lowest time panel of each column only
        if k + 2 < len(time_axes):
            ax.tick_params(labelbottom=False)
        else:
            ax.set_xlabel("time [s]")
    _hysteresis(axes.flat[len(panels)], ds, f"({letters[len(panels)]}) hysteresis loop: nut minus screw by "
                                            "direction of motion")
    for ax in axes.flat[len(panels) + 1:]:
        ax.set_visible(False)
    title = (f"scene '{ds.attrs.get('scene', '?')}': status {ds.attrs.get('status')}; backlash feature (Eq. 9.12) "
             f"{float(ds['backlash_feature']) * _MICRO:.3f} µm measured, "
             f"{float(ds['backlash_feature_true']) * _MICRO:.3f} µm "
             "true signals")
    fig.suptitle("\n".join(textwrap.wrap(title, 110)), fontsize=11)
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig
