"""Memoryless analog channels are stepped only before each reading: same readings as dense stepping."""

import numpy as np
import pytest

from sensors.analog import AN_REFRESH_PERIOD, AS_SIZE, analog_init, analog_read, analog_step
from twin.engine.instrumentation import (
    CURRENT_MONITOR,
    INSTRUMENTS,
    PRELOAD_CELL,
    TORQUE_METER,
    _lookback,
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
