"""Motor resolver angle reading (Table 9.5 "Motor resolver").

Resolution 0.8' (constant), accuracy ±10' and offset ±0.02 %FS (Gaussian).
The accuracy is modelled as a deterministic error of that amplitude at
``h`` cycles per revolution, ``h = 2`` by default: amplitude imbalance and
imperfect quadrature of the sine/cosine windings both produce a
twice-per-revolution angle error, the dominant term of a resolver's error
curve. The offset is a fraction of the full scale, one revolution (2 pi rad).
The resolver-to-digital output is mid-tread quantised to the resolution.

Mounting angle (issue 33; an extension of Table 9.5, the thesis is silent): the
accuracy error and the R/D quantisation grid are fixed to the rotor, while the
test measures the motor angle ``theta`` from wherever the rotor stood at its
start. With the rotor at the absolute angle ``phi`` at the start, the R/D reads
``quantize(theta + phi + offset + accuracy sin(h (theta + phi)))`` and the drive
uses it less the constant ``phi`` (its speed loop differentiates the angle, so
the constant cancels); ``phi`` sets where along the test the error harmonic and
the grid fall. ``phi = 0`` is the reading of a rotor that starts at zero.

Parameter rows (float64, ``RES_SIZE``) from :func:`resolver_parameters`, one
column per lane (``sensors.lanes``): ``RES_RESOLUTION`` [rad], ``RES_ACCURACY``
amplitude [rad], ``RES_OFFSET`` [rad], ``RES_HARMONIC`` error cycles per
revolution, ``RES_MOUNTING_ANGLE`` absolute rotor angle at the start [rad].
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numba
import numpy as np

from numerics.elementary import sin
from numerics.jit import SCALAR
from sensors.acquisition import quantize
from sensors.parameters import sensor_values

RES_RESOLUTION = 0
RES_ACCURACY = 1
RES_OFFSET = 2
RES_HARMONIC = 3
RES_MOUNTING_ANGLE = 4
RES_SIZE = 5


def resolver_parameters(params: Mapping[str, float]) -> np.ndarray:
    """One lane's parameter vector of the motor resolver from the ``sensors`` group."""
    v = sensor_values(params)
    harmonic = v["sensors.resolver_error_harmonic"]
    if not float(harmonic).is_integer():
        raise ValueError(f"sensors.resolver_error_harmonic: must be an integer, got {harmonic!r}")
    mounting = v["sensors.resolver_mounting_angle"]
    if not 0.0 <= mounting <= 2.0 * math.pi:
        raise ValueError(f"sensors.resolver_mounting_angle: must be in [0, 2 pi] rad, got {mounting!r}")
    p = np.zeros(RES_SIZE)
    p[RES_RESOLUTION] = v["sensors.resolver_resolution"]
    p[RES_ACCURACY] = v["sensors.resolver_accuracy"]
    p[RES_OFFSET] = v["sensors.resolver_offset"] * 2.0 * math.pi
    p[RES_HARMONIC] = harmonic
    p[RES_MOUNTING_ANGLE] = mounting
    return p


@numba.njit(**SCALAR)
def resolver_angle(params, lane, theta):
    """Measured motor angle [rad] of column ``lane`` for the true mechanical angle ``theta`` [rad] since the start.

    ``quantize(rotor + offset + accuracy * sin(h * rotor), resolution) - phi`` with ``rotor = theta + phi``,
    ``phi`` the mounting angle (module docstring); multi-turn (not wrapped), as the drive tracks whole
    revolutions. ``sin`` is :func:`numerics.elementary.sin` (the same bits on every CPU and in a vector loop).
    """
    mounting = params[RES_MOUNTING_ANGLE, lane]
    rotor = theta + mounting
    error = params[RES_OFFSET, lane] + params[RES_ACCURACY, lane] * sin(params[RES_HARMONIC, lane] * rotor)
    return quantize(rotor + error, params[RES_RESOLUTION, lane]) - mounting
