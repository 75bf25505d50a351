"""Motor resolver angle reading."""

import math

import numpy as np
import pytest
from bench_helpers import bench_sensors

from sensors.resolver import RES_OFFSET, RES_RESOLUTION, resolver_angle, resolver_parameters

ARCMIN = math.pi / 10800


def test_ideal_resolver_quantises_to_0p8_arcmin():
    p = resolver_parameters(bench_sensors())
    assert p[RES_RESOLUTION] == pytest.approx(0.8 * ARCMIN)
    theta = np.random.default_rng(9).uniform(-50.0, 50.0, 5000)  # multi-turn
    err = np.array([resolver_angle(th, p) for th in theta]) - theta
    assert np.max(np.abs(err)) <= 0.4 * ARCMIN * (1 + 1e-9)


def test_accuracy_is_a_twice_per_revolution_error_of_the_given_amplitude():
    p = resolver_parameters(bench_sensors({"sensors.resolver_accuracy": 10 * ARCMIN}))
    theta = np.linspace(0.0, 2 * math.pi, 4001)
    err = np.array([resolver_angle(th, p) for th in theta]) - theta
    np.testing.assert_allclose(err, 10 * ARCMIN * np.sin(2 * theta), atol=0.4 * ARCMIN * (1 + 1e-9))
    assert np.max(err) == pytest.approx(10 * ARCMIN, abs=0.4 * ARCMIN)


def test_offset_is_a_fraction_of_one_revolution():
    p = resolver_parameters(bench_sensors({"sensors.resolver_offset": 2e-4}))
    assert p[RES_OFFSET] == pytest.approx(2e-4 * 2 * math.pi)  # 4.32 arcmin
    theta = np.random.default_rng(10).uniform(0.0, 2 * math.pi, 20000)
    err = np.array([resolver_angle(th, p) for th in theta]) - theta
    assert err.mean() == pytest.approx(2e-4 * 2 * math.pi, abs=0.02 * ARCMIN)


def test_out_of_bound_accuracy_is_rejected_by_name():
    with pytest.raises(ValueError, match="sensors.resolver_accuracy"):
        resolver_parameters(bench_sensors({"sensors.resolver_accuracy": 11 * ARCMIN}))
    with pytest.raises(ValueError, match="sensors.resolver_error_harmonic"):
        resolver_parameters(bench_sensors({"sensors.resolver_error_harmonic": 2.5}))
