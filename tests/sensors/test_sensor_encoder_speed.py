"""Encoder speed: period and frequency methods and the switch between them."""

import math

import numpy as np
import pytest
from bench_helpers import bench_sensors

from sensors.encoder import (
    ENC_RESOLUTION,
    ENC_STATE_SIZE,
    encoder_frequency_speed,
    encoder_init,
    encoder_parameters,
    encoder_period_speed,
    encoder_speed,
    encoder_step,
    linear_encoder_parameters,
    speed_switch_threshold,
    torque_meter_encoder_parameters,
)

RES = 1.0e-6
WINDOW = 1.0e-3  # sampling period = frequency-method window
DT = 1.0e-5  # integration step



def _lane(p):
    """One lane's parameter vector as a one-lane group (lane 0, ``sensors.lanes``)."""
    return np.ascontiguousarray(p.reshape(-1, 1))

def _constant_speed_run(p, v, duration):
    """Per-sample (period, frequency, switched) estimates at constant speed v, after warm-up."""
    state = np.zeros((ENC_STATE_SIZE, 1))
    x0 = 0.37 * RES  # edges not aligned with the steps
    encoder_init(state, _lane(p), 0, x0, 0.0)
    steps_per_sample = round(WINDOW / DT)
    out = []
    for k in range(1, round(duration / DT) + 1):
        t = k * DT
        encoder_step(state, _lane(p), 0, x0 + v * t, t)
        if k % steps_per_sample == 0:
            period = encoder_period_speed(state, _lane(p), 0, t)
            frequency = encoder_frequency_speed(state, _lane(p), 0, t)
            switched = encoder_speed(state, _lane(p), 0, t)
            if t > 3.0 * RES / v + 2.0 * WINDOW:  # two edges and one full window seen
                out.append((period, frequency, switched))
    return np.array(out)


def _bounds(v, tick):
    """Documented error bounds: period v^2 T / (res - v T); frequency res / T_w."""
    return v * v * tick / (RES - v * tick), RES / WINDOW


def test_switch_threshold_is_the_crossover_of_the_two_error_bounds():
    tick = 2.5e-8
    v_sw = speed_switch_threshold(RES, tick, WINDOW)
    assert v_sw == pytest.approx(0.2)  # bench linear encoder, docs/sensors.md
    b_p, b_f = _bounds(v_sw, tick)
    assert v_sw * v_sw * tick / RES == pytest.approx(b_f)  # leading-order period bound equals frequency bound
    p = torque_meter_encoder_parameters(bench_sensors())
    assert speed_switch_threshold(p[ENC_RESOLUTION], tick, WINDOW) == pytest.approx(157.08, rel=1e-4)


@pytest.mark.parametrize("v", [2e-4, 2e-3, 2e-2, -5e-3])
def test_period_method_is_accurate_and_chosen_at_low_speed(v):
    p = linear_encoder_parameters(bench_sensors(), fidelity=1)  # 40 MHz timer: v_sw = 0.2 m/s
    tick = 2.5e-8
    est = _constant_speed_run(p, v, duration=max(0.03, 20 * RES / abs(v)))
    b_p, b_f = _bounds(abs(v), tick)
    assert b_p < b_f
    assert len(est) >= 5
    assert np.all(np.abs(est[:, 0] - v) <= b_p * (1 + 1e-9))
    assert np.all(np.abs(est[:, 1] - v) <= b_f * (1 + 1e-9))
    np.testing.assert_array_equal(est[:, 2], est[:, 0])  # the switch picks the period method
    if abs(v) < RES / WINDOW:  # below one count per window the frequency method really is worse
        assert np.max(np.abs(est[:, 1] - v)) > b_p


@pytest.mark.parametrize("v", [0.06, 0.11, 0.17, -0.13])
def test_frequency_method_is_accurate_and_chosen_at_high_speed(v):
    tick = 1.0e-6  # slow timer: v_sw = 0.0316 m/s; edge intervals not whole ticks
    p = encoder_parameters(resolution=RES, timer_period=tick, fidelity=1)
    assert abs(v) > speed_switch_threshold(RES, tick, WINDOW) + RES / WINDOW
    est = _constant_speed_run(p, v, duration=0.02)
    b_p, b_f = _bounds(abs(v), tick)
    assert b_f < b_p
    assert np.all(np.abs(est[:, 1] - v) <= b_f * (1 + 1e-9))
    np.testing.assert_array_equal(est[:, 2], est[:, 1])  # the switch picks the frequency method
    assert np.max(np.abs(est[:, 0] - v)) > b_f  # and the period method would have been worse


def test_period_method_reads_zero_on_dither_and_decays_after_a_stop():
    p = linear_encoder_parameters(bench_sensors(), fidelity=1)
    tick = 2.5e-8
    state = np.zeros((ENC_STATE_SIZE, 1))
    encoder_init(state, _lane(p), 0, 0.5e-6, 0.0)
    v = 1e-3
    t = 0.0
    for k in range(1, 1001):  # 10 ms at 1 mm/s, then stop at x_stop
        t = k * DT
        encoder_step(state, _lane(p), 0, 0.5e-6 + v * t, t)
    x_stop = 0.5e-6 + v * t
    assert encoder_period_speed(state, _lane(p), 0, t) == pytest.approx(v, rel=1e-3)
    t_late = t + 0.05
    encoder_step(state, _lane(p), 0, x_stop, t_late)
    last_edge = math.floor(x_stop / RES) * RES - 0.5e-6
    elapsed_ticks = math.floor(t_late / tick) - math.floor(last_edge / v / tick)
    assert encoder_period_speed(state, _lane(p), 0, t_late) == pytest.approx(RES / (elapsed_ticks * tick), rel=1e-12)
    # dither across the edge just below: back then forward -> same edge twice
    edge = math.floor(x_stop / RES) * RES
    encoder_step(state, _lane(p), 0, edge - 1e-9, t_late + DT)
    encoder_step(state, _lane(p), 0, edge + 1e-9, t_late + 2 * DT)
    assert encoder_period_speed(state, _lane(p), 0, t_late + 2 * DT) == 0.0


def test_fidelity_zero_speed_is_the_exact_window_mean():
    p = linear_encoder_parameters(bench_sensors(), fidelity=0)
    state = np.zeros((ENC_STATE_SIZE, 1))
    encoder_init(state, _lane(p), 0, 0.0, 0.0)
    encoder_step(state, _lane(p), 0, 1.234567e-7, 1e-3)
    assert encoder_speed(state, _lane(p), 0, 1e-3) == pytest.approx(1.234567e-4, rel=1e-12)


def test_phase_error_shows_as_period_method_ripple():
    # Consecutive edges are 90 deg +/- delta apart, so the period method reads
    # v * 90 / (90 +/- delta); the frequency method is unaffected.
    delta = 30.0
    p = encoder_parameters(resolution=RES, timer_period=2.5e-8, phase_error=math.radians(delta))
    v = 0.0103  # 2.575 signal periods per sample: samples fall after every kind of edge
    est = _constant_speed_run(p, v, duration=0.03)
    b_p, b_f = _bounds(v, 2.5e-8)
    expected = v * 90.0 / np.array([90.0 + delta, 90.0 - delta])
    # Between edges the elapsed-time bound can pull a reading below the last
    # interval's value, never outside the two spacings' values.
    assert np.all((est[:, 0] >= expected[0] - b_p) & (est[:, 0] <= expected[1] + b_p))
    for value in expected:  # both edge spacings are seen
        assert np.min(np.abs(est[:, 0] - value)) <= b_p
    assert np.all(np.abs(est[:, 1] - v) <= b_f * (1 + 1e-9))
