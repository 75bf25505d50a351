"""Levels where the verdict lives (issue 42, item 2): an adaptive search of the fault sizes of an observability sweep.

A spec's fixed sweep levels may straddle the requirement (0 and 5 µm around 1 µm: the verdict stays undetermined
whatever the runs) or leave the minimum detectable size between levels far apart. The search adds levels to the
sweep, each a new data set of the same campaign, until the minimum detectable size is bracketed to a stated
resolution, always trying the requirement itself first; as a stretch, the runs per level grow in stages until the
verdict is decided. docs/level_search.md gives the rules, the measurements that chose the placement method and the
bench run.

**A level is a data set.** An added level is the sweep's reference data set with the fault condition changed
(backlash ``b``, or preload ``reference - loss``) and ``seeds_from`` the reference: run ``i`` of every added level
draws the reference's uncertain values and noise of run ``i`` (common random numbers, :mod:`campaigns.runner.sampling`).
Its numbers therefore depend on the spec and its fault size only, never on when or after which other levels it was
added, nor on its position in the spec; the final campaign (fixed levels, then the added ones by size) is stored and
analysed as any other (:func:`store`). The added levels differ from the reference, and from each other, only in the
fault: for a model whose feature grows with the fault run by run, their detected fractions (the same runs against
the same threshold) never fall as the level grows, so one crossing is bracketed. The analysis's bootstrap resamples
every data set on its own, as if the levels were independent; their positive correlation then widens its bounds
(conservative), which the known-answer tests (tests/campaigns/test_level_search.py) measure.

**Where the next level goes.** The evidence is always the measured levels: the verdict and the bounds are those of
:func:`campaigns.analysis.campaign_analysis.bootstrap_minimum_detectable` (the bracket of the interpolated estimate:
the last level not detected with the power and the first detected; bounds: sweep levels at the confidence). After
the requirement, a level goes inside that bracket while it is wider than the resolution, then into the widest gap
inside the bounds wider than it (:func:`next_level`): ``bisection`` at the middle, ``monotone_fit`` where a probit
curve fitted to every level's detected count predicts the crossing or a bound. The fit only places levels.

**Looks (stretch).** ``stages`` lists the runs per level of each look; every sweep level grows to the next stage
while the verdict is undetermined. The verdict's confidence holds over the looks by Bonferroni: each of the ``K``
looks uses bounds at ``1 - (1 - confidence) / K`` (:func:`look_confidence`), so the chance that any look states a
wrong verdict is at most that of one look at ``confidence`` (each bound is one-sided at ``(1 - c) / 2``).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError
from scipy import optimize, stats

from campaigns.analysis.campaign_analysis import analyze
from campaigns.analysis.vocabulary import BACKLASH_REQUIREMENT, SWEEP_QUANTITIES
from campaigns.bench.adapter import BenchCatalog, simulate_run
from campaigns.bench.campaign import run_campaign
from campaigns.runner.execution import build_request
from campaigns.runner.files import atomic_write
from campaigns.runner.provenance import provenance
from campaigns.runner.runs import RunModel, execute_group
from campaigns.runner.sampling import sample_run
from campaigns.runner.spec import MAX_RUNS_PER_DATASET, CampaignSpec, read_spec, validate_spec
from campaigns.runner.storage import ChunkStore
from campaigns.statistics.defaults import FALSE_ALARM_RATE, POWER
from campaigns.statistics.detection import bootstrap_minimum_detectable, requirement_verdict, runs_to_decide
from campaigns.statistics.order_statistics import detection_run_floor
from twin.errors import InputError

#: Spawn-key tag of the search's bootstrap streams (one per look and step), far from the data-set indices and from
#: campaigns.analysis.campaign_analysis's tags.
SEARCH_STREAM = 1_000_043
#: Prefix of an added level's data-set name (``added_b1_25um``, ``added_loss150N``).
PREFIX = "added"
#: Most levels a search may add (a typing slip beyond it: each costs a level's runs, and 30 bisections split a
#: sweep's gap by 1e9).
MAX_LEVELS = 30
#: File beside results.nc with every look and step of the search (levels, runs, bracket, bounds, verdict).
LOG_NAME = "level_search.json"


class LevelSearchError(InputError):
    """A level search cannot start; ``problems`` lists every reason, each naming its setting."""

    def __init__(self, problems: list[str]):
        super().__init__("level search", problems)


class Settings(BaseModel):
    """What the search aims at and may spend.

    ``feature``: the feature whose minimum detectable fault size is searched. ``resolution`` [SI, the fault's unit]:
    the widest gap of adjacent levels around the estimate and inside its bounds that ends the search
    (:func:`next_level`; None: only the requirement level is added). ``method``: ``bisection`` or ``monotone_fit``
    (:func:`next_level`; bisection by measurement, docs/level_search.md). ``max_levels``: levels the search may
    add (the requirement's included). ``stages``: runs per level at each look (empty: the spec's
    ``runs_per_dataset``, one look). ``runs``: the most runs the search may execute, the fixed sweep levels'
    included (None: no cap beyond the levels and stages). ``confidence``: of the verdict over all looks.
    ``n_boot``, ``seed``: the bootstrap of each look.
    """

    model_config = ConfigDict(extra="forbid")

    feature: str
    resolution: float | None = Field(default=None, gt=0)
    method: Literal["bisection", "monotone_fit"] = "bisection"
    max_levels: int = Field(default=8, ge=0, le=MAX_LEVELS)
    stages: list[int] = []
    runs: int | None = Field(default=None, gt=0)
    confidence: float = Field(default=0.95, gt=0.5, lt=1.0)
    n_boot: int = Field(default=1000, ge=100, le=100_000)
    seed: int = Field(default=0, ge=0)

    @classmethod
    def checked(cls, **fields) -> Settings:
        """The settings from user input (the CLI's options): every invalid field in one :class:`LevelSearchError`,
        ``field: what is allowed (got value)``."""
        try:
            return cls(**fields)
        except ValidationError as exc:
            raise LevelSearchError([f"{'.'.join(str(p) for p in e['loc'])}: {e['msg']} (got {e['input']!r})"
                                    for e in exc.errors()]) from None


def look_confidence(confidence: float, looks: int) -> float:
    """Confidence of each of ``looks`` looks so that all together hold ``confidence`` (Bonferroni: the
    probabilities of a wrong verdict at each look add up to at most ``1 - confidence``)."""
    return 1.0 - (1.0 - confidence) / looks


@dataclass(frozen=True)
class Sweep:
    """The spec's fault sweep as the search sees it: the condition, its reference data set and value, the side the
    fault moves it to (+1 backlash, -1 preload loss), the requirement [SI] and the fixed levels ``{name: size}``."""

    condition: str
    reference: str
    reference_value: float
    sign: float
    requirement: float
    fixed: dict[str, float]

    @staticmethod
    def of(data: dict) -> Sweep:
        """The sweep of a validated spec's raw data (``read_spec``)."""
        observability = data.get("observability") or {}
        condition = observability.get("condition", "backlash")
        by_name = {d["name"]: d for d in data["datasets"]}
        values = {n: float(by_name[n]["conditions"][condition]) for n in observability["sweep"]}
        reference = observability.get("reference") or next(n for n, v in values.items() if v == 0.0)
        others = [v - values[reference] for n, v in values.items() if n != reference]
        requirement = observability.get("requirement") or BACKLASH_REQUIREMENT
        return Sweep(condition, reference, values[reference], -1.0 if others and max(others) <= 0 else 1.0,
                     float(requirement), {n: abs(v - values[reference]) for n, v in values.items()})

    def level_name(self, size: float) -> str:
        _, _, scale, unit = SWEEP_QUANTITIES[self.condition]
        text = f"{size * scale:.6g}".replace(".", "_").replace("+", "")
        stem = "b" if self.condition == "backlash" else "loss"
        return f"{PREFIX}_{stem}{text}{'um' if unit == 'µm' else unit}"


def plan_problems(spec: CampaignSpec, sweep: Sweep | None, settings: Settings) -> list[str]:
    """Every reason the search cannot start, before any run: the feature, the sweep, the requirement within the
    fault's range, the stages and the run budget against the detection floor, and the resolution against what the
    allowed levels can resolve (bisection's worst case: the widest gap of the sweep halved once per level)."""
    problems = []
    if settings.feature not in spec.features:
        problems.append(f"feature: {settings.feature!r} is not a feature of the spec ({', '.join(spec.features)})")
    if sweep is None:
        return problems + ["observability.sweep: the spec has no observability sweep, so there is no level to add"]
    quantity, unit, scale, shown = SWEEP_QUANTITIES[sweep.condition]
    largest = max(sweep.fixed.values())

    def fmt(value: float) -> str:
        return f"{value * scale:.4g} {shown}"

    if not 0.0 < sweep.requirement <= largest:
        problems.append(f"requirement: {fmt(sweep.requirement)} is outside the fault's range (0, {fmt(largest)}] "
                        f"spanned by the sweep: the search places {quantity} levels between the reference and the "
                        "largest fixed level; add a fixed level at or beyond the requirement")
    looks = settings.stages or [spec.runs_per_dataset]
    floor = detection_run_floor(FALSE_ALARM_RATE, POWER, look_confidence(settings.confidence, len(looks)))
    if any(b <= a for a, b in zip(looks, looks[1:], strict=False)):
        problems.append(f"stages: {looks} must increase from look to look (runs per level)")
    where = "stages" if settings.stages else "runs_per_dataset"
    if looks[0] < floor:
        problems.append(
            f"{where}: {looks[0]} runs per level at the first look is below the floor of {floor}: with fewer, no "
            f"order statistic bounds the detection quantiles at the look's confidence "
            f"{look_confidence(settings.confidence, len(looks)):.4g} ({settings.confidence:g} over {len(looks)} "
            f"look(s), Bonferroni); allowed: {floor} to {MAX_RUNS_PER_DATASET}")
    if looks[-1] > MAX_RUNS_PER_DATASET:
        problems.append(f"stages: {looks[-1]} runs per level is above the most a campaign allows, "
                        f"{MAX_RUNS_PER_DATASET}")
    needs_requirement = sweep.requirement not in sweep.fixed.values()
    first = (len(sweep.fixed) + needs_requirement) * looks[0]
    if settings.runs is not None and settings.runs < first:
        problems.append(f"runs: a budget of {settings.runs} runs is below the floor of {first}: the fixed sweep's "
                        f"{len(sweep.fixed)} levels{' and the requirement level' if needs_requirement else ''} at "
                        f"{looks[0]} runs each, before any level is placed")
    if needs_requirement and settings.max_levels < 1:
        problems.append("max_levels: 0 levels cannot add the requirement level the sweep lacks; allowed: at least 1")
    if settings.resolution is not None and 0.0 < sweep.requirement <= largest:
        levels = sorted({*sweep.fixed.values(), sweep.requirement})
        widest = max(b - a for a, b in zip(levels, levels[1:], strict=False))
        halvings = max(0, math.ceil(math.log2(widest / settings.resolution) - 1e-12))
        free = settings.max_levels - needs_requirement
        if halvings > free:
            problems.append(
                f"resolution: {fmt(settings.resolution)} is finer than the sweep can resolve with max_levels = "
                f"{settings.max_levels}: its widest gap, {fmt(widest)}, needs {halvings} bisections"
                f"{' besides the requirement level' if needs_requirement else ''}; allowed: at least "
                f"{fmt(widest / 2 ** max(free, 0))}, or raise max_levels")
    return problems


@dataclass
class Step:
    """One evaluation of the sweep: the look (0-based) and its runs per level, the levels ``{name: size}`` and the
    one just ``added``, what the bootstrap at the look's ``confidence`` found (estimate, bracket, bounds, each level's
    detection probability with its standard error, in the order of ``levels``), the ok runs ``used`` per level, the
    verdict and the runs executed so far."""

    look: int
    runs_per_level: int
    levels: dict[str, float]
    added: str | None
    estimate: float
    bracket: tuple[float, float]
    bounds: tuple[float, float]
    probability: list[float]
    probability_se: list[float]
    used: list[int]
    confidence: float
    verdict: str
    runs_used: int


def probit_fit(sizes, flagged, runs) -> tuple[float, float] | None:
    """``(a, b)`` of the probit curve ``p(x) = Phi(a + b x)``, ``b > 0``, fitted by maximum likelihood to ``flagged``
    of ``runs`` at each fault size ``x`` [SI]; None when the fit fails. A monotone fit of detection against fault
    size (Finney 1971, *Probit Analysis*, ch. 4): exact for a feature whose levels shift one normal distribution
    (the synthetic model against a fixed threshold), a placement rule only for any other."""
    x, k, n = (np.asarray(v, dtype=float) for v in (sizes, flagged, runs))
    span = float(np.ptp(x)) or 1.0
    u = x / span  # scaled to O(1), so one start suits every unit

    def nll(theta):
        p = np.clip(stats.norm.cdf(theta[0] + math.exp(theta[1]) * u), 1e-12, 1.0 - 1e-12)
        return -float(np.sum(k * np.log(p) + (n - k) * np.log1p(-p)))

    found = optimize.minimize(nll, np.array([stats.norm.ppf(FALSE_ALARM_RATE), math.log(4.0)]), method="Nelder-Mead",
                              options={"xatol": 1e-6, "fatol": 1e-9, "maxiter": 2000})
    return (float(found.x[0]), math.exp(found.x[1]) / span) if found.success else None


def probit_level(fit: tuple[float, float] | None, probability: float) -> float:
    """The fault size where the fitted curve reaches ``probability`` (NaN without a fit)."""
    if fit is None:
        return math.nan
    return float((stats.norm.ppf(probability) - fit[0]) / fit[1])


def open_gaps(sizes, bounds: tuple[float, float], resolution: float) -> list[tuple[float, float]]:
    """Gaps between adjacent levels inside the bootstrap ``bounds`` (an infinite upper bound: up to the largest
    level) wider than ``resolution``, widest first: where the bounds are set by the levels' spacing rather than
    by the runs' sampling."""
    levels = np.unique(np.asarray(sizes, dtype=float))
    low, high = bounds
    high = min(high, float(levels[-1]))
    gaps = [(float(a), float(b)) for a, b in zip(levels[:-1], levels[1:], strict=True)
            if a >= low and b <= high and b - a > resolution * (1 + 1e-9)]
    return sorted(gaps, key=lambda g: g[0] - g[1])


def next_level(method: str, step: Step, resolution: float, power: float = POWER) -> float | None:
    """The fault size of the next level, or None when the levels resolve the minimum detectable size to
    ``resolution``: the estimate's bracket (the adjacent levels around it) and every gap inside the bounds no wider.

    A bracket wider than the resolution is split first, then a gap inside the bounds (:func:`open_gaps`): once the
    levels there are no farther apart than the resolution, the bounds are the runs' sampling uncertainty rounded out
    to the resolution. ``bisection`` splits the bracket, then the widest gap, at the middle. ``monotone_fit`` fits a
    probit curve to every level's detected count (:func:`probit_fit`) and puts the bracket's level where it crosses
    the power, then a gap's level where the curve predicts a bound: ``power -+ z se`` with ``se`` the bootstrap
    standard error of the bracket's detection probabilities and ``z`` the bounds' normal quantile (a level beyond
    it is detected, or missed, in all but ``(1 - c) / 2`` of the replicates), else at the widest gap's middle.
    Either is kept at least half the resolution from both ends, so each level shrinks its gap by that much, and
    rounded to a tenth of the resolution, so the names and the report's numbers stay short.
    """
    sizes = list(step.levels.values())
    fit = None
    if method == "monotone_fit":
        fit = probit_fit(sizes, [round(p * m) for p, m in zip(step.probability, step.used, strict=True)], step.used)
    low, high = step.bracket
    if high - low > resolution * (1 + 1e-9):
        x = probit_level(fit, power) if fit else 0.5 * (low + high)
    else:
        gaps = open_gaps(sizes, step.bounds, resolution)
        if not gaps:
            return None
        (low, high), x = gaps[0], 0.5 * sum(gaps[0])
        if fit is not None:
            names = list(step.levels)
            around = [step.probability_se[names.index(n)] for n, v in step.levels.items() if v in step.bracket]
            half = stats.norm.ppf(0.5 + 0.5 * step.confidence) * float(np.mean(around))
            targets = [probit_level(fit, min(max(power + side * half, 1e-3), 1 - 1e-3)) for side in (-1, 1)]
            inside = [(gap, t) for gap in gaps for t in targets if gap[0] < t < gap[1]]
            if inside:
                (low, high), x = inside[0]
    if not math.isfinite(x):  # the fit failed: bisect
        x = 0.5 * (low + high)
    x = min(max(x, low + 0.5 * resolution), high - 0.5 * resolution)
    step_size = resolution / 10.0
    rounded = round(x / step_size) * step_size
    return rounded if low < rounded < high else 0.5 * (low + high)


@dataclass
class Result:
    """A finished search: the final campaign's validated spec, the sweep, the settings, every step (the last holds the
    verdict with its bounds at the look confidence), why the search stopped, and the run records ``{(data set, run):
    record}`` (for :func:`store`)."""

    spec: CampaignSpec
    sweep: Sweep
    settings: Settings
    steps: list[Step]
    stop_reason: str
    records: dict = field(repr=False)

    @property
    def last(self) -> Step:
        return self.steps[-1]

    @property
    def resolved(self) -> bool:
        """Whether the levels resolve the minimum detectable size to the resolution (:func:`next_level`)."""
        resolution = self.settings.resolution
        low, high = self.last.bracket
        return (resolution is not None and math.isfinite(self.last.estimate)
                and high - low <= resolution * (1 + 1e-9)
                and not open_gaps(list(self.last.levels.values()), self.last.bounds, resolution))

    @property
    def runs_used(self) -> int:
        return len(self.records)

    @property
    def added(self) -> list[str]:
        return [s.added for s in self.steps if s.added is not None]


class _Draws:
    """``samples[d, i]`` of :func:`campaigns.runner.sampling.sample` for one run at a time, by the same function
    (:func:`~campaigns.runner.sampling.sample_run`): the search draws only the runs it executes."""

    def __init__(self, spec: CampaignSpec):
        self.spec, self.distributions = spec, spec.distributions()
        self.targets = [d.target for d in self.distributions]

    def __getitem__(self, key: tuple[int, int]) -> np.ndarray:
        d, i = key
        spec = self.spec
        return sample_run(self.distributions, spec.root_seed, spec.seed_index(d), i,
                          spec.fixed_columns(d, self.targets), **spec.unit_draws(i, self.targets))


class _Runs:
    """The search's runs, executed in this process in the run function's lane groups and kept by (data set name,
    run index): a level's runs never change once run (their seeds do not depend on the spec's other levels)."""

    def __init__(self, run_function: RunModel):
        self.run_function, self.records = run_function, {}

    def values(self, spec: CampaignSpec, name: str, runs: int, feature: str) -> np.ndarray:
        """The used values of ``feature`` (status ok, finite) of the first ``runs`` runs of data set ``name``."""
        d = [x.name for x in spec.datasets].index(name)
        missing = [i for i in range(runs) if (name, i) not in self.records]
        draws, lanes = _Draws(spec), self.run_function.lanes
        requests = [build_request(spec, draws, d, i) for i in missing]
        for first in range(0, len(requests), lanes):
            group = requests[first:first + lanes]
            for request, record in zip(group, execute_group(self.run_function, group), strict=True):
                self.records[name, request.run_index] = record
        used = [self.records[name, i] for i in range(runs)]
        return np.array([r["features"][feature] for r in used if r["status"] == "ok"
                         and math.isfinite(r["features"][feature])])


def _with_levels(data: dict, sweep: Sweep, added: dict[str, float], runs: int) -> dict:
    """The spec data with the added levels as data sets (the reference's with the fault condition changed and its
    seeds), after the spec's own, by size; the sweep lists every level by size."""
    by_name = {d["name"]: d for d in data["datasets"]}
    reference = by_name[sweep.reference]
    seeds = reference.get("seeds_from") or sweep.reference
    _, _, scale, shown = SWEEP_QUANTITIES[sweep.condition]
    datasets = list(data["datasets"])
    for name, size in sorted(added.items(), key=lambda item: item[1]):
        datasets.append({**{k: v for k, v in reference.items() if k not in ("name", "description", "seeds_from")},
                         "name": name, "seeds_from": seeds,
                         "description": f"added by the level search: {size * scale:.4g} {shown} "
                                        f"({sweep.reference}'s conditions and seeds)",
                         "conditions": {**reference.get("conditions", {}),
                                        sweep.condition: sweep.reference_value + sweep.sign * size}})
    levels = {**sweep.fixed, **added}
    return {**data, "datasets": datasets, "runs_per_dataset": runs,
            "observability": {**data["observability"], "sweep": sorted(levels, key=lambda n: levels[n])}}


def search(spec_path: str | Path, settings: Settings, *, run_function: RunModel | None = None, catalog=None,
           runs: int | None = None, progress: Callable[[str], None] | None = None) -> Result:
    """Run the level search on the sweep of the spec at ``spec_path`` (module docstring).

    Parameters
    ----------
    spec_path : str or Path
        A campaign spec with an observability sweep (``extends`` applies).
    settings : Settings
    run_function : callable, optional
        Default :func:`campaigns.bench.adapter.simulate_run`; runs execute in this process.
    catalog : Catalog, optional
        Default: the bench's, for the spec's base parameters and scene.
    runs : int, optional
        Override ``runs_per_dataset`` (the first look's runs per level when ``settings.stages`` is empty).
    progress : callable, optional
        ``progress(line)`` after each step.

    Raises
    ------
    LevelSearchError
        Before any run, listing every problem of the plan (:func:`plan_problems`); SpecError for an invalid spec.
    """
    data = read_spec(Path(spec_path))
    if runs is not None:
        data["runs_per_dataset"] = runs
    base = data.get("base", {}) if isinstance(data.get("base"), dict) else {}
    catalog = catalog or BenchCatalog(base.get("parameters", "bench"), base.get("scene", "nominal"))
    spec = validate_spec(data, catalog)
    sweep = Sweep.of(data) if spec.observability.sweep else None
    problems = plan_problems(spec, sweep, settings)
    if problems:
        raise LevelSearchError(problems)
    executor = _Runs(run_function or simulate_run)
    looks = settings.stages or [spec.runs_per_dataset]
    confidence = look_confidence(settings.confidence, len(looks))
    added: dict[str, float] = {}
    steps: list[Step] = []
    report = progress or (lambda line: None)

    def evaluate(look: int, n: int, new: str | None) -> Step:
        current = _with_levels(data, sweep, added, n)
        current_spec = validate_spec(current, catalog)
        levels = {**sweep.fixed, **added}
        names = list(levels)
        samples = [executor.values(current_spec, name, n, settings.feature) for name in names]
        found = bootstrap_minimum_detectable(
            [levels[x] for x in names], samples, names.index(sweep.reference), false_alarm_rate=FALSE_ALARM_RATE,
            power=POWER, n_boot=settings.n_boot, confidence=confidence,
            seed=np.random.SeedSequence(settings.seed, spawn_key=(SEARCH_STREAM, look, len(steps))))
        step = Step(look, n, dict(levels), new, found["estimate"], found["bracket"], found["bounds"],
                    [float(p) for p in found["probability"]], [float(e) for e in found["probability_se"]],
                    [len(s) for s in samples], confidence, requirement_verdict(*found["bounds"], sweep.requirement),
                    len(executor.records))
        steps.append(step)
        report(_step_line(step, sweep))
        return step

    def budget_allows(extra: int) -> bool:
        return settings.runs is None or len(executor.records) + extra <= settings.runs

    stop = ""
    for look, n in enumerate(looks):
        if look > 0:
            if not budget_allows((n - looks[look - 1]) * (len(sweep.fixed) + len(added))):
                stop = f"run budget: growing every level to {n} runs would exceed {settings.runs} runs"
                break
        step = evaluate(look, n, None)
        while True:
            size, stop = _next_size(step, sweep, settings)
            if size is None:
                break
            if len(added) >= settings.max_levels:
                stop = f"level budget: max_levels = {settings.max_levels} levels added"
                break
            if not budget_allows(n):
                stop = f"run budget: another level of {n} runs would exceed {settings.runs} runs"
                break
            name = sweep.level_name(size)
            added[name] = size
            step = evaluate(look, n, name)
        if stop or step.verdict != "undetermined":
            break
    last = steps[-1]
    if not stop:
        decided = last.verdict != "undetermined"
        stop = ("verdict decided" if decided else f"verdict undetermined after {len(looks)} look(s)") + (
            "; levels within the resolution around the estimate and inside its bounds"
            if settings.resolution is not None else "")
    final = _with_levels(data, sweep, added, last.runs_per_level)
    return Result(validate_spec(final, catalog), sweep, settings, steps, stop, executor.records)


def _next_size(step: Step, sweep: Sweep, settings: Settings) -> tuple[float | None, str]:
    """The next level's size (None: none), and why the search must stop there (empty: it may go on)."""
    if sweep.requirement not in step.levels.values():
        return sweep.requirement, ""
    if settings.resolution is None:
        return None, ""
    if not math.isfinite(step.estimate):
        return None, (f"no level is detected with {POWER:g} probability: the minimum detectable size lies beyond the "
                      "sweep's largest level; add a larger fixed level")
    return next_level(settings.method, step, settings.resolution), ""


def _step_line(step: Step, sweep: Sweep) -> str:
    _, _, scale, shown = SWEEP_QUANTITIES[sweep.condition]

    def fmt(value: float) -> str:
        return f"{value * scale:.4g}" if math.isfinite(value) else "inf"

    what = f"added {step.added} ({fmt(step.levels[step.added])} {shown})" if step.added else "levels as given"
    return (f"look {step.look + 1}, {step.runs_per_level} runs per level, {what}: estimate {fmt(step.estimate)} "
            f"{shown}, bracket {fmt(step.bracket[0])}-{fmt(step.bracket[1])} {shown}, bounds {fmt(step.bounds[0])}-"
            f"{fmt(step.bounds[1])} {shown}, {step.verdict}, {step.runs_used} runs so far")


def statement(result: Result) -> str:
    """The search's finding in one sentence: the verdict with its bounds, the bracket, the confidence rule, the
    levels added and the runs used; an undetermined verdict says how many runs would decide it."""
    sweep, last, settings = result.sweep, result.last, result.settings
    quantity, _, scale, shown = SWEEP_QUANTITIES[sweep.condition]
    looks = len(settings.stages) or 1

    def fmt(value: float) -> str:
        return f"{value * scale:.3g} {shown}" if math.isfinite(value) else "beyond the sweep"

    rule = (f"{settings.confidence * 100:g} % over {looks} looks (Bonferroni, each at "
            f"{look_confidence(settings.confidence, looks) * 100:.4g} %)" if looks > 1
            else f"{settings.confidence * 100:g} %")
    text = (f"{last.verdict}: minimum detectable {quantity} between the adjacent levels {fmt(last.bracket[0])} and "
            f"{fmt(last.bracket[1])} ({rule} bootstrap bounds: above {fmt(last.bounds[0])}, at most "
            f"{fmt(last.bounds[1])}) against the {fmt(sweep.requirement)} requirement; {len(result.added)} level(s) "
            f"added by {settings.method.replace('_', ' ')} ({', '.join(result.added) or 'none'}), "
            f"{last.runs_per_level} runs per level, {result.runs_used} runs in all; stopped: {result.stop_reason}")
    if last.verdict == "undetermined":
        names = list(last.levels)
        _, reason = runs_to_decide([last.levels[x] for x in names], last.probability, last.probability_se,
                                   min(last.used), sweep.requirement,
                                   confidence=look_confidence(settings.confidence, looks), labels=names)
        text += f"; {reason}"
    return text


def store(result: Result, out_dir: str | Path, *, run_function: RunModel | None = None, workers: int = 1,
          analyse: bool = True, progress: bool = False) -> Path:
    """Store the final campaign as any campaign: the search's runs written as chunk files of the final spec, then
    :func:`campaigns.runner.execution.run_campaign` resumes it (only the runs the search did not need execute: the
    spec's data sets outside the sweep), writes ``results.nc`` (and, for the bench, the loop margins and the fidelity
    audit the spec asks for), and :func:`campaigns.analysis.campaign_analysis.analyze` writes ``analysis.nc``. The
    search's steps go to :data:`LOG_NAME` beside them. Returns the path of ``results.nc``."""
    run_function = run_function or simulate_run
    out = Path(out_dir)
    spec = result.spec
    chunks = ChunkStore(out, spec, provenance=provenance(run_function))
    index = {d.name: k for k, d in enumerate(spec.datasets)}
    for name in index:
        records = [dict(r, dataset_index=index[name]) for (n, i), r in sorted(result.records.items())
                   if n == name and i < spec.runs_per_dataset]
        if records:
            chunks.write_chunk(records)
    results = run_campaign(spec, out, workers=workers, resume=True, progress=progress,
                           run_function=None if run_function is simulate_run else run_function)
    log = {"statement": statement(result), "stop_reason": result.stop_reason,
           "settings": result.settings.model_dump(), "steps": [_step_record(s) for s in result.steps]}
    atomic_write(out / LOG_NAME, lambda tmp: tmp.write_text(json.dumps(log, indent=1)))
    if analyse:
        analyze(results)
    return results


def _step_record(step: Step) -> dict:
    def finite(value: float) -> float | None:  # JSON has no inf
        return value if math.isfinite(value) else None

    return {"look": step.look, "runs_per_level": step.runs_per_level, "added": step.added, "levels": step.levels,
            "estimate": finite(step.estimate), "bracket": [finite(v) for v in step.bracket],
            "bounds": [finite(v) for v in step.bounds],
            "detection_probability": step.probability,
            "used_runs": step.used,
            "verdict": step.verdict, "runs_used": step.runs_used}
