"""Campaign specification: the TOML file, its validation and its canonical form.

A spec is validated completely before anything runs. Structural problems
(types, signs, ``min > max``, NaN) and problems found against the model's
:class:`~campaigns.runner.catalog.Catalog` (unknown parameter, unknown scene,
incompatible unit) are collected together and raised as one
:class:`SpecError` listing every problem with its field path.

The uncertainty table is *resolved* during validation: each row becomes a
:class:`Distribution` with absolute parameters in the target's SI unit, using
the nominal value from the parameter set (relative rows, ``%Nom`` in Table 9.5)
and the unit table below (absolute rows).
"""

from __future__ import annotations

import hashlib
import json
import math
import string
import tomllib
from pathlib import Path
from typing import Annotated, Literal

import pydantic
from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    PlainValidator,
    PrivateAttr,
    ValidationInfo,
    field_validator,
    model_validator,
)

from campaigns.runner.catalog import CONDITION_CHOICES, CONDITION_UNITS, Catalog, spelling_hint
from campaigns.runner.control_limits import ControlLimits
from campaigns.runner.distributions import Distribution, DistributionKind
from campaigns.runner.ranges import resolve, shape_problems
from campaigns.statistics.within_unit_floors import DESIGN_REVIEW_QUANTILE, MIN_REPEATS, MIN_UNITS
from twin.errors import InputError
from twin.fidelity import requested_levels
from twin.scenes import CONDITIONS as SCENE_CONDITIONS
from twin.scenes import split_targets
from twin.scenes.procedure import procedure_problems
from twin.solver import MAX_DT
from twin.tomlfiles import read_inheriting

#: Largest ``runs_per_dataset`` a spec may ask for. At 20 000 runs the Monte Carlo standard error of a
#: detection probability is at most 0.35 percentage points and that of a mean 0.7 % of the spread, far
#: below the model's other uncertainties (the thesis study uses 1000). Beyond it the cost is out of
#: proportion: the driver samples every run before anything is submitted and keeps the samples in memory,
#: and the wall time of the runs grows with them (docs/performance.md, "The figures behind the campaign code's
#: constants"). A larger study is several campaigns with different ``root_seed`` values.
MAX_RUNS_PER_DATASET = 20_000

#: Physical bounds of the solver and execution fields, ``field: (low, high, unit, what it is and why the range)``,
#: checked before anything runs (:func:`in_range`); the CLI checks its ``--dt``, ``--duration``, ``--timeout`` and
#: ``--workers`` against the same table.
BOUNDS = {
    # the finest step of the work-precision ladder (125 us / 1024, docs/accuracy.md); below it a 10 s procedure is
    # over 1e8 steps (hours per run) for no accuracy the twin can show; the coarsest is the solver's own (MAX_DT)
    "dt": (1.0e-7, MAX_DT, "s", "integration step"),
    # at least 10 samples per 1 ms acquisition period; at most one sample per second (the shortest procedure is 10 s)
    "output_dt": (1.0e-4, 1.0, "s", "output spacing"),
    # the longest built-in test procedure is 10 s; a procedure 60 times longer is a mistake, not a test
    "duration": (1.0e-3, 600.0, "s", "simulated duration"),
    # one hour of wall clock per run is far beyond any procedure's run time (docs/performance.md), and the budget
    # bounds what a hung run (and the compile warm-up's timed run) holds the queue
    "timeout": (1.0e-3, 3600.0, "s", "wall-clock budget of one run"),
    "runs_per_dataset": (1, MAX_RUNS_PER_DATASET, "", "runs per data set"),
    "fidelity_audit_runs": (0, MAX_RUNS_PER_DATASET, "", "runs per data set re-run at full fidelity"),
    # each kept trace holds the run's whole time series (10 001 samples per variable) in the driver and results.nc
    "trace_runs": (0, 100, "", "traced runs per data set"),
    "decimation": (1, 10_000, "", "trace decimation (keep every n-th output sample)"),
    "chunk_size": (1, 10_000, "", "runs per task"),
    "workers": (1, 256, "", "worker processes"),
}


def in_range(field: str, value, *, bound: str | None = None) -> None:
    """Raise ``ValueError`` naming the value and its allowed range unless ``value`` is within ``BOUNDS[bound or
    field]`` (the message is the problem a spec or the CLI reports for ``field``)."""
    low, high, unit, what = BOUNDS[bound or field]
    if value is None or low <= value <= high:
        return
    suffix = f" {unit}" if unit else ""
    raise ValueError(f"{value:g}{suffix} is outside the allowed range [{low:g}, {high:g}]{suffix} ({what})")


def _bounded(kind, bound: str):
    """A spec field of type ``kind`` checked against ``BOUNDS[bound]``."""

    def check(value):
        in_range(bound, value)
        return value

    return Annotated[kind, AfterValidator(check)]


class SpecError(InputError):
    """A campaign spec is invalid; ``problems`` lists every problem with its field path."""

    def __init__(self, problems: list[str]):
        super().__init__("campaign spec", problems)


#: Longest campaign, data-set or search name. A campaign's name is its default output directory (``out/<name>``) and
#: appears in file names; a file-system name holds 255 bytes, and a procedure search's candidate campaigns are named
#: ``<search>-<candidate>-<stage>`` (:data:`SEARCH_NAME_MAX_LENGTH`).
NAME_MAX_LENGTH = 100
#: A procedure search's name leaves room for its candidates' ``-p12-round3`` (13 characters up to ``-p999-round99``).
SEARCH_NAME_MAX_LENGTH = NAME_MAX_LENGTH - 20
_NAME_CHARACTERS = frozenset(string.ascii_letters + string.digits + "_-")


