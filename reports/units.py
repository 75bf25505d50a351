"""Display units and number formatting shared by the figures and the tables.

Values are stored in SI units; a report shows them with the SI prefix that
suits their magnitude (backlash in µm, positions in mm, forces in N or kN) and
pressures in bar, the unit of the bench's pneumatic components.
"""

from __future__ import annotations

import math

import numpy as np

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


def axis_label(name: str, unit: str) -> str:
    """``name [unit]``; dimensionless quantities get ``[–]``."""
    return f"{name} [{unit or '–'}]"


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
