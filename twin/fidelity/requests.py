"""A fidelity request as the levels it asks for, and the requests the studies use.

The table of subsystems and levels is :mod:`twin.levels` (one home); this module checks a request against it.
"""

from __future__ import annotations

from twin.levels import SUBSYSTEMS


def requested_levels(fidelity) -> tuple[dict[str, str], list[str]]:
    """Expand a fidelity request into ``{subsystem: level or "auto"}`` and list its problems.

    ``fidelity`` is ``"auto"``, ``"full"`` or a mapping ``{subsystem: level}`` (a level may be
    ``"auto"``) whose other subsystems take its ``"default"`` entry (``"auto"`` or ``"full"``,
    ``"auto"`` if absent). Each problem names its field. The one check of a request, shared by
    :func:`twin.fidelity.resolve_fidelity` and the campaign spec.
    """
    choices = {"default": fidelity} if isinstance(fidelity, str) else dict(fidelity)
    default = choices.pop("default", "auto")
    problems = []
    if default not in ("auto", "full"):
        problems.append(f"fidelity: {default!r} is not 'auto', 'full' or a mapping {{subsystem: level}}")
    requested = {name: (s.full if default == "full" else "auto") for name, s in SUBSYSTEMS.items()}
    for name, level in choices.items():
        if name not in SUBSYSTEMS:
            problems.append(f"fidelity.{name}: unknown subsystem {name!r}; allowed: default, {', '.join(SUBSYSTEMS)}")
        elif level != "auto" and level not in SUBSYSTEMS[name].level_names:
            problems.append(f"fidelity.{name}: level {level!r} is not one of auto, "
                            f"{', '.join(SUBSYSTEMS[name].level_names)}")
        else:
            requested[name] = level
    return requested, problems


#: Instruments and output converters ideal: with ``"default": "full"`` this is the bench's full
#: plant seen through perfect sensors, the setting of the solver studies (app.studies).
IDEAL_INSTRUMENTS = {"encoders": "ideal", "analog_sensors": "ideal", "torque_meter_refresh": "ideal",
                     "output_converters": "ideal"}


def full_plant(pneumatics: str = "full", **instruments: str) -> dict[str, str]:
    """Request for the full plant (every stiff mode present) with the given load system, seen through
    ideal instruments and converters unless ``instruments`` sets some: the setting of the solver
    studies and the physics tests."""
    return {"default": "full", **IDEAL_INSTRUMENTS, "pneumatics": pneumatics, **instruments}
