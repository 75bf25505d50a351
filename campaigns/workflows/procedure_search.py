"""The test-procedure designer (issue 29): which test procedure lets the bench see a fault grow within one unit soonest,
and at what test duration.

A search spec (TOML, :class:`SearchSpec`) names a within-unit campaign (its units, uncertainty rows, features, solver
and seed: every candidate is tested on the same units, common random numbers), the fault (``backlash`` growth or
``preload_loss``), the procedure's knobs with their ranges (:data:`twin.scenes.procedure.KNOBS`), the growth levels
and a budget of runs. The search:

1. **Coarse design.** Candidate ``p00`` is the base scene itself (the thesis's procedure, the reference every other
   candidate is compared with); then the spec's anchors (procedures named by the engineer); the others are a Latin
   hypercube over the knobs' ranges (``scipy.stats.qmc``, seeded
   by the campaign's root seed; counts rounded, choices by equal shares).
2. **Screening rounds (successive halving).** Each candidate runs a within-unit campaign at two levels, the unit's
   baseline and the screening level (the requirement by default). Its score per feature is the screening estimate:
   the 95th-percentile unit's detectable growth, each unit's figure extrapolated linearly from its own shift at the
   screening level by the within-unit detection rule (:func:`campaigns.analysis.within_unit.extrapolated_detectable`),
   with bounds from a bootstrap over units (the same resampled units for every candidate, so differences are paired).
   The better half goes on to the next round with twice the repeats, until ``finalists`` remain.
3. **Finalists.** Each finalist runs the full within-unit campaign at every level on fresh units (a root seed of its
   own, :data:`FINAL_STREAM`, shared by the finalists), and its verdict with bounds is the within-unit analysis's
   (:mod:`campaigns.analysis.within_unit`), never the screening estimate's: the runs that picked a candidate do not
   judge it.

Outputs (``search.nc``, CF): every candidate's knobs, test duration, scores with bounds, the round it reached, the
finalists' verdicts, the Pareto front of detectability against duration, the rank, the difference to the best
(paired bootstrap) and the one command that re-runs its evidence (its campaign spec and directory under
``candidates/``). The statement of the search (best procedure, its bounds, what it beats) is computed here once.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
import pandas as pd
import xarray as xr
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator
from scipy.stats import qmc

from campaigns.analysis.campaign_analysis import analyze
from campaigns.analysis.vocabulary import BACKLASH_REQUIREMENT, REQUIREMENT_SOURCE, SWEEP_QUANTITIES
from campaigns.analysis.within_unit import extrapolated_detectable, unit_values
from campaigns.bench.adapter import force_demand_peak
from campaigns.bench.campaign import load_spec, run_campaign
from campaigns.runner.files import CONVENTIONS
from campaigns.runner.spec import SearchName, SpecError, read_spec
from campaigns.statistics.within_unit_floors import DESIGN_REVIEW_QUANTILE, MIN_REPEATS, MIN_UNITS
from campaigns.units import display_scale, quantity, quantity_range
from twin.scenes import load_scene
from twin.scenes.procedure import (
    KNOBS,
    MINIMUM_PEAK_SPEED,
    NOMINAL_SPEED,
    procedure_duration,
    procedure_problems,
    with_defaults,
)

#: The fault a search is about: the scene condition that carries it and how a growth ``g`` sets it from the
#: procedure's knobs (a backlash grows from 0; a preload is lost from the procedure's preload setting).
FAULTS = {
    "backlash": ("backlash", lambda knobs, growth: {"backlash": growth}),
    "preload_loss": ("preload", lambda knobs, growth: {"preload": float(knobs["preload"]) - growth}),
}
#: Bootstrap replicates over units of the screening estimates (their 95 % percentile bounds and paired differences).
SCREENING_BOOTSTRAP = 1000
#: Confidence of the screening bounds.
SCREENING_CONFIDENCE = 0.95
#: Candidates of a ``--quick`` search (the reference and two others, or the reference and the spec's anchors).
QUICK_CANDIDATES = 3
#: Spawn-key tag of the coarse design's and the screening bootstrap's streams (from the campaign's root seed; far from
#: the data-set indices of the runs' streams, like campaigns.analysis.campaign_analysis's tags).
DESIGN_STREAM = 1_000_039
#: Spawn-key tag of the finalists' root seed: their campaigns test fresh units with fresh noise, so the verdict of a
#: candidate the screening picked does not reuse the runs that picked it (common random numbers across finalists).
FINAL_STREAM = 1_000_041
#: Upper bounds of the budget (a typing slip, not a search: 100 candidates of 60 x 3 x 2 runs is 36000 runs).
MAX_CANDIDATES, MAX_ROUNDS, MAX_UNITS, MAX_REPEATS, MAX_RUNS = 100, 5, 10_000, 100, 10_000_000


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Budget(_Strict):
    """How much the search may run: ``candidates`` in the coarse design (the reference included), ``rounds`` of
    screening (each keeps the better half for the next, with twice the repeats), ``finalists`` (the best of the last
    round) that get the full campaign, the ``units`` and the first round's ``repeats`` of every campaign, and ``runs``,
    the most runs the plan may take (the search refuses a plan above it before any run)."""

    runs: int = Field(gt=0, le=MAX_RUNS)
    candidates: int = Field(ge=2, le=MAX_CANDIDATES)
    finalists: int = Field(default=2, ge=1)
    rounds: int = Field(default=1, ge=1, le=MAX_ROUNDS)
    units: int = Field(default=MIN_UNITS, ge=MIN_UNITS, le=MAX_UNITS)
    repeats: int = Field(default=MIN_REPEATS, ge=MIN_REPEATS, le=MAX_REPEATS)

    @model_validator(mode="after")
    def _finalists_within_candidates(self) -> Budget:
        if self.finalists > self.candidates:
            raise ValueError(f"finalists = {self.finalists} is more than the {self.candidates} candidates")
        return self


class SearchSpec(_Strict):
    """A procedure search (TOML). Knob ranges: ``[low, high]`` for a number or a count, a single number to fix it,
    a list of choices (or one) for a choice knob; knobs not given keep the thesis's value (``KNOBS[k].default``)."""

    name: SearchName
    description: str = ""
    campaign: str
    fault: Literal["backlash", "preload_loss"]
    scene: str
    levels: list[float] = Field(min_length=1)
    screening_level: float | None = None
    features: list[str] = Field(min_length=1)
    knobs: dict[str, float | list[float] | str | list[str]] = {}
    reference: dict[str, float | str] = {}
    anchors: list[dict[str, float | str]] = []
    budget: Budget

    #: set by :func:`load_search`: the spec file, the campaign's merged data and its text
    path: Path | None = None
    campaign_data: dict = {}
    text: str = ""

    @property
    def condition(self) -> str:
        return FAULTS[self.fault][0]

    @property
    def fault_unit(self) -> str:
        return SWEEP_QUANTITIES[self.condition][1]

    @property
    def requirement(self) -> float:
        return float(self.campaign_data.get("observability", {}).get("requirement") or BACKLASH_REQUIREMENT)

    @property
    def requirement_source(self) -> str:
        return str(self.campaign_data.get("observability", {}).get("requirement_source") or REQUIREMENT_SOURCE)

    @property
    def screening(self) -> float:
        return self.requirement if self.screening_level is None else self.screening_level

    def ranges(self) -> dict[str, tuple]:
        """Every knob: ``("range", low, high)``, ``("fixed", value)`` or ``("choices", [...])``."""
        out = {}
        for name, knob in KNOBS.items():
            given = self.knobs.get(name, knob.default)
            if knob.choices:
                out[name] = ("choices", [given] if isinstance(given, str) else list(given))
            elif isinstance(given, list) and len(given) == 2 and given[0] != given[1]:
                out[name] = ("range", float(min(given)), float(max(given)))
            else:
                out[name] = ("fixed", float(given[0] if isinstance(given, list) else given))
        return out


