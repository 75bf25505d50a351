"""The executive summary (page 1): the verdicts of the requirements and the strongest influences."""

from __future__ import annotations

import math

import numpy as np

from campaigns.analysis import BACKLASH_REQUIREMENT
from reports.builder import SUMMARY_INFLUENCES, VERDICT_TONES, Builder, statement_tone
from reports.model import Callout, Paragraph
from reports.sections.correlations import rank_order
from reports.sections.fidelity import AUTO_INTEGRATOR
from reports.units import number, quantity


def backlash_requirement(analysis) -> tuple[float, str]:
    """The requirement the observability verdict is about, as the analysis states it."""
    if "requirement" in analysis.attrs:
        return float(analysis.attrs["requirement"]), str(analysis.attrs.get("requirement_source", ""))
    if "minimum_detectable_backlash" in analysis:
        attrs = analysis["minimum_detectable_backlash"].attrs
        return float(attrs.get("requirement", BACKLASH_REQUIREMENT)), str(attrs.get("requirement_source", "Table 9.3"))
    return BACKLASH_REQUIREMENT, "Table 9.3"


def verdicts(b: Builder, link: str):
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


#: Control-limit statements quoted on page 1 before "and N more"; the section lists all of them.
QUOTED_LIMITS = 3


def control_robustness(analysis) -> Callout:
    """One callout on the loop margins: how many design-limit checks have each verdict, and the statements
    of those that are not met (or, when none is "not met", of those left undetermined), verbatim."""
    if "margin_limit_verdict" not in analysis:
        return Callout("Control robustness: this campaign's runs carry no loop margins (no bench loops were "
                       "linearised), so no design limit is checked.", "info", "control_robustness")
    verdict = [str(v) for v in analysis["margin_limit_verdict"].values]
    statement = [str(s) for s in analysis["margin_limit_statement"].values]
    counts = ", ".join(f"{verdict.count(v)} {v}" for v in ("met", "not met", "undetermined", "insufficient data")
                       if verdict.count(v))
    worst = "not met" if "not met" in verdict else "undetermined" if "undetermined" in verdict else None
    text = (f"Control robustness (loop margins of every run against the design limits): {len(verdict)} checks: "
            f"{counts}.")
    if worst:
        quoted = [s for v, s in zip(verdict, statement, strict=True) if v == worst]
        text += " " + " ".join(f"{s}." for s in quoted[:QUOTED_LIMITS])
        if len(quoted) > QUOTED_LIMITS:
            text += f" And {len(quoted) - QUOTED_LIMITS} more {worst}."
    tone = "bad" if worst == "not met" else "good" if set(verdict) == {"met"} else "info"
    return Callout(text, tone, "control_robustness")


def _influences(b: Builder, feature: str) -> str:
    """The strongest influences on a feature: effect sizes when the analysis has them, else |Spearman ρ| (labelled)."""
    a = b.analysis
    parameters = [str(p) for p in a["parameter"].values]
    sufficient = [d for d in b.datasets if b.insufficient(d, feature) is None]
    if not sufficient:
        return (f"{feature}: insufficient data in every data set (fewer than {b.min_ok_runs} ok runs); "
                "no influence is ranked.")
    unit = b.results[feature].attrs.get("units", "")
    if "effect_size" in a:
        effect = np.abs(
            a["effect_size"].sel(feature=feature, dataset=sufficient).transpose("parameter", "dataset").values)
        if "first_order_index_ci" in a:  # an index whose interval includes 0 is not an influence the data resolve
            lower = a["first_order_index_ci"].sel(feature=feature, dataset=sufficient, bound="lower")
            effect = np.where(lower.transpose("parameter", "dataset").values > 0.0, effect, np.nan)
        if not np.isfinite(effect).any():
            return (f"{feature}: no tolerance's first-order index is resolved above zero (95 % bootstrap interval) "
                    "in any data set: the spread is not explained by a sampled tolerance at this sample size.")
        best = np.nanargmax(np.where(np.isfinite(effect), effect, -np.inf), axis=1)
        strength = np.array([effect[j, best[j]] for j in range(len(parameters))])
        items = []
        for j in rank_order(strength)[:SUMMARY_INFLUENCES]:
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
    strength = np.array([magnitude[j, best[j]] if np.isfinite(magnitude[j, best[j]]) else np.nan
                         for j in range(len(parameters))])
    items = []
    for j in rank_order(strength)[:SUMMARY_INFLUENCES]:
        dataset = sufficient[best[j]]
        lo, hi = a["spearman_ci"].sel(feature=feature, dataset=dataset).values[j]
        items.append(
            f"{parameters[j]} (ρ = {rho[j, best[j]]:+.2f} [{lo:+.2f}, {hi:+.2f}] in {dataset}, "
            f"n = {b.n_used(dataset, feature)})")
    return ((f"{feature}, strongest |Spearman ρ| (a rank correlation, not an effect size: this analysis.nc has no "
             "effect_size): " + "; ".join(items) + ".") if items
            else f"{feature}: no parameter with a finite correlation.")


def build(b: Builder):
    spec, results, a = b.spec, b.results, b.analysis
    status = results["status"].values
    requirement, source = backlash_requirement(a)
    sweep = "sweep_point" in a.dims and a.sizes["sweep_point"] > 0
    yield Paragraph(
        f"Question. {spec.get('description') or spec['name']}. Can the bench tell the data sets' conditions apart with "
        f"{', '.join(b.features)} when {b.parameter_counts(names=False)} are drawn per run, "
        "which of them move the features most"
        + (f", and is the minimum detectable backlash within the {quantity(requirement, 'm')} requirement ({source})?"
           if sweep else "? (No observability sweep in the spec: no requirement verdict is sought.)")
    )
    yield from verdicts(b, "observability")
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
        + ("" if b.conditions.from_scene
           else "; read from the spec's overrides (results.nc stores no effective scene conditions)")
        + f", and the runs the statistics use (status ok, finite feature; at least {b.min_ok_runs} needed, "
          f"{b.min_ok_source}).",
        ("Data set", "Conditions", "Runs used", "Data"), rows, muted,
    )
    for feature in b.measured:
        yield Callout(_influences(b, feature), "info", "correlations")
    n_failed = int((status != "ok").sum())
    yield Callout(f"Failures: {n_failed} of {status.size} runs failed"
                  + (" (left out of every statistic)." if n_failed else "."),
                  "bad" if n_failed else "good", "failures")
    yield control_robustness(a)
    audit = str(results.attrs.get("fidelity_audit", "not recorded in results.nc"))
    checked = ("automatic model simplification and integrator against full fidelity with RK4"
               if (b.spec.get("solver") or {}).get("integrator") == AUTO_INTEGRATOR
               else "automatic model simplification against full fidelity")
    yield Callout(f"Fidelity audit ({checked}): {audit}.", statement_tone(audit), "fidelity")
