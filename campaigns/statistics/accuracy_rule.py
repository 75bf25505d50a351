"""The accuracy rule (issue 32, decision 1): a configuration is judged where it is used, at campaign level.

A configuration (a step, a method, a fidelity level) is **accepted** against the tight reference when, on every data
set and every feature, over the same sampled runs (paired: run i has the same parameters and the same noise under
both, so their difference is the configuration's effect alone):

* the 95 % Student-t interval of the mean paired shift (candidate - reference) lies within the tolerance of the
  feature's unit (:data:`MEAN_SHIFT_TOLERANCES`: ±:data:`MEAN_SHIFT_TOLERANCE` for a length,
  ±:data:`TORQUE_SHIFT_TOLERANCE` for a torque);
* the 95 % interval of the standard-deviation ratio (candidate / reference) lies within 1 ± :data:`SD_RATIO_TOLERANCE`;
* every verdict of ``analysis.nc`` (the requirement verdicts, the control-limit verdicts) is unchanged, and so is the
  top-:data:`TOP_RANKED` sensitivity ranking of every data set and feature;

with at least :data:`MIN_PAIRED_RUNS` paired runs per data set. It replaces the per-run rule (one run within 0.1 um
of one tight run), which the reference itself cannot decide on the free-nut data sets (docs/accuracy.md).

:func:`judge_accuracy` applies the whole rule once and returns every verdict with its bounds and n;
:func:`paired_verdict` is its per-data-set/feature part (the fidelity audit applies that part to its few runs).
Verdicts are those of :data:`campaigns.statistics.paired_comparison.VERDICTS`: ``met`` when the interval lies within
the tolerance,
``not met`` when it lies wholly outside it, ``undetermined`` otherwise, ``insufficient data`` below the minimum
number of paired runs (then no figure is printed: the data do not resolve it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy.stats import norm, t

from campaigns.statistics.defaults import CONFIDENCE
from campaigns.statistics.paired_comparison import VERDICTS, Verdict, worst_verdict

#: m: half a tenth of the 1 um backlash the bench must detect (Table 9.3): a shift of the mean at most this large
#: moves no detection threshold by more than 5 % of the requirement (issue 32, decision 1).
MEAN_SHIFT_TOLERANCE = 0.05e-6
#: The standard deviation may change by at most 10 %: the detection probability and the minimum detectable backlash
#: are set by the spread of the features, and the run-to-run sigma at n = 200 is itself known only to about +-10 %
#: (chi-square interval), so a smaller change could not move a campaign's conclusions (issue 32, decision 1).
SD_RATIO_TOLERANCE = 0.10
#: Fewest paired runs per data set for a verdict of the rule: a first-order index (the sensitivity ranking) is
#: printed from 200 used runs (campaigns.statistics.sensitivity.MIN_RUNS), and at 200 the sd ratio's jackknife interval
#: holds its nominal 95 % with skewed, heteroscedastic and two-outcome differences (docs/accuracy.md, "Why these
#: numbers"; tests/campaigns/test_accuracy_rule.py).
MIN_PAIRED_RUNS = 200
#: The sensitivity ranking compared: the tolerances with the largest lower bound of the first-order index's interval
#: (the report's sensitivity table, reports/sections/correlations.py), resolved ones only (lower bound > 0).
TOP_RANKED = 3
#: The tight reference: every subsystem at full fidelity, RK4 at 15.625 us: the largest step of the reference
#: ensemble (campaigns.bench.reference_ensemble), on the converged side of RK4's step study (order ~5 down to 16 us),
#: 8 steps per 125 us drive period; 4x below the full model's 62.5 us default (docs/accuracy.md).
REFERENCE_SOLVER = {"integrator": "rk4", "dt": 15.625e-6, "fidelity": "full"}


#: N m: half a tenth of the change of the true drag torque (Eq. 7.85) that the 200 N preload loss the demo's preload
#: sweep must detect causes (its requirement, campaigns/specs/demo.toml), from 1000 N to 800 N under data set 5
#: conditions (the change: docs/fidelity.md, "The tolerance of a torque"). As for a length, a shift of the mean at most
#: this large moves no detection threshold by more than 5 % of the requirement (10 N of preload loss).
TORQUE_SHIFT_TOLERANCE = 1.43e-3


@dataclass(frozen=True)
class Tolerance:
    """The mean-shift tolerance of features in one SI unit, and how statements print them (``shown``, ``scale``:
    one display unit for every figure of that unit, four decimals)."""

    value: float
    shown: str
    scale: float
    source: str

    def text(self, value: float, signed: bool = True) -> str:
        """``value`` [SI] in the display unit, e.g. ``+0.0100 µm``."""
        return f"{value * self.scale:{'+' if signed else ''}.4f} {self.shown}"


#: The one table of mean-shift tolerances, by the feature's SI unit (its ``units`` attribute in ``results.nc``): the
#: feature's unit decides its tolerance and the unit its statements print.
MEAN_SHIFT_TOLERANCES = {
    "m": Tolerance(MEAN_SHIFT_TOLERANCE, "µm", 1e6, "5 % of the 1 µm backlash requirement (Table 9.3)"),
    "N m": Tolerance(TORQUE_SHIFT_TOLERANCE, "mN·m", 1e3,
                     "5 % of the drag-torque change of the 200 N preload-loss requirement (docs/fidelity.md)"),
}


def tolerance_for(unit: str) -> Tolerance:
    """The :data:`MEAN_SHIFT_TOLERANCES` entry of an SI unit.

    Raises
    ------
    ValueError
        For a unit the table has no tolerance for, naming the units it has.
    """
    if unit not in MEAN_SHIFT_TOLERANCES:
        raise ValueError(f"no mean-shift tolerance for features in {unit!r}; the accuracy rule has tolerances for "
                         f"{', '.join(repr(u) for u in MEAN_SHIFT_TOLERANCES)} "
                         "(campaigns.statistics.accuracy_rule.MEAN_SHIFT_TOLERANCES)")
    return MEAN_SHIFT_TOLERANCES[unit]


def _scaled(tolerance: float, unit: str) -> Tolerance:
    """The display of ``unit`` with another tolerance value (a caller's own, e.g. a study's)."""
    shown = tolerance_for(unit)
    return Tolerance(tolerance, shown.shown, shown.scale, shown.source)


def pairs_for_tolerance(sd_of_differences: float, tolerance: float = MEAN_SHIFT_TOLERANCE,
                        confidence: float = CONFIDENCE) -> int:
    """Fewest paired runs whose mean-shift interval is no wider than ±``tolerance`` (normal quantile: the t quantile's
    large-n limit): the smallest n at which a zero shift with this spread of paired differences could be met."""
    z = norm.ppf(0.5 + confidence / 2)
    return max(2, math.ceil((z * sd_of_differences / tolerance) ** 2))


def mean_shift_verdict(differences, *, tolerance: float = MEAN_SHIFT_TOLERANCE, min_pairs: int = MIN_PAIRED_RUNS,
                       confidence: float = CONFIDENCE, unit: str = "m") -> Verdict:
    """Is the mean of paired differences (candidate - reference, in SI ``unit``) within ±``tolerance``?

    The statement prints the figures in the display unit of ``unit`` (:data:`MEAN_SHIFT_TOLERANCES`).

    Student-t interval ``mean ± t(n-1) s / sqrt(n)``: ``met`` when it lies within ±tolerance (equivalence shown),
    ``not met`` when it lies wholly beyond +tolerance or below -tolerance, ``undetermined`` otherwise (then the
    statement says from how many paired runs a zero shift with this spread would be met), ``insufficient data``
    below ``min_pairs`` finite pairs (at least 2). Non-finite differences are left out.
    """
    shown = _scaled(tolerance, unit)
    d = np.asarray(differences, dtype=float)
    d = d[np.isfinite(d)]
    n, needed = int(d.size), max(min_pairs, 2)
    if n < needed:
        return Verdict("insufficient data", math.nan, math.nan, math.nan, n,
                       f"insufficient data: {n} paired run{'s' if n != 1 else ''}, at least {needed} needed "
                       f"(tolerance ±{shown.text(tolerance, False)})")
    mean, sd = float(d.mean()), float(d.std(ddof=1))
    half = float(t.ppf(0.5 + confidence / 2, n - 1) * sd / math.sqrt(n))
    lower, upper = mean - half, mean + half
    if -tolerance <= lower and upper <= tolerance:
        verdict = "met"
    elif lower > tolerance or upper < -tolerance:
        verdict = "not met"
    else:
        verdict = "undetermined"
    more = (f"; at this spread a zero shift is resolved from {pairs_for_tolerance(sd, tolerance, confidence)} "
            "paired runs" if verdict == "undetermined" else "")
    return Verdict(verdict, mean, lower, upper, n,
                   f"{verdict}: mean shift {shown.text(mean)} ({confidence * 100:g} % t interval {shown.text(lower)} "
                   f"to {shown.text(upper)}, n = {n}; tolerance ±{shown.text(tolerance, False)}{more})")


def _leave_one_out_sum_of_squares(x: np.ndarray) -> np.ndarray:
    """``sum((x_j - mean_without_i)^2 for j != i)`` for every i, in closed form (no n^2 loop)."""
    n = x.size
    deviation = x - x.mean()
    return float(np.sum(deviation**2)) - n / (n - 1) * deviation**2


def sd_ratio_verdict(candidate, reference, *, tolerance: float = SD_RATIO_TOLERANCE,
                     min_pairs: int = MIN_PAIRED_RUNS, confidence: float = CONFIDENCE, unit: str = "m") -> Verdict:
    """Is the standard deviation of the candidate's runs within ``1 ± tolerance`` of the reference's (paired runs)?

    The interval is the jackknife interval of the log variance ratio (Miller 1968, "Jackknifing variances", Ann. Math.
    Statist. 39, 567): ``L = ln(s_c^2 / s_r^2)``, ``L_i`` the same without pair i, ``se^2 = (n-1)/n sum (L_i -
    mean L_i)^2``, ratio interval ``exp((L ± t(n-1) se) / 2)``. Leaving out whole pairs keeps the pairing, and the
    jackknife needs no normality: the Pitman-Morgan interval (exact for bivariate normal pairs) falls far below its
    nominal coverage when the differences' spread depends on the run, this one holds it at 200 pairs (coverage
    figures: docs/accuracy.md, "Why these numbers"; tests/campaigns/test_accuracy_rule.py). ``met`` within
    ``[1 - tolerance, 1 + tolerance]``, ``not met`` wholly outside it, ``undetermined`` otherwise, ``insufficient
    data`` below ``min_pairs`` (at least 3) finite pairs or when one run carries all the spread (no jackknife). A
    feature without spread in both samples is ``met`` (unchanged), without spread in one only ``not met``.
    """
    sd = tolerance_for(unit)  # the standard deviations printed in the feature's display unit
    c, r = np.asarray(candidate, dtype=float), np.asarray(reference, dtype=float)
    both = np.isfinite(c) & np.isfinite(r)
    c, r = c[both], r[both]
    n, needed = int(c.size), max(min_pairs, 3)
    bounds = f"{1 - tolerance:.2f} to {1 + tolerance:.2f}"
    if n < needed:
        return Verdict("insufficient data", math.nan, math.nan, math.nan, n,
                       f"insufficient data: {n} paired run{'s' if n != 1 else ''}, at least {needed} needed "
                       f"(sd ratio tolerance {bounds})")
    sd_c, sd_r = float(c.std(ddof=1)), float(r.std(ddof=1))
    if sd_c == 0 or sd_r == 0:  # a feature the sampled values do not move (in either: its spread is unchanged)
        verdict, ratio = ("met", 1.0) if sd_c == sd_r else ("not met", math.inf if sd_r == 0 else 0.0)
        return Verdict(verdict, ratio, ratio, ratio, n,
                       f"{verdict}: sd {sd.text(sd_c, False)} against {sd.text(sd_r, False)} (n = {n}; tolerance "
                       f"{bounds} of the reference's)")
    ss_c, ss_r = _leave_one_out_sum_of_squares(c), _leave_one_out_sum_of_squares(r)
    if not (np.all(ss_c > 0) and np.all(ss_r > 0)):
        return Verdict("insufficient data", math.nan, math.nan, math.nan, n,
                       f"insufficient data: the spread of {n} paired runs rests on a single run (sd ratio tolerance "
                       f"{bounds})")
    log_ratio = math.log(np.var(c, ddof=1) / np.var(r, ddof=1))
    left_out = np.log(ss_c / ss_r)
    se = math.sqrt((n - 1) / n * float(np.sum((left_out - left_out.mean()) ** 2)))
    half = float(t.ppf(0.5 + confidence / 2, n - 1) * se)
    ratio, lower, upper = math.exp(log_ratio / 2), math.exp((log_ratio - half) / 2), math.exp((log_ratio + half) / 2)
    if 1 - tolerance <= lower and upper <= 1 + tolerance:
        verdict = "met"
    elif upper < 1 - tolerance or lower > 1 + tolerance:
        verdict = "not met"
    else:
        verdict = "undetermined"
    return Verdict(verdict, ratio, lower, upper, n,
                   f"{verdict}: sd ratio {ratio:.4f} (sd {sd.text(sd_c, False)} against {sd.text(sd_r, False)}; "
                   f"{confidence * 100:g} % jackknife interval {lower:.4f} to {upper:.4f}, n = {n}; "
                   f"tolerance {bounds})")


@dataclass(frozen=True)
class PairedVerdict:
    """The rule's verdict on one data set and feature: its two parts and, worst first, the verdict of both."""

    verdict: str
    mean: Verdict
    sd: Verdict

    @property
    def statement(self) -> str:
        """The one sentence every output prints: the verdict, then each part with its numbers and its own verdict
        (one clause when neither part has the runs it needs)."""
        if self.mean.verdict == self.sd.verdict == "insufficient data" and self.mean.n == self.sd.n:
            return f"insufficient data: {_body(self.mean)}; sd ratio: the same"
        return f"{self.verdict}: {_body(self.mean)}: {self.mean.verdict}; {_body(self.sd)}: {self.sd.verdict}"


