"""Two designs compared: campaign A against campaign B (``twin campaign compare A/results.nc B/results.nc``).

Two campaigns of the same study with one design change (another encoder, another preload, a tighter tolerance) answer
"is B better than A?" only through their differences, each with its bounds:

**Pairing (common random numbers).** Run ``i`` of data set ``d`` draws its tolerances and its noise from
``SeedSequence(root_seed, spawn_key=(d, i))`` (docs/campaigns.md, Sampling and seeding). Two campaigns with the same
``root_seed``, the same data sets in the same order and the same number of runs therefore give run ``i`` the same
noise, and the same values of every tolerance whose row is unchanged *as long as the rows before it draw alike* (a
draw stream is consumed in table order). Whether that holds is not assumed but checked on the stored values: pairing
holds when the two campaigns share the seed and the data sets, and every parameter they both sample is bit-identical
run by run except those whose resolved distribution differs (the design change). Then run ``i`` of A and of B differ
in the design alone and the comparison is *paired*; otherwise it is *unpaired* and says why.

**Feature distributions.** Per data set and feature, over the runs ok with a finite feature (in both, when paired):

* the mean shift ``mean(B) - mean(A)`` with its 95 % Student-t interval: of the paired differences (paired), or
  Welch's (unpaired);
* the standard-deviation shift ``sd(B) - sd(A)`` with a 95 % percentile-bootstrap interval (2000 resamples, seeded;
  pairs resampled together when paired);
* a shift is *resolved* when its interval excludes 0.

**Verdicts.** Each requirement verdict of A's and B's analyses (``analysis.nc`` beside the results) side by side with
their statements, and whether it changed; the design-limit verdicts (loop margins) likewise.

The page-1 sentence (:attr:`Comparison.sentence`) names the verdicts that changed, else the resolved shift largest
relative to A's spread, else says no difference is resolved.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from campaigns.analysis import mean_shift
from campaigns.units import estimate_with_interval

#: Confidence of every interval of the comparison.
CONFIDENCE = 0.95
#: Bootstrap resamples of the standard-deviation shift, and their seed.
N_BOOT = 2000
SEED = 20261126
#: Fewest runs (pairs) per data set for an interval.
MIN_RUNS = 3
#: Shifts smaller than this (in the feature's SI unit) are round-off, shown as 0 (describe_shift).
ROUND_OFF = 1e-15


@dataclass(frozen=True)
class Shift:
    """A difference B - A with its interval (SI units of the feature); NaN where too few runs."""

    estimate: float
    lower: float
    upper: float

    @property
    def resolved(self) -> bool:
        return math.isfinite(self.lower) and (self.lower > 0 or self.upper < 0)


@dataclass(frozen=True)
class FeatureShift:
    dataset: str
    feature: str
    unit: str
    n_a: int
    n_b: int
    mean_a: float
    mean_b: float
    sd_a: float
    sd_b: float
    mean: Shift
    sd: Shift


@dataclass(frozen=True)
class VerdictChange:
    what: str
    verdict_a: str
    verdict_b: str
    statement_a: str
    statement_b: str

    @property
    def changed(self) -> bool:
        return self.verdict_a != self.verdict_b


@dataclass(frozen=True)
class Comparison:
    name_a: str
    name_b: str
    paired: bool
    pairing: str
    design_changes: list[str]
    shifts: list[FeatureShift]
    verdicts: list[VerdictChange] = field(default_factory=list)
    sentence: str = ""


def _spec(results: xr.Dataset) -> dict:
    return json.loads(results.attrs.get("spec_json", "{}"))


def pairing(a: xr.Dataset, b: xr.Dataset) -> tuple[bool, str, list[str]]:
    """Whether run i of A and of B share their draws (module docstring): ``(paired, why, design changes)``."""
    spec_a, spec_b = _spec(a), _spec(b)
    seed_a, seed_b = spec_a.get("spec", {}).get("root_seed"), spec_b.get("spec", {}).get("root_seed")
    names_a, names_b = [str(d) for d in a["dataset"].values], [str(d) for d in b["dataset"].values]
    resolved_a = {r["target"]: r for r in spec_a.get("resolved", [])}
    resolved_b = {r["target"]: r for r in spec_b.get("resolved", [])}
    changed = sorted(t for t in set(resolved_a) | set(resolved_b) if resolved_a.get(t) != resolved_b.get(t))
    if seed_a != seed_b:
        return False, f"different root seeds ({seed_a} and {seed_b}): run i of A and of B draw independently", changed
    if names_a != names_b:
        return False, "the data sets differ (names or order): the runs' seeds differ", changed
    if a.sizes["run"] != b.sizes["run"]:
        runs = min(a.sizes["run"], b.sizes["run"])
        note = f"; the first {runs} runs of each data set are compared"
    else:
        note = ""
    runs = min(a.sizes["run"], b.sizes["run"])
    shared = [str(v) for v in a.data_vars if a[v].attrs.get("role") == "sampled"
              and v in b and b[v].attrs.get("role") == "sampled" and str(v) not in changed]
    different = [p for p in shared if not np.array_equal(a[p].isel(run=slice(0, runs)).values,
                                                         b[p].isel(run=slice(0, runs)).values, equal_nan=True)]
    if different:
        return False, (f"the same seed, but {len(different)} unchanged tolerance(s) drew other values "
                       f"({', '.join(different[:3])}{' ...' if len(different) > 3 else ''}): a changed row before "
                       "them consumed the draw stream differently"), changed
    return True, (f"same root seed {seed_a}, same data sets; {len(shared)} tolerances bit-identical run by run, "
                  f"{len(changed)} changed by the design" + note), changed


def _mean_shift(a: np.ndarray, b: np.ndarray, paired: bool) -> Shift:
    return Shift(*mean_shift(b, a, paired=paired, confidence=CONFIDENCE, min_runs=MIN_RUNS))


def _sd_shift(a: np.ndarray, b: np.ndarray, paired: bool, rng: np.random.Generator) -> Shift:
    if min(len(a), len(b)) < MIN_RUNS:
        return Shift(math.nan, math.nan, math.nan)
    estimate = float(b.std(ddof=1) - a.std(ddof=1))
    ia = rng.integers(0, len(a), (N_BOOT, len(a)))
    ib = ia if paired else rng.integers(0, len(b), (N_BOOT, len(b)))
    boot = b[ib].std(axis=1, ddof=1) - a[ia].std(axis=1, ddof=1)
    alpha = 0.5 * (1.0 - CONFIDENCE)
    lower, upper = np.quantile(boot, [alpha, 1.0 - alpha])
    return Shift(estimate, float(lower), float(upper))


def _verdicts(analysis_a: xr.Dataset | None, analysis_b: xr.Dataset | None) -> list[VerdictChange]:
    if analysis_a is None or analysis_b is None:
        return []
    out = []
    if "requirement_verdict" in analysis_a and "requirement_verdict" in analysis_b:
        for feature in (str(f) for f in analysis_a["feature"].values):
            if feature not in analysis_b["feature"].values:
                continue
            out.append(VerdictChange(
                f"{feature}: minimum detectable fault size against the requirement",
                str(analysis_a["requirement_verdict"].sel(feature=feature).item()),
                str(analysis_b["requirement_verdict"].sel(feature=feature).item()),
                str(analysis_a["requirement_statement"].sel(feature=feature).item()),
                str(analysis_b["requirement_statement"].sel(feature=feature).item())))
    if "margin_limit_verdict" in analysis_a and "margin_limit_verdict" in analysis_b:
        for check in (str(c) for c in analysis_a["limit_check"].values):
            if check not in analysis_b["limit_check"].values:
                continue
            out.append(VerdictChange(
                f"design limit {check.replace('_', ' ')}",
                str(analysis_a["margin_limit_verdict"].sel(limit_check=check).item()),
                str(analysis_b["margin_limit_verdict"].sel(limit_check=check).item()),
                str(analysis_a["margin_limit_statement"].sel(limit_check=check).item()),
                str(analysis_b["margin_limit_statement"].sel(limit_check=check).item())))
    return out


def describe_shift(shift: Shift, unit: str) -> str:
    """``+0.31 µm (95 % interval 0.20 … 0.42 µm)`` in the unit and to the precision the interval resolves
    (:func:`campaigns.units.estimate_with_interval`), or ``–`` without an interval."""
    if not math.isfinite(shift.lower):
        return "–"
    # below ROUND_OFF: the round-off of runs identical in both designs (attometres of a position), not a difference
    estimate, lower, upper = (0.0 if abs(v) < ROUND_OFF else v for v in (shift.estimate, shift.lower, shift.upper))
    return estimate_with_interval(estimate, lower, upper, unit, CONFIDENCE)


def compare(a: xr.Dataset, b: xr.Dataset, analysis_a: xr.Dataset | None = None,
            analysis_b: xr.Dataset | None = None) -> Comparison:
    """Campaign ``b`` (the candidate design) against campaign ``a`` (the baseline): every difference is ``b - a``
    (module docstring). ``twin campaign compare A B`` and ``twin report A --against B`` both read "A against B":
    they pass B as the baseline."""
    name_a = str(_spec(a).get("spec", {}).get("name", "A"))
    name_b = str(_spec(b).get("spec", {}).get("name", "B"))
    paired, why, changed = pairing(a, b)
    runs = min(a.sizes["run"], b.sizes["run"])
    features = [str(v) for v in a.data_vars if a[v].attrs.get("role") == "feature"
                and v in b and b[v].attrs.get("role") == "feature"]
    datasets = [str(d) for d in a["dataset"].values if d in b["dataset"].values]
    rng = np.random.default_rng(SEED)
    shifts = []
    for dataset in datasets:
        ra, rb = a.sel(dataset=dataset).isel(run=slice(0, runs)), b.sel(dataset=dataset).isel(run=slice(0, runs))
        for feature in features:
            va, vb = ra[feature].values.astype(float), rb[feature].values.astype(float)
            ok_a = (ra["status"].values == "ok") & np.isfinite(va)
            ok_b = (rb["status"].values == "ok") & np.isfinite(vb)
            if paired:
                both = ok_a & ok_b
                xa, xb = va[both], vb[both]
            else:
                xa, xb = va[ok_a], vb[ok_b]
            shifts.append(FeatureShift(
                dataset, feature, str(a[feature].attrs.get("units", "")), len(xa), len(xb),
                float(xa.mean()) if len(xa) else math.nan, float(xb.mean()) if len(xb) else math.nan,
                float(xa.std(ddof=1)) if len(xa) > 1 else math.nan, float(xb.std(ddof=1)) if len(xb) > 1 else math.nan,
                _mean_shift(xa, xb, paired), _sd_shift(xa, xb, paired, rng)))
    verdicts = _verdicts(analysis_a, analysis_b)
    comparison = Comparison(name_a, name_b, paired, why, changed, shifts, verdicts)
    return Comparison(name_a, name_b, paired, why, changed, shifts, verdicts, sentence(comparison))


def sentence(c: Comparison) -> str:
    """The one sentence of page 1 (module docstring)."""
    how = "paired run by run" if c.paired else "unpaired"
    changed = [v for v in c.verdicts if v.changed]
    if changed:
        items = "; ".join(f"{v.what}: {v.verdict_a} in {c.name_a}, {v.verdict_b} in {c.name_b}" for v in changed[:3])
        more = f" (and {len(changed) - 3} more)" if len(changed) > 3 else ""
        return f"{c.name_b} against {c.name_a} ({how}): {len(changed)} verdict(s) change: {items}{more}."
    resolved = [s for s in c.shifts if s.mean.resolved and s.sd_a > 0]
    same = f"every verdict the same ({len(c.verdicts)} compared)" if c.verdicts else "no analyses to compare verdicts"
    if not resolved:
        return (f"{c.name_b} against {c.name_a} ({how}): {same}; no shift of any feature's mean is resolved "
                f"({CONFIDENCE * 100:g} % intervals include 0).")
    top = max(resolved, key=lambda s: abs(s.mean.estimate) / s.sd_a)
    return (f"{c.name_b} against {c.name_a} ({how}): {same}; the largest resolved change is {top.feature} in "
            f"{top.dataset}, {describe_shift(top.mean, top.unit)} in its mean, "
            f"{abs(top.mean.estimate) / top.sd_a:.2g} of {c.name_a}'s spread there "
            f"({sum(s.mean.resolved for s in c.shifts)} of {len(c.shifts)} mean shifts resolved).")