def _problems(spec: SearchSpec) -> list[str]:
    """Every problem the fields do not show alone: knobs, levels, features, the budget against the plan."""
    problems = []
    for name, given in spec.knobs.items():
        if name not in KNOBS:
            problems += [f"knobs.{p}" for p in procedure_problems({name: given})]
            continue
        knob = KNOBS[name]
        values = given if isinstance(given, list) else [given]
        if knob.choices and not values:
            problems.append(f"knobs.{name}: give at least one of {', '.join(knob.choices)}")
        elif not knob.choices and (not values or len(values) > 2 or any(isinstance(v, str) for v in values)):
            problems.append(f"knobs.{name}: give [low, high] or one number [{knob.unit}], got {given!r}")
        else:  # each value against the knob's own range (speed limits of a pair: below, over the ranges)
            problems += [p for v in values if (p := knob.problem(f"knobs.{name}", v)) is not None]
    if problems:
        return problems
    ranges = spec.ranges()
    slowest = 2 * math.pi * ranges["amplitude"][1] * ranges["frequency"][1]
    fastest = 2 * math.pi * ranges["amplitude"][-1] * ranges["frequency"][-1]
    if fastest < MINIMUM_PEAK_SPEED or slowest > NOMINAL_SPEED:
        problems.append(f"knobs.amplitude, knobs.frequency: their ranges allow peak sled speeds of "
                        f"{slowest * 1e3:.3g}-{fastest * 1e3:.3g} mm/s, none within the bench's "
                        f"{MINIMUM_PEAK_SPEED * 1e3:g}-{NOMINAL_SPEED * 1e3:g} mm/s (twin.scenes.procedure)")
    if sorted(spec.levels) != list(spec.levels) or len(set(spec.levels)) != len(spec.levels) or spec.levels[0] <= 0:
        problems.append(f"levels: must be positive growths in increasing order [{spec.fault_unit}], got {spec.levels}")
    for k, anchor in enumerate(spec.anchors):
        problems += [f"anchors[{k}].{p}" for p in procedure_problems(anchor)]
    if len(spec.anchors) > spec.budget.candidates - 1:
        problems.append(f"budget.candidates: {spec.budget.candidates} cannot hold the reference and the "
                        f"{len(spec.anchors)} anchors")
    elif len(spec.anchors) < spec.budget.candidates - 1 and not _free_knobs(spec):
        problems.append(f"knobs: none has a range or a choice, so the {spec.budget.candidates - 1 - len(spec.anchors)}"
                        " design candidates would all be one procedure; give ranges, or budget.candidates = 1 + the "
                        "anchors")
    campaign_condition = spec.campaign_data.get("observability", {}).get("condition", "backlash")
    if campaign_condition != spec.condition:
        problems.append(f"campaign: its observability sweep is over {campaign_condition!r}, the search's fault over "
                        f"{spec.condition!r}: its requirement and units would not apply; name a {spec.fault} campaign")
    if spec.screening <= 0:
        problems.append(f"screening_level: must be a positive growth [{spec.fault_unit}], got {spec.screening:g}")
    problems += [f"reference.{p}" for p in procedure_problems(spec.reference)]
    problems += [f"reference.{name}: not a condition of the reference; allowed: preload, zero_procedure"
                 for name in spec.reference if name in KNOBS and name not in ("preload", "zero_procedure")]
    if spec.fault == "preload_loss":
        lowest = min(ranges["preload"][1], float(reference_setting(spec)["preload"]))
        largest = max([*spec.levels, spec.screening])
        if largest > lowest:
            problems.append(f"levels, screening_level: a loss of {largest:g} N is more than the lowest preload "
                            f"setting {lowest:g} N of knobs.preload and the reference")
    campaign_features = spec.campaign_data.get("features", [])
    for feature in spec.features:
        if feature not in campaign_features:
            problems.append(f"features: {feature!r} is not a feature of the campaign "
                            f"({', '.join(campaign_features)})")
        elif feature.endswith("_true"):
            problems.append(f"features: {feature!r} is a true-state feature the bench cannot measure; "
                            "a procedure is chosen on what the sensors see")
    if not problems:
        needed, smallest = plan_runs(spec), plan_runs(spec, smallest=True)
        if smallest > spec.budget.runs:
            problems.append(f"budget.runs: {spec.budget.runs} runs cannot rank anything: the smallest plan (2 "
                            f"candidates, 1 finalist, {spec.budget.units} units x {spec.budget.repeats} repeats) "
                            f"needs {smallest}")
        elif needed > spec.budget.runs:
            problems.append(f"budget.runs: the plan needs {needed} runs ({describe_plan(spec)}), more than the "
                            f"{spec.budget.runs} allowed; lower budget.candidates or budget.finalists, or raise "
                            "budget.runs")
    return problems


