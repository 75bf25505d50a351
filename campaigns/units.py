"""Units of a campaign spec and of measured channels: parsed by a units library, the ±range convention, and how a
value stored in SI is shown (prefix, precision).

Inside the model every value is SI; a spec row may be given in a handier unit (``um``, ``degC``, ``%``, ``kg m^2``)
and a measured channel in the unit its file states (``mm``, ``deg``, ``N m``). :func:`conversion` turns any unit
pint understands into the SI unit a parameter, condition or signal is stored in, as ``si = value * scale + offset``.
Spellings engineers write that pint alone does not read are normalised first (:func:`normalise`): ``kg·m²``,
``kg m2``, ``kg*m^2``, ``kg*m**2`` and ``kg m^2`` are the same unit.
"""

from __future__ import annotations

import functools
import math
import re

import numpy as np

#: A datasheet "± range" read as a Gaussian is taken to hold ±3 sigma.
#: Datasheets quote tolerance bands that practically every unit meets; ±3 sigma
#: covers 99.73 % of a normal population, which is the usual convention for such
#: limits (and the one that keeps the sampled values inside the band almost
#: always). This is the only place the factor is defined.
HALF_RANGE_SIGMAS = 3.0

#: Examples of spec units, for error messages (any unit pint reads is accepted).
EXAMPLES = "m, mm, um, µm, rad, deg, arcmin, K, degC, Pa, bar, N, kN, N m, kg m^2, 1, %, 1/K, %/K"

_SUPERSCRIPTS = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻", "0123456789-")
_PRODUCT_SIGNS = re.compile(r"\s*[·⋅×]\s*")
_SUPERSCRIPT_RUN = re.compile(r"([⁻]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+)")
# a unit symbol directly followed by digits ("m2", "m3"): an exponent, as in "kg/m3"
_TRAILING_EXPONENT = re.compile(r"(?<=[A-Za-zµΩ])(\d+)(?![\d.])")


def normalise(text: str) -> str:
    """A unit as pint reads it: ``·`` ``⋅`` ``×`` as products, superscripts and trailing digits as powers, ``^``
    as ``**``, ``Ω`` as ``ohm``."""
    text = _PRODUCT_SIGNS.sub("*", text.strip())
    text = _SUPERSCRIPT_RUN.sub(lambda m: "**" + m.group(1).translate(_SUPERSCRIPTS), text)
    text = _TRAILING_EXPONENT.sub(r"**\1", text)
    return text.replace("^", "**").replace("Ω", "ohm")


@functools.cache
def registry():
    """The one pint registry (lazy: pint costs about 0.3 s to import and build; only unit conversions need it)."""
    import pint  # lazy: start-up cost, see above

    return pint.UnitRegistry(autoconvert_offset_to_baseunit=True)


#: Longest unit text read (a unit is a few symbols; a longer text is refused before the parser sees it).
MAX_UNIT_LENGTH = 60


def _shown(text: str) -> str:
    """``text`` as an error message shows it: quoted, cut at :data:`MAX_UNIT_LENGTH` characters."""
    return repr(text) if len(text) <= MAX_UNIT_LENGTH else f"{text[:MAX_UNIT_LENGTH]!r}... ({len(text)} characters)"


@functools.cache
def conversion(unit: str, si_unit: str) -> tuple[float, float]:
    """``(scale, offset)`` with ``si = value * scale + offset`` from ``unit`` to ``si_unit``.

    Offsets (``degC`` to ``K``) apply to absolute values only, never to half ranges or sigmas.

    Raises
    ------
    ValueError
        Naming the unit that is not understood, or both units when they do not convert (different dimensions),
        and nothing else whatever the text: pint's parser is Python's tokenizer and evaluator, which raise
        ``TokenError`` (``deg)``), ``AssertionError`` (``m*``), ``ZeroDivisionError`` (``1/0``) and more.
    """
    import pint  # lazy: start-up cost (the registry is built on first use)

    ureg = registry()
    parsed = {}
    for text in (unit, si_unit):
        if not isinstance(text, str) or len(text) > MAX_UNIT_LENGTH:
            what = _shown(text) if isinstance(text, str) else f"of type {type(text).__name__}"
            raise ValueError(f"unknown unit {what}: a unit is a text of at most {MAX_UNIT_LENGTH} characters; "
                             f"e.g. {EXAMPLES}")
        try:
            parsed[text] = ureg.parse_units(normalise(text)) if text.strip() not in ("", "1") else ureg.dimensionless
        except Exception as exc:  # noqa: BLE001 - any failure of the parser on the user's text is that text's fault
            raise ValueError(f"unknown unit {_shown(text)} ({type(exc).__name__}); e.g. {EXAMPLES}") from None
    try:
        zero = ureg.Quantity(0.0, parsed[unit]).to(parsed[si_unit]).magnitude
        one = ureg.Quantity(1.0, parsed[unit]).to(parsed[si_unit]).magnitude
    except pint.errors.DimensionalityError:
        raise ValueError(f"unit {_shown(unit)} does not convert to {_shown(si_unit)} (the target's SI unit): "
                         f"{ureg.Quantity(1.0, parsed[unit]).dimensionality} is not "
                         f"{ureg.Quantity(1.0, parsed[si_unit]).dimensionality}") from None
    except Exception as exc:  # noqa: BLE001 - e.g. OverflowError of a power too large
        raise ValueError(f"unit {_shown(unit)} does not convert to {_shown(si_unit)} ({type(exc).__name__})") from None
    scale, offset = float(one - zero), float(zero)
    if not (math.isfinite(scale) and math.isfinite(offset) and scale != 0.0):
        raise ValueError(f"unit {_shown(unit)} does not convert to {_shown(si_unit)}: its scale {scale:g} is not a "
                         "finite, non-zero number")
    return scale, offset


def known_unit(unit: str) -> bool:
    """Whether pint reads ``unit`` (after :func:`normalise`)."""
    try:
        conversion(unit, unit)
    except ValueError:
        return False
    return True


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
