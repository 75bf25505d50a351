"""Generic analog force/torque channel: transducer, conditioner, output, DAQ.

The torque meter and both load cells share one signal chain (Sec. 9.3: the
force/torque signal "has been digitalised before being saved as simulation
result to simulate the measurement noise and the sensor characteristics"):

    measurand -> gain/offset errors (incl. temperature) -> volts
              -> optional first-order conditioner (preload, Table B.8)
              -> optional refresh sample-and-hold + output D/A (torque meter 1 kHz,
                 16 bit, Table B.5; external load cell 19.2 kHz, Table B.13)
              -> + electrical noise (Table 9.5) -> DAQ A/D -> engineering units

Only the parameter builders differ per sensor (``torque_meter.py``,
``load_cell.py``); the compiled functions here serve all three.

Lane form (``sensors.lanes``): parameters and state are ``[row, lane]`` arrays
(rows below, one column per lane); :func:`analog_init`, :func:`analog_step` and
:func:`analog_read` take ``(state, params, lane, ...)`` and act on column ``lane``,
branch-free (every case computed, the answer chosen by selects).

Parameter rows (float64, ``AN_SIZE``), built by :func:`analog_parameters` for
one lane, completed for the integration step by :func:`with_integration_step`:

==========================  ====================================================
``AN_FULL_SCALE``           measurand mapped to the output full scale [N or N*m]
``AN_OUTPUT_FULL_SCALE``    transducer/conditioner output full scale [V]
``AN_GAIN``                 effective relative sensitivity (1 + errors) [1]
``AN_OFFSET``               effective zero offset, fraction of full scale [1]
``AN_TAU``                  conditioner time constant [s], 0 = none
``AN_REFRESH_PERIOD``       output refresh period [s], 0 = continuous
``AN_OUTPUT_BITS``          output D/A word length (sign incl.), 0 = analog
``AN_DAQ_FULL_SCALE``       DAQ input range [V]
``AN_DAQ_BITS``             DAQ word length (sign incl.)
``AN_NOISE_HALF_WIDTH``     electrical-noise half width for this channel [V]
``AN_LAG_GAIN``             conditioner lag over one integration step,
                            ``1 - exp(-dt/tau)`` (NaN until the step is set)
``AN_LAG_TAU_OVER_DT``      ``tau / dt`` (NaN until the step is set)
==========================  ====================================================

State rows (float64, ``AS_SIZE``), set by :func:`analog_init`:

==========================  ====================================================
``AS_T``                    time of the last step [s]
``AS_INPUT``                transducer voltage at the last step [V]
``AS_FILTERED``             conditioner output at the last step [V]
``AS_NEXT_REFRESH``         index of the next refresh instant (``origin + index * period``) [-]
``AS_OUTPUT``               voltage presented to the DAQ [V]
``AS_REFRESH_ORIGIN``       time the refresh instants are counted from [s]
==========================  ====================================================
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numba
import numpy as np

from numerics.jit import SCALAR
from sensors.acquisition import convert, lag_gain, lag_step, validate_converter

AN_FULL_SCALE = 0
AN_OUTPUT_FULL_SCALE = 1
AN_GAIN = 2
AN_OFFSET = 3
AN_TAU = 4
AN_REFRESH_PERIOD = 5
AN_OUTPUT_BITS = 6
AN_DAQ_FULL_SCALE = 7
AN_DAQ_BITS = 8
AN_NOISE_HALF_WIDTH = 9
AN_LAG_GAIN = 10
AN_LAG_TAU_OVER_DT = 11
AN_SIZE = 12

AS_T = 0
AS_INPUT = 1
AS_FILTERED = 2
AS_NEXT_REFRESH = 3
AS_OUTPUT = 4
AS_REFRESH_ORIGIN = 5
AS_SIZE = 6


def analog_parameters(
    *,
    full_scale: float,
    output_full_scale: float,
    gain: float,
    offset: float,
    tau: float,
    refresh_period: float,
    output_bits: float,
    daq_full_scale: float,
    daq_bits: float,
    noise_half_width: float,
) -> np.ndarray:
    """Validate and pack one lane's channel parameters (rows in the module docstring).

    The conditioner's lag coefficients depend on the integration step and are left NaN here, so that a channel
    stepped before :func:`with_integration_step` reads NaN instead of a silently wrong lag.

    Raises
    ------
    ValueError
        Naming the offending field for a non-positive scale or gain, a negative
        time constant / refresh period / noise, or an invalid converter.
    """
    for name, value in (("full_scale", full_scale), ("output_full_scale", output_full_scale), ("gain", gain)):
        if not value > 0.0:
            raise ValueError(f"{name}: must be > 0, got {value!r}")
    for name, value in (("tau", tau), ("refresh_period", refresh_period), ("noise_half_width", noise_half_width)):
        if not value >= 0.0:
            raise ValueError(f"{name}: must be >= 0 (0 disables it), got {value!r}")
    if not math.isfinite(offset):
        raise ValueError(f"offset: must be finite, got {offset!r}")
    if output_bits != 0:
        validate_converter("output_bits", output_full_scale, output_bits)
    validate_converter("daq_bits", daq_full_scale, daq_bits)
    p = np.zeros(AN_SIZE)
    p[AN_FULL_SCALE] = full_scale
    p[AN_OUTPUT_FULL_SCALE] = output_full_scale
    p[AN_GAIN] = gain
    p[AN_OFFSET] = offset
    p[AN_TAU] = tau
    p[AN_REFRESH_PERIOD] = refresh_period
    p[AN_OUTPUT_BITS] = output_bits
    p[AN_DAQ_FULL_SCALE] = daq_full_scale
    p[AN_DAQ_BITS] = daq_bits
    p[AN_NOISE_HALF_WIDTH] = noise_half_width
    p[AN_LAG_GAIN] = np.nan
    p[AN_LAG_TAU_OVER_DT] = np.nan
    return p


def with_integration_step(p: np.ndarray, dt: float) -> np.ndarray:
    """A copy of channel parameters ``p`` (one lane's vector or a ``[row, lane]`` group) completed for a fixed
    integration step ``dt`` [s]: the conditioner's lag coefficients ``1 - exp(-dt/tau)`` (:func:`lag_gain`, the
    same function and bits as computing it at every step) and ``tau / dt``, so that no exponential runs per step.

    :func:`analog_step` then assumes that every step lasts ``dt`` (the fixed-step loop's ``t_k - t_(k-1)``,
    equal to ``dt`` up to the rounding of the clock); a caller with another step sets it again.
    """
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt: the integration step must be a finite time > 0 s, got {dt!r}")
    q = np.array(p, dtype=np.float64, copy=True)
    taus = q[AN_TAU].reshape(-1)
    gains = np.array([lag_gain(dt, float(tau)) for tau in taus])
    q[AN_LAG_GAIN] = gains.reshape(q[AN_LAG_GAIN].shape)
    q[AN_LAG_TAU_OVER_DT] = q[AN_TAU] / dt
    return q


@numba.njit(**SCALAR)
def transducer_voltage(params, lane, x):
    """Transducer output voltage of column ``lane`` for measurand ``x`` (before conditioning).

    ``V = V_FS * (gain * x / x_FS + offset)``: sensitivity errors and their
    temperature effect act on the gain (%Nom), zero errors and their
    temperature effect on the offset (%FS), Sec. 9.4.
    """
    gain, offset = params[AN_GAIN, lane], params[AN_OFFSET, lane]
    return params[AN_OUTPUT_FULL_SCALE, lane] * (gain * x / params[AN_FULL_SCALE, lane] + offset)


@numba.njit(**SCALAR)
def output_stage(params, lane, v):
    """Sensor-side output stage: the D/A if the sensor has one (``AN_OUTPUT_BITS > 0``), else the analog
    voltage ``v`` (a select: the conversion is computed either way)."""
    bits = params[AN_OUTPUT_BITS, lane]
    converted = convert(v, params[AN_OUTPUT_FULL_SCALE, lane], bits)
    return converted if bits > 0.0 else v


@numba.njit(**SCALAR)
def analog_init(state, params, lane, x0, t0):
    """Initialise column ``lane`` of ``state`` at time ``t0`` in steady state with measurand ``x0``.

    The output holds the converted ``x0`` and the next refresh is one period
    after ``t0``.
    """
    v = transducer_voltage(params, lane, x0)
    state[AS_T, lane] = t0
    state[AS_INPUT, lane] = v
    state[AS_FILTERED, lane] = v
    state[AS_REFRESH_ORIGIN, lane] = t0
    state[AS_NEXT_REFRESH, lane] = 1.0
    state[AS_OUTPUT, lane] = output_stage(params, lane, v)


@numba.njit(**SCALAR)
def analog_step(state, params, lane, x, t):
    """Advance column ``lane`` of the channel to time ``t`` where the true measurand is ``x``.

    Call at every integration step (call pattern (a)) of the step ``dt`` set by
    :func:`with_integration_step`. The conditioner is the exact first-order lag
    with the input linear over the step (:func:`sensors.acquisition.lag_step`,
    its coefficients precomputed). With a refresh period the output is a
    sample-and-hold of the (conditioned) signal taken at the refresh instants,
    linearly interpolated inside the step: a peak falling between two refresh
    instants is lost (Sec. 9.3, torque meter). If a step spans several refresh
    instants only the last one is visible. A refresh instant equal to the step's
    end ``t`` is taken in this step.

    Branch-free: the lag, the refresh and the held output are computed in every
    case and chosen by selects (no lag without a conditioner, no change for a
    step of zero length, the output refreshed when a refresh instant is due or
    continuously without a hold).

    Parameters
    ----------
    state : numpy.ndarray
        Channel states ``[AS_SIZE, L]``, column ``lane`` updated in place.
    params : numpy.ndarray
        Channel parameters ``[AN_SIZE, L]`` (:func:`analog_parameters`, :func:`with_integration_step`).
    lane : int
        Lane: the column of ``state`` and ``params`` this call reads and writes.
    x : float
        True measurand at ``t`` [N or N*m].
    t : float
        Time at the end of the step [s], > ``state[AS_T, lane]``.
    """
    # every value is loaded and computed first, the selects choose between scalars (a select between array
    # loads or calls would stay a branch: LLVM cannot speculate it, and the lane loop would not vectorise)
    t_prev = state[AS_T, lane]
    u_prev = state[AS_INPUT, lane]
    y_prev = state[AS_FILTERED, lane]
    origin = state[AS_REFRESH_ORIGIN, lane]
    next_index = state[AS_NEXT_REFRESH, lane]
    output_before = state[AS_OUTPUT, lane]
    tau = params[AN_TAU, lane]
    period = params[AN_REFRESH_PERIOD, lane]
    dt = t - t_prev
    u = transducer_voltage(params, lane, x)
    lagged = lag_step(y_prev, u_prev, u, params[AN_LAG_GAIN, lane], params[AN_LAG_TAU_OVER_DT, lane])
    lagged = lagged if dt > 0.0 else y_prev
    y = lagged if tau > 0.0 else u

    held = period > 0.0
    # The refresh instants are counted from the origin (origin + m * period, one rounding each), never accumulated:
    # the last instant at or before t is then the same whether the channel was stepped every step or only when due.
    last = np.floor((t - origin) / period)
    last = last + 1.0 if origin + (last + 1.0) * period <= t else last
    last = last - 1.0 if origin + last * period > t else last
    due = held & (last >= next_index)
    t_refresh = origin + last * period
    y_refresh = y_prev + (y - y_prev) * (t_refresh - t_prev) / dt
    y_refresh = y_refresh if dt > 0.0 else y
    presented = output_stage(params, lane, y_refresh if held else y)
    state[AS_OUTPUT, lane] = presented if (due | (not held)) else output_before
    state[AS_NEXT_REFRESH, lane] = last + 1.0 if due else next_index
    state[AS_T, lane] = t
    state[AS_INPUT, lane] = u
    state[AS_FILTERED, lane] = y


@numba.njit(**SCALAR)
def analog_read(state, params, lane, noise):
    """DAQ reading of column ``lane`` of the channel in engineering units (call pattern (b)).

    The output voltage plus one pre-drawn electrical-noise sample ``noise``
    [V] is converted by the DAQ and scaled back with the *nominal*
    sensitivity: the acquisition system does not know the sensor's errors.

    Parameters
    ----------
    state : numpy.ndarray
        Channel states ``[AS_SIZE, L]``, already stepped to the sample instant.
    params : numpy.ndarray
        Channel parameters ``[AN_SIZE, L]``.
    lane : int
        Lane: the column of ``state`` and ``params`` this call reads and writes.
    noise : float
        Noise sample [V], e.g. from :func:`sensors.acquisition.draw_uniform_noise`
        with half width ``params[AN_NOISE_HALF_WIDTH, lane]``.

    Returns
    -------
    float
        Measured value [N or N*m].
    """
    v = convert(state[AS_OUTPUT, lane] + noise, params[AN_DAQ_FULL_SCALE, lane], params[AN_DAQ_BITS, lane])
    return v * params[AN_FULL_SCALE, lane] / params[AN_OUTPUT_FULL_SCALE, lane]


def sensor_channel(
    values: Mapping[str, float],
    *,
    room_temperature: float,
    full_scale: float,
    output_full_scale: float,
    sensitivity_errors: Sequence[float],
    sensitivity_tempcos: Sequence[float],
    offsets: Sequence[float],
    offset_tempcos: Sequence[float],
    tau: float = 0.0,
    refresh_period: float = 0.0,
    output_bits: float = 0.0,
) -> np.ndarray:
    """Channel parameters of a force/torque sensor at a given room temperature.

    Sec. 9.4: "the overall sensitivity and offset of each sensor with respect
    to the temperature has been calculated as a function of the deviation of
    the room temperature from the nominal one of 25 °C". The error terms add
    (their products are second order, < 1e-5):

        gain   = 1 + sum(sensitivity_errors) + sum(sensitivity_tempcos) * dT
        offset =     sum(offsets)            + sum(offset_tempcos)      * dT

    with ``dT = room_temperature - sensors.reference_temperature`` [K]. The
    DAQ and the electrical noise come from the ``sensors`` group (``values``,
    as given to :func:`sensors.parameters.sensor_values`).
    """
    if not (math.isfinite(room_temperature) and room_temperature > 0.0):
        raise ValueError(f"room_temperature: must be a finite absolute temperature > 0 K, got {room_temperature!r}")
    delta_t = room_temperature - values["sensors.reference_temperature"]
    return analog_parameters(
        full_scale=full_scale,
        output_full_scale=output_full_scale,
        gain=1.0 + sum(sensitivity_errors) + sum(sensitivity_tempcos) * delta_t,
        offset=sum(offsets) + sum(offset_tempcos) * delta_t,
        tau=tau,
        refresh_period=refresh_period,
        output_bits=output_bits,
        daq_full_scale=values["sensors.daq_full_scale"],
        daq_bits=values["sensors.daq_bits"],
        noise_half_width=values["sensors.electrical_noise_half_width"] * output_full_scale,
    )


def select_range(values: Mapping[str, float], name: str) -> int:
    """The measuring range (1 or 2) selected by parameter ``name``."""
    selected = values[name]
    if selected not in (1.0, 2.0):
        raise ValueError(f"{name}: measuring range must be 1 or 2, got {selected!r}")
    return int(selected)
