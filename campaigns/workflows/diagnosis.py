"""A measured test placed against a campaign: how usual its features are in each data set, and the fault size the
campaign's feature-to-fault relation gives it.

Inputs: a measured test (:mod:`campaigns.workflows.measured`, ``twin measure import``: features computed from the
bench's channels by the twin's own code) and a campaign's ``results.nc``. Nothing is simulated; this module imports no
twin code (the report calls it).

Per data set and feature (runs with status ok and a finite feature, ``n``):

* the **percentile** of the measured value among the data set's runs (mid-rank: runs below plus half the runs equal,
  over ``n``);
* the **95 % prediction interval** of one more run of the data set, ``mean ± t(0.975, n-1) s sqrt(1 + 1/n)`` (the
  normal-theory interval for a new observation, Hahn & Meeker 1991, *Statistical Intervals*, Sec. 4.6; it assumes the
  feature is normally spread within a data set, as a mean over 10 001 acquisition samples of many small independent
  tolerances is), and the two-sided **p-value** of the measured value under it: ``2 P(T_{n-1} > |x - mean| / (s
  sqrt(1 + 1/n)))``. The test is *consistent* with a data set when ``p >= 0.05`` (inside the interval). Below
  :data:`MIN_RUNS` runs nothing is judged.

**Fault size** (campaigns with an ``[observability]`` sweep: data sets that differ only in the fault's condition):
along the sweep levels ``b_1 < ... < b_m`` the data sets' means must change monotonically with ``b`` (else no size is
inferred, and the statement says so). For a rising relation, a level whose prediction interval lies wholly below the
measured value is *too small* for it, one whose interval lies wholly above it *too large*. The bounds are sweep
levels, never values between them (between two levels the campaign has no runs): the **lower bound** is the largest
too-small level below every too-large one (the reference itself when the test is consistent with it: then the bench
may be healthy), the **upper bound** the smallest too-large level above it (open, "beyond the sweep", when there is
none). Each excluded level is excluded at 5 %, so the fault lies between the bounds with about 90 % confidence or more
(5 % at each end, Bonferroni; a level beyond the nearest one is far less likely to be excluded wrongly, and a monotone
relation only lowers the chance for levels on the wrong side) if the test's tolerances are drawn from the campaign's
table. The **estimate** inverts
the piecewise-linear relation of the means (the sweep level where the measured value crosses the means, interpolated
between adjacent levels), printed only rounded at the leading digit of the bounds' half-width (as the analysis prints
its interpolated minima, :func:`campaigns.analysis.campaign_analysis.printed_estimate`) and only when both bounds are
finite.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np
import xarray as xr
from scipy import stats

from campaigns.analysis.vocabulary import SWEEP_QUANTITIES
from campaigns.statistics.defaults import CONFIDENCE  # of the prediction intervals: a level's exclusion is 1 - it
from campaigns.statistics.detection import printed_estimate
from campaigns.units import quantity as shown_value  # fault_size's `quantity` is the fault's name
from campaigns.units import quantity_range

#: Fewest ok runs a data set needs before a test is judged against it (a standard deviation with 2 degrees of
#: freedom; the interval's t factor is then 4.3, so the judgement is conservative, not wrong).
MIN_RUNS = 3
#: The smallest p-value printed as a number (p_text).
SMALLEST_P = 1e-3


@dataclass(frozen=True)
class Placement:
    """The measured value of one feature against one data set's runs."""

    dataset: str
    n: int
    value: float
    percentile: float = math.nan
    mean: float = math.nan
    std: float = math.nan
    low: float = math.nan
    high: float = math.nan
    p_value: float = math.nan

    @property
    def judged(self) -> bool:
        return self.n >= MIN_RUNS and math.isfinite(self.value) and math.isfinite(self.p_value)

    @property
    def consistent(self) -> bool | None:
        """Inside the data set's prediction interval (None: not judged)."""
        return (self.p_value >= 1.0 - CONFIDENCE) if self.judged else None

    def side(self) -> str:
        """``"inside"``, ``"above"`` or ``"below"`` its prediction interval, ``"not judged"``."""
        if not self.judged:
            return "not judged"
        return "inside" if self.consistent else ("above" if self.value > self.high else "below")


@dataclass(frozen=True)
class FaultSize:
    """The fault size of the measured test from the campaign's sweep, in SI units (``lower``/``upper``: sweep levels,
    ``upper = inf`` when the sweep does not bound it; ``estimate`` NaN where not printed)."""

    quantity: str
    unit: str
    lower: float
    upper: float
    lower_name: str
    upper_name: str
    estimate: float
    healthy: bool
    statement: str


@dataclass(frozen=True)
class Diagnosis:
    """The whole placement of a measured test: per feature its placements and fault size, and one verdict."""

    test: str
    features: list[str]
    placements: dict[str, list[Placement]]
    fault: dict[str, FaultSize | None]
    verdict: str
    notes: list[str] = field(default_factory=list)


