"""Scenes: test procedures of the bench, as data (TOML).

A scene is what an engineer would write on a test sheet: how long the test
lasts, the sled position demand, the external force demand, and the conditions
(:data:`CONDITIONS`: preload and its configuration, ball-screw axial backlash,
room temperature, supply pressure, how the bench is initialised and where the
encoders are zeroed, whether the pneumatic cylinder is attached, where the load
cell's electrical noise enters). The thesis's
data sets of Table 9.4 are the scenes ``ds1`` ... ``ds5``; ``ds6``/``ds7``
repeat ``ds2`` with 5 um / 40 um backlash; ``nominal`` is the Fig. 9.6/9.7 case.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from numerics.units import value_in
from twin.errors import SceneError, did_you_mean
from twin.layout import OUTPUT_NAMES
from twin.scenes.procedure import apply_procedure
from twin.scenes.profiles import compile_profile
from twin.tomlfiles import read_inheriting

LIBRARY = Path(__file__).parent / "library"


class Condition(NamedTuple):
    """One condition of a test procedure: a number in an SI unit, or one of a few named choices.

    A named tuple whose first field is the unit, so ``CONDITIONS[name][0]`` is the unit.

    Attributes
    ----------
    unit : str
        SI unit of a numeric condition; ``""`` for a choice.
    description : str
        What it states about the test (with its source).
    allowed : str
        The allowed values, as an error message prints them.
    check : callable, optional
        Range check of a numeric condition.
    choices : tuple of str
        The values of a choice condition (empty for a number).
    default : optional
        Value of a condition a scene does not state; ``None``: the scene must state it.
    """

    unit: str
    description: str
    allowed: str
    check: Callable[[float], bool] | None = None
    choices: tuple[str, ...] = ()
    default: Any = None

    @property
    def numeric(self) -> bool:
        return not self.choices

    def problem(self, name: str, value) -> str | None:
        """What is wrong with ``value`` (naming the field and what is allowed), or None."""
        if self.choices:
            return (None if value in self.choices
                    else f"conditions.{name}: {value!r} is not one of {', '.join(self.choices)}")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            return f"conditions.{name}: must be a finite number [{self.unit}], got {value!r}"
        return (None if self.check(value)
                else f"conditions.{name}: {value:g} {self.unit} is out of range; allowed: {self.allowed}")


#: Zero procedures: how the bench is initialised at t = 0 and where the encoders are zeroed (docs/model.md).
#: "preloaded" is the default of a scene that does not state it: a real bench is zeroed after assembly.
ZERO_PROCEDURES = {
    "thesis": "Sec. 9.3.2: every element unloaded at t = 0 (nuts centred in their backlash, disc springs "
              "compressed by the preload but not yet pushing the nuts), encoders zeroed there; the springs "
              "load the nuts during the run, so the preload condition is the spring force at assembly",
    "preloaded": "start at rest in the static equilibrium of the preloaded nuts, encoders zeroed there (what a "
                 "real bench does after assembly); the preload condition is the preload at that equilibrium",
}
#: States of the pneumatic cylinder (Sec. 9.2): what holds the master nut besides the screw.
CYLINDER_STATES = {
    "attached": "rod pinned to the master nut by its jags (Sec. 9.2), the force loop holding the force demand "
                "(0 N in a force-free test) through the piston's seal friction",
    "detached": "rod end unpinned: no force of any kind from the load system on the master nut (a force "
                "demand is then impossible)",
}

#: Where the external-force load cell's electrical noise (Table 9.5, +/-2.5 %FS) enters (docs/model.md, "Where the
#: electrical noise enters"): a model-form condition, because the thesis does not settle it.
NOISE_PATHS = {
    "feedback": "one noisy DAQ conversion per acquisition instant serves the record and the force loop (Sec. 9.2: the "
                "cRIO acquires every sensor and closes the force loop; Sec. 9.3.2: the loop acts on 'the force "
                "feedback measured by the load cell'): the noise reaches the valve and, with the cylinder attached, "
                "the master nut",
    "recorded": "the noise is in the recorded signals only (Sec. 9.3.1: the signals are 'digitalised before being "
                "saved ... to simulate the measurement noise'): the force loop reads the same conversion without the "
                "noise sample",
}

#: Every condition a scene states: the one table of names, units and allowed values
#: (campaigns.runner.catalog derives the campaigns' condition units from it).
CONDITIONS: dict[str, Condition] = {
    "preload": Condition("N", "preload between the nuts (its meaning depends on zero_procedure)", ">= 0",
                         lambda v: v >= 0),
    "preload_configuration": Condition("", "O separates the nuts, X draws them together (Eq. 9.8)", "O, X",
                                       choices=("O", "X")),
    "backlash": Condition("m", "total axial play of each nut", "0 ... 1e-3 m", lambda v: 0 <= v <= 1e-3),
    "room_temperature": Condition("K", "room and air temperature", "200 ... 400 K", lambda v: 200 < v < 400),
    "supply_pressure": Condition("Pa", "pneumatic supply pressure (absolute)", "> 0 (absolute)", lambda v: v > 0),
    "zero_procedure": Condition("", "how the bench is initialised and where the encoders are zeroed",
                                ", ".join(ZERO_PROCEDURES), choices=tuple(ZERO_PROCEDURES), default="preloaded"),
    "cylinder": Condition("", "state of the pneumatic cylinder", ", ".join(CYLINDER_STATES),
                          choices=tuple(CYLINDER_STATES), default="attached"),
    "noise_path": Condition("", "where the load cell's electrical noise enters: the force loop's feedback and the "
                                "record, or the record only", ", ".join(NOISE_PATHS), choices=tuple(NOISE_PATHS),
                            default="feedback"),
}
#: Prefix that names a scene condition among parameter names (``scene.backlash`` beside ``motor.inertia``) in
#: ``--set`` overrides and campaign uncertainty targets; :func:`split_targets` is the one parser of such names.
SCENE_PREFIX = "scene."


def split_targets(values: Mapping[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """Split ``{"scene.<condition>": v, "<group>.<parameter>": v, ...}`` into (conditions, parameter values).

    Conditions lose the prefix (they are :data:`CONDITIONS` keys); every other name is a parameter name.
    """
    conditions = {name.removeprefix(SCENE_PREFIX): v for name, v in values.items() if name.startswith(SCENE_PREFIX)}
    parameters = {name: v for name, v in values.items() if not name.startswith(SCENE_PREFIX)}
    return conditions, parameters


_TOP_FIELDS = {"base", "name", "description", "duration", "conditions", "position_demand", "force_demand", "outputs"}


@dataclass(frozen=True)
class Scene:
    """A validated test procedure.

    Attributes
    ----------
    name, description : str
    duration : float
        Test length [s].
    position_demand, force_demand : list of dict
        Profile segments (see :mod:`twin.scenes.profiles`): sled position [m]
        and external force on the master nut [N, positive along +x].
    conditions : dict
        Every condition of :data:`CONDITIONS` (those with a default may be left
        out of the file): ``preload`` [N], ``preload_configuration`` ("O" separates
        the nuts, "X" draws them together), ``backlash`` [m] (total axial play of
        each nut), ``room_temperature`` [K], ``supply_pressure`` [Pa, absolute],
        ``zero_procedure`` (:data:`ZERO_PROCEDURES`, default "preloaded"),
        ``cylinder`` (:data:`CYLINDER_STATES`, default "attached") and
        ``noise_path`` (:data:`NOISE_PATHS`, default "feedback").
    outputs : tuple of str
        Signals and features the test must produce (:data:`twin.layout.OUTPUT_NAMES`);
        empty means all of them. The automatic fidelity (:mod:`twin.fidelity`) models
        only what these need.
    """

    name: str
    description: str
    duration: float
    position_demand: list = field(default_factory=list)
    force_demand: list = field(default_factory=list)
    conditions: Mapping[str, Any] = field(default_factory=dict)
    outputs: tuple[str, ...] = ()

    def __post_init__(self):
        defaults = {name: c.default for name, c in CONDITIONS.items()
                    if c.default is not None and name not in self.conditions}
        object.__setattr__(self, "conditions", {**self.conditions, **defaults})
        problems = validate_scene(self)
        if problems:
            raise SceneError(problems)

    def condition(self, name: str):
        return self.conditions[name]

    def with_conditions(self, overrides: Mapping[str, Any]) -> Scene:
        """Copy with some conditions replaced (validated; all problems reported at once). A numeric condition may be
        given as a text with its unit (``{"backlash": "20 um"}``), converted to the condition's SI unit
        (:func:`numerics.units.value_in`)."""
        converted, problems = {}, []
        for name, value in overrides.items():
            condition = CONDITIONS.get(name)
            if isinstance(value, str) and condition is not None and condition.numeric:
                try:
                    value = value_in(value, condition.unit)
                except ValueError as exc:
                    problems.append(f"conditions.{name}: {exc}")
                    continue
            converted[name] = value
        try:
            scene = replace(self, conditions={**self.conditions, **converted})
        except SceneError as exc:
            problems += exc.problems
        if problems:
            raise SceneError(problems)
        return scene

    def with_procedure(self, knobs: Mapping[str, Any]) -> Scene:
        """Copy with the demand profiles, duration, preload and zero procedure of a test procedure's knobs
        (:mod:`twin.scenes.procedure`); empty ``knobs``: the scene itself."""
        return apply_procedure(self, knobs)

    def with_duration(self, duration: float) -> Scene:
        return replace(self, duration=duration)

    def position_table(self) -> np.ndarray:
        return compile_profile(self.position_demand, "position_demand")[0]

    def force_table(self) -> np.ndarray:
        return compile_profile(self.force_demand, "force_demand")[0]

    @property
    def has_force_demand(self) -> bool:
        table = self.force_table()
        return bool(np.any(table[:, 3:5] != 0.0) or np.any(table[:, 5] != 0.0))

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "description": self.description,
            "duration": self.duration,
            "conditions": dict(self.conditions),
            "position_demand": list(self.position_demand),
            "force_demand": list(self.force_demand),
            "outputs": list(self.outputs),
        }


def validate_scene(scene: Scene) -> list[str]:
    """Every problem of a scene, each naming its field and what is allowed."""
    problems = []
    if not (isinstance(scene.duration, (int, float)) and math.isfinite(scene.duration) and scene.duration > 0):
        problems.append(f"duration: must be a positive number of seconds, got {scene.duration!r}")
    for name, value in scene.conditions.items():
        if name not in CONDITIONS:
            suggestion = did_you_mean(name, CONDITIONS)
            problems.append(f"conditions.{name}: unknown condition; {suggestion + ' ' if suggestion else ''}"
                            f"allowed: {', '.join(CONDITIONS)}")
        elif (problem := CONDITIONS[name].problem(name, value)) is not None:
            problems.append(problem)
    problems += [f"conditions.{c}: missing" for c in CONDITIONS if c not in scene.conditions]
    if not isinstance(scene.outputs, tuple) or not all(isinstance(o, str) for o in scene.outputs):
        problems.append(f"outputs: must be a list of output names, got {scene.outputs!r}")
    else:
        problems += [f"outputs: {o!r} is not a signal or feature of the bench; allowed: {', '.join(OUTPUT_NAMES)}"
                     for o in scene.outputs if o not in OUTPUT_NAMES]
    for name in ("position_demand", "force_demand"):
        segments = getattr(scene, name)
        if not isinstance(segments, list):
            problems.append(f"{name}: must be a list of segments")
            continue
        problems += compile_profile(segments, name)[1]
    if scene.conditions.get("cylinder") == "detached" and isinstance(scene.force_demand, list) and scene.force_demand \
            and not problems and scene.has_force_demand:
        problems.append("conditions.cylinder: 'detached' cannot apply the scene's force demand; "
                        "use 'attached' or remove force_demand")
    return problems


def scene_from_dict(data: Mapping[str, Any], default_name: str = "scene") -> Scene:
    """Build a scene from a parsed TOML mapping (all problems reported at once)."""
    problems = [f"{k}: unknown field; allowed: {', '.join(sorted(_TOP_FIELDS))}" for k in data if k not in _TOP_FIELDS]
    if "duration" not in data:
        problems.append("duration: missing")
    if problems:
        raise SceneError(problems)
    return Scene(
        name=str(data.get("name", default_name)),
        description=str(data.get("description", "")),
        duration=data["duration"],
        position_demand=list(data.get("position_demand", [])),
        force_demand=list(data.get("force_demand", [])),
        conditions=dict(data.get("conditions", {})),
        outputs=tuple(data.get("outputs", [])) if isinstance(data.get("outputs", []), list) else data["outputs"],
    )


def list_scenes() -> list[str]:
    """Names of the scenes shipped with BenchTwin."""
    return sorted(p.stem for p in LIBRARY.glob("*.toml"))


def load_scene(name_or_path: str | Path | Scene) -> Scene:
    """Load a built-in scene by name, or a scene TOML file.

    Raises
    ------
    SceneError
        Unknown scene, malformed TOML, or any invalid field (all listed).
    """
    if isinstance(name_or_path, Scene):
        return name_or_path
    path = Path(name_or_path)
    if not path.is_file():
        path = LIBRARY / f"{name_or_path}.toml"
        if not path.is_file():
            raise SceneError(
                [f"scene: '{name_or_path}' is neither a file nor a built-in scene ({', '.join(list_scenes())})"])
    return scene_from_dict(_read_with_base(path), default_name=path.stem)


def _read_scene_file(path: Path) -> dict:
    try:
        return tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise SceneError([f"{path.name}: not valid TOML ({exc})"]) from None


def _locate_base(path: Path, base, seen: tuple[Path, ...]) -> Path:
    """A ``base = "other"`` field names a scene file beside this one, or a built-in scene."""
    base_path = path.parent / f"{base}.toml"
    if not base_path.is_file():
        base_path = LIBRARY / f"{base}.toml"
    if not base_path.is_file() or base_path.resolve() in seen:
        raise SceneError(
            [f"{path.name}.base: '{base}' is not a scene file or built-in scene (or the chain is circular)"])
    return base_path


def _read_with_base(path: Path) -> dict:
    """Parse a scene file; a ``base = "other"`` field inherits that scene's fields (conditions are merged key by
    key, :mod:`twin.tomlfiles`), so data sets do not copy the demand profiles."""
    return read_inheriting(path, "base", _read_scene_file, _locate_base)
