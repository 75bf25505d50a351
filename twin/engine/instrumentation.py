"""The bench's instruments inside the compiled loop, over a group of lanes: what the controller and the DAQ read.

Wires the measurement models of :mod:`sensors` (their lane form: ``(state, params, l, ...)``, branch-free) to the
bench state. Every instrument has a fidelity level (Sec. 9.3, Table 9.5; the ``encoders`` and ``analog_sensors``
subsystems of :mod:`twin.levels`, shared by a group):

``ideal``
    the true signal.
``quantized``
    resolutions, converters and refresh/filters, no errors and no noise.
``full``
    edge-accurate encoders with their phase/asymmetry/precision errors and mounting phases, the sensitivity,
    offset and temperature errors of the analog channels, and the electrical noise of Table 9.5 drawn from the
    run's Generator.

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

A group's instruments are two arrays: ``parameters[instrument, row, lane]`` and ``states[instrument, row, lane]``
(each instrument's rows in its sensor module's layout, ``ENC_*``, ``AN_*``, ``AS_*``, ``RES_*``), and the pre-drawn
noise ``noise[sample, instrument, lane]``. The encoders are stepped after every integration step (every lane
computes its count: a select is cheaper than a branch here); an analog channel only where a reading depends on the
step (:func:`channel_due`, decided for the whole group).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numba
import numpy as np

from numerics.jit import KERNEL, SCALAR
from sensors.acquisition import draw_uniform_noise
from sensors.analog import (
    AN_GAIN,
    AN_NOISE_HALF_WIDTH,
    AN_OFFSET,
    AN_REFRESH_PERIOD,
    AN_SIZE,
    AN_TAU,
    AS_NEXT_REFRESH,
    AS_REFRESH_ORIGIN,
    AS_SIZE,
    analog_init,
    analog_parameters,
    analog_read,
    analog_step,
    with_integration_step,
)
from sensors.encoder import (
    ENC_SIZE,
    ENC_STATE_SIZE,
    encoder_init,
    encoder_reading,
    encoder_speed,
    encoder_step,
    linear_encoder_parameters,
    torque_meter_encoder_parameters,
)
from sensors.load_cell import load_cell_parameters, preload_load_cell_parameters
from sensors.resolver import RES_ACCURACY, RES_OFFSET, RES_SIZE, resolver_angle, resolver_parameters
from sensors.torque_meter import torque_meter_parameters
from twin.components import reducer
from twin.engine.codes import ANALOG_SENSORS, CURRENT_LOOP, ENCODERS
from twin.engine.plant import W, sensed_current
from twin.layout import K, M, S
from twin.levels import SUBSYSTEMS

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
ROW = max(ENC_SIZE, AN_SIZE, RES_SIZE)
STATE_ROW = max(ENC_STATE_SIZE, AS_SIZE)
#: Readings an acquisition instant keeps (layout twin.layout.M, from M.SLED on).
N_MEASURED = M.EXTERNAL - M.SLED + 1

#: Level codes of the instrument subsystems (twin.levels: full first) and the sensors' own fidelity numbers.
FULL, QUANTIZED, IDEAL = (SUBSYSTEMS["encoders"].level_names.index(name) for name in ("full", "quantized", "ideal"))
SENSOR_FIDELITY = {"full": 2, "quantized": 1, "ideal": 0}
if SUBSYSTEMS["analog_sensors"].level_names != SUBSYSTEMS["encoders"].level_names:
    raise ImportError("twin.engine.instrumentation reads the encoders' and the analog sensors' levels alike")


@dataclass(frozen=True)
class Instruments:
    """One run's instruments: packed parameters (one row block per instrument) and pre-drawn noise."""

    parameters: np.ndarray   # (N_INSTRUMENTS, ROW)
    noise: np.ndarray        # (n_samples, N_INSTRUMENTS) [V]; zero columns for digital instruments


