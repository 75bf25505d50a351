"""Automatic fidelity selection: the rules of ``rules.toml`` applied to a scene, each decision explained.

A scene is a test procedure: its demands, duration and conditions, and the
outputs it must produce. :func:`resolve_fidelity` turns a requested fidelity
(``"auto"``, ``"full"`` or a per-subsystem mapping) into a :class:`Fidelity`:
one level per subsystem of :data:`twin.levels.SUBSYSTEMS` and the
reason for it. The rules themselves are data (``rules.toml``); this module
only evaluates their conditions, and every condition reports its numbers.

The gate: on a scene whose stored speedup of the automatic levels (``speed.toml``, measured by
``benchmarks/fidelity_speed.py``) is below the rules' ``min_lane_speedup``, ``"auto"`` keeps the full level
of every subsystem the rules would simplify (docs/fidelity.md, "Fidelity that pays").
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path

import numpy as np

from twin.components import reducer
from twin.engine.model import contact_constants, contact_position_for_force
from twin.errors import OptionError
from twin.fidelity.requests import requested_levels
from twin.layout import N_CONSTANTS, N_STATES, OUTPUT_NAMES
from twin.levels import SUBSYSTEMS, level_code
from twin.parameters import ParameterSet
from twin.physics.motor import equivalent_resistance, equivalent_voltage_limit
from twin.scenes import Scene
from twin.scenes.profiles import profile_values

RULES_FILE = Path(__file__).with_name("rules.toml")
#: The stored lane-engine speedup of the automatic levels per built-in scene (``benchmarks/fidelity_speed.py --write``).
SPEED_FILE = Path(__file__).with_name("speed.toml")
#: Fields of ``speed.toml``'s ``[measurement]``: what the stored ratios were measured on.
MEASUREMENT_FIELDS = ("machine", "date", "load", "lanes", "repeats")
PROFILE_GRID = 1.0e-3  # s: demand profiles are sampled at the acquisition period to find their peak speed
RULE_KEYS = {"subsystem", "level", "because"}
SETTINGS = ("contact_load_allowance", "hot_winding_temperature_rise",  # the [settings] the conditions read
            "min_lane_speedup")  # and the gate


@dataclass(frozen=True)
class Fidelity:
    """A resolved fidelity configuration: a level and a reason for every subsystem.

    Attributes
    ----------
    levels : dict
        Subsystem -> level name.
    reasons : dict
        Subsystem -> why this level ("requested", or the rule and its numbers).
    peak_contact_load : float
        The scene's peak contact load on a nut [N], used by the ``linear`` contact level.
    """

    levels: Mapping[str, str]
    reasons: Mapping[str, str]
    peak_contact_load: float

    def level(self, subsystem: str) -> str:
        return self.levels[subsystem]

    @property
    def removed_states(self) -> tuple:
        return tuple(sorted({s for name, level in self.levels.items()
                             for s in SUBSYSTEMS[name].level(level).removes_states}))

    @property
    def active_states(self) -> np.ndarray:
        """Indices (layout :class:`twin.layout.S`) of the integrated states."""
        removed = set(self.removed_states)
        return np.array([j for j in range(N_STATES) if j not in removed], dtype=np.int64)

    @property
    def removed_signals(self) -> tuple[str, ...]:
        return tuple(s for name, level in self.levels.items() for s in SUBSYSTEMS[name].level(level).removes_signals)

    def summary(self) -> str:
        """One line, ``subsystem=level, ...`` (stored in result attributes)."""
        return ", ".join(f"{name}={level}" for name, level in self.levels.items())

    def explain(self) -> str:
        """One line per subsystem: the level, what it models and why it was chosen."""
        width = max(map(len, self.levels))
        lines = [f"{name:<{width}}  {level:<15} {self.reasons[name]}" for name, level in self.levels.items()]
        lines.append(f"integrated states: {self.active_states.size} of {N_STATES}")
        return "\n".join(lines)


def load_rules(path: Path = RULES_FILE) -> tuple[dict, list[dict]]:
    """Parse and check a rules file: ``(settings, rules)``, shared between calls (do not modify them).

    Parsed once per process and file version (path, modification time and size), since every run
    resolves its fidelity against the same file.

    Raises
    ------
    OptionError
        A missing setting, or an unknown subsystem, level or condition in a rule (all listed).
    """
    stat = Path(path).stat()
    return _parsed_rules(Path(path), stat.st_mtime_ns, stat.st_size)


@lru_cache(maxsize=8)
def _parsed_rules(path: Path, mtime_ns: int, size: int) -> tuple[dict, list[dict]]:
    """:func:`load_rules` of one version of the file (the stat fields are the cache key)."""
    data = tomllib.loads(path.read_text())
    rules = data.get("rules", [])
    settings = data.get("settings", {})
    problems = [f"{path.name}: settings.{key}: missing or not a number" for key in SETTINGS
                if isinstance(settings.get(key), bool) or not isinstance(settings.get(key), (int, float))]
    for k, rule in enumerate(rules):
        where = f"{path.name}: rules[{k}]"
        subsystem = SUBSYSTEMS.get(rule.get("subsystem"))
        if subsystem is None:
            problems.append(f"{where}.subsystem: {rule.get('subsystem')!r} is not one of {', '.join(SUBSYSTEMS)}")
        elif rule.get("level") not in subsystem.level_names:
            problems.append(f"{where}.level: {rule.get('level')!r} is not one of {', '.join(subsystem.level_names)}")
        unknown = set(rule) - RULE_KEYS - set(CONDITIONS)
        if unknown:
            problems.append(
                f"{where}: unknown condition(s) {', '.join(sorted(unknown))}; allowed: {', '.join(CONDITIONS)}")
    if problems:
        raise OptionError(problems)
    return settings, rules


def load_speedups(path: Path = SPEED_FILE) -> dict[str, float]:
    """Parse and check a speed file: ``{scene name: measured full / auto speedup}``, shared between calls.

    Parsed once per process and file version, as :func:`load_rules`.

    Raises
    ------
    OptionError
        A missing field of ``[measurement]`` or of a scene's entry, or a speedup that is not a positive number
        (all listed, each naming its field); no such file.
    """
    try:
        stat = Path(path).stat()
    except OSError as exc:
        raise OptionError([f"speed_file: cannot read {path} ({exc.strerror})"]) from None
    return _parsed_speedups(Path(path), stat.st_mtime_ns, stat.st_size)


@lru_cache(maxsize=8)
def _parsed_speedups(path: Path, mtime_ns: int, size: int) -> dict[str, float]:
    """:func:`load_speedups` of one version of the file (the stat fields are the cache key)."""
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise OptionError([f"{path.name}: not valid TOML ({exc})"]) from None
    measurement, scenes = data.get("measurement"), data.get("scenes")
    problems = list(_speed_file_problems(path.name, measurement, scenes))
    if problems:
        raise OptionError(problems)
    return {name: float(entry["speedup"]) for name, entry in scenes.items()}


def _speed_file_problems(name: str, measurement, scenes) -> Iterator[str]:
    if not isinstance(measurement, dict):
        yield f"{name}: measurement: missing table ({', '.join(MEASUREMENT_FIELDS)} of the stored ratios)"
    else:
        yield from (f"{name}: measurement.{key}: missing" for key in MEASUREMENT_FIELDS if key not in measurement)
    if not isinstance(scenes, dict):
        yield f"{name}: scenes: missing table ([scenes.<scene>] with speedup = full / auto)"
        return
    for scene, entry in scenes.items():
        value = entry.get("speedup") if isinstance(entry, dict) else None
        if value is None:
            yield f"{name}: scenes.{scene}.speedup: missing"
        elif isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            yield f"{name}: scenes.{scene}.speedup: must be a positive number (full / auto), got {value!r}"


def _shown(path: Path) -> str:
    """A file as a reason cites it: relative to the package's parent when it lies inside (twin/fidelity/...)."""
    try:
        return Path(path).resolve().relative_to(Path(__file__).resolve().parents[2]).as_posix()
    except ValueError:
        return str(path)


