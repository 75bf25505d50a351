"""The report's content: sections, tables, figures and captions from the stored data.

:func:`build` turns the loaded inputs (:mod:`reports.inputs`) into one
:class:`reports.model.Report`. Every number shown is read from ``results.nc``
or ``analysis.nc`` (or the accuracy data set); nothing is simulated. Figures
and tables are numbered in the order they appear, which both renderers keep.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np

from campaigns.analysis import BACKLASH_REQUIREMENT
from reports import control_robustness, figures
from reports.conditions import dataset_conditions
from reports.figures import MAX_TRACES, Group, Line, Panel
from reports.inputs import Inputs
from reports.model import Callout, Figure, Heading, Paragraph, Report, Section, Table
from reports.units import axis_label, display_scale, number, quantity

#: Parameters shown in a tornado chart (the strongest by |Spearman ρ|): two charts fit on a page.
TORNADO_PARAMETERS = 10
#: Ok runs below which a data set's statistics are greyed out, when analysis.nc states no ``min_ok_runs``
#: (older analyses): fewer runs than this give correlations of ±1 by chance alone.
FALLBACK_MIN_OK_RUNS = 10
#: Influences per feature in the executive summary.
SUMMARY_INFLUENCES = 3
#: Tone of each requirement verdict (CONTRACT.md: the analysis writes exactly one of these).
VERDICT_TONES = {"met": "good", "not met": "bad", "undetermined": "info", "insufficient data": "muted"}
#: Parameter rows of a correlation heat map (with wrapped names, a page holds about this many).
HEATMAP_PARAMETERS = 20
#: Parameters in the scatter plots of a feature.
SCATTER_PARAMETERS = 4
#: Run indices listed per row of the failed-runs table before "and N more".
LISTED_RUNS = 12
#: Standard deviation, relative to the mean, below which a feature counts as constant (floating-point round-off).
_ROUND_OFF = 1e-12
#: Two-sided normal quantile of the 95 % band of a correlation under independence.
_Z95 = 1.96
#: Trace panels in the order of Figs. 9.6/9.7/9.12: title, quantity (axis label) and the stored variables each draws.
TRACE_PANELS = (
    ("Position demand and response", "position", ("position_demand", "nut1_position", "linear_encoder_position")),
    ("Motor current", "current", ("motor_current", "motor_current_measured", "current_demand")),
    ("Preload and external force", "force", ("preload_force", "preload_force_measured", "external_force", "external_force_measured", "force_demand")),
    ("Chamber pressures", "pressure (absolute)", ("chamber1_pressure", "chamber2_pressure")),
)
#: Variables of the nut-minus-screw signal of Eq. 9.12 (Fig. 9.11).
NUT, SCREW = "nut1_position", "screw_equivalent_position"
SECTION_TITLES = {
    "summary": "Campaign and provenance",
    "distributions": "Feature distributions",
    "correlations": "Correlations",
    "scatter": "Feature against the top-ranked parameters",
    "traces": "Representative traces",
    "observability": "Observability",
    "failures": "Failed runs",
    "speed": "Speed and accuracy",
    "fidelity": "Fidelity",
    "control_robustness": control_robustness.TITLE,
}


class _Builder:
    """Shared state while building: the inputs, the colours of the data sets and the numbering."""

    def __init__(self, inputs: Inputs):
        self.inputs = inputs
        self.results, self.analysis, self.spec = inputs.results, inputs.analysis, inputs.spec["spec"]
        self.datasets = [str(d) for d in self.results["dataset"].values]
        self.color = {name: f"C{i % 10}" for i, name in enumerate(self.datasets)}
        self.features = [str(v) for v in self.results.data_vars if self.results[v].attrs.get("role") == "feature"]
        self.measured = [f for f in self.features if not (f.endswith("_true") and f.removesuffix("_true") in self.features)]
        self.parameters = [str(v) for v in self.results.data_vars if self.results[v].attrs.get("role") == "sampled"]
        # one source for the parameter counts of every sentence and caption: sampled, and of those varying
        self.constant = [p for p in self.parameters if not np.ptp(np.nan_to_num(self.results[p].values.astype(float)))]
        self.varying = [p for p in self.parameters if p not in self.constant]
        self.conditions = dataset_conditions(self.results, self.spec)
        stated = self.analysis.attrs.get("min_ok_runs")
        self.min_ok_runs = int(stated) if stated is not None else FALLBACK_MIN_OK_RUNS
        self.min_ok_source = ("analysis.nc, min_ok_runs" if stated is not None
                              else "the report's default; this analysis.nc states no minimum")
        self._figures = 0
        self._tables = 0

    def figure(self, key: str, caption: str, png: bytes) -> Figure:
        self._figures += 1
        return Figure(self._figures, key, caption, png)

    def table(self, caption: str, header, rows, muted=()) -> Table:
        self._tables += 1
        return Table(self._tables, caption, tuple(header), tuple(tuple(r) for r in rows), tuple(muted))

    def parameter_counts(self, names: bool = True) -> str:
        """``38 sampled values, of which 36 vary from run to run (2 constant: a, b)``."""
        text = f"{len(self.parameters)} sampled value(s), of which {len(self.varying)} vary from run to run"
        if not self.constant:
            return text
        return text + (f" ({len(self.constant)} constant by their distribution: {', '.join(self.constant)})" if names
                       else f" ({len(self.constant)} constant)")

    def n_used(self, dataset: str, feature: str) -> int:
        return int(self.analysis["n_used"].sel(dataset=dataset, feature=feature))

    def insufficient(self, dataset: str, feature: str) -> str | None:
        """Why a data set's statistics of a feature rest on too few runs (None when they do not).

        The analysis decides (``data_sufficient``); an older analysis without it is judged
        against ``min_ok_runs`` or the report's stated default.
        """
        n = self.n_used(dataset, feature)
        if "data_sufficient" in self.analysis:
            if int(self.analysis["data_sufficient"].sel(dataset=dataset, feature=feature)):
                return None
        elif n >= self.min_ok_runs:
            return None
        return f"insufficient data: {n} ok run(s) < {self.min_ok_runs}"

    def true_of(self, feature: str) -> str | None:
        """The true-signal counterpart of a measured feature, if the campaign stored one."""
        name = feature + "_true"
        return name if name in self.features else None

    def used_mask(self, feature: str, dataset: str) -> np.ndarray:
        """The runs of a data set that the statistics use (status ok, finite feature), as in :mod:`campaigns.analysis`."""
        row = self.results.sel(dataset=dataset)
        return (row["status"].values == "ok") & np.isfinite(row[feature].values.astype(float))

    def used(self, feature: str, dataset: str) -> np.ndarray:
        """Feature values of the runs the statistics use."""
        return self.results[feature].sel(dataset=dataset).values[self.used_mask(feature, dataset)]

    def pair(self, feature: str) -> list[str]:
        """A measured feature and, when stored, its true-signal counterpart."""
        true = self.true_of(feature)
        return [feature, true] if true else [feature]

    def feature_scale(self, feature: str) -> tuple[float, str]:
        """One display unit for a feature and its true counterpart, so their panels compare directly."""
        unit = self.results[feature].attrs.get("units", "")
        return display_scale(unit, np.concatenate([self.results[f].values.ravel() for f in self.pair(feature)]))

    def distribution_panels(self, feature: str, datasets: list[str]) -> list[Panel]:
        """Density panels of a feature (measured, then true signals) over the given data sets."""
        factor, unit = self.feature_scale(feature)
        pair = self.pair(feature)
        return [Panel(f"{f} ({kind})" if len(pair) > 1 else f, axis_label(f, unit), f"probability density [1/{unit}]",
                      tuple(Group(d, self.used(f, d) * factor, self.color[d]) for d in datasets))
                for f, kind in zip(pair, ("measured", "true signals"))]

    def describe(self, dataset: str) -> str:
        """``ds3 (backlash 0 µm, preload 0 kN, external force 4 kN)``: every condition that tells the data sets apart."""
        entry = next(d for d in self.spec["datasets"] if d["name"] == dataset)
        scene = entry.get("scene") or self.spec["base"]["scene"]
        parts = ([f"scene {scene}"] if scene != dataset else []) + ([self.conditions.label(dataset)] if self.conditions.shown else [])
        return f"{dataset} ({'; '.join(parts)})" if parts else dataset

    def label(self, name: str) -> str:
        """The stored long name of a variable (its name when it has none)."""
        return self.results[name].attrs.get("long_name", name) if name in self.results else name


def _solver(spec: dict) -> str:
    """The campaign's solver configuration in words (unset entries are the model's defaults)."""
    solver = spec.get("solver", {})
    return ", ".join(f"{k} = {'model default' if v is None else v}" for k, v in solver.items()) or "model defaults"


def build(inputs: Inputs, generated_at: str) -> Report:
    """The report model of a campaign.

    Parameters
    ----------
    inputs : Inputs
        The loaded results, analysis and optional accuracy data.
    generated_at : str
        Timestamp recorded in the report.

    Returns
    -------
    Report
    """
    b = _Builder(inputs)
    executive = tuple(_executive(b))  # first, so its data-set table is Table 1
    sections = tuple(
        Section(key, SECTION_TITLES[key], tuple(make(b)))
        for key, make in (
            ("summary", _summary),
            ("distributions", _distributions),
            ("correlations", _correlations),
            ("scatter", _scatter),
            ("traces", _traces),
            ("observability", _observability),
            ("failures", _failures),
            ("speed", _speed),
            ("fidelity", _fidelity),
            ("control_robustness", control_robustness.blocks),
        )
    )
    status = b.results["status"].values
    facts = (
        ("Campaign", f"{b.spec['name']}: {b.spec.get('description') or '–'}"),
        ("Runs", f"{status.size} ({int((status == 'ok').sum())} succeeded, {int((status != 'ok').sum())} failed)"),
        ("Spec hash", b.results.attrs.get("spec_hash", "–")),
        ("Results created", b.results.attrs.get("date_created", "–")),
        ("Report generated", generated_at),
    )
    return Report(
        title=f"Monte Carlo campaign report: {b.spec['name']}",
        subtitle="BenchTwin, ball-screw test bench digital twin (Bertolino 2020, Sec. 9.4)",
        generated_at=generated_at,
        facts=facts,
        executive=executive,
        sections=sections,
    )


# --- Executive summary (page 1) ------------------------------------------------------------------


def _requirement(analysis) -> tuple[float, str]:
    """The requirement the observability verdict is about, as the analysis states it."""
    if "requirement" in analysis.attrs:
        return float(analysis.attrs["requirement"]), str(analysis.attrs.get("requirement_source", ""))
    if "minimum_detectable_backlash" in analysis:
        attrs = analysis["minimum_detectable_backlash"].attrs
        return float(attrs.get("requirement", BACKLASH_REQUIREMENT)), str(attrs.get("requirement_source", "Table 9.3"))
    return BACKLASH_REQUIREMENT, "Table 9.3"


def _verdicts(b: _Builder, link: str):
    """One callout per feature with the analysis's requirement statement, verbatim; never composed here."""
    a = b.analysis
    if "requirement_statement" not in a or "requirement_verdict" not in a:
        yield Callout("Requirement verdict: not available. This analysis.nc holds no requirement_verdict / "
                      "requirement_statement (written by an older analysis); re-run `twin campaign analyze` on the "
                      "results to obtain the verdict with its bounds and sample size.", "info", link)
        return
    for feature in [str(f) for f in a["feature"].values]:
        statement = str(a["requirement_statement"].sel(feature=feature).item())
        verdict = str(a["requirement_verdict"].sel(feature=feature).item())
        yield Callout(f"{feature}: {statement}", VERDICT_TONES.get(verdict, "info"), link)


