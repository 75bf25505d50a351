"""The tables of docs/findings.md, printed from a campaign's results.nc and analysis.nc.

Every number of docs/findings.md comes from the stored files through this script, so the document can
be regenerated after the model changes instead of being edited by hand:

    .venv/bin/python scripts/findings_tables.py out/thesis/results.nc [--analysis out/thesis/analysis.nc]

Prints Markdown: the feature statistics per data set (mean with its 95 % confidence interval, standard
deviation, n), the dominant tolerances per data set (given-data first-order index with its bootstrap
interval and the effect size in µm, beside Spearman and PRCC; the interval alone where the analysis withheld the
index), the separation of the data sets, and the observability verdicts verbatim from analysis.nc (a sweep level
the analysis does not resolve is given as the bracket of sweep levels it states, never an interpolated number).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
import xarray as xr
from scipy import stats

TOP_TOLERANCES = 3


def um(value: float, digits: int = 2) -> str:
    return "–" if not math.isfinite(value) else f"{value * 1e6:.{digits}f}"


def in_units(value: float, units: str, digits: int = 2) -> str:
    """A feature value: in µm for a length (units "m"), else in the feature's own units, e.g. N m."""
    if units == "m":
        return um(value, digits)
    return "–" if not math.isfinite(value) else f"{value:.{digits + 2}g} {units}"


