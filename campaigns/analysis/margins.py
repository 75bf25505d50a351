"""Control robustness of a campaign: the loop margins of every run against design limits.

The bench adapter stores, per run, the gain margin, phase margin, crossover frequency and peak
sensitivity ``|S|max`` of each control loop at the run's sampled parameters (variables with
``role = "margin"``, :func:`campaigns.bench.adapter.margin_variables`). Per data set this module computes

* the distribution of each margin (empirical quantiles, inverted CDF, over every run whose margin is not NaN:
  the margins are a property of the parameters, so failed runs count too);
* its worst case and the run that has it (smallest gain/phase margin and crossover, largest ``|S|max``);
* its Spearman rank correlation with each feature (e.g. ``f_b``), with a percentile-bootstrap interval
  and ``n`` (runs that are ok with a finite feature and margin), by the analysis's own estimator;
* the runs below the design limits (:class:`ControlLimits`, the spec's optional ``[control_limits]``
  table; defaults in ``docs/control_design.md``);

and, for each loop and limit over the whole campaign, a verdict on the limit: the fraction of runs
beyond it, with its exact (Clopper-Pearson) 95 % interval, against the allowed fraction
``max_fraction_beyond``, decided by the analysis's verdict rule
(:func:`campaigns.statistics.detection.requirement_verdict`): ``met`` when the upper bound is within the allowed
fraction, ``not met`` when the lower bound is at or above it, ``undetermined`` otherwise, and
``insufficient data`` below ``min_ok_runs`` runs with the margin. The one-sentence statement of each
verdict is stored in ``analysis.nc`` and printed verbatim by the CLI and the report.

:func:`control_robustness` is one of the analyses :func:`campaigns.analysis.campaign_analysis.analysis_dataset`
composes.
"""

from __future__ import annotations

import json
import math

import numpy as np
import xarray as xr
from scipy import stats

from campaigns.analysis.settings import AnalysisSettings, on_threads
from campaigns.analysis.vocabulary import features_of
from campaigns.runner.control_limits import ControlLimits
from campaigns.statistics.correlation import bootstrap_correlation
from campaigns.statistics.defaults import CONFIDENCE
from campaigns.statistics.detection import MAX_RUNS_TO_DECIDE, requirement_verdict

__all__ = ["ControlLimits", "LIMITS", "control_robustness", "limits_of", "statements"]

#: Quantiles of each margin's distribution.
QUANTILES = (0.0, 0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99, 1.0)
#: Which end of a margin's distribution is the worst case.
WORST = {"gain_margin": "min", "phase_margin": "min", "crossover_frequency": "min", "peak_sensitivity": "max"}
#: Spawn-key tag of the margin-correlation bootstraps' random streams.
_MARGIN_STREAM = 1_000_099


#: ``{limit: (metric, field of ControlLimits, comparison, unit, symbol)}``: a run is beyond the limit when
#: ``comparison(margin, limit)`` is true. ``unit`` is the limit's (and the statements'): the gain margin limit is
#: in dB (``[control_limits]``), the stored gain margins are amplitude ratios (units "1"), compared as such.
LIMITS = {
    "phase_margin": ("phase_margin", "phase_margin_min", "<", "degree", "PM"),
    "gain_margin": ("gain_margin", "gain_margin_min", "<", "dB", "GM"),
    "peak_sensitivity": ("peak_sensitivity", "peak_sensitivity_max", ">", "1", "|S|max"),
}
_UNIT_TEXT = {"degree": "°", "dB": " dB", "1": "", "Hz": " Hz"}


def as_ratio(values, units: str):
    """Gain margins as amplitude ratios: files written before the ratio was stored hold them in dB."""
    values = np.asarray(values, dtype=float)
    return 10.0 ** (values / 20.0) if units == "dB" else values