def _influences(b: _Builder, feature: str) -> str:
    """The strongest influences on a feature: effect sizes when the analysis has them, else |Spearman ρ| (labelled)."""
    a = b.analysis
    parameters = [str(p) for p in a["parameter"].values]
    sufficient = [d for d in b.datasets if b.insufficient(d, feature) is None]
    if not sufficient:
        return f"{feature}: insufficient data in every data set (fewer than {b.min_ok_runs} ok runs); no influence is ranked."
    unit = b.results[feature].attrs.get("units", "")
    if "effect_size" in a:
        effect = np.abs(a["effect_size"].sel(feature=feature, dataset=sufficient).transpose("parameter", "dataset").values)
        if "first_order_index_ci" in a:  # an index whose interval includes 0 is not an influence the data resolve
            lower = a["first_order_index_ci"].sel(feature=feature, dataset=sufficient, bound="lower")
            effect = np.where(lower.transpose("parameter", "dataset").values > 0.0, effect, np.nan)
        if not np.isfinite(effect).any():
            return (f"{feature}: no tolerance's first-order index is resolved above zero (95 % bootstrap interval) in any "
                    "data set: the spread is not explained by a sampled tolerance at this sample size.")
        best = np.nanargmax(np.where(np.isfinite(effect), effect, -np.inf), axis=1)
        strength = np.array([effect[j, best[j]] for j in range(len(parameters))])
        items = []
        for j in _ranked(strength)[:SUMMARY_INFLUENCES]:
            dataset = sufficient[best[j]]
            text = f"{parameters[j]} moves it by {quantity(strength[j], unit)} in {dataset}"
            if "first_order_index" in a:
                s1 = a["first_order_index"].sel(feature=feature, dataset=dataset).values[j]
                bounds = (a["first_order_index_ci"].sel(feature=feature, dataset=dataset).values[j]
                          if "first_order_index_ci" in a else (math.nan, math.nan))
                text += f" (first-order index {number(s1, 2)} [{number(bounds[0], 2)}, {number(bounds[1], 2)}])"
            items.append(text + f", n = {b.n_used(dataset, feature)}")
        return f"{feature}: " + "; ".join(items) + "."
    rho = a["spearman"].sel(feature=feature, dataset=sufficient).transpose("parameter", "dataset").values
    magnitude = np.where(np.isfinite(rho), np.abs(rho), -np.inf)
    best = np.argmax(magnitude, axis=1)
    strength = np.array([magnitude[j, best[j]] if np.isfinite(magnitude[j, best[j]]) else np.nan for j in range(len(parameters))])
    items = []
    for j in _ranked(strength)[:SUMMARY_INFLUENCES]:
        dataset = sufficient[best[j]]
        lo, hi = a["spearman_ci"].sel(feature=feature, dataset=dataset).values[j]
        items.append(f"{parameters[j]} (ρ = {rho[j, best[j]]:+.2f} [{lo:+.2f}, {hi:+.2f}] in {dataset}, n = {b.n_used(dataset, feature)})")
    return (f"{feature}, strongest |Spearman ρ| (a rank correlation, not an effect size: this analysis.nc has no "
            "effect_size): " + "; ".join(items) + ".") if items else f"{feature}: no parameter with a finite correlation."