def mean_interval(mean: float, std: float, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Student-t confidence interval of the mean of ``n`` runs."""
    if n < 2 or not math.isfinite(std):
        return math.nan, math.nan
    half = stats.t.ppf(0.5 + confidence / 2, n - 1) * std / math.sqrt(n)
    return mean - half, mean + half


def feature_table(results: xr.Dataset, analysis: xr.Dataset) -> None:
    features = [str(f) for f in analysis.feature.values]
    print("| data set | conditions | feature | n ok | mean [µm] (95 % CI) | std [µm] |")
    print("|---|---|---|---|---|---|")
    conditions = json.loads(results.attrs.get("dataset_conditions", "{}") or "{}")
    spec = json.loads(results.attrs["spec_json"])["spec"]
    overrides = {d["name"]: d.get("conditions", {}) for d in spec["datasets"]}
    for name in (str(d) for d in analysis.dataset.values):
        stated = conditions.get(name) or overrides.get(name, {})
        label = ", ".join(f"{k} {v['value'] if isinstance(v, dict) else v}" for k, v in stated.items()
                          if k in ("backlash", "preload", "external_force_peak", "zero_procedure", "cylinder"))
        for feature in features:
            row = analysis.sel(dataset=name, feature=feature)
            n, mean, std = int(row.n_used), float(row.feature_mean), float(row.feature_std)
            low, high = mean_interval(mean, std, n)
            units = str(results[feature].attrs.get("units", "m")) if feature in results else "m"
            print(f"| {name} | {label} | {feature} | {n} | {in_units(mean, units)} ({in_units(low, units)} – "
                  f"{in_units(high, units)}) | {in_units(std, units, 3)} |")
            label = ""


def tolerance_table(results: xr.Dataset, analysis: xr.Dataset) -> None:
    """The three tolerances per data set whose first-order index has the largest lower bound. An index the analysis
    withheld (``first_order_index_flag``: too few runs, or the estimate outside its own interval) is printed as its
    interval only, with the reason; so is its effect size."""
    if "first_order_index" not in analysis:
        print("(no first-order indices in this analysis)")
        return
    measured = [str(f) for f in analysis.feature.values if not str(f).endswith("_true")]
    floor = int(analysis.attrs.get("first_order_min_runs", 0))
    print("| data set | feature | tolerance | first-order index (95 % CI) | effect size [µm] | Spearman | PRCC |")
    print("|---|---|---|---|---|---|---|")
    for name in (str(d) for d in analysis.dataset.values):
        for feature in measured:
            row = analysis.sel(dataset=name, feature=feature)
            lower = row.first_order_index_ci.sel(bound="lower").values
            if not np.isfinite(lower).any():
                print(f"| {name} | {feature} | (insufficient data) | | | | |")
                continue
            units = str(results[feature].attrs.get("units", "m")) if feature in results else "m"
            flags = row.first_order_index_flag.values if "first_order_index_flag" in row else np.zeros(len(lower))
            for k in np.argsort(-np.nan_to_num(lower, nan=-np.inf), kind="stable")[:TOP_TOLERANCES]:
                p = row.isel(parameter=k)
                low, high = (float(v) for v in p.first_order_index_ci.values)
                interval = f"({low:.2f} – {high:.2f})"
                why = withheld(int(flags[k]), int(row.n_used), floor)
                index = f"– {interval}, interval only: {why}" if why else f"{float(p.first_order_index):.2f} {interval}"
                effect = (f"({in_units(float(p.effect_size_ci[0]), units, 3)} – "
                          f"{in_units(float(p.effect_size_ci[1]), units, 3)})" if why
                          else in_units(float(p.effect_size), units, 3))
                print(f"| {name} | {feature} | {str(p.parameter.values)} | {index} | {effect} | "
                      f"{float(p.spearman):+.2f} | {float(p.prcc):+.2f} |")


def withheld(flag: int, n: int, floor: int) -> str:
    """Why the analysis withheld a first-order index, from its flag bits (empty: it did not)."""
    reasons = ([f"{n} ok runs < {floor}"] if flag & 1 else []) + (
        ["the estimate fell outside its own interval"] if flag & 2 else [])
    return "; ".join(reasons)


def separation_table(analysis: xr.Dataset) -> None:
    names = [str(d) for d in analysis.dataset.values]
    for feature in (str(f) for f in analysis.feature.values if not str(f).endswith("_true")):
        print(f"\nDetection probability of `{feature}` (row flagged against a threshold at the "
              f"{float(analysis.attrs.get('false_alarm_rate', 0.05)):.0%} false-alarm rate of the column):\n")
        print("| | " + " | ".join(names) + " |")
        print("|---|" + "---|" * len(names))
        p = analysis.detection_probability.sel(feature=feature)
        for a in names:
            print(f"| {a} | " + " | ".join(f"{float(p.sel(dataset=a, reference=b)):.2f}" for b in names) + " |")


def observability(analysis: xr.Dataset) -> None:
    if "requirement_statement" not in analysis:
        print("(no observability sweep in this campaign)")
        return
    if "sweep_point" in analysis.dims:
        points = [str(s) for s in analysis.sweep_point.values]
        if "sweep_backlash" in analysis:
            levels = [f"{um(float(b), 1)} µm" for b in analysis.sweep_backlash.values]
        else:  # another swept quantity, e.g. the preload loss of preload_loss.toml
            # the swept quantity is the one sweep_ variable indexed by the sweep point alone
            swept = next(v for v in analysis.data_vars
                         if str(v).startswith("sweep_") and analysis[v].dims == ("sweep_point",))
            levels = [f"{float(b):g} {analysis.attrs.get('requirement_units', '')}".strip()
                      for b in analysis[swept].values]
        print("| feature | " + " | ".join(f"{p} ({level})" for p, level in zip(points, levels, strict=False)) + " |")
        print("|---|" + "---|" * len(points))
        for feature in (str(f) for f in analysis.feature.values):
            probability = analysis.sweep_detection_probability.sel(feature=feature).values
            print(f"| {feature} | " + " | ".join(f"{v:.2f}" for v in probability) + " |")
    print()
    for feature in (str(f) for f in analysis.feature.values):
        print(f"- `{feature}`: {str(analysis.requirement_statement.sel(feature=feature).values)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path)
    parser.add_argument("--analysis", type=Path, help="default: analysis.nc beside the results")
    args = parser.parse_args()
    results = xr.load_dataset(args.results)
    analysis = xr.load_dataset(args.analysis or args.results.with_name("analysis.nc"))
    print(f"<!-- {results.attrs['campaign']}: spec hash {results.attrs['spec_hash'][:16]}, root seed "
          f"{results.attrs.get('root_seed_entropy')}, {results.sizes['run']} runs per data set -->\n")
    print("### Feature per data set\n")
    feature_table(results, analysis)
    print("\n### Dominant tolerances\n")
    tolerance_table(results, analysis)
    print("\n### Separation\n")
    separation_table(analysis)
    print("\n### Observability\n")
    observability(analysis)


if __name__ == "__main__":
    main()