def _body(verdict: Verdict) -> str:
    """A part's statement without its leading verdict (every statement starts with ``"<verdict>: "``)."""
    return verdict.statement.removeprefix(f"{verdict.verdict}: ")


def paired_verdict(candidate, reference, *, mean_tolerance: float | None = None,
                   sd_tolerance: float = SD_RATIO_TOLERANCE, min_pairs: int = MIN_PAIRED_RUNS,
                   confidence: float = CONFIDENCE, unit: str = "m") -> PairedVerdict:
    """The rule on one data set and feature: the mean shift and the sd ratio over the pairs finite in both (SI
    ``unit``; ``mean_tolerance`` None: the unit's, :data:`MEAN_SHIFT_TOLERANCES`)."""
    mean_tolerance = tolerance_for(unit).value if mean_tolerance is None else mean_tolerance
    c, r = np.asarray(candidate, dtype=float), np.asarray(reference, dtype=float)
    both = np.isfinite(c) & np.isfinite(r)
    mean = mean_shift_verdict(c[both] - r[both], tolerance=mean_tolerance, min_pairs=min_pairs, confidence=confidence,
                              unit=unit)
    sd = sd_ratio_verdict(c[both], r[both], tolerance=sd_tolerance, min_pairs=min_pairs, confidence=confidence,
                          unit=unit)
    return PairedVerdict(worst_verdict([mean.verdict, sd.verdict]), mean, sd)


