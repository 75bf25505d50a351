"""What a model offers to a campaign: targets with nominal values, scenes, features.

The spec is validated against a catalog and its relative ranges are resolved
with the catalog's nominal values. :class:`campaigns.bench.BenchCatalog` is the
bench twin's catalog; :data:`campaigns.testing.SYNTHETIC_CATALOG` is the fast
synthetic model's.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache
from typing import Mapping, Protocol, Sequence


@cache
def condition_units() -> dict[str, str]:
    """Scene conditions a data set may override with a number (``scene.with_conditions`` keys) and their SI units.

    The numeric conditions of the bench's scene table (``twin.scenes.CONDITIONS``, the one source), plus
    ``external_force``, a condition of the synthetic test model only (campaigns.testing): the bench's
    scenes apply an external force as a force demand profile, and ``BenchCatalog.condition_names`` leaves
    it out, so a bench spec naming it is rejected with the list of the conditions the scenes accept.
    The twin is imported on first use, not with this module: the synthetic model's run processes never load it.
    """
    # lazy: start-up cost (the synthetic model's run processes never load the twin and its compiled code)
    from twin.scenes import CONDITIONS

    return {**{name: condition.unit for name, condition in CONDITIONS.items() if condition.numeric}, "external_force": "N"}


@cache
def condition_choices() -> dict[str, tuple[str, ...]]:
    """Scene conditions a data set may set to one of a few named choices (``zero_procedure``, ``cylinder``,
    ``preload_configuration``) and their choices, from the same table (imported on first use)."""
    # lazy: start-up cost, as above
    from twin.scenes import CONDITIONS

    return {name: condition.choices for name, condition in CONDITIONS.items() if condition.choices}


def __getattr__(name: str):
    """``CONDITION_UNITS`` and ``CONDITION_CHOICES``: :func:`condition_units` and :func:`condition_choices`,
    computed on first access (PEP 562)."""
    if name == "CONDITION_UNITS":
        return condition_units()
    if name == "CONDITION_CHOICES":
        return condition_choices()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

#: Prefix of uncertainty targets that are scene conditions rather than parameters.
SCENE_PREFIX = "scene."


class Catalog(Protocol):
    """Interface the spec validation needs from a model.

    Attributes
    ----------
    parameter_names : sequence of str
        Names accepted by ``ParameterSet.with_values``.
    scene_names : sequence of str
        Scenes a data set may start from.
    condition_names : sequence of str
        Conditions ``scene.with_conditions`` accepts.
    feature_units : mapping of str to (unit, long_name), or None
        Features the run function computes; ``None`` accepts any name.
    """

    parameter_names: Sequence[str]
    scene_names: Sequence[str]
    condition_names: Sequence[str]
    feature_units: Mapping[str, tuple[str, str]] | None

    def nominal(self, target: str) -> tuple[float, str]:
        """Nominal value and SI unit of a parameter or ``scene.<condition>``; KeyError if unknown."""


@dataclass(frozen=True)
class StaticCatalog:
    """A catalog given as plain data (used by the synthetic test model).

    Parameters
    ----------
    parameters : mapping of str to (value, unit)
        Parameter nominal values and units.
    conditions : mapping of str to float
        Nominal scene conditions (SI units of :func:`condition_units`); their
        names are the accepted conditions.
    scene_names : sequence of str
    feature_units : mapping of str to (unit, long_name), or None
    """

    parameters: Mapping[str, tuple[float, str]]
    conditions: Mapping[str, float]
    scene_names: Sequence[str]
    feature_units: Mapping[str, tuple[str, str]] | None = field(default=None)

    @property
    def parameter_names(self) -> list[str]:
        return list(self.parameters)

    @property
    def condition_names(self) -> list[str]:
        return list(self.conditions)

    def nominal(self, target: str) -> tuple[float, str]:
        return lookup_nominal(target, self.parameters, self.conditions)


def lookup_nominal(
    target: str, parameters: Mapping[str, tuple[float, str]], conditions: Mapping[str, float]
) -> tuple[float, str]:
    """Shared target lookup of the catalogs; the KeyError message names what is known."""
    if target.startswith(SCENE_PREFIX):
        key = target.removeprefix(SCENE_PREFIX)
        if key not in conditions:
            raise KeyError(f"unknown scene condition {target!r}; known: {', '.join(SCENE_PREFIX + c for c in conditions)}")
        return float(conditions[key]), condition_units()[key]
    if target not in parameters:
        group = target.split(".")[0]
        siblings = [n for n in parameters if n.startswith(group + ".")]
        hint = f"known in '{group}': {', '.join(siblings)}" if siblings else f"known groups: {', '.join(sorted({n.split('.')[0] for n in parameters}))}"
        raise KeyError(f"unknown parameter {target!r}; {hint}")
    return parameters[target]