def load_search(path: str | Path, *, quick: bool = False, catalog=None) -> SearchSpec:
    """Read and check a search spec; every problem in one :class:`campaigns.runner.spec.SpecError` before any run.

    ``quick`` replaces the budget by a plan that still ranks: :data:`QUICK_CANDIDATES` candidates (or the reference
    and the anchors), one screening round, one finalist, the floors of units and repeats: a first look. ``catalog``
    validates the candidates' campaigns (default: the bench's)."""
    path = Path(path)
    try:
        text = path.read_text()
        data = tomllib.loads(text)
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise SpecError([f"{path}: cannot read the search spec ({exc})"]) from None
    if quick and isinstance(data.get("budget"), dict):
        anchors = data.get("anchors") if isinstance(data.get("anchors"), list) else []
        data["budget"] = {**data["budget"], "candidates": max(QUICK_CANDIDATES, len(anchors) + 1), "finalists": 1,
                          "rounds": 1, "units": MIN_UNITS, "repeats": MIN_REPEATS}
    try:
        spec = SearchSpec.model_validate(data)
    except ValidationError as exc:
        raise SpecError([f"{'.'.join(str(p) for p in e['loc'])}: {e['msg']}" for e in exc.errors()]) from None
    campaign = (path.parent / spec.campaign).resolve()
    try:
        campaign_data = read_spec(campaign)
    except SpecError as exc:
        raise SpecError([f"campaign: {p}" for p in exc.problems]) from None
    spec = spec.model_copy(update={"path": path.resolve(), "campaign_data": campaign_data, "text": text})
    if quick:
        spec = spec.model_copy(update={"budget": spec.budget.model_copy(update={"runs": plan_runs(spec)})})
    problems = _problems(spec)
    if not problems:
        failing: dict[str, list[str]] = {}  # problem -> the candidates whose campaign has it
        candidates = design(spec)
        with tempfile.TemporaryDirectory() as scratch:
            for stage, candidate in ((s, c) for s in stages(spec) for c in candidates):  # before any run
                try:
                    write_candidate_spec(spec, candidate, stage.name, stage.repeats, Path(scratch), catalog)
                except SpecError as exc:
                    for problem in exc.problems:
                        failing.setdefault(f"{stage.name}: {problem}", []).append(candidate.name)
                (Path(scratch) / f"{stage.name}.toml").unlink(missing_ok=True)
        problems += [f"campaign of {', '.join(names)}: {problem}" for problem, names in failing.items()]
    if problems:
        raise SpecError(problems)
    return spec


@dataclass(frozen=True)
class Candidate:
    """One procedure of the search: its name (``p00`` the reference), its knobs (empty for the reference: the base
    scene's own profiles) and the knob values shown for it."""

    name: str
    knobs: dict
    shown: dict = field(default_factory=dict)

    @property
    def reference(self) -> bool:
        return not self.knobs


def design(spec: SearchSpec) -> list[Candidate]:
    """The coarse design: the reference, the spec's ``anchors`` (procedures the engineer wants compared, the knobs
    they leave out at the thesis's values), then Latin-hypercube points over the knobs' ranges up to
    ``budget.candidates`` (each knob's range cut in as many strata, one point in each: every knob is spread over its
    range even with a handful of candidates)."""
    ranges = spec.ranges()
    free = _free_knobs(spec)
    count = spec.budget.candidates - 1 - len(spec.anchors)
    seed = np.random.SeedSequence(int(spec.campaign_data.get("root_seed", 0)), spawn_key=(DESIGN_STREAM,))
    points = (qmc.LatinHypercube(len(free), seed=np.random.default_rng(seed)).random(count) if free
              else np.zeros((count, 0)))
    reference = Candidate("p00", {}, reference_knobs(spec))
    candidates = [reference] + [Candidate(f"p{c:02d}", with_defaults(a), with_defaults(a))
                                for c, a in enumerate(spec.anchors, start=1)]
    for c, point in enumerate(points, start=len(candidates)):
        knobs = {}
        for name, r in ranges.items():
            if name in free:
                u = float(point[free.index(name)])
                if r[0] == "choices":
                    knobs[name] = r[1][min(int(u * len(r[1])), len(r[1]) - 1)]
                else:
                    value = r[1] + u * (r[2] - r[1])
                    knobs[name] = int(round(value)) if KNOBS[name].integer else float(f"{value:.4g}")
            else:
                knobs[name] = r[1][0] if r[0] == "choices" else (int(r[1]) if KNOBS[name].integer else r[1])
        knobs = _within_speed(knobs, ranges["frequency"])
        candidates.append(Candidate(f"p{c:02d}", knobs, knobs))
    return candidates


def _free_knobs(spec: SearchSpec) -> list[str]:
    """The knobs the design varies: a range, or more than one choice."""
    return [k for k, r in spec.ranges().items() if r[0] == "range" or (r[0] == "choices" and len(r[1]) > 1)]


def _within_speed(knobs: dict, frequencies: tuple) -> dict:
    """A design point faster than the bench (Table 9.3) or too slow for the features gets the nearest frequency its
    amplitude allows within the spec's frequency range (the knobs' box is not cut to the speed limits, so the Latin
    hypercube spans the box); where none does, the point stays and the validation of every candidate refuses it."""
    circumference = 2 * math.pi * knobs["amplitude"]
    # 0.1 % inside the limits: the design's 4 significant digits must not round a frequency back over one
    low = max(1.001 * MINIMUM_PEAK_SPEED / circumference, frequencies[1])
    high = min(0.999 * NOMINAL_SPEED / circumference, frequencies[-1])
    if low > high:
        return knobs
    frequency = min(max(knobs["frequency"], low), high)
    return {**knobs, "frequency": float(f"{frequency:.4g}")} if frequency != knobs["frequency"] else knobs