def _executive(b: _Builder):
    spec, results, a = b.spec, b.results, b.analysis
    status = results["status"].values
    requirement, source = _requirement(a)
    sweep = "sweep_point" in a.dims and a.sizes["sweep_point"] > 0
    yield Paragraph(
        f"Question. {spec.get('description') or spec['name']}. Can the bench tell the data sets' conditions apart with "
        f"{', '.join(b.features)} when {b.parameter_counts(names=False)} are drawn per run, which of them move the features most"
        + (f", and is the minimum detectable backlash within the {quantity(requirement, 'm')} requirement ({source})?"
           if sweep else "? (No observability sweep in the spec: no requirement verdict is sought.)")
    )
    yield from _verdicts(b, "observability")
    rows, muted = [], []
    for name in b.datasets:
        s = results["status"].sel(dataset=name).values
        reasons = [r for r in (b.insufficient(name, f) for f in b.measured) if r]
        used = min(b.n_used(name, f) for f in b.measured)
        rows.append((name, b.conditions.label(name) or "–", f"{used} of {s.size}", reasons[0] if reasons else "–"))
        muted.append(bool(reasons))
    common = b.conditions.common_text()
    yield b.table(
        "Data sets: the conditions that differ between them or from the base scene "
        f"'{spec['base']['scene']}'" + (f" (all share {common})" if common else "")
        + ("" if b.conditions.from_scene else "; read from the spec's overrides (results.nc stores no effective scene conditions)")
        + f", and the runs the statistics use (status ok, finite feature; at least {b.min_ok_runs} needed, {b.min_ok_source}).",
        ("Data set", "Conditions", "Runs used", "Data"), rows, muted,
    )
    for feature in b.measured:
        yield Callout(_influences(b, feature), "info", "correlations")
    n_failed = int((status != "ok").sum())
    yield Callout(f"Failures: {n_failed} of {status.size} runs failed" + (" (left out of every statistic)." if n_failed else "."),
                  "bad" if n_failed else "good", "failures")
    audit = str(results.attrs.get("fidelity_audit", "not recorded in results.nc"))
    tone = "good" if audit.startswith("passed") else "bad" if audit.startswith("FLAGGED") else "info"
    yield Callout(f"Fidelity audit (automatic model simplification against full fidelity): {audit}.", tone, "fidelity")


# --- Summary -----------------------------------------------------------------------------------