def decibels(ratio):
    """An amplitude ratio in dB (``20 log10``; ``inf`` stays ``inf``): how the statements and the report show a
    gain margin."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return 20.0 * np.log10(np.asarray(ratio, dtype=float))


def margin_values(results: xr.Dataset, name: str) -> np.ndarray:
    """A stored margin variable's values, gain margins as amplitude ratios whatever file version holds them."""
    return as_ratio(results[name].values, str(results[name].attrs.get("units", "")))


def limits_of(results: xr.Dataset) -> ControlLimits:
    """The campaign's limits: its spec's ``control_limits`` (``results.attrs["spec_json"]``), else the defaults."""
    spec = json.loads(results.attrs.get("spec_json", "{}")).get("spec", {})
    return ControlLimits(**spec.get("control_limits", {}))


def _margin_variables(results: xr.Dataset) -> list[str]:
    return [str(v) for v in results.data_vars if results[v].attrs.get("role") == "margin"]


def _beyond(values: np.ndarray, comparison: str, limit: float) -> np.ndarray:
    with np.errstate(invalid="ignore"):
        return values < limit if comparison == "<" else values > limit


def _fraction_interval(k: int, n: int, confidence: float) -> tuple[float, float]:
    """Exact (Clopper-Pearson) interval of a binomial fraction ``k/n`` (scipy.stats.binomtest)."""
    ci = stats.binomtest(k, n).proportion_ci(confidence_level=confidence, method="exact")
    return float(ci.low), float(ci.high)


def _value(value: float, unit: str) -> str:
    """A margin with its unit; an infinite gain margin says why it is infinite, ``nan`` reads "nan"."""
    if not math.isfinite(value):
        # only a gain margin is infinite: the loop's phase never reaches -180 deg (e.g. the analog current loop)
        return "∞ dB, no phase crossover" if value > 0 else str(value)
    return f"{value:.3g}{_UNIT_TEXT.get(unit, ' ' + unit)}"


def _shown(value: float, limit: str) -> str:
    """A stored margin value as the statements show it (a gain margin ratio in dB)."""
    return _value(float(decibels(value)) if limit == "gain_margin" else value, LIMITS[limit][3])




def _fraction_bounds(k: float, n: float, confidence: float) -> tuple[float, float]:
    """The Clopper-Pearson bounds through the beta quantiles (``k`` may be fractional: a fraction held at ``k/n``);
    equal to :func:`_fraction_interval` for whole ``k``."""
    alpha = 1.0 - confidence
    lower = 0.0 if k <= 0 else float(stats.beta.ppf(0.5 * alpha, k, n - k + 1))
    upper = 1.0 if k >= n else float(stats.beta.ppf(1.0 - 0.5 * alpha, k + 1, n - k))
    return lower, upper


