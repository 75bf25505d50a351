"""The edge-accurate decoder's timing internals: the wrap-around edge gap, the peak-frequency diagnostic, the edge
times of a step that crosses several edges, and the speed method chosen from the window since the last sample.

Each expected value is written out from the definitions in sensors/encoder.py's docstrings (linear motion inside a
step, ``res / sqrt(T_clk T_w)`` switch speed), at start times far from zero so that a time measured from the wrong
origin shows.
"""

import math

import numpy as np
import pytest

from sensors.encoder import (
    ENC_EDGE,
    ENC_S_COUNT,
    ENC_S_EDGE_DIR,
    ENC_S_EDGE_T,
    ENC_S_PEAK_FREQUENCY,
    ENC_S_PREV_EDGE_DIR,
    ENC_S_PREV_EDGE_T,
    ENC_STATE_SIZE,
    edge_angles,
    encoder_frequency_speed,
    encoder_init,
    encoder_overspeed,
    encoder_parameters,
    encoder_period_speed,
    encoder_speed,
    encoder_step,
    speed_switch_threshold,
)

RES = 1.0e-6  # Table B.4
PERIOD = 4.0 * RES
TICK = 2.5e-8
T0 = 100.0  # s: the start of the encoder's life, far from t = 0



def _lane(p):
    """One lane's parameter vector as a one-lane group (lane 0, ``sensors.lanes``)."""
    return np.ascontiguousarray(p.reshape(-1, 1))

def _params(**kw):
    return encoder_parameters(resolution=RES, timer_period=TICK, **kw)


def _edge_position(n: float, p) -> float:
    """Scale position of edge number ``n`` (four edges per signal period)."""
    j = math.floor(n / 4)
    return p[ENC_EDGE + int(n - 4 * j)] + j * PERIOD


def test_the_edge_order_check_includes_the_gap_to_the_next_period():
    """phase 1.0 rad with both duty asymmetries 0.6 rad: the three gaps inside the period stay positive, but the
    B fall passes the next period's A rise (gap pi/2 - 0.3 - 1.0 - 0.3 < 0): the decoder would count backwards."""
    angles = edge_angles(1.0, 0.6, 0.6)
    assert (np.diff(angles) > 0).all() and angles[0] + 2 * math.pi - angles[3] < 0
    with pytest.raises(ValueError, match="edges out of quadrature order"):
        _params(phase_error=1.0, asymmetry_a=0.6, asymmetry_b=0.6)
    _params(phase_error=0.9, asymmetry_a=0.6, asymmetry_b=0.6)  # gap +0.07 rad: accepted


def test_peak_frequency_is_the_scale_travel_per_signal_period_over_the_step_duration():
    p = _params()
    state = np.zeros((ENC_STATE_SIZE, 1))
    encoder_init(state, _lane(p), 0, 0.0, T0)
    encoder_step(state, _lane(p), 0, 0.3e-5, T0 + 1e-5)  # 0.3 m/s: 75 kHz signal
    assert state[ENC_S_PEAK_FREQUENCY, 0] == pytest.approx(0.3e-5 / (PERIOD * 1e-5), rel=1e-9)
    assert encoder_overspeed(state, 50e3).tolist() == [True]
    encoder_step(state, _lane(p), 0, 0.4e-5, T0 + 2e-5)  # slower: the peak is kept
    assert state[ENC_S_PEAK_FREQUENCY, 0] == pytest.approx(75e3, rel=1e-9)


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_a_step_across_several_edges_times_the_last_two_by_linear_interpolation(direction):
    p = _params(phase_error=math.radians(25.0))
    v = direction * 0.013
    x0 = 0.1e-6
    state = np.zeros((ENC_STATE_SIZE, 1))
    encoder_init(state, _lane(p), 0, x0, T0)
    dt = 2.5e-4  # 3.25 µm: several edges in one step
    encoder_step(state, _lane(p), 0, x0 + v * dt, T0 + dt)
    count = state[ENC_S_COUNT, 0]
    last = count if direction > 0 else count + 1  # backward, the last edge is count + 1
    previous = last - direction
    for slot, n in ((ENC_S_EDGE_T, last), (ENC_S_PREV_EDGE_T, previous)):
        assert state[slot, 0] == pytest.approx(T0 + (_edge_position(n, p) - x0) / v, rel=1e-12, abs=1e-12)
    assert state[ENC_S_EDGE_DIR, 0] == direction and state[ENC_S_PREV_EDGE_DIR, 0] == direction
    # the period method reads the interval between those two edges, counted in timer ticks
    interval = math.floor(state[ENC_S_EDGE_T, 0] / TICK) - math.floor(state[ENC_S_PREV_EDGE_T, 0] / TICK)
    assert encoder_period_speed(state, _lane(p), 0, T0 + dt) == direction * RES / (interval * TICK)


def test_the_speed_method_is_chosen_from_the_window_since_the_last_sample():
    """At 10 mm/s over a 1 ms window the switch speed is res / sqrt(T_clk T_w) = 0.2 m/s: the period method is the
    better one and is returned (measured from the sample at T0 = 100 s, not from t = 0)."""
    p = _params()
    state = np.zeros((ENC_STATE_SIZE, 1))
    encoder_init(state, _lane(p), 0, 0.3e-6, T0)
    v, window = 0.01, 1e-3
    for k in range(1, 101):
        t = T0 + k * window / 100
        encoder_step(state, _lane(p), 0, 0.3e-6 + v * (t - T0), t)
    assert v < speed_switch_threshold(RES, TICK, window)
    period, frequency = encoder_period_speed(state, _lane(p), 0, t), encoder_frequency_speed(state, _lane(p), 0, t)
    assert period != frequency
    assert encoder_speed(state, _lane(p), 0, t) == period
    # a second sample at the same instant has an empty window: no frequency estimate, no method to choose
    assert encoder_speed(state, _lane(p), 0, t) == 0.0


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_one_edge_after_zeroing_gives_no_period_yet(direction):
    """The period method needs two edges in the same direction: after zeroing and a single edge there is no interval,
    and the estimate is exactly 0 in either direction (not the speed over an interval from the start of time)."""
    p = _params()
    state = np.zeros((ENC_STATE_SIZE, 1))
    x0 = 0.5 * RES  # mid-way between two edges of the ideal pattern
    encoder_init(state, _lane(p), 0, x0, T0)
    encoder_step(state, _lane(p), 0, x0 + direction * RES, T0 + 1e-3)  # exactly one edge crossed
    assert state[ENC_S_EDGE_DIR, 0] == direction and state[ENC_S_PREV_EDGE_DIR, 0] == 0.0
    speed = encoder_period_speed(state, _lane(p), 0, T0 + 1e-3)
    assert speed == 0.0 and math.copysign(1.0, speed) == 1.0
