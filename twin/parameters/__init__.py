"""Parameter sets: named, unit-tagged values with their source.

A parameter set is a directory of TOML files, one per component; a parameter's
full name is ``<file stem>.<key>``. Each entry carries ``value``, ``unit`` and
exactly one of ``source`` (a datasheet table or thesis equation) or
``assumption`` (the reasoning behind a value the thesis does not give), plus
optional bounds ``min`` / ``gt`` / ``max`` (and ``integer = true`` for a count) that every
override is checked against. See ``docs/architecture.md``.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from types import MappingProxyType

from numerics.units import value_in
from twin.errors import ParameterError, did_you_mean

BUILTIN_DIR = Path(__file__).parent
#: A value more than this many times its nominal, or less than its inverse, is flagged as implausible (a warning
#: before any run, never an error). Table 9.5's widest tolerance is ±50 % of a nominal and the bench's conditions
#: stay within a factor of a few of the thesis values, so a factor of 100 is beyond any deliberate variation; it is
#: the size of the slips that do happen: a unit prefix (mm as m: 1000), an exponent typed wrong (1.65 for 1.65e-4:
#: 1e4), a percentage typed as a fraction (100).
PLAUSIBLE_FACTOR = 100.0
#: Values a :class:`ParameterSet`'s repr shows (the rest: :meth:`ParameterSet.to_frame`).
_REPR_VALUES = 3
_ALLOWED_KEYS = {"value", "unit", "source", "assumption", "min", "gt", "max", "integer", "table_9_5",
                 "table_9_5_extension"}


@dataclass(frozen=True)
class Parameter:
    """One parameter value with its unit, provenance and allowed range."""

    name: str
    value: float
    unit: str
    source: str | None = None
    assumption: str | None = None
    min: float | None = None
    gt: float | None = None
    max: float | None = None
    integer: bool = False  # a count: only whole numbers are allowed
    table_9_5: str | None = None
    table_9_5_extension: str | None = None  # an uncertainty the bench has that Table 9.5 does not list (issue 33)

    @property
    def is_assumption(self) -> bool:
        return self.assumption is not None

    def allowed(self) -> str:
        """Human-readable allowed range, used in error messages."""
        parts = []
        if self.gt is not None:
            parts.append(f"> {self.gt:g}")
        if self.min is not None:
            parts.append(f">= {self.min:g}")
        if self.max is not None:
            parts.append(f"<= {self.max:g}")
        if self.integer:
            return f"a whole number {' and '.join(parts)}".rstrip()
        return " and ".join(parts) if parts else "any finite number"

    def resolved(self, value: float | str) -> float | str:
        """``value`` in this parameter's unit: a number as it stands, a text with a unit (``"3 mrad"``,
        ``"1.65e-4 kg m^2"``) converted (:func:`numerics.units.value_in`).

        Raises
        ------
        ValueError
            Naming the parameter and the text, or both units when they do not convert.
        """
        if not isinstance(value, str):
            return value
        try:
            return value_in(value, self.unit)
        except ValueError as exc:
            raise ValueError(f"{self.name}: {exc}") from None

    def check(self, value: float) -> str | None:
        """Return a problem description if ``value`` is not allowed, else None."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return f"{self.name}: value {value!r} is not a number ({self.unit})"
        if not math.isfinite(value):
            return f"{self.name}: value {value!r} is not finite; allowed: {self.allowed()} [{self.unit}]"
        if (
            (self.gt is not None and not value > self.gt)
            or (self.min is not None and value < self.min)
            or (self.max is not None and value > self.max)
        ):
            return f"{self.name}: value {value:g} {self.unit} is out of range; allowed: {self.allowed()}"
        if self.integer and value != math.floor(value):
            return f"{self.name}: value {value:g} {self.unit} is not a whole number; allowed: {self.allowed()}"
        return None


    def implausible(self, value: float) -> str | None:
        """A warning when ``value`` lies more than :data:`PLAUSIBLE_FACTOR` times away from the nominal (in either
        direction), else None; values with another sign or a zero nominal are judged by the bounds alone."""
        if (isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value)
                or self.value == 0.0 or value == 0.0 or (value > 0) != (self.value > 0)):
            return None
        ratio = value / self.value
        if 1.0 / PLAUSIBLE_FACTOR <= ratio <= PLAUSIBLE_FACTOR:
            return None
        provenance = self.source if self.source is not None else f"assumption: {self.assumption}"
        return (f"{self.name} = {value:g} {self.unit} is {ratio:.3g} times its nominal {self.value:g} {self.unit} "
                f"({provenance[:80]}); more than {PLAUSIBLE_FACTOR:g} times off the nominal is usually a unit or "
                f"exponent slip (allowed: {self.allowed()})")


