"""Test procedures as knobs: the few numbers a test-rig engineer turns, compiled into a scene.

A procedure replaces a scene's demand profiles by one parametrised test (issue 29, "a test-procedure designer"):
a dwell at rest (the external force, if any, applied in its first ``FORCE_RISE_TIME``), then ``cycles`` cycles of the
thesis's raised-cosine sinusoid (Fig. 9.6a: ``0 -> 2 amplitude -> 0`` at ``frequency``, zero initial speed), then
``SETTLE_TIME`` at rest. The preload setting and the zero procedure are scene conditions the procedure sets; the
fault (backlash, preload loss) stays a condition of the data set, applied after the procedure.

Each knob is declared once in :data:`KNOBS` (unit, what it sets, the bench's limit and its source); the campaign
spec (``[datasets.procedure]``) and the procedure search (:mod:`campaigns.workflows.procedure_search`) validate against
it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

from twin.errors import SceneError, did_you_mean
from twin.features import MOTION_SPEED_THRESHOLD

#: Table 9.3: the bench's linear stroke [m], nominal linear speed [m/s] and maximum load [N].
STROKE = 0.300
NOMINAL_SPEED = 0.070
MAXIMUM_LOAD = 12_000.0
#: Rise of the external force at the start of the dwell [s]: the nominal scene's 50 ms smooth step (Fig. 9.7a).
FORCE_RISE_TIME = 0.05
#: Rest after the motion [s]: the nominal scene's hold after its sinusoid (Fig. 9.6a, 4.5-5.0 s), so the last
#: reversal's transient settles inside the record.
SETTLE_TIME = 0.5
#: Smallest peak sled speed of a procedure [m/s]: five times the features' motion threshold (1 mm/s), so most of each
#: cycle counts as motion for the hysteresis.
MINIMUM_PEAK_SPEED = 5 * MOTION_SPEED_THRESHOLD


@dataclass(frozen=True)
class Knob:
    """One knob of a test procedure.

    Attributes
    ----------
    unit : str
        SI unit (``"1"`` for a count, ``""`` for a choice).
    description : str
        What it sets in the test.
    low, high : float
        The bench's range (inclusive), for a number or a count.
    limit : str
        Why the range is what it is (its source).
    default : number or str
        The thesis's value (Fig. 9.6/9.7 nominal scene, Table 9.4 data set 2).
    choices : tuple of str
        The values of a choice knob (empty for a number).
    integer : bool
        A count (whole numbers only).
    """

    unit: str
    description: str
    low: float = -math.inf
    high: float = math.inf
    limit: str = ""
    default: Any = None
    choices: tuple[str, ...] = ()
    integer: bool = False

    def problem(self, name: str, value) -> str | None:
        """What is wrong with ``value`` for this knob (naming it and what is allowed), or None."""
        if self.choices:
            return None if value in self.choices else f"{name}: {value!r} is not one of {', '.join(self.choices)}"
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            return f"{name}: must be a finite number [{self.unit}], got {value!r}"
        if self.integer and value != int(value):
            return f"{name}: must be a whole number, got {value!r}"
        if not self.low <= value <= self.high:
            return f"{name}: {value:g} {self.unit} is outside the bench's range {self.low:g} ... {self.high:g} " \
                   f"{self.unit} ({self.limit})"
        return None


#: Every knob of a procedure, in display order.
KNOBS: dict[str, Knob] = {
    "preload": Knob("N", "preload setting between the nuts (a scene condition; its meaning follows zero_procedure)",
                    0.0, MAXIMUM_LOAD, "Table 9.3: maximum load 12 kN", default=0.0),
    "external_force": Knob("N", "axial force the cylinder holds on the master nut through the test (+ along +x)",
                           -MAXIMUM_LOAD, MAXIMUM_LOAD, "Table 9.3: maximum load 12 kN", default=0.0),
    "amplitude": Knob("m", "half the stroke of each motion cycle (the sled goes 0 -> 2 amplitude -> 0)",
                      0.1e-3, STROKE / 2, "Table 9.3: linear stroke 300 mm", default=5.0e-3),
    "frequency": Knob("Hz", "motion cycles per second (peak sled speed 2 pi frequency amplitude)",
                      0.05, 10.0, "peak speed within Table 9.3's 70 mm/s nominal speed is checked with the amplitude",
                      default=1.0),
    "cycles": Knob("1", "motion cycles (two reversals each)", 1, 50, "at least one cycle so the screw moves both "
                   "ways; 50 cycles is a 50 s test at 1 Hz", default=4, integer=True),
    "dwell": Knob("s", "rest before the motion (the external force rises in its first 50 ms)", 0.1, 10.0,
                  "at least twice the force's 50 ms rise", default=0.5),
    "zero_procedure": Knob("", "how the bench is initialised and where the encoders are zeroed "
                           "(twin.scenes.ZERO_PROCEDURES)", choices=("thesis", "preloaded"), default="thesis"),
}


def procedure_problems(knobs: Mapping[str, Any]) -> list[str]:
    """Every problem of a procedure's knob values (unknown knobs with a did-you-mean, values outside the bench's
    ranges, a motion faster than the bench or too slow for the features), each naming its knob (the caller
    prefixes where the knobs were given)."""
    problems = []
    for name, value in knobs.items():
        if name not in KNOBS:
            hint = did_you_mean(name, KNOBS)
            problems.append(f"{name}: unknown knob; {hint + ' ' if hint else ''}allowed: {', '.join(KNOBS)}")
        elif (problem := KNOBS[name].problem(name, value)) is not None:
            problems.append(problem)
    if problems:
        return problems
    full = with_defaults(knobs)
    speed = peak_speed(full)
    if speed > NOMINAL_SPEED * (1 + 1e-9):
        problems.append(f"frequency, amplitude: peak sled speed 2 pi frequency amplitude = {speed * 1e3:.3g} mm/s "
                        f"is above the bench's {NOMINAL_SPEED * 1e3:g} mm/s (Table 9.3); lower frequency or amplitude")
    elif speed < MINIMUM_PEAK_SPEED:
        problems.append(f"frequency, amplitude: peak sled speed 2 pi frequency amplitude = {speed * 1e3:.3g} mm/s "
                        f"is below {MINIMUM_PEAK_SPEED * 1e3:g} mm/s: the features would see hardly any motion "
                        "(twin.features.MOTION_SPEED_THRESHOLD); raise frequency or amplitude")
    return problems


def with_defaults(knobs: Mapping[str, Any]) -> dict[str, Any]:
    """Every knob: the given values, the thesis's default for the others."""
    return {name: knobs.get(name, knob.default) for name, knob in KNOBS.items()}


