"""Section "Speed and accuracy": the solver study (work-precision, stability, campaign accuracy)."""

from __future__ import annotations

import numpy as np

from reports import figures
from reports.builder import Builder, solver_description
from reports.figures import Line, Panel
from reports.model import Callout
from reports.units import axis_label, display_scale, number, quantity


def build(b: Builder):
    study = b.inputs.accuracy
    if study is None:
        yield Callout("Speed-versus-accuracy chart and solver statistics: not available (no work-precision study was "
                      "given; run `twin accuracy --out DIR` and pass DIR/work_precision.nc).")
        return
    ok = study["status"].values == "ok"
    error = study["feature_error"].values.astype(float)
    factor, unit = display_scale(study["feature_error"].attrs.get("units", "m"), error[ok])
    panels_of = [str(p) for p in study["panel"].values] if "panel" in study.variables else [""] * study.sizes["run"]
    methods = list(dict.fromkeys(str(m) for m in study["method"].values))
    adaptive = np.isnan(study["dt"].values) if "dt" in study.variables else np.zeros(study.sizes["run"], dtype=bool)
    panels, rows = [], []
    for panel in dict.fromkeys(panels_of):
        lines = []
        for k, method in enumerate(methods):
            runs = np.flatnonzero([p == panel and str(m) == method
                                   for p, m in zip(panels_of, study["method"].values, strict=False)])
            good = runs[ok[runs] & (error[runs] > 0)]  # a log axis cannot show an exact zero
            if len(good):
                good = good[np.argsort(study["wall_time"].values[good])]
                label = method + (" (rtol ladder)" if adaptive[good].all() else "")
                lines.append(Line(label, study["wall_time"].values[good], error[good] * factor, f"C{k % 10}", "-"))
            if len(runs):
                best = runs[ok[runs]]
                rows.append((panel.replace("_", " ") or "–", method, f"{len(best)} of {len(runs)}",
                             number(study["wall_time"].values[best].min()) if len(best) else "–",
                             quantity(np.nanmin(error[best]), "m") if len(best) and np.isfinite(error[best]).any()
                             else "–"))
        panels.append(Panel(panel.replace("_", " "), "wall time of one run [s]",
                            axis_label("backlash-feature error", unit), tuple(lines)))
    yield b.figure(
        "speed-accuracy",
        f"Work-precision study of scene '{study.attrs.get('scene', '?')}' ({study.attrs.get('duration', '?')} s): "
        f"error of the backlash feature against the reference ({study.attrs.get('reference', '?')}) versus the wall "
        "time of one run, per solver method. Configurations to the lower left are both fast and accurate; the "
        f"campaign ran with {solver_description(b.spec)}.",
        figures.work_precision(panels),
    )
    yield b.table("Solver methods of the study: successful runs, fastest run and smallest backlash-feature error.",
                  ("Panel", "Method", "Runs ok", "Fastest run [s]", "Smallest feature error"), rows)
    yield b.table("Study configuration, machine and the reference solver's statistics, as stored with the study.",
                  ("Item", "Value"), [(k, v if isinstance(v, str) else number(v, 4)) for k, v in study.attrs.items()])
