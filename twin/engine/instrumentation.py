"""The bench's instruments inside the compiled loop: what the controller and the DAQ read.

Wires the measurement models of :mod:`sensors` to the bench state. Every
instrument has a fidelity level (Sec. 9.3, Table 9.5):

``ideal`` (0)
    the true signal.
``quantized`` (1)
    resolutions, converters and refresh/filters, no errors and no noise.
``full`` (2)
    edge-accurate encoders with their phase/asymmetry/precision errors, the
    sensitivity, offset and temperature errors of the analog channels, and the
    electrical noise of Table 9.5 drawn from the caller's Generator.

Instruments and what they measure:

=======================  ==========================  ==========================================
instrument               measurand                   used by
=======================  ==========================  ==========================================
linear encoder           master-nut (sled) position  position loop, acquisition, Eq. 9.12
torque-meter encoder     screw angle                 acquisition, Eq. 9.12
resolver                 motor angle                 drive speed loop
torque meter             transmitted torque T_tm     acquisition
preload load cell        preload force               acquisition
load cell                external force              force loop, acquisition
current monitor          Hall-sensor current         acquisition
=======================  ==========================  ==========================================
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numba
import numpy as np

from sensors.acquisition import draw_uniform_noise
from sensors.analog import (
    AN_GAIN,
    AN_NOISE_HALF_WIDTH,
    AN_OFFSET,
    AN_REFRESH_PERIOD,
    AN_SIZE,
    AN_TAU,
    AS_SIZE,
    analog_init,
    analog_parameters,
    analog_read,
    with_integration_step,
)
from sensors.encoder import (
    ENC_SIZE,
    ENC_STATE_SIZE,
    encoder_init,
    encoder_reading,
    encoder_speed,
    linear_encoder_parameters,
    torque_meter_encoder_parameters,
)
from sensors.lanes import one_lane
from sensors.load_cell import load_cell_parameters, preload_load_cell_parameters
from sensors.resolver import RES_ACCURACY, RES_OFFSET, RES_SIZE, resolver_angle, resolver_parameters
from sensors.torque_meter import torque_meter_parameters
from twin.engine.plant import sensed_current
from twin.layout import K, S

LINEAR_ENCODER = 0
TORQUE_METER_ENCODER = 1
RESOLVER = 2
TORQUE_METER = 3
PRELOAD_CELL = 4
LOAD_CELL = 5
CURRENT_MONITOR = 6
INSTRUMENTS = ("linear_encoder", "torque_meter_encoder", "resolver", "torque_meter", "preload_load_cell",
               "load_cell", "current_monitor")
N_INSTRUMENTS = len(INSTRUMENTS)
ANALOG = (TORQUE_METER, PRELOAD_CELL, LOAD_CELL, CURRENT_MONITOR)
LEVELS = {"ideal": 0, "quantized": 1, "full": 2}
ROW = max(ENC_SIZE, AN_SIZE, RES_SIZE)
STATE_ROW = max(ENC_STATE_SIZE, AS_SIZE)



@dataclass(frozen=True)
class Instruments:
    """Packed parameters (one row per instrument), levels and pre-drawn noise for one run."""

    parameters: np.ndarray   # (len(INSTRUMENTS), ROW)
    levels: np.ndarray       # (len(INSTRUMENTS),) int codes
    lookback: np.ndarray     # (len(INSTRUMENTS),) steps before an acquisition in which a channel must be stepped
    noise: np.ndarray        # (n_samples, len(INSTRUMENTS)) [V]; zero columns for digital instruments
    names: dict[str, str]    # instrument -> level name


# Fidelity subsystem (twin.fidelity) -> the instruments whose level it sets.
INSTRUMENT_GROUPS = {
    "encoders": ("linear_encoder", "torque_meter_encoder", "resolver"),
    "analog_sensors": ("torque_meter", "preload_load_cell", "load_cell", "current_monitor"),
}


def instrument_levels(fidelity) -> dict[str, str]:
    """Instrument -> level name, from the ``encoders`` and ``analog_sensors`` levels of a
    :class:`twin.fidelity.Fidelity`."""
    return {name: fidelity.level(group) for group, names in INSTRUMENT_GROUPS.items() for name in names}


def build_instruments(p: Mapping[str, float], room_temperature: float, levels: Mapping[str, str],
                      rng: np.random.Generator, n_samples: int, dt: float,
                      torque_meter_refresh: bool = True) -> Instruments:
    """Pack the instruments of one run (parameters from the ``sensors`` group of ``p``).

    Parameters
    ----------
    p : mapping
        Parameter values (the whole set; the ``sensors.*`` and ``motor.max_current`` entries are used).
    room_temperature : float
        Scene room temperature [K]: drives every temperature effect.
    levels : mapping
        Instrument -> level name (see :func:`instrument_levels`).
    rng : numpy.random.Generator
        Source of the electrical noise (one column per analog channel, drawn in a fixed order).
    n_samples : int
        Number of acquisition samples of the run.
    dt : float
        Integration step [s] (sets how many steps before a reading a memoryless channel is stepped, and the
        conditioners' lag coefficients, :func:`sensors.analog.with_integration_step`).
    torque_meter_refresh : bool
        Model the torque meter's 1 kHz sample-and-hold (True) or read it continuously.
    """
    codes = np.array([LEVELS[levels[name]] for name in INSTRUMENTS], dtype=np.int64)
    rows = np.zeros((len(INSTRUMENTS), ROW))
    rows[LINEAR_ENCODER, :ENC_SIZE] = linear_encoder_parameters(p, fidelity=int(codes[LINEAR_ENCODER]))
    rows[TORQUE_METER_ENCODER, :ENC_SIZE] = torque_meter_encoder_parameters(
        p, fidelity=int(codes[TORQUE_METER_ENCODER]))
    rows[RESOLVER, :RES_SIZE] = resolver_parameters(p)
    rows[TORQUE_METER, :AN_SIZE] = torque_meter_parameters(p, room_temperature=room_temperature)
    if not torque_meter_refresh:
        rows[TORQUE_METER, AN_REFRESH_PERIOD] = 0.0
    rows[PRELOAD_CELL, :AN_SIZE] = preload_load_cell_parameters(p, room_temperature=room_temperature)
    rows[LOAD_CELL, :AN_SIZE] = load_cell_parameters(p, room_temperature=room_temperature)
    rows[CURRENT_MONITOR, :AN_SIZE] = analog_parameters(
        full_scale=p["motor.max_current"], output_full_scale=p["sensors.current_monitor_full_scale"], gain=1.0,
        offset=0.0,
        tau=0.0, refresh_period=0.0, output_bits=0.0, daq_full_scale=p["sensors.daq_full_scale"],
        daq_bits=p["sensors.daq_bits"],
        noise_half_width=p["sensors.electrical_noise_half_width"] * p["sensors.current_monitor_full_scale"])
    if codes[RESOLVER] < LEVELS["full"]:
        rows[RESOLVER, RES_ACCURACY] = 0.0
        rows[RESOLVER, RES_OFFSET] = 0.0
    noise = np.zeros((n_samples, len(INSTRUMENTS)))
    for channel in ANALOG:
        if codes[channel] < LEVELS["full"]:
            rows[channel, AN_GAIN] = 1.0
            rows[channel, AN_OFFSET] = 0.0
            rows[channel, AN_NOISE_HALF_WIDTH] = 0.0
        rows[channel, :AN_SIZE] = with_integration_step(rows[channel, :AN_SIZE], dt)
        noise[:, channel] = draw_uniform_noise(rng, n_samples, rows[channel, AN_NOISE_HALF_WIDTH])
    return Instruments(rows, codes, _lookback(rows, dt), noise, dict(levels))


def _lookback(rows: np.ndarray, dt: float) -> np.ndarray:
    """Steps before each acquisition instant in which an instrument must be stepped.

    Encoders and filtered channels carry state from step to step: every step.
    A channel without a filter only needs its value at the last refresh before
    the reading, which falls within the last ``ceil(refresh / dt)`` steps; one
    more step gives the interpolation its start value. Skipping the other steps
    gives the same readings at a fraction of the cost (when a refresh instant
    ties with the end of a step, floating-point rounding of the accumulated
    refresh time decides which side it falls on, dense or lazy alike).
    """
    every_step = np.iinfo(np.int64).max
    lookback = np.full(len(INSTRUMENTS), every_step, dtype=np.int64)
    for channel in ANALOG:
        if rows[channel, AN_TAU] == 0.0:
            lookback[channel] = int(np.ceil(rows[channel, AN_REFRESH_PERIOD] / dt - 1e-9)) + 1
    return lookback


@numba.njit(cache=True)
def sled_measurand(x, c):
    """Position on the linear encoder's scale [m]."""
    return c[K.ENCODER_SCALE_ORIGIN] + x[S.NUT1_POSITION] - c[K.NUT1_ZERO]


@numba.njit(cache=True)
def screw_angle_measurand(x, c):
    """Screw angle seen by the torque meter's encoder [rad]."""
    return x[S.SCREW_ANGLE] - c[K.SCREW_ANGLE_ZERO]


@numba.njit(cache=True)
def instruments_init(state, rows, x, c, t, torque, preload, external):
    """Zero the encoders and settle the analog channels on the initial state.

    Each instrument's row of ``state`` and ``rows`` is a one-lane group of the lane-form sensor functions
    (:func:`sensors.lanes.one_lane`, lane 0)."""
    encoder_init(one_lane(state[LINEAR_ENCODER]), one_lane(rows[LINEAR_ENCODER]), 0, sled_measurand(x, c), t)
    encoder_init(one_lane(state[TORQUE_METER_ENCODER]), one_lane(rows[TORQUE_METER_ENCODER]), 0,
                 screw_angle_measurand(x, c), t)
    analog_init(one_lane(state[TORQUE_METER]), one_lane(rows[TORQUE_METER]), 0, torque, t)
    analog_init(one_lane(state[PRELOAD_CELL]), one_lane(rows[PRELOAD_CELL]), 0, preload, t)
    analog_init(one_lane(state[LOAD_CELL]), one_lane(rows[LOAD_CELL]), 0, external, t)
    analog_init(one_lane(state[CURRENT_MONITOR]), one_lane(rows[CURRENT_MONITOR]), 0, sensed_current(x, c), t)


@numba.njit(cache=True)
def analog_due(level, lookback, steps_to_sample, tau, refresh_period, next_refresh, t, dt):
    """Whether an analog channel (its ``level``, :func:`_lookback` entry, ``AN_TAU``, ``AN_REFRESH_PERIOD`` and
    ``AS_NEXT_REFRESH``) must be stepped at the end ``t`` of a step of ``dt``, ``steps_to_sample`` steps
    before the next acquisition instant (0 at the instant itself).

    Dense stepping gives the same readings as: the steps in the channel's look-back window
    (:func:`_lookback`) and, for a channel with a sample-and-hold output and no filter, of those only
    the step that contains a refresh instant and the step before it (which gives the
    interpolation its start value); between refreshes the output is held whatever the input.
    """
    if level == 0 or steps_to_sample >= lookback:
        return False
    if tau > 0.0 or refresh_period == 0.0:
        return True
    # The next step ends at about t + dt: half a step of margin absorbs the rounding of both clocks.
    return t + 1.5 * dt >= next_refresh


@numba.njit(cache=True)
def linear_encoder_position(state, rows, levels, x, c):
    """Sled position read by the linear encoder, zeroed at the start [m]."""
    if levels[LINEAR_ENCODER] == 0:
        return x[S.NUT1_POSITION] - c[K.NUT1_ZERO]
    return encoder_reading(one_lane(state[LINEAR_ENCODER]), one_lane(rows[LINEAR_ENCODER]), 0)


@numba.njit(cache=True)
def screw_angle_measured(state, rows, levels, x, c):
    """Screw angle read by the torque meter's encoder, zeroed at the start [rad]."""
    if levels[TORQUE_METER_ENCODER] == 0:
        return x[S.SCREW_ANGLE] - c[K.SCREW_ANGLE_ZERO]
    return encoder_reading(one_lane(state[TORQUE_METER_ENCODER]), one_lane(rows[TORQUE_METER_ENCODER]), 0)


@numba.njit(cache=True)
def sled_speed_measured(state, rows, levels, x, t):
    """Sled speed by the period/frequency method of the linear encoder [m/s]."""
    if levels[LINEAR_ENCODER] == 0:
        return x[S.NUT1_SPEED]
    return encoder_speed(one_lane(state[LINEAR_ENCODER]), one_lane(rows[LINEAR_ENCODER]), 0, t)


@numba.njit(cache=True)
def motor_angle_measured(rows, levels, x, c):
    """Motor angle read by the resolver [rad]."""
    angle = c[K.RATIO] * x[S.REDUCER_ANGLE]
    if levels[RESOLVER] == 0:
        return angle
    return resolver_angle(one_lane(rows[RESOLVER]), 0, angle)


@numba.njit(cache=True)
def analog_measured(state, rows, levels, channel, true_value, noise):
    """DAQ reading of an analog channel (true value at the ideal level)."""
    if levels[channel] == 0:
        return true_value
    return analog_read(one_lane(state[channel]), one_lane(rows[channel]), 0, noise)