def build_instruments(p: Mapping[str, float], room_temperature: float, levels: Mapping[str, str],
                      rng: np.random.Generator, n_samples: int, dt: float) -> Instruments:
    """Pack the instruments of one run (parameters from the ``sensors`` group of ``p``).

    Parameters
    ----------
    p : mapping
        Parameter values (the whole set; the ``sensors.*`` and ``motor.max_current`` entries are used).
    room_temperature : float
        Scene room temperature [K]: drives every temperature effect.
    levels : mapping
        The run's fidelity levels (``encoders``, ``analog_sensors``, ``torque_meter_refresh``).
    rng : numpy.random.Generator
        Source of the electrical noise (one column per analog channel, drawn in a fixed order).
    n_samples : int
        Number of acquisition samples of the run.
    dt : float
        Integration step [s] (the analog conditioners' lag coefficients are computed for it).
    """
    encoders = SENSOR_FIDELITY[levels["encoders"]]
    analog = levels["analog_sensors"]
    rows = np.zeros((N_INSTRUMENTS, ROW))
    rows[LINEAR_ENCODER, :ENC_SIZE] = linear_encoder_parameters(p, fidelity=encoders)
    rows[TORQUE_METER_ENCODER, :ENC_SIZE] = torque_meter_encoder_parameters(p, fidelity=encoders)
    rows[RESOLVER, :RES_SIZE] = resolver_parameters(p)
    rows[TORQUE_METER, :AN_SIZE] = torque_meter_parameters(p, room_temperature=room_temperature)
    if levels["torque_meter_refresh"] == "ideal":
        rows[TORQUE_METER, AN_REFRESH_PERIOD] = 0.0
    rows[PRELOAD_CELL, :AN_SIZE] = preload_load_cell_parameters(p, room_temperature=room_temperature)
    rows[LOAD_CELL, :AN_SIZE] = load_cell_parameters(p, room_temperature=room_temperature)
    rows[CURRENT_MONITOR, :AN_SIZE] = analog_parameters(
        full_scale=p["motor.max_current"], output_full_scale=p["sensors.current_monitor_full_scale"], gain=1.0,
        offset=0.0, tau=0.0, refresh_period=0.0, output_bits=0.0, daq_full_scale=p["sensors.daq_full_scale"],
        daq_bits=p["sensors.daq_bits"],
        noise_half_width=p["sensors.electrical_noise_half_width"] * p["sensors.current_monitor_full_scale"])
    if encoders < SENSOR_FIDELITY["full"]:
        rows[RESOLVER, RES_ACCURACY] = 0.0
        rows[RESOLVER, RES_OFFSET] = 0.0
    noise = np.zeros((n_samples, N_INSTRUMENTS))
    for channel in ANALOG:
        if analog != "full":
            rows[channel, AN_GAIN] = 1.0
            rows[channel, AN_OFFSET] = 0.0
            rows[channel, AN_NOISE_HALF_WIDTH] = 0.0
        rows[channel, :AN_SIZE] = with_integration_step(rows[channel, :AN_SIZE], dt)
        noise[:, channel] = draw_uniform_noise(rng, n_samples, rows[channel, AN_NOISE_HALF_WIDTH])
    return Instruments(rows, noise)


@numba.njit(**SCALAR)
def sled_measurand(x, c, lane):
    """Position on the linear encoder's scale [m]: the sled's travel since the zero, read at the encoder's reading
    point (the Abbe error of the guides' angular errors, :mod:`twin.physics.guides`) on a scale expanded by the room
    temperature, ``K.SCALE_READING_GAIN`` (:func:`twin.engine.model.scale_reading_gain`)."""
    return c[K.ENCODER_SCALE_ORIGIN, lane] + (x[S.NUT1_POSITION, lane] - c[K.NUT1_ZERO, lane]) * c[
        K.SCALE_READING_GAIN, lane]