class ParameterSet(Mapping[str, Parameter]):
    """An immutable, validated mapping ``name -> Parameter``.

    Load with :func:`load_parameters`; derive variants with :meth:`with_values`.
    """

    def __init__(self, name: str, parameters: Mapping[str, Parameter]):
        self.name = name
        self._parameters = MappingProxyType(dict(parameters))

    def __getitem__(self, name: str) -> Parameter:
        try:
            return self._parameters[name]
        except KeyError:
            raise ParameterError([_unknown(name, self._parameters)]) from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._parameters)

    def __len__(self) -> int:
        return len(self._parameters)

    @property
    def names(self) -> list[str]:
        return list(self._parameters)

    def value(self, name: str) -> float:
        return self[name].value

    def values(self) -> dict[str, float]:  # type: ignore[override]
        """Plain ``{name: value}`` dictionary (SI units)."""
        return {n: p.value for n, p in self._parameters.items()}

    def with_values(self, overrides: Mapping[str, float | str]) -> ParameterSet:
        """Return a copy with some values replaced; every override is validated.

        A value is a number in the parameter's SI unit or a text with its unit (``{"reducer.backlash": "3 mrad"}``),
        converted to that unit (:meth:`Parameter.resolved`).

        Raises
        ------
        ParameterError
            Listing every unknown name and every out-of-range value at once.
        """
        problems = []
        updated = dict(self._parameters)
        for name, value in overrides.items():
            if name not in self._parameters:
                problems.append(_unknown(name, self._parameters))
                continue
            try:
                value = self._parameters[name].resolved(value)
            except ValueError as exc:
                problems.append(str(exc))
                continue
            problem = self._parameters[name].check(value)
            if problem:
                problems.append(problem)
            else:
                updated[name] = replace(self._parameters[name], value=float(value))
        if problems:
            raise ParameterError(problems)
        return ParameterSet(self.name, updated)

    def implausible(self, overrides: Mapping[str, float | str]) -> list[str]:
        """Warnings for override values far from their nominal (:meth:`Parameter.implausible`): said before any run,
        the run still goes ahead (an extreme value may be meant). Unknown names and values that do not convert are
        :meth:`with_values`' business."""
        warnings = []
        for name, value in overrides.items():
            if name in self._parameters:
                try:
                    warning = self._parameters[name].implausible(self._parameters[name].resolved(value))
                except ValueError:
                    continue
                if warning is not None:
                    warnings.append(warning)
        return warnings

    def table(self) -> list[dict]:
        """Rows (name, value, unit, source/assumption) for documentation and reports."""
        return [
            {
                "name": p.name,
                "value": p.value,
                "unit": p.unit,
                "provenance": p.source if p.source is not None else f"ASSUMPTION: {p.assumption}",
            }
            for p in self._parameters.values()
        ]

    def to_frame(self):
        """The parameters as a pandas DataFrame indexed by name: ``value`` (SI), ``unit`` and ``source`` (the
        datasheet or equation, or ``ASSUMPTION: ...``), the rows of :meth:`table`."""
        import pandas as pd  # lazy: start-up cost (``import twin`` does not load pandas)

        frame = pd.DataFrame(self.table()).rename(columns={"provenance": "source"})
        return frame.set_index("name")

    def __repr__(self) -> str:
        shown = ", ".join(f"{p.name}={p.value:g} {p.unit}" for p in list(self._parameters.values())[:_REPR_VALUES])
        more = len(self) - _REPR_VALUES
        return (f"ParameterSet({self.name!r}, {len(self)} parameters: {shown}"
                f"{f', ... {more} more; .to_frame() for all' if more > 0 else ''})")


