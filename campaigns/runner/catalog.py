"""What a model offers to a campaign: targets with nominal values, scenes, features.

The spec is validated against a catalog and its relative ranges are resolved
with the catalog's nominal values. :class:`campaigns.bench.adapter.BenchCatalog` is the
bench twin's catalog; :data:`campaigns.runner.synthetic.SYNTHETIC_CATALOG` is the fast
synthetic model's.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache
from typing import Protocol

from twin.errors import did_you_mean


def _scenes():
    """The twin's scene module, the one table of scene conditions (``twin.scenes.CONDITIONS``) and the one
    parser of ``scene.`` targets (lazy: start-up cost; the synthetic model's run processes never load the twin)."""
    import twin.scenes

    return twin.scenes


@cache
def condition_units() -> dict[str, str]:
    """The bench scenes' numeric conditions (``scene.with_conditions`` keys) and their SI units, from the scene
    table ``twin.scenes.CONDITIONS``. A model with other conditions declares their units in its catalog
    (:attr:`StaticCatalog.condition_units`)."""
    return {name: condition.unit for name, condition in _scenes().CONDITIONS.items() if condition.numeric}


@cache
def condition_choices() -> dict[str, tuple[str, ...]]:
    """The bench scenes' conditions that take one of a few named choices (``zero_procedure``, ``cylinder``,
    ``preload_configuration``) and their choices, from the same table."""
    return {name: condition.choices for name, condition in _scenes().CONDITIONS.items() if condition.choices}


def __getattr__(name: str):
    """``CONDITION_UNITS`` and ``CONDITION_CHOICES``: :func:`condition_units` and :func:`condition_choices`,
    computed on first access (PEP 562)."""
    if name == "CONDITION_UNITS":
        return condition_units()
    if name == "CONDITION_CHOICES":
        return condition_choices()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
    condition_units : mapping of str to str
        SI unit of each numeric condition.
    feature_units : mapping of str to (unit, long_name), or None
        Features the run function computes; ``None`` accepts any name.
    """

    parameter_names: Sequence[str]
    scene_names: Sequence[str]
    condition_names: Sequence[str]
    condition_units: Mapping[str, str]
    feature_units: Mapping[str, tuple[str, str]] | None

    def nominal(self, target: str) -> tuple[float, str]:
        """Nominal value and SI unit of a parameter or ``scene.<condition>``; KeyError if unknown."""

    def support_checks(self, spec) -> tuple[list[str], list[str]]:
        """``(problems, warnings)`` of a validated ``CampaignSpec``'s sampled ranges and fixed parameters against
        the model's own bounds, before anything runs (problems refuse the spec, warnings are printed)."""


@dataclass(frozen=True)
class StaticCatalog:
    """A catalog given as plain data (used by the synthetic test model).

    Parameters
    ----------
    parameters : mapping of str to (value, unit)
        Parameter nominal values and units.
    conditions : mapping of str to (value, unit)
        Nominal scene conditions and their SI units; their names are the
        accepted conditions.
    scene_names : sequence of str
    feature_units : mapping of str to (unit, long_name), or None
    """

    parameters: Mapping[str, tuple[float, str]]
    conditions: Mapping[str, tuple[float, str]]
    scene_names: Sequence[str]
    feature_units: Mapping[str, tuple[str, str]] | None = field(default=None)

    @property
    def condition_units(self) -> dict[str, str]:
        return {name: unit for name, (_, unit) in self.conditions.items()}

    @property
    def parameter_names(self) -> list[str]:
        return list(self.parameters)

    @property
    def condition_names(self) -> list[str]:
        return list(self.conditions)

    def nominal(self, target: str) -> tuple[float, str]:
        return lookup_nominal(target, self.parameters, self.conditions)

    def support_checks(self, spec) -> tuple[list[str], list[str]]:
        """A catalog given as data states no bounds: nothing to check."""
        return [], []



def lookup_nominal(
    target: str, parameters: Mapping[str, tuple[float, str]], conditions: Mapping[str, tuple[float, str]]
) -> tuple[float, str]:
    """Shared target lookup of the catalogs (value and unit); the KeyError message names what is known."""
    scenes = _scenes()
    condition = scenes.split_targets({target: None})[0]
    if condition:
        (key,) = condition
        if key not in conditions:
            names = [scenes.SCENE_PREFIX + c for c in conditions]
            raise KeyError(f"unknown scene condition {target!r}; {spelling_hint(target, names)}"
                           f"known: {', '.join(names)}")
        value, unit = conditions[key]
        return float(value), unit
    if target not in parameters:
        group = target.split(".")[0]
        siblings = [n for n in parameters if n.startswith(group + ".")]
        hint = (f"known in '{group}': {', '.join(siblings)}" if siblings
                else f"known groups: {', '.join(sorted({n.split('.')[0] for n in parameters}))}")
        raise KeyError(f"unknown parameter {target!r}; {spelling_hint(target, parameters)}{hint}")
    return parameters[target]


def spelling_hint(name: str, known) -> str:
    """``"did you mean 'x'? "`` for a likely misspelling (:func:`twin.errors.did_you_mean`), else ``""``."""
    suggestion = did_you_mean(name, known)
    return f"{suggestion} " if suggestion else ""