def reference_setting(spec: SearchSpec) -> dict:
    """The reference's preload and zero procedure: the base scene's, or the search spec's ``reference`` table's."""
    scene = load_scene(spec.scene)
    return {"preload": float(scene.conditions["preload"]), "zero_procedure": scene.conditions["zero_procedure"],
            **spec.reference}


def reference_knobs(spec: SearchSpec) -> dict:
    """The knobs shown for the reference: its preload and zero procedure, its scene's largest force demand, and
    the thesis's motion (the Fig. 9.6 profile has the same sinusoid, then steps and a ramp)."""
    return {**with_defaults({}), **reference_setting(spec),
            "external_force": force_demand_peak(load_scene(spec.scene))}


def test_duration(spec: SearchSpec, candidate: Candidate) -> float:
    """Length of one test under the candidate's procedure [s] (the reference: its scene's)."""
    return procedure_duration(candidate.knobs) if candidate.knobs else float(load_scene(spec.scene).duration)


def candidate_campaign(spec: SearchSpec, candidate: Candidate, stage: str, repeats: int) -> dict:
    """The candidate's within-unit campaign at ``stage`` (``"round<k>"``: baseline and screening level;
    ``"final"``: every level), as the fields its spec file sets over the search's campaign (``extends``)."""
    growths = [0.0, spec.screening] if stage != "final" else [0.0, *spec.levels]
    knobs = with_defaults(candidate.knobs) if candidate.knobs else reference_setting(spec)
    set_fault = FAULTS[spec.fault][1]
    datasets = []
    for k, growth in enumerate(growths):
        dataset = {"name": f"g{k}", "scene": spec.scene,
                   "description": f"{spec.fault.replace('_', ' ')} {growth:g} {spec.fault_unit} "
                                  f"({'baseline' if k == 0 else 'growth'}) under procedure {candidate.name}",
                   "conditions": {**_fault_free(spec), **({} if candidate.knobs else dict(spec.reference)),
                                  **set_fault(knobs, growth)}}
        if candidate.knobs:
            dataset["procedure"] = dict(candidate.knobs)
        datasets.append(dataset)
    observability = {**spec.campaign_data.get("observability", {}), "sweep": [d["name"] for d in datasets],
                     "condition": spec.condition}
    if spec.condition == "preload":
        observability["reference"] = "g0"
    else:
        observability.pop("reference", None)
    overrides = {
        "name": f"{spec.name}-{candidate.name}-{stage}",
        "description": f"procedure search {spec.name}: candidate {candidate.name}, {stage}",
        "runs_per_dataset": spec.budget.units * repeats,
        "features": list(spec.features),
        "units": {"count": spec.budget.units, "repeats": repeats},
        "observability": observability,
        "fidelity_audit": {"runs": 0},
        "traces": {"runs_per_dataset": 0},
        "datasets": datasets,
    }
    if stage == "final":
        overrides["root_seed"] = final_seed(spec)
    return overrides


def final_seed(spec: SearchSpec) -> int:
    """The finalists' root seed, from the campaign's (:data:`FINAL_STREAM`)."""
    root = int(spec.campaign_data.get("root_seed", 0))
    return int(np.random.SeedSequence(root, spawn_key=(FINAL_STREAM,)).generate_state(1)[0])


def write_candidate_spec(spec: SearchSpec, candidate: Candidate, stage: str, repeats: int, directory: Path,
                         catalog=None):
    """Write the candidate's campaign spec ``<directory>/<stage>.toml`` (it ``extends`` the search's campaign by a
    relative path) and load it as every campaign is loaded: what runs is what the file says, so the one command
    ``twin campaign run <file>`` repeats it. An existing file with other content is refused."""
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{stage}.toml"
    campaign = Path(spec.path).parent / spec.campaign if spec.path else Path(spec.campaign)
    text = write_toml({"extends": os.path.relpath(campaign.resolve(), directory.resolve()),
                       **candidate_campaign(spec, candidate, stage, repeats)})
    if path.exists() and path.read_text() != text:
        raise SpecError([f"{path}: exists with another campaign; choose a new --out"])
    path.write_text(text)
    return load_spec(path, catalog=catalog)


def _fault_free(spec: SearchSpec) -> dict:
    """Conditions every data set of a candidate holds besides the fault: a healthy screw otherwise (no backlash in a
    preload-loss search)."""
    return {"backlash": 0.0} if spec.fault == "preload_loss" else {}


def plan_runs(spec: SearchSpec, *, smallest: bool = False) -> int:
    """Runs the plan takes: every screening round, then the finalists' campaigns."""
    return sum(stage.runs for stage in stages(spec, smallest=smallest))


@dataclass(frozen=True)
class Stage:
    """One stage of the plan: ``name`` (``round<k>`` or ``final``), how many candidates run it with how many repeats
    per unit and level, at how many levels, and its runs."""

    name: str
    candidates: int
    repeats: int
    levels: int
    runs: int


def stages(spec: SearchSpec, *, smallest: bool = False) -> list[Stage]:
    """The plan: each screening round (2 levels; halving the candidates and doubling the repeats from round to round
    until the last round picks the finalists), then the finalists' full campaigns."""
    budget = spec.budget
    candidates, finalists = (2, 1) if smallest else (budget.candidates, budget.finalists)
    out, alive, repeats = [], candidates, budget.repeats
    while True:
        out.append(Stage(f"round{len(out)}", alive, repeats, 2, alive * budget.units * repeats * 2))
        following = max(finalists, math.ceil(alive / 2))
        if following <= finalists or len(out) == budget.rounds:  # the last round picks the finalists
            break
        alive, repeats = following, repeats * 2
    levels = len(spec.levels) + 1
    out.append(Stage("final", finalists, budget.repeats, levels, finalists * budget.units * budget.repeats * levels))
    return out


def describe_plan(spec: SearchSpec) -> str:
    """The plan in words: the stages and their runs."""
    words = [f"{s.name}: {'the best ' if s.name == 'final' else ''}{s.candidates}"
             f"{' candidates' if s.name != 'final' else ''} x {spec.budget.units} units x {s.repeats} repeats x "
             f"{s.levels} levels = {s.runs} runs" for s in stages(spec)]
    return "; ".join(words) + f"; total {plan_runs(spec)} runs"


