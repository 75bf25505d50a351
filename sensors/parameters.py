"""Sensor parameters as data: the ``sensors`` group of a parameter set.

The values, units, provenance and bounds live in ``twin/parameters/bench/sensors.toml`` and are checked by
the parameter set that holds them (:class:`twin.parameters.ParameterSet`), once, when the set is loaded or
changed. The sensor models take those values as a plain mapping of full names to SI values and import nothing
from the bench model (``docs/architecture.md``: sensors are the bottom layer).
"""

from __future__ import annotations

from collections.abc import Mapping

GROUP = "sensors"


class SensorValues(dict):
    """``{"sensors.<key>": value}``; a missing name is an error that names it."""

    def __missing__(self, name: str) -> float:
        raise ValueError(f"{name}: missing from the sensor parameters given (pass the whole validated "
                         f"'{GROUP}' group, e.g. twin.load_parameters('bench').values())")


def sensor_values(params: Mapping[str, float]) -> SensorValues:
    """The ``sensors.*`` entries of ``params`` (already validated values, SI units) as floats.

    Parameters
    ----------
    params : mapping
        Full parameter names to values, e.g. ``twin.load_parameters("bench").values()``; entries of
        other groups are ignored (they belong to other components).
    """
    return SensorValues({name: float(value) for name, value in params.items()
                         if name.split(".", 1)[0] == GROUP})
