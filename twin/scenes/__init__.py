"""Scenes: test procedures of the bench, as data (TOML).

A scene is what an engineer would write on a test sheet: how long the test
lasts, the sled position demand, the external force demand, and the conditions
(preload and its configuration, ball-screw axial backlash, room temperature,
supply pressure). The thesis's data sets of Table 9.4 are the scenes
``ds1`` ... ``ds5``; ``ds6``/``ds7`` repeat ``ds2`` with 5 um / 40 um backlash;
``nominal`` is the Fig. 9.6/9.7 case.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from twin.engine.layout import OUTPUT_NAMES
from twin.errors import SceneError
from twin.scenes.profiles import compile_profile

LIBRARY = Path(__file__).parent / "library"

# Condition name -> (unit, check, allowed-range text).
CONDITIONS: dict[str, tuple[str, Any, str]] = {
    "preload": ("N", lambda v: v >= 0, ">= 0"),
    "backlash": ("m", lambda v: 0 <= v <= 1e-3, "0 ... 1e-3 m"),
    "room_temperature": ("K", lambda v: 200 < v < 400, "200 ... 400 K"),
    "supply_pressure": ("Pa", lambda v: v > 0, "> 0 (absolute)"),
}
PRELOAD_CONFIGURATIONS = ("O", "X")
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
        ``preload`` [N], ``preload_configuration`` ("O" separates the nuts,
        "X" draws them together), ``backlash`` [m] (total axial play of each
        nut), ``room_temperature`` [K], ``supply_pressure`` [Pa, absolute].
    outputs : tuple of str
        Signals and features the test must produce (:data:`twin.engine.layout.OUTPUT_NAMES`);
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
        problems = validate_scene(self)
        if problems:
            raise SceneError(problems)

    def condition(self, name: str):
        return self.conditions[name]

    def with_conditions(self, overrides: Mapping[str, Any]) -> "Scene":
        """Copy with some conditions replaced (validated; all problems reported at once)."""
        return replace(self, conditions={**self.conditions, **overrides})

    def with_duration(self, duration: float) -> "Scene":
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
        if name == "preload_configuration":
            if value not in PRELOAD_CONFIGURATIONS:
                problems.append(f"conditions.preload_configuration: {value!r} is not one of {PRELOAD_CONFIGURATIONS}")
            continue
        if name not in CONDITIONS:
            problems.append(f"conditions.{name}: unknown condition; allowed: {', '.join([*CONDITIONS, 'preload_configuration'])}")
            continue
        unit, ok, allowed = CONDITIONS[name]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            problems.append(f"conditions.{name}: must be a finite number [{unit}], got {value!r}")
        elif not ok(value):
            problems.append(f"conditions.{name}: {value:g} {unit} is out of range; allowed: {allowed}")
    missing = [c for c in [*CONDITIONS, "preload_configuration"] if c not in scene.conditions]
    problems += [f"conditions.{c}: missing" for c in missing]
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
            raise SceneError([f"scene: '{name_or_path}' is neither a file nor a built-in scene ({', '.join(list_scenes())})"])
    return scene_from_dict(_read_with_base(path, seen=()), default_name=path.stem)


def _read_with_base(path: Path, seen: tuple[Path, ...]) -> dict:
    """Parse a scene file; a ``base = "other"`` field inherits that scene's fields
    (conditions are merged key by key), so data sets do not copy the demand profiles."""
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise SceneError([f"{path.name}: not valid TOML ({exc})"]) from None
    base = data.pop("base", None)
    if base is None:
        return data
    base_path = path.parent / f"{base}.toml"
    if not base_path.is_file():
        base_path = LIBRARY / f"{base}.toml"
    if not base_path.is_file() or base_path.resolve() in seen:
        raise SceneError([f"{path.name}.base: '{base}' is not a scene file or built-in scene (or the chain is circular)"])
    merged = _read_with_base(base_path, seen + (path.resolve(),))
    conditions = {**merged.get("conditions", {}), **data.pop("conditions", {})}
    return {**merged, **data, "conditions": conditions}
