"""Figures of one run, in the layout of Figs. 9.6/9.7 (used by the CLI and the reports)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (backend must be chosen first)
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

_MICRO = 1e6
_MILLI = 1e3


def plot_run(ds: xr.Dataset, path: str | Path | None = None) -> plt.Figure:
    """Six-panel overview of a run: position, nut-minus-screw, current, forces, speed command, temperature.

    Parameters
    ----------
    ds : xarray.Dataset
        Output of :func:`twin.simulate`.
    path : str or Path, optional
        If given, the figure is saved there (format from the suffix) and closed.
    """
    t = ds["time"].values
    fig, axes = plt.subplots(3, 2, figsize=(11, 8.5), sharex=True, constrained_layout=True)
    ax = axes[0, 0]
    ax.plot(t, ds["position_demand"] * _MILLI, label="demand", lw=1.0)
    ax.plot(t, ds["nut1_position"] * _MILLI, label="sled (true)", lw=1.0, ls="--")
    if "linear_encoder_position" in ds:
        ax.plot(t, ds["linear_encoder_position"] * _MILLI, label="linear encoder", lw=0.8)
    ax.set_ylabel("position [mm]")
    ax.set_title("(a) position demand and response")
    ax.legend(fontsize=8)

    ax = axes[0, 1]
    ax.plot(t, (ds["nut1_position"] - ds["screw_equivalent_position"]) * _MICRO, lw=0.8, label="true")
    if "screw_angle_measured" in ds:
        lead_arm = ds.attrs["screw_lead"] / (2 * np.pi)
        measured = ds["linear_encoder_position"] - lead_arm * ds["screw_angle_measured"]
        ax.plot(t, measured * _MICRO, lw=0.6, alpha=0.8, label="encoders")
        ax.legend(fontsize=8)
    ax.set_ylabel("x_n1 - p*theta_s/2pi [um]")
    ax.set_title("(b) nut minus screw equivalent position")

    ax = axes[1, 0]
    ax.plot(t, ds["motor_current"], lw=0.6, label="true")
    if "motor_current_measured" in ds:
        ax.plot(t, ds["motor_current_measured"], lw=0.5, alpha=0.7, label="measured")
        ax.legend(fontsize=8)
    ax.set_ylabel("motor current [A]")
    ax.set_title("(c) motor current")

    ax = axes[1, 1]
    ax.plot(t, ds["preload_force"], lw=1.0, label="preload")
    ax.plot(t, ds["external_force"], lw=1.0, label="external force")
    if "chamber1_pressure" in ds:
        ax.plot(t, ds["force_demand"], lw=0.8, ls=":", label="force demand")
    ax.set_ylabel("force [N]")
    ax.set_title("(d) preload and external force")
    ax.legend(fontsize=8)

    ax = axes[2, 0]
    ax.plot(t, ds["speed_command"], lw=0.6)
    ax.set_ylabel("speed command [rad/s]")
    ax.set_title("(e) motor speed command (after the 11-bit input)")
    ax.set_xlabel("time [s]")

    ax = axes[2, 1]
    if "winding_temperature" in ds:
        ax.plot(t, ds["winding_temperature"] - 273.15, lw=1.0)
        ax.set_title("(f) winding temperature")
    else:
        ax.set_title("(f) winding temperature: not modelled (motor_thermal=frozen)")
    ax.set_ylabel("winding temperature [degC]")
    ax.set_xlabel("time [s]")

    fig.suptitle(f"scene '{ds.attrs.get('scene', '?')}': status {ds.attrs.get('status')}, backlash feature "
                 f"{float(ds['backlash_feature']) * _MICRO:.3f} um measured, "
                 f"{float(ds['backlash_feature_true']) * _MICRO:.3f} um true")
    for a in axes.flat:
        a.grid(True, alpha=0.3)
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig
