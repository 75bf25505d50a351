"""The sensor functions as an engine calls them: inside one compiled loop, one lane, noise pre-drawn."""

import math

import numba
import numpy as np
from bench_helpers import bench_sensors

from sensors.acquisition import draw_uniform_noise
from sensors.analog import AN_NOISE_HALF_WIDTH, AS_SIZE, analog_init, analog_read, analog_step, with_integration_step
from sensors.encoder import (
    ENC_STATE_SIZE,
    encoder_init,
    encoder_reading,
    encoder_speed,
    encoder_step,
    linear_encoder_parameters,
)
from sensors.lanes import lane_group
from sensors.resolver import resolver_angle, resolver_parameters
from sensors.torque_meter import torque_meter_parameters

DT, STEPS_PER_SAMPLE, SAMPLES = 1e-5, 100, 200


@numba.njit
def _loop(p_enc, p_tm, p_res, noise, out):
    enc = np.zeros((ENC_STATE_SIZE, 1))
    tm = np.zeros((AS_SIZE, 1))
    encoder_init(enc, p_enc, 0, 0.0, 0.0)
    analog_init(tm, p_tm, 0, 0.0, 0.0)
    for j in range(SAMPLES):
        for k in range(STEPS_PER_SAMPLE):
            t = (j * STEPS_PER_SAMPLE + k + 1) * DT
            x = 1e-3 * math.sin(2 * math.pi * 5.0 * t)  # sled: 1 mm at 5 Hz
            encoder_step(enc, p_enc, 0, x, t)
            analog_step(tm, p_tm, 0, 3.0 * math.sin(2 * math.pi * 5.0 * t), t)
        out[j, 0] = encoder_reading(enc, p_enc, 0)
        out[j, 1] = encoder_speed(enc, p_enc, 0, t)
        out[j, 2] = analog_read(tm, p_tm, 0, noise[j])
        out[j, 3] = resolver_angle(p_res, 0, 100.0 * t)


def _run(seed):
    p_enc = linear_encoder_parameters(bench_sensors({"sensors.linear_encoder_phase_error": 0.3}))
    p_tm = with_integration_step(torque_meter_parameters(bench_sensors(), room_temperature=303.15), DT)
    noise = draw_uniform_noise(np.random.default_rng(seed), SAMPLES, p_tm[AN_NOISE_HALF_WIDTH])
    out = np.empty((SAMPLES, 4))
    _loop(lane_group([p_enc]), lane_group([p_tm]), lane_group([resolver_parameters(bench_sensors())]), noise, out)
    return out


def test_sensors_run_inside_a_compiled_loop_and_reproduce_from_the_seed():
    a, b, c = _run(11), _run(11), _run(12)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a[:, 2], c[:, 2])  # only the noisy channel differs
    np.testing.assert_array_equal(a[:, [0, 1, 3]], c[:, [0, 1, 3]])
    t = np.arange(1, SAMPLES + 1) * STEPS_PER_SAMPLE * DT
    x = 1e-3 * np.sin(2 * np.pi * 5.0 * t)
    assert np.max(np.abs(a[:, 0] - x)) <= 1e-6 + 0.3 / (2 * np.pi) * 4e-6  # count + phase error
    v = 1e-3 * 2 * np.pi * 5.0 * np.cos(2 * np.pi * 5.0 * t)
    v_max = 1e-3 * 2 * np.pi * 5.0
    ripple = 0.3 / (np.pi / 2 - 0.3)  # phase-error ripple of the period method, docs/sensors.md
    assert np.max(np.abs(a[:, 1] - v)) < (ripple + 0.05) * v_max  # + lag of one edge interval
    # torque: ±2.5 %FS noise on 50 N*m (±1.25 N*m) plus hold lag of up to one refresh period
    torque = 3.0 * np.sin(2 * np.pi * 5.0 * t)
    assert np.max(np.abs(a[:, 2] - torque)) <= 1.25 + 3.0 * 2 * np.pi * 5.0 * 1e-3 + 0.01
