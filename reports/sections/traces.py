"""Section "Representative traces": the stored time series (Figs. 9.6, 9.7, 9.11, 9.12)."""

from __future__ import annotations

import numpy as np

from reports import figures
from reports.builder import NUT, SCREW, TRACE_PANELS, Builder
from reports.figures import Line, Panel
from reports.model import Callout, Paragraph
from reports.units import axis_label, display_scale


def _trace_run(b: Builder, dataset: str, variables: list[str]) -> int | None:
    """The first kept trace of a successful run with data (else of any run with data)."""
    results = b.results
    runs = [int(r) for r in results["trace_run"].values]
    has_data = [r for r in runs
                if any(np.isfinite(results[v].sel(dataset=dataset, trace_run=r).values).any() for v in variables)]
    ok = [r for r in has_data if results["status"].sel(dataset=dataset, run=r).item() == "ok"]
    return (ok or has_data or [None])[0]


def _trace_line(b: Builder, variable: str, dataset: str, run: int, style: str, color: str, factor: float) -> Line:
    values = b.results[f"trace_{variable}"].sel(dataset=dataset, trace_run=run).values * factor
    return Line(variable.replace("_", " "), b.results["trace_time"].values, values, color, style)


def build(b: Builder):
    stored = [str(v).removeprefix("trace_") for v in b.results.data_vars if str(v).startswith("trace_")]
    if not stored or "trace_time" not in b.results.coords:
        yield Callout("Not available: results.nc holds no traces (set [traces] in the campaign spec to keep some).")
        return
    yield Paragraph(
        "Signals of single runs, decimated as stored in results.nc (Figs. 9.6, 9.7, 9.11 and 9.12 of the thesis): one "
        "figure per data set from its first successful traced run, then the nut-minus-screw position of every data set."
    )
    derived = NUT in stored and SCREW in stored
    groups = [(title, quantity_name, [v for v in variables if v in stored])
              for title, quantity_name, variables in TRACE_PANELS]
    placed = {v for *_, variables in groups for v in variables} | ({SCREW} if derived else set())
    groups += [(v.replace("_", " "), v.replace("_", " "), [v]) for v in stored if v not in placed]
    for name in b.datasets:
        run = _trace_run(b, name, [f"trace_{v}" for v in stored])
        if run is None:
            yield Callout(f"Data set {name}: every kept trace is empty (the traced runs failed before writing data).")
            continue
        panels = []
        for title, quantity_name, variables in groups:
            if not variables:
                continue
            unit = b.results[f"trace_{variables[0]}"].attrs.get("units", "")
            factor, shown = display_scale(unit,
                                          np.concatenate([b.results[f"trace_{v}"].values.ravel() for v in variables]))
            lines = tuple(_trace_line(b, v, name, run, ("-", "--", ":", "-.")[k % 4], f"C{k}", factor)
                          for k, v in enumerate(variables))
            complete = len(variables) == len(next((v for t, _, v in TRACE_PANELS if t == title), variables))
            # a panel's title names only what it draws: a partial group is titled by its signals
            panels.append(Panel(title if complete else ", ".join(line.label for line in lines).capitalize(), "time [s]",
                                axis_label(quantity_name, shown), lines))
            if derived and title.startswith("Position"):
                panels.append(_nut_minus_screw_panel(b, [(name, run)]))
        status = b.results["status"].sel(dataset=name, run=run).item()
        yield b.figure(f"traces-{name}",
                       f"Run {run} of data set {b.describe(name)} (status {status}). " + _drawn(panels),
                       figures.time_series(panels))
    if derived:
        pairs = [(name, _trace_run(b, name, [f"trace_{NUT}", f"trace_{SCREW}"])) for name in b.datasets]
        panels = [_nut_minus_screw_panel(b, [(n, r)], title=b.describe(n)) for n, r in pairs if r is not None]
        yield b.figure(
            "traces-nut-minus-screw",
            "Nut position minus the screw's equivalent position (the integrand of Eq. 9.12, Fig. 9.11) for one run "
            "of each data set, one panel per data set on a shared axis. Look at the gap between data sets with and "
            "without backlash at motion reversals.",
            figures.time_series(panels, sharey=True),
        )


def _drawn(panels: list[Panel]) -> str:
    """A caption naming exactly the signals drawn, panel by panel, and what to check in them."""
    text = "Panels from the top: " + "; ".join(
        f"{p.title.lower()} ({', '.join(line.label for line in p.items)})" for p in panels) + "."
    drawn = {line.label for p in panels for line in p.items}
    checks = []
    if {"position demand", "nut1 position"} <= drawn:
        checks.append("that the response follows the demand")
    forces = sorted(label for label in drawn if label.endswith("force"))
    if forces:
        checks.append(f"that the {' and '.join(forces)} hold their expected levels")
    return text + (f" Check {' and '.join(checks)}." if checks else "")


def _nut_minus_screw_panel(b: Builder, runs: list[tuple[str, int]],
                           title: str = "Nut minus screw equivalent position") -> Panel:
    time = b.results["trace_time"].values
    differences = {name: (b.results[f"trace_{NUT}"] - b.results[f"trace_{SCREW}"])
                   .sel(dataset=name, trace_run=run).values
                   for name, run in runs}
    factor, unit = display_scale("m", np.concatenate(list(differences.values())))
    lines = tuple(Line(name if len(runs) > 1 else "x_n1 − p·θ_s/2π", time, d * factor, b.color[name])
                  for name, d in differences.items())
    return Panel(title, "time [s]", axis_label("x_n1 − p·θ_s/2π", unit), lines)
