"""The executive summary (page 1): a decision per requirement in plain words, then what it rests on.

Every decision is read from ``analysis.nc`` (the verdicts are computed once, in
:mod:`campaigns.analysis.campaign_analysis` and
:mod:`campaigns.analysis.margins`); this module only puts their numbers into words:

* GO: the requirement is met (its 95 % bound is within it); NO-GO: not met (its 95 % bound is beyond it);
  UNDETERMINED: the bounds straddle the requirement, the runs cannot tell yet, with the runs that would decide it
  (``runs_to_decide``, ``margin_limit_runs_to_decide``) or why no number of runs would; NO DATA: too few runs.
* One line per requirement: the minimum detectable fault size per measured feature (the ideal-sensor reading beside
  it) for each fault sweep of the spec (backlash, preload loss), the features its ``[[observability]]`` table names
  alone (every feature when it names none), and each design limit of the loop margins over every loop; then each
  sweep's detection figure.

Then the comparison with another design and the measured tests (when given), the data sets, the strongest influences,
the failures, the model check, and a glossary of the terms used.
"""

from __future__ import annotations

import json
import math

import numpy as np

from campaigns.analysis.campaign_analysis import mean_text
from campaigns.analysis.vocabulary import marked_features
from campaigns.statistics.paired_comparison import worst_verdict
from campaigns.workflows.diagnosis import p_text
from reports.builder import SUMMARY_INFLUENCES, Builder
from reports.detection import backlash_requirement, detection_answer, minimum_detectable, sweep_views, swept
from reports.model import Callout, Paragraph
from reports.outline import title
from reports.phrases import NO_VERDICT, REANALYZE, decision, feature_words, plain_name, statement_tone, tone
from reports.ranking import rank_order
from reports.units import quantity, quantity_range

#: Design limits in words: limit -> (what, unit symbol, comparison words).
LIMIT_WORDS = {
    "phase_margin": ("Phase margin at least {value:g}°", "below it"),
    "gain_margin": ("Gain margin at least {value:g} dB", "below it"),
    "peak_sensitivity": ("Peak sensitivity |S|max at most {value:g}", "above it"),
}
#: Terms a page-1 reader meets, and what they mean.
GLOSSARY = {
    "GO / NO-GO / UNDETERMINED / NO DATA": "the requirement is met / not met at 95 % confidence; the runs cannot tell "
                                           "yet (the bounds straddle it); too few runs for any verdict",
    "95 % bounds": "the range that holds the true value with 95 % confidence given the runs (bootstrap or exact "
                   "binomial)",
    "backlash feature f_b": "mean over the test of |nut position − screw position| at each 1 ms sample (Eq. 9.12, "
                            "Bertolino 2020), from the linear encoder and the torque-meter encoder",
    "backlash hysteresis": "mean nut-minus-screw position while the screw moves back minus while it moves forward: "
                           "grows with the backlash, independent of where the encoders were zeroed",
    "ideal sensors": "the same feature from the simulated true positions instead of the encoders' readings: what a "
                     "perfect instrument would give",
    "sweep, sweep level": "data sets that differ only in the fault size (e.g. backlash 0, 5, 40, 80 µm), each a level",
    "detection probability": "share of a faulty data set's runs beyond the threshold that flags 5 % of the fault-free "
                             "runs (a 5 % false-alarm rate)",
    "minimum detectable backlash": "the smallest backlash detected in 95 % of runs; its bounds are sweep levels "
                                   "(between two levels the campaign has no runs)",
    "runs used": "runs that ended normally with a finite feature; the statistics use only these",
    "first-order index": "share of a feature's variance that one tolerance explains alone (0 to 1); its effect size "
                         "is how far that tolerance alone moves the feature; below 200 runs only its interval is given",
    "phase margin, gain margin, |S|max": "how far a control loop is from instability (larger margins, smaller "
                                         "|S|max are safer), computed at each run's sampled parameters",
    "model check (fidelity audit)": "runs repeated with the full model to check the automatic simplification",
}




def within_unit_decision(b: Builder, feature: str) -> Callout | None:
    """The within-unit decision of a campaign with ``[units]``: the analysis's verdict and statement, verbatim, on
    the line after the between-unit decision (``None`` for other campaigns)."""
    a = b.analysis
    if "within_unit_requirement_statement" not in a:
        return None
    verdict = str(a["within_unit_requirement_verdict"].sel(feature=feature).item())
    statement = str(a["within_unit_requirement_statement"].sel(feature=feature).item())
    return Callout(f"{decision(verdict)} — within unit (the same unit tested as it wears), "
                   f"{feature_words(b.results, feature)}: {statement}", tone(verdict), "observability")