def screening_scores(values: np.ndarray, growth: float, *, seed, n_boot: int = SCREENING_BOOTSTRAP,
                     confidence: float = SCREENING_CONFIDENCE) -> dict:
    """Screening estimates of several candidates on the same units.

    Parameters
    ----------
    values : array (candidate, 2, unit, repeat)
        One feature's values at the baseline and the screening level, NaN for failed runs.
    growth : float
        The screening level's growth [fault unit].
    seed
        Of the bootstrap over units (one resample of unit indices serves every candidate: paired).

    Returns
    -------
    dict
        ``estimate`` (candidate,): the 95th-percentile unit's extrapolated detectable growth (inf: the quantile unit
        does not move towards detection); ``low``/``high``: percentile bootstrap bounds; ``replicates``
        (n_boot, candidate) for paired differences.
    """
    n_candidates, _, n_units, _ = values.shape
    per_unit = np.stack([extrapolated_detectable(values[c], growth) for c in range(n_candidates)])
    estimate = _quantile_unit(per_unit)
    rng = np.random.default_rng(seed)
    replicates = np.empty((n_boot, n_candidates))
    for b in range(n_boot):
        units = rng.integers(0, n_units, n_units)
        replicates[b] = _quantile_unit(np.stack([extrapolated_detectable(values[c][:, units], growth)
                                                 for c in range(n_candidates)]))
    tail = (1.0 - confidence) / 2.0
    low = np.quantile(replicates, tail, axis=0, method="inverted_cdf")
    high = np.quantile(replicates, 1.0 - tail, axis=0, method="inverted_cdf")
    return {"estimate": estimate, "low": low, "high": high, "replicates": replicates}


def _quantile_unit(per_unit: np.ndarray) -> np.ndarray:
    """The design-review unit's figure along the last axis (an order statistic, so that inf stays inf)."""
    finite_or_inf = np.where(np.isnan(per_unit), math.inf, per_unit)
    return np.quantile(finite_or_inf, DESIGN_REVIEW_QUANTILE, axis=-1, method="inverted_cdf")


def run_search(spec: SearchSpec, out: str | Path, *, workers: int = 2, resume: bool = False, progress: bool = True,
               run_function=None, catalog=None, announce: Callable[[str, str], None] | None = None) -> Path:
    """Run the search and write ``search.nc`` (and ``ranking.csv``) in ``out``; returns the search.nc path.

    Every candidate's campaigns go under ``out/candidates/<name>/`` with their spec files; ``resume`` continues
    them (finished runs kept). ``run_function``/``catalog``: another model (the tests' synthetic one)."""
    out = Path(out)
    announce = announce or (lambda stage, message: None)
    candidates = design(spec)
    alive = list(candidates)
    plan = stages(spec)
    features = list(spec.features)
    # feature -> candidate -> (estimate, low, high): of round 0 (every candidate on the same units and repeats, the
    # table's comparable figure) and of the last round the candidate ran (what selected it)
    scores = {f: {} for f in features}
    last_scores = {f: {} for f in features}
    round0 = {f: {} for f in features}  # feature -> candidate -> round-0 bootstrap replicates (paired differences)
    round_reached = {}
    evidence = {}
    for k, stage in enumerate(plan[:-1]):
        announce(stage.name, f"{len(alive)} candidates x {spec.budget.units} units x {stage.repeats} repeats x 2 "
                             f"levels ({stage.runs} runs)")
        values = {f: [] for f in features}
        for candidate in alive:
            results = _run_candidate(spec, candidate, stage.name, stage.repeats, out, workers=workers, resume=resume,
                                     progress=progress, run_function=run_function, catalog=catalog)
            evidence[candidate.name] = results.parent
            round_reached[candidate.name] = k
            with xr.open_dataset(results, engine="netcdf4") as handle:
                loaded = handle.load()
            for f in features:
                _, v, _ = unit_values(loaded, f, ["g0", "g1"], spec.condition, "g0" if spec.condition == "preload"
                                      else None)
                values[f].append(v)
        seed = np.random.SeedSequence(int(spec.campaign_data.get("root_seed", 0)), spawn_key=(DESIGN_STREAM, k))
        best_per_candidate = np.full(len(alive), math.inf)
        best_replicates = np.full((SCREENING_BOOTSTRAP, len(alive)), math.inf)
        for f in features:
            found = screening_scores(np.stack(values[f]), spec.screening, seed=seed)
            for c, candidate in enumerate(alive):
                last_scores[f][candidate.name] = (found["estimate"][c], found["low"][c], found["high"][c])
                if k == 0:
                    scores[f][candidate.name] = last_scores[f][candidate.name]
                    round0[f][candidate.name] = found["replicates"][:, c]
            best_per_candidate = np.minimum(best_per_candidate, found["estimate"])
            best_replicates = np.minimum(best_replicates, found["replicates"])
        # the next stage's candidates: the better half, or the finalists after the last round (the plan's rule)
        kept = sorted(np.argsort(best_per_candidate, kind="stable")[:plan[k + 1].candidates])
        # how sure the screening is of its pick: the share of bootstrap replicates whose best candidate was kept
        decided = np.isfinite(best_replicates).any(axis=1)  # a replicate where no candidate reaches picks none
        selection_confidence = (float(np.isin(np.argmin(best_replicates[decided], axis=1), kept).mean())
                                if decided.any() else math.nan)
        alive = [alive[i] for i in kept]
    finals = {}
    announce("final", f"{len(alive)} finalists x {spec.budget.units} units x {spec.budget.repeats} repeats x "
                      f"{len(spec.levels) + 1} levels")
    for candidate in alive:
        results = _run_candidate(spec, candidate, "final", spec.budget.repeats, out, workers=workers, resume=resume,
                                 progress=progress, run_function=run_function, catalog=catalog)
        evidence[candidate.name] = results.parent
        analysis = analyze(results)
        with xr.open_dataset(analysis, engine="netcdf4") as handle:
            finals[candidate.name] = handle.load()
    table = search_dataset(spec, candidates, scores, last_scores, round0, round_reached, finals, evidence, out,
                           selection_confidence)
    path = out / "search.nc"
    table.to_netcdf(path, engine="netcdf4")
    ranking_table(table).to_csv(out / "ranking.csv", index=False)
    return path