def place(value: float, runs: np.ndarray, dataset: str, confidence: float = CONFIDENCE) -> Placement:
    """:class:`Placement` of ``value`` among ``runs`` (module docstring)."""
    runs = np.asarray(runs, dtype=float)
    n = len(runs)
    if n == 0 or not math.isfinite(value):
        return Placement(dataset, n, value)
    percentile = float(((runs < value).sum() + 0.5 * (runs == value).sum()) / n)
    if n < MIN_RUNS:
        return Placement(dataset, n, value, percentile)
    mean, std = float(runs.mean()), float(runs.std(ddof=1))
    scale = std * math.sqrt(1.0 + 1.0 / n)
    half = float(stats.t.ppf(0.5 + 0.5 * confidence, n - 1)) * scale
    if scale > 0:
        p_value = float(2.0 * stats.t.sf(abs(value - mean) / scale, n - 1))
    else:
        p_value = 1.0 if value == mean else 0.0
    return Placement(dataset, n, value, percentile, mean, std, mean - half, mean + half, p_value)


def _used(results: xr.Dataset, feature: str, dataset: str) -> np.ndarray:
    row = results.sel(dataset=dataset)
    values = row[feature].values.astype(float)
    return values[(row["status"].values == "ok") & np.isfinite(values)]


def p_text(p_value: float) -> str:
    """``p = 0.12``; below :data:`SMALLEST_P` only ``p < 0.001``: smaller tail probabilities rest on the normal shape
    of the data set's spread far beyond its runs (59 runs show the shape to about their 1/59 tail), so their digits
    are not resolved by the campaign."""
    return f"p < {SMALLEST_P:g}" if p_value < SMALLEST_P else f"p = {p_value:.2g}"


def fault_size(feature: str, value: float, feature_unit: str, placements: dict[str, Placement],
               levels: dict[str, float], reference: str, condition: str) -> FaultSize | None:
    """The fault size a measured value gives along a sweep (module docstring); None when it cannot be inferred."""
    quantity, unit, scale, shown = SWEEP_QUANTITIES[condition]
    order = sorted(levels, key=lambda name: levels[name])
    judged = [name for name in order if placements[name].judged]
    if len(judged) < 2 or not math.isfinite(value):
        return None

    def level(name: str) -> str:
        return f"{levels[name] * scale:.3g} {shown} ({name})"

    means = np.array([placements[name].mean for name in judged])
    steps = np.diff(means)
    if not ((steps > 0).all() or (steps < 0).all()):
        shown_means = ", ".join(f"{shown_value(placements[n].mean, feature_unit)} ({n})" for n in judged)
        return FaultSize(quantity, unit, math.nan, math.nan, "", "", math.nan, False,
                         f"no {quantity} is inferred from {feature}: its mean does not change monotonically along the "
                         f"sweep ({shown_means})")
    rising = steps[0] > 0
    too_small = [n for n in judged if placements[n].side() == ("above" if rising else "below")]
    too_large = [n for n in judged if placements[n].side() == ("below" if rising else "above")]
    first_large = min((levels[n] for n in too_large), default=math.inf)
    small = [n for n in too_small if levels[n] < first_large]
    lower_name = max(small, key=lambda n: levels[n]) if small else reference
    upper_candidates = [n for n in too_large if levels[n] > levels[lower_name]]
    upper_name = min(upper_candidates, key=lambda n: levels[n]) if upper_candidates else ""
    lower = levels[lower_name] if small else levels[reference]
    upper = levels[upper_name] if upper_name else math.inf
    healthy = not small and placements[reference].consistent is True
    # the estimate: where the value crosses the piecewise-linear relation of the means
    xs, ys = np.array([levels[n] for n in judged]), means if rising else -means
    target = value if rising else -value
    estimate = float(np.interp(target, ys, xs)) if ys[0] <= target <= ys[-1] else (
        xs[0] if target < ys[0] else math.nan)
    printed = printed_estimate(estimate, (lower, upper)) if math.isfinite(upper) else math.nan
    measured = f"{feature} = {shown_value(value, feature_unit)}"
    if healthy:
        bound = (f"{quantity} below {level(upper_name)}, the smallest sweep level it is not consistent with"
                 if upper_name else f"the sweep bounds no {quantity} from above (consistent up to {level(order[-1])})")
        statement = (f"consistent with a healthy bench: {measured} lies within the {CONFIDENCE * 100:g} % prediction "
                     f"interval of the fault-free data set {reference} (percentile "
                     f"{placements[reference].percentile * 100:.0f} %, {placements[reference].n} runs); {bound}")
    else:
        between = (f"{quantity} between {level(lower_name)} and {level(upper_name)}" if upper_name
                   else f"{quantity} above {level(lower_name)}")
        statement = (between + (f" (estimate {printed * scale:.3g} {shown})" if math.isfinite(printed) else "")
                     + f": {measured} " + _bounds_in_words(placements, levels, judged, lower_name, upper_name,
                                                           bool(small), level))
    return FaultSize(quantity, unit, lower, upper, lower_name, upper_name, printed, healthy, statement)


