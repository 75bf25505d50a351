"""Charts of the studies: work-precision (error against wall time) and the stability map."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (backend must be chosen first)
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.ticker import NullFormatter  # noqa: E402

from app.studies.work_precision import quantization_floor  # noqa: E402
from twin.simulation import DEFAULT_DT, DEFAULT_INTEGRATOR  # noqa: E402

PANEL_TITLES = {"quantizers_off": "quantizers off (ideal instruments): convergence order",
                "quantizers_on": "quantizers on (encoders, resolver, converters)"}
METRIC_LABELS = {"feature_error": "backlash-feature error [um]", "nut_position_error": "max nut-position error [um]",
                 "current_rms_error": "RMS motor-current error [A]",
                 "pressure_error": "max chamber-pressure error [Pa]"}
SCALE = {"feature_error": 1e6, "nut_position_error": 1e6, "current_rms_error": 1.0, "pressure_error": 1.0}


def work_precision_chart(study: xr.Dataset, path: str | Path | None = None,
                         metrics=("feature_error", "nut_position_error", "current_rms_error"),
                         sampling_error: float | None = None) -> plt.Figure:
    """Log error against log wall time, one line per method, one column per panel.

    ``sampling_error`` (optional, [m]) draws the Monte Carlo sampling error of the
    feature mean (1.96 sigma / sqrt(N)) on the feature rows: a configuration whose
    error sits well below it cannot change a campaign's conclusions.
    """
    panels = [p for p in PANEL_TITLES if p in set(study.panel.values)]
    metrics = [m for m in metrics if np.isfinite(study[m].values).any()]
    fig, axes = plt.subplots(len(metrics), len(panels), figsize=(6.2 * len(panels), 3.6 * len(metrics)),
                             squeeze=False, constrained_layout=True)
    for col, panel in enumerate(panels):
        data = study.where(study.panel == panel, drop=True)
        for row, metric in enumerate(metrics):
            ax = axes[row, col]
            for method in dict.fromkeys(data.method.values):
                runs = data.where((data.method == method) & (data.status == "ok"), drop=True)
                if runs.sizes["run"] == 0:
                    continue
                order = np.argsort(runs.wall_time.values)
                error = np.maximum(runs[metric].values[order] * SCALE[metric], 1e-16)
                if str(method).startswith("auto"):  # the opt-in automatic integrator: one point, over the ladders
                    ax.loglog(runs.wall_time.values[order], error, "*", ms=13, color="k", zorder=5,
                              label=f"{method}, opt-in")
                    continue
                label = method + (" (rtol ladder)" if np.isnan(runs.dt.values).all() else "")
                ax.loglog(runs.wall_time.values[order], error, "o-", ms=4, lw=1.2, label=label)
                default = np.isclose(runs.dt.values[order], DEFAULT_DT, rtol=1e-9, atol=0.0)
                if method == DEFAULT_INTEGRATOR and default.any():  # ring the default configuration
                    ax.loglog(runs.wall_time.values[order][default], error[default], "o", ms=12, mfc="none", color="k",
                              mec="k", mew=1.5, label=f"{method} {DEFAULT_DT * 1e6:g} us, the default")
            if panel == "quantizers_on":
                floor = quantization_floor(study, metric) * SCALE[metric]
                if np.isfinite(floor) and floor > 0:
                    ax.axhline(floor, color="k", ls=":", lw=1, label="quantization-decision floor")
            if metric == "feature_error" and sampling_error:
                ax.axhline(sampling_error * 1e6, color="tab:red", ls="--", lw=1,
                           label="Monte Carlo error 1.96 sigma/sqrt(N)")
            ax.xaxis.set_minor_formatter(NullFormatter())  # labelled minor ticks overlap on a short decade
            ax.set_xlabel("wall time of one run [s]")
            ax.set_ylabel(METRIC_LABELS[metric])
            ax.grid(True, which="both", alpha=0.3)
            if row == 0:
                ax.set_title(PANEL_TITLES[panel], fontsize=10)
            if row == 0 and col == 0:
                ax.legend(fontsize=7)
    fig.suptitle(f"work-precision, scene '{study.attrs.get('scene')}' ({study.attrs.get('duration')} s), "
                 f"reference {study.attrs.get('reference')}", fontsize=10)
    _save(fig, path)
    return fig


def stability_chart(stability: xr.Dataset, path: str | Path | None = None) -> plt.Figure:
    """Measured largest stable step against omega_max, with the theoretical 2.8/omega and 2/omega lines."""
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    omega = stability.omega_max.values
    grid = np.linspace(omega.min() * 0.9, omega.max() * 1.1, 50)
    for name, color in (("rk4", "tab:blue"), ("semi_implicit_euler", "tab:orange")):
        if f"limit_{name}" not in stability:
            continue
        factor = float((stability[f"theory_{name}"] * stability.omega_max).values[0])
        ax.plot(omega, stability[f"limit_{name}"].values * 1e6, "o", color=color, label=f"{name}: measured")
        ax.plot(grid, factor / grid * 1e6, "-", color=color, lw=1, label=f"{name}: {factor:g}/omega")
    ax.set_xlabel("largest eigenvalue modulus omega_max at the loaded state [rad/s]")
    ax.set_ylabel("largest stable step [us]")
    ax.set_title("stability limits of the explicit methods (preload, force and sled-mass sweeps)", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    _save(fig, path)
    return fig


def campaign_accuracy_chart(comparison: xr.Dataset, path: str | Path | None = None) -> plt.Figure:
    """Shift of the feature's mean and sigma per candidate solver and data set, against 1.96 sigma/sqrt(N).

    A candidate is good enough for campaigns when its bars sit well below the dashed
    Monte Carlo sampling-error line of its data set.
    """
    datasets = list(comparison.dataset.values)
    candidates = list(comparison.candidate.values)
    fig, axes = plt.subplots(1, len(datasets), figsize=(5.5 * len(datasets), 4), squeeze=False,
                             constrained_layout=True)
    width = 0.8 / len(candidates)
    for ax, name in zip(axes[0], datasets, strict=False):
        data = comparison.sel(dataset=name)
        for i, candidate in enumerate(candidates):
            values = [abs(float(data[v].sel(candidate=candidate))) * 1e6
                      for v in ("mean_shift", "sigma_shift", "max_paired_difference")]
            ax.bar(np.arange(3) + i * width, np.maximum(values, 1e-7), width, label=candidate)
        ax.axhline(float(data.sampling_error[0]) * 1e6, color="tab:red", ls="--", lw=1.2,
                   label="1.96 sigma / sqrt(N)")
        ax.set_yscale("log")
        ax.set_xticks(np.arange(3) + 0.4 - width / 2)
        ax.set_xticklabels(["|mean shift|", "|sigma shift|", "max paired diff."])
        ax.set_ylabel("backlash feature [um]")
        ks = ", ".join(f"{float(k):.2f}" for k in data.ks_distance.values)
        ax.set_title(f"{name}: N = {int(data.n[0])}, KS distances {ks}", fontsize=9)
        ax.grid(True, axis="y", which="both", alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(f"campaign-level accuracy against {comparison.attrs.get('reference')}", fontsize=10)
    _save(fig, path)
    return fig


def _save(fig: plt.Figure, path: str | Path | None) -> None:
    if path is None:
        return
    path = Path(path)
    for suffix in (".png", ".svg"):
        fig.savefig(path.with_suffix(suffix), dpi=120, metadata={"Date": None} if suffix == ".svg" else None)
    plt.close(fig)
