"""The analysis of a campaign: every analysis of its ``results.nc``, composed into ``analysis.nc``.

Each analysis is a function ``(results, settings) -> xarray.Dataset`` (:class:`campaigns.analysis.settings.
AnalysisSettings`), in a module of its own, and all of them use successful runs only (status ``"ok"`` and a finite
feature; :func:`campaigns.analysis.vocabulary.used`):

* :func:`campaigns.analysis.feature_statistics.feature_statistics`: runs used, excluded and per status, the
  mean, standard deviation and quantiles of each feature with their intervals;
* :func:`campaigns.analysis.correlations.correlations`: Pearson, Spearman, PRCC and the first-order index of
  each feature against each sampled value;
* :func:`campaigns.analysis.separation.separation`: overlap and detection probability between data sets;
* :func:`campaigns.analysis.observability.observability_analysis`: the minimum detectable fault along the sweep
  and the verdict on the requirement (Table 9.3's 1 µm backlash by default);
* :func:`campaigns.analysis.within_unit.within_unit_analysis`: the same judged within a unit (within-unit
  campaigns);
* :func:`campaigns.analysis.margins.control_robustness`: the loop margins against their limits.

Sample-size floors, each from the statistic's own confidence: ``min_ok_runs`` for moments and correlations (which
carry their own intervals), :data:`campaigns.statistics.order_statistics.MIN_DETECTION_RUNS` for the quantile that
sets the detection threshold, and :data:`campaigns.statistics.sensitivity.MIN_RUNS` for the first-order index.
"""

from __future__ import annotations

import json
from datetime import UTC, datetime
from pathlib import Path

import xarray as xr

from campaigns.analysis import model_form
from campaigns.analysis.correlations import correlations
from campaigns.analysis.feature_statistics import feature_statistics
from campaigns.analysis.margins import control_robustness
from campaigns.analysis.observability import observability_analysis
from campaigns.analysis.separation import separation
from campaigns.analysis.settings import AnalysisSettings
from campaigns.analysis.vocabulary import (
    SWEEP_QUANTITIES,
    marked_features,
    requirement_of,
    runs_text,
    stored_spec,
)
from campaigns.analysis.within_unit import within_unit_analysis
from campaigns.runner.files import CONVENTIONS, atomic_write, cf_encoding
from campaigns.statistics import sensitivity
from campaigns.statistics.defaults import CONFIDENCE
from campaigns.statistics.order_statistics import floor_reason
from campaigns.units import estimate_with_interval
from campaigns.units import quantity as quantity_text

#: The analyses of :func:`analysis_dataset`, in the order their variables are merged.
ANALYSES = (feature_statistics, correlations, separation, observability_analysis, within_unit_analysis,
            control_robustness)


def analysis_dataset(results: xr.Dataset, **options) -> xr.Dataset:
    """Every analysis of :data:`ANALYSES` on an opened results dataset, merged, with the settings in the attributes.

    ``options`` are the fields of :class:`campaigns.analysis.settings.AnalysisSettings` (``n_boot``, ``confidence``,
    ``false_alarm_rate``, ``power``, ``seed``, ``min_ok_runs``, ``min_detection_runs``, ``sensitivity_boot``).
    A data set with fewer than ``min_ok_runs`` used runs of a feature is flagged in ``data_sufficient`` and gets NaN
    correlations, indices and detection probabilities for that feature; its mean, standard deviation and quantiles
    are computed at any n, each with the interval its method allows there.
    """
    settings = AnalysisSettings(**options)
    parts = [analyse(results, settings) for analyse in ANALYSES]
    analysis = xr.merge([part.drop_attrs(deep=False) for part in parts], combine_attrs="override")
    analysis.attrs = attributes(results, settings) | parts[ANALYSES.index(within_unit_analysis)].attrs
    return analysis


def attributes(results: xr.Dataset, settings: AnalysisSettings) -> dict:
    """The global attributes of ``analysis.nc``: what it analyses and with which settings."""
    observability = stored_spec(results)["observability"]
    condition = observability.get("condition", "backlash")
    requirement, source = requirement_of(observability)
    return {
        "Conventions": CONVENTIONS,
        "title": f"Analysis of {results.attrs.get('title', 'a BenchTwin campaign')}",
        "source_spec_hash": results.attrs.get("spec_hash", ""),
        "selection": "statistics use runs with status 'ok' and a finite feature; see n_used, n_excluded, n_status",
        "bootstrap": json.dumps({"method": "percentile, pairs resampled", "n_boot": settings.n_boot,
                                 "confidence": settings.confidence, "seed": settings.seed}),
        "false_alarm_rate": settings.false_alarm_rate,
        "detection_power": settings.power,
        "backlash_sweep": json.dumps(observability["sweep"]),
        "min_ok_runs": settings.min_ok_runs,
        "min_detection_runs": settings.detection_runs,
        "min_detection_runs_reason": floor_reason(settings.false_alarm_rate, settings.power, settings.confidence),
        "first_order_min_runs": sensitivity.MIN_RUNS,
        "observability_condition": condition,
        "requirement": requirement,
        "requirement_units": SWEEP_QUANTITIES[condition][1],
        "requirement_source": source,
    }


