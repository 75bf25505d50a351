"""The model-form table: what each modelling assumption does to the features and to the verdicts.

A model-form study (``campaigns/specs/model_form.toml``, issue 33; ``model_form_requirement.toml`` around the 1 µm
requirement, issue 42) is a campaign whose data sets are baselines and one-at-a-time variants: a variant data set is
named ``<baseline>__<label>`` and differs from its baseline in exactly one scene condition (the *assumption*; the
spec states it in both), in the parameters it fixes alone (a parameter variant, named
``<baseline>__<assumption>_<value>``: one assumption may be several parameters, e.g. every ball-groove friction
coefficient), or in the level of one fidelity subsystem alone (a model variant: the assumption is the subsystem, e.g.
the seal's friction law). From the campaign's results and analysis this module computes, per assumption and variant,
per baseline data set and feature:

* the shift of the feature's mean against the baseline with its t interval at the analysis's confidence
  (:func:`campaigns.statistics.intervals.mean_shift`): of the run-by-run differences when the variant takes its
  baseline's seeds (``seeds_from``: run ``i`` of both is one unit with one noise record under two assumptions, common
  random numbers), else Welch's for independent samples. A shift is stated only where its interval excludes zero
  (``shift_status``);
* the requirement verdict of the observability sweep with every sweep data set replaced by its variant, computed by
  :func:`campaigns.analysis.observability.observability_sweep` with the analysis's settings and bootstrap stream,
  against the analysis's verdict (both in the vocabulary of :data:`campaigns.statistics.paired_comparison.VERDICTS`);
* the shift of the detection probability at the requirement (the sweep's, linearly interpolated between the levels
  around the requirement when none sits at it) with its percentile bootstrap interval, paired where the variant takes
  its baseline's seeds (run ``i`` of both arms drawn together); a verdict counts as ``changed`` only where the verdicts
  differ *and* that interval excludes zero, else ``changed_within_noise``: with ~60 runs per level a verdict near its
  boundary flips between two samples of the same model, and such a flip is not evidence by itself (issue 42 item 6);

and one sentence, :func:`headline`: the assumption that changes the most verdicts or, when none changes one, the one
whose resolved shift of a feature is largest. :func:`write_model_form` writes it all as ``model_form.nc``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from campaigns.analysis.observability import observability_sweep
from campaigns.analysis.settings import MODEL_FORM_STREAM, OBSERVABILITY_STREAM
from campaigns.analysis.vocabulary import sweep_levels
from campaigns.analysis.vocabulary import used as ok_runs
from campaigns.runner.files import write_netcdf
from campaigns.statistics.detection import detection_probabilities, detection_probability, printed_estimate
from campaigns.statistics.intervals import mean_shift

#: Between a baseline data set's name and its variant's label: ``ds2__noise_path_recorded``.
SEPARATOR = "__"
#: The table's file, beside ``analysis.nc``.
FILE_NAME = "model_form.nc"
#: ``shift_status`` values: the interval excludes zero (``resolved``) or not; too few ok runs on either side; or the
#: study has no such variant of the data set.
SHIFT_STATUS = ("not_resolved", "resolved", "insufficient_data", "not_run")
#: ``verdict_change`` values: both verdicts given and equal; given and different, the detection probability at the
#: requirement shifted beyond its sampling noise (its interval excludes zero); not both given (insufficient data on
#: either side, or a sweep data set without this variant); given and different within the noise (the interval holds
#: zero, or no interval: a flip of two samples near the verdict's boundary, not evidence). Appended, so the flag
#: values of older tables keep their meaning.
VERDICT_CHANGE = ("unchanged", "changed", "not_compared", "changed_within_noise")
#: ``assumption_kind`` values: what a variant changes (:func:`variants`).
ASSUMPTION_KINDS = ("condition", "parameters", "fidelity")


@dataclass(frozen=True)
class Variant:
    """A variant data set: its baseline and the one assumption that differs, with both values as written.

    A condition variant changes one scene condition (``assumption`` is its name); a parameter variant fixes
    parameters (``parameters``, JSON, SI units) and is named ``<baseline>__<assumption>_<value>``; a fidelity variant
    sets one subsystem's level (``assumption`` is the subsystem, :mod:`twin.levels`; ``"auto"`` where a data set
    leaves it to the automatic choice). ``kind`` says which (:data:`ASSUMPTION_KINDS`). ``paired`` when it takes
    its baseline's seeds (``seeds_from``): run ``i`` of both is then one unit under two assumptions.
    """

    dataset: str
    baseline: str
    assumption: str
    value: str
    baseline_value: str
    paired: bool = False
    parameters: str = ""
    kind: str = "condition"

    @property
    def label(self) -> str:
        return f"{self.assumption}={self.value}"


def _changed(mine: dict, theirs: dict) -> list[str]:
    return sorted(k for k in set(mine) | set(theirs) if mine.get(k) != theirs.get(k))


def variants(spec: dict) -> list[Variant]:
    """The variant data sets of a spec (its ``spec`` table, as stored in ``results.nc``), in spec order.

    Raises
    ------
    ValueError
        A ``<baseline>__<label>`` data set whose baseline is not a data set, whose scene differs from it, or that
        does not differ from it in exactly one condition stated by both, in its fixed parameters alone, or in one
        subsystem's fidelity level alone.
    """
    datasets = {d["name"]: d for d in spec["datasets"]}
    sampled = {u["target"] for u in spec.get("uncertainties", [])}
    found, problems = [], []
    for name, entry in datasets.items():
        if SEPARATOR not in name:
            continue
        baseline, label = name.split(SEPARATOR, 1)
        if baseline not in datasets:
            problems.append(f"{name}: no baseline data set {baseline!r}")
            continue
        base = datasets[baseline]
        if entry.get("scene") != base.get("scene"):
            problems.append(f"{name}: scene {entry.get('scene')!r}, its baseline's is {base.get('scene')!r}")
            continue
        paired = entry.get("seeds_from") == baseline
        mine, theirs = entry.get("conditions", {}), base.get("conditions", {})
        conditions = _changed(mine, theirs)
        fixed, fixed_base = entry.get("parameters", {}), base.get("parameters", {})
        parameters = _changed(fixed, fixed_base)
        # a data set without levels of its own runs the automatic choice (the spec stores none as absent or null)
        model, model_base = entry.get("fidelity") or {}, base.get("fidelity") or {}
        levels = _changed(model, model_base)
        if levels and not conditions and not parameters:
            if len(levels) != 1:
                problems.append(f"{name}: a fidelity variant sets one subsystem's level (differs in: "
                                f"{', '.join(f'fidelity.{k}' for k in levels)})")
                continue
            key = levels[0]
            found.append(Variant(name, baseline, key, str(model.get(key, "auto")), str(model_base.get(key, "auto")),
                                 paired, kind="fidelity"))
            continue
        if parameters and not conditions and not levels:
            assumption, _, value = label.rpartition("_")
            if not assumption:
                problems.append(f"{name}: a variant of parameters is named <baseline>__<assumption>_<value>")
                continue
            baseline_value = ("set by the data set" if any(k in fixed_base for k in parameters)
                              else "sampled" if any(k in sampled for k in parameters) else "nominal")
            found.append(Variant(name, baseline, assumption, value, baseline_value, paired,
                                 json.dumps({k: fixed[k] for k in parameters if k in fixed}, sort_keys=True),
                                 kind="parameters"))
            continue
        if (parameters or levels or len(conditions) != 1 or conditions[0] not in mine
                or conditions[0] not in theirs):
            differs = conditions + parameters + [f"fidelity.{k}" for k in levels]
            problems.append(f"{name}: must differ from {baseline} in exactly one condition stated by both, in its "
                            f"parameters alone, or in one subsystem's fidelity level alone (differs in: "
                            f"{', '.join(differs) or 'none'})")
            continue
        key = conditions[0]
        found.append(Variant(name, baseline, key, str(mine[key]), str(theirs[key]), paired))
    if problems:
        raise ValueError("model-form study: " + "; ".join(problems))
    return found


def _settings(analysis: xr.Dataset) -> dict:
    """The analysis's own settings of the observability verdict (its attributes), so a variant is judged as the
    baseline was."""
    boot = json.loads(analysis.attrs["bootstrap"])
    return {"n_boot": int(boot["n_boot"]), "confidence": float(boot["confidence"]), "seed": int(boot["seed"]),
            "false_alarm_rate": float(analysis.attrs["false_alarm_rate"]),
            "power": float(analysis.attrs["detection_power"]),
            "min_runs": int(analysis.attrs["min_detection_runs"]),
            "condition": str(analysis.attrs["observability_condition"]),
            "requirement": float(analysis.attrs["requirement"]),
            "requirement_source": str(analysis.attrs["requirement_source"])}


def _variant_verdict(results: xr.Dataset, spec: dict, by_baseline: dict[str, str], feature: str, f: int,
                     settings: dict) -> tuple[str, str]:
    """The sweep's verdict and statement with every sweep data set replaced by its variant (``by_baseline``);
    ``("insufficient data", why)`` when a sweep data set has no such variant."""
    observability = spec["observability"]
    sweep = list(observability["sweep"])
    missing = [n for n in sweep if n not in by_baseline]
    if not sweep or missing:
        why = "no observability sweep" if not sweep else f"no variant of sweep data set(s) {', '.join(missing)}"
        return "insufficient data", f"insufficient data: {why}"
    swapped = results.sel(dataset=[by_baseline[n] for n in sweep]).assign_coords(
        dataset=np.array(sweep, dtype=object))
    found = observability_sweep(
        swapped, feature, sweep, false_alarm_rate=settings["false_alarm_rate"], power=settings["power"],
        n_boot=settings["n_boot"], confidence=settings["confidence"], min_runs=settings["min_runs"],
        seed=np.random.SeedSequence(settings["seed"], spawn_key=(OBSERVABILITY_STREAM, f)),
        condition=settings["condition"], reference=observability.get("reference"),
        requirement=settings["requirement"], requirement_source=settings["requirement_source"])
    return str(found["requirement_verdict"].item()), str(found["requirement_statement"].item())


def _requirement_weights(levels: np.ndarray, requirement: float) -> dict[int, float]:
    """``{sweep index: weight}`` whose weighted sum of detection probabilities is the probability at the requirement:
    the level at it (weight 1), else linear interpolation between the levels around it; empty when the requirement
    lies outside the sweep."""
    at = np.flatnonzero(levels == requirement)
    if len(at):
        return {int(at[0]): 1.0}
    below, above = np.flatnonzero(levels < requirement), np.flatnonzero(levels > requirement)
    if not len(below) or not len(above):
        return {}
    lo, hi = int(below[np.argmax(levels[below])]), int(above[np.argmin(levels[above])])
    w = (requirement - levels[lo]) / (levels[hi] - levels[lo])
    return {lo: 1.0 - w, hi: w}


def detection_shift(results: xr.Dataset, spec: dict, by_baseline: dict[str, str], feature: str, paired: bool,
                    settings: dict, seed) -> tuple[float, float, float]:
    """Shift of the detection probability at the requirement, variant minus baseline, and its percentile bootstrap
    interval at the analysis's confidence: ``(shift, lower, upper)``, all NaN when a data set it needs has fewer used
    runs than the detection floor (``settings["min_runs"]``) or the requirement lies outside the sweep.

    Each arm's probability is that of :func:`campaigns.statistics.detection.detection_probability` (the threshold
    from the arm's own reference) at the sweep level at the requirement, or interpolated between the levels around
    it (:func:`_requirement_weights`). Each bootstrap replicate resamples the runs of every data set it needs, the
    reference with them; ``paired``: one draw of run indices for both arms (runs used in both; run ``i`` of the
    variant is run ``i`` of the baseline under the other assumption), else independent draws per arm.
    """
    sweep = list(spec["observability"]["sweep"])
    levels, reference = sweep_levels(results, sweep, settings["condition"], spec["observability"].get("reference"))
    weights = _requirement_weights(levels, settings["requirement"])
    nan3 = (math.nan, math.nan, math.nan)
    if not weights:
        return nan3
    used = ok_runs(results, feature)
    arms = {}
    for k in sorted({reference, *weights}):
        base, variant = (results[feature].sel(dataset=n).where(used.sel(dataset=n)).values
                         for n in (sweep[k], by_baseline[sweep[k]]))
        if paired:
            kept = np.isfinite(base) & np.isfinite(variant)
            arms[k] = (base[kept], variant[kept])
        else:
            arms[k] = (base[np.isfinite(base)], variant[np.isfinite(variant)])
    if min(min(len(a), len(b)) for a, b in arms.values()) < settings["min_runs"]:
        return nan3
    far, n_boot = settings["false_alarm_rate"], settings["n_boot"]
    rng = np.random.default_rng(seed)
    draws = {}
    for k, (base, variant) in arms.items():
        first = rng.integers(0, len(base), (n_boot, len(base)))
        draws[k] = (first, first if paired else rng.integers(0, len(variant), (n_boot, len(variant))))
    estimate, replicates = [], []
    for arm in (0, 1):  # baseline, variant
        ref = arms[reference][arm]
        estimate.append(sum(w * detection_probability(ref, arms[k][arm], far) for k, w in weights.items()))
        replicates.append(sum(w * detection_probabilities(ref[draws[reference][arm]], arms[k][arm][draws[k][arm]],
                                                           far) for k, w in weights.items()))
    alpha = 0.5 * (1.0 - settings["confidence"])
    lower, upper = np.quantile(replicates[1] - replicates[0], [alpha, 1.0 - alpha])
    return float(estimate[1] - estimate[0]), float(lower), float(upper)


def verdict_change(baseline: str, variant: str, shift_ci: tuple[float, float]) -> str:
    """The :data:`VERDICT_CHANGE` value of a variant's verdict against the baseline's: ``changed`` only where the
    verdicts differ and the detection probability's shift at the requirement is resolved (``shift_ci`` excludes
    zero), ``changed_within_noise`` where they differ without it."""
    if "insufficient data" in (baseline, variant):
        return "not_compared"
    if baseline == variant:
        return "unchanged"
    lower, upper = shift_ci
    return "changed" if lower > 0.0 or upper < 0.0 else "changed_within_noise"


def model_form_dataset(results: xr.Dataset, analysis: xr.Dataset) -> xr.Dataset:
    """The model-form table of a campaign (see the module docstring and the variables' ``long_name``).

    Raises
    ------
    ValueError
        When the campaign is not a model-form study (no ``<baseline>__<label>`` data set), or see :func:`variants`.
    """
    spec = json.loads(results.attrs["spec_json"])["spec"]
    found = variants(spec)
    if not found:
        raise ValueError("not a model-form study: no data set is named <baseline>__<label>")
    settings = _settings(analysis)
    confidence, min_runs = settings["confidence"], int(analysis.attrs["min_ok_runs"])
    features = [str(f) for f in analysis["feature"].values]
    labels = list(dict.fromkeys(v.label for v in found))
    baselines = list(dict.fromkeys(v.baseline for v in found))
    shape = (len(labels), len(baselines), len(features))
    shift, bounds = np.full(shape, math.nan), np.full(shape + (2,), math.nan)
    status = np.full(shape, SHIFT_STATUS.index("not_run"), dtype=np.int8)
    n_variant, n_baseline = np.zeros(shape, dtype=np.int32), np.zeros(shape, dtype=np.int32)
    used = {feature: ok_runs(results, feature) for feature in features}
    for v in found:
        i, d = labels.index(v.label), baselines.index(v.baseline)
        for f, feature in enumerate(features):
            # unused runs as NaN, so that a paired shift keeps run i against run i
            a, b = (results[feature].sel(dataset=n).where(used[feature].sel(dataset=n)).values
                    for n in (v.dataset, v.baseline))
            kept = np.isfinite(a) & np.isfinite(b) if v.paired else None
            n_variant[i, d, f], n_baseline[i, d, f] = ((kept.sum(), kept.sum()) if v.paired
                                                       else (np.isfinite(a).sum(), np.isfinite(b).sum()))
            shift[i, d, f], bounds[i, d, f, 0], bounds[i, d, f, 1] = mean_shift(
                a, b, paired=v.paired, confidence=confidence, min_runs=min_runs)
            status[i, d, f] = SHIFT_STATUS.index(
                "insufficient_data" if not math.isfinite(shift[i, d, f])
                else "resolved" if bounds[i, d, f, 0] > 0 or bounds[i, d, f, 1] < 0 else "not_resolved")
    baseline_verdict = [str(analysis["requirement_verdict"].sel(feature=f).item()) for f in features]
    verdict = np.empty((len(labels), len(features)), dtype=object)
    statement = np.empty_like(verdict)
    change = np.empty(verdict.shape, dtype=np.int8)
    detection, detection_ci = np.full(verdict.shape, math.nan), np.full(verdict.shape + (2,), math.nan)
    first = {label: next(v for v in found if v.label == label) for label in labels}
    for i, label in enumerate(labels):
        by_baseline = {v.baseline: v.dataset for v in found if v.label == label}
        for f, feature in enumerate(features):
            verdict[i, f], statement[i, f] = _variant_verdict(results, spec, by_baseline, feature, f, settings)
            if "insufficient data" not in (verdict[i, f], baseline_verdict[f]):
                detection[i, f], detection_ci[i, f, 0], detection_ci[i, f, 1] = detection_shift(
                    results, spec, by_baseline, feature, first[label].paired, settings,
                    np.random.SeedSequence(settings["seed"], spawn_key=(MODEL_FORM_STREAM, i, f)))
            change[i, f] = VERDICT_CHANGE.index(
                verdict_change(baseline_verdict[f], str(verdict[i, f]), tuple(detection_ci[i, f])))
    units = [str(results[f].attrs.get("units", "1")) for f in features]
    feature_units = {"units": units[0]} if len(set(units)) == 1 else {
        "comment": "in the units of each feature, given by the feature_units coordinate"}
    cells = ("variant", "dataset", "feature")
    table = xr.Dataset(
        {
            "assumption": ("variant", np.array([first[k].assumption for k in labels], dtype=object),
                           {"long_name": "the modelling assumption the variant changes: a scene condition, the "
                                         "parameters in variant_parameters, or a fidelity subsystem's level"}),
            "assumption_kind": ("variant", np.array([first[k].kind for k in labels], dtype=object),
                                {"long_name": "what the variant changes: " + ", ".join(ASSUMPTION_KINDS)}),
            "variant_parameters": ("variant", np.array([first[k].parameters for k in labels], dtype=object),
                                   {"long_name": "the parameters the variant fixes, JSON, SI units (empty for a "
                                                 "scene condition or a fidelity level)"}),
            "pairing": ("variant", np.array(["paired" if first[k].paired else "independent" for k in labels],
                                            dtype=object),
                        {"long_name": "paired: the variant takes its baseline's seeds (seeds_from), the shift is "
                                      "that of run-by-run differences; independent: Welch's two-sample interval"}),
            "variant_value": ("variant", np.array([first[k].value for k in labels], dtype=object),
                              {"long_name": "the assumption's value in the variant data sets"}),
            "baseline_value": ("variant", np.array([first[k].baseline_value for k in labels], dtype=object),
                               {"long_name": "the assumption's value in the baseline data sets"}),
            "mean_shift": (cells, shift, {
                "long_name": "mean of the feature in the variant minus mean in the baseline (used runs); NaN unless "
                             "shift_status is resolved or not_resolved; print it only where resolved",
                **feature_units}),
            "mean_shift_ci": (cells + ("bound",), bounds, {
                "long_name": f"{confidence:g} t interval of mean_shift: of the run-by-run differences where the "
                             "variant is paired, Welch's where independent (see pairing)", **feature_units}),
            "shift_status": (cells, status, {
                "long_name": "whether the interval of mean_shift excludes zero (resolved), too few used runs on "
                             f"either side (insufficient_data: fewer than {min_runs}), or no such variant of the "
                             "data set (not_run)",
                "flag_values": np.arange(len(SHIFT_STATUS), dtype=np.int8),
                "flag_meanings": " ".join(SHIFT_STATUS)}),
            "n_variant": (cells, n_variant, {"units": "1", "long_name": "used runs of the variant data set (paired: "
                                                                        "runs used on both sides)"}),
            "n_baseline": (cells, n_baseline, {"units": "1", "long_name": "used runs of the baseline data set "
                                                                          "(paired: runs used on both sides)"}),
            "baseline_verdict": ("feature", np.array(baseline_verdict, dtype=object), {
                "long_name": "requirement verdict of the analysis (baseline sweep): met / not met / undetermined / "
                             "insufficient data"}),
            "variant_verdict": (("variant", "feature"), verdict, {
                "long_name": "requirement verdict with every sweep data set replaced by its variant, same settings "
                             "and bootstrap stream as the analysis"}),
            "variant_statement": (("variant", "feature"), statement, {
                "long_name": "the variant's requirement verdict with its bounds and sample size, in one sentence"}),
            "detection_shift": (("variant", "feature"), detection, {
                "units": "1",
                "long_name": "detection probability at the requirement, variant minus baseline (the sweep level at "
                             "the requirement, or linear interpolation between the levels around it); NaN where "
                             "the verdicts are not compared"}),
            "detection_shift_ci": (("variant", "feature", "bound"), detection_ci, {
                "units": "1",
                "long_name": f"{confidence:g} percentile bootstrap interval of detection_shift: every data set it "
                             "needs resampled, the reference with it; paired variants draw one set of run indices "
                             "for both arms"}),
            "verdict_change": (("variant", "feature"), change, {
                "long_name": "whether the variant changes the requirement verdict: changed only where the verdicts "
                             "differ and detection_shift_ci excludes zero, changed_within_noise where they differ "
                             "without it (a flip near the boundary, not evidence); not_compared: insufficient data "
                             "on either side",
                "flag_values": np.arange(len(VERDICT_CHANGE), dtype=np.int8),
                "flag_meanings": " ".join(VERDICT_CHANGE)}),
        },
        coords={
            "variant": ("variant", np.array(labels, dtype=object), {"long_name": "assumption=value of the variant"}),
            "dataset": ("dataset", np.array(baselines, dtype=object), {"long_name": "baseline data set"}),
            "feature": ("feature", np.array(features, dtype=object)),
            "feature_units": ("feature", np.array(units, dtype=object), {"long_name": "units of each feature"}),
            "bound": ("bound", np.array(["lower", "upper"], dtype=object)),
        },
    )
    table.attrs = {
        "source_spec_hash": results.attrs.get("spec_hash", ""),
        "confidence": confidence,
        "min_ok_runs": min_runs,
        "method": "one-at-a-time variants of scene conditions, parameters or fidelity levels against their baseline "
                  "data sets; "
                  "mean shift with a t interval (paired where the variant takes its baseline's seeds, else Welch); "
                  "requirement verdict of the observability sweep recomputed on the variants, a change counted only "
                  "where the bootstrap interval of the detection probability's shift at the requirement excludes "
                  "zero",
    }
    table.attrs["headline"] = headline(table)
    return table


def shown_quantities(values, half_width: float, unit: str, extra: int = 1) -> list[str]:
    """Values in the feature's display unit (µm for m) to the leading digit of the interval's half-width plus
    ``extra`` digits: 0 for an estimate (rounded there, :func:`campaigns.statistics.detection.printed_estimate`),
    1 for the bounds, so those of a narrow interval read apart. 3 significant digits for an interval of zero width."""
    scale, shown = (1e6, "µm") if unit == "m" else (1.0, unit)
    if not half_width > 0:
        return [f"{v * scale:.3g} {shown}" for v in values]
    decimals = max(0, extra - math.floor(math.log10(half_width * scale)))
    return [f"{v * scale:.{decimals}f} {shown}" for v in values]


def headline(table: xr.Dataset) -> str:
    """One sentence from the numbers: the assumption that changes the most requirement verdicts (``changed``: beyond
    their sampling noise); when none changes one, how many differ within that noise and the assumption with the
    largest resolved feature shift (ranked by the distance of its interval from zero,
    the size the data guarantee), printed rounded to its interval; never a shift the interval does not resolve."""
    assumptions = list(dict.fromkeys(str(a) for a in table["assumption"].values))
    varied = ", ".join(assumptions)
    change = table["verdict_change"].values
    of = {a: change[table["assumption"].values == a] for a in assumptions}
    changed = {a: int((of[a] == VERDICT_CHANGE.index("changed")).sum()) for a in assumptions}
    compared = int((change != VERDICT_CHANGE.index("not_compared")).sum())
    most = max(changed.values())
    if most > 0:
        leaders = [a for a in assumptions if changed[a] == most]
        cases = []
        for i, f in zip(*np.nonzero(change == VERDICT_CHANGE.index("changed")), strict=True):
            if str(table["assumption"].values[i]) in leaders:
                cases.append(f"{table['variant'].values[i]}, {table['feature'].values[f]}: "
                             f"{table['baseline_verdict'].values[f]} → {table['variant_verdict'].values[i, f]}")
        n = [str(int((of[a] != VERDICT_CHANGE.index("not_compared")).sum())) for a in leaders]
        who = (f"{leaders[0]} moves the requirement verdicts most, changing {most} of its {n[0]} compared verdicts"
               if len(leaders) == 1 else f"{' and '.join(leaders)} move the requirement verdicts most, each changing "
               f"{most} (of {' and '.join(n)} compared)")
        return f"Of the assumptions varied ({varied}), {who}: {'; '.join(cases)}."
    noisy = int((change == VERDICT_CHANGE.index("changed_within_noise")).sum())
    opening = (f"No assumption varied ({varied}) changes a requirement verdict ({compared} compared"
               + (f", {change.size - compared} not compared: insufficient data" if compared < change.size else "")
               + (f"; {noisy} differ{'s' if noisy == 1 else ''} within the verdicts' sampling noise, the detection "
                  "probability's shift at the requirement not resolved" if noisy else "")
               + ")")
    resolved = table["shift_status"].values == SHIFT_STATUS.index("resolved")
    if not resolved.any():
        return opening + "; no shift of a feature's mean is resolved by its interval."
    ci = table["mean_shift_ci"].values
    guaranteed = np.where(resolved, np.minimum(np.abs(ci[..., 0]), np.abs(ci[..., 1])), -1.0)
    i, d, f = np.unravel_index(int(np.argmax(guaranteed)), guaranteed.shape)
    lower, upper = ci[i, d, f]
    unit = str(table["feature_units"].values[f])
    value = printed_estimate(float(table["mean_shift"].values[i, d, f]), (lower, upper))
    (shown,) = shown_quantities((abs(value),), 0.5 * (upper - lower), unit, extra=0)
    low, high = shown_quantities((lower, upper), 0.5 * (upper - lower), unit)
    confidence = float(table.attrs["confidence"])
    return (f"{opening}; {table['assumption'].values[i]} moves the features most: with "
            f"{table['assumption'].values[i]} = {table['variant_value'].values[i]} instead of "
            f"{table['baseline_value'].values[i]}, the mean of {table['feature'].values[f]} in "
            f"{table['dataset'].values[d]} shifts by {'+' if value >= 0 else '-'}{shown} "
            f"({confidence * 100:g} % interval {low} to {high}, "
            f"n = {int(table['n_variant'].values[i, d, f])} and {int(table['n_baseline'].values[i, d, f])} runs).")


def variant_lines(table: xr.Dataset) -> list[str]:
    """One line per variant and feature whose verdicts were compared: the variant's verdict statement, the shift of
    the detection probability at the requirement with its interval, and the verdict change (``verdict_change``)."""
    lines = []
    for i, variant in enumerate(table["variant"].values):
        for f, feature in enumerate(table["feature"].values):
            change = VERDICT_CHANGE[int(table["verdict_change"].values[i, f])]
            if change == "not_compared":
                continue
            shift = float(table["detection_shift"].values[i, f])
            low, high = (float(v) for v in table["detection_shift_ci"].values[i, f])
            lines.append(f"{variant}, {feature}: {table['variant_statement'].values[i, f]} "
                         f"(baseline {table['baseline_verdict'].values[f]}; detection probability at the requirement "
                         f"{shift:+.2f}, {float(table.attrs['confidence']) * 100:g} % interval {low:+.2f} to "
                         f"{high:+.2f}): {change.replace('_', ' ')}")
    return lines


def is_model_form(results: xr.Dataset) -> bool:
    """Whether a campaign is a model-form study (a data set named ``<baseline>__<label>``)."""
    return any(SEPARATOR in str(n) for n in results["dataset"].values)


def write_model_form(results: xr.Dataset, analysis: xr.Dataset, path: str | Path) -> Path:
    """Write :func:`model_form_dataset` as a CF netCDF file (``model_form.nc``)."""
    table = model_form_dataset(results, analysis)
    return write_netcdf(table, path, title=f"Model-form table of {results.attrs.get('title', 'a BenchTwin campaign')}",
                        history=f"campaigns.analysis.model_form.write_model_form -> {Path(path).name}")