def paired_values(candidate: xr.Dataset, reference: xr.Dataset, dataset: str, feature: str):
    """One data set's feature values of the runs ok in both campaigns (the same run indices), candidate first."""
    runs = min(candidate.sizes["run"], reference.sizes["run"])
    a = candidate.sel(dataset=dataset).isel(run=slice(0, runs))
    b = reference.sel(dataset=dataset).isel(run=slice(0, runs))
    ok = ((a.status == "ok") & (b.status == "ok")).values
    return a[feature].values[ok], b[feature].values[ok]


def top_ranked(analysis: xr.Dataset, dataset: str, feature: str, k: int = TOP_RANKED) -> tuple[str, ...]:
    """The ``k`` tolerances with the largest lower bound of the first-order index's interval, among those the runs
    resolve (lower bound > 0), largest first (ties in parameter order): the sensitivity ranking the rule compares."""
    lower = analysis["first_order_index_ci"].sel(dataset=dataset, feature=feature, bound="lower").values
    resolved = np.flatnonzero(np.isfinite(lower) & (lower > 0))
    order = resolved[np.argsort(-lower[resolved], kind="stable")][:k]
    return tuple(str(analysis["parameter"].values[j]) for j in order)


def analysis_verdicts(analysis: xr.Dataset) -> dict[str, str]:
    """Every verdict stored in ``analysis.nc`` (each ``*_verdict`` variable, one entry per element), by a label that
    names the variable and its coordinates, e.g. ``requirement_verdict[backlash_feature]``."""
    found = {}
    for name in sorted(str(v) for v in analysis.data_vars if str(v).endswith("_verdict")):
        values = analysis[name]
        for index in np.ndindex(values.shape):
            labels = [str(values[dim].values[i]) if dim in values.coords else str(i)
                      for dim, i in zip(values.dims, index, strict=True)]
            found[f"{name}[{', '.join(labels)}]" if labels else name] = str(values.values[index])
    return found


