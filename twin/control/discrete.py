"""Discrete-time PI controller with anti-windup, as run by the drive and the cRIO."""

import numba

from numerics.jit import SCALAR


@numba.njit(**SCALAR)
def pi_step(error, integral, kp, ki, sample_time, limit):
    """One sample of a PI controller with output saturation and conditional-integration anti-windup.

    ``u = kp e + I``; the output is clamped to ``+/-limit``; the integral
    ``I += ki e T`` is only accumulated when that does not push a saturated
    output further into saturation (Astrom & Hagglund, *Advanced PID Control*,
    2006, Sec. 3.5).

    Returns
    -------
    (output, new_integral)
    """
    unsaturated = kp * error + integral
    output = min(max(unsaturated, -limit), limit)
    if output == unsaturated or (unsaturated > 0.0) != (error > 0.0):
        integral += ki * error * sample_time
    return output, integral