@numba.njit(**SCALAR)
def screw_angle_measurand(x, c, lane):
    """Screw angle seen by the torque meter's encoder [rad]."""
    return x[S.SCREW_ANGLE, lane] - c[K.SCREW_ANGLE_ZERO, lane]


@numba.njit(**SCALAR)
def _analog_measurand(x, c, w, lane, channel, current_loop):
    """What analog channel ``channel`` measures in lane ``lane``, from the work rows of
    :func:`twin.engine.plant.measurands` (or :func:`~twin.engine.plant.internal_forces`)."""
    if channel == TORQUE_METER:
        return w[W.TORQUE, lane]
    if channel == PRELOAD_CELL:
        return w[W.PRELOAD, lane]
    if channel == LOAD_CELL:
        return w[W.EXTERNAL, lane]
    return sensed_current(x, c, lane, current_loop)


@numba.njit(**KERNEL)
def instruments_init(t, x, c, w, levels, parameters, states):
    """Zero the encoders and settle the analog channels on the initial state of every lane (``w`` holds the
    initial forces)."""
    lanes = x.shape[1]
    for lane in range(lanes):
        encoder_init(states[LINEAR_ENCODER], parameters[LINEAR_ENCODER], lane, sled_measurand(x, c, lane), t)
        encoder_init(states[TORQUE_METER_ENCODER], parameters[TORQUE_METER_ENCODER], lane,
                     screw_angle_measurand(x, c, lane), t)
        for channel in ANALOG:
            analog_init(states[channel], parameters[channel], lane,
                        _analog_measurand(x, c, w, lane, channel, levels[CURRENT_LOOP]), t)


@numba.njit(**KERNEL)
def _encoders_advance(t, x, c, parameters, states, lanes):
    linear, linear_state = parameters[LINEAR_ENCODER], states[LINEAR_ENCODER]
    for lane in range(lanes):
        encoder_step(linear_state, linear, lane, sled_measurand(x, c, lane), t)
    rotary, rotary_state = parameters[TORQUE_METER_ENCODER], states[TORQUE_METER_ENCODER]
    for lane in range(lanes):
        encoder_step(rotary_state, rotary, lane, screw_angle_measurand(x, c, lane), t)


@numba.njit(**KERNEL)
def _channel_advance(t, x, c, w, parameters, states, lanes, channel, current_loop):
    p, state = parameters[channel], states[channel]
    for lane in range(lanes):
        analog_step(state, p, lane, _analog_measurand(x, c, w, lane, channel, current_loop), t)


@numba.njit(**SCALAR)
def channel_due(parameters, states, channel, t, dt, steps_to_sample):
    """Whether analog channel ``channel`` must be stepped at the end ``t`` of a step of ``dt``, ``steps_to_sample``
    steps before the next acquisition instant (0 at the instant itself); the same answer for every lane of a group,
    whose channels share their time constant and refresh period (:func:`group_timing`).

    Stepping at every step gives the same readings as stepping: a filtered channel (``tau > 0``) or a continuous
    one without a refresh at every step; an unfiltered channel with a refresh only in the last
    ``ceil(refresh / dt) + 1`` steps before a reading (its value at the last refresh, and the step before for the
    interpolation's start), and of those only the step that contains a refresh instant and the step before it.
    """
    tau = parameters[channel, AN_TAU, 0]
    period = parameters[channel, AN_REFRESH_PERIOD, 0]
    if tau > 0.0 or period == 0.0:
        return tau > 0.0 or steps_to_sample < 1
    if steps_to_sample >= math.ceil(period / dt - 1e-9) + 1:
        return False
    # the next step ends at about t + dt: half a step of margin absorbs the rounding of both clocks
    return t + 1.5 * dt >= states[channel, AS_REFRESH_ORIGIN, 0] + states[channel, AS_NEXT_REFRESH, 0] * period


def group_timing(instruments: Instruments) -> tuple:
    """What the analog channels' stepping decision (:func:`channel_due`) reads, for a group key: runs share a group
    only if their channels share it."""
    return tuple(float(instruments.parameters[channel, row]) for channel in ANALOG
                 for row in (AN_TAU, AN_REFRESH_PERIOD))