def _summary(b: _Builder):
    spec, results = b.spec, b.results
    status = results["status"].values
    n_failed = int((status != "ok").sum())
    yield Paragraph(
        f"Campaign '{spec['name']}' ran the model with parameter set '{spec['base']['parameters']}' on "
        f"{len(b.datasets)} data set(s) of {results.sizes['run']} runs each ({status.size} runs). "
        f"Each run drew {b.parameter_counts()} (Table 9.5 rows of the spec) and computed the "
        f"feature(s) {', '.join(b.features)}. Everything below is read from the stored files; no simulation was re-run."
    )
    yield Callout(
        f"{status.size - n_failed} of {status.size} runs succeeded; {n_failed} failed"
        + (" (see Failed runs)." if n_failed else "."),
        "bad" if n_failed else "good",
    )
    execution = spec.get("execution", {})
    traces = spec.get("traces", {})
    bootstrap = json.loads(b.analysis.attrs.get("bootstrap", "{}") or "{}")
    rows = [
        ("Campaign", spec["name"]),
        ("Description", spec.get("description") or "–"),
        ("Spec hash (SHA-256)", results.attrs.get("spec_hash", "–")),
        ("Parameter set", spec["base"]["parameters"]),
        ("Base scene", spec["base"]["scene"]),
        ("Features", ", ".join(b.features)),
        ("Runs per data set", str(results.sizes["run"])),
        ("Root seed", results.attrs.get("root_seed_entropy", str(spec.get("root_seed", "–")))),
        ("Seeding", results.attrs.get("seeding", "–")),
        ("Solver", _solver(spec)),
        ("Execution", ", ".join(f"{k} = {'adaptive' if v is None else v}" for k, v in execution.items()) or "–"),
        ("Traces kept", f"{traces.get('runs_per_dataset', 0)} run(s) per data set, decimated by {traces.get('decimation', 1)}: "
                        f"{', '.join(traces.get('variables', [])) or 'none'}"),
        ("Half-range sigmas", number(results.attrs.get("half_range_sigmas"))),
        ("Results created", results.attrs.get("date_created", "–")),
        ("Campaign elapsed time", f"{number(results.attrs['execution_wall_time'])} s for "
                                  f"{results.attrs.get('execution_executed_runs', '–')} runs on "
                                  f"{results.attrs.get('execution_workers', '–')} worker(s) (last invocation)"
         if "execution_wall_time" in results.attrs else "–"),
        ("Analysis", "computed in memory from results.nc (no analysis.nc given)" if b.inputs.analysis_computed else "analysis.nc"),
        ("Bootstrap", ", ".join(f"{k} = {v}" for k, v in bootstrap.items()) or "–"),
    ]
    rows += [(f"Input file ({f.role})", f"{f.name}, SHA-256 {f.sha256}") for f in b.inputs.files]
    yield b.table("Campaign specification, solver configuration and provenance.", ("Item", "Value"), rows)

    statuses = sorted(set(status.ravel().tolist()) - {"ok"})

    def counts(label: str, s: np.ndarray, w: np.ndarray) -> list[str]:
        return ([label, str(s.size), str(int((s == "ok").sum()))] + [str(int((s == st).sum())) for st in statuses]
                + [number(np.nanmedian(w)) if np.isfinite(w).any() else "–", number(np.nansum(w))])

    rows = [counts(b.describe(n), results["status"].sel(dataset=n).values, results["wall_time"].sel(dataset=n).values)
            for n in b.datasets]
    rows.append(counts("all", status, results["wall_time"].values))
    yield b.table(
        "Data sets (scene and conditions), runs per status and wall time. Wall time is machine dependent; "
        "the total is the sum over runs (the campaign's elapsed time is shorter when workers run in parallel).",
        ["Data set", "Runs", "ok"] + statuses + ["Median wall time per run [s]", "Total wall time [s]"],
        rows,
    )

    rows = []
    for name in b.parameters:
        dist = json.loads(results[name].attrs.get("distribution", "{}") or "{}")
        unit = results[name].attrs.get("units", "")
        shape = ", ".join(f"{key} {quantity(dist[key], unit)}" for key in ("nominal", "mean", "low", "high", "value") if key in dist)
        if "sigma" in dist:  # a lognormal's sigma is that of the logarithm, without unit
            shape += f", sigma {number(dist['sigma'])} (log)" if dist.get("kind") == "lognormal" else f", sigma {quantity(dist['sigma'], unit)}"
        rows.append((name, dist.get("kind", "–"), shape, dist.get("source") or "–"))
    yield b.table("Uncertain parameters (sampled per run) with their resolved distributions; the Source column quotes the spec.",
                  ("Parameter", "Distribution", "Values", "Source"), rows)

    versions = json.loads(results.attrs.get("package_versions", "{}") or "{}")
    yield b.table("Package versions recorded when the campaign ran.", ("Package", "Version"), sorted(versions.items()))


# --- Feature distributions -----------------------------------------------------------------------


def _distributions(b: _Builder):
    yield Paragraph(
        "Probability density of each feature over the successful runs of every data set: a histogram with a Gaussian "
        "kernel density estimate (Figs. 9.8 and 9.10 of the thesis). The measured feature (from the bench's sensors) "
        "is drawn beside the true-signal feature (from the model's states): their difference is what the "
        f"instrumentation adds. With more than {MAX_TRACES} data sets each gets its own row on a shared axis. "
        "Failed runs are left out."
    )
    for feature in b.measured:
        stacked = len(b.datasets) > MAX_TRACES
        yield b.figure(
            f"distribution-{feature}",
            f"{b.label(feature)}: "
            + ("measured (left) and from the true signals (right), " if b.true_of(feature) else "")
            + ("one row per data set, each row scaled to its own peak. " if stacked else "all data sets. ")
            + "Look at how far apart the data sets with and without backlash lie compared with the width of each "
            "distribution, and at the shift caused by preload or external force. Data sets: "
            + "; ".join(b.describe(d) for d in b.datasets) + ".",
            figures.distributions(b.distribution_panels(feature, b.datasets)),
        )
    rows, muted = [], []
    for name in b.datasets:
        for feature in b.features:
            f = b.analysis.sel(dataset=name, feature=feature)
            mean, std, unit = float(f["feature_mean"]), float(f["feature_std"]), b.results[feature].attrs.get("units", "")
            # a spread at round-off level is a constant feature, not a measurement of scatter
            spread = "0 (constant)" if std <= _ROUND_OFF * abs(mean) else quantity(std, unit)
            reason = b.insufficient(name, feature)
            rows.append((name, feature, str(int(f["n_used"])), quantity(mean, unit), spread, reason or "–"))
            muted.append(reason is not None)
    yield b.table("Mean and standard deviation of each feature over the runs used (status ok, finite feature); greyed "
                  "rows rest on too few runs.",
                  ("Data set", "Feature", "Runs used", "Mean", "Standard deviation", "Data"), rows, muted)


# --- Correlations ----------------------------------------------------------------------------------


def _ranked(values: np.ndarray) -> np.ndarray:
    """Indices of the finite entries, strongest magnitude first (ties in parameter order)."""
    finite = np.flatnonzero(np.isfinite(values))
    return finite[np.argsort(-np.abs(values[finite]), kind="stable")]


def _ranked_over_datasets(analysis, feature: str) -> np.ndarray:
    """Parameter indices by their largest |Spearman ρ| in any data set (parameters without one left out)."""
    rho = np.abs(analysis["spearman"].sel(feature=feature).transpose("parameter", "dataset").values)
    strongest = np.array([row[np.isfinite(row)].max() if np.isfinite(row).any() else np.nan for row in rho])
    return _ranked(strongest)