def _change_verdict(changed: bool, n: int, min_pairs: int) -> str:
    """``met`` (unchanged), ``not met`` (changed), or ``insufficient data`` below ``min_pairs`` paired runs."""
    return "insufficient data" if n < min_pairs else "not met" if changed else "met"


def _analysis_checks(judged: xr.Dataset, candidate: xr.Dataset, reference: xr.Dataset,
                     min_pairs: int) -> tuple[xr.Dataset, dict[str, str]]:
    """The rule's analysis part: per data set and feature the top ranking of each analysis and whether it changed
    (judged on that cell's paired runs), per analysis verdict each campaign's and whether it changed (judged on the
    fewest paired runs of any cell: a campaign-level verdict rests on all of them). Returns the judgement with these
    variables and ``{what was checked: met / not met / insufficient data}``."""
    cells = [(str(d), str(f)) for d in judged.dataset.values for f in judged.feature.values]
    dims, shape = ("dataset", "feature"), (judged.sizes["dataset"], judged.sizes["feature"])
    rankings = {cell: (top_ranked(reference, *cell), top_ranked(candidate, *cell)) for cell in cells}
    ranking = {cell: _change_verdict(ref != cand, int(judged.n.sel(dataset=cell[0], feature=cell[1])), min_pairs)
               for cell, (ref, cand) in rankings.items()}
    for label, which in (("reference", 0), ("candidate", 1)):
        judged[f"ranking_{label}"] = (
            dims, np.array([" > ".join(rankings[c][which]) or "none resolved" for c in cells], dtype=object)
            .reshape(shape),
            {"long_name": f"the {label}'s top-{TOP_RANKED} tolerances by the lower bound of the first-order "
                          "index's interval (resolved ones only)"})
    judged["ranking_verdict"] = (dims, np.array([ranking[c] for c in cells], dtype=object).reshape(shape),
                                 {"long_name": "met: the top ranking is unchanged; not met: changed; "
                                               f"insufficient data below {min_pairs} paired runs"})
    verdicts = {"reference": analysis_verdicts(reference), "candidate": analysis_verdicts(candidate)}
    checks = sorted(set(verdicts["reference"]) | set(verdicts["candidate"]))
    fewest = int(judged.n.min())
    unchanged = [_change_verdict(verdicts["reference"].get(c) != verdicts["candidate"].get(c), fewest, min_pairs)
                 for c in checks]
    judged = judged.assign_coords(verdict_check=np.array(checks, dtype=object))
    for label, found in verdicts.items():
        judged[f"verdict_{label}"] = ("verdict_check", np.array([found.get(c, "absent") for c in checks], dtype=object),
                                      {"long_name": f"the {label}'s analysis verdict"})
    judged["verdict_unchanged"] = ("verdict_check", np.array(unchanged, dtype=object),
                                   {"long_name": "met: the analysis verdict is unchanged; not met: changed; "
                                                 f"insufficient data below {min_pairs} paired runs"})
    changes = {f"{d}/{f} ranking": v for (d, f), v in ranking.items()}
    return judged, changes | dict(zip(checks, unchanged, strict=True))


