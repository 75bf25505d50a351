"""Report section "Control robustness": the loop margins of every run against the design limits.

Reads only what the campaign stored: the per-run margins of ``results.nc`` (``role = "margin"``,
:func:`campaigns.bench.adapter.margin_variables`) and the statistics and verdicts of ``analysis.nc``
(:mod:`campaigns.analysis.margins`). The verdict statements are printed verbatim.
"""

from __future__ import annotations

import json
import math

import numpy as np

from campaigns.analysis.margins import decibels, margin_values
from reports import figures
from reports.model import Callout, Paragraph
from reports.phrases import tone

#: Figures of merit drawn against their limits: (metric, axis label, limit field, limit side).
_DRAWN = (
    ("phase_margin", "phase margin [°]", "phase_margin_min", "below"),
    ("gain_margin", "gain margin [dB]", "gain_margin_min", "below"),
    ("peak_sensitivity", "|S|max [1]", "peak_sensitivity_max", "above"),
)
#: Runs listed in the table of runs beyond the limits before "and N more".
LISTED = 40
_UNITS = {"degree": "°", "dB": " dB", "1": "", "Hz": " Hz"}


def _text(value: float, unit: str) -> str:
    if not math.isfinite(value):
        return "∞" if value > 0 else "–"
    return f"{value:.3g}{_UNITS.get(unit, ' ' + unit)}"


def _shown(values, metric: str, unit: str):
    """Values of a margin as the report shows them, and their unit: gain margins (amplitude ratios) in dB."""
    return (decibels(values), "dB") if metric == "gain_margin" else (np.asarray(values, dtype=float), unit)


def _statistic(analysis, name: str, what: str):
    """``<margin>_quantile`` / ``<margin>_worst`` of an analysis (``margin_quantile`` / ``margin_worst`` along
    ``margin`` in analyses written before one variable per margin)."""
    if f"{name}_{what}" in analysis:
        return analysis[f"{name}_{what}"]
    old = analysis[f"margin_{what}"].sel(margin=name)
    return old.copy(data=10.0 ** (old.values / 20.0)) if name.endswith("gain_margin") else old


def _margins(results) -> list[str]:
    return [str(v) for v in results.data_vars if results[v].attrs.get("role") == "margin"]


def _figure(results, datasets: list[str], limits: dict) -> bytes:
    """One panel per figure of merit (rows) and loop (columns): each run's value per data set against the limit."""
    loops = list(dict.fromkeys(str(results[m].attrs["loop"]) for m in _margins(results)))
    grid = []
    for metric, _, field, side in _DRAWN:
        row = []
        for loop in loops:
            name = f"{loop}_loop_{metric}"
            values = (_shown(margin_values(results, name), metric, "")[0] if name in results
                      else np.full((len(datasets), 1), np.nan))
            note = "no phase crossover:\nGM = ∞" if np.isinf(values).any() else "not computed"
            row.append((values, float(limits[field]), side, note))
        grid.append(row)
    return figures.limit_strips(grid, datasets, row_labels=[label for _, label, _, _ in _DRAWN],
                                col_titles=[f"{loop} loop" for loop in loops])


