"""Units of a campaign spec: the units a row of the uncertainty table may use, and the ±range convention.

Inside the model every value is SI; a spec may give a row in a handier unit (``um``, ``degC``, ``%``), which
:mod:`campaigns.ranges` converts with this table.
"""

from __future__ import annotations

import math

#: A datasheet "± range" read as a Gaussian is taken to hold ±3 sigma.
#: Datasheets quote tolerance bands that practically every unit meets; ±3 sigma
#: covers 99.73 % of a normal population, which is the usual convention for such
#: limits (and the one that keeps the sampled values inside the band almost
#: always). This is the only place the factor is defined.
HALF_RANGE_SIGMAS = 3.0

#: Spec unit -> (SI unit, scale, offset): ``si = value * scale + offset``.
#: Offsets apply to absolute values only, never to half ranges or sigmas.
UNITS: dict[str, tuple[str, float, float]] = {
    "m": ("m", 1.0, 0.0),
    "mm": ("m", 1e-3, 0.0),
    "um": ("m", 1e-6, 0.0),
    "µm": ("m", 1e-6, 0.0),
    "rad": ("rad", 1.0, 0.0),
    "deg": ("rad", math.pi / 180.0, 0.0),
    "arcmin": ("rad", math.pi / 10800.0, 0.0),
    "K": ("K", 1.0, 0.0),
    "degC": ("K", 1.0, 273.15),
    "Pa": ("Pa", 1.0, 0.0),
    "bar": ("Pa", 1e5, 0.0),
    "N": ("N", 1.0, 0.0),
    "kN": ("N", 1e3, 0.0),
    "1": ("1", 1.0, 0.0),
    "%": ("1", 1e-2, 0.0),
    "1/K": ("1/K", 1.0, 0.0),
    "%/K": ("1/K", 1e-2, 0.0),
}
