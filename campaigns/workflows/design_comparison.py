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

**What changed.** The two specs as stored in the results (``spec_json``) are compared field by field
(:func:`spec_changes`): each difference is named with both values (``datasets[ds2].parameters.sensors.
torque_meter_encoder_pulses_per_turn: 2000 (nominal) → 5000``), data sets by name and uncertainty rows by target; a
value one spec leaves out is the parameter set's nominal where there is one. Names and descriptions are not compared.

**Runs that failed.** A run that did not end ok (timeout, diverged, ...) has no feature: per data set and side the
comparison counts them, and a shift with fewer than ``MIN_RUNS`` runs (pairs) has no interval: it *could not be made*,
and the sentence says so instead of counting it among the shifts that are not resolved.

**Verdicts.** Each requirement verdict of A's and B's analyses (``analysis.nc`` beside the results) side by side with
their statements, and whether it changed; the design-limit verdicts (loop margins) likewise.

The page-1 sentence (:attr:`Comparison.sentence`) names the verdicts that changed, else the resolved shift largest
relative to A's spread, else says no difference is resolved.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from campaigns.statistics.defaults import CONFIDENCE
from campaigns.statistics.intervals import mean_shift
from campaigns.units import estimate_with_interval

#: Bootstrap resamples of the standard-deviation shift, and their seed.
N_BOOT = 2000
SEED = 20261126
#: Fewest runs (pairs) per data set for an interval.
MIN_RUNS = 3
#: Shifts smaller than this (in the feature's SI unit) are the round-off of runs identical in both designs, shown as
#: 0 (describe_shift).
IDENTICAL_RUNS_ROUND_OFF = 1e-15


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

    @property
    def made(self) -> bool:
        """Whether the comparison could be made (enough runs ok on both sides for an interval)."""
        return math.isfinite(self.mean.lower)


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
    #: Every difference of the two specs, with both values (:func:`spec_changes`).
    spec_changes: list[str] = field(default_factory=list)
    #: Runs compared per data set, and per side the runs that did not end ok, by data set and by status.
    runs: int = 0
    failed_a: dict[str, int] = field(default_factory=dict)
    failed_b: dict[str, int] = field(default_factory=dict)
    statuses_a: dict[str, int] = field(default_factory=dict)
    statuses_b: dict[str, int] = field(default_factory=dict)


def _spec(results: xr.Dataset) -> dict:
    return json.loads(results.attrs.get("spec_json", "{}"))


#: Spec fields that name or describe, not what a campaign does.
_NOT_COMPARED = ("name", "description")
#: What identifies an entry of a list of tables: a data set by its name, an uncertainty row by its target.
_KEYS = ("name", "target")


def _value(value) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return json.dumps(value, sort_keys=True)
    return repr(value) if isinstance(value, str) else str(value)


def _keyed(items: list) -> dict | None:
    """A list of tables as ``{"[key]": table}`` when each has a name or a target, else None (a plain list)."""
    for key in _KEYS:
        if items and all(isinstance(i, dict) and key in i for i in items):
            return {f"[{i[key]}]": i for i in items}
    return None


def spec_changes(spec_a: dict, spec_b: dict, names: tuple[str, str] = ("A", "B"),
                 nominal: Callable[[str, str], str | None] | None = None) -> list[str]:
    """Every difference of two canonical specs (the ``spec`` of :meth:`CampaignSpec.canonical`), one line each
    (module docstring); ``names`` say whose a data set or row only one has. A value one spec leaves out reads
    ``not set``; in a data set's ``parameters``, ``nominal(parameter_set, target)`` (the parameter set's value as
    text, or None when unknown), else ``the parameter set's nominal``. (The results hold no nominal values, and
    this module may not load the twin to read them: the reports import it.)"""
    out: list[str] = []
    sets = (spec_a.get("base", {}).get("parameters"), spec_b.get("base", {}).get("parameters"))

    def absent(path: str, side: int) -> str:
        parameter = path.partition(".parameters.")[2] if path.startswith("datasets[") else ""
        if not parameter:
            return "not set"
        found = nominal(sets[side], parameter) if nominal is not None and isinstance(sets[side], str) else None
        return found or "the parameter set's nominal"

    def walk(a, b, path: str) -> None:
        if isinstance(a, dict) or isinstance(b, dict):
            a, b = (x if isinstance(x, dict) else {} for x in (a, b))
            for key in sorted(set(a) | set(b)):
                if key not in _NOT_COMPARED:
                    walk(a.get(key), b.get(key), f"{path}.{key}" if path else key)
        elif isinstance(a, list) and isinstance(b, list) and (ka := _keyed(a)) is not None \
                and (kb := _keyed(b)) is not None:
            for key in list(ka) + [k for k in kb if k not in ka]:
                if key not in kb or key not in ka:
                    out.append(f"{path}{key}: only in {names[0] if key in ka else names[1]}")
                else:
                    walk(ka[key], kb[key], f"{path}{key}")
        elif a != b:
            old = _value(a) if a is not None else absent(path, 0)
            new = _value(b) if b is not None else absent(path, 1)
            out.append(f"{path}: {old} → {new}")

    walk(spec_a, spec_b, "")
    return out