def _gate(scene: Scene, settings: Mapping[str, float], speed_file: Path | None) -> tuple[bool, str]:
    """Whether the automatic levels pay on ``scene`` (by its stored speedup), and the words that say so."""
    if speed_file is None:
        return True, ""
    least = settings["min_lane_speedup"]
    speedup = load_speedups(speed_file).get(scene.name)
    where = _shown(speed_file)
    if speedup is None:
        return True, f"no speed measurement stored for scene '{scene.name}' ({where}): the rules apply"
    if speedup < least:
        return False, (f"automatic levels buy {speedup:.2f}x on {scene.name} ({where}), below {least:.2f}x: "
                       "full model")
    return True, f"automatic levels buy {speedup:.2f}x on {scene.name} ({where}), at least {least:.2f}x"


class SceneNeeds:
    """What a scene asks of the model: its demands, duration, conditions and requested outputs."""

    def __init__(self, scene: Scene, params: ParameterSet, outputs: frozenset[str], curvature: str,
                 settings: Mapping[str, float]):
        self.scene = scene
        self.params = params
        self.outputs = outputs
        self.curvature = curvature
        self.settings = settings

    @cached_property
    def peak_force_demand(self) -> float:
        return float(np.max(np.abs(_sampled(self.scene, self.scene.force_table()))))

    @cached_property
    def peak_contact_load(self) -> float:
        """Preload + largest |force demand| + the rules' allowance [N]."""
        return self.scene.condition("preload") + self.peak_force_demand + self.settings["contact_load_allowance"]

    @cached_property
    def peak_motor_speed(self) -> float:
        """Largest motor speed the position demand asks for [rad/s]."""
        speed = peak_demand_speed(self.scene)
        return reducer.motor_speed(speed / self.params.value("ball_screw.lead") * 2.0 * math.pi, self.params.values())

    @cached_property
    def contact(self) -> np.ndarray:
        """Contact constants of the full model, the stiffness fit included (for the deflection conditions)."""
        c = np.zeros(N_CONSTANTS)
        contact_constants(c, self.params.values(), self.curvature)
        return c