def _runs_text(runs: float, reason: str, n: int) -> str:
    if math.isfinite(runs):
        return f"About {runs:.0f} ok runs per sweep data set (now {n}) would decide it if the estimate holds."
    if math.isinf(runs):
        return f"It would take {reason}."
    return reason[:1].upper() + reason[1:] + "." if reason else ""


def observability_decision(b: Builder, feature: str, analysis=None) -> Callout:
    """The decision on the detection requirement with one measured feature (the ideal-sensor reading beside it), along
    the sweep ``analysis`` is the view of (:func:`reports.detection.sweep_views`; the first sweep by default)."""
    a = b.analysis if analysis is None else analysis
    requirement, source = backlash_requirement(a)
    quantity_name, unit, scale, shown = swept(a)

    def fault(value: float) -> str:  # in the fault quantity's own unit (µm for a backlash), as the analysis says it
        return f"{value * scale:.3g} {shown}" if math.isfinite(value) else "–"

    verdict = str(a["requirement_verdict"].sel(feature=feature).item())
    source_words = source.removeprefix("Bertolino (2020) ").split(":")[0]
    what = (f"Detect a {fault(requirement)} {quantity_name} ({source_words}) with "
            f"{feature_words(b.results, feature)}")
    bounds_name = minimum_detectable(quantity_name) + "_ci"
    lower, upper = ((float(v) for v in a[bounds_name].sel(feature=feature).values) if bounds_name in a
                    else (math.nan, math.nan))
    sweep = [str(s) for s in a["sweep_point"].values] if "sweep_point" in a.dims else []
    n = min((b.n_used(d, feature) for d in sweep if d in b.datasets), default=0)
    runs = float(a["runs_to_decide"].sel(feature=feature)) if "runs_to_decide" in a else math.nan
    reason = str(a["runs_to_decide_reason"].sel(feature=feature).item()) if "runs_to_decide_reason" in a else ""
    smallest = f"the smallest {quantity_name} detected in 95 % of runs"
    if verdict == "met":
        text = (f"{smallest.capitalize()} is at most {fault(upper)} (95 % bound), within the requirement; "
                f"{n} ok runs per sweep level.")
    elif verdict == "not met":
        text = (f"{smallest.capitalize()} is above {fault(lower)} (95 % bound: a level not detected), "
                f"beyond the requirement; {n} ok runs per sweep level.")
    elif verdict == "undetermined":
        upper_text = fault(upper) if math.isfinite(upper) else "beyond the sweep"
        text = (f"{smallest.capitalize()} lies between {fault(lower)} and {upper_text} (95 % bounds), "
                f"and the requirement lies between them: {n} runs per sweep level cannot tell yet. "
                + (_runs_text(runs, reason, n) if "runs_to_decide" in a else
                   f"This analysis.nc does not state the runs that would decide it ({REANALYZE})."))
    elif not sweep:
        text = "The spec has no observability sweep, so no detection verdict is sought."
    else:
        text = (f"{n} ok runs per sweep level; " + (f"{runs:.0f} are needed before any verdict."
                                                     if math.isfinite(runs) else "too few for any verdict."))
    text = f"{decision(verdict)} — {what}: {text}"
    true = b.true_of(feature)
    if true is not None and true in marked_features(a):
        true_verdict = str(a["requirement_verdict"].sel(feature=true).item())
        text += f" With ideal sensors: {decision(true_verdict)}."
    return Callout(text, tone(verdict), "observability")


