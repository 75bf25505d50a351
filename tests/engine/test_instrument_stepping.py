"""Analog channels are stepped only when a reading depends on the step: same readings as dense stepping."""

import numpy as np
import pytest

from sensors.analog import AN_REFRESH_PERIOD, AN_TAU, AS_NEXT_REFRESH, AS_SIZE, analog_init, analog_read, analog_step
from twin.engine.instrumentation import (
    CURRENT_MONITOR,
    INSTRUMENTS,
    LOAD_CELL,
    PRELOAD_CELL,
    STATE_ROW,
    TORQUE_METER,
    _lookback,
    analog_due,
    build_instruments,
)

DT = 3.125e-5
SAMPLE_EVERY = 32  # 1 ms acquisition


@pytest.mark.parametrize("channel", [TORQUE_METER, CURRENT_MONITOR])
def test_lookback_stepping_reads_like_dense_stepping(bench, channel):
    instruments = build_instruments(bench.values(), 298.15, {k: "full" for k in INSTRUMENTS},
                                    np.random.default_rng(0), 4, DT)
    table = instruments.parameters.copy()
    # A refresh period incommensurate with the step over the test window: no refresh instant ties
    # with a step end (ties are decided by rounding, dense or lazy alike).
    if table[channel, AN_REFRESH_PERIOD] > 0:
        table[channel, AN_REFRESH_PERIOD] = 7.071e-4
    rows, lookback = table[channel], _lookback(table, DT)[channel]
    assert lookback < SAMPLE_EVERY  # the saving is real
    signal = np.cumsum(np.random.default_rng(1).normal(size=SAMPLE_EVERY * 40 + 1)) * 5.0
    dense, lazy = np.zeros(AS_SIZE), np.zeros(AS_SIZE)
    analog_init(dense, signal[0], 0.0, rows)
    analog_init(lazy, signal[0], 0.0, rows)
    for k in range(1, signal.size):
        analog_step(dense, signal[k], k * DT, rows)
        if (SAMPLE_EVERY - k % SAMPLE_EVERY) % SAMPLE_EVERY < lookback:
            analog_step(lazy, signal[k], k * DT, rows)
        if k % SAMPLE_EVERY == 0:
            assert analog_read(lazy, 0.0, rows) == analog_read(dense, 0.0, rows)


def test_filtered_channel_is_stepped_every_step(bench):
    instruments = build_instruments(bench.values(), 298.15, {k: "full" for k in INSTRUMENTS},
                                    np.random.default_rng(0), 4, DT)
    assert instruments.lookback[PRELOAD_CELL] == np.iinfo(np.int64).max


@pytest.mark.parametrize("dt", [6.25e-5, 3.125e-5])
@pytest.mark.parametrize("channel", [TORQUE_METER, PRELOAD_CELL, LOAD_CELL, CURRENT_MONITOR])
def test_channels_stepped_only_when_due_read_like_the_lookback_window(bench, channel, dt):
    """The loop's rule (the look-back window, and in it, for a sample-and-hold output, only the steps that end at
    or just before a refresh instant) reads like stepping every step of the window, with the bench's own refresh
    periods: the torque meter's 1 kHz refresh ties with the 1 kHz acquisition (its window is every step: dense
    stepping), the load cell's 19.2 kHz is faster than a step."""
    sample_every = round(1e-3 / dt)
    instruments = build_instruments(bench.values(), 298.15, {k: "full" for k in INSTRUMENTS},
                                    np.random.default_rng(0), 4, dt)
    rows, levels, lookback = instruments.parameters, instruments.levels, instruments.lookback
    signal = np.cumsum(np.random.default_rng(2).normal(size=sample_every * 40 + 1)) * 5.0
    window, due = np.zeros((len(INSTRUMENTS), STATE_ROW)), np.zeros((len(INSTRUMENTS), STATE_ROW))
    analog_init(window[channel], signal[0], 0.0, rows[channel])
    analog_init(due[channel], signal[0], 0.0, rows[channel])
    stepped = 0
    for k in range(1, signal.size):
        t = k * dt
        steps_to_sample = (sample_every - k % sample_every) % sample_every
        if steps_to_sample < lookback[channel]:
            analog_step(window[channel], signal[k], t, rows[channel])
        if analog_due(levels[channel], lookback[channel], steps_to_sample, rows[channel, AN_TAU],
                      rows[channel, AN_REFRESH_PERIOD], due[channel, AS_NEXT_REFRESH], t, dt):
            analog_step(due[channel], signal[k], t, rows[channel])
            stepped += 1
        if k % sample_every == 0:
            assert analog_read(due[channel], 0.0, rows[channel]) == analog_read(window[channel], 0.0, rows[channel])
    if channel != PRELOAD_CELL:  # the filtered channel needs every step
        assert stepped <= 0.2 * signal.size