def _unknown(name: str, known: Mapping[str, Parameter]) -> str:
    group = name.split(".")[0]
    siblings = sorted(n for n in known if n.startswith(group + "."))
    hint = (f"; known in '{group}': {', '.join(siblings)}" if siblings
            else f"; known groups: {', '.join(sorted({n.split('.')[0] for n in known}))}")
    suggestion = did_you_mean(name, known)
    return f"{name}: unknown parameter; {suggestion} ({hint[2:]})" if suggestion else f"{name}: unknown parameter{hint}"


def available_parameter_sets() -> list[str]:
    """Names of the parameter sets shipped with the package."""
    return sorted(p.name for p in BUILTIN_DIR.iterdir() if p.is_dir() and any(p.glob("*.toml")))


def load_parameters(name_or_path: str | Path = "bench") -> ParameterSet:
    """Load a parameter set by built-in name or from a directory / single TOML file.

    Parameters
    ----------
    name_or_path : str or Path
        A built-in set name (see :func:`available_parameter_sets`), a directory
        of component TOML files, or one TOML file.

    Raises
    ------
    ParameterError
        If the set does not exist or any entry is malformed (all problems listed).
    """
    path = Path(name_or_path)
    if not path.exists():
        builtin = BUILTIN_DIR / str(name_or_path)
        if not builtin.is_dir():
            raise ParameterError(
                [f"params: '{name_or_path}' is neither a file/directory nor a built-in set "
                 f"({', '.join(available_parameter_sets())})"]
            )
        path = builtin
    files = sorted(path.glob("*.toml")) if path.is_dir() else [path]
    problems: list[str] = []
    parameters: dict[str, Parameter] = {}
    for file in files:
        try:
            data = tomllib.loads(file.read_text())
        except tomllib.TOMLDecodeError as exc:
            problems.append(f"{file.name}: not valid TOML ({exc})")
            continue
        for key, entry in data.items():
            name = f"{file.stem}.{key}"
            parameter, entry_problems = _parse_entry(name, entry)
            problems.extend(entry_problems)
            if parameter is not None:
                parameters[name] = parameter
    if problems:
        raise ParameterError(problems)
    return ParameterSet(path.stem if path.is_file() else path.name, parameters)


def _parse_entry(name: str, entry) -> tuple[Parameter | None, list[str]]:
    if not isinstance(entry, dict):
        return None, [f"{name}: expected a table with value/unit/source, got {type(entry).__name__}"]
    problems = [f"{name}.{k}: unknown field; allowed: {', '.join(sorted(_ALLOWED_KEYS))}" for k in entry
                if k not in _ALLOWED_KEYS]
    if "value" not in entry:
        problems.append(f"{name}.value: missing")
    if not isinstance(entry.get("unit"), str):
        problems.append(f"{name}.unit: missing or not a string (use SI, '1' for dimensionless)")
    if ("source" in entry) == ("assumption" in entry):
        problems.append(f"{name}: give exactly one of 'source' (datasheet/equation) or 'assumption' (reasoning)")
    for bound in ("min", "gt", "max"):
        if bound in entry and not isinstance(entry[bound], (int, float)):
            problems.append(f"{name}.{bound}: must be a number")
    if "integer" in entry and not isinstance(entry["integer"], bool):
        problems.append(f"{name}.integer: must be true or false")
    if problems:
        return None, problems
    parameter = Parameter(
        name=name,
        value=entry["value"],
        unit=entry["unit"],
        source=entry.get("source"),
        assumption=entry.get("assumption"),
        min=entry.get("min"),
        gt=entry.get("gt"),
        max=entry.get("max"),
        integer=entry.get("integer", False),
        table_9_5=entry.get("table_9_5"),
        table_9_5_extension=entry.get("table_9_5_extension"),
    )
    problem = parameter.check(entry["value"])
    if problem:
        return None, [problem]
    return replace(parameter, value=float(entry["value"])), []
