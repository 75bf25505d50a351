"""Fidelity audit: the automatic fidelity against the full model, over the same sampled runs.

A campaign runs at ``fidelity = "auto"`` by default: each subsystem of the twin at the
cheapest level its scene and outputs allow (``twin.fidelity``). The audit re-runs the
first ``N`` runs of every data set at full fidelity, with the same parameters and the
same noise (run ``i`` of data set ``d`` has the same seeds in both), and judges, per data set
and feature, the accuracy rule's paired part (:func:`campaigns.statistics.accuracy_rule.judge_accuracy`,
docs/accuracy.md): the 95 % Student-t interval of the mean shift auto - full within ±:data:`MEAN_SHIFT_TOLERANCE` and
the 95 % jackknife interval of the standard-deviation ratio auto / full within 1 ± 10 %; ``met`` when both are,
``not met`` when either interval lies wholly outside its tolerance, ``undetermined`` otherwise, ``insufficient
data`` below :data:`AUDIT_MIN_PAIRS` paired runs. The rule's other parts (200 paired runs, unchanged analysis
verdicts and sensitivity rankings) judge a default configuration (:mod:`campaigns.bench.solver_accuracy`), not a
campaign's few audit runs. The largest paired difference, the Monte Carlo error of the mean
(``1.96 sigma / sqrt(N)``) and the KS p-value are reported beside it (the KS test is no part of the
verdict: paired samples are not independent, and at ten runs it has no power), and so is the scene's numerical
sensitivity floor (``campaigns/bench/numerical_floor.toml``): how far single paired runs may differ with nothing wrong,
which the t interval already carries as spread.

The full-fidelity runs take the full model's default step (62.5 us: the screw's axial mode and the analog current
loop are back), so the audit judges the automatic levels and the step they allow together.

The verdict is a result, not an error: it is recorded in ``results.nc`` (``fidelity_audit*``
attributes, one statement per data set and feature, printed verbatim by the CLI and the report), and
a ``not met`` names the rule to fix (``twin/fidelity/rules.toml``).
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import xarray as xr

from campaigns.runner.execution import run_campaign
from campaigns.runner.runs import RunModel
from campaigns.runner.spec import CampaignSpec, FidelityAudit, Observability, Traces
from campaigns.runner.storage import write_netcdf
from campaigns.statistics.accuracy_rule import MEAN_SHIFT_TOLERANCE, SD_RATIO_TOLERANCE, judge_accuracy
from campaigns.statistics.paired_comparison import VERDICTS, compare_features, worst_verdict
from twin.scenes import list_scenes, load_scene

#: Fewest paired runs for an audit verdict: the fewest at which the sd ratio's jackknife interval was simulated.
#: At 5-10 pairs its coverage is below the nominal 95 % when paired differences take two outcomes (docs/accuracy.md,
#: "Why these numbers"): an audit's sd verdict is a screen, not the rule. The rule's 200 pairs accept a default
#: configuration, not a campaign's few audit runs.
AUDIT_MIN_PAIRS = 5
#: Per built-in scene and feature, the spread of tight runs that differ only in their step or by picometres [m]
#: (benchmarks/numerical_floor.py; docs/accuracy.md, "What the tight reference can and cannot tell").
NUMERICAL_FLOOR_FILE = Path(__file__).with_name("numerical_floor.toml")


#: Units and long names of the figures of :func:`campaigns.statistics.paired_comparison.compare_features` in the
#: audit's file.
_COMPARISON_META = {
    "mean_shift": ("m", "mean of the feature, auto - full, over the paired ok runs"),
    "sigma_shift": ("m", "standard deviation of the feature, auto - full"),
    "max_paired_difference": ("m", "largest |auto - full| of a paired run"),
    "sampling_error": ("m", "Monte Carlo error of the mean: 1.96 sigma / sqrt(n)"),
    "ks_distance": ("1", "Kolmogorov-Smirnov distance between the auto and full samples"),
    "ks_pvalue": ("1", "Kolmogorov-Smirnov p-value (not part of the verdict)"),
    "n": ("1", "paired ok runs"),
}


def has_automatic_choice(spec: CampaignSpec) -> bool:
    """Whether the spec leaves the fidelity levels to the automatic choice the audit checks (anything but
    ``"full"``)."""
    return spec.solver.fidelity != "full"


def full_fidelity_variant(spec: CampaignSpec, runs: int) -> CampaignSpec:
    """The spec's first ``runs`` runs of every data set at full fidelity (with the full model's default step unless
    the spec names one), without traces or audit."""
    solver = {"fidelity": "full"}
    return spec.model_copy(update={
        "name": f"{spec.name}_full_fidelity",
        "runs_per_dataset": runs,
        "solver": spec.solver.model_copy(update=solver),
        "traces": Traces(),
        "observability": Observability(),
        "fidelity_audit": FidelityAudit(runs=0),
    })


def numerical_floors(spec: CampaignSpec, features: list[str]) -> dict[tuple[str, str], float]:
    """``{(data set, feature): floor [m]}`` for the data sets that run a built-in scene whose floor was measured
    (``campaigns/bench/numerical_floor.toml``) with the scene's own conditions; the others have none (0 in the
    audit)."""
    with NUMERICAL_FLOOR_FILE.open("rb") as handle:
        table = tomllib.load(handle)
    floors = {}
    for dataset in spec.datasets:
        name = dataset.scene or spec.base.scene
        if name not in table or name not in list_scenes():
            continue
        scene = load_scene(name)
        if dataset.procedure or any(scene.conditions.get(k) != v for k, v in dataset.conditions.items()):
            continue  # another procedure or other conditions than those measured: the floor is not known
        floors.update({(dataset.name, f): float(table[name][f]) for f in features if f in table[name]})
    return floors


def compare_fidelity(auto: xr.Dataset, full: xr.Dataset, features: list[str],
                     floors: Mapping[tuple[str, str], float] | None = None) -> xr.Dataset:
    """Per data set and feature: the :func:`campaigns.statistics.paired_comparison.compare_features` figures of the
    auto runs against their full-fidelity twins, the rule's verdict (``verdict``, ``statement``, the mean shift's
    interval ``shift_lower``/``shift_upper``, the sd ratio with its interval), the scene's ``numerical_floor``
    (context, no part of the verdict) and the wall-time speedup."""
    floors = floors or {}
    runs = full.sizes["run"]
    paired = auto.isel(run=slice(0, runs))
    per_feature = [compare_features(paired, full, f).expand_dims(feature=[f]) for f in features]
    audit = xr.concat(per_feature, dim="feature").transpose("dataset", "feature")
    # the module's tolerance passed at call time: what the audit states is what it judged
    judged = judge_accuracy(paired, full, features, min_pairs=AUDIT_MIN_PAIRS, mean_tolerance=MEAN_SHIFT_TOLERANCE)
    interval = "95 % Student-t interval of the paired mean shift auto - full"
    for name, source, attrs in (
        ("verdict", "verdict", {"long_name": "audit verdict: " + " / ".join(VERDICTS)}),
        ("statement", "statement", {"long_name": "the verdict with the numbers it rests on (printed verbatim)"}),
        ("shift_lower", "mean_shift_lower", {"units": "m", "long_name": f"{interval}, lower"}),
        ("shift_upper", "mean_shift_upper", {"units": "m", "long_name": f"{interval}, upper"}),
        ("sd_ratio", "sd_ratio", {"units": "1", "long_name": "standard deviation ratio auto / full"}),
        ("sd_ratio_lower", "sd_ratio_lower", {"units": "1", "long_name": "95 % jackknife interval of sd_ratio, lower"}),
        ("sd_ratio_upper", "sd_ratio_upper", {"units": "1", "long_name": "95 % jackknife interval of sd_ratio, upper"}),
    ):
        audit[name] = judged[source].transpose("dataset", "feature").assign_attrs(attrs)
    cells = [(d, f) for d in audit.dataset.values for f in features]
    floor = np.array([floors.get((str(d), f), 0.0) for d, f in cells]).reshape(audit.sizes["dataset"], len(features))
    audit["numerical_floor"] = (("dataset", "feature"), floor,
                                {"units": "m", "long_name": "numerical sensitivity floor of the scene (0: not "
                                                            "measured): how far single paired runs may differ; not "
                                                            "part of the verdict"})
    both = (paired.status == "ok") & (full.status == "ok")
    audit["speedup"] = full.wall_time.where(both).sum("run") / paired.wall_time.where(both).sum("run")
    audit["speedup"].attrs.update(units="1", long_name="full-fidelity wall time / auto wall time over the paired runs")
    # campaigns.statistics.paired_comparison's figures, described for CF
    for name, (unit, long_name) in _COMPARISON_META.items():
        if name in audit:
            audit[name].attrs = {"units": audit[name].attrs.get("units", unit), "long_name": long_name}
    audit.attrs.update(runs=runs, mean_shift_tolerance=MEAN_SHIFT_TOLERANCE, sd_ratio_tolerance=SD_RATIO_TOLERANCE,
                       min_paired_runs=AUDIT_MIN_PAIRS, verdict=overall_verdict(audit))
    return audit


def overall_verdict(audit: xr.Dataset) -> str:
    """The campaign's audit in one line: the worst verdict
    (:func:`campaigns.statistics.paired_comparison.worst_verdict`) and the data set/feature pairs that have it."""
    cells = {(d, f): audit.verdict.sel(dataset=d, feature=f).item()
             for d in audit.dataset.values for f in audit.feature.values}
    worst = worst_verdict(cells.values())
    meaning = {"met": "auto is within the tolerances of full fidelity on every data set and feature (mean shift, "
                      "standard deviation)",
               "not met": "auto differs from full fidelity (the fidelity rule to fix)",
               "undetermined": "the audit's runs cannot resolve the tolerances",
               "insufficient data": "too few paired runs"}[worst]
    named = [f"{d}/{f}" for (d, f), v in cells.items() if v == worst]
    return f"{worst}: {meaning}" + ("" if worst == "met" else f": {', '.join(named)}")


def summary_attrs(audit: xr.Dataset) -> dict[str, str]:
    """``fidelity_audit*`` attributes for ``results.nc`` (what the CLI and the report's Fidelity section print):
    per data set, the speedup and per feature its statement, largest paired difference, MC error and KS p-value,
    features separated by `` | ``."""
    attrs = {"fidelity_audit_runs": str(audit.attrs["runs"])}
    for name in audit.dataset.values:
        lines = []
        for feature in audit.feature.values:
            row = audit.sel(dataset=name, feature=feature)
            lines.append(f"{feature}: {row.statement.item()}; max paired "
                         f"{float(row.max_paired_difference) * 1e6:.4f} µm, MC error "
                         f"{float(row.sampling_error) * 1e6:.4f} µm, KS p {float(row.ks_pvalue):.2f}")
        speedup = float(audit.speedup.sel(dataset=name))
        attrs[f"fidelity_audit_{name}"] = f"speedup x{speedup:.2f}; " + " | ".join(lines)
    attrs["fidelity_audit"] = audit.attrs["verdict"]
    return attrs


def audit_campaign(results_path: Path, spec: CampaignSpec, run_model: RunModel, **run_options) -> xr.Dataset | None:
    """Run the full-fidelity twin of the campaign's first runs with ``run_model``, compare, and record the audit in
    ``results.nc``. Returns the audit (also written as ``fidelity_audit.nc``), or None when there is
    nothing to audit (audit off, full fidelity already, or a model that reports no fidelity).

    ``run_options`` are those of :func:`campaigns.runner.execution.run_campaign` (workers, scheduler, resume,
    progress, allow_version_mix, announce); the audit's runs are a campaign of their own in
    ``results_path.parent / "fidelity_audit"``."""
    with xr.open_dataset(results_path) as handle:
        auto = handle.load()
    reported = any(k.startswith("fidelity_") and k != "fidelity_requested" for k in auto.attrs)
    runs = min(spec.fidelity_audit.runs, spec.runs_per_dataset)
    if runs < 2 or not has_automatic_choice(spec) or not reported:
        why = ("the campaign runs at full fidelity with a named integrator" if not has_automatic_choice(spec)
               else "the run function reports no fidelity" if not reported
               else f"fidelity_audit.runs = {spec.fidelity_audit.runs} with {spec.runs_per_dataset} run(s) "
                    "per data set; it needs 2 or more")
        _write_attrs(results_path, auto, {"fidelity_audit": f"not run ({why})"})
        return None
    out_dir = results_path.parent / "fidelity_audit"
    announce = run_options.get("announce") or (lambda stage, message: None)
    announce("fidelity audit", f"{spec.name}: re-running {runs * len(spec.datasets)} runs at full fidelity to check "
                               "the automatic choice")
    full_path = run_campaign(full_fidelity_variant(spec, runs), out_dir, run_function=run_model, **run_options)
    with xr.open_dataset(full_path) as handle:
        full = handle.load()
    audit = compare_fidelity(auto, full, list(spec.features), numerical_floors(spec, list(spec.features)))
    write_netcdf(audit, out_dir / "fidelity_audit.nc", title=f"BenchTwin fidelity audit of campaign {spec.name}",
                 history=f"fidelity audit of {runs} run(s) per data set: auto against full fidelity "
                         "(campaigns.bench.fidelity_audit)")
    _write_attrs(results_path, auto, summary_attrs(audit))
    return audit


def _write_attrs(path: Path, results: xr.Dataset, attrs: dict[str, str]) -> None:
    results.attrs.update(attrs)
    write_netcdf(results, path, title=str(results.attrs.get("title", "")),
                 history=f"fidelity_audit attributes recorded: {attrs.get('fidelity_audit', '')}")