def build(b):
    """The section's blocks (``b``: the report builder of :mod:`reports.content`)."""
    results, analysis = b.results, b.analysis
    margins = _margins(results)
    if not margins or "margin_limit_statement" not in analysis:
        yield Callout("Not available: this campaign's results hold no loop margins (campaigns run before issue 19, "
                      "or a run function other than the bench's), or its analysis predates them.", "muted")
        return
    limits = json.loads(analysis["margin_limit_verdict"].attrs["control_limits"])
    yield Paragraph(
        "Every run's parameter set is linearised around the loops as the twin runs them (the drive's analog current "
        "loop; the digital speed loop at the drive's sample time with the resolver-difference speed measurement; the "
        "position loop at the controller's sample time over the lifted closed speed loop; the force loop where the "
        "cylinder is attached, at the scene's force demand), with zero-order holds and the sampling delays "
        "(twin.control.margins, docs/control_design.md). The gains are the nominal design's; the sampled tolerances "
        "change the plant under them. Design limits: phase margin ≥ "
        f"{limits['phase_margin_min']:g}°, gain margin ≥ {limits['gain_margin_min']:g} dB, |S|max ≤ "
        f"{limits['peak_sensitivity_max']:g}; a limit is met when the exact {95:g} % upper bound of the fraction of "
        f"runs beyond it is within {limits['max_fraction_beyond'] * 100:g} %."
    )
    for verdict, statement in zip(analysis["margin_limit_verdict"].values, analysis["margin_limit_statement"].values,
                                  strict=True):
        yield Callout(str(statement), tone(str(verdict)))
    yield b.figure(
        "control-robustness-margins",
        "Loop margins of every run (dots, one column per data set; black bar: median) against the design limits "
        "(dashed red line; the shaded side is beyond the limit). Columns: the loops; rows: phase margin, gain margin "
        "and peak sensitivity |S|max. The current loop is analog and second order: its phase never reaches −180°, "
        "so its gain margin is infinite.",
        _figure(results, b.datasets, limits),
    )
    features = [str(f) for f in analysis["feature"].values]
    f_b = features.index("backlash_feature") if "backlash_feature" in features else 0
    rows = []
    for name in analysis["margin"].values:
        metric = str(results[str(name)].attrs["metric"])
        median, unit = _shown(_statistic(analysis, str(name), "quantile").sel(margin_probability=0.5).values, metric,
                              str(results[str(name)].attrs.get("units", "")))
        worst = _shown(_statistic(analysis, str(name), "worst").values, metric, unit)[0]
        pick = np.nanargmin if metric != "peak_sensitivity" else np.nanargmax
        if np.isnan(worst).all():
            rows.append((str(name), "–", "–", "–", "–"))
            continue
        d = int(pick(worst)) if np.isfinite(worst).any() else 0
        run = int(analysis["margin_worst_run"].sel(margin=name).values[d])
        rho = analysis["margin_spearman"].sel(margin=name).values  # (dataset, feature)
        column = rho[:, f_b]
        if np.isfinite(column).any():
            k = int(np.nanargmax(np.abs(column)))
            lower, upper = analysis["margin_spearman_ci"].sel(margin=name).values[k, f_b]
            n = int(analysis["margin_spearman_n"].sel(margin=name).values[k, f_b])
            strongest = f"{column[k]:+.2f} [{lower:+.2f}, {upper:+.2f}], n = {n} ({b.datasets[k]})"
        elif np.isinf(worst).all():
            strongest = "– (infinite: no phase crossover)"
        else:
            n = int(analysis["margin_spearman_n"].sel(margin=name).values[:, f_b].max())
            strongest = (f"– (at most {n} runs per data set; {b.min_ok_runs} needed)" if n < b.min_ok_runs
                         else "– (the margin is constant)")
        rows.append((str(name), f"{_text(float(np.nanmin(median)), unit)} – {_text(float(np.nanmax(median)), unit)}",
                     _text(float(worst[d]), unit), f"{b.datasets[d]} run {run}", strongest))
    yield b.table(
        "Loop margins per data set: the range of the data sets' medians, the worst case over the campaign with its "
        f"run, and the strongest Spearman correlation with {features[f_b]} over the data sets (95 % bootstrap "
        "interval, runs used; ok runs with finite margin and feature). Quantiles of every data set are in analysis.nc "
        "(<margin>_quantile; gain margins stored as amplitude ratios, shown here in dB).",
        ("Margin", "Median (data-set range)", "Worst", "Worst run", f"Spearman ρ with {features[f_b]}"), rows)
    violated = analysis["margin_limits_violated"].values
    found = [(b.datasets[d], int(analysis["run"].values[r]), str(violated[d, r]))
             for d, r in zip(*np.nonzero(violated != ""), strict=True)]
    if not found:
        yield Callout("No run has a margin beyond a design limit.", "good")
        return
    rows = [(name, str(run), str(results["status"].sel(dataset=name).values[run]), what)
            for name, run, what in found[:LISTED]]
    more = f" The first {LISTED} of {len(found)} are listed." if len(found) > LISTED else ""
    yield b.table(f"Runs with a margin beyond a design limit ({len(found)} run(s)).{more}",
                  ("Data set", "Run", "Status", "Margins beyond the limits"), rows)
