"""Fidelity audit: the automatic fidelity against the full model, over the same sampled runs.

A campaign runs at ``fidelity = "auto"`` by default: each subsystem of the twin at the
cheapest level its scene and outputs allow (``twin.fidelity``), where that level measurably pays, and one set of
levels along each fault sweep (:func:`campaigns.bench.campaign.sweep_fidelity`). A data set whose runs all took the
full model's levels (:func:`simplified_datasets`, from the levels each run recorded) runs the same model with the same
step as a full-fidelity run, so its audit pairs would be identical bit for bit: it is **not re-run**, and it is
recorded as ``met`` with the statement "identical: the automatic choice is the full model" (``basis = "identical"``
in ``fidelity_audit.nc``). The audit re-runs the data sets the automatic choice simplifies, with the same parameters
and the same noise (run ``i`` of data set ``d`` has the same seeds in both), and judges, per data set and feature,
the accuracy rule's paired part (:func:`campaigns.statistics.accuracy_rule.judge_accuracy`, docs/accuracy.md): the
95 % Student-t interval of the mean shift auto - full within the tolerance of the feature's unit
(:data:`campaigns.statistics.accuracy_rule.MEAN_SHIFT_TOLERANCES`: ±0.05 µm for a length, ±1.43 mN·m for a torque)
and the 95 % jackknife interval of the standard-deviation ratio auto / full within 1 ± 10 %; ``met`` when both are,
``not met`` when either interval lies wholly outside its tolerance, ``undetermined`` otherwise, ``insufficient
data`` below :data:`AUDIT_MIN_PAIRS` paired runs.

**How many pairs** (:func:`audit_pairs`): ``fidelity_audit.runs`` is the audit's budget per data set of the
campaign, the ``runs x data sets`` full-fidelity runs it always cost; it is shared among the simplified data sets
only, each re-running the same number of its first runs, at most all of them. The sd ratio's interval needs the
pairs (at 10 it spans about ±10 % by itself): the demo's one simplified data set gets all its 59 runs.

The rule's other parts (200 paired runs, unchanged analysis verdicts and sensitivity rankings) judge a default
configuration (:mod:`campaigns.bench.solver_accuracy`), not a campaign's audit runs. The largest paired difference,
the Monte Carlo error of the mean (``1.96 sigma / sqrt(N)``) and the KS p-value are reported beside it (the KS test
is no part of the verdict: paired samples are not independent), and so is the scene's numerical sensitivity floor
(``campaigns/bench/numerical_floor.toml``): how far single paired runs may differ with nothing wrong, which the t
interval already carries as spread.

The full-fidelity runs take the full model's default step (62.5 us: the screw's axial mode and the analog current
loop are back), so the audit judges the automatic levels and the step they allow together.

The verdict is a result, not an error: it is recorded in ``results.nc`` (``fidelity_audit*``
attributes, one statement per data set and feature, printed verbatim by the CLI and the report), and
a ``not met`` names the rule to fix (``twin/fidelity/rules.toml``). Settings the audit cannot judge with (a
``fidelity_audit.runs`` below :data:`AUDIT_MIN_PAIRS`, a feature whose unit has no tolerance) are refused before any
run (:func:`audit_problems`).
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import xarray as xr

import twin
from campaigns.runner.execution import run_campaign
from campaigns.runner.runs import RunModel
from campaigns.runner.spec import CampaignSpec, FidelityAudit, Observability, Traces
from campaigns.runner.storage import write_netcdf
from campaigns.statistics.accuracy_rule import (
    MEAN_SHIFT_TOLERANCES,
    SD_RATIO_TOLERANCE,
    judge_accuracy,
    tolerance_for,
)
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


#: The statement of a data set the audit does not re-run (:func:`simplified_datasets`).
IDENTICAL = ("met: identical: the automatic choice is the full model (every run of the data set at the full levels "
             "and step); not re-run")

#: The ``basis`` of such a data set in ``fidelity_audit.nc``.
IDENTICAL_BASIS = "identical: the automatic choice is the full model; not re-run"

#: Units and long names of the figures of :func:`campaigns.statistics.paired_comparison.compare_features` in the
#: audit's file (``feature_unit``: the feature's SI unit, a variable of the file).
_COMPARISON_META = {
    "mean_shift": ("feature_unit", "mean of the feature, auto - full, over the paired ok runs"),
    "sigma_shift": ("feature_unit", "standard deviation of the feature, auto - full"),
    "max_paired_difference": ("feature_unit", "largest |auto - full| of a paired run"),
    "sampling_error": ("feature_unit", "Monte Carlo error of the mean: 1.96 sigma / sqrt(n)"),
    "ks_distance": ("1", "Kolmogorov-Smirnov distance between the auto and full samples"),
    "ks_pvalue": ("1", "Kolmogorov-Smirnov p-value (not part of the verdict)"),
    "n": ("1", "paired ok runs"),
}


def has_automatic_choice(spec: CampaignSpec) -> bool:
    """Whether the spec leaves the fidelity levels to the automatic choice the audit checks (anything but
    ``"full"``)."""
    return spec.solver.fidelity != "full"


def audit_problems(spec: CampaignSpec, units: dict[str, str] | None = None) -> list[str]:
    """What in ``spec`` the audit cannot judge with, one problem per line (empty: fine; nothing to check when the
    audit is off or the spec runs full fidelity): a ``fidelity_audit.runs`` from 1 to :data:`AUDIT_MIN_PAIRS` - 1
    (no verdict from so few pairs: 0 turns the audit off), a feature whose unit (``units``, default the spec's
    catalog's, :meth:`CampaignSpec.feature_meta`) has no mean-shift tolerance."""
    runs = spec.fidelity_audit.runs
    if runs == 0 or not has_automatic_choice(spec):
        return []
    problems = [] if runs >= AUDIT_MIN_PAIRS else [
        f"fidelity_audit.runs: {runs} is below the {AUDIT_MIN_PAIRS} paired runs an audit verdict needs "
        "(campaigns.bench.fidelity_audit.AUDIT_MIN_PAIRS); give 5 or more, or 0 to turn the audit off"]
    for feature in spec.features:
        unit = (units or {}).get(feature) or spec.feature_meta(feature)[0]
        if unit not in MEAN_SHIFT_TOLERANCES:
            problems.append(f"features: {feature} is in {unit!r}, and the fidelity audit has tolerances for "
                            f"{', '.join(repr(u) for u in MEAN_SHIFT_TOLERANCES)} only "
                            "(campaigns.statistics.accuracy_rule.MEAN_SHIFT_TOLERANCES); set fidelity_audit.runs = 0 "
                            "or leave the feature out")
    return problems


def simplified_datasets(spec: CampaignSpec, results_attrs: Mapping[str, object]) -> dict[str, bool]:
    """``{data set: whether the automatic choice simplified its model}``: True unless every run of the data set
    recorded the levels the full model takes for its scene and conditions (``results.nc``'s ``fidelity_<data set>``:
    the distinct levels of its runs). The same levels give the same step and the same numbers: no audit run can
    tell them apart."""
    outputs = list(spec.features) + (list(spec.traces.variables) if spec.traces.runs_per_dataset else [])
    found = {}
    for dataset in spec.datasets:
        scene = (load_scene(dataset.scene or spec.base.scene).with_procedure(dataset.procedure)
                 .with_conditions(dataset.conditions))
        params = twin.load_parameters(spec.base.parameters).with_values(dataset.parameters)
        full = twin.fidelity.resolve_fidelity(scene, params, "full", outputs).summary()
        found[dataset.name] = str(results_attrs.get(f"fidelity_{dataset.name}", "")) != full
    return found


def audit_pairs(spec: CampaignSpec, simplified: int) -> int:
    """Paired runs per simplified data set: the audit's budget, ``fidelity_audit.runs`` per data set of the campaign,
    shared among the ``simplified`` data sets, at most every run of one (module docstring)."""
    if simplified == 0:
        return 0
    return min(spec.runs_per_dataset, spec.fidelity_audit.runs * len(spec.datasets) // simplified)


def full_fidelity_variant(spec: CampaignSpec, runs: int) -> CampaignSpec:
    """The spec's first ``runs`` runs of every data set at full fidelity (with the full model's default step unless
    the spec names one), without traces or audit (the audit runs the data sets it needs of it:
    :func:`campaigns.runner.execution.run_campaign`'s ``datasets``)."""
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
    """Per data set of ``full`` and feature: the :func:`campaigns.statistics.paired_comparison.compare_features`
    figures of the auto runs against their full-fidelity twins, the rule's verdict (``verdict``, ``statement``, the
    mean shift's interval ``shift_lower``/``shift_upper``, the sd ratio with its interval; the tolerance and the unit
    by the feature's unit), the scene's ``numerical_floor`` (context, no part of the verdict) and the wall-time
    speedup."""
    floors = floors or {}
    runs = full.sizes["run"]
    paired = auto.sel(dataset=full.dataset.values).isel(run=slice(0, runs))
    per_feature = [compare_features(paired, full, f).expand_dims(feature=[f]) for f in features]
    audit = xr.concat(per_feature, dim="feature").transpose("dataset", "feature")
    judged = judge_accuracy(paired, full, features, min_pairs=AUDIT_MIN_PAIRS)  # each feature's unit's tolerance
    interval = "95 % Student-t interval of the paired mean shift auto - full"
    for name, source, attrs in (
        ("verdict", "verdict", {"long_name": "audit verdict: " + " / ".join(VERDICTS)}),
        ("statement", "statement", {"long_name": "the verdict with the numbers it rests on (printed verbatim)"}),
        ("shift_lower", "mean_shift_lower", {"units": "feature_unit", "long_name": f"{interval}, lower"}),
        ("shift_upper", "mean_shift_upper", {"units": "feature_unit", "long_name": f"{interval}, upper"}),
        ("sd_ratio", "sd_ratio", {"units": "1", "long_name": "standard deviation ratio auto / full"}),
        ("sd_ratio_lower", "sd_ratio_lower", {"units": "1", "long_name": "95 % jackknife interval of sd_ratio, lower"}),
        ("sd_ratio_upper", "sd_ratio_upper", {"units": "1", "long_name": "95 % jackknife interval of sd_ratio, upper"}),
    ):
        audit[name] = judged[source].transpose("dataset", "feature").assign_attrs(attrs)
    audit["feature_unit"] = judged["feature_unit"]
    audit["mean_shift_tolerance"] = judged["mean_shift_tolerance"]
    cells = [(d, f) for d in audit.dataset.values for f in features]
    floor = np.array([floors.get((str(d), f), 0.0) for d, f in cells]).reshape(audit.sizes["dataset"], len(features))
    audit["numerical_floor"] = (("dataset", "feature"), floor,
                                {"units": "feature_unit", "long_name": "numerical sensitivity floor of the scene (0: "
                                 "not measured): how far single paired runs may differ; not part of the verdict"})
    both = (paired.status == "ok") & (full.status == "ok")
    audit["speedup"] = full.wall_time.where(both).sum("run") / paired.wall_time.where(both).sum("run")
    audit["speedup"].attrs.update(units="1", long_name="full-fidelity wall time / auto wall time over the paired runs")
    # campaigns.statistics.paired_comparison's figures, described for CF
    for name, (unit, long_name) in _COMPARISON_META.items():
        if name in audit:
            audit[name].attrs = {"units": unit, "long_name": long_name}
    audit["basis"] = ("dataset", np.full(audit.sizes["dataset"], f"{runs} paired runs", dtype=object),
                      {"long_name": "what the verdict rests on: paired runs auto against full, or identity"})
    audit.attrs.update(runs=runs, sd_ratio_tolerance=SD_RATIO_TOLERANCE, min_paired_runs=AUDIT_MIN_PAIRS)
    audit.attrs["verdict"] = overall_verdict(audit)
    return audit


def with_identical(audit: xr.Dataset | None, names: list[str], features: list[str], units: Mapping[str, str],
                   order: list[str]) -> xr.Dataset:
    """The audit of the re-run data sets (``audit``; None when there are none) with the data sets ``names`` that
    were not re-run (their automatic choice is the full model) added, in the campaign's ``order``: verdict ``met``,
    the :data:`IDENTICAL` statement, no figures (NaN, n = 0), ``basis`` saying which is which."""
    dims = ("dataset", "feature")
    if audit is None:
        audit = xr.Dataset(
            {"verdict": (dims, np.empty((0, len(features)), dtype=object)),
             "statement": (dims, np.empty((0, len(features)), dtype=object)),
             "n": (dims, np.zeros((0, len(features)), dtype=np.int32)), "speedup": ("dataset", np.zeros(0)),
             "feature_unit": ("feature", np.array([units[f] for f in features], dtype=object)),
             "mean_shift_tolerance": ("feature", np.array([tolerance_for(units[f]).value for f in features])),
             "basis": ("dataset", np.empty(0, dtype=object))},
            coords={"dataset": np.array([], dtype=object), "feature": np.array(features, dtype=object)},
            attrs={"runs": 0, "sd_ratio_tolerance": SD_RATIO_TOLERANCE, "min_paired_runs": AUDIT_MIN_PAIRS})
    audit = audit.reset_coords(drop=True)  # the results' per-data-set coordinates (scene, ...): not the audit's
    fills = {"verdict": "met", "statement": IDENTICAL, "n": 0}
    added = {}
    for name, variable in audit.data_vars.items():
        if "dataset" not in variable.dims:
            added[name] = variable
            continue
        shape = tuple(len(names) if dim == "dataset" else audit.sizes[dim] for dim in variable.dims)
        kind = variable.dtype.kind
        value = fills.get(name, np.nan if kind == "f" else "" if kind == "O" else 0)
        added[name] = (variable.dims, np.full(shape, value, dtype=variable.dtype), variable.attrs)
    identical = xr.Dataset(added, coords={"dataset": np.array(names, dtype=object), "feature": audit.feature.values})
    merged = xr.concat([audit, identical], dim="dataset", data_vars="minimal", coords="minimal", compat="override")
    merged = merged.sel(dataset=[d for d in order if d in merged.dataset.values])
    merged["basis"] = ("dataset", np.array([IDENTICAL_BASIS if d in names else f"{int(audit.attrs['runs'])} paired "
                                            "runs" for d in merged.dataset.values], dtype=object),
                       {"long_name": "what the verdict rests on: paired runs auto against full, or identity"})
    merged.attrs = {**audit.attrs, "identical_datasets": ", ".join(names)}
    merged.attrs["verdict"] = overall_verdict(merged)
    return merged


def overall_verdict(audit: xr.Dataset) -> str:
    """The campaign's audit in one line: the worst verdict
    (:func:`campaigns.statistics.paired_comparison.worst_verdict`) and the data set/feature pairs that have it, and
    which data sets were judged by their paired runs and which are identical (not re-run)."""
    cells = {(d, f): audit.verdict.sel(dataset=d, feature=f).item()
             for d in audit.dataset.values for f in audit.feature.values}
    worst = worst_verdict(cells.values())
    identical = [str(d) for d, b in zip(audit.dataset.values, audit.basis.values, strict=True)
                 if b == IDENTICAL_BASIS]
    rerun = [str(d) for d in audit.dataset.values if str(d) not in identical]
    pairs = int(audit.attrs.get("runs", 0))
    scope = (f"on {', '.join(rerun)} ({pairs} paired runs each)" + (
        f" and identical on the other {len(identical)} data set(s), whose automatic choice is the full model (not "
        "re-run)" if identical else ""))
    meaning = {"met": f"auto is within the tolerances of full fidelity (mean shift, standard deviation) {scope}"
                      if rerun else "the automatic choice is the full model on every data set (identical: nothing "
                                    "re-run)",
               "not met": "auto differs from full fidelity (the fidelity rule to fix)",
               "undetermined": "the audit's runs cannot resolve the tolerances",
               "insufficient data": "too few paired runs"}[worst]
    named = [f"{d}/{f}" for (d, f), v in cells.items() if v == worst]
    return f"{worst}: {meaning}" + ("" if worst == "met" else f": {', '.join(named)}")


def summary_attrs(audit: xr.Dataset) -> dict[str, str]:
    """``fidelity_audit*`` attributes for ``results.nc`` (what the CLI and the report's Fidelity section print):
    per data set, the speedup and per feature its statement, largest paired difference, MC error and KS p-value in
    the feature's display unit, features separated by `` | ``; a data set not re-run, the :data:`IDENTICAL`
    statement."""
    attrs = {"fidelity_audit_runs": str(audit.attrs["runs"])}
    for name in audit.dataset.values:
        if audit.basis.sel(dataset=name).item() == IDENTICAL_BASIS:
            attrs[f"fidelity_audit_{name}"] = IDENTICAL
            continue
        lines = []
        for feature in audit.feature.values:
            row = audit.sel(dataset=name, feature=feature)
            shown = tolerance_for(str(audit.feature_unit.sel(feature=feature).item()))
            lines.append(f"{feature}: {row.statement.item()}; max paired "
                         f"{shown.text(float(row.max_paired_difference), False)}, MC error "
                         f"{shown.text(float(row.sampling_error), False)}, KS p {float(row.ks_pvalue):.2f}")
        speedup = float(audit.speedup.sel(dataset=name))
        attrs[f"fidelity_audit_{name}"] = f"speedup x{speedup:.2f}; " + " | ".join(lines)
    attrs["fidelity_audit"] = audit.attrs["verdict"]
    return attrs


def audit_campaign(results_path: Path, spec: CampaignSpec, run_model: RunModel, **run_options) -> xr.Dataset | None:
    """Run the full-fidelity twins of the campaign's first runs of every data set the automatic choice simplifies
    with ``run_model``, compare, and record the audit in ``results.nc``. Returns the audit (also written as
    ``fidelity_audit.nc``, every data set in it: the identical ones with their statement), or None when there is
    nothing to audit (audit off, full fidelity already, or a model that reports no fidelity).

    ``run_options`` are those of :func:`campaigns.runner.execution.run_campaign` (workers, scheduler, resume,
    progress, allow_version_mix, announce, cluster: the campaign's own, so that no second one starts); the audit's
    runs are a campaign of their own in ``results_path.parent / "fidelity_audit"``."""
    with xr.open_dataset(results_path) as handle:
        auto = handle.load()
    reported = any(k.startswith("fidelity_") and k != "fidelity_requested" for k in auto.attrs)
    simplified = simplified_datasets(spec, auto.attrs) if reported else {}
    runs = audit_pairs(spec, sum(simplified.values()))
    enough = spec.fidelity_audit.runs > 0 and (runs >= AUDIT_MIN_PAIRS or not any(simplified.values()))
    if not (enough and has_automatic_choice(spec) and reported):
        why = ("the campaign runs at full fidelity with a named integrator" if not has_automatic_choice(spec)
               else "the run function reports no fidelity" if not reported
               else "fidelity_audit.runs = 0" if spec.fidelity_audit.runs == 0
               else f"{spec.runs_per_dataset} run(s) per data set; a verdict needs {AUDIT_MIN_PAIRS} paired runs")
        _write_attrs(results_path, auto, {"fidelity_audit": f"not run ({why})"})
        return None
    out_dir = results_path.parent / "fidelity_audit"
    names = [d.name for d in spec.datasets]
    rerun = [d for d in names if simplified[d]]
    identical = [d for d in names if not simplified[d]]
    announce = run_options.get("announce") or (lambda stage, message: None)
    announce("fidelity audit", f"{spec.name}: " + (
        f"re-running {runs} run(s) of {', '.join(rerun)} at full fidelity, whose automatic choice simplifies the "
        "model; " if rerun else "") + (f"{len(identical)} data set(s) run the full model already (identical, not "
                                        "re-run)" if identical else "every data set simplified"))
    features = list(spec.features)
    audit = None
    if rerun:
        full_path = run_campaign(full_fidelity_variant(spec, runs), out_dir, run_function=run_model, datasets=rerun,
                                 **run_options)
        with xr.open_dataset(full_path) as handle:
            full = handle.load()
        audit = compare_fidelity(auto, full, features, numerical_floors(spec, features))
    units = {f: str(auto[f].attrs.get("units", spec.feature_meta(f)[0])) for f in features}
    audit = with_identical(audit, identical, features, units, names)
    out_dir.mkdir(parents=True, exist_ok=True)
    write_netcdf(audit, out_dir / "fidelity_audit.nc", title=f"BenchTwin fidelity audit of campaign {spec.name}",
                 history=f"fidelity audit: {runs} paired run(s) of {', '.join(rerun) or 'no data set'}, auto against "
                         f"full fidelity; {', '.join(identical) or 'none'} identical (campaigns.bench.fidelity_audit)")
    _write_attrs(results_path, auto, summary_attrs(audit))
    return audit


def _write_attrs(path: Path, results: xr.Dataset, attrs: dict[str, str]) -> None:
    results.attrs.update(attrs)
    write_netcdf(results, path, title=str(results.attrs.get("title", "")),
                 history=f"fidelity_audit attributes recorded: {attrs.get('fidelity_audit', '')}")