def _fixed_changes(spec_a: dict, spec_b: dict) -> list[str]:
    """Parameters a data set fixes differently in the two specs (by name of data set)."""
    by_name = [{d.get("name"): d.get("parameters") or {} for d in s.get("datasets", [])} for s in (spec_a, spec_b)]
    return sorted({t for name in set(by_name[0]) & set(by_name[1])
                   for t in set(by_name[0][name]) | set(by_name[1][name])
                   if by_name[0][name].get(t) != by_name[1][name].get(t)})


def pairing(a: xr.Dataset, b: xr.Dataset) -> tuple[bool, str, list[str]]:
    """Whether run i of A and of B share their draws (module docstring): ``(paired, why, design changes)``: the
    tolerances whose resolved distributions differ, and the parameters a data set fixes differently."""
    spec_a, spec_b = _spec(a), _spec(b)
    seed_a, seed_b = spec_a.get("spec", {}).get("root_seed"), spec_b.get("spec", {}).get("root_seed")
    names_a, names_b = [str(d) for d in a["dataset"].values], [str(d) for d in b["dataset"].values]
    resolved_a = {r["target"]: r for r in spec_a.get("resolved", [])}
    resolved_b = {r["target"]: r for r in spec_b.get("resolved", [])}
    redrawn = sorted(t for t in set(resolved_a) | set(resolved_b) if resolved_a.get(t) != resolved_b.get(t))
    fixed = _fixed_changes(spec_a.get("spec", {}), spec_b.get("spec", {}))
    changed = sorted(set(redrawn) | set(fixed))
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
    fixed_text = f", {len(fixed)} parameter(s) a data set fixes otherwise" if fixed else ""
    return True, (f"same root seed {seed_a}, same data sets; {len(shared)} tolerances bit-identical run by run, "
                  f"{len(redrawn)} drawn from another distribution{fixed_text}" + note), changed


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
    # attometres of a position: the round-off of runs identical in both designs, not a difference
    estimate, lower, upper = (0.0 if abs(v) < IDENTICAL_RUNS_ROUND_OFF else v
                              for v in (shift.estimate, shift.lower, shift.upper))
    return estimate_with_interval(estimate, lower, upper, unit, CONFIDENCE)


def compare(a: xr.Dataset, b: xr.Dataset, analysis_a: xr.Dataset | None = None,
            analysis_b: xr.Dataset | None = None, *, nominal: Callable[[str, str], str | None] | None = None
            ) -> Comparison:
    """Campaign ``b`` (the candidate design) against campaign ``a`` (the baseline): every difference is ``b - a``
    (module docstring). ``twin campaign compare A B`` and ``twin report A --against B`` both read "A against B":
    they pass B as the baseline. ``nominal`` reads a parameter's nominal for the spec differences
    (:func:`spec_changes`)."""
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
    specs = (_spec(a).get("spec", {}), _spec(b).get("spec", {}))
    comparison = Comparison(name_a, name_b, paired, why, changed, shifts, verdicts,
                            spec_changes=spec_changes(*specs, (name_a, name_b), nominal),
                            runs=runs, **_failures(a, datasets, runs, "a"), **_failures(b, datasets, runs, "b"))
    return dataclasses.replace(comparison, sentence=sentence(comparison))