def summary(analysis: xr.Dataset) -> tuple[list[str], list[str]]:
    """What a user must see of an analysis: per feature, the requirement statement, and the insufficient data sets.

    Returns
    -------
    tuple of list of str
        ``(statements, warnings)``: ``"<feature>: <requirement_statement>"`` per feature, then
        ``"<feature> (<condition> sweep): ..."`` for each further fault sweep (a within-unit campaign's
        ``"<feature> within unit: <within_unit_requirement_statement>"`` after it), each sweep's for the features it
        marks (:func:`campaigns.analysis.vocabulary.marked_features`) alone, and one warning per feature with data
        sets below ``min_ok_runs`` ok runs.
    """
    statements, warnings = [], []
    min_ok_runs = int(analysis.attrs["min_ok_runs"])
    further = sorted(str(v) for v in analysis.data_vars if str(v).startswith("requirement_statement_"))
    marked = {key: marked_features(analysis, key)
              for key in ["", *(name.removeprefix("requirement_statement") for name in further)]}
    for feature in (str(f) for f in analysis["feature"].values):
        if feature in marked[""]:
            statements.append(f"{feature}: {analysis['requirement_statement'].sel(feature=feature).item()}")
        for name in further:  # each further fault sweep's verdict (campaigns.analysis.vocabulary.sweep_key)
            if feature in marked[name.removeprefix("requirement_statement")]:
                statements.append(f"{feature} ({name.removeprefix('requirement_statement_')} sweep): "
                                  f"{analysis[name].sel(feature=feature).item()}")
        if "within_unit_requirement_statement" in analysis and feature in marked[""]:
            statements.append(f"{feature} within unit: "
                              f"{analysis['within_unit_requirement_statement'].sel(feature=feature).item()}")
        n_used = analysis["n_used"].sel(feature=feature)
        short = [f"{d} ({runs_text(int(n))})" for d, n in zip(analysis["dataset"].values, n_used.values, strict=False)
                 if n < min_ok_runs]
        if len(short) == len(n_used) > 1 and len(set(n_used.values)) == 1:
            short = [f"all {len(short)} data sets ({runs_text(int(n_used[0]))} each)"]
        if short:
            means = [f"{d} {mean_text(analysis, str(d), feature)}" for d, n in zip(
                analysis["dataset"].values, n_used.values, strict=True) if 0 < n < min_ok_runs]
            warnings.append(
                f"{feature}: insufficient data in {', '.join(short)}: fewer than {min_ok_runs} ok runs, "
                "their correlations, indices and detection probabilities are NaN"
                + (f"; their means (flagged): {', '.join(means)}" if means else ""))
    return statements, warnings


def mean_text(analysis: xr.Dataset, dataset: str, feature: str) -> str:
    """A data set's mean of a feature with its t interval, at the precision the interval resolves: ``1.23 µm (95 %
    interval 1.1 … 1.4 µm, n = 8)``; one run has no interval, and says so."""
    cell = analysis.sel(dataset=dataset, feature=feature)
    n, mean = int(cell["n_used"]), float(cell["feature_mean"])
    unit = str(analysis["feature_units"].sel(feature=feature).item()) if "feature_units" in analysis.coords else "1"
    if "feature_mean_ci" not in analysis or n < 2:
        return f"{quantity_text(mean, unit)} ({runs_text(n)}, no interval)" if n else "– (no ok run)"
    low, high = (float(v) for v in cell["feature_mean_ci"].values)
    confidence = float(json.loads(analysis.attrs.get("bootstrap", "{}")).get("confidence", CONFIDENCE))
    return estimate_with_interval(mean, low, high, unit, confidence).removeprefix("+").replace(")", f", n = {n})", 1)


def analyze(results_path: str | Path, out_path: str | Path | None = None, **options) -> Path:
    """Analyse a campaign's ``results.nc`` and write ``analysis.nc`` (and, for a model-form study, its table
    ``model_form.nc`` beside it: :mod:`campaigns.analysis.model_form`).

    Parameters
    ----------
    results_path : str or Path
    out_path : str or Path, optional
        Default: ``analysis.nc`` next to the results.
    **options
        ``n_boot``, ``confidence``, ``false_alarm_rate``, ``power``, ``seed``
        (see :func:`analysis_dataset`).

    Returns
    -------
    Path
        The written file.
    """
    results_path = Path(results_path)
    out_path = Path(out_path) if out_path is not None else results_path.with_name("analysis.nc")
    with xr.open_dataset(results_path, engine="netcdf4") as results:
        analysis = analysis_dataset(results.load(), **options)
        history = str(results.attrs.get("history", "")).strip()
    stamp = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    analysis.attrs["history"] = "\n".join(
        [line for line in (history, f"{stamp}: "
                                    f"campaigns.analysis.campaign_analysis.analyze({results_path.name})") if line])
    atomic_write(out_path, lambda tmp: analysis.to_netcdf(tmp, engine="netcdf4", encoding=cf_encoding(analysis)))
    if model_form.is_model_form(results):  # a model-form study: its table beside the analysis (issue 33)
        model_form.write_model_form(results, analysis, out_path.with_name(model_form.FILE_NAME))
    return out_path