def peak_demand_speed(scene: Scene) -> float:
    """Largest sled speed [m/s] the scene's position demand asks for, on the :data:`PROFILE_GRID`."""
    position = _sampled(scene, scene.position_table())
    return float(np.max(np.abs(np.diff(position)))) / PROFILE_GRID if position.size > 1 else 0.0


def _sampled(scene: Scene, table: np.ndarray) -> np.ndarray:
    return profile_values(table, np.arange(0.0, scene.duration + PROFILE_GRID, PROFILE_GRID))


def _force_demand(needs: SceneNeeds, wanted: bool, decided) -> tuple[bool, str]:
    has = needs.scene.has_force_demand
    return has == wanted, f"force demand {'present' if has else 'none'}"


def _outputs_exclude(needs: SceneNeeds, names: list[str], decided) -> tuple[bool, str]:
    clash = sorted(needs.outputs & set(names))
    return not clash, f"requested: {', '.join(clash)}" if clash else "none of its outputs requested"


def _decided(needs: SceneNeeds, wanted: Mapping[str, str], decided) -> tuple[bool, str]:
    ok = all(decided.get(k) == v for k, v in wanted.items())
    return ok, ", ".join(f"{k}={decided.get(k)}" for k in wanted)


def _not_decided(needs: SceneNeeds, unwanted: Mapping[str, str], decided) -> tuple[bool, str]:
    ok = all(decided.get(k) != v for k, v in unwanted.items())
    return ok, ", ".join(f"{k}={decided.get(k)}" for k in unwanted)


def _voltage_fraction(needs: SceneNeeds, limit: float, decided) -> tuple[bool, str]:
    """Peak voltage of the power-consistent equivalent circuit (:mod:`twin.physics.motor`: back-EMF ``k_t w`` and
    ``R_eq`` hot at the maximum current) over the largest voltage the inverter applies to it."""
    p = needs.params
    rise = needs.settings["hot_winding_temperature_rise"]
    hot = equivalent_resistance(p.value("motor.winding_resistance_20C")) * (
        1.0 + p.value("motor.resistance_temperature_coefficient") * rise)
    voltage = p.value("motor.torque_constant") * needs.peak_motor_speed + hot * p.value("motor.max_current")
    fraction = voltage / equivalent_voltage_limit(p.value("drive.dc_bus_voltage"),
                                                  p.value("drive.phase_voltage_amplitude_limit"))
    return fraction <= limit, f"peak voltage demand {fraction:.2f} of the inverter's limit (limit {limit:g})"


def _duration_over_tau(needs: SceneNeeds, limit: float, decided) -> tuple[bool, str]:
    ratio = needs.scene.duration / needs.params.value("motor.thermal_time_constant")
    return ratio <= limit, f"duration / tau_w = {ratio:.3f} (limit {limit:g})"