def _run_candidate(spec, candidate, stage, repeats, out, *, catalog, **options) -> Path:
    """Run the candidate's campaign of ``stage``; resumed, a finished one (its results.nc of the same spec hash) is
    read as it is, so a search resumed under another code version re-runs nothing it has (its files name their
    versions)."""
    directory = out / "candidates" / candidate.name
    campaign = write_candidate_spec(spec, candidate, stage, repeats, directory, catalog)
    finished = directory / stage / "results.nc"
    if options.get("resume") and finished.exists():
        with xr.open_dataset(finished, engine="netcdf4") as stored:
            if stored.attrs.get("spec_hash") == campaign.spec_hash():
                return finished
    return run_campaign(campaign, directory / stage, catalog=catalog, **options)


def write_toml(data: dict) -> str:
    """TOML text of a candidate's spec overrides (strings, numbers, lists, tables and arrays of tables)."""
    lines, tables = [], []
    for key, value in data.items():
        if isinstance(value, dict):
            tables.append((key, value))
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            tables.append((key, value))
        else:
            lines.append(f"{key} = {_toml_value(value)}")
    for key, value in tables:
        if isinstance(value, dict):
            lines += ["", f"[{key}]"] + [f"{k} = {_toml_value(v)}" for k, v in value.items()]
        else:
            for item in value:
                lines += ["", f"[[{key}]]"] + [f"{k} = {_toml_value(v)}" for k, v in item.items()]
    return "\n".join(lines) + "\n"


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"cannot write {value!r} as TOML")


def _final_figures(analysis: xr.Dataset, features: list[str], condition: str) -> dict:
    """The finalist's best feature by the within-unit analysis (the smallest upper bound, then the smallest lower
    bound — the last level not detected — of the design-review unit's detectable growth) with its bounds, verdict and
    statement."""
    stem = SWEEP_QUANTITIES[condition][0].replace(" ", "_")
    bounds = analysis[f"within_unit_minimum_detectable_{stem}_ci"].sel(unit_quantile=DESIGN_REVIEW_QUANTILE)
    rows = []
    for feature in features:
        low, high = (float(v) for v in bounds.sel(feature=feature).values)
        rows.append((high if math.isfinite(high) else math.inf, low, feature))
    high, low, feature = min(rows, key=lambda row: (row[0], row[1]))
    return {"feature": feature, "low": low, "high": high,
            "verdict": str(analysis["within_unit_requirement_verdict"].sel(feature=feature).item()),
            "statement": str(analysis["within_unit_requirement_statement"].sel(feature=feature).item())}