def _correlations(b: _Builder):
    a = b.analysis
    parameters = [str(p) for p in a["parameter"].values]
    bootstrap = json.loads(a.attrs.get("bootstrap", "{}") or "{}")
    yield Paragraph(
        "Spearman rank correlation between each feature and each sampled value, per data set, over the runs used. "
        f"Whiskers are {bootstrap.get('confidence', 0.95):.0%} percentile-bootstrap intervals "
        f"({bootstrap.get('n_boot', 'n')} resamples of the runs); diamonds are the partial rank correlation "
        "coefficients (PRCC: the dependence left after removing the other parameters' influence). The grey band "
        "holds correlations that independence would produce 95 % of the time with this many runs "
        "(±1.96/√(n−1)): a bar whose interval reaches into it is not established."
    )
    if not parameters:
        yield Callout("No sampled parameters: the spec has no uncertainties, so there is nothing to correlate.")
        return
    for feature in b.measured:
        for name in b.datasets:
            sel = a.sel(dataset=name, feature=feature)
            rho = sel["spearman"].values
            order = _ranked(rho)[:TORNADO_PARAMETERS]
            n = int(sel["n_used"])
            constant = [parameters[j] for j in np.flatnonzero(~np.isfinite(rho))]
            if len(order) == 0:
                reason = b.insufficient(name, feature)
                yield Callout(f"{feature}, data set {b.describe(name)}: " + (f"{reason} (minimum from {b.min_ok_source}); the "
                              "analysis computed no statistics." if reason else f"no correlation could be computed ({n} runs used)."),
                              "muted" if reason else "info")
                continue
            ci = sel["spearman_ci"]
            shown = len(order)
            reason = b.insufficient(name, feature)
            yield b.figure(
                f"tornado-{feature}-{name}",
                f"Correlation of {feature} with the sampled parameters, data set {b.describe(name)}, {n} runs; the "
                f"{shown} strongest by |ρ| of the {np.isfinite(rho).sum()} with a correlation ({b.parameter_counts(names=False)})."
                + (f" Greyed: {reason} (minimum from {b.min_ok_source}); with so few runs a correlation of ±1 arises by chance, so none of these bars is "
                   "a finding." if reason else
                   " The top bars are the tolerances that drive the spread of the feature; look for bars clear of the grey band.")
                + (f" Not shown (no correlation: constant, or no variance in this data set): {', '.join(constant)}." if constant else ""),
                figures.tornado(
                    [parameters[j] for j in order],
                    rho[order],
                    ci.sel(bound="lower").values[order],
                    ci.sel(bound="upper").values[order],
                    interval=f"{bootstrap.get('confidence', 0.95):.0%} bootstrap interval",
                    marker=("PRCC", sel["prcc"].values[order]),
                    band=_Z95 / math.sqrt(n - 1) if n > 1 else None,
                    xlabel=f"Spearman correlation with {feature} [–]",
                    title=f"{feature}, {name}",
                    muted=reason and f"insufficient data (n = {n})",
                ),
            )
    for feature in b.features:
        rho = a["spearman"].sel(feature=feature).transpose("parameter", "dataset").values.copy()
        thin = [d for d in b.datasets if b.insufficient(d, feature)]
        rho[:, [b.datasets.index(d) for d in thin]] = np.nan  # too few runs: left blank, not ranked
        ranked = _ranked(np.array([np.nanmax(np.abs(r)) if np.isfinite(r).any() else np.nan for r in rho]))
        order = ranked[:HEATMAP_PARAMETERS]
        if not len(order):
            continue
        left = len(ranked) - len(order)
        yield b.figure(
            f"heatmap-{feature}",
            f"Spearman correlation of {feature} with each parameter (rows, strongest first) in each data set (columns). "
            "Look for rows that stay strong across data sets (a tolerance that matters whatever the test) and for the "
            "data set whose column is palest (the test procedure least sensitive to the tolerances)."
            + (f" The {left} weakest parameters are not shown." if left > 0 else "")
            + (f" Blank columns marked 'n<{b.min_ok_runs}' ({', '.join(thin)}): insufficient data, fewer than "
               f"{b.min_ok_runs} ok runs." if thin else ""),
            figures.heatmap(rho[order], [parameters[j] for j in order],
                            [f"{d}\nn<{b.min_ok_runs}" if d in thin else d for d in b.datasets], colorbar_label="Spearman ρ [–]",
                            xlabel="data set", ylabel="sampled parameter", vmin=-1.0, vmax=1.0, cmap="RdBu_r", center=0.0),
        )
    rows, muted = [], []
    for feature in b.measured:
        for name in b.datasets:
            sel = a.sel(dataset=name, feature=feature)
            reason = b.insufficient(name, feature)
            for rank, j in enumerate(_ranked(sel["spearman"].values)[:3], start=1):
                lo, hi = sel["spearman_ci"].values[j]
                prcc = sel["prcc"].values[j]
                rows.append((feature, name, str(rank), parameters[j], f"{sel['spearman'].values[j]:+.2f} [{lo:+.2f}, {hi:+.2f}]",
                             number(prcc, 2) if np.isfinite(prcc) or sel["n_used"] > len(b.varying) + 1
                             else f"– (needs more than {len(b.varying) + 1} ok runs: one per varying parameter, plus one)",
                             reason or "–"))
                muted.append(reason is not None)
            if reason and not np.isfinite(sel["spearman"].values).any():
                rows.append((feature, name, "–", "–", "–", "–", reason))
                muted.append(True)
    yield b.table("The three strongest parameters per data set: Spearman ρ with its bootstrap interval, and PRCC; "
                  "greyed rows rest on too few runs and are not findings.",
                  ("Feature", "Data set", "Rank", "Parameter", "Spearman ρ [interval]", "PRCC", "Data"), rows, muted)
    if "first_order_index" in a and "effect_size" in a:
        yield from _sensitivity_table(b, parameters)


def _sensitivity_table(b: _Builder, parameters: list[str]):
    """The three largest first-order indices per data set with their intervals and effect sizes (analysis.nc)."""
    a = b.analysis
    method = a["first_order_index"].attrs.get("method", "given-data first-order index")
    yield Paragraph(
        f"Rank correlations cannot see a tolerance whose effect is not monotone (a V-shaped dependence has ρ ≈ 0), and "
        f"a strong ρ may belong to a negligible effect. The first-order index ({method}) is the share of the feature's "
        "variance a tolerance explains alone, monotone or not; the effect size is how much it moves the feature (the "
        "standard deviation of the feature's conditional mean over the tolerance's range). An index whose interval "
        "includes 0 is not resolved by this many runs."
    )
    rows, muted = [], []
    for feature in b.measured:
        unit = b.results[feature].attrs.get("units", "")
        for name in b.datasets:
            sel = a.sel(dataset=name, feature=feature)
            reason = b.insufficient(name, feature)
            index = sel["first_order_index"].values
            for j in _ranked(index)[:3]:
                lo, hi = sel["first_order_index_ci"].values[j]
                rows.append((feature, name, parameters[j], f"{index[j]:.2f} [{lo:.2f}, {hi:.2f}]",
                             quantity(float(sel["effect_size"].values[j]), unit),
                             f"{sel['spearman'].values[j]:+.2f}", "yes" if lo > 0 else "no (interval includes 0)",
                             reason or "–"))
                muted.append(reason is not None or not lo > 0)
            if reason and not np.isfinite(index).any():
                rows.append((feature, name, "–", "–", "–", "–", "–", reason))
                muted.append(True)
    yield b.table("The three largest first-order indices per data set, with their bootstrap intervals, the effect size "
                  "and Spearman ρ beside them; greyed rows are not resolved or rest on too few runs.",
                  ("Feature", "Data set", "Parameter", "First-order index [interval]", "Effect size", "Spearman ρ",
                   "Resolved", "Data"), rows, muted)


