"""Units of a campaign spec and of measured channels: parsed by a units library, and the ±range convention.

Inside the model every value is SI; a spec row may be given in a handier unit (``um``, ``degC``, ``%``, ``kg m^2``)
and a measured channel in the unit its file states (``mm``, ``deg``, ``N m``). :func:`conversion` turns any unit
pint understands into the SI unit a parameter, condition or signal is stored in, as ``si = value * scale + offset``.
Spellings engineers write that pint alone does not read are normalised first (:func:`normalise`): ``kg·m²``,
``kg m2``, ``kg*m^2``, ``kg*m**2`` and ``kg m^2`` are the same unit.
"""

from __future__ import annotations

import functools
import re

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


@functools.cache
def conversion(unit: str, si_unit: str) -> tuple[float, float]:
    """``(scale, offset)`` with ``si = value * scale + offset`` from ``unit`` to ``si_unit``.

    Offsets (``degC`` to ``K``) apply to absolute values only, never to half ranges or sigmas.

    Raises
    ------
    ValueError
        Naming the unit that is not understood, or both units when they do not convert (different dimensions).
    """
    import pint  # lazy: start-up cost (the registry is built on first use)

    ureg = registry()
    parsed = {}
    for text in (unit, si_unit):
        try:
            parsed[text] = ureg.parse_units(normalise(text)) if text.strip() not in ("", "1") else ureg.dimensionless
        except (pint.errors.PintError, ValueError, TypeError, AttributeError, SyntaxError) as exc:
            raise ValueError(f"unknown unit {text!r} ({type(exc).__name__}); e.g. {EXAMPLES}") from None
    try:
        zero = ureg.Quantity(0.0, parsed[unit]).to(parsed[si_unit]).magnitude
        one = ureg.Quantity(1.0, parsed[unit]).to(parsed[si_unit]).magnitude
    except pint.errors.DimensionalityError:
        raise ValueError(f"unit {unit!r} does not convert to {si_unit!r} (the target's SI unit): "
                         f"{ureg.Quantity(1.0, parsed[unit]).dimensionality} is not "
                         f"{ureg.Quantity(1.0, parsed[si_unit]).dimensionality}") from None
    return float(one - zero), float(zero)


def known_unit(unit: str) -> bool:
    """Whether pint reads ``unit`` (after :func:`normalise`)."""
    try:
        conversion(unit, unit)
    except ValueError:
        return False
    return True