def peak_speed(knobs: Mapping[str, Any]) -> float:
    """Peak sled speed of the motion [m/s]: the raised cosine's ``2 pi f A``."""
    return 2.0 * math.pi * float(knobs["frequency"]) * float(knobs["amplitude"])


def procedure_duration(knobs: Mapping[str, Any]) -> float:
    """Length of the test [s]: dwell, the motion cycles, the settling rest."""
    full = with_defaults(knobs)
    return float(full["dwell"]) + int(full["cycles"]) / float(full["frequency"]) + SETTLE_TIME


def procedure_profiles(knobs: Mapping[str, Any]) -> dict[str, Any]:
    """The scene fields a procedure sets: ``duration``, ``position_demand``, ``force_demand`` and its conditions."""
    full = with_defaults(knobs)
    dwell, cycles, frequency = float(full["dwell"]), int(full["cycles"]), float(full["frequency"])
    motion_end = dwell + cycles / frequency
    position = [{"kind": "hold", "end": dwell},
                {"kind": "sinusoid", "end": motion_end, "amplitude": float(full["amplitude"]),
                 "frequency": frequency, "phase": -math.pi / 2}]
    force = float(full["external_force"])
    force_demand = [] if force == 0.0 else [{"kind": "smooth_step", "end": FORCE_RISE_TIME, "to": force}]
    return {"duration": procedure_duration(full), "position_demand": position, "force_demand": force_demand,
            "conditions": {"preload": float(full["preload"]), "zero_procedure": full["zero_procedure"]}}


def apply_procedure(scene, knobs: Mapping[str, Any]):
    """``scene`` with its demand profiles, duration, preload and zero procedure replaced by the procedure's
    (its outputs, its other conditions and its name kept). An empty ``knobs`` returns the scene itself."""
    if not knobs:
        return scene
    problems = procedure_problems(knobs)
    if problems:
        raise SceneError([f"procedure.{problem}" for problem in problems])
    fields = procedure_profiles(knobs)
    return replace(scene, duration=fields["duration"], position_demand=fields["position_demand"],
                   force_demand=fields["force_demand"], conditions={**scene.conditions, **fields["conditions"]})
