"""Motor resolver angle reading (Table 9.5 "Motor resolver").

Resolution 0.8' (constant), accuracy ±10' and offset ±0.02 %FS (Gaussian).
The accuracy is modelled as a deterministic error of that amplitude at
``h`` cycles per revolution, ``h = 2`` by default: amplitude imbalance and
imperfect quadrature of the sine/cosine windings both produce a
twice-per-revolution angle error, the dominant term of a resolver's error
curve. The offset is a fraction of the full scale, one revolution (2 pi rad).
The resolver-to-digital output is mid-tread quantised to the resolution.

Parameter array (float64, length ``RES_SIZE``) from :func:`resolver_parameters`:
``RES_RESOLUTION`` [rad], ``RES_ACCURACY`` amplitude [rad], ``RES_OFFSET``
[rad], ``RES_HARMONIC`` error cycles per revolution.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numba
import numpy as np

from sensors.acquisition import quantize
from sensors.parameters import sensor_values

RES_RESOLUTION = 0
RES_ACCURACY = 1
RES_OFFSET = 2
RES_HARMONIC = 3
RES_SIZE = 4


def resolver_parameters(params: Mapping[str, float]) -> np.ndarray:
    """Parameter array of the motor resolver from the ``sensors`` group."""
    v = sensor_values(params)
    harmonic = v["sensors.resolver_error_harmonic"]
    if not float(harmonic).is_integer():
        raise ValueError(f"sensors.resolver_error_harmonic: must be an integer, got {harmonic!r}")
    p = np.zeros(RES_SIZE)
    p[RES_RESOLUTION] = v["sensors.resolver_resolution"]
    p[RES_ACCURACY] = v["sensors.resolver_accuracy"]
    p[RES_OFFSET] = v["sensors.resolver_offset"] * 2.0 * math.pi
    p[RES_HARMONIC] = harmonic
    return p


@numba.njit(cache=True)
def resolver_angle(theta, p):
    """Measured motor angle [rad] for true mechanical angle ``theta`` [rad].

    ``quantize(theta + offset + accuracy * sin(h * theta), resolution)``;
    multi-turn (not wrapped), as the drive tracks whole revolutions.
    """
    error = p[RES_OFFSET] + p[RES_ACCURACY] * math.sin(p[RES_HARMONIC] * theta)
    return quantize(theta + error, p[RES_RESOLUTION])