# --- Scatter plots -----------------------------------------------------------------------------------


def _scatter(b: _Builder):
    a = b.analysis
    parameters = [str(p) for p in a["parameter"].values]
    yield Paragraph(
        "The feature against its top-ranked parameters (largest |Spearman ρ| in any data set). Each data set's mean is "
        "subtracted from its feature values, so data sets with different backlash share one axis and the dependence "
        "within a data set is visible."
    )
    for feature in b.measured:
        factor, unit = b.feature_scale(feature)
        top = [parameters[j] for j in _ranked_over_datasets(a, feature)[:SCATTER_PARAMETERS]]
        if not top:
            yield Callout(f"{feature}: no parameter with a finite correlation, nothing to plot.")
            continue
        panels = []
        for parameter in top:
            values = b.results[parameter]
            p_factor, p_unit = display_scale(values.attrs.get("units", ""), values.values)
            points = []
            for name in b.datasets:
                mask = b.used_mask(feature, name)
                if mask.any():
                    y = b.results[feature].sel(dataset=name).values[mask]
                    x = b.results[parameter].sel(dataset=name).values[mask]
                    points.append(Line(name, x * p_factor, (y - y.mean()) * factor, b.color[name]))
            panels.append(Panel(parameter, axis_label(parameter, p_unit), axis_label(f"{feature} − data-set mean", unit), tuple(points)))
        yield b.figure(
            f"scatter-{feature}",
            f"{feature} (minus its data-set mean) against its {len(top)} top-ranked parameters, one colour per data set. "
            "A clear slope means the tolerance moves the feature; compare the vertical spread it explains with the "
            "backlash to be detected.",
            figures.scatter(panels),
        )


# --- Traces --------------------------------------------------------------------------------------------


def _trace_run(b: _Builder, dataset: str, variables: list[str]) -> int | None:
    """The first kept trace of a successful run with data (else of any run with data)."""
    results = b.results
    runs = [int(r) for r in results["trace_run"].values]
    has_data = [r for r in runs if any(np.isfinite(results[v].sel(dataset=dataset, trace_run=r).values).any() for v in variables)]
    ok = [r for r in has_data if results["status"].sel(dataset=dataset, run=r).item() == "ok"]
    return (ok or has_data or [None])[0]


def _trace_line(b: _Builder, variable: str, dataset: str, run: int, style: str, color: str, factor: float) -> Line:
    values = b.results[f"trace_{variable}"].sel(dataset=dataset, trace_run=run).values * factor
    return Line(variable.replace("_", " "), b.results["trace_time"].values, values, color, style)