def limit_decisions(analysis) -> list[Callout]:
    """One decision per design limit (phase margin, gain margin, |S|max) over every loop, from the analysis's
    ``margin_limit_*`` variables; the worst loop's numbers are the ones that decide."""
    if "margin_limit_verdict" not in analysis:
        return [Callout("Control robustness: this campaign's runs carry no loop margins (no bench loops were "
                        "linearised), so no design limit is checked.", "info", "control_robustness")]
    checks = [str(c) for c in analysis["limit_check"].values]
    limits = json.loads(analysis["margin_limit_verdict"].attrs.get("control_limits", "{}") or "{}")
    allowed = float(limits.get("max_fraction_beyond", 0.01))
    thresholds = {"phase_margin": limits.get("phase_margin_min", 30.0),
                  "gain_margin": limits.get("gain_margin_min", 6.0),
                  "peak_sensitivity": limits.get("peak_sensitivity_max", 2.0)}
    out = []
    for limit, (words, side) in LIMIT_WORDS.items():
        rows = [i for i, c in enumerate(checks) if c.endswith("_loop_" + limit)]
        if not rows:
            continue
        verdicts = [str(analysis["margin_limit_verdict"].values[i]) for i in rows]
        worst = worst_verdict(verdicts)
        loops = ", ".join(c.removesuffix("_loop_" + limit) for c in (checks[i] for i in rows))
        what = words.format(value=thresholds[limit]) + f" in every loop ({loops})"
        if not all(v in analysis for v in ("margin_limit_counts", "margin_limit_fraction", "margin_limit_fraction_ci")):
            pick = next(i for i, v in zip(rows, verdicts, strict=True) if v == worst)  # an older analysis: quote it
            out.append(Callout(f"{decision(worst)} — {what}: "
                               f"{analysis['margin_limit_statement'].values[pick]}.", tone(worst),
                               "control_robustness"))
            continue
        counts, fractions = analysis["margin_limit_counts"].values, analysis["margin_limit_fraction"].values
        pick = max((i for i, v in zip(rows, verdicts, strict=True) if v == worst),
                   key=lambda i: np.nan_to_num(fractions[i], nan=-1.0))
        loop = checks[pick].removesuffix("_loop_" + limit)
        k, n = int(counts[pick][0]), int(counts[pick][1])
        low, high = (float(v) for v in analysis["margin_limit_fraction_ci"].values[pick])
        runs = (float(analysis["margin_limit_runs_to_decide"].values[pick])
                if "margin_limit_runs_to_decide" in analysis else math.nan)
        share = f"{allowed * 100:g} % of runs allowed {side}"
        if worst == "met":
            worst_case = (f"no loop has a run {side} (of {n} runs each)" if k == 0
                          else f"the worst loop ({loop}) has {k} of {n} runs {side}")
            text = f"{worst_case}: the share {side} is under {high * 100:.2g} % at 95 % confidence ({share})."
        elif worst == "not met":
            text = (f"the {loop} loop has {k} of {n} runs {side} ({k / n * 100:.2g} %; at least {low * 100:.2g} % at "
                    f"95 % confidence, {share}).")
        elif worst == "undetermined":
            observed = (f"no run of {n} in the {loop} loop is {side}, but {n} runs show the share {side} only to be "
                        f"under {high * 100:.2g} % (95 % confidence), not under the {allowed * 100:g} % allowed"
                        if k == 0 else
                        f"{k} of {n} runs of the {loop} loop are {side}: the share {side} is {low * 100:.2g}–"
                        f"{high * 100:.2g} % (95 % confidence) and the {allowed * 100:g} % allowed lies inside")
            decides = "GO" if k / n < allowed else "NO-GO"
            more = (f"; about {runs:.0f} runs with the same share would decide {decides}" if math.isfinite(runs)
                    else "; no number of runs decides it at this share" if "margin_limit_runs_to_decide" in analysis
                    else "")
            text = observed + more + "."
        else:
            text = f"{n} runs with the margin; too few for any verdict."
        out.append(Callout(f"{decision(worst)} — {what}: {text}", tone(worst),
                           "control_robustness"))
    return out


def _influences(b: Builder, feature: str) -> str:
    """The strongest influences on a feature: effect sizes when the analysis has them (their intervals where the
    analysis withholds the index: ``first_order_index_flag``), else |Spearman ρ| (labelled)."""
    a = b.analysis
    parameters = [str(p) for p in a["parameter"].values]
    words = feature_words(b.results, feature)
    sufficient = [d for d in b.datasets if b.insufficient(d, feature) is None]
    if not sufficient:
        return (f"What moves {words}: insufficient data in every data set (fewer than {b.min_ok_runs} ok runs); "
                "no influence is ranked.")
    unit = b.results[feature].attrs.get("units", "")
    if "effect_size" in a:
        def values(name):
            return a[name].sel(feature=feature, dataset=sufficient).transpose("parameter", "dataset", ...).values

        effect = np.abs(values("effect_size"))
        effect_ci = values("effect_size_ci") if "effect_size_ci" in a else np.stack([effect, effect], axis=-1)
        index_ci = values("first_order_index_ci") if "first_order_index_ci" in a else None
        flags = values("first_order_index_flag") if "first_order_index_flag" in a else np.zeros(effect.shape, int)
        resolved = index_ci[..., 0] > 0.0 if index_ci is not None else np.isfinite(effect)
        # rank by what every row has: the lower bound of the effect size (the point where the index is resolved)
        strength = np.where(resolved, np.where(flags == 0, effect, effect_ci[..., 0]), np.nan)
        if not np.isfinite(strength).any():
            return (f"What moves {words}: no tolerance's first-order index is resolved above zero (95 % bootstrap "
                    "interval) in any data set: the spread is not explained by a sampled tolerance at this sample "
                    "size.")
        best = np.nanargmax(np.where(np.isfinite(strength), strength, -np.inf), axis=1)
        top = np.array([strength[j, best[j]] for j in range(len(parameters))])
        items = []
        for j in rank_order(top)[:SUMMARY_INFLUENCES]:
            d = best[j]
            dataset = sufficient[d]
            if flags[j, d]:
                text = (f"{plain_name(parameters[j])} moves it by {quantity_range(*effect_ci[j, d], unit)} in "
                        f"{dataset} (explains {index_ci[j, d, 0] * 100:.0f}–{index_ci[j, d, 1] * 100:.0f} % of its "
                        "variance; interval only: the index itself is not resolved at this sample size)")
            else:
                text = f"{plain_name(parameters[j])} moves it by {quantity(effect[j, d], unit)} in {dataset}"
                if index_ci is not None:
                    s1 = float(a["first_order_index"].sel(feature=feature, dataset=dataset).values[j])
                    text += (f" (explains {s1 * 100:.0f} % of its variance, 95 % interval "
                             f"{index_ci[j, d, 0] * 100:.0f}–{index_ci[j, d, 1] * 100:.0f} %)")
            items.append(text + f", n = {b.n_used(dataset, feature)}")
        return f"What moves {words} most: " + "; ".join(items) + "."
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
            f"{plain_name(parameters[j])} (ρ = {rho[j, best[j]]:+.2f} [{lo:+.2f}, {hi:+.2f}] in {dataset}, "
            f"n = {b.n_used(dataset, feature)})")
    return ((f"What moves {words}, by the strongest |Spearman ρ| (a rank correlation, not an effect size: this "
             "analysis.nc has no effect_size): " + "; ".join(items) + ".") if items
            else f"What moves {words}: no parameter with a finite correlation.")


def _asks(view) -> str:
    """``a backlash of 1 µm (Table 9.3)``: what one sweep asks the bench to detect."""
    requirement, source = backlash_requirement(view)
    quantity_name, unit, _, _ = swept(view)
    source = source.removeprefix("Bertolino (2020) ").split(":")[0]
    return f"a {quantity_name} of {quantity(requirement, unit)} ({source})"


def _question(b: Builder) -> str:
    spec = b.spec
    views = [view for _, view in sweep_views(b.analysis) if "sweep_point" in view.dims and view.sizes["sweep_point"]]
    n_sampled, n_varying = len(b.parameters), len(b.varying)
    asks = (f"can the bench detect {' and '.join(_asks(view) for view in views)} with its sensors"
            if views else "how do the data sets differ (the spec has no observability sweep, so no detection "
                          "requirement is judged)")
    return (f"What this campaign answers ({spec.get('description') or spec['name']}): {asks}, when "
            f"{n_varying} of {n_sampled} sampled tolerances and conditions vary from run to run as in the spec; "
            "which of them move the result most; and do the control loops keep their design margins?")


def _measured_cells(b: Builder) -> dict[str, str]:
    """The data-set table's "Measured test" cell of each data set: each test's placement there."""
    cells = {name: [] for name in b.datasets}
    for found in b.inputs.measured:
        headline = next((f for f in found.features if not f.endswith("_true")), found.features[0])
        for placement in found.placements[headline]:
            where = {"inside": "consistent", "above": "above its range", "below": "below its range",
                     "not judged": "not judged"}[placement.side()]
            cells[placement.dataset].append(f"{found.test}: {where} (percentile {placement.percentile * 100:.0f} %"
                                            + (f", {p_text(placement.p_value)})" if placement.judged else ")"))
    return {name: "; ".join(items) or "–" for name, items in cells.items()}


def _audit_summary(audit: str) -> str:
    """The fidelity audit's stored verdict with its list of ``dataset/feature`` pairs counted (the Fidelity section
    lists them): ``undetermined: ...: 9 data-set/feature pairs in ds2, ds6, ds7``."""
    head, _, tail = audit.rpartition(": ")
    items = [item.strip() for item in tail.split(",")]
    if not head or not items or not all("/" in item for item in items):
        return audit
    datasets = sorted({item.split("/")[0] for item in items})
    return (f"{head}: {len(items)} data-set/feature pair(s) in {', '.join(datasets)} (listed in the "
            f"{title('fidelity')} section)")


def build(b: Builder):
    a = b.analysis
    results = b.results
    yield Paragraph(_question(b))
    yield Paragraph("Decisions, one line per requirement (GO: met, NO-GO: not met, UNDETERMINED: the runs cannot tell "
                    "yet, with the runs that would decide it; each links to its section):")
    verdicts = "requirement_statement" in a and "requirement_verdict" in a
    if not verdicts:
        yield Callout(NO_VERDICT, "info", "observability")
    for key, view in sweep_views(a) if verdicts else ():
        for feature in (f for f in b.measured if f in marked_features(view)):  # the features the sweep is about
            yield observability_decision(b, feature, view)
            if not key and (within := within_unit_decision(b, feature)) is not None:
                yield within
        if (answer := detection_answer(view)) is not None:  # the answer in a picture, right below its decisions
            yield b.figure("detection-sweep" + key.replace("_", "-"), *reversed(answer))
    yield from limit_decisions(a)
    if b.inputs.comparison is not None:
        c = b.inputs.comparison
        sentence = c.sentence
        for feature in sorted(b.results.data_vars, key=len, reverse=True):  # the longest first: f_true before f
            if b.results[feature].attrs.get("role") == "feature":
                sentence = sentence.replace(f" is {feature} in ", f" is {feature_words(b.results, feature)} in ")
        changes = ", ".join(plain_name(p) for p in c.design_changes)
        yield Callout(sentence + (f" The designs differ in: {changes}." if changes else ""), "info", "comparison")
    for found in b.inputs.measured:
        healthy = any(f is not None and f.healthy for f in found.fault.values())
        verdict = found.verdict
        for feature in found.features:  # the feature in words, as everywhere on page 1
            verdict = verdict.replace(f"{feature} = ", f"{feature_words(b.results, feature)} = ")
        yield Callout(f"Measured test {found.test}: {verdict}.", "good" if healthy else "info", "measured")
    rows, muted = [], []
    cells = _measured_cells(b)
    headline = b.measured[0]
    for name in b.datasets:
        s = results["status"].sel(dataset=name).values
        reasons = [r for r in (b.insufficient(name, f) for f in b.measured) if r]
        used = min(b.n_used(name, f) for f in b.measured)
        rows.append((name, b.conditions.label(name) or "–", f"{used} of {s.size}" + (f" ({reasons[0]})" if reasons
                                                                                      else ""),
                     mean_text(a, name, headline) if "feature_mean" in a else "–", cells[name]))
        muted.append(bool(reasons))
    common = b.conditions.common_text()
    measured = ("; Measured test: where each measured test given to the report lies in the data set's runs "
                f"(§ {title('measured')})" if b.inputs.measured
                else "; Measured test: none given (`twin report RESULTS --measured TEST.nc` places a bench test "
                     "here)")
    yield b.table(
        "Data sets: the conditions that differ between them or from the base scene "
        f"'{b.spec['base']['scene']}'" + (f" (all share {common})" if common else "")
        + ("" if b.conditions.from_scene
           else "; read from the spec's overrides (results.nc stores no effective scene conditions)")
        + f"; the runs the statistics use (status ok, finite feature; at least {b.min_ok_runs} needed, "
          f"{b.min_ok_source}); the mean of {headline} with its 95 % Student t interval (given at any n; on a greyed "
          "row it rests on a normal shape so few runs cannot check)" + measured + ".",
        ("Data set", "Conditions", "Runs used", f"Mean of {headline}", "Measured test"), rows, muted,
    )
    for feature in b.measured:
        yield Callout(_influences(b, feature), "info", "correlations")
    status = results["status"].values
    n_failed = int((status != "ok").sum())
    yield Callout(f"Failures: {n_failed} of {status.size} runs failed"
                  + (" (left out of every statistic)." if n_failed else "."),
                  "bad" if n_failed else "good", "failures")
    audit = _audit_summary(str(results.attrs.get("fidelity_audit", "not recorded in results.nc")))
    yield Callout(f"Model check, fidelity audit (automatic model simplification against full fidelity): {audit}.",
                  statement_tone(audit), "fidelity")
    yield b.table("Terms used on this page.", ("Term", "Meaning"), list(GLOSSARY.items()))