def _nut_roll_deflection(needs: SceneNeeds, limit: float, decided) -> tuple[bool, str]:
    arm = needs.params.value("ball_screw.lead") / (2.0 * math.pi)
    deflection = arm**2 * needs.peak_contact_load / needs.params.value("sled.guide_roll_stiffness")
    return deflection <= limit, (f"roll share of the nut deflection {deflection * 1e9:.2f} nm at "
                                 f"{needs.peak_contact_load:.0f} N (limit {limit * 1e9:g} nm)")


def _angle_deflection_error(needs: SceneNeeds, limit: float, decided) -> tuple[bool, str]:
    deflections = [contact_position_for_force(needs.contact, level_code("contact", model), needs.peak_contact_load)
                   for model in ("variable_angle", "constant_angle")]
    error = abs(deflections[0] - deflections[1])
    return error <= limit, (f"variable vs constant angle: {error * 1e9:.2f} nm of {deflections[0] * 1e6:.2f} um "
                            f"deflection at {needs.peak_contact_load:.0f} N (limit {limit * 1e9:g} nm)")


def _twist_deflection(needs: SceneNeeds, limit: float, decided) -> tuple[bool, str]:
    """Shaft twist's share of the nut-to-screw difference under the net axial load (force demand + allowance)
    at the longest shaft (sled at the end of its stroke): ``(p/2pi)^2 F l / (G J_p)``."""
    value = needs.params.value
    arm = value("ball_screw.lead") / (2.0 * math.pi)
    length = value("ball_screw.bearing_to_nut_distance") + value("sled.stroke_limit")
    load = needs.peak_force_demand + needs.settings["contact_load_allowance"]
    torsional = value("ball_screw.shear_modulus") * math.pi * value("ball_screw.screw_root_diameter") ** 4 / 32.0
    deflection = arm**2 * load * length / torsional
    return deflection <= limit, (f"twist share of the nut-to-screw difference {deflection * 1e9:.1f} nm at "
                                 f"{load:.0f} N net axial load, {length * 1e3:.0f} mm of shaft "
                                 f"(limit {limit * 1e9:g} nm)")


def _min_preload(needs: SceneNeeds, limit: float, decided) -> tuple[bool, str]:
    preload = needs.scene.condition("preload")
    return preload >= limit, f"preload {preload:.0f} N (at least {limit:g} N)"


CONDITIONS = {
    "force_demand": _force_demand,
    "min_preload": _min_preload,
    "outputs_exclude": _outputs_exclude,
    "decided": _decided,
    "not_decided": _not_decided,
    "max_voltage_fraction": _voltage_fraction,
    "max_duration_over_thermal_tau": _duration_over_tau,
    "max_nut_roll_deflection": _nut_roll_deflection,
    "max_angle_deflection_error": _angle_deflection_error,
    "max_twist_deflection": _twist_deflection,
}


def scene_levels(scene: Scene, requested: Mapping[str, str], fidelity,
                 problems: list[str]) -> dict[str, tuple[str, str]]:
    """Levels the scene's conditions fix, whatever the request: ``{subsystem: (level, reason)}``.

    An attached cylinder (``conditions.cylinder``) is part of the bench and fixes nothing: the request
    and the rules decide how it is modelled. A detached cylinder takes the load system out of the bench,
    so the pneumatics are ``"absent"`` even under ``"full"``; asking for another level explicitly is a problem.
    """
    if scene.condition("cylinder") != "detached":
        return {}
    explicit = not isinstance(fidelity, str) and fidelity.get("pneumatics", "auto") not in ("auto", "absent")
    if explicit:
        problems.append(f"fidelity.pneumatics: {requested['pneumatics']!r} needs the cylinder the scene "
                        f"'{scene.name}' detaches (conditions.cylinder = 'detached'); use 'absent' or 'auto'")
    return {"pneumatics": ("absent",
                           "the scene's cylinder is detached (conditions.cylinder): no force on the master nut")}