def check_name(name: str, max_length: int = NAME_MAX_LENGTH) -> str:
    """The one rule of names (campaigns, data sets, searches): 1 to ``max_length`` ASCII letters, digits, ``_`` or
    ``-``. No path separator and no dot, so ``../../tmp/x`` cannot lead ``out/<name>`` elsewhere; no space, quote or
    control character, so a name reads the same in a shell, a file name and a page."""
    if not name:
        raise ValueError("a name must not be empty (letters, digits, _ and -)")
    if len(name) > max_length:
        raise ValueError(f"a name of {len(name)} characters; at most {max_length} (letters, digits, _ and -)")
    bad = sorted(set(name) - _NAME_CHARACTERS)
    if bad:
        raise ValueError(f"{name!r} holds {' '.join(repr(c) for c in bad[:5])}: a name is letters, digits, _ and - "
                         "only (it names the output directory out/<name> and files)")
    return name


#: A campaign's or a data set's name (:func:`check_name`).
Name = Annotated[str, AfterValidator(check_name)]
#: A procedure search's name (:mod:`campaigns.workflows.procedure_search`): the same rule, shorter.
SearchName = Annotated[str, AfterValidator(lambda name: check_name(name, SEARCH_NAME_MAX_LENGTH))]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class Base(_Strict):
    """The base scene and parameter set every run starts from."""

    scene: str = "nominal"
    parameters: str = "bench"

    @field_validator("scene")
    @classmethod
    def _known_scene(cls, scene: str, info: ValidationInfo) -> str:
        catalog = _catalog(info)
        if catalog is not None and scene not in catalog.scene_names:
            raise ValueError(f"unknown scene {scene!r}; {spelling_hint(scene, catalog.scene_names)}"
                             f"known: {', '.join(catalog.scene_names)}")
        return scene


class Solver(_Strict):
    """Options passed to the simulation (``twin.simulate``).

    ``fidelity`` is ``"auto"`` (default: each subsystem at the cheapest level the
    scene and the campaign's features and traces allow), ``"full"``, or a table
    ``{subsystem = level}`` (see ``twin fidelity levels``).
    """

    integrator: str = "rk4"  # or any other twin.simulate integrator
    # the CPU lane engine, or the CUDA one (twin.Solver.engine; docs/gpu.md): refused before any run without a GPU
    engine: Literal["cpu", "cuda"] = "cpu"
    dt: _bounded(float | None, "dt") = None
    output_dt: _bounded(float | None, "output_dt") = None
    fidelity: str | dict[str, str] = "auto"

    @field_validator("fidelity")
    @classmethod
    def _known_fidelity(cls, fidelity):
        problems = requested_levels(fidelity)[1]
        if problems:
            raise ValueError("\n".join(problems))  # one problem per line, split in validate_spec
        return fidelity


class FidelityAudit(_Strict):
    """After the campaign, re-run the first ``runs`` runs of every data set at full fidelity
    (same parameters, same noise) and compare the features (:mod:`campaigns.bench.fidelity_audit`).
    ``0`` skips it; it is also skipped when the campaign already runs at full fidelity with a named integrator."""

    runs: _bounded(int, "fidelity_audit_runs") = 10


class Execution(_Strict):
    """Per-run limits and isolation.

    ``timeout`` is the wall-clock budget of one run in seconds; the run function
    receives it as ``wall_time_limit``; with ``isolation = "process"`` a run
    still busy ``campaigns.runner.runs.kill_grace(timeout)`` seconds later is killed
    (see :mod:`campaigns.runner.sandbox`); without isolation a run that returns over its
    budget is recorded as a timeout (see :mod:`campaigns.runner.runs`). ``chunk_size`` fixes the number of runs per
    task; by default it adapts to the measured run time (see :mod:`campaigns.runner.execution`).
    """

    timeout: _bounded(float, "timeout") = 600.0
    isolation: Literal["process", "none"] = "process"
    chunk_size: _bounded(int | None, "chunk_size") = None


class Traces(_Strict):
    """Decimated time series kept for the first ``runs_per_dataset`` runs of each data set.

    The default variables are the signals of Eq. 9.12, true and measured: what the backlash
    feature is made of. Every traced variable is an output the automatic fidelity must keep
    (adding ``motor_current`` keeps the full current loop in every run of the campaign).
    """

    runs_per_dataset: _bounded(int, "trace_runs") = 0
    variables: list[str] = ["position_demand", "nut1_position", "screw_equivalent_position", "linear_encoder_position"]
    decimation: _bounded(int, "decimation") = 10


def _known_condition(name: str, info: ValidationInfo) -> str:
    catalog = _catalog(info)
    if catalog is None:  # structural validation only (e.g. a stored spec replayed): the model is not known
        return name
    known = list(catalog.condition_names)
    if name not in known:
        raise ValueError(f"unknown condition {name}; {spelling_hint(name, known)}"
                         f"the model's scenes accept: {', '.join(known)}")
    return name


# Condition names are validated as dictionary keys so that a bad value and a bad name are both reported.
ConditionName = Annotated[str, AfterValidator(_known_condition)]


