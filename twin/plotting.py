"""Figures of one run, in the layout of Figs. 9.6/9.7 (used by the CLI and the reports)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (backend must be chosen first)
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

_MICRO = 1e6
_MILLI = 1e3
_KELVIN_OFFSET = 273.15


def _panels(ds: xr.Dataset) -> list[tuple[str, str, list[tuple[str, np.ndarray, dict]]]]:
    """The panels the run's signals allow: (title, y label, [(legend label, values, line style)]).

    A signal the run did not produce (a subsystem at a reduced fidelity, an output not
    requested) gives no panel, so no panel is ever drawn empty.
    """
    panels = []
    lines = [(label, ds[name].values * _MILLI, style) for label, name, style in (
        ("demand", "position_demand", {"lw": 1.0}),
        ("sled (true)", "nut1_position", {"lw": 1.0, "ls": "--"}),
        ("linear encoder", "linear_encoder_position", {"lw": 0.8})) if name in ds]
    panels.append(("position demand and response", "position [mm]", lines))
    lines = [("true", (ds["nut1_position"] - ds["screw_equivalent_position"]).values * _MICRO, {"lw": 0.8})]
    if {"screw_angle_measured", "linear_encoder_position"} <= set(ds.data_vars):
        lead_arm = ds.attrs["screw_lead"] / (2 * np.pi)
        measured = ds["linear_encoder_position"] - lead_arm * ds["screw_angle_measured"]
        lines.append(("encoders", measured.values * _MICRO, {"lw": 0.6, "alpha": 0.8}))
    panels.append(("nut minus screw equivalent position", "x_n1 − p·θ_s/2π [µm]", lines))
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


def plot_run(ds: xr.Dataset, path: str | Path | None = None) -> plt.Figure:
    """Overview of a run on a two-column grid: position, nut-minus-screw, current, forces, speed command, temperature.

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
    rows = (len(panels) + 1) // 2
    fig, axes = plt.subplots(rows, 2, figsize=(12, 0.9 + 2.3 * rows), sharex=True, constrained_layout=True,
                             squeeze=False)
    for k, (ax, (title, ylabel, lines)) in enumerate(zip(axes.flat, panels, strict=False)):
        for label, values, style in lines:
            ax.plot(t, values, label=label, **style)
        ax.set_title(f"({'abcdef'[k]}) {title}", fontsize=10)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        if len(lines) > 1:
            ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    for ax in axes.flat[len(panels):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    if len(panels) % 2:  # the last panel's neighbour is hidden: its time labels go on the panel above
        axes[-2, 1].tick_params(labelbottom=True)
        axes[-2, 1].set_xlabel("time [s]")
    title = (f"scene '{ds.attrs.get('scene', '?')}': status {ds.attrs.get('status')}; backlash feature (Eq. 9.12) "
             f"{float(ds['backlash_feature']) * _MICRO:.3f} µm measured, "
             f"{float(ds['backlash_feature_true']) * _MICRO:.3f} µm "
             "true signals")
    fig.suptitle("\n".join(textwrap.wrap(title, 110)), fontsize=11)
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig
