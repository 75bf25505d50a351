"""Section "Correlations": rank correlations, first-order indices and effect sizes of the parameters."""

from __future__ import annotations

import json
import math

import numpy as np

from reports import figures
from reports.builder import HEATMAP_PARAMETERS, TORNADO_PARAMETERS, Z95, Builder
from reports.model import Callout, Paragraph
from reports.phrases import INSUFFICIENT
from reports.ranking import largest_first, rank_order
from reports.units import number, quantity, quantity_range


def build(b: Builder):
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
            order = rank_order(rho)[:TORNADO_PARAMETERS]
            n = int(sel["n_used"])
            constant = [parameters[j] for j in np.flatnonzero(~np.isfinite(rho))]
            if len(order) == 0:
                reason = b.insufficient(name, feature)
                yield Callout(f"{feature}, data set {b.describe(name)}: "
                              + (f"{reason} (minimum from {b.min_ok_source}); the analysis computed no statistics."
                                 if reason else f"no correlation could be computed ({n} runs used)."),
                              "muted" if reason else "info")
                continue
            ci = sel["spearman_ci"]
            shown = len(order)
            reason = b.insufficient(name, feature)
            yield b.figure(
                f"tornado-{feature}-{name}",
                f"Correlation of {feature} with the sampled parameters, data set {b.describe(name)}, {n} runs; the "
                f"{shown} strongest by |ρ| of the {np.isfinite(rho).sum()} with a correlation "
                f"({b.parameter_counts(names=False)})."
                + (f" Greyed: {reason} (minimum from {b.min_ok_source}); with so few runs a correlation of ±1 arises "
                   "by chance, so none of these bars is a finding." if reason else
                   " The top bars are the tolerances that drive the spread of the feature; look for bars clear of the "
                   "grey band.")
                + (f" Not shown (no correlation: constant, or no variance in this data set): {', '.join(constant)}."
                   if constant else ""),
                figures.tornado(
                    [parameters[j] for j in order],
                    rho[order],
                    ci.sel(bound="lower").values[order],
                    ci.sel(bound="upper").values[order],
                    interval=f"{bootstrap.get('confidence', 0.95):.0%} bootstrap interval",
                    marker=("PRCC", sel["prcc"].values[order]),
                    band=Z95 / math.sqrt(n - 1) if n > 1 else None,
                    xlabel=f"Spearman correlation with {feature} [–]",
                    title=f"{feature}, {name}",
                    muted=reason and f"{INSUFFICIENT} (n = {n})",
                ),
            )
    for feature in b.features:
        rho = a["spearman"].sel(feature=feature).transpose("parameter", "dataset").values.copy()
        thin = [d for d in b.datasets if b.insufficient(d, feature)]
        rho[:, [b.datasets.index(d) for d in thin]] = np.nan  # too few runs: left blank, not ranked
        ranked = rank_order(np.array([np.nanmax(np.abs(r)) if np.isfinite(r).any() else np.nan for r in rho]))
        order = ranked[:HEATMAP_PARAMETERS]
        if not len(order):
            continue
        left = len(ranked) - len(order)
        yield b.figure(
            f"heatmap-{feature}",
            f"Spearman correlation of {feature} with each parameter (rows, strongest first) in each data set "
            "(columns). Look for rows that stay strong across data sets (a tolerance that matters whatever the test) "
            "and for the data set whose column is palest (the test procedure least sensitive to the tolerances)."
            + (f" The {left} weakest parameters are not shown." if left > 0 else "")
            + (f" Blank columns marked 'n<{b.min_ok_runs}' ({', '.join(thin)}): insufficient data, fewer than "
               f"{b.min_ok_runs} ok runs." if thin else ""),
            figures.heatmap(rho[order], [parameters[j] for j in order],
                            [f"{d}\nn<{b.min_ok_runs}" if d in thin else d for d in b.datasets],
                            colorbar_label="Spearman ρ [–]",
                            xlabel="data set", ylabel="sampled parameter", vmin=-1.0, vmax=1.0, cmap="RdBu_r",
                            center=0.0),
        )
    rows, muted = [], []
    for feature in b.measured:
        for name in b.datasets:
            sel = a.sel(dataset=name, feature=feature)
            reason = b.insufficient(name, feature)
            for rank, j in enumerate(rank_order(sel["spearman"].values)[:3], start=1):
                lo, hi = sel["spearman_ci"].values[j]
                prcc = sel["prcc"].values[j]
                rows.append((feature, name, str(rank), parameters[j],
                             f"{sel['spearman'].values[j]:+.2f} [{lo:+.2f}, {hi:+.2f}]",
                             number(prcc, 2) if np.isfinite(prcc) or sel["n_used"] > len(b.varying) + 1
                             else f"– (needs more than {len(b.varying) + 1} ok runs: one per varying parameter, "
                                  "plus one)",
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


def _sensitivity_table(b: Builder, parameters: list[str]):
    """The three tolerances with the largest first-order index per data set (analysis.nc): ranked by the lower bound of
    the index's interval, what the runs resolve; a withheld index (``first_order_index_flag``) shows its interval only,
    with the reason."""
    a = b.analysis
    method = a["first_order_index"].attrs.get("method", "given-data first-order index")
    floor = int(a.attrs.get("first_order_min_runs", a["first_order_index"].attrs.get("min_runs", 0)))
    yield Paragraph(
        f"Rank correlations cannot see a tolerance whose effect is not monotone (a V-shaped dependence has ρ ≈ 0), and "
        f"a strong ρ may belong to a negligible effect. The first-order index ({method}) is the share of the feature's "
        "variance a tolerance explains alone, monotone or not; the effect size is how much it moves the feature (the "
        "standard deviation of the feature's conditional mean over the tolerance's range). An index whose interval "
        "includes 0 is not resolved by this many runs."
        + (f" Below {floor} ok runs the index itself is not given, only its interval: with 38 tolerances that do "
           "nothing, the largest of their indices averages above 0.1 by chance alone there (docs/campaigns.md)."
           if floor else "")
    )
    rows, muted = [], []
    for feature in b.measured:
        unit = b.results[feature].attrs.get("units", "")
        for name in b.datasets:
            sel = a.sel(dataset=name, feature=feature)
            reason = b.insufficient(name, feature)
            index, bounds = sel["first_order_index"].values, sel["first_order_index_ci"].values
            flags = sel["first_order_index_flag"].values if "first_order_index_flag" in sel else np.zeros(len(index))
            for j in largest_first(bounds[:, 0])[:3]:
                lo, hi = bounds[j]
                withheld = _withheld(int(flags[j]), int(sel["n_used"]), floor)
                shown = (f"interval only: [{lo:.2f}, {hi:.2f}]" if withheld
                         else f"{index[j]:.2f} [{lo:.2f}, {hi:.2f}]")
                resolved = "yes" if lo > 0 else "no (interval includes 0)"
                effect_lo, effect_hi = (float(v) for v in sel["effect_size_ci"].values[j])
                effect = (f"[{quantity_range(effect_lo, effect_hi, unit, separator=', ')}]" if withheld
                          else quantity(float(sel["effect_size"].values[j]), unit))
                rows.append((feature, name, parameters[j], shown, effect,
                             f"{sel['spearman'].values[j]:+.2f}", resolved,
                             "; ".join(r for r in (reason, withheld) if r) or "–"))
                muted.append(reason is not None or not lo > 0 or bool(withheld))
            if reason and not np.isfinite(bounds).any():
                rows.append((feature, name, "–", "–", "–", "–", "–", reason))
                muted.append(True)
    yield b.table("The three tolerances per data set whose first-order index has the largest lower bound, with the "
                  "index and its bootstrap interval, the effect size and Spearman ρ beside them; greyed rows are not "
                  "resolved, rest on too few runs, or give the interval only (the Data column says why).",
                  ("Feature", "Data set", "Parameter", "First-order index [interval]", "Effect size", "Spearman ρ",
                   "Resolved", "Data"), rows, muted)


def _withheld(flag: int, n: int, floor: int) -> str | None:
    """Why the analysis withheld a first-order index (its ``first_order_index_flag`` bits), in words."""
    reasons = []
    if flag & 1:
        reasons.append(f"index withheld: {n} ok runs < {floor}")
    if flag & 2:
        reasons.append("index withheld: the estimate fell outside its own bootstrap interval")
    return "; ".join(reasons) or None