def _bounds_in_words(placements: dict[str, Placement], levels: dict[str, float], judged: list[str], lower_name: str,
                     upper_name: str, excluded_below: bool, level) -> str:
    """What the data sets say about the bounds of a fault size that is not healthy, each claim as the placements have
    it: the lower bound's level excluded (or the side of the fault-free data set's interval the test lies on), the
    levels between the bounds it is consistent with, the upper bound's level excluded or no level too large (a level
    the test is consistent with is never called too small)."""
    interval = f"{CONFIDENCE * 100:g} % prediction interval"
    reference = placements[lower_name]
    if excluded_below:
        text = f"lies {reference.side()} the {interval} of {level(lower_name)}"
    elif reference.judged:
        text = f"lies {reference.side()} the {interval} of the fault-free data set {level(lower_name)}"
    else:
        text = f"is not judged against the fault-free data set {level(lower_name)} ({reference.n} runs)"
    ceiling = levels[upper_name] if upper_name else math.inf
    consistent = [n for n in judged if levels[lower_name] < levels[n] < ceiling and placements[n].consistent]
    if consistent:
        text += f", within that of {', '.join(level(n) for n in consistent)}"
    if upper_name:
        return text + f" and {placements[upper_name].side()} that of {level(upper_name)}"
    if lower_name == judged[-1]:
        return text + ", the sweep's largest level: the sweep does not bound it from above"
    if consistent:
        return text + ("; no sweep level's interval lies wholly on the other side of it, so the sweep does not bound "
                       "it from above")
    return text + f"; the sweep's largest level is {level(judged[-1])}: it does not bound it from above"


def diagnose(test: xr.Dataset, results: xr.Dataset, *, confidence: float = CONFIDENCE) -> Diagnosis:
    """Place a measured test (``twin measure import``'s Dataset) against a campaign's results (module docstring).

    Raises
    ------
    ValueError
        When the test and the campaign share no feature.
    """
    spec = json.loads(results.attrs.get("spec_json", "{}")).get("spec", {})
    campaign_features = [str(v) for v in results.data_vars if results[v].attrs.get("role") == "feature"]
    features = [f for f in campaign_features if f in test.data_vars and math.isfinite(float(test[f]))]
    if not features:
        raise ValueError(f"the measured test and the campaign share no feature with a value (campaign: "
                         f"{', '.join(campaign_features)}; test: "
                         f"{', '.join(v for v in test.data_vars if test[v].attrs.get('role') == 'feature')})")
    names = [str(d) for d in results["dataset"].values]
    placements = {f: [place(float(test[f]), _used(results, f, d), d, confidence) for d in names] for f in features}
    observability = spec.get("observability", {}) or {}
    sweep = list(observability.get("sweep") or [])
    condition = observability.get("condition", "backlash")
    notes = []
    fault: dict[str, FaultSize | None] = {}
    if sweep and f"condition_{condition}" in results:
        values = {n: float(results[f"condition_{condition}"].sel(dataset=n)) for n in sweep}
        reference = observability.get("reference") or next(n for n in sweep if values[n] == 0.0)
        levels = {n: abs(values[n] - values[reference]) for n in sweep}
        for f in features:
            by_name = {p.dataset: p for p in placements[f]}
            fault[f] = fault_size(f, float(test[f]), str(results[f].attrs.get("units", "")), by_name, levels,
                                  reference, condition)
        scenes = {(d.get("scene") or spec.get("base", {}).get("scene")) for d in spec.get("datasets", [])
                  if d.get("name") in sweep}
        test_scene = str(test.attrs.get("scene", "")) or None
        if test_scene and scenes and test_scene not in scenes:
            notes.append(f"the test followed scene {test_scene}; the sweep's data sets follow "
                         f"{', '.join(sorted(scenes))}: the features compare only if the procedures are the same")
    else:
        notes.append("the campaign has no observability sweep: no fault size is inferred, only the placement per data "
                     "set")
    headline = next((f for f in features if not f.endswith("_true")), features[0])
    found = fault.get(headline)
    if found is not None:
        verdict = found.statement
    else:
        consistent = [p.dataset for p in placements[headline] if p.consistent]
        judged = [p for p in placements[headline] if p.judged]
        verdict = (f"{headline} of the test is consistent with data set(s) {', '.join(consistent)} and with none "
                   f"of the other {len(judged) - len(consistent)} judged" if consistent
                   else f"{headline} of the test is consistent with none of the {len(judged)} judged data sets")
    return Diagnosis(str(test.attrs.get("measured_test", "measured test")), features, placements, fault, verdict,
                     notes)


def describe(placement: Placement, unit: str) -> str:
    """One data set's placement in words: ``63rd percentile, inside the 95 % interval (p = 0.41, 59 runs)``."""
    if placement.n == 0:
        return "no ok runs"
    if not placement.judged:
        return f"percentile {placement.percentile * 100:.0f} % ({placement.n} runs: too few to judge)"
    where = {"inside": "consistent", "above": "above its range", "below": "below its range"}[placement.side()]
    return (f"{where}: percentile {placement.percentile * 100:.0f} %, {p_text(placement.p_value)} "
            f"({CONFIDENCE * 100:g} % interval {quantity_range(placement.low, placement.high, unit, 3, ' … ')}, "
            f"{placement.n} runs)")