def fraction_runs_to_decide(k: int, n: int, allowed: float, confidence: float = CONFIDENCE) -> float:
    """The fewest runs at which an undetermined limit verdict would be decided if the observed fraction ``k/n`` held:
    the smallest ``N > n`` whose exact (Clopper-Pearson) interval around ``k N / n`` runs beyond the limit lies wholly
    within the allowed fraction (met) or wholly beyond it (not met). ``0 of 350`` runs beyond a 1 % limit: the upper
    bound is ``1 - 0.025^(1/N)``, within 1 % from ``N = 368``. NaN when the fraction equals the allowed one (no number
    of runs decides it), ``inf`` beyond :data:`MAX_RUNS_TO_DECIDE`."""
    fraction = k / n
    if fraction == allowed or n <= 0:
        return math.nan
    met = fraction < allowed

    def decided(runs: int) -> bool:
        lower, upper = _fraction_bounds(fraction * runs, runs, confidence)
        return upper <= allowed if met else lower >= allowed

    high = n + 1
    while not decided(high):
        if high > MAX_RUNS_TO_DECIDE:
            return math.inf
        high *= 2
    low = max(n, high // 2)
    while high - low > 1:  # the bounds narrow as runs grow: bisect between a size that does not and one that does
        middle = (low + high) // 2
        low, high = (low, middle) if decided(middle) else (middle, high)
    return float(high)


def limit_statement(verdict: str, loop: str, limit: str, threshold: float, k: int, n: int, bounds, allowed: float,
                    worst: float, worst_where: str, *, confidence: float, min_ok_runs: int) -> str:
    """The one sentence stating a limit's verdict with the numbers it rests on (``threshold`` in the limit's unit,
    ``worst`` as stored: a gain margin as an amplitude ratio)."""
    _, _, comparison, unit, symbol = LIMITS[limit]
    rule = f"{loop} loop {symbol} {'≥' if comparison == '<' else '≤'} {_value(threshold, unit)}"
    if verdict == "insufficient data":
        return (f"insufficient data: {rule}: {n} run{'s' if n != 1 else ''} with a finite margin "
                f"(at least {min_ok_runs} needed)")
    lower, upper = bounds
    return (f"{verdict}: {rule}: {k} of {n} runs beyond the limit ({confidence * 100:g} % exact bounds on the "
            f"fraction: {lower * 100:.2g}–{upper * 100:.2g} %, allowed {allowed * 100:g} %); worst "
            f"{_shown(worst, limit)} ({worst_where})")


def control_robustness(results: xr.Dataset, settings: AnalysisSettings) -> xr.Dataset:
    """The control-robustness statistics of a campaign's results (variables prefixed ``margin_``): the margins'
    quantiles and worst runs, their Spearman correlation with each feature, and per loop and limit the fraction of
    runs beyond it with its exact bounds and verdict (:func:`campaigns.statistics.detection.requirement_verdict`).
    Without margin variables (a campaign that did not run the bench) the result is empty.
    """
    features = features_of(results)
    n_boot, confidence, seed, min_ok_runs = settings.n_boot, settings.confidence, settings.seed, settings.min_ok_runs
    margins = _margin_variables(results)
    if not margins:
        return xr.Dataset()
    limits = limits_of(results)
    names = [str(n) for n in results["dataset"].values]
    runs = results["run"].values
    loops = list(dict.fromkeys(str(results[m].attrs["loop"]) for m in margins))
    n_d, n_m, n_f = len(names), len(margins), len(features)
    quantiles = np.full((n_d, n_m, len(QUANTILES)), math.nan)
    n_finite = np.zeros((n_d, n_m), dtype=np.int32)  # netCDF classic integers (CF 1.8)
    worst = np.full((n_d, n_m), math.nan)
    worst_run = np.full((n_d, n_m), -1, dtype=np.int32)
    spearman = np.full((n_d, n_m, n_f), math.nan)
    spearman_ci = np.full((n_d, n_m, n_f, 2), math.nan)
    n_corr = np.zeros((n_d, n_m, n_f), dtype=np.int32)
    ok = (results["status"] == "ok").values
    correlated = []  # (data set, margin, feature, margin values, feature values) of each Spearman bootstrap
    for m, name in enumerate(margins):
        values = margin_values(results, name)
        metric = str(results[name].attrs["metric"])
        for d in range(n_d):
            finite = ~np.isnan(values[d])
            n_finite[d, m] = int(finite.sum())
            if not finite.any():
                continue
            # empirical quantiles without interpolation: an infinite gain margin (no phase crossover) stays infinite
            quantiles[d, m] = np.quantile(values[d][finite], QUANTILES, method="inverted_cdf")
            pick = np.argmin if WORST[metric] == "min" else np.argmax
            index = np.nonzero(finite)[0][pick(values[d][finite])]
            worst[d, m], worst_run[d, m] = values[d, index], runs[index]
            for f, feature in enumerate(features):
                used = ok[d] & finite & np.isfinite(values[d]) & np.isfinite(results[feature].values[d])
                n_corr[d, m, f] = int(used.sum())
                x, y = values[d][used], results[feature].values[d][used]
                if n_corr[d, m, f] < min_ok_runs or np.ptp(x) == 0.0 or np.ptp(y) == 0.0:
                    continue  # too few runs, or a constant margin (e.g. an infinite gain margin): no correlation
                correlated.append((d, m, f, x, y))

    def correlate(task) -> None:
        d, m, f, x, y = task
        spearman[d, m, f], *spearman_ci[d, m, f] = bootstrap_correlation(
            x, y, "spearman", n_boot=n_boot, confidence=confidence,
            seed=np.random.SeedSequence(seed, spawn_key=(_MARGIN_STREAM, d, m, f)))

    on_threads(correlate, correlated)  # each bootstrap alone, from its own stream

    # runs beyond a limit, and the verdict per loop and limit over the campaign
    beyond_count = np.zeros((n_d, len(runs)), dtype=np.int32)
    beyond_text = np.full((n_d, len(runs)), "", dtype=object)
    verdicts, sentences, fraction, fraction_ci, counts, to_decide = [], [], [], [], [], []
    for loop in loops:
        for limit, (metric, field, comparison, unit, symbol) in LIMITS.items():
            name = f"{loop}_loop_{metric}"
            threshold = getattr(limits, field)
            values = margin_values(results, name) if name in results else np.full((n_d, len(runs)), math.nan)
            stored = float(10.0 ** (threshold / 20.0)) if unit == "dB" else threshold  # the limit as stored
            beyond = _beyond(values, comparison, stored)
            for d, r in zip(*np.nonzero(beyond), strict=True):
                beyond_count[d, r] += 1
                entry = f"{loop} {symbol} {_shown(values[d, r], limit)}"
                beyond_text[d, r] = f"{beyond_text[d, r]}; {entry}" if beyond_text[d, r] else entry
            n, k = int((~np.isnan(values)).sum()), int(beyond.sum())
            finite = ~np.isnan(values)
            if finite.any():
                pick = np.nanargmin if WORST[metric] == "min" else np.nanargmax
                d_w, r_w = np.unravel_index(pick(np.where(finite, values, np.nan)), values.shape)
                worst_value, worst_where = float(values[d_w, r_w]), f"{names[d_w]} run {int(runs[r_w])}"
            else:
                worst_value, worst_where = math.nan, "none"
            if n < min_ok_runs:
                verdict, bounds = "insufficient data", (math.nan, math.nan)
            else:
                bounds = _fraction_interval(k, n, confidence)
                verdict = requirement_verdict(*bounds, limits.max_fraction_beyond)
            verdicts.append(verdict)
            sentences.append(limit_statement(verdict, loop, limit, threshold, k, n, bounds, limits.max_fraction_beyond,
                                             worst_value, worst_where, confidence=confidence, min_ok_runs=min_ok_runs))
            to_decide.append(fraction_runs_to_decide(k, n, limits.max_fraction_beyond, confidence)
                             if verdict == "undetermined" else float(min_ok_runs) if verdict == "insufficient data"
                             else math.nan)
            fraction.append(k / n if n else math.nan)
            fraction_ci.append(bounds)
            counts.append((k, n))
    check = [f"{loop}_loop_{limit}" for loop in loops for limit in LIMITS]
    # one variable per margin for the statistics in the margin's own units (CF: one unit per variable)
    per_margin = {}
    for m, name in enumerate(margins):
        unit = "1" if str(results[name].attrs.get("metric")) == "gain_margin" else str(results[name].attrs.get("units",
                                                                                                             "1"))
        what = f"{results[name].attrs.get('loop', '')} loop {str(results[name].attrs.get('metric', name))}".strip()
        per_margin[f"{name}_quantile"] = (("dataset", "margin_probability"), quantiles[:, m], {
            "units": unit, "long_name": f"quantiles of the {what} over the runs with a finite margin"})
        per_margin[f"{name}_worst"] = (("dataset",), worst[:, m], {
            "units": unit, "long_name": f"worst case of the {what} (smallest gain/phase margin and crossover, "
                                        "largest |S|max)"})
    out = xr.Dataset(
        {
            **per_margin,
            "margin_n": (("dataset", "margin"), n_finite, {"units": "1", "long_name": "runs with a finite margin"}),
            "margin_worst_run": (("dataset", "margin"), worst_run,
                                 {"units": "1", "long_name": "run index of the worst case (-1: none)"}),
            "margin_spearman": (("dataset", "margin", "feature"), spearman,
                                {"units": "1", "long_name": "Spearman rank correlation of the margin with the feature "
                                                            "(ok runs, finite margin and feature)"}),
            "margin_spearman_ci": (("dataset", "margin", "feature", "bound"), spearman_ci,
                                   {"units": "1", "long_name": f"{confidence * 100:g} % percentile-bootstrap interval "
                                                               "of margin_spearman"}),
            "margin_spearman_n": (("dataset", "margin", "feature"), n_corr,
                                  {"units": "1", "long_name": "runs entering margin_spearman"}),
            "margin_runs_beyond_limits": (("dataset", "run"), beyond_count,
                                          {"units": "1", "long_name": "number of design limits the run's margins "
                                                                      "violate"}),
            "margin_limits_violated": (("dataset", "run"), beyond_text,
                                       {"long_name": "the run's margins beyond the design limits (empty: none)"}),
            "margin_limit_fraction": (("limit_check",), np.array(fraction),
                                      {"units": "1", "long_name": "fraction of the campaign's runs beyond the limit"}),
            "margin_limit_fraction_ci": (("limit_check", "bound"), np.array(fraction_ci, dtype=float).reshape(-1, 2),
                                         {"units": "1", "long_name": f"{confidence * 100:g} % exact (Clopper-Pearson) "
                                                                     "interval of margin_limit_fraction"}),
            "margin_limit_counts": (("limit_check", "count"), np.array(counts, dtype=np.int32).reshape(-1, 2),
                                    {"units": "1", "long_name": "runs beyond the limit and runs with the margin"}),
            "margin_limit_verdict": (("limit_check",), np.array(verdicts, dtype=object),
                                     {"long_name": "verdict on the design limit: met / not met / undetermined / "
                                                   "insufficient data", "control_limits": limits.model_dump_json()}),
            "margin_limit_runs_to_decide": (("limit_check",), np.array(to_decide, dtype=float), {
                "units": "1",
                "long_name": "runs (with the margin) at which an undetermined verdict would be decided if the "
                             "observed fraction beyond the limit held (campaigns.analysis.margins."
                             "fraction_runs_to_decide; NaN: decided, or the fraction equals the allowed one)"}),
            "margin_limit_statement": (("limit_check",), np.array(sentences, dtype=object),
                                       {"long_name": "the verdict on the design limit with its numbers, in one "
                                                     "sentence"}),
        },
        coords={
            "dataset": ("dataset", np.array(names, dtype=object)),
            "run": ("run", runs, {"units": "1", "long_name": "run index within the data set"}),
            "feature": ("feature", np.array(features, dtype=object)),
            "bound": ("bound", np.array(["lower", "upper"], dtype=object)),
            "margin": ("margin", np.array(margins, dtype=object)),
            "margin_probability": ("margin_probability", np.array(QUANTILES),
                                   {"units": "1", "long_name": "probability of the margin quantile"}),
            "limit_check": ("limit_check", np.array(check, dtype=object)),
            "count": ("count", np.array(["beyond", "total"], dtype=object)),
        },
    )
    out["margin_probability"].encoding["_FillValue"] = None  # a coordinate has no missing values (CF 2.5.1)
    return out


def statements(analysis: xr.Dataset) -> list[str]:
    """The limit statements of an analysis (``"<limit_check>: <statement>"``), empty without margins."""
    if "margin_limit_statement" not in analysis:
        return []
    return [str(s) for s in analysis["margin_limit_statement"].values]
