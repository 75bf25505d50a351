"""Sensor parameters: the ``sensors`` group of a parameter set.

The values, units, provenance and bounds live in
``twin/parameters/bench/sensors.toml``; this module only resolves a caller's
parameter set or overrides against that file, so bounds are checked by the
same code as every other parameter (:class:`twin.parameters.ParameterSet`).
"""

from __future__ import annotations

from functools import lru_cache
from typing import Mapping

from twin.parameters import BUILTIN_DIR, ParameterSet, load_parameters

GROUP = "sensors"
SENSORS_TOML = BUILTIN_DIR / "bench" / "sensors.toml"


@lru_cache(maxsize=1)
def _bench_sensors() -> ParameterSet:
    return load_parameters(SENSORS_TOML)


def validate_sensor_values(params: ParameterSet | Mapping[str, float] | None = None) -> dict[str, float]:
    """Complete, validated ``{"sensors.<key>": value}`` dictionary.

    Parameters
    ----------
    params : ParameterSet or mapping or None
        A parameter set (e.g. ``twin.load_parameters("bench")``), already
        validated against its own files, or a mapping of full names to values
        (SI units), validated here against the bench file. Entries of other
        groups are ignored (they belong to other components); ``sensors.*``
        entries override the bench values; missing ones take the bench values.

    Raises
    ------
    twin.ParameterError
        (a ``ValueError``) listing every unknown ``sensors.*`` name and every
        value outside its bounds, each with the field name and what is allowed.
    """
    base = _bench_sensors()
    if params is None:
        return base.values()
    ours = {name: value for name, value in params.items() if name.split(".", 1)[0] == GROUP}
    if isinstance(params, ParameterSet):
        return {**base.values(), **{name: parameter.value for name, parameter in ours.items()}}
    return base.with_values(ours).values()
