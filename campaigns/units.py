"""Units of a campaign spec and of measured channels: parsed by a units library, the ±range convention, and how a
value stored in SI is shown (prefix, precision).

Inside the model every value is SI; a spec row may be given in a handier unit (``um``, ``degC``, ``%``, ``kg m^2``)
and a measured channel in the unit its file states (``mm``, ``deg``, ``N m``). :func:`conversion` turns any unit
pint understands into the SI unit a parameter, condition or signal is stored in, as ``si = value * scale + offset``.
Spellings engineers write that pint alone does not read are normalised first (:func:`normalise`): ``kg·m²``,
``kg m2``, ``kg*m^2``, ``kg*m**2`` and ``kg m^2`` are the same unit.
"""

from __future__ import annotations

import math

import numpy as np

# The one parser of units (numerics.units), re-exported: a spec row's and a measured channel's unit are read as a
# --set value's is.
from numerics.units import EXAMPLES as EXAMPLES
from numerics.units import MAX_UNIT_LENGTH as MAX_UNIT_LENGTH
from numerics.units import conversion as conversion
from numerics.units import known_unit as known_unit
from numerics.units import normalise as normalise
from numerics.units import registry as registry

#: A datasheet "± range" read as a Gaussian is taken to hold ±3 sigma.
#: Datasheets quote tolerance bands that practically every unit meets; ±3 sigma
#: covers 99.73 % of a normal population, which is the usual convention for such
#: limits (and the one that keeps the sampled values inside the band almost
#: always). This is the only place the factor is defined.
HALF_RANGE_SIGMAS = 3.0

# --- Display: how a value stored in SI reads (the report, the CLI and the comparison's and diagnosis's sentences) ---

#: Units that take an SI prefix.
_PREFIXABLE = {"m", "N", "A", "s", "V", "W", "N m", "N/m", "rad"}
_PREFIXES = ((1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "µ"), (1e-9, "n"), (1e-12, "p"),
             (1e-15, "f"))
#: Units shown in another unit: SI unit -> (display unit, SI value of one display unit).
_CONVERTED = {"Pa": ("bar", 1e5)}
_DIMENSIONLESS = {"", "1"}


def display_scale(unit: str, values) -> tuple[float, str]:
    """Factor to multiply SI values by, and the unit of the result.

    Parameters
    ----------
    unit : str
        SI unit of ``values`` (the ``units`` attribute).
    values : array_like
        The values to show; their largest finite magnitude picks the prefix.

    Returns
    -------
    tuple of (float, str)
    """
    if unit in _CONVERTED:
        shown, size = _CONVERTED[unit]
        return 1.0 / size, shown
    if unit in _DIMENSIONLESS:
        return 1.0, "–"
    magnitude = np.abs(np.asarray(values, dtype=float))
    magnitude = magnitude[np.isfinite(magnitude)]
    if unit not in _PREFIXABLE or magnitude.size == 0 or magnitude.max() == 0:
        return 1.0, unit
    reference = magnitude.max()
    size, prefix = next(((size, prefix) for size, prefix in _PREFIXES if reference >= size), _PREFIXES[-1])
    return 1.0 / size, prefix + unit


def number(value, digits: int = 3) -> str:
    """A number with ``digits`` significant digits; NaN and None as an en dash."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    value = float(value)
    if math.isnan(value):
        return "–"
    return f"{value:.{digits}g}"


def quantity(value: float, unit: str, digits: int = 3) -> str:
    """A value in SI units shown with its display unit, e.g. ``2.5e-6, "m"`` -> ``"2.5 µm"``."""
    if value is None or not math.isfinite(value):
        return "–"
    factor, shown = display_scale(unit, [value])
    return f"{number(value * factor, digits)} {shown}" if shown != "–" else number(value, digits)


def quantity_range(low: float, high: float, unit: str, digits: int = 2, separator: str = "–") -> str:
    """Two values in one display unit chosen by the larger, e.g. ``0–3.1 µm`` (never ``0 m`` for a zero bound):
    an interval reads in the unit that shows it."""
    finite = [v for v in (low, high) if v is not None and math.isfinite(v)]
    if not finite:
        return "–"
    factor, shown = display_scale(unit, finite)
    text = f"{_significant(low * factor, digits)}{separator}{_significant(high * factor, digits)}"
    return f"{text} {shown}" if shown != "–" else text


def _significant(value: float, digits: int) -> str:
    """``value`` rounded to ``digits`` significant digits without an exponent below 1e6 (``120``, not ``1.2e+02``)."""
    if not math.isfinite(value):
        return "–"
    if value == 0:
        return "0"
    rounded = round(value, digits - 1 - math.floor(math.log10(abs(value))))
    return f"{rounded:.6g}"


def estimate_with_interval(estimate: float, low: float, high: float, unit: str, confidence: float = 0.95) -> str:
    """``+0.6 nm (95 % interval -0.7 … 1.9 nm)``: the three in one display unit, chosen by the largest, each rounded
    at the second significant digit of the interval's half-width, the precision the interval resolves (JCGM 100:2008,
    GUM, Sec. 7.2.6: a result is stated to the precision of its uncertainty; the second digit keeps the bounds apart
    when the half-width's first digit is 1), at most 3 significant digits. A zero-width interval around 0 (the runs
    agree to the last bit) says so."""
    if not all(math.isfinite(v) for v in (estimate, low, high)):
        return "–"
    half_width = 0.5 * (high - low)
    if half_width <= 0.0 and estimate == 0.0:
        return f"0 ({confidence * 100:g} % interval 0 … 0: identical in every run)"
    factor, shown = display_scale(unit, [estimate, low, high])
    shown = "" if shown == "–" else f" {shown}"
    if half_width > 0.0:
        largest = max(abs(estimate), abs(low), abs(high)) * factor
        # decimals (negative: rounded to tens, hundreds), and never beyond 3 significant digits of the largest value:
        # an interval far narrower than the values (round-off of near-identical runs) resolves no more than that
        digits = min(1 - math.floor(math.log10(half_width * factor)), 2 - math.floor(math.log10(largest)))

        def text(value: float) -> str:
            rounded = round(value * factor, digits)
            return f"{rounded + 0.0:.{max(digits, 0)}f}"  # + 0.0: a value rounded to zero reads 0, not -0
    else:
        def text(value: float) -> str:
            return _significant(value * factor, 3)
    sign = "+" if round(estimate * factor, 12) > 0 else ""
    return f"{sign}{text(estimate)}{shown} ({confidence * 100:g} % interval {text(low)} … {text(high)}{shown})"


def feature_units(units: list[str], holder: str = "the feature_units coordinate") -> dict[str, str]:
    """The ``units`` attribute of a variable along the feature axis: the features' common unit, or (features in
    several units; CF gives one unit per variable) a comment that points at ``holder``, the variable of the file
    that gives each feature's unit."""
    if len(set(units)) == 1:
        return {"units": units[0]}
    return {"comment": f"in the units of each feature, given by {holder} (" + ", ".join(sorted(set(units))) + ")"}
