"""Range resolution: a row of the uncertainty table (Table 9.5) as a distribution in SI units.

A row gives its range as ``half_range`` (± around the nominal), ``low``/``high`` (absolute, or percent of the
nominal when ``relative``) or ``sigma``; :func:`resolve` turns it into a
:class:`~campaigns.runner.distributions.Distribution` with the nominal value and unit from the model's catalog,
:func:`shape_problems` says what is wrong with it first.
"""

from __future__ import annotations

import math

from campaigns.runner.distributions import Distribution
from campaigns.units import EXAMPLES, HALF_RANGE_SIGMAS, conversion, known_unit


def shape_problems(row) -> list[str]:
    """Every problem of the row's shape: which fields a distribution needs, takes or refuses, and its unit."""
    kind = row.distribution
    given = {k for k in ("half_range", "low", "high", "sigma", "value") if getattr(row, k) is not None}
    problems = []
    if row.low is not None and row.high is not None and row.low > row.high:
        problems.append(f"low ({row.low:g}) > high ({row.high:g})")
    if ("low" in given) != ("high" in given):
        problems.append("give both low and high")
    if "half_range" in given and {"low", "high"} & given:
        problems.append("give either half_range or low/high, not both")
    if row.relative and row.unit not in (None, "%"):
        problems.append(f"relative rows are in percent of nominal; unit must be '%' or omitted, got {row.unit!r}")
    if not row.relative and row.unit is not None and (not isinstance(row.unit, str) or not known_unit(row.unit)):
        problems.append(f"unknown unit {row.unit!r}; any unit of the pint library, e.g. {EXAMPLES}")
    has_range = bool({"half_range", "low"} & given)
    if kind == "constant":
        if given - {"value"}:
            problems.append("a constant takes only 'value' (or nothing: the nominal)")
    elif "value" in given:
        problems.append(f"'value' is only for constant distributions, not {kind}")
    if kind == "uniform" and not has_range:
        problems.append("a uniform distribution needs half_range or low/high")
    if kind == "gaussian" and not (has_range or "sigma" in given):
        problems.append("a gaussian needs half_range, low/high or sigma")
    if kind == "truncated_gaussian" and not has_range:
        problems.append("a truncated gaussian needs half_range or low/high (the truncation bounds)")
    if kind == "lognormal" and not (row.relative and "half_range" in given):
        problems.append("a lognormal needs relative = true and half_range (percent of the median)")
    if "sigma" in given and kind not in ("gaussian", "truncated_gaussian"):
        problems.append(f"'sigma' is only for gaussian distributions, not {kind}")
    if "mean" in given and "sigma" not in given:
        problems.append("'mean' goes with 'sigma'")
    return problems

def resolve(row, nominal: float, unit: str) -> Distribution:
    """Convert a row to absolute SI parameters around the target's ``nominal`` value in its SI ``unit``.

    Raises
    ------
    ValueError
        On a relative range around a zero nominal, or a unit that does not convert to the target's.
    """
    if row.relative:
        if nominal == 0.0:
            raise ValueError(f"relative range on {row.target} whose nominal value is 0")

        def absolute(p: float) -> float:
            return nominal * (1.0 + p / 100.0)

        def delta(d: float) -> float:
            return abs(nominal) * d / 100.0

    else:
        spec_unit = row.unit or unit
        if spec_unit == unit:
            scale, offset = 1.0, 0.0
        else:
            try:
                scale, offset = conversion(spec_unit, unit)
            except ValueError as exc:
                raise ValueError(f"{row.target}: {exc}") from None

        def absolute(p: float) -> float:
            return p * scale + offset

        def delta(d: float) -> float:
            return d * scale

    low = high = math.nan
    if row.half_range is not None:
        low, high = nominal - delta(row.half_range), nominal + delta(row.half_range)
    elif row.low is not None:
        low, high = sorted((absolute(row.low), absolute(row.high)))
    common = dict(target=row.target, kind=row.distribution, unit=unit, nominal=nominal, source=row.source)
    if row.distribution == "constant":
        return Distribution(**common, value=nominal if row.value is None else absolute(row.value))
    if row.distribution == "uniform":
        return Distribution(**common, low=low, high=high)
    if row.distribution == "lognormal":
        sigma_log = math.log1p(row.half_range / 100.0) / HALF_RANGE_SIGMAS
        return Distribution(**common, mean=nominal, sigma=sigma_log)
    if row.sigma is not None:
        mean = nominal if row.mean is None else absolute(row.mean)
        sigma = delta(row.sigma)
    else:
        mean, sigma = 0.5 * (low + high), 0.5 * (high - low) / HALF_RANGE_SIGMAS
    if row.distribution == "truncated_gaussian":
        return Distribution(**common, mean=mean, sigma=sigma, low=low, high=high)
    return Distribution(**common, mean=mean, sigma=sigma)
