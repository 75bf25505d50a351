"""Signal-chain primitives shared by every sensor model.

A/D and D/A conversion (one mid-tread quantiser), the first-order lag used by
the Hall current sensor and the preload conditioner, the uniform electrical
noise of Table 9.5 and the convention that turns a Table 9.5 "± range,
Gaussian" row into a standard deviation.

Sources: Sec. 9.3 ("the force/torque signal ... has been digitalised ... to
simulate the measurement noise and the sensor characteristics effect on the
read signal resolution"), Sec. 9.4 and Table 9.5 (electrical noise ±2.5 %FS,
uniform), Table B.3 (drive analog input 11 bits + sign, ±10 V), Table B.5
(torque-meter 16-bit D/A). Conventions are documented in ``docs/sensors.md``.

The compiled functions are scalar laws of floats (``numerics.jit.SCALAR``: inlined into their caller, IEEE
division), branch-free in their data and free of libm calls, so a loop over lanes that calls them vectorises and
gives every lane the same bits whatever its lane mates (``sensors.lanes``).
"""

from __future__ import annotations

import numba
import numpy as np

from numerics.elementary import SHIFTER, SHIFTER_BITS, as_int, expm1, pow2i
from numerics.jit import SCALAR

#: A Table 9.5 Gaussian "± range" is read as ± this many standard deviations.
RANGE_SIGMAS = 3.0


@numba.njit(**SCALAR)
def quantize(value, lsb):
    """Mid-tread quantisation of ``value`` to a multiple of ``lsb``.

    Mid-tread (zero is a reconstruction level) is the transfer function of
    bipolar converters and resolver-to-digital converters: a zero input reads
    exactly zero and the error is bounded by ±lsb/2. Ties round towards
    +inf (``floor(x + 1/2)``), one fixed code transition, not to even.

    Parameters
    ----------
    value : float
        Input in any unit.
    lsb : float
        Quantisation step, > 0, same unit.

    Returns
    -------
    float
        ``lsb * floor(value / lsb + 1/2)``. ``np.floor``, not ``math.floor``:
        numba's ``math.floor`` returns an int64 (a float->int conversion,
        garbage beyond 2^63 and for NaN, and no single vector instruction);
        ``np.floor`` stays a float (exact, vectorises). NaN stays NaN.
    """
    return lsb * np.floor(value / lsb + 0.5)


@numba.njit(**SCALAR)
def power_of_two(n):
    """``2**n`` for an integer-valued float ``-1022 <= n <= 1023``, exactly.

    No ``pow`` call (a libm call would stop a lane loop from vectorising) and no float->int value conversion:
    the low bits of ``n + 1.5*2^52`` are the integer ``n`` (the shifter of :mod:`numerics.elementary`), read by a
    bit cast, and :func:`numerics.elementary.pow2i` builds the power from its exponent bits.
    """
    return pow2i(as_int(n + SHIFTER) - SHIFTER_BITS)


@numba.njit(**SCALAR)
def converter_lsb(full_scale, bits):
    """Step of a bipolar converter of ``bits`` bits (sign included) over ±``full_scale``:
    ``full_scale / 2**(bits - 1)``."""
    return full_scale / power_of_two(bits - 1.0)


@numba.njit(**SCALAR)
def convert(value, full_scale, bits):
    """Bipolar A/D or D/A conversion: saturation then mid-tread quantisation.

    A two's-complement converter of ``bits`` bits (sign included) over
    ±``full_scale`` has ``lsb = full_scale / 2**(bits - 1)`` and codes
    ``-2**(bits-1) .. 2**(bits-1) - 1``; inputs beyond the range saturate at
    the extreme codes. Table B.3's "11 bits + sign" is ``bits = 12``; the
    torque meter's 16-bit D/A (Table B.5) is ``bits = 16``.

    Parameters
    ----------
    value : float
        Input [V] (or any unit consistent with ``full_scale``).
    full_scale : float
        Half range of the converter, > 0 (10 V for every channel of the bench).
    bits : float
        Word length including the sign bit, integer-valued, 2 ... 1023.

    Returns
    -------
    float
        The reconstructed (converted) value; NaN for a NaN input (a diverged
        signal is not a reading: it is not saturated into a code).
    """
    lsb = converter_lsb(full_scale, bits)
    level = quantize(value, lsb)
    saturated = min(max(level, -full_scale), full_scale - lsb)
    return level if level != level else saturated


