"""Helpers shared by the bench tests (importable: conftest modules are not)."""

import twin
from twin.fidelity import full_plant


def plant_fidelity(scene) -> dict:
    """:func:`twin.fidelity.full_plant` with the load system only where the scene demands a force."""
    return full_plant("full" if twin.load_scene(scene).has_force_demand else "absent")


def bench_sensors(overrides: dict | None = None) -> dict[str, float]:
    """The bench parameter values with ``overrides``, validated by the parameter set (as a model build does):
    what the sensor builders take as data. A bad override raises :class:`twin.ParameterError` naming it."""
    return twin.load_parameters("bench").with_values(overrides or {}).values()
