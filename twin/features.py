"""Scalar backlash features of a run: declared once, accumulated at the acquisition instants, finished after the run.

Both features are built from the same signal as Eq. 9.12, the nut-to-screw difference at the
acquisition instants ``t_k`` (the 1 ms position-loop/acquisition period)::

    d_k = x_n1(t_k) - p theta_s(t_k) / (2 pi)

taken from the linear encoder and the torque-meter encoder (the measured features) or from the
states (``*_true``), each zeroed by the scene's zero procedure (:data:`twin.scenes.ZERO_PROCEDURES`).

``backlash_feature`` (Eq. 9.12)
    ``f_b = (1/N) sum_k |d_k|``. The absolute value makes it depend on where the encoders were
    zeroed: zeroed with the nut centred in its backlash, a free nut reads ``~b/2``; zeroed on a
    preloaded flank, ``~0``.
``backlash_hysteresis``
    The width of the hysteresis loop of ``d`` against the screw position (Fig. 5.12, 7.18d: "the
    backlash can be visualised by means of an hysteresis loop")::

        H = mean(d_k | screw moving -) - mean(d_k | screw moving +)

    where sample ``k`` is "moving +" when the screw equivalent position advanced by more than
    ``v_min T`` since the previous sample (``-`` when it retreated by more) and samples in between
    (holds, reversals) are left out. A screw that drives a free nut through friction keeps it on
    its trailing flank, ``d = -b/2`` moving +, ``+b/2`` moving -, so ``H ~ b``, plus twice the
    deflection of the chain under the friction force, minus the share of moving samples in which
    the nut is still crossing the gap after a reversal. A zero shifts every ``d_k`` by the same
    constant, which cancels in the difference of the two means: ``H`` does not depend on where,
    or how, the encoders were zeroed. NaN when the screw never moved both ways.
``drag_torque_feature`` (preload observability, beyond the thesis)
    Half the width of the torque hysteresis over the constant-speed segments::

        T_d = [mean(T_k | screw moving + at constant speed) - mean(T_k | moving - at constant speed)] / 2

    from the torque meter (or the true transmitted torque, ``_true``). A sample is "at constant
    speed" when the screw moved by more than ``v_min T`` since the previous sample and its step
    differs from the previous step by less than ``CONSTANT_SPEED_TOLERANCE`` of it, so the inertial
    torque of the accelerations is left out. The friction torques that oppose the rotation (the
    ball-groove drag of both nuts, which grows with the preload, Eqs. 5.17-5.24 and 7.85; the
    bearings; the guide and seal friction reflected through ``p/2pi``) change sign with the motion,
    a constant load torque and the torque meter's offset do not: the half difference keeps the
    former and cancels the latter. NaN when the screw never moved both ways at constant speed.

The features are accumulated with a few additions per acquisition instant (never per integration
step) by :func:`accumulate` and finished by :func:`finish`; the compiled loop, the scipy reference
path, :func:`twin.simulate` and the campaigns' catalog (``campaigns.bench.adapter``) all use this module.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

import numba
import numpy as np

#: Smallest screw speed that counts as motion for the hysteresis [m/s]: well below the nominal
#: profile's commanded speeds (20 mm/s ramp, 31 mm/s sinusoid peak), above the position loop's
#: dither at a hold; 1 um per 1 ms sample is 1.6 counts of the torque-meter encoder (0.625 um).
MOTION_SPEED_THRESHOLD = 1.0e-3
#: Largest relative change of the screw's step between two acquisition samples that counts as constant
#: speed for ``drag_torque_feature`` (1 %: at 1 ms samples, an acceleration below 10 (m/s^2)/(m/s) of speed,
#: i.e. the sinusoid's crests and the ramps' plateaus of the thesis profiles, not their starts and stops).
CONSTANT_SPEED_TOLERANCE = 0.01


@dataclass(frozen=True)
class Feature:
    """A scalar feature of a run: unit, long name, and what it is computed from."""

    unit: str
    long_name: str
    description: str


_D = "d = x_n1 - p*theta_s/(2*pi) at the acquisition instants"
_SOURCES = {"": "the linear encoder and the torque-meter encoder", "_true": "the true states"}
_TORQUE_SOURCES = {"": "the torque meter", "_true": "the true transmitted torque"}

#: Every feature of a run, name -> declaration (``twin.simulate`` outputs, campaign features).
FEATURES: dict[str, Feature] = {
    **{f"backlash_feature{suffix}": Feature(
        "m", f"backlash feature f_b of Eq. 9.12 from {source}",
        f"mean over the acquisition samples of |d|, {_D}, both encoders zeroed by the scene's zero_procedure")
       for suffix, source in _SOURCES.items()},
    **{f"backlash_hysteresis{suffix}": Feature(
        "m", f"backlash hysteresis width from {source}",
        f"mean of d while the screw moves - minus its mean while it moves +, {_D}; samples below "
        f"{MOTION_SPEED_THRESHOLD * 1e3:g} mm/s of screw speed left out; independent of the encoder zero")
       for suffix, source in _SOURCES.items()},
    **{f"drag_torque_feature{suffix}": Feature(
        "N m", f"half width of the torque hysteresis at constant speed from {source}",
        f"(mean torque while the screw moves + at constant speed - mean while it moves - at constant speed) / 2 at "
        f"the acquisition instants; constant speed: step above {MOTION_SPEED_THRESHOLD * 1e3:g} mm/s of screw speed "
        f"and within {CONSTANT_SPEED_TOLERANCE * 100:g} % of the previous step; the friction torques opposing the "
        f"rotation (ball-groove drag, which grows with the preload; bearings; guides) without load or offset")
       for suffix, source in _TORQUE_SOURCES.items()},
}


class A(IntEnum):
    """Accumulators of one signal source (true or measured) in the loop memory."""

    SUM_ABS = 0          # sum of |d| (Eq. 9.12)
    SUM_UP = 1           # sum of d while the screw moves +
    COUNT_UP = 2
    SUM_DOWN = 3         # sum of d while the screw moves -
    COUNT_DOWN = 4
    PREVIOUS_SCREW = 5   # screw equivalent position at the previous acquisition [m]
    SUM_TORQUE_UP = 6    # sum of the torque while the screw moves + at constant speed
    COUNT_TORQUE_UP = 7
    SUM_TORQUE_DOWN = 8  # sum of the torque while the screw moves - at constant speed
    COUNT_TORQUE_DOWN = 9
    PREVIOUS_STEP = 10   # screw travel between the two previous acquisitions [m]


N_ACCUMULATORS = len(A)


@numba.njit(cache=True)
def accumulate(acc, sled, screw, torque, first, threshold):
    """Add one acquisition sample: sled position and screw equivalent position ``p theta_s / 2 pi`` [m],
    torque on the screw [N m].

    ``acc`` is the accumulator block (layout :class:`A`); ``first`` marks the first sample (no
    previous screw position); ``threshold`` is the screw travel per sample that counts as motion [m].
    """
    d = sled - screw
    acc[A.SUM_ABS] += abs(d)
    step = 0.0
    if not first:
        step = screw - acc[A.PREVIOUS_SCREW]
        if step > threshold:
            acc[A.SUM_UP] += d
            acc[A.COUNT_UP] += 1.0
        elif step < -threshold:
            acc[A.SUM_DOWN] += d
            acc[A.COUNT_DOWN] += 1.0
        if abs(step) > threshold and abs(step - acc[A.PREVIOUS_STEP]) < CONSTANT_SPEED_TOLERANCE * abs(step):
            if step > 0.0:
                acc[A.SUM_TORQUE_UP] += torque
                acc[A.COUNT_TORQUE_UP] += 1.0
            else:
                acc[A.SUM_TORQUE_DOWN] += torque
                acc[A.COUNT_TORQUE_DOWN] += 1.0
    acc[A.PREVIOUS_SCREW] = screw
    acc[A.PREVIOUS_STEP] = step


def finish(acc: np.ndarray, samples: float) -> dict[str, float]:
    """``{"backlash_feature": f_b, "backlash_hysteresis": H}`` [m] and ``{"drag_torque_feature": T_d}`` [N m]
    from one accumulator block after ``samples`` acquisition instants (NaN where there is nothing to average)."""
    feature = acc[A.SUM_ABS] / samples if samples > 0 else math.nan
    moved_both_ways = acc[A.COUNT_UP] > 0 and acc[A.COUNT_DOWN] > 0
    hysteresis = (acc[A.SUM_DOWN] / acc[A.COUNT_DOWN] - acc[A.SUM_UP] / acc[A.COUNT_UP]
                  if moved_both_ways else math.nan)
    turned_both_ways = acc[A.COUNT_TORQUE_UP] > 0 and acc[A.COUNT_TORQUE_DOWN] > 0
    drag = (0.5 * (acc[A.SUM_TORQUE_UP] / acc[A.COUNT_TORQUE_UP] - acc[A.SUM_TORQUE_DOWN] / acc[A.COUNT_TORQUE_DOWN])
            if turned_both_ways else math.nan)
    return {"backlash_feature": float(feature), "backlash_hysteresis": float(hysteresis),
            "drag_torque_feature": float(drag)}