@numba.njit(**KERNEL)
def instruments_advance(t, dt, x, c, w, levels, parameters, states, steps_to_sample):
    """Advance every lane's instruments to time ``t``, the end of an integration step of ``dt`` (``w`` holds the
    measurands at ``t``: :func:`twin.engine.plant.measurands`), ``steps_to_sample`` steps before the next
    acquisition instant: the encoders every step, an analog channel when :func:`channel_due`."""
    lanes = x.shape[1]
    if levels[ENCODERS] != IDEAL:
        _encoders_advance(t, x, c, parameters, states, lanes)
    if levels[ANALOG_SENSORS] != IDEAL:
        for channel in ANALOG:
            if channel_due(parameters, states, channel, t, dt, steps_to_sample):
                _channel_advance(t, x, c, w, parameters, states, lanes, channel, levels[CURRENT_LOOP])


@numba.njit(**SCALAR)
def motor_angle_measured(x, c, lane, levels, parameters):
    """Motor angle read by the resolver in lane ``lane`` [rad] (the true one at the ideal level)."""
    angle = reducer.motor_angle_at(x, c, lane)
    if levels[ENCODERS] == IDEAL:
        return angle
    return resolver_angle(parameters[RESOLVER], lane, angle)


@numba.njit(**SCALAR)
def acquire(t, x, c, w, lane, levels, memory, parameters, states, noise, n):
    """Read every channel of lane ``lane`` at an acquisition instant (sample ``n``) into its memory rows
    ``M.SLED`` ... ``M.EXTERNAL`` (``w`` holds this instant's forces), and the load-cell reading the force loop
    acts on into ``M.FORCE_FEEDBACK``: the recorded one under the scene's ``noise_path = "feedback"``, the same
    conversion without its noise sample under ``"recorded"`` (``K.FORCE_FEEDBACK_NOISE``; a select, both computed)."""
    encoders_ideal = levels[ENCODERS] == IDEAL
    if encoders_ideal:
        memory[M.SLED, lane] = x[S.NUT1_POSITION, lane] - c[K.NUT1_ZERO, lane]
        memory[M.SCREW_ANGLE, lane] = x[S.SCREW_ANGLE, lane] - c[K.SCREW_ANGLE_ZERO, lane]
        memory[M.SLED_SPEED, lane] = x[S.NUT1_SPEED, lane]
    else:
        memory[M.SLED, lane] = encoder_reading(states[LINEAR_ENCODER], parameters[LINEAR_ENCODER], lane)
        memory[M.SCREW_ANGLE, lane] = encoder_reading(states[TORQUE_METER_ENCODER], parameters[TORQUE_METER_ENCODER],
                                                      lane)
        memory[M.SLED_SPEED, lane] = encoder_speed(states[LINEAR_ENCODER], parameters[LINEAR_ENCODER], lane, t)
    analog_ideal = levels[ANALOG_SENSORS] == IDEAL
    for channel in ANALOG:
        true_value = _analog_measurand(x, c, w, lane, channel, levels[CURRENT_LOOP])
        reading = true_value if analog_ideal else analog_read(states[channel], parameters[channel], lane,
                                                              noise[n, channel, lane])
        if channel == TORQUE_METER:
            memory[M.TORQUE, lane] = reading
        elif channel == PRELOAD_CELL:
            memory[M.PRELOAD, lane] = reading
        elif channel == LOAD_CELL:
            memory[M.EXTERNAL, lane] = reading
            clean = true_value if analog_ideal else analog_read(states[channel], parameters[channel], lane, 0.0)
            memory[M.FORCE_FEEDBACK, lane] = reading if c[K.FORCE_FEEDBACK_NOISE, lane] > 0.0 else clean
        else:
            memory[M.CURRENT, lane] = reading