def search_dataset(spec: SearchSpec, candidates: list[Candidate], scores: dict, last_scores: dict, round0: dict,
                   round_reached: dict, finals: dict, evidence: dict, out: Path,
                   selection_confidence: float) -> xr.Dataset:
    """``search.nc``: every candidate's knobs, duration, scores, round, verdicts, Pareto front, rank and evidence.

    ``scores``/``last_scores``: ``{feature: {candidate: (estimate, low, high)}}`` of round 0 and of the last round
    each candidate ran; ``round0``: ``{feature: {candidate: bootstrap replicates}}`` of round 0;
    ``selection_confidence``: the share of the last round's bootstrap replicates whose best candidate was kept."""
    names = [c.name for c in candidates]
    features = list(spec.features)
    unit = spec.fault_unit
    estimate = np.array([[scores[f][n][0] for f in features] for n in names], dtype=float)
    low = np.array([[scores[f][n][1] for f in features] for n in names], dtype=float)
    high = np.array([[scores[f][n][2] for f in features] for n in names], dtype=float)
    note = np.where(np.isinf(estimate), "no estimate: the design-review unit's feature did not move at the screening "
                    "level, or it had fewer than 3 ok tests at a level (see the candidate's campaign)", "")
    best_f = np.argmin(np.where(np.isfinite(estimate), estimate, math.inf), axis=1)
    take = np.arange(len(names))
    score, score_low, score_high = estimate[take, best_f], low[take, best_f], high[take, best_f]
    last = np.array([[last_scores[f][n] for f in features] for n in names], dtype=float)  # (candidate, feature, 3)
    last_best = np.argmin(np.where(np.isfinite(last[:, :, 0]), last[:, :, 0], math.inf), axis=1)
    last = last[take, last_best]
    durations = np.array([test_duration(spec, c) for c in candidates])
    final = {n: _final_figures(finals[n], features, spec.condition) for n in finals}
    # rank: finalists by their verdict's bounds, then the others by the round they reached and their score in it
    def key(k: int):
        n = names[k]
        if n in final:
            return (0, final[n]["high"], final[n]["low"], score[k])
        return (1, -round_reached[n], last[k, 0] if math.isfinite(last[k, 0]) else math.inf, durations[k])
    order = sorted(range(len(names)), key=key)
    rank = np.empty(len(names), dtype=np.int32)
    rank[order] = np.arange(1, len(names) + 1)
    best = order[0]
    # paired differences to the best on round 0 (every candidate on the same units and repeats)
    replicate = np.stack([np.min(np.stack([round0[f][n] for f in features]), axis=0) for n in names])
    first = np.min(estimate, axis=1)
    with np.errstate(invalid="ignore"):
        # neither reached (inf - inf): a tie, not a loss
        differences = np.where(np.isinf(replicate) & np.isinf(replicate[best]), 0.0, replicate - replicate[best])
        difference = np.where(np.isinf(first) & np.isinf(first[best]), 0.0, first - first[best])
    tail = (1.0 - SCREENING_CONFIDENCE) / 2.0
    difference_low = np.quantile(np.where(np.isnan(differences), math.inf, differences), tail, axis=1,
                                 method="inverted_cdf")
    difference_high = np.quantile(np.where(np.isnan(differences), math.inf, differences), 1 - tail, axis=1,
                                  method="inverted_cdf")
    for array in (difference, difference_low, difference_high):
        array[best] = math.nan
    pareto = pareto_front(np.where(np.isfinite(score), score, math.inf), durations)
    fault_units = {"units": unit}
    variables = {}
    for name, knob in KNOBS.items():
        values = [c.shown[name] for c in candidates]
        attrs = {"long_name": knob.description}
        if knob.choices:
            variables[f"knob_{name}"] = ("candidate", np.array(values, dtype=object), attrs)
        else:
            variables[f"knob_{name}"] = ("candidate", np.array(values, dtype=float), attrs | {"units": knob.unit})
    rel = {n: os.path.relpath(evidence[n], out) for n in names}
    finals_stage = {n: "final" if n in final else f"round{round_reached[n]}" for n in names}
    rerun = [f"twin campaign run {os.path.join(os.path.dirname(rel[n]), finals_stage[n] + '.toml')}"
             f"{' --analyze' if n in final else ''}" for n in names]
    ds = xr.Dataset(
        {
            **variables,
            "test_duration": ("candidate", durations, {"units": "s", "long_name": "length of one test"}),
            "reference": ("candidate", np.array([c.reference for c in candidates], dtype=np.int8), {
                "long_name": "the reference procedure (the base scene's own profiles)", "flag_values": np.array(
                    [0, 1], dtype=np.int8), "flag_meanings": "candidate reference"}),
            "screening_estimate": (("candidate", "feature"), np.where(np.isfinite(estimate), estimate, math.nan),
                                   fault_units | {"long_name": "screening estimate of round 0 (every candidate on the "
                                                  "same units and repeats): the 95th-percentile unit's detectable "
                                                  "growth, extrapolated from the screening level"}),
            "screening_low": (("candidate", "feature"), np.where(np.isfinite(low), low, math.nan), fault_units | {
                "long_name": "lower bound of the screening estimate (bootstrap over units)"}),
            "screening_high": (("candidate", "feature"), np.where(np.isfinite(high), high, math.nan), fault_units | {
                "long_name": "upper bound of the screening estimate (bootstrap over units; NaN: not reached)"}),
            "screening_note": (("candidate", "feature"), note.astype(object), {"long_name": "why no estimate"}),
            "best_feature": ("candidate", np.array([features[k] for k in best_f], dtype=object), {
                "long_name": "the feature with the smallest screening estimate"}),
            "score": ("candidate", np.where(np.isfinite(score), score, math.nan), fault_units | {
                "long_name": "screening estimate of the best feature"}),
            "score_low": ("candidate", np.where(np.isfinite(score_low), score_low, math.nan), fault_units),
            "score_high": ("candidate", np.where(np.isfinite(score_high), score_high, math.nan), fault_units),
            "score_last_round": ("candidate", np.where(np.isfinite(last[:, 0]), last[:, 0], math.nan), fault_units | {
                "long_name": "screening estimate of the best feature in the last round the candidate ran (more "
                             "repeats than round 0: what selected it)"}),
            "score_last_round_low": ("candidate", np.where(np.isfinite(last[:, 1]), last[:, 1], math.nan), fault_units),
            "score_last_round_high": ("candidate", np.where(np.isfinite(last[:, 2]), last[:, 2], math.nan),
                                      fault_units),
            "round_reached": ("candidate", np.array([round_reached[n] for n in names], dtype=np.int32), {
                "units": "1", "long_name": "last screening round the candidate ran (0: eliminated after the first)"}),
            "finalist": ("candidate", np.array([n in final for n in names], dtype=np.int8), {
                "long_name": "ran the full within-unit campaign"}),
            "within_unit_low": ("candidate", np.array([final[n]["low"] if n in final else math.nan for n in names]),
                                fault_units | {"long_name": "lower bound of the 95th-percentile unit's detectable "
                                               "growth (full campaign of a finalist)"}),
            "within_unit_high": ("candidate", np.array([final[n]["high"] if n in final else math.nan
                                                        for n in names]),
                                 fault_units | {"long_name": "upper bound of the 95th-percentile unit's detectable "
                                                "growth (inf: above the largest level)"}),
            "within_unit_feature": ("candidate", np.array([final[n]["feature"] if n in final else ""
                                                          for n in names], dtype=object), {
                "long_name": "the finalist's feature with the smallest bounds in its full campaign (the bounds, "
                             "verdict and statement are this feature's)"}),
            "within_unit_verdict": ("candidate", np.array([final[n]["verdict"] if n in final else ""
                                                          for n in names], dtype=object), {
                "long_name": "within-unit verdict of a finalist: met / not met / undetermined / insufficient data"}),
            "within_unit_statement": ("candidate", np.array([final[n]["statement"] if n in final else ""
                                                            for n in names], dtype=object)),
            "pareto": ("candidate", pareto.astype(np.int8), {
                "long_name": "on the Pareto front of screening estimate against test duration"}),
            "rank": ("candidate", rank, {"units": "1", "long_name": "rank (1: the best procedure)"}),
            "difference_to_best": ("candidate", difference, fault_units | {
                "long_name": "this candidate's round-0 score minus the best's (the same units and repeats)"}),
            "difference_low": ("candidate", difference_low, fault_units),
            "difference_high": ("candidate", difference_high, fault_units),
            "evidence": ("candidate", np.array([rel[n] for n in names], dtype=object), {
                "long_name": "the candidate's last campaign directory, relative to the search directory"}),
            "rerun": ("candidate", np.array(rerun, dtype=object), {
                "long_name": "the command that runs that campaign again (the same seeds, so the same numbers) from the "
                             "search directory, into out/<campaign name>"}),
        },
        coords={"candidate": ("candidate", np.array(names, dtype=object)),
                "feature": ("feature", np.array(features, dtype=object))},
    )
    ds.attrs.update({
        "Conventions": CONVENTIONS, "title": f"test-procedure search {spec.name}", "name": spec.name,
        "description": spec.description, "fault": spec.fault, "fault_unit": unit,
        "requirement": spec.requirement, "requirement_source": spec.requirement_source,
        "knobs": json.dumps(list(KNOBS)), "best": names[best],
        "reference_procedure": f"the base scene {spec.scene}'s own procedure ({load_scene(spec.scene).description})",
        "verdict": final[names[best]]["verdict"] if names[best] in final else "insufficient data",
        "search_spec": spec.text, "plan": describe_plan(spec),
        "root_seed": int(spec.campaign_data.get("root_seed", 0)), "units": spec.budget.units,
        "repeats": spec.budget.repeats, "screening_level": spec.screening,
        "selection_confidence": selection_confidence,
        "history": "written by twin procedure search (campaigns.workflows.procedure_search)",
    })
    ds.attrs["statement"] = search_statement(ds)
    return ds