def resolve_fidelity(scene: Scene, params: ParameterSet, fidelity: str | Mapping[str, str] = "auto",
                     outputs=None, curvature: str = "thesis", rules_file: Path = RULES_FILE,
                     speed_file: Path | None = SPEED_FILE) -> Fidelity:
    """Resolve the requested fidelity for a scene.

    Parameters
    ----------
    scene, params
        The test and the parameter set.
    fidelity : "auto", "full" or mapping
        The request (:func:`twin.fidelity.requests.requested_levels`).
    outputs : iterable of str, optional
        Signals and features the caller needs; ``None`` takes the scene's
        ``outputs`` (every output if the scene names none).
    curvature : str
        Groove curvature formulas (:data:`twin.engine.model.CURVATURE_FORMULAS`).
    rules_file : path
        The rules (:func:`load_rules`); their ``min_lane_speedup`` sets the gate.
    speed_file : path or None
        The stored speedups (:func:`load_speedups`). A subsystem left to ``"auto"`` keeps the level its rule
        chooses only if the scene's stored speedup (found by ``scene.name``: a scene derived from a built-in
        one, with other conditions or another procedure, keeps its name) is at least ``min_lane_speedup``;
        below it, its full level, the reason saying so with the number. A scene with no stored speedup (a
        user's scene) takes the rules' levels, the reason saying that none is stored. Explicitly requested
        levels and the levels a scene's conditions fix are never changed. ``None``: the rules alone (what
        ``benchmarks/fidelity_speed.py`` measures).

    Raises
    ------
    OptionError
        Unknown subsystem, level or output; a level the scene cannot run with
        (``"absent"`` pneumatics with a force demand) or that cannot produce a
        requested output; a bad rules or speed file. All problems are listed at once.
    """
    requested, problems = requested_levels(fidelity)
    wanted = frozenset(OUTPUT_NAMES if outputs is None and not scene.outputs else
                       (scene.outputs if outputs is None else outputs))
    problems += [f"outputs: {name!r} is not a signal or feature of the bench"
                 for name in sorted(wanted - set(OUTPUT_NAMES))]
    if problems:
        raise OptionError(problems)

    settings, rules = load_rules(rules_file)
    pays, gate_reason = _gate(scene, settings, speed_file) if "auto" in requested.values() else (True, "")
    needs = SceneNeeds(scene, params, wanted, curvature, settings)
    fixed = scene_levels(scene, requested, fidelity, problems)
    levels, reasons = {}, {}
    for name, subsystem in SUBSYSTEMS.items():
        if name in fixed:
            levels[name], reasons[name] = fixed[name]
            continue
        if requested[name] != "auto":
            levels[name], reasons[name] = requested[name], "requested"
            if name == "pneumatics" and requested[name] != subsystem.full:
                reasons[name] += (" (the scene's cylinder is attached: this level drops the force loop "
                                  "and the seal friction on the master nut)")
            continue
        levels[name], reasons[name] = subsystem.full, "no rule allows a cheaper level"
        refusals = []
        for rule in (r for r in rules if r["subsystem"] == name):
            checks = [CONDITIONS[key](needs, value, levels) for key, value in rule.items() if key in CONDITIONS]
            if all(ok for ok, _ in checks):
                levels[name] = rule["level"]
                reasons[name] = f"{rule['because']} ({'; '.join(text for _, text in checks)})"
                break
            refusals.append(f"not {rule['level']}: {'; '.join(text for ok, text in checks if not ok)}")
        if refusals and levels[name] == subsystem.full:
            reasons[name] = "; ".join(refusals)
        elif levels[name] != subsystem.full and gate_reason:  # the gate, before later rules read this decision
            if pays:
                reasons[name] += f"; {gate_reason}"
            else:
                reasons[name] = f"{gate_reason} (the rules would take {levels[name]}: {reasons[name]})"
                levels[name] = subsystem.full
        if name == "pneumatics" and levels[name] == subsystem.full:
            reasons[name] += (" (the scene's cylinder is attached, conditions.cylinder: the force loop holds "
                              "the force demand through the piston's seal friction)")

    if levels["pneumatics"] == "absent" and scene.has_force_demand:
        problems.append(f"fidelity.pneumatics: 'absent' cannot apply the force demand of scene '{scene.name}'; "
                        "use 'full' or 'ideal'")
    explicit = outputs is not None or bool(scene.outputs)
    for name, level in levels.items():
        lost = sorted(wanted & set(SUBSYSTEMS[name].level(level).removes_signals))
        if lost and explicit:
            problems.append(
                f"fidelity.{name}: level {level!r} does not produce the requested output(s) {', '.join(lost)}")
    if problems:
        raise OptionError(problems)
    return Fidelity(levels, reasons, needs.peak_contact_load)
