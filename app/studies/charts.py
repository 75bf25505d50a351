"""Charts of the studies: work-precision (error against wall time) and the stability map."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (backend must be chosen first)
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.ticker import NullFormatter  # noqa: E402

from app.studies.work_precision import DEFAULT_POINT, quantization_floor  # noqa: E402
from campaigns.statistics.accuracy_rule import tolerance_for  # noqa: E402
from twin.solver import DEFAULT_DT, DEFAULT_SOLVER  # noqa: E402

PANEL_TITLES = {"quantizers_off": "quantizers off (ideal instruments): convergence order",
                "quantizers_on": "quantizers on (encoders, resolver, converters)"}
METRIC_LABELS = {"feature_error": "backlash-feature error [um]", "nut_position_error": "max nut-position error [um]",
                 "current_rms_error": "RMS motor-current error [A]",
                 "pressure_error": "max chamber-pressure error [Pa]"}
SCALE = {"feature_error": 1e6, "nut_position_error": 1e6, "current_rms_error": 1.0, "pressure_error": 1.0}


def work_precision_chart(study: xr.Dataset, path: str | Path | None = None,
                         metrics=("feature_error", "nut_position_error", "current_rms_error"),
                         sampling_error: float | None = None) -> plt.Figure:
    """Log error against log wall time, one line per method, one column per panel; the default configuration (the
    quasi-static screw axial at the step it chooses) as a star beside the previous default (RK4 at 62.5 us on the
    full plant, ringed).

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
                if str(method).startswith(DEFAULT_POINT):  # the default configuration: one point, over the ladders
                    ax.loglog(runs.wall_time.values[order], error, "*", ms=13, color="k", zorder=5,
                              label=f"the default: {method.removeprefix(DEFAULT_POINT).strip(' ()')} at "
                                    f"{float(runs.dt.values[0]) * 1e6:g} us")
                    continue
                label = method + (" (rtol ladder)" if np.isnan(runs.dt.values).all() else "")
                ax.loglog(runs.wall_time.values[order], error, "o-", ms=4, lw=1.2, label=label)
                previous = np.isclose(runs.dt.values[order], DEFAULT_DT, rtol=1e-9, atol=0.0)
                if method == DEFAULT_SOLVER.integrator and previous.any():  # ring the previous default beside the new
                    ax.loglog(runs.wall_time.values[order][previous], error[previous], "o", ms=12, mfc="none",
                              color="k", mec="k", mew=1.5,
                              label=f"the previous default: {method} at {DEFAULT_DT * 1e6:g} us, dynamic screw axial")
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


def campaign_accuracy_chart(judged: xr.Dataset, path: str | Path | None = None) -> plt.Figure:
    """The accuracy rule per candidate, data set and feature
    (:func:`campaigns.bench.solver_accuracy.campaign_accuracy`): the mean paired shift and the sd ratio, each with its
    95 % interval, against the tolerance band (shaded).

    A candidate meets the rule on a cell when its interval lies inside the band; a cell without an interval
    (insufficient data) is not drawn.
    """
    features = [str(f) for f in judged.feature.values]
    datasets = [str(d) for d in judged.dataset.values]
    candidates = [str(c) for c in judged.candidate.values]
    fig, axes = plt.subplots(2, len(features), figsize=(4.2 * len(features), 6.5), squeeze=False,
                             constrained_layout=True)
    width = 0.7 / len(candidates)
    x = np.arange(len(datasets))
    for row, name in enumerate(("mean_shift", "sd_ratio")):
        for col, feature in enumerate(features):
            if name == "mean_shift":  # in the display unit of the feature's own unit, against its own tolerance
                # (the same along the candidates, which the judged file stacks)
                shown = tolerance_for(str(judged["feature_unit"].sel(feature=feature).values.flat[0]))
                scale, label, centre = shown.scale, f"mean paired shift [{shown.shown}]", 0.0
                tolerance = float(judged["mean_shift_tolerance"].sel(feature=feature).values.flat[0]) * scale
            else:
                scale, label, centre = 1.0, "sd ratio candidate / reference", 1.0
                tolerance = judged.attrs["sd_ratio_tolerance"]
            ax = axes[row, col]
            ax.axhspan(centre - tolerance, centre + tolerance, color="tab:green", alpha=0.15, lw=0,
                       label="tolerance")
            ax.axhline(centre, color="k", lw=0.6)
            for i, candidate in enumerate(candidates):
                cell = judged.sel(candidate=candidate, feature=feature)
                value, lower, upper = (cell[f"{name}{s}"].values * scale for s in ("", "_lower", "_upper"))
                shown = np.isfinite(lower)
                offset = x + (i - (len(candidates) - 1) / 2) * width
                ax.errorbar(offset[shown], value[shown], yerr=[(value - lower)[shown], (upper - value)[shown]],
                            fmt="o", ms=4, capsize=3, label=candidate)
            ax.set_xticks(x)
            ax.set_xticklabels(datasets)
            ax.set_ylabel(label)
            ax.grid(True, axis="y", alpha=0.3)
            if row == 0:
                ax.set_title(feature, fontsize=9)
    axes[0, 0].legend(fontsize=7)
    n = int(judged.n.min())
    fig.suptitle(f"accuracy rule against {judged.attrs.get('reference', 'the reference')}: 95 % intervals "
                 f"(fewest paired runs {n}; none drawn below {judged.attrs.get('min_paired_runs')})", fontsize=10)
    _save(fig, path)
    return fig


def save_png(fig: plt.Figure, path: Path, dpi: int) -> Path:
    """``fig`` laid out and written as a PNG at ``path``, then closed: the chapter studies' figures."""
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def _save(fig: plt.Figure, path: str | Path | None) -> None:
    if path is None:
        return
    path = Path(path)
    for suffix in (".png", ".svg"):
        fig.savefig(path.with_suffix(suffix), dpi=120, metadata={"Date": None} if suffix == ".svg" else None)
    plt.close(fig)
