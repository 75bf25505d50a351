"""Observability: along the spec's fault sweep (data sets that differ only in the swept condition), the smallest
fault detectable against the reference data set, compared with the requirement (Table 9.3's 1 µm backlash by
default). The sweep levels bracketing it are the finding; a value between them is printed only where the sweep
resolves it (:func:`campaigns.statistics.detection.sweep_resolution`).

A within-unit campaign's between-unit sweep uses one test per unit (repeat 0 of each unit): a unit's tests share its
fixed errors and are not independent draws (:mod:`campaigns.analysis.within_unit` judges them within the unit).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from campaigns.analysis.settings import OBSERVABILITY_STREAM, AnalysisSettings
from campaigns.analysis.vocabulary import (
    BACKLASH_REQUIREMENT,
    REQUIREMENT_SOURCE,
    RESOLUTION_ATTRS,
    STATEMENT_ATTRS,
    SWEEP_FEATURE,
    SWEEP_FEATURE_ATTRS,
    SWEEP_QUANTITIES,
    VERDICT_ATTRS,
    features_of,
    is_within_unit,
    requirement_of,
    runs_text,
    stored_spec,
    sweep_features,
    sweep_levels,
    sweeps_of,
    used,
)
from campaigns.statistics.defaults import CONFIDENCE, FALSE_ALARM_RATE, POWER
from campaigns.statistics.detection import (
    DETECTION_INTERVAL_METHOD,
    RESOLUTIONS,
    bootstrap_minimum_detectable,
    detection_probability,
    requirement_verdict,
    runs_to_decide,
)
from campaigns.statistics.order_statistics import MIN_DETECTION_RUNS, detection_run_floor, floor_reason


def requirement_statement(
    verdict: str,
    estimate: float,
    bounds: tuple[float, float],
    n_used: dict[str, int],
    *,
    resolution: str = "resolved",
    bracket: tuple[float, float] = (math.nan, math.nan),
    levels: dict[str, float] | None = None,
    confidence: float = CONFIDENCE,
    power: float = POWER,
    false_alarm_rate: float = FALSE_ALARM_RATE,
    min_runs: int = MIN_DETECTION_RUNS,
    condition: str = "backlash",
    requirement: float = BACKLASH_REQUIREMENT,
    requirement_source: str = "Table 9.3",
) -> str:
    """The one sentence that states the verdict on the requirement (Table 9.3's by default), from the numbers.

    Parameters
    ----------
    verdict : str
        From :func:`requirement_verdict`, or ``"insufficient data"``.
    estimate : float
        The value that may be printed [SI] (``printed`` of :func:`bootstrap_minimum_detectable`); used only when
        ``resolution`` is ``"resolved"``.
    bounds : tuple of float
        Bootstrap bounds [SI] (lower: a level not detected, upper: a level detected, ``inf``: possibly beyond the
        sweep).
    n_used : dict
        Ok runs of each sweep data set (empty: no sweep).
    resolution, bracket
        From :func:`sweep_resolution`; the sweep levels around the estimate (:func:`minimum_detectable`).
    levels : dict, optional
        Fault size of each sweep data set [SI]: every level the sentence gives is named by its data set.
    confidence, power, false_alarm_rate, min_runs
        As used for the numbers (``min_runs``: the floor of every sweep data set, :func:`detection_run_floor`).
    condition, requirement, requirement_source
        The swept condition (:data:`SWEEP_QUANTITIES`), the requirement on its fault size (SI) and its source.
    """
    quantity, _, scale, unit = SWEEP_QUANTITIES[condition]
    names = {}
    for name, value in (levels or {}).items():
        names.setdefault(float(value), name)

    def fmt(value: float) -> str:  # in the display unit of the fault quantity (µm for the backlash)
        shown = value * scale  # three significant digits, never an exponent (1000 N, not 1e+03 N)
        return f"{shown:.3g} {unit}" if abs(shown) < 1000 else f"{shown:.0f} {unit}"

    def level(value: float) -> str:  # a sweep level, named by its data set
        return f"{fmt(value)} ({names[value]})" if value in names else fmt(value)

    against = f"against the {fmt(requirement)} requirement of {requirement_source}"
    if not n_used:
        return (
            "insufficient data: the spec has no observability sweep, "
            f"so no minimum detectable {quantity} is estimated {against}")
    short = [f"{name} has {runs_text(n)}" for name, n in n_used.items() if n < min_runs]
    if len(short) == len(n_used) > 1 and len(set(n_used.values())) == 1:
        short = [f"each of the {len(n_used)} sweep data sets has {runs_text(next(iter(n_used.values())))}"]
    if short:
        return (
            f"insufficient data: {', '.join(short)}; at least {min_runs} per sweep data set are needed "
            f"({floor_reason(false_alarm_rate, power, confidence)}), "
            f"so no minimum detectable {quantity} is estimated {against}"
        )
    counts = sorted(set(n_used.values()))
    runs = f"{counts[0]}" if len(counts) == 1 else f"{counts[0]}–{counts[-1]}"
    lower, upper = bounds
    if resolution == "resolved":
        value = fmt(estimate)
    elif resolution == "between_adjacent_levels":
        value = f"between the adjacent sweep levels {level(bracket[0])} and {level(bracket[1])}"
    else:
        value = (f"above {level(bracket[0])}, the largest sweep level: detection probability below {power * 100:g} % "
                 "along the whole sweep")
    upper_text = f"at most {level(upper)}" if math.isfinite(upper) else "possibly beyond the sweep"
    return (
        f"{verdict}: minimum detectable {quantity} {value} ({confidence * 100:g} % bootstrap bounds: above "
        f"{level(lower)}, {upper_text}; {runs} ok runs per sweep data set, {len(n_used)} data sets) {against}"
    )


def observability_sweep(
    results: xr.Dataset,
    feature: str,
    datasets: list[str],
    *,
    false_alarm_rate: float = FALSE_ALARM_RATE,
    power: float = POWER,
    n_boot: int = 1000,
    confidence: float = CONFIDENCE,
    min_runs: int | None = None,
    seed=None,
    condition: str = "backlash",
    reference: str | None = None,
    requirement: float = BACKLASH_REQUIREMENT,
    requirement_source: str = REQUIREMENT_SOURCE,
) -> xr.Dataset:
    """Detection probability along a fault sweep, the minimum detectable fault size and the verdict.

    Parameters
    ----------
    results : xarray.Dataset
        Campaign results (``results.nc``).
    feature : str
    datasets : list of str
        The sweep (data sets differing only in backlash, ``observability.sweep``
        of the spec); the data set with zero backlash is the reference.
    false_alarm_rate, power : float
        The detection threshold flags ``false_alarm_rate`` of the reference runs;
        the minimum detectable backlash is where the detection probability reaches ``power``.
    n_boot, confidence, seed
        Bootstrap of :func:`bootstrap_minimum_detectable`.
    min_runs : int, optional
        Ok runs every sweep data set needs (default :func:`detection_run_floor` of the settings); below it the
        verdict is ``"insufficient data"`` and the detection probability of that data set is NaN (of every data
        set, when the reference is short).
    condition, reference, requirement, requirement_source
        The swept scene condition (:data:`SWEEP_QUANTITIES`; ``observability.condition`` of the
        spec), the reference data set (default: the one where it is zero), the requirement on the
        fault size (SI) and its source.

    Returns
    -------
    xarray.Dataset
        ``sweep_<q>(sweep_point)``, ``sweep_detection_probability(sweep_point)``,
        the scalar ``minimum_detectable_<q>`` (the requirement in its attributes; NaN unless the sweep
        resolves it), ``minimum_detectable_status`` (:data:`RESOLUTIONS`, numeric flags),
        ``minimum_detectable_bracket(bound)`` (the sweep levels around the estimate),
        ``minimum_detectable_<q>_ci(bound)``, ``requirement_verdict`` and ``requirement_statement``,
        where ``<q>`` is the fault quantity (``backlash``, ``preload_loss``).
    """
    backlash, reference = sweep_levels(results, datasets, condition, reference)
    mask = used(results, feature)
    samples = [results[feature].sel(dataset=n).values[mask.sel(dataset=n).values] for n in datasets]
    n_used = {n: len(s) for n, s in zip(datasets, samples, strict=False)}
    if min_runs is None:
        min_runs = detection_run_floor(false_alarm_rate, power, confidence)
    settings = {"false_alarm_rate": false_alarm_rate, "power": power, "confidence": confidence}
    found, verdict, needed, needed_reason = _detection(backlash, samples, reference, datasets, n_used, min_runs,
                                                       settings, n_boot, seed, condition, requirement)
    statement = requirement_statement(
        verdict, found["printed"], found["bounds"], n_used, resolution=found["resolution"], bracket=found["bracket"],
        levels=dict(zip(datasets, backlash, strict=True)), min_runs=min_runs, condition=condition,
        requirement=requirement, requirement_source=requirement_source.removeprefix("Bertolino (2020) ").split(":")[0],
        **settings,
    )
    return _sweep_dataset(datasets, reference, backlash, found, verdict, statement, needed, needed_reason, n_boot,
                          settings, condition, requirement, requirement_source)


def _detection(levels: np.ndarray, samples: list[np.ndarray], reference: int, datasets: list[str],
               n_used: dict[str, int], min_runs: int, settings: dict, n_boot: int, seed, condition: str,
               requirement: float) -> tuple[dict, str, float, str]:
    """The numbers of :func:`observability_sweep`: ``(found, verdict, runs_to_decide, its reason)``, ``found`` as
    :func:`bootstrap_minimum_detectable` returns it (its fields NaN and the resolution ``insufficient_data`` below
    the run floor, where only the data sets with enough runs, and a reference with enough, get a probability)."""
    false_alarm_rate, power, confidence = settings["false_alarm_rate"], settings["power"], settings["confidence"]
    if min(n_used.values()) < min_runs:
        nan2 = (math.nan, math.nan)
        reason = (f"{min_runs} ok runs per sweep data set are needed before any verdict "
                  f"({floor_reason(false_alarm_rate, power, confidence)})")
        enough = [len(s) >= min_runs and n_used[datasets[reference]] >= min_runs for s in samples]
        probability = np.array([detection_probability(samples[reference], s, false_alarm_rate) if ok else math.nan
                                for s, ok in zip(samples, enough, strict=False)])
        found = {"estimate": math.nan, "printed": math.nan, "bracket": nan2, "bounds": nan2, "probability": probability,
                 "resolution": "insufficient_data", "probability_ci": np.full((len(datasets), 2), math.nan)}
        return found, "insufficient data", float(min_runs), reason
    found = bootstrap_minimum_detectable(levels, samples, reference, n_boot=n_boot, seed=seed, **settings)
    verdict = requirement_verdict(*found["bounds"], requirement)
    if verdict != "undetermined":
        return found, verdict, math.nan, "the verdict is decided"
    _, _, scale, shown = SWEEP_QUANTITIES[condition]
    needed, reason = runs_to_decide(
        levels, found["probability"], found["probability_se"], min(n_used.values()), requirement, power=power,
        confidence=confidence, labels=[f"{b * scale:.3g} {shown} ({n})" for b, n in zip(levels, datasets, strict=True)])
    return found, verdict, needed, reason


def _sweep_dataset(datasets: list[str], reference: int, levels: np.ndarray, found: dict, verdict: str,
                   statement: str, needed: float, needed_reason: str, n_boot: int, settings: dict, condition: str,
                   requirement: float, requirement_source: str) -> xr.Dataset:
    """The variables of :func:`observability_sweep` from its numbers, with their attributes."""
    false_alarm_rate, power, confidence = settings["false_alarm_rate"], settings["power"], settings["confidence"]
    quantity, unit, _, _ = SWEEP_QUANTITIES[condition]
    stem = quantity.replace(" ", "_")
    return xr.Dataset(
        {
            f"sweep_{stem}": ("sweep_point", levels,
                              {"units": unit, "long_name": f"{quantity} of the sweep data set"}),
            "sweep_detection_probability": (
                "sweep_point",
                found["probability"],
                {"units": "1",
                 "long_name": f"detection probability at false-alarm rate {false_alarm_rate:g} against "
                              f"{datasets[reference]} (NaN: insufficient data)"},
            ),
            "sweep_detection_probability_ci": (
                ("sweep_point", "bound"),
                found["probability_ci"],
                {"units": "1", "long_name": f"{confidence:g} interval of sweep_detection_probability (NaN: "
                                            "insufficient data)", "method": DETECTION_INTERVAL_METHOD}),
            f"minimum_detectable_{stem}": (
                (),
                found["estimate"] if found["resolution"] == "resolved" else math.nan,
                {
                    "units": unit,
                    "long_name": f"smallest {quantity} detected with probability {power:g} at false-alarm rate "
                                 f"{false_alarm_rate:g}, interpolated along the sweep, only where the sweep "
                                 "resolves it (minimum_detectable_status = resolved), else NaN: read "
                                 "minimum_detectable_bracket; print it rounded at the leading digit of the "
                                 "half-width of its bounds (campaigns.statistics.detection.printed_estimate)",
                    "requirement": requirement,
                    "requirement_source": requirement_source,
                },
            ),
            "minimum_detectable_status": ((), np.int8(RESOLUTIONS.index(found["resolution"])), RESOLUTION_ATTRS),
            "minimum_detectable_bracket": (
                "bound",
                np.array(found["bracket"]),
                {"units": unit,
                 "long_name": f"sweep levels bracketing minimum_detectable_{stem} (inf: never detected)"},
            ),
            f"minimum_detectable_{stem}_ci": (
                "bound",
                np.array(found["bounds"]),
                {
                    "units": unit,
                    "long_name": f"bootstrap bounds of the minimum detectable {quantity}: "
                                 "lower = a sweep level not detected "
                    "(the minimum lies above it), upper = a sweep level detected (inf: not reached)",
                    "confidence": confidence,
                    "n_boot": n_boot,
                },
            ),
            "requirement_verdict": ((), verdict, VERDICT_ATTRS),
            "requirement_statement": ((), statement, STATEMENT_ATTRS),
            "runs_to_decide": ((), needed, {
                "units": "1",
                "long_name": "ok runs per sweep data set at which an undetermined (or insufficient-data) verdict "
                             "would be decided if the estimate holds "
                             "(campaigns.statistics.detection.runs_to_decide); NaN: "
                             "decided, or no number of runs decides it (runs_to_decide_reason says which)"}),
            "runs_to_decide_reason": ((), needed_reason, {"long_name": "how runs_to_decide was derived, or why "
                                                                       "there is none"}),
        },
        coords={
            "sweep_point": ("sweep_point", np.array(datasets, dtype=object), {"long_name": "data set of the sweep"}),
            "bound": ("bound", np.array(["lower", "upper"], dtype=object)),
        },
    )


def observability_analysis(results: xr.Dataset, settings: AnalysisSettings) -> xr.Dataset:
    """:func:`observability_sweep` of every feature along each of the stored spec's sweeps, along a ``feature``
    dimension; without a sweep, the verdict ``insufficient data`` with the statement that says why.

    The first sweep's variables keep the names of a spec with one sweep (feature ``f`` bootstraps from
    ``SeedSequence(seed, spawn_key=(OBSERVABILITY_STREAM, f))``); each further sweep's carry its
    :func:`campaigns.analysis.vocabulary.sweep_key` (``requirement_verdict_preload`` along ``sweep_point_preload``,
    the ``sweep`` attribute naming the condition, its verdict's attributes the requirement), with their own streams
    ``(OBSERVABILITY_STREAM, f, k)`` for the k-th sweep. Every feature gets each sweep's verdict; each sweep's
    :data:`~campaigns.analysis.vocabulary.SWEEP_FEATURE` marks those its table's ``features`` names (all by default),
    the ones page 1 and the printed summary give. A within-unit campaign's sweep takes one test per unit, and
    its statement says so."""
    spec = stored_spec(results)
    features = features_of(results)
    feature = ("feature", np.array(features, dtype=object))
    sweeps = sweeps_of(spec)
    if not sweeps:
        statement = requirement_statement("insufficient data", math.nan, (math.nan, math.nan), {})
        n = len(features)
        return xr.Dataset({
            "requirement_verdict": ("feature", np.full(n, "insufficient data", dtype=object), VERDICT_ATTRS),
            "requirement_statement": ("feature", np.full(n, statement, dtype=object), STATEMENT_ATTRS),
            "runs_to_decide": ("feature", np.full(n, math.nan), {"units": "1"}),
            "runs_to_decide_reason": ("feature", np.full(n, "no observability sweep", dtype=object)),
        }, coords={"feature": feature})
    within_unit = is_within_unit(spec)
    # A unit's tests share its fixed errors: between units, one test per unit keeps the sweep's runs independent.
    between_units = results.isel(run=results["repeat"].values == 0) if within_unit else results
    parts = [_sweep_analysis(between_units, features, table, settings, k) for k, (_, table) in enumerate(sweeps)]
    combined = parts[0].assign_coords(feature=feature)
    if within_unit:
        combined["requirement_statement"] = ("feature", np.array(
            [f"{statement}; between units: one test per unit (repeat 0 of each of the "
             f"{between_units.sizes['run']} units), since a unit's tests share its fixed errors and are not "
             "independent draws" for statement in combined["requirement_statement"].values], dtype=object),
            STATEMENT_ATTRS)
    further = [_keyed(part.assign_coords(feature=feature), key, table)
               for part, (key, table) in zip(parts[1:], sweeps[1:], strict=True)]
    return xr.merge([combined, *further], combine_attrs="override") if further else combined


def _sweep_analysis(results: xr.Dataset, features: list[str], table: dict, settings: AnalysisSettings,
                    index: int) -> xr.Dataset:
    """:func:`observability_sweep` of every feature along one sweep table, concatenated along ``feature``."""
    condition = table.get("condition", "backlash")
    requirement, source = requirement_of(table)
    per_feature = [
        observability_sweep(
            results, name, table["sweep"], false_alarm_rate=settings.false_alarm_rate, power=settings.power,
            n_boot=settings.n_boot, confidence=settings.confidence, min_runs=settings.detection_runs,
            seed=np.random.SeedSequence(settings.seed, spawn_key=(OBSERVABILITY_STREAM, f) + ((index,) if index
                                                                                                else ())),
            condition=condition, reference=table.get("reference"), requirement=requirement,
            requirement_source=source,
        )
        for f, name in enumerate(features)
    ]
    levels = f"sweep_{SWEEP_QUANTITIES[condition][0].replace(' ', '_')}"
    combined = xr.concat([s.drop_vars(levels) for s in per_feature], dim="feature")
    combined[levels] = per_feature[0][levels]
    marked = sweep_features(table, features)
    combined[SWEEP_FEATURE] = ("feature", np.array([f in marked for f in features], dtype=np.int8),
                               SWEEP_FEATURE_ATTRS)
    return combined


def _keyed(part: xr.Dataset, key: str, table: dict) -> xr.Dataset:
    """A further sweep's variables and sweep dimension named with its ``key``, each marked with the ``sweep`` it
    belongs to, and what the analysis's global attributes say of the first sweep on its verdict."""
    condition = table.get("condition", "backlash")
    requirement, source = requirement_of(table)
    keyed = part.rename({name: f"{name}{key}" for name in [*part.data_vars, "sweep_point"]})
    for name in keyed.data_vars:
        if name != "feature":
            keyed[name].attrs["sweep"] = condition
    keyed[f"requirement_verdict{key}"].attrs.update({
        "observability_condition": condition, "requirement": requirement,
        "requirement_units": SWEEP_QUANTITIES[condition][1], "requirement_source": source,
        "sweep_reference": str(table.get("reference") or ""), "sweep_data_sets": " ".join(table["sweep"])})
    return keyed