@numba.njit(**SCALAR)
def lag_gain(dt, tau):
    """``1 - exp(-dt / tau)``: the fraction of a step input a first-order lag of time constant ``tau`` reaches
    in ``dt`` (accurate for ``dt << tau``: computed as ``-expm1(-dt / tau)``, :mod:`numerics.elementary`)."""
    # tau = 0 (no conditioner): 1 exactly, as -expm1(-inf) gives in compiled code, without dividing by zero in
    # plain Python (NUMBA_DISABLE_JIT)
    return -expm1(-dt / tau) if tau > 0.0 else 1.0


@numba.njit(**SCALAR)
def lag_step(y0, u0, u1, gain, tau_over_dt):
    """Exact discretisation of ``tau dy/dt + y = u`` over one step, from its coefficients.

    With the input linear between its step-end values ``u0`` and ``u1``:

        y1 = u1 + a (y0 - u0) - (u1 - u0) (tau / dt) (1 - a),  a = exp(-dt / tau)

    ``gain`` is ``1 - a`` (:func:`lag_gain`) and ``tau_over_dt`` is ``tau / dt``; a caller with a fixed step
    computes both once (``sensors.analog``), :func:`first_order_lag` computes them per call.
    """
    return u1 + (1.0 - gain) * (y0 - u0) - (u1 - u0) * tau_over_dt * gain


@numba.njit(**SCALAR)
def first_order_lag(y0, u0, u1, dt, tau):
    """Exact discretisation of ``tau dy/dt + y = u`` over one step.

    The input is taken linear between its step-end values ``u0`` and ``u1``
    (first-order hold), which is exact for the piecewise-linear input the
    integrator produces and keeps the correct ramp lag ``tau du/dt`` even
    when ``dt >> tau``:

        y1 = u1 + a (y0 - u0) - (u1 - u0) (tau / dt) (1 - a),  a = exp(-dt / tau)

    Used for the Hall current sensor (Sec. 9.3, "a simple first order transfer
    function") and the preload conditioner (Table B.8, 10 kHz cut-off). The law
    is :func:`lag_step`; branch-free (a select returns ``y0`` for ``dt <= 0``).

    Parameters
    ----------
    y0 : float
        Output at the start of the step.
    u0, u1 : float
        Input at the start and end of the step.
    dt : float
        Step [s]; ``dt <= 0`` returns ``y0`` unchanged.
    tau : float
        Time constant [s], > 0.

    Returns
    -------
    float
        Output at the end of the step.
    """
    y1 = lag_step(y0, u0, u1, lag_gain(dt, tau), tau / dt)
    return y1 if dt > 0.0 else y0


def validate_converter(name: str, full_scale: float, bits: float) -> None:
    """Check a converter's range and word length.

    Raises
    ------
    ValueError
        Naming ``name`` if ``full_scale <= 0`` or ``bits`` is not an integer >= 2.
    """
    if not full_scale > 0.0:
        raise ValueError(f"{name}: full scale must be > 0 V, got {full_scale!r}")
    if not (float(bits).is_integer() and bits >= 2):
        raise ValueError(f"{name}: bits must be an integer >= 2 (sign included), got {bits!r}")


def draw_uniform_noise(rng: np.random.Generator, n: int, half_width: float) -> np.ndarray:
    """Pre-draw ``n`` samples of uniform electrical noise in ±``half_width``.

    Table 9.5 ("Electrical noise ±2.5 %FS, U"): for a ±10 V channel
    ``half_width = 0.025 * 10 V``. The compiled loop consumes one sample per
    reading; drawing from the caller's Generator makes a run reproducible from
    its seed.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of randomness, owned by the caller.
    n : int
        Number of samples, >= 0.
    half_width : float
        Half width of the support, >= 0 (same unit as the signal, e.g. V).

    Returns
    -------
    numpy.ndarray
        float64 array of shape ``(n,)``.
    """
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng: expected numpy.random.Generator, got {type(rng).__name__}")
    if int(n) != n or n < 0:
        raise ValueError(f"n: number of noise samples must be an integer >= 0, got {n!r}")
    if not half_width >= 0.0:
        raise ValueError(f"half_width: must be >= 0, got {half_width!r}")
    return rng.uniform(-half_width, half_width, size=int(n))


def sigma_from_range(half_range: float) -> float:
    """Standard deviation of a Table 9.5 Gaussian row from its ± half range.

    Convention (``docs/sensors.md``): a datasheet tolerance ±h is a guaranteed
    acceptance limit and is read as ±3 sigma, so ``sigma = h / 3``; the
    campaign truncates sensor error draws at ±h (``truncated_gaussian``),
    which removes 0.27 % of the mass and keeps every value inside the
    parameter bounds.
    """
    if not half_range >= 0.0:
        raise ValueError(f"half_range: must be >= 0, got {half_range!r}")
    return half_range / RANGE_SIGMAS