def _failures(results: xr.Dataset, datasets: list[str], runs: int, side: str) -> dict:
    """``failed_<side>`` (runs not ok per data set) and ``statuses_<side>`` (how many of each status) of the runs
    compared."""
    status = results["status"].sel(dataset=datasets).isel(run=slice(0, runs)).values.astype(str)
    failed = status != "ok"
    kinds, counts = np.unique(status[failed], return_counts=True)
    return {f"failed_{side}": {d: int(n) for d, n in zip(datasets, failed.sum(axis=1), strict=True)},
            f"statuses_{side}": {str(k): int(n) for k, n in zip(kinds, counts, strict=True)}}


def failure_text(c: Comparison, *, detail: bool = False) -> str:
    """``runs that did not end ok: 24 of 56 in B, none in A``, with ``detail`` by status and data set (``24 of 56 in
    B (timeout 24; ds3 8 of 8, ...)``), or ``""`` when every run compared of both ended ok."""
    total = c.runs * len(c.failed_a)
    parts = []
    for name, failed, statuses in ((c.name_b, c.failed_b, c.statuses_b), (c.name_a, c.failed_a, c.statuses_a)):
        n = sum(failed.values())
        kinds = ", ".join(f"{k} {v}" for k, v in sorted(statuses.items()))
        where = ", ".join(f"{d} {k} of {c.runs}" for d, k in failed.items() if k)
        parts.append(f"none in {name}" if n == 0 else f"{n} of {total} in {name}"
                     + (f" ({kinds}; {where})" if detail else ""))
    if all(p.startswith("none") for p in parts):
        return ""
    return "runs that did not end ok: " + ("; " if detail else ", ").join(parts)


def unmade_text(c: Comparison) -> str:
    """Which comparisons could not be made, or ``""``."""
    unmade = [s for s in c.shifts if not s.made]
    if not unmade:
        return ""
    datasets = list(dict.fromkeys(s.dataset for s in unmade))
    entirely = [d for d in datasets if all(not s.made for s in c.shifts if s.dataset == d)]
    where = ", ".join(datasets) if entirely == datasets else ", ".join(
        f"{s.dataset} {s.feature}" for s in unmade[:6]) + (" ..." if len(unmade) > 6 else "")
    both = "pairs ok in both" if c.paired else "runs ok on a side"
    return (f"{len(unmade)} of {len(c.shifts)} comparisons could not be made (fewer than {MIN_RUNS} {both} with "
            f"a finite feature: {where})")


def sentence(c: Comparison) -> str:
    """The one sentence of page 1 (module docstring): the verdicts that changed, else the largest resolved shift,
    else that none is resolved among the comparisons made; then which could not be made and the runs that failed."""
    how = "paired run by run" if c.paired else "unpaired"
    notes = "".join(f"; {text}" for text in (unmade_text(c), failure_text(c)) if text)
    changed = [v for v in c.verdicts if v.changed]
    if changed:
        items = "; ".join(f"{v.what}: {v.verdict_a} in {c.name_a}, {v.verdict_b} in {c.name_b}" for v in changed[:3])
        more = f" (and {len(changed) - 3} more)" if len(changed) > 3 else ""
        return f"{c.name_b} against {c.name_a} ({how}): {len(changed)} verdict(s) change: {items}{more}{notes}."
    made = [s for s in c.shifts if s.made]
    resolved = [s for s in made if s.mean.resolved and s.sd_a > 0]
    same = f"every verdict the same ({len(c.verdicts)} compared)" if c.verdicts else "no analyses to compare verdicts"
    if not made:
        return f"{c.name_b} against {c.name_a} ({how}): {same}{notes}."  # notes: no comparison could be made
    among = f" among the {len(made)} comparisons made" if len(made) < len(c.shifts) else ""
    if not resolved:
        return (f"{c.name_b} against {c.name_a} ({how}): {same}; no shift of any feature's mean is resolved{among} "
                f"({CONFIDENCE * 100:g} % intervals include 0){notes}.")
    top = max(resolved, key=lambda s: abs(s.mean.estimate) / s.sd_a)
    return (f"{c.name_b} against {c.name_a} ({how}): {same}; the largest resolved change is {top.feature} in "
            f"{top.dataset}, {describe_shift(top.mean, top.unit)} in its mean, "
            f"{abs(top.mean.estimate) / top.sd_a:.2g} of {c.name_a}'s spread there "
            f"({sum(s.mean.resolved for s in made)} of {len(made)} mean shifts resolved){notes}.")