def pareto_front(score: np.ndarray, duration: np.ndarray) -> np.ndarray:
    """Candidates no other beats on both: a smaller or equal score and test duration, one of them strictly."""
    front = np.zeros(len(score), dtype=bool)
    for k in range(len(score)):
        if not math.isfinite(score[k]):
            continue
        dominated = (score <= score[k]) & (duration <= duration[k]) & ((score < score[k]) | (duration < duration[k]))
        front[k] = not dominated.any()
    return front


def _knob_words(ds: xr.Dataset, candidate: str) -> str:
    """The candidate's knobs in words, numbers in their display units (campaigns.units)."""
    words = []
    for name, knob in KNOBS.items():
        value = ds[f"knob_{name}"].sel(candidate=candidate).item()
        words.append(f"{name} {value if knob.choices else quantity(value, knob.unit, digits=4)}")
    return ", ".join(words)


def _interval(low: float, high: float, unit: str) -> str:
    """A bracket of detectable growths in its display unit; an infinite upper bound reads "above"."""
    if not math.isfinite(high):
        return f"above {quantity(low, unit)}" if math.isfinite(low) else "not resolved"
    return quantity_range(low, high, unit, digits=3)


def _signed(low: float, high: float, unit: str) -> str:
    """A difference's interval with its signs, in one display unit (``inf``: the other never reaches detection)."""
    scale, shown = display_scale(unit, [low, high])
    ends = [f"{v * scale:+.3g}" if math.isfinite(v) else ("+inf" if v > 0 else "-inf") for v in (low, high)]
    return f"{ends[0]} to {ends[1]} {shown}"


def search_statement(ds: xr.Dataset) -> str:
    """The search's finding in one paragraph, computed once: the best procedure, its within-unit verdict with its
    bounds, and what it beats (the reference, paired over the same units), with the sample sizes."""
    unit, best = ds.attrs["fault_unit"], ds.attrs["best"]
    row = ds.sel(candidate=best)
    fault = "backlash growth" if ds.attrs["fault"] == "backlash" else "preload loss"
    requirement = quantity(float(ds.attrs["requirement"]), unit)
    n = int((ds["finalist"] == 1).sum())
    head = (f"{row['within_unit_verdict'].item() or 'insufficient data'}: the best of {ds.sizes['candidate']} "
            f"procedures is {best} ({'the reference' if int(row['reference']) else _knob_words(ds, best)}; "
            f"{float(row['test_duration']):.3g} s per test): the 95th-percentile unit detects a {fault} of "
            f"{_interval(float(row['within_unit_low']), float(row['within_unit_high']), unit)} with "
            f"{row['within_unit_feature'].item()} (requirement {requirement}; {ds.attrs['units']} units x "
            f"{ds.attrs['repeats']} tests per level on fresh units, {n} finalist(s) with the full sweep"
            + (f"; the screening kept the best candidate of {float(ds.attrs['selection_confidence']) * 100:.0f} % of "
               "its bootstrap replicates" if math.isfinite(float(ds.attrs["selection_confidence"])) else "") + ").")
    reference = [str(c) for c in ds["candidate"].values if int(ds["reference"].sel(candidate=c))]
    if not reference or reference[0] == best:
        others = ds.where(ds["candidate"] != best, drop=True)
        if others.sizes["candidate"] == 0:
            return head
        runner = str(others["candidate"].values[int(np.argmin(others["rank"].values))])
        return (head + f" The reference (the base scene's procedure) is the best; the next, {runner}, has a "
                f"screening estimate larger by {_signed(*_difference(ds, runner), unit)} (95 % paired bootstrap over "
                "the same units, round 0).")
    low, high = _difference(ds, reference[0])
    if low > 0:
        verdict = "beats the reference"
    elif high < 0:
        verdict = "does not beat the reference, which screens better"
    else:
        verdict = "is not distinguished from the reference"
    return (head + f" It {verdict} ({reference[0]}, {float(ds['test_duration'].sel(candidate=reference[0])):.3g} s): "
            f"the reference's screening estimate minus the best's is {_signed(low, high, unit)} (95 % paired "
            f"bootstrap over the same units, round 0).")


def _difference(ds: xr.Dataset, candidate: str) -> tuple[float, float]:
    row = ds.sel(candidate=candidate)
    return float(row["difference_low"]), float(row["difference_high"])


def ranking_table(ds: xr.Dataset):
    """The ranked candidates as a table (``ranking.csv``): knobs with units in the headers, scores in the fault's
    display unit."""
    unit = ds.attrs["fault_unit"]
    scale, shown = (1e6, "um") if unit == "m" else (1.0, unit)
    rows = []
    for k in np.argsort(ds["rank"].values):
        row = ds.isel(candidate=int(k))
        entry = {"rank": int(row["rank"]), "candidate": str(row["candidate"].item())}
        for name, knob in KNOBS.items():
            entry[f"{name} [{knob.unit}]" if knob.unit else name] = row[f"knob_{name}"].item()
        entry["test_duration [s]"] = float(row["test_duration"])
        entry["best_feature"] = row["best_feature"].item()
        for var in ("score", "score_low", "score_high", "within_unit_low", "within_unit_high", "difference_to_best",
                    "difference_low", "difference_high"):
            entry[f"{var} [{shown}]"] = float(row[var]) * scale
        entry["within_unit_verdict"] = row["within_unit_verdict"].item()
        entry["pareto"] = bool(row["pareto"])
        entry["round_reached"] = int(row["round_reached"])
        entry["evidence"] = row["evidence"].item()
        entry["rerun"] = row["rerun"].item()
        rows.append(entry)
    return pd.DataFrame(rows)
