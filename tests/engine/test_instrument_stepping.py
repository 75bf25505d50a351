"""Analog channels are stepped only when a reading depends on the step (twin.engine.instrumentation.channel_due):
the same readings as stepping at every step, with far fewer steps for the sample-and-hold channels."""

import numpy as np
import pytest

from sensors.analog import AN_REFRESH_PERIOD, AN_TAU, analog_init, analog_read, analog_step
from twin.engine.instrumentation import (
    ANALOG,
    CURRENT_MONITOR,
    LOAD_CELL,
    N_INSTRUMENTS,
    PRELOAD_CELL,
    STATE_ROW,
    TORQUE_METER,
    build_instruments,
    channel_due,
    group_timing,
)

FULL = {"encoders": "full", "analog_sensors": "full", "torque_meter_refresh": "modelled"}
ACQUISITION = 1e-3  # s


def _instruments(bench, dt, refresh=None):
    """One run's instruments as a one-lane group (``parameters[instrument, row, lane]``), the torque meter's refresh
    period replaced by ``refresh`` if given."""
    parameters = build_instruments(bench.values(), 298.15, FULL, np.random.default_rng(0), 4, dt).parameters.copy()
    if refresh is not None:
        parameters[TORQUE_METER, AN_REFRESH_PERIOD] = refresh
    return np.ascontiguousarray(parameters[:, :, None])


def _readings(parameters, channel, dt, signal):
    """Readings at every acquisition instant of ``channel`` stepped at every step and stepped when due (the loop's
    counter: ``steps_to_sample`` steps from the end of the step to the next acquisition), and the due steps taken."""
    sample_every = round(ACQUISITION / dt)
    every, due = np.zeros((N_INSTRUMENTS, STATE_ROW, 1)), np.zeros((N_INSTRUMENTS, STATE_ROW, 1))
    p = parameters[channel]
    analog_init(every[channel], p, 0, signal[0], 0.0)
    analog_init(due[channel], p, 0, signal[0], 0.0)
    stepped, readings = 0, []
    for k in range(1, signal.size):
        t = k * dt
        steps_to_sample = (sample_every - k % sample_every) % sample_every
        analog_step(every[channel], p, 0, signal[k], t)
        if channel_due(parameters, due, channel, t, dt, steps_to_sample):
            analog_step(due[channel], p, 0, signal[k], t)
            stepped += 1
        if steps_to_sample == 0:
            readings.append((analog_read(due[channel], p, 0, 0.0), analog_read(every[channel], p, 0, 0.0)))
    return np.array(readings), stepped


@pytest.mark.parametrize("dt", [1.25e-4, 6.25e-5, 3.125e-5])
@pytest.mark.parametrize("channel", [TORQUE_METER, PRELOAD_CELL, LOAD_CELL, CURRENT_MONITOR])
def test_channels_stepped_only_when_due_read_like_every_step(bench, channel, dt):
    """With the bench's own channels: the torque meter's 1 kHz refresh ties with the 1 kHz acquisition, the load
    cell's and the preload cell's conditioners are filters (stepped every step), the current
    monitor is continuous (stepped only at the reading). Exactly the readings of stepping every step, at the
    default step and at its halves."""
    parameters = _instruments(bench, dt)
    signal = np.cumsum(np.random.default_rng(2).normal(size=round(ACQUISITION / dt) * 40 + 1)) * 5.0
    readings, stepped = _readings(parameters, channel, dt, signal)
    assert len(readings) == 40
    np.testing.assert_array_equal(readings[:, 0], readings[:, 1])
    if parameters[channel, AN_TAU, 0] > 0.0:
        assert channel in (PRELOAD_CELL, LOAD_CELL) and stepped == signal.size - 1  # a filter needs every step
    else:
        assert stepped <= 0.5 * signal.size  # the saving is real (at 125 us: 3 steps of 8 for the torque meter)


@pytest.mark.parametrize("dt", [6.25e-5, 3.125e-5])
def test_a_refresh_incommensurate_with_the_step_reads_like_every_step(bench, dt):
    """A refresh period that never ties with a step end (7.071e-4 s): the due rule still finds the steps that hold
    each refresh instant, and only about ``2 / (refresh / dt)`` of the window's steps are taken."""
    parameters = _instruments(bench, dt, refresh=7.071e-4)
    signal = np.cumsum(np.random.default_rng(1).normal(size=round(ACQUISITION / dt) * 40 + 1)) * 5.0
    readings, stepped = _readings(parameters, TORQUE_METER, dt, signal)
    np.testing.assert_array_equal(readings[:, 0], readings[:, 1])
    assert stepped <= 0.2 * signal.size


def test_the_decision_is_a_group_key(bench):
    """The due decision reads the first lane's time constants and refresh periods for the whole group: runs whose
    channels differ in them must not share a group, so they are part of its key."""
    a = build_instruments(bench.values(), 298.15, FULL, np.random.default_rng(0), 4, 6.25e-5)
    b = build_instruments(bench.values(), 308.15, FULL, np.random.default_rng(1), 4, 6.25e-5)
    assert group_timing(a) == group_timing(b)  # temperature and noise are the lane's own
    ideal_refresh = build_instruments(bench.values(), 298.15, {**FULL, "torque_meter_refresh": "ideal"},
                                      np.random.default_rng(0), 4, 6.25e-5)
    assert group_timing(ideal_refresh) != group_timing(a)
    assert len(group_timing(a)) == 2 * len(ANALOG)