def _condition_value(value):
    """A finite number or a word; which of the two a condition takes is checked against the scene table
    (:meth:`Dataset._condition_values`), so one bad value gives one problem, not one per type tried."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"must be a number or one of the condition's choices, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"Input should be a finite number (got {value!r})")
    return float(value)


ConditionValue = Annotated[float | str, PlainValidator(_condition_value)]


def _known_parameter(name: str, info: ValidationInfo) -> str:
    if split_targets({name: None})[0]:
        raise ValueError(f"{name} is a scene condition: set it in the data set's conditions")
    catalog = _catalog(info)
    if catalog is not None:
        try:
            catalog.nominal(name)
        except KeyError as exc:
            raise ValueError(str(exc.args[0])) from None
    return name


def _finite(value):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"must be a finite number in the parameter's SI unit, got {value!r}")
    return float(value)


ParameterName = Annotated[str, AfterValidator(_known_parameter)]
FiniteValue = Annotated[float, PlainValidator(_finite)]


class Dataset(_Strict):
    """A named set of condition overrides applied to a scene (Table 9.4).

    ``parameters`` fixes parameters for this data set only, in SI units as the parameter files give them: a
    modelling assumption varied one data set at a time (a model-form study). A parameter the uncertainty table
    samples is then not sampled in this data set: its drawn value is replaced by the fixed one (the draws still
    happen, so every other row keeps its value). ``seeds_from`` names another data set whose random streams this
    one uses (its uncertain values and its noise, run by run: common random numbers), so that the two differ only in
    what the data set changes and their difference can be read run by run (:mod:`campaigns.runner.sampling`).
    ``procedure`` replaces the scene's demand profiles by a test procedure's knobs (:data:`twin.scenes.procedure.KNOBS`:
    preload setting, external force, motion amplitude and frequency, cycles, dwell, zero procedure); the data set's
    ``conditions`` apply after it (a preload loss is the condition ``preload`` below the procedure's setting).
    ``fidelity`` replaces ``solver.fidelity`` for this data set's runs (``{subsystem: level}``): the campaign sets it
    on the members of a fault sweep whose automatic levels differ from the sweep's
    (:func:`campaigns.bench.campaign.sweep_fidelity`), so that every level of a sweep runs one model.
    """

    name: Name
    scene: str | None = None
    description: str = ""
    conditions: dict[ConditionName, ConditionValue] = {}
    parameters: dict[ParameterName, FiniteValue] = {}
    seeds_from: str | None = None
    procedure: dict[str, int | float | str] = {}
    fidelity: dict[str, str] | None = None

    @field_validator("fidelity")
    @classmethod
    def _known_levels(cls, fidelity: dict[str, str] | None) -> dict[str, str] | None:
        problems = requested_levels(fidelity)[1] if fidelity is not None else []
        if problems:
            raise ValueError("\n".join(problems))  # one problem per line, split in validate_spec
        return fidelity

    @field_validator("scene")
    @classmethod
    def _known_scene(cls, scene: str | None, info: ValidationInfo) -> str | None:
        return Base._known_scene(scene, info) if scene is not None else None

    @field_validator("procedure")
    @classmethod
    def _procedure_knobs(cls, procedure: dict[str, int | float | str]) -> dict[str, int | float | str]:
        """Known knobs within the bench's ranges (every problem listed)."""
        problems = procedure_problems(procedure)
        if problems:
            raise ValueError("\n".join(problems))  # one problem per line, split in validate_spec
        return procedure

    @field_validator("conditions")
    @classmethod
    def _condition_values(cls, conditions: dict[str, float | str]) -> dict[str, float | str]:
        """A numeric condition takes a number, a choice condition one of its choices (every problem listed)."""
        problems = []
        for name, value in conditions.items():
            choices = CONDITION_CHOICES.get(name)
            if choices is not None and value not in choices:
                problems.append(f"{name}: {value!r} is not one of {', '.join(choices)}")
            elif choices is None and isinstance(value, str):
                problems.append(f"{name}: must be a number [{CONDITION_UNITS.get(name, '')}], got {value!r}")

        if problems:
            raise ValueError("\n".join(problems))  # one problem per line, split in validate_spec
        return conditions


#: Unit slips a spec value in SI units may hide: SI unit -> (unit meant, its SI value): ``backlash = 80`` meant
#: ``80 µm`` (8e-05 m). Offered in the message of a value out of range when the value in that unit is in range.
UNIT_SLIPS = {"m": (("µm", 1e-6), ("mm", 1e-3)), "N": (("kN", 1e3),), "Pa": (("bar", 1e5), ("kPa", 1e3), ("MPa", 1e6)),
              "K": (("degC", None),)}


def condition_range_problem(name: str, value) -> str | None:
    """A bench scene condition's value outside its range (``twin.scenes.CONDITIONS``), said with its SI unit, the
    range and, when the number read in a handier unit would be in range, the SI value meant:
    ``backlash: 80 m is outside the allowed range 0 ... 1e-3 m (total axial play of each nut); spec values are in SI
    units: for 80 µm write 8e-05``."""
    condition = SCENE_CONDITIONS.get(name)
    if condition is None or not condition.numeric or isinstance(value, (str, bool)) or not math.isfinite(value):
        return None
    if condition.check(value):
        return None
    text = (f"{name}: {value:g} {condition.unit} is outside the allowed range {condition.allowed} "
            f"({condition.description})")
    for unit, size in UNIT_SLIPS.get(condition.unit, ()):
        meant = value + 273.15 if size is None else value * size
        if condition.check(meant):
            return text + f"; spec values are in SI units: for {value:g} {unit} write {meant:g}"
    return text


class Observability(_Strict):
    """The fault sweep analysed for the minimum detectable fault size.

    ``sweep`` names data sets that differ only in the scene condition ``condition``
    (each sets it). For ``"backlash"`` (default) the reference is the data set with zero backlash
    and the requirement is Table 9.3's 1 µm. For ``"preload"`` (preload loss) the reference is
    named by ``reference`` (the healthy preload), the fault size is the loss ``preload_ref -
    preload``, and ``requirement`` [N] with its ``requirement_source`` must be given.

    ``features`` names the campaign's features the sweep's verdicts are about (those that respond to its fault:
    the backlash features for a backlash sweep, the drag torque for a preload loss); page 1 and the printed summary
    give the verdicts of those alone. Empty (the default): every feature of the campaign.
    """

    sweep: list[str] = []
    condition: Literal["backlash", "preload"] = "backlash"
    reference: str | None = None
    requirement: float | None = Field(default=None, gt=0)
    requirement_source: str = ""
    features: list[str] = []


#: Rows of the bench's table that change from test to test of one unit, besides the scene conditions (room
#: temperature, supply pressure): the load cell's repeatability (a per-test scatter by definition) and the encoders'
#: mounting phases (where a test's start falls within a 4 µm or 2.5 µm signal period moves with the start position,
#: which the screw's thermal growth alone shifts by ~18 µm over Table 9.5's 20 K); docs/campaigns.md, "Within-unit
#: campaigns", argues every row.
PER_TEST_BY_NATURE = ("sensors.load_cell_repeatability_error", "sensors.linear_encoder_mounting_phase",
                      "sensors.torque_meter_encoder_mounting_phase")


def _unit_floor(count: int) -> int:
    if count < MIN_UNITS:
        raise ValueError(f"{count} units is below the floor of {MIN_UNITS}: with fewer, not even the largest unit "
                         f"bounds the {DESIGN_REVIEW_QUANTILE * 100:g}th-percentile unit the within-unit verdict is "
                         "about with 95 % confidence (campaigns.statistics.within_unit_floors.MIN_UNITS)")
    return count


def _repeat_floor(repeats: int) -> int:
    if repeats < MIN_REPEATS:
        raise ValueError(f"{repeats} repeats is below the floor of {MIN_REPEATS}: the check that the units share one "
                         "test-to-test scatter (Brown-Forsythe) needs 3 tests per unit and fault level "
                         "(campaigns.statistics.within_unit_floors.MIN_REPEATS)")
    return repeats


class Units(_Strict):
    """A within-unit campaign: the same ``count`` units tested ``repeats`` times at every fault level (issue 29).

    Run ``i`` of every data set tests unit ``i // repeats`` for the ``i % repeats``-th time, so ``runs_per_dataset``
    must be ``count * repeats``. The rows of the uncertainty table named in ``per_test`` are redrawn from test to
    test; every other row is a fixed error of the unit, drawn once per unit and shared by all its tests in every
    data set (:mod:`campaigns.runner.sampling`). ``per_test`` defaults to the table's ``scene.*`` rows (the test
    conditions) and its rows among :data:`PER_TEST_BY_NATURE`. The fault levels are the observability sweep's data
    sets; analysis adds the within-unit verdict (:mod:`campaigns.analysis.within_unit`) beside the between-unit one,
    which then uses one test per unit (repeat 0).
    """

    count: Annotated[int, AfterValidator(_unit_floor)]
    repeats: Annotated[int, AfterValidator(_repeat_floor)]
    per_test: list[str] | None = None


class Uncertainty(_Strict):
    """One row of the uncertainty table (Table 9.5).

    The range is given either as ``half_range`` (± around the nominal), as
    ``low``/``high`` (absolute values, or percent deviations from nominal when
    ``relative``), or as ``sigma`` (optionally with ``mean``). ``relative = true``
    marks the ``%Nom`` rows: numbers are percent of the nominal value.
    """

    target: str
    distribution: DistributionKind
    relative: bool = False
    unit: str | None = None
    half_range: float | None = Field(default=None, ge=0)
    low: float | None = None
    high: float | None = None
    sigma: float | None = Field(default=None, ge=0)
    mean: float | None = None
    value: float | None = None
    source: str = ""

    _distribution: Distribution | None = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _resolve(self, info: ValidationInfo) -> Uncertainty:
        catalog = _catalog(info)
        problems = self.problems(catalog)
        if problems:
            raise ValueError("\n".join(problems))  # one problem per line, split in validate_spec
        if catalog is not None:
            self._distribution = self._resolved(*catalog.nominal(self.target))
        return self

    def problems(self, catalog: Catalog | None) -> list[str]:
        """Every problem of the row: its shape, its target, and converting it to SI units.

        Also called on rows whose fields failed validation (built with ``model_construct``
        from their well-typed fields, see :func:`validate_spec`), so a row with a bad
        ``sigma`` still reports an unknown target.
        """
        problems = self._shape_problems()
        if catalog is None:
            return problems
        try:
            nominal, unit = catalog.nominal(self.target)
        except KeyError as exc:
            return problems + [str(exc.args[0])]
        if not problems:
            try:
                self._resolved(nominal, unit)
            except ValueError as exc:
                problems.append(str(exc))
        return problems

    @property
    def distribution_resolved(self) -> Distribution:
        """The resolved :class:`Distribution` (set when validated with a catalog)."""
        if self._distribution is None:
            raise RuntimeError(f"uncertainty {self.target!r} was validated without a catalog; use load_spec")
        return self._distribution

    def _shape_problems(self) -> list[str]:
        return shape_problems(self)

    def _resolved(self, nominal: float, unit: str) -> Distribution:
        """Convert the row to absolute SI parameters (raises ValueError on unit problems)."""
        return resolve(self, nominal, unit)


class CampaignSpec(_Strict):
    """A validated Monte Carlo campaign. Build it with :func:`load_spec`."""

    name: Name
    description: str = ""
    root_seed: int = Field(ge=0)
    runs_per_dataset: _bounded(int, "runs_per_dataset")
    features: list[str] = Field(min_length=1)
    base: Base = Base()
    solver: Solver = Solver()
    fidelity_audit: FidelityAudit = FidelityAudit()
    execution: Execution = Execution()
    traces: Traces = Traces()
    datasets: list[Dataset] = Field(min_length=1)
    uncertainties: list[Uncertainty] = []
    observability: Observability = Observability()
    #: The sweeps after the first when the spec gives ``[[observability]]`` tables (:meth:`_sweep_tables`).
    further_sweeps: list[Observability] = []
    control_limits: ControlLimits = ControlLimits()
    units: Units | None = None

    _feature_units: dict[str, tuple[str, str]] = PrivateAttr(default_factory=dict)
    _warnings: list[str] = PrivateAttr(default_factory=list)
    _condition_units: dict[str, str] = PrivateAttr(default_factory=dict)

    @model_validator(mode="before")
    @classmethod
    def _sweep_tables(cls, data):
        """``[[observability]]`` (an array of sweep tables) is the first sweep in ``observability`` and the others in
        ``further_sweeps``, so that a spec with one sweep, and everything that reads ``observability``, stays as it
        was; the single table ``[observability]`` passes unchanged."""
        if not isinstance(data, dict) or not isinstance(data.get("observability"), list):
            return data
        tables = data["observability"]
        if not tables or "further_sweeps" in data:
            raise ValueError("observability: give one [observability] table, or one [[observability]] table per "
                             "fault sweep" + ("" if tables else " (the array is empty)")
                             + (", not further_sweeps beside it" if "further_sweeps" in data else ""))
        return {**data, "observability": tables[0], "further_sweeps": tables[1:]}

    @property
    def sweeps(self) -> list[Observability]:
        """Every fault sweep of the spec, the first first (empty without a sweep)."""
        return ([self.observability] if self.observability.sweep else []) + list(self.further_sweeps)

    @field_validator("features")
    @classmethod
    def _known_features(cls, features: list[str], info: ValidationInfo) -> list[str]:
        catalog = _catalog(info)
        known = catalog.feature_units if catalog is not None else None
        unknown = [f for f in features if known is not None and f not in known]
        if unknown:
            hints = "".join(spelling_hint(f, known) for f in unknown)
            raise ValueError(f"unknown feature(s) {', '.join(unknown)}; {hints}known: {', '.join(known)}")
        if len(set(features)) != len(features):
            raise ValueError("duplicate features")
        return features

    @model_validator(mode="after")
    def _consistent(self, info: ValidationInfo) -> CampaignSpec:
        catalog = _catalog(info)
        if catalog is not None and catalog.feature_units is not None:
            self._feature_units = {f: tuple(catalog.feature_units[f]) for f in self.features}
        if catalog is not None:
            self._condition_units = dict(catalog.condition_units)
        problems = cross_field_problems(self.model_dump())
        if problems:
            raise ValueError("\n".join(problems))  # one problem per line, split in validate_spec
        return self

    @property
    def warnings(self) -> list[str]:
        """What validation found suspicious but not wrong (a sampled range far from its nominal, a Gaussian whose
        tail crosses a bound): said before any run, the campaign still runs (:func:`support_checks`)."""
        return list(self._warnings)

    def feature_meta(self, feature: str) -> tuple[str, str]:
        """Unit and long name of a feature, as the catalog declared them (``("1", name)`` if it did not)."""
        return self._feature_units.get(feature, ("1", feature))

    def condition_units(self) -> dict[str, str]:
        """SI unit of each numeric condition, as the catalog declared them (the bench scenes' table if the
        spec was validated without a catalog)."""
        return self._condition_units or dict(CONDITION_UNITS)

    def seed_index(self, dataset_index: int) -> int:
        """The index of the data set whose random streams data set ``dataset_index`` uses: its own, or that of the
        data set its ``seeds_from`` names (:mod:`campaigns.runner.sampling`)."""
        named = self.datasets[dataset_index].seeds_from
        return dataset_index if named is None else [d.name for d in self.datasets].index(named)

    def fixed_columns(self, dataset_index: int, targets: list[str]) -> dict[int, float]:
        """The columns of the uncertainty table (``targets``, in table order) that data set ``dataset_index`` fixes
        by its ``parameters``, with their values."""
        fixed = self.datasets[dataset_index].parameters
        return {k: fixed[t] for k, t in enumerate(targets) if t in fixed}

    def per_test_targets(self) -> list[str]:
        """The targets redrawn from test to test in a within-unit campaign (``units.per_test``, by default the
        table's ``scene.*`` rows and its rows among :data:`PER_TEST_BY_NATURE`); empty without ``[units]``."""
        if self.units is None:
            return []
        if self.units.per_test is not None:
            return list(self.units.per_test)
        return [u.target for u in self.uncertainties
                if split_targets({u.target: None})[0] or u.target in PER_TEST_BY_NATURE]

    def unit_draws(self, run_index: int, targets: list[str]) -> dict:
        """What :func:`campaigns.runner.sampling.sample_run` needs of ``[units]`` for run ``run_index``: the unit it
        tests and the columns of the table (``targets``) drawn once per unit; ``{}`` without ``[units]``."""
        if self.units is None:
            return {}
        per_test = set(self.per_test_targets())
        return {"unit": run_index // self.units.repeats,
                "per_unit": [k for k, t in enumerate(targets) if t not in per_test]}

    def distributions(self) -> list[Distribution]:
        """The resolved uncertainty table, in spec order (the sampling order)."""
        return [u.distribution_resolved for u in self.uncertainties]

    def canonical(self) -> dict:
        """The spec with its resolved distributions, as plain JSON-ready data.

        ``control_limits`` is left out when it holds the defaults, the solver's ``engine`` when it is the CPU's, and
        ``units``, ``further_sweeps``, a sweep's ``features`` and a data
        set's ``parameters``, ``seeds_from``, ``procedure`` and ``fidelity`` when not used, so specs written before
        they existed keep their hash (and their results directories).
        """
        spec = self.model_dump(mode="json")
        if self.control_limits == ControlLimits():
            del spec["control_limits"]
        if self.units is None:
            del spec["units"]
        else:  # the rows as sampled, so that a change of the default is a change of the hash
            spec["units"]["per_test"] = self.per_test_targets()
        if not self.further_sweeps:
            del spec["further_sweeps"]
        for table in [spec["observability"], *spec.get("further_sweeps", [])]:
            if not table["features"]:  # every feature: specs written before sweeps named theirs keep their hash
                del table["features"]
        if self.solver.engine == "cpu":  # the default engine: specs written before the CUDA one keep their hash
            del spec["solver"]["engine"]
        for dataset in spec["datasets"]:  # left out when not used, so specs written before them keep their hash
            if not dataset["parameters"]:
                del dataset["parameters"]
            if dataset["seeds_from"] is None:
                del dataset["seeds_from"]
            if not dataset["procedure"]:
                del dataset["procedure"]
            if dataset["fidelity"] is None:
                del dataset["fidelity"]
        return {"spec": spec, "resolved": [d.as_dict() for d in self.distributions()]}

    def to_json(self) -> str:
        """Canonical JSON text (sorted keys): what the spec hash is computed on."""
        return json.dumps(self.canonical(), sort_keys=True, separators=(",", ":"))

    def spec_hash(self) -> str:
        """SHA-256 of :meth:`to_json`; keys the chunk store so results of different specs never mix."""
        return hashlib.sha256(self.to_json().encode()).hexdigest()


def _catalog(info: ValidationInfo) -> Catalog | None:
    return (info.context or {}).get("catalog")


def _path(loc: tuple) -> str:
    if len(loc) > 1 and loc[0] == "further_sweeps" and isinstance(loc[1], int):  # as written: [[observability]]
        loc = (f"observability[{loc[1] + 1}]", *loc[2:])
    out = ""
    for part in loc:
        if part == "[key]":
            continue
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def _listed(data: dict, key: str) -> list[dict]:
    """The tables of a list field, skipping entries of the wrong type (those are field errors)."""
    value = data.get(key)
    return [v for v in value if isinstance(v, dict)] if isinstance(value, list) else []


def cross_field_problems(data: dict) -> list[str]:
    """Problems between fields: duplicate data sets and targets, a condition both set and sampled,
    an inconsistent observability sweep.

    Works on raw spec data as well as on a validated spec's ``model_dump()``: entries of the
    wrong type are skipped (they are reported as field errors), so these checks run whatever
    else is wrong with the spec.
    """
    problems = []
    datasets = _listed(data, "datasets")
    names = [d["name"] for d in datasets if isinstance(d.get("name"), str)]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        problems.append(f"datasets: duplicate name(s) {', '.join(duplicates)}")
    targets = [u["target"] for u in _listed(data, "uncertainties") if isinstance(u.get("target"), str)]
    duplicates = sorted({t for t in targets if targets.count(t) > 1})
    if duplicates:
        problems.append(f"uncertainties: target(s) listed twice: {', '.join(duplicates)}")
    sampled = set(split_targets(dict.fromkeys(targets))[0])
    for k, dataset in enumerate(data.get("datasets") if isinstance(data.get("datasets"), list) else []):
        conditions = dataset.get("conditions") if isinstance(dataset, dict) else None
        clash = sorted(sampled & set(conditions)) if isinstance(conditions, dict) else []
        if clash:
            problems.append(f"datasets[{k}].conditions: {', '.join(clash)} also sampled in uncertainties")
        for name, value in (conditions.items() if isinstance(conditions, dict) else ()):
            if isinstance(value, (int, float)) and (problem := condition_range_problem(name, value)) is not None:
                problems.append(f"datasets[{k}].conditions: {problem}")
    problems += _seeds_from_problems(datasets)
    tables = sweep_tables(data)
    for path, observability in tables:
        sweep = observability.get("sweep")
        if len(tables) > 1 and not sweep:
            problems.append(f"{path}.sweep: empty; each [[observability]] table names the data sets of its sweep")
        if isinstance(sweep, list):
            problems += [f"{path}{p}" for p in _sweep_problems([n for n in sweep if isinstance(n, str)], datasets,
                                                                  observability)]
        problems += [f"{path}.features: {p}" for p in _sweep_feature_problems(observability.get("features"),
                                                                               data.get("features"))]
    conditions = [t.get("condition", "backlash") for _, t in tables]
    twice = sorted({c for c in conditions if isinstance(c, str) and conditions.count(c) > 1})
    if twice:
        problems.append(f"observability: {', '.join(twice)} swept by more than one table; a spec sweeps each "
                        "condition once (the analysis names a sweep's variables after its condition: "
                        "campaigns.analysis.vocabulary.sweep_key)")
    if isinstance(data.get("units"), dict):
        first = tables[0][1].get("sweep") if tables else None
        problems += _units_problems(data["units"], data, targets, first if isinstance(first, list) else [])
        if len(tables) > 1:
            problems.append("units: a within-unit campaign takes one observability sweep (its fault levels are the "
                            "levels each unit is tested at)")
    return problems


def sweep_tables(data: dict) -> list[tuple[str, dict]]:
    """The sweep tables of raw spec data or of a validated spec's ``model_dump()``, each with the field path its
    problems are reported under: ``[("observability", table)]`` for the single table, ``observability[k]`` for the
    k-th of ``[[observability]]`` (``further_sweeps`` being the tables after the first). Entries of the wrong type are
    skipped (they are field errors)."""
    observability = data.get("observability")
    if isinstance(observability, list):
        return [(f"observability[{k}]", t) for k, t in enumerate(observability) if isinstance(t, dict)]
    further = data.get("further_sweeps") if isinstance(data.get("further_sweeps"), list) else []
    if not further:
        return [("observability", observability)] if isinstance(observability, dict) else []
    first = [("observability[0]", observability)] if isinstance(observability, dict) else []
    return first + [(f"observability[{k + 1}]", t) for k, t in enumerate(further) if isinstance(t, dict)]


def _units_problems(units: dict, data: dict, targets: list[str], sweep: list) -> list[str]:
    """``[units]`` against the rest of the spec: its ``per_test`` rows are rows of the table, the fault levels are an
    observability sweep, and every run of a data set is one test of one unit (``runs_per_dataset = count x
    repeats``)."""
    problems = []
    per_test = units.get("per_test")
    for name in per_test if isinstance(per_test, list) else []:
        if isinstance(name, str) and name not in targets:
            problems.append(f"units.per_test: {name!r} is not a row of the uncertainty table; "
                            f"{spelling_hint(name, targets)}per_test names rows of uncertainties: "
                            f"{', '.join(targets) or 'none'}")
    if not sweep:
        problems.append("units: a within-unit campaign needs observability.sweep: its data sets are the fault levels "
                        "each unit is tested at (the healthy reference and at least one fault size)")
    observability = data.get("observability") if isinstance(data.get("observability"), dict) else {}
    condition = observability.get("condition", "backlash")
    levels = [d.get("conditions", {}).get(condition) for d in _listed(data, "datasets")
              if d.get("name") in sweep and isinstance(d.get("conditions"), dict)]
    if len(set(levels)) < len(levels):
        problems.append(f"units: the sweep's data sets must each set a different {condition} (one fault level each)")
    count, repeats, runs = units.get("count"), units.get("repeats"), data.get("runs_per_dataset")
    if all(isinstance(v, int) and not isinstance(v, bool) for v in (count, repeats, runs)) and runs != count * repeats:
        problems.append(f"runs_per_dataset: {runs} runs, but [units] tests {count} units {repeats} times each: set "
                        f"runs_per_dataset = {count * repeats} (run i of a data set is test i % {repeats} of unit "
                        f"i // {repeats})")
    return problems


def _seeds_from_problems(datasets: list[dict]) -> list[str]:
    """``seeds_from`` names another data set, one that uses its own seeds (no chains: each data set's streams are
    read from its own entry or from one other)."""
    by_name = {d["name"]: d for d in datasets if isinstance(d.get("name"), str)}
    problems = []
    for k, dataset in enumerate(datasets):
        named = dataset.get("seeds_from")
        if named is None or not isinstance(named, str):
            continue
        if named == dataset.get("name"):
            problems.append(f"datasets[{k}].seeds_from: names the data set itself; leave it out to use its own seeds")
        elif named not in by_name:
            problems.append(f"datasets[{k}].seeds_from: unknown data set {named!r}; "
                            f"{spelling_hint(named, list(by_name))}known: {', '.join(by_name)}")
        elif by_name[named].get("seeds_from") is not None:
            problems.append(f"datasets[{k}].seeds_from: {named!r} itself uses the seeds of "
                            f"{by_name[named]['seeds_from']!r}; name that data set instead")
    return problems


def _sweep_problems(sweep: list[str], datasets: list[dict], observability: dict) -> list[str]:
    """The problems of one sweep table, each starting with the field below the table (``.sweep: ...``)."""
    if not sweep:
        return []
    condition = observability.get("condition", "backlash")
    reference = observability.get("reference")
    by_name = {d["name"]: d for d in datasets if isinstance(d.get("name"), str)}
    unknown = [n for n in sweep if n not in by_name]
    if unknown:
        return [f".sweep: unknown data set(s) {', '.join(unknown)}"]
    conditions = {n: by_name[n].get("conditions") if isinstance(by_name[n].get("conditions"), dict) else {}
                  for n in sweep}
    problems = [f".sweep: data set {n} does not set conditions.{condition}" for n in sweep
                if condition not in conditions[n]]
    if reference is not None:
        if reference not in sweep:
            problems.append(f".reference: {reference!r} is not in the table's sweep")
    elif condition != "backlash":
        problems.append(f".reference: required for a {condition} sweep (the healthy data set)")
    else:
        zeros = [n for n in sweep if conditions[n].get("backlash") == 0.0]
        if not problems and len(zeros) != 1:
            problems.append(f".sweep: needs exactly one zero-backlash reference, found {len(zeros)}")
    if condition != "backlash" and observability.get("requirement") is None:
        problems.append(f".requirement: required for a {condition} sweep (the fault size to detect)")
    if len(sweep) < 2:
        problems.append(f".sweep: needs the reference and at least one {condition} level")
    return problems


def _sweep_feature_problems(named, features) -> list[str]:
    """A sweep's ``features`` against the campaign's: each one of them, once (entries of the wrong type are field
    errors)."""
    if not isinstance(named, list) or not isinstance(features, list):
        return []
    allowed = [f for f in features if isinstance(f, str)]
    names = [n for n in named if isinstance(n, str)]
    problems = []
    unknown = [n for n in names if n not in allowed]
    if unknown:
        hints = "".join(spelling_hint(n, allowed) for n in unknown)
        problems.append(f"{', '.join(map(repr, unknown))} not among the campaign's features; {hints}allowed: "
                        f"{', '.join(allowed)} (leave the list out for all of them)")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        problems.append(f"{', '.join(twice)} listed twice")
    return problems


#: Fields of an uncertainty row and their types, for the checks of rows whose fields failed validation.
_ROW_TYPES = {"target": str, "distribution": str, "relative": bool, "unit": str, "half_range": float, "low": float,
              "high": float, "sigma": float, "mean": float, "value": float, "source": str}


def _row_problems(data: dict, rows: set[int], catalog: Catalog | None) -> list[str]:
    """:meth:`Uncertainty.problems` of the given rows, built from their raw fields.

    A numeric field of the wrong type counts as given (NaN), so the row's shape is judged
    as written; its own type error is already reported.
    """
    problems = []
    table = data.get("uncertainties")
    for k in sorted(rows):
        row = table[k]
        if not isinstance(row, dict) or not isinstance(row.get("target"), str):
            continue
        fields = {"relative": False, "unit": None, "source": "", "distribution": None}
        for key, kind in _ROW_TYPES.items():
            if key not in row:
                continue
            value = row[key]
            if kind is float:
                fields[key] = (float(value) if isinstance(value, (int, float)) and not isinstance(value, bool)
                               else math.nan)
            elif isinstance(value, kind):
                fields[key] = value
        uncertainty = Uncertainty.model_construct(**fields)
        problems += [f"uncertainties[{k}]: {p}" for p in uncertainty.problems(catalog)]
    return problems


def _field_names(loc: tuple) -> list[str]:
    """The fields a spec table at ``loc`` (an error's location, the unknown key last) accepts."""
    tables = [part for part in loc[:-1] if not isinstance(part, int)]
    if not tables:
        return list(CampaignSpec.model_fields)
    annotation = CampaignSpec.model_fields[tables[0]].annotation if tables[0] in CampaignSpec.model_fields else None
    model = getattr(annotation, "__args__", (annotation,))[0] if annotation is not None else None
    return list(model.model_fields) if len(tables) == 1 and hasattr(model, "model_fields") else []


def validate_spec(data: dict, catalog: Catalog | None) -> CampaignSpec:
    """Validate spec data (a parsed TOML document) against ``catalog``.

    Parameters
    ----------
    data : dict
        The parsed spec.
    catalog : Catalog or None
        What the model offers (parameter names and nominals, scenes, features).
        ``None`` checks the structure only; the result then cannot be sampled.

    Raises
    ------
    SpecError
        Listing every problem, each prefixed by its field path.
    """
    problems, failed_rows = [], set()
    try:
        spec = CampaignSpec.model_validate(data, context={"catalog": catalog})
    except pydantic.ValidationError as exc:
        for err in exc.errors():
            if len(err["loc"]) > 2 and err["loc"][0] == "uncertainties" and isinstance(err["loc"][1], int):
                failed_rows.add(err["loc"][1])
            path = _path(err["loc"])
            if err["type"] == "extra_forbidden":
                known = _field_names(err["loc"])
                problems.append(f"{path}: unknown field; {spelling_hint(str(err['loc'][-1]), known)}"
                                f"allowed: {', '.join(known)}" if known else f"{path}: unknown field")
                continue
            if err["type"] != "value_error":
                problems.append(f"{path}: {err['msg']} (got {err['input']!r})")
                continue
            for line in err["msg"].removeprefix("Value error, ").splitlines():
                problems.append(f"{path}: {line}" if path else line)
    # Pydantic skips a model's own checks once one of its fields failed: run them on the raw data too.
    problems += [p for p in _row_problems(data, failed_rows, catalog) + cross_field_problems(data) if p not in problems]
    if problems:
        raise SpecError(problems)
    found, spec._warnings = catalog.support_checks(spec) if catalog is not None else ([], [])
    if found:
        raise SpecError(found)
    return spec


def _read_spec_file(path: Path) -> dict:
    try:
        return tomllib.loads(path.read_bytes().decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise SpecError([f"{path}: not UTF-8 text (byte 0x{exc.object[exc.start]:02x} at offset {exc.start}); "
                         "save the spec as UTF-8"]) from None
    except OSError as exc:
        raise SpecError([f"{path}: cannot read the spec: {exc.strerror or exc}"]) from None
    except tomllib.TOMLDecodeError as exc:
        raise SpecError([f"{path}: {exc}"]) from None


def _locate_parent(path: Path, parent, seen: tuple[Path, ...]) -> Path:
    """``extends = "other.toml"``: another spec file, relative to this one."""
    if not isinstance(parent, str) or not parent:
        raise SpecError([f"{path}: extends: must be the path of another spec file (a string), got {parent!r}"])
    parent_path = (path.parent / parent).resolve()
    if parent_path in seen:
        raise SpecError([f"{path}: extends: cycle through {parent_path}"])
    return parent_path


def read_spec(path: Path) -> dict:
    """Parse a spec file, applying ``extends`` (tables merged key by key, other fields replaced:
    :mod:`twin.tomlfiles`, the scenes' inheritance too)."""
    return read_inheriting(Path(path), "extends", _read_spec_file, _locate_parent)


def read_spec_data(path: str | Path, runs: int | None = None, *, timeout: float | None = None) -> dict:
    """Read a campaign spec (TOML) with its overrides, not yet validated (:func:`validate_spec`).

    Parameters
    ----------
    path : str or Path
        The spec file. ``extends = "other.toml"`` inherits every field of
        another spec (path relative to this file); tables are merged key by
        key, other fields replaced.
    runs : int, optional
        Override ``runs_per_dataset`` (the CLI's ``--runs``).
    timeout : float, optional
        Override ``execution.timeout`` [s] (the CLI's ``--timeout``).

    Raises
    ------
    SpecError
        If the file cannot be read or parsed.
    """
    data = read_spec(Path(path))
    if runs is not None:
        data["runs_per_dataset"] = runs
    if timeout is not None:
        execution = data.get("execution")
        data["execution"] = {**(execution if isinstance(execution, dict) else {}), "timeout": timeout}
    return data


def load_spec(path: str | Path, runs: int | None = None, *, timeout: float | None = None,
              catalog: Catalog) -> CampaignSpec:
    """Read (:func:`read_spec_data`) and validate a campaign spec against a model's ``catalog``; the bench twin's
    entry, which defaults to its catalog, is :func:`campaigns.bench.campaign.load_spec` (``campaigns.load_spec``).

    Returns
    -------
    CampaignSpec
        Validated, with the uncertainty table resolved.

    Raises
    ------
    SpecError
        If the file cannot be read or parsed, or listing every validation problem.
    """
    return validate_spec(read_spec_data(path, runs, timeout=timeout), catalog)