def _traces(b: _Builder):
    stored = [str(v).removeprefix("trace_") for v in b.results.data_vars if str(v).startswith("trace_")]
    if not stored or "trace_time" not in b.results.coords:
        yield Callout("Not available: results.nc holds no traces (set [traces] in the campaign spec to keep some).")
        return
    yield Paragraph(
        "Signals of single runs, decimated as stored in results.nc (Figs. 9.6, 9.7, 9.11 and 9.12 of the thesis): one "
        "figure per data set from its first successful traced run, then the nut-minus-screw position of every data set."
    )
    derived = NUT in stored and SCREW in stored
    groups = [(title, quantity_name, [v for v in variables if v in stored]) for title, quantity_name, variables in TRACE_PANELS]
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
            factor, shown = display_scale(unit, np.concatenate([b.results[f"trace_{v}"].values.ravel() for v in variables]))
            lines = tuple(_trace_line(b, v, name, run, ("-", "--", ":", "-.")[k % 4], f"C{k}", factor) for k, v in enumerate(variables))
            complete = len(variables) == len(next((v for t, _, v in TRACE_PANELS if t == title), variables))
            # a panel's title names only what it draws: a partial group is titled by its signals
            panels.append(Panel(title if complete else ", ".join(line.label for line in lines).capitalize(), "time [s]",
                                axis_label(quantity_name, shown), lines))
            if derived and title.startswith("Position"):
                panels.append(_nut_minus_screw_panel(b, [(name, run)]))
        status = b.results["status"].sel(dataset=name, run=run).item()
        yield b.figure(f"traces-{name}", f"Run {run} of data set {b.describe(name)} (status {status}). " + _drawn(panels),
                       figures.time_series(panels))
    if derived:
        pairs = [(name, _trace_run(b, name, [f"trace_{NUT}", f"trace_{SCREW}"])) for name in b.datasets]
        panels = [_nut_minus_screw_panel(b, [(n, r)], title=b.describe(n)) for n, r in pairs if r is not None]
        yield b.figure(
            "traces-nut-minus-screw",
            "Nut position minus the screw's equivalent position (the integrand of Eq. 9.12, Fig. 9.11) for one run of each "
            "data set, one panel per data set on a shared axis. Look at the gap between data sets with and without "
            "backlash at motion reversals.",
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


def _nut_minus_screw_panel(b: _Builder, runs: list[tuple[str, int]], title: str = "Nut minus screw equivalent position") -> Panel:
    time = b.results["trace_time"].values
    differences = {name: (b.results[f"trace_{NUT}"] - b.results[f"trace_{SCREW}"]).sel(dataset=name, trace_run=run).values
                   for name, run in runs}
    factor, unit = display_scale("m", np.concatenate(list(differences.values())))
    lines = tuple(Line(name if len(runs) > 1 else "x_n1 − p·θ_s/2π", time, d * factor, b.color[name]) for name, d in differences.items())
    return Panel(title, "time [s]", axis_label("x_n1 − p·θ_s/2π", unit), lines)


# --- Observability -------------------------------------------------------------------------------------


def _observability(b: _Builder):
    a = b.analysis
    fa = float(a.attrs.get("false_alarm_rate", 0.05))
    power = float(a.attrs.get("detection_power", 0.95))
    yield Paragraph(
        f"Separation between data sets: the detection probability is the fraction of a data set's runs beyond the "
        f"threshold that flags {fa:.0%} of a reference data set's runs (false alarms); the overlap coefficient is the "
        "shared area of the two feature histograms (1: indistinguishable, 0: disjoint)."
    )
    for feature in b.measured:
        detection = a["detection_probability"].sel(feature=feature).transpose("dataset", "reference").values
        yield b.figure(
            f"separation-{feature}",
            f"Detection probability of {feature}: runs of the row data set flagged by a threshold set on the column data set "
            f"at a {fa:.0%} false-alarm rate. Cells near 1 mean the bench tells the two conditions apart; compare the data sets "
            "with backlash (rows) against those without (columns).",
            figures.heatmap(detection, b.datasets, b.datasets, colorbar_label="detection probability [–]",
                            xlabel="reference data set (threshold)", ylabel="tested data set", vmin=0.0, vmax=1.0, cmap="viridis"),
        )
        overlap = a["overlap"].sel(feature=feature).transpose("dataset", "reference").values
        yield b.figure(
            f"overlap-{feature}",
            f"Overlap coefficient of the {feature} distributions of each pair of data sets. Low values (dark) mean "
            "well-separated distributions; the diagonal is 1 by definition.",
            figures.heatmap(overlap, b.datasets, b.datasets, colorbar_label="overlap coefficient [–]",
                            xlabel="data set", ylabel="data set", vmin=0.0, vmax=1.0, cmap="magma"),
        )
    yield Heading("Minimum detectable backlash")
    # the verdict is the analysis's sentence, verbatim (with its bounds and n); the report adds only facts of the curve
    yield from _verdicts(b, "")
    if "sweep_backlash" not in a or "minimum_detectable_backlash" not in a:
        yield Callout("Not available: the campaign spec has no observability sweep ([observability] sweep), so the "
                      "minimum detectable backlash cannot be compared with the 1 µm requirement.")
        return
    sweep = [str(s) for s in a["sweep_point"].values]
    backlash = a["sweep_backlash"].values
    requirement, source = _requirement(a)
    factor, unit = display_scale("m", [requirement])
    yield Paragraph(
        f"Along the sweep {', '.join(sweep)} (data sets differing only in backlash: "
        f"{', '.join(quantity(x, 'm') for x in backlash)}), the detection probability against the zero-backlash data set "
        f"is interpolated linearly to where it reaches {power:.0%}: the minimum detectable backlash."
    )
    minimum = {f: float(a["minimum_detectable_backlash"].sel(feature=f)) for f in b.features}
    probability = {f: a["sweep_detection_probability"].sel(feature=f).values for f in b.features}
    for feature in b.features:
        if not math.isfinite(minimum[feature]):
            yield Callout(f"{feature}: the detection probability never reaches {power:.0%} along the sweep.", "info")
    if (backlash > 0).any():
        smallest = int(np.flatnonzero(backlash == backlash[backlash > 0].min())[0])
        bounded = [f for f in b.features if probability[f][smallest] >= power]
        if bounded:
            yield Paragraph(
                f"For {', '.join(bounded)} the smallest non-zero level of the sweep ({quantity(backlash[smallest], 'm')}) is "
                "already detected, so the minimum detectable backlash is an upper bound from the interpolation between "
                "0 and that level. Add data sets with backlash near the requirement to resolve it."
            )
    curves = [Line(f, backlash * factor, probability[f], f"C{k}", "-" if k == 0 else "--") for k, f in enumerate(b.features)]
    minima = [(f"{f}: minimum detectable {number(minimum[f] * factor)} {unit}", minimum[f] * factor, f"C{k}")
              for k, f in enumerate(b.features)]
    yield b.figure(
        "detection-sweep",
        f"Detection probability against backlash along the sweep, per feature. Where a curve crosses the {power:.0%} line "
        f"(star) is the minimum detectable backlash, the green line the requirement; the verdict above also weighs the "
        f"bootstrap bounds of the star's position.",
        figures.detection(curves, power=power, false_alarm_rate=fa,
                          requirement=(f"requirement {number(requirement * factor)} {unit} ({source.split(':')[0]})", requirement * factor),
                          minima=minima, xlabel=axis_label("backlash", unit)),
    )
    for feature in b.measured:
        yield b.figure(
            f"sweep-distribution-{feature}",
            f"{feature} for the sweep data sets (Fig. 9.10 style). The smallest backlash whose distribution clears the "
            "zero-backlash one is what the bench can observe.",
            figures.distributions(b.distribution_panels(feature, sweep)),
        )


# --- Failed runs ---------------------------------------------------------------------------------------


def _failures(b: _Builder):
    results = b.results
    status = results["status"].values
    failed = np.argwhere(status != "ok")
    if len(failed) == 0:
        yield Callout("Every run succeeded: no failed runs.", "good")
        return
    yield Callout(f"{len(failed)} of {status.size} runs failed. They are left out of every statistic above.", "bad")
    groups: dict[tuple[str, str, str], list[int]] = {}
    for d, r in failed:
        key = (b.datasets[d], str(status[d, r]), str(results["failure_reason"].values[d, r]))
        groups.setdefault(key, []).append(int(results["run"].values[r]))
    rows = []
    for (name, st, reason), runs in groups.items():
        listed = ", ".join(map(str, runs[:LISTED_RUNS])) + (f" and {len(runs) - LISTED_RUNS} more" if len(runs) > LISTED_RUNS else "")
        rows.append((name, st, str(len(runs)), listed, reason or "–"))
    yield b.table("Failed runs grouped by data set, status and reason (run indices within the data set).",
                  ("Data set", "Status", "Count", "Runs", "Reason"), rows)
    meanings = json.loads(results["status"].attrs.get("flag_meanings", "{}") or "{}")
    present = sorted({str(s) for s in status.ravel()} - {"ok"})
    yield b.table("What each status means.", ("Status", "Meaning"), [(s, meanings.get(s, "–")) for s in present])


# --- Speed and accuracy ----------------------------------------------------------------------------------


def _speed(b: _Builder):
    study = b.inputs.accuracy
    if study is None:
        yield Callout("Speed-versus-accuracy chart and solver statistics: not available (no work-precision study was given; "
                      "run `twin accuracy --out DIR` and pass DIR/work_precision.nc).")
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
            runs = np.flatnonzero([p == panel and str(m) == method for p, m in zip(panels_of, study["method"].values)])
            good = runs[ok[runs] & (error[runs] > 0)]  # a log axis cannot show an exact zero
            if len(good):
                good = good[np.argsort(study["wall_time"].values[good])]
                label = method + (" (rtol ladder)" if adaptive[good].all() else "")
                lines.append(Line(label, study["wall_time"].values[good], error[good] * factor, f"C{k % 10}", "-"))
            if len(runs):
                best = runs[ok[runs]]
                rows.append((panel.replace("_", " ") or "–", method, f"{len(best)} of {len(runs)}",
                             number(study["wall_time"].values[best].min()) if len(best) else "–",
                             quantity(np.nanmin(error[best]), "m") if len(best) and np.isfinite(error[best]).any() else "–"))
        panels.append(Panel(panel.replace("_", " "), "wall time of one run [s]", axis_label("backlash-feature error", unit), tuple(lines)))
    yield b.figure(
        "speed-accuracy",
        f"Work-precision study of scene '{study.attrs.get('scene', '?')}' ({study.attrs.get('duration', '?')} s): error of "
        f"the backlash feature against the reference ({study.attrs.get('reference', '?')}) versus the wall time of one run, "
        f"per solver method. Configurations to the lower left are both fast and accurate; the campaign ran with {_solver(b.spec)}.",
        figures.work_precision(panels),
    )
    yield b.table("Solver methods of the study: successful runs, fastest run and smallest backlash-feature error.",
                  ("Panel", "Method", "Runs ok", "Fastest run [s]", "Smallest feature error"), rows)
    yield b.table("Study configuration, machine and the reference solver's statistics, as stored with the study.",
                  ("Item", "Value"), [(k, v if isinstance(v, str) else number(v, 4)) for k, v in study.attrs.items()])


# --- Fidelity -------------------------------------------------------------------------------------------


#: One feature's line of a ``fidelity_audit_<data set>`` attribute (campaigns.fidelity_audit.summary_attrs).
_AUDIT_LINE = re.compile(r"(?P<feature>\w+): mean shift (?P<shift>[-+0-9.e]+) um, max paired (?P<paired>[-+0-9.e]+) um, "
                         r"MC error (?P<error>[-+0-9.e]+) um, KS p (?P<p>[-+0-9.e]+|nan) -> (?P<verdict>\w+)")


def _microns(text: str) -> str:
    """An audit figure as stored (µm, four decimals), in one unit down the column."""
    return f"{text} µm" if text not in ("nan", "") else "–"


def _fidelity(b: _Builder):
    attrs = {k: str(v) for k, v in b.results.attrs.items() if k.startswith("fidelity")}
    if not attrs:
        yield Callout("No fidelity configuration or audit is recorded in results.nc (no attribute named fidelity*).")
        return
    requested = attrs.pop("fidelity_requested", "").strip('"') or "–"
    audit = attrs.pop("fidelity_audit", "not recorded")
    runs = attrs.pop("fidelity_audit_runs", None)
    yield Paragraph(
        f"The campaign asked for fidelity '{requested}': with 'auto' each subsystem of the twin runs at the cheapest level "
        "the scene and its outputs allow (twin/fidelity/rules.toml). The audit re-runs the first "
        + (f"{runs} " if runs else "")
        + "runs of every data set at full fidelity with the same parameters and noise and compares the features: a data "
        "set passes when every feature's paired mean shift is below the tolerance and a two-sample Kolmogorov-Smirnov "
        "test does not reject."
    )
    tone = "good" if audit.startswith("passed") else "bad" if audit.startswith("FLAGGED") else "info"
    yield Callout(f"Audit result: {audit}.", tone)
    configured = [(d, attrs.pop(f"fidelity_{d}")) for d in b.datasets if f"fidelity_{d}" in attrs]
    if configured:
        yield b.table("Subsystem levels the automatic choice used, per data set (subsystem = level).",
                      ("Data set", "Subsystem levels"), [(d, level.replace("=", " = ")) for d, level in configured])
    rows, speedups = [], []
    for d in b.datasets:
        text = attrs.pop(f"fidelity_audit_{d}", None)
        if text is None:
            continue
        speedup = re.search(r"speedup x([-+0-9.e]+|nan)", text)
        lines = list(_AUDIT_LINE.finditer(text))
        if not lines:  # a format this report does not know: shown as stored, in µm
            rows.append((d, "–", text.replace(" um", " µm"), "", "", "", "", ""))
            continue
        for k, m in enumerate(lines):
            shown_speedup = f"{float(speedup.group(1)):.2f}" if speedup and k == 0 else ""
            if speedup and k == 0:
                speedups.append(float(speedup.group(1)))
            rows.append((d, m["feature"], _microns(m["shift"]), _microns(m["paired"]), _microns(m["error"]), m["p"],
                         "pass" if m["verdict"] == "pass" else "flagged: rule to fix", shown_speedup))
    if rows:
        yield b.table(
            "Automatic against full fidelity on the same runs: paired mean shift of the feature, largest paired difference, "
            "Monte Carlo error of the mean (1.96 σ/√N), KS p-value, result, and speedup = full-fidelity wall time / "
            "automatic wall time over the paired runs.",
            ("Data set", "Feature", "Mean shift", "Largest paired difference", "Monte Carlo error", "KS p", "Result", "Speedup"),
            rows,
        )
        slower = [x for x in speedups if x < 1]
        yield Paragraph(
            "Speedup above 1: the automatic choice ran faster than full fidelity. "
            + (f"Here {len(slower)} of {len(speedups)} data sets show a speedup below 1, i.e. the automatic runs took longer. "
               "The audit times the first runs of each data set, which on freshly started workers include loading the "
               "compiled model, and wall time depends on the machine's load; it says nothing about accuracy, which the "
               "mean-shift and KS columns judge." if slower else
               "Wall time depends on the machine's load and on the first runs' start-up; it says nothing about accuracy.")
        )
    if attrs:
        yield b.table("Other fidelity attributes recorded in results.nc.", ("Attribute", "Value"),
                      [(k, v.replace(" um", " µm")) for k, v in attrs.items()])