def judge_accuracy(candidate: xr.Dataset, reference: xr.Dataset, features, *,
                   candidate_analysis: xr.Dataset | None = None, reference_analysis: xr.Dataset | None = None,
                   min_pairs: int = MIN_PAIRED_RUNS, mean_tolerance: float | None = None,
                   sd_tolerance: float = SD_RATIO_TOLERANCE, confidence: float = CONFIDENCE) -> xr.Dataset:
    """The rule, applied once: a candidate campaign against the reference campaign over the same sampled runs.

    Parameters
    ----------
    candidate, reference : xarray.Dataset
        The two campaigns' ``results.nc`` (same spec and seed: run i of a data set has the same parameters and noise).
    features : sequence of str
        The features judged.
    candidate_analysis, reference_analysis : xarray.Dataset, optional
        Their ``analysis.nc``: with both, the analysis verdicts and the sensitivity rankings are compared too
        (the fidelity audit, whose few runs have no analysis, judges the mean shift and the sd ratio only).
    min_pairs : int
        Fewest paired runs (ok in both) per data set for any verdict.
    mean_tolerance : float, optional
        The mean-shift tolerance of every feature (in its SI unit); default: each feature's by its unit, the
        reference's ``units`` attribute (:data:`MEAN_SHIFT_TOLERANCES`; a unit it lacks is a ``ValueError``).

    Returns
    -------
    xarray.Dataset
        Per ``dataset`` x ``feature``: ``n``, the mean shift with its interval and verdict, the sd ratio with its
        interval and verdict, ``verdict`` and ``statement`` (both parts); with analyses, per data set and feature
        the ranking of each campaign and ``ranking_verdict`` and, per ``verdict_check`` (an element of an analysis
        verdict), each campaign's verdict and ``verdict_unchanged``. ``attrs["verdict"]`` is the worst of all, and
        ``attrs["statement"]`` says which data sets and features have it.
    """
    features = [str(f) for f in features]
    names = [str(d) for d in reference.dataset.values]
    units = {f: str(reference[f].attrs.get("units", "m")) for f in features}
    tolerances = {f: tolerance_for(units[f]).value if mean_tolerance is None else mean_tolerance for f in features}
    cells = {(d, f): paired_verdict(*paired_values(candidate, reference, d, f), mean_tolerance=tolerances[f],
                                    sd_tolerance=sd_tolerance, min_pairs=min_pairs, confidence=confidence,
                                    unit=units[f])
             for d in names for f in features}
    dims, shape = ("dataset", "feature"), (len(names), len(features))

    def grid(value, dtype=float):
        return np.array([value(cells[d, f]) for d in names for f in features], dtype=dtype).reshape(shape)

    interval = f"{confidence * 100:g} % interval"
    judged = xr.Dataset(
        {
            "n": (dims, grid(lambda c: c.mean.n, np.int32), {"units": "1", "long_name": "paired runs ok in both"}),
            "mean_shift": (dims, grid(lambda c: c.mean.estimate),
                           {"units": "feature_unit", "long_name": "mean paired shift, candidate - reference"}),
            "mean_shift_lower": (dims, grid(lambda c: c.mean.lower),
                                 {"units": "feature_unit",
                                  "long_name": f"mean paired shift, {interval} (Student t), lower"}),
            "mean_shift_upper": (dims, grid(lambda c: c.mean.upper),
                                 {"units": "feature_unit",
                                  "long_name": f"mean paired shift, {interval} (Student t), upper"}),
            "mean_shift_verdict": (dims, grid(lambda c: c.mean.verdict, object),
                                   {"long_name": "mean shift within ±mean_shift_tolerance: " + " / ".join(VERDICTS)}),
            "feature_unit": ("feature", np.array([units[f] for f in features], dtype=object),
                             {"long_name": "SI unit of the feature, of its mean shift and its tolerance"}),
            "mean_shift_tolerance": ("feature", np.array([tolerances[f] for f in features]),
                                     {"units": "feature_unit", "long_name": "mean-shift tolerance of the feature "
                                      "(campaigns.statistics.accuracy_rule.MEAN_SHIFT_TOLERANCES by its unit)"}),
            "sd_ratio": (dims, grid(lambda c: c.sd.estimate),
                         {"units": "1", "long_name": "standard deviation ratio, candidate / reference"}),
            "sd_ratio_lower": (dims, grid(lambda c: c.sd.lower),
                               {"units": "1", "long_name": f"sd ratio, {interval} (jackknife), lower"}),
            "sd_ratio_upper": (dims, grid(lambda c: c.sd.upper),
                               {"units": "1", "long_name": f"sd ratio, {interval} (jackknife), upper"}),
            "sd_ratio_verdict": (dims, grid(lambda c: c.sd.verdict, object),
                                 {"long_name": f"sd ratio within 1 ± {sd_tolerance:g}: " + " / ".join(VERDICTS)}),
            "verdict": (dims, grid(lambda c: c.verdict, object),
                        {"long_name": "the rule on the data set and feature (the worse of its parts): "
                                      + " / ".join(VERDICTS)}),
            "statement": (dims, grid(lambda c: c.statement, object),
                          {"long_name": "the verdict with the numbers it rests on (printed verbatim)"}),
        },
        coords={"dataset": np.array(names, dtype=object), "feature": np.array(features, dtype=object)},
    )
    failing = {f"{d}/{f}": c.verdict for (d, f), c in cells.items()}
    if candidate_analysis is not None and reference_analysis is not None:
        judged, changes = _analysis_checks(judged, candidate_analysis, reference_analysis, min_pairs)
        failing |= changes
    worst = worst_verdict(failing.values())
    named = [key for key, v in failing.items() if v == worst]
    if worst == "met":
        unchanged = ", every analysis verdict and ranking unchanged" if len(failing) > len(cells) else ""
        summary = f"every data set and feature within the tolerances{unchanged}, n >= {min_pairs}"
    elif worst == "insufficient data":
        summary = (f"{len(named)} of {len(failing)} checks lack the data (fewest paired runs {int(judged.n.min())}, "
                   f"at least {min_pairs} needed)")
    else:
        summary = ", ".join(named)
    judged.attrs.update(
        verdict=worst, statement=f"{worst}: {summary}", sd_ratio_tolerance=sd_tolerance, min_paired_runs=min_pairs,
        confidence=confidence, top_ranked=TOP_RANKED,
    )
    return judged
