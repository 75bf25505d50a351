"""Units: the one parser of a unit or a value written with one (``"20 um"``, ``"3 mrad"``, ``"25 degC"``).

Inside the model every value is SI; a value may be given in a handier unit wherever a user types one: a ``--set``
override, :meth:`twin.ParameterSet.with_values`, :meth:`twin.Scene.with_conditions`, a campaign spec row, a measured
channel's unit. :func:`conversion` turns any unit pint understands into the SI unit a parameter, condition or signal
is stored in, as ``si = value * scale + offset``; :func:`value_in` reads a number with its unit. Spellings engineers
write that pint alone does not read are normalised first (:func:`normalise`): ``kg·m²``, ``kg m2``, ``kg*m^2``,
``kg*m**2`` and ``kg m^2`` are the same unit.

A module of the bottom layer, so that the twin, the campaign runner (:mod:`campaigns.units` re-exports it) and the
analysis, which may not import the twin, share one parser.
"""

from __future__ import annotations

import decimal
import functools
import math
import re

#: Examples of units, for error messages (any unit pint reads is accepted).
EXAMPLES = "m, mm, um, µm, rad, deg, arcmin, K, degC, Pa, bar, N, kN, N m, kg m^2, 1, %, 1/K, %/K"

_SUPERSCRIPTS = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻", "0123456789-")
_PRODUCT_SIGNS = re.compile(r"\s*[·⋅×]\s*")
_SUPERSCRIPT_RUN = re.compile(r"([⁻]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+)")
# a unit symbol directly followed by digits ("m2", "m3"): an exponent, as in "kg/m3"
_TRAILING_EXPONENT = re.compile(r"(?<=[A-Za-zµΩ])(\d+)(?![\d.])")
# a value written with its unit: the number first (Python's float syntax), then the unit, spaced or not
_VALUE_WITH_UNIT = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*")


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


def value_in(text: str, si_unit: str) -> float:
    """The value ``text`` (a number and an optional unit: ``"20 um"``, ``"20um"``, ``"3 mrad"``, ``"25 degC"``,
    ``"2e-5"``) in ``si_unit``; a number without a unit is taken to be in ``si_unit`` already.

    Raises
    ------
    ValueError
        When the text is not a number with a unit, the unit is unknown, or it does not convert to ``si_unit``
        (naming both units and their dimensions).
    """
    match = _VALUE_WITH_UNIT.fullmatch(text)
    if match is None:
        raise ValueError(f"{text!r} is not a number with an optional unit, e.g. '20 um', '3 mrad' or '2e-5' "
                         f"(a number alone is in {si_unit})")
    number, unit = match.group(1), match.group(2)
    if not unit:
        return float(number)
    scale, offset = conversion(unit, si_unit)
    # in decimal, rounded once: "80 um" is 8e-05 to the bit, as a scene file's 8e-05 is (80 * 1e-6 in binary is not)
    with decimal.localcontext(prec=60):
        return float(decimal.Decimal(number) * decimal.Decimal(repr(scale)) + decimal.Decimal(repr(offset)))
