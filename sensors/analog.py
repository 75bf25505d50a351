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

Parameter array layout (float64, length ``AN_SIZE``), built by
:func:`analog_parameters`:

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
==========================  ====================================================

State array layout (float64, length ``AS_SIZE``), set by :func:`analog_init`:

==========================  ====================================================
``AS_T``                    time of the last step [s]
``AS_INPUT``                transducer voltage at the last step [V]
``AS_FILTERED``             conditioner output at the last step [V]
``AS_NEXT_REFRESH``         next refresh instant [s]
``AS_OUTPUT``               voltage presented to the DAQ [V]
==========================  ====================================================
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numba
import numpy as np

from sensors.acquisition import convert, first_order_lag, validate_converter

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
AN_SIZE = 10

AS_T = 0
AS_INPUT = 1
AS_FILTERED = 2
AS_NEXT_REFRESH = 3
AS_OUTPUT = 4
AS_SIZE = 5


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
    """Validate and pack an analog channel's parameters (layout in the module docstring).

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
    return p


@numba.njit(cache=True)
def transducer_voltage(x, p):
    """Transducer output voltage for measurand ``x`` (before conditioning).

    ``V = V_FS * (gain * x / x_FS + offset)``: sensitivity errors and their
    temperature effect act on the gain (%Nom), zero errors and their
    temperature effect on the offset (%FS), Sec. 9.4.
    """
    return p[AN_OUTPUT_FULL_SCALE] * (p[AN_GAIN] * x / p[AN_FULL_SCALE] + p[AN_OFFSET])


@numba.njit(cache=True)
def _output(v, p):
    """Sensor-side output stage: the D/A if the sensor has one, else the analog voltage."""
    if p[AN_OUTPUT_BITS] > 0.0:
        return convert(v, p[AN_OUTPUT_FULL_SCALE], p[AN_OUTPUT_BITS])
    return v


@numba.njit(cache=True)
def analog_init(state, x0, t0, p):
    """Initialise ``state`` at time ``t0`` in steady state with measurand ``x0``.

    The output holds the converted ``x0`` and the next refresh is one period
    after ``t0``.
    """
    v = transducer_voltage(x0, p)
    state[AS_T] = t0
    state[AS_INPUT] = v
    state[AS_FILTERED] = v
    state[AS_NEXT_REFRESH] = t0 + p[AN_REFRESH_PERIOD]
    state[AS_OUTPUT] = _output(v, p)


@numba.njit(cache=True)
def analog_step(state, x, t, p):
    """Advance the channel to time ``t`` where the true measurand is ``x``.

    Call at every integration step (call pattern (a)). With a refresh period
    the output is a sample-and-hold of the (conditioned) signal taken at the
    refresh instants, linearly interpolated inside the step: a peak falling
    between two refresh instants is lost (Sec. 9.3, torque meter). If a step
    spans several refresh instants only the last one is visible.

    Parameters
    ----------
    state : numpy.ndarray
        Channel state (layout in the module docstring), updated in place.
    x : float
        True measurand at ``t`` [N or N*m].
    t : float
        Time at the end of the step [s], > ``state[AS_T]``.
    p : numpy.ndarray
        Channel parameters from :func:`analog_parameters`.
    """
    t_prev = state[AS_T]
    dt = t - t_prev
    u = transducer_voltage(x, p)
    y_prev = state[AS_FILTERED]
    if p[AN_TAU] > 0.0:
        y = first_order_lag(y_prev, state[AS_INPUT], u, dt, p[AN_TAU])
    else:
        y = u
    period = p[AN_REFRESH_PERIOD]
    if period > 0.0:
        t_next = state[AS_NEXT_REFRESH]
        if t >= t_next:
            n_refresh = math.floor((t - t_next) / period) + 1.0
            t_refresh = t_next + (n_refresh - 1.0) * period
            y_refresh = y_prev + (y - y_prev) * (t_refresh - t_prev) / dt if dt > 0.0 else y
            state[AS_OUTPUT] = _output(y_refresh, p)
            state[AS_NEXT_REFRESH] = t_next + n_refresh * period
    else:
        state[AS_OUTPUT] = _output(y, p)
    state[AS_T] = t
    state[AS_INPUT] = u
    state[AS_FILTERED] = y


@numba.njit(cache=True)
def analog_read(state, noise, p):
    """DAQ reading of the channel in engineering units (call pattern (b)).

    The output voltage plus one pre-drawn electrical-noise sample ``noise``
    [V] is converted by the DAQ and scaled back with the *nominal*
    sensitivity: the acquisition system does not know the sensor's errors.

    Parameters
    ----------
    state : numpy.ndarray
        Channel state, already stepped to the sample instant.
    noise : float
        Noise sample [V], e.g. from :func:`sensors.acquisition.draw_uniform_noise`
        with half width ``p[AN_NOISE_HALF_WIDTH]``.
    p : numpy.ndarray
        Channel parameters.

    Returns
    -------
    float
        Measured value [N or N*m].
    """
    v = convert(state[AS_OUTPUT] + noise, p[AN_DAQ_FULL_SCALE], p[AN_DAQ_BITS])
    return v * p[AN_FULL_SCALE] / p[AN_OUTPUT_FULL_SCALE]


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
