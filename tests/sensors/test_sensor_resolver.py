"""Motor resolver angle reading."""

import math

import numpy as np
import pytest
from bench_helpers import bench_sensors

from sensors.resolver import RES_MOUNTING_ANGLE, RES_OFFSET, RES_RESOLUTION, resolver_angle, resolver_parameters

ARCMIN = math.pi / 10800


def _readings(p, theta):
    """Resolver readings of one lane's parameter vector ``p`` (lane 0 of a one-lane group) at the angles ``theta``."""
    lane = np.ascontiguousarray(p.reshape(-1, 1))
    return np.array([resolver_angle(lane, 0, th) for th in theta])


def test_ideal_resolver_quantises_to_0p8_arcmin():
    p = resolver_parameters(bench_sensors())
    assert p[RES_RESOLUTION] == pytest.approx(0.8 * ARCMIN)
    theta = np.random.default_rng(9).uniform(-50.0, 50.0, 5000)  # multi-turn
    err = _readings(p, theta) - theta
    assert np.max(np.abs(err)) <= 0.4 * ARCMIN * (1 + 1e-9)


def test_accuracy_is_a_twice_per_revolution_error_of_the_given_amplitude():
    p = resolver_parameters(bench_sensors({"sensors.resolver_accuracy": 10 * ARCMIN}))
    theta = np.linspace(0.0, 2 * math.pi, 4001)
    err = _readings(p, theta) - theta
    np.testing.assert_allclose(err, 10 * ARCMIN * np.sin(2 * theta), atol=0.4 * ARCMIN * (1 + 1e-9))
    assert np.max(err) == pytest.approx(10 * ARCMIN, abs=0.4 * ARCMIN)


def test_offset_is_a_fraction_of_one_revolution():
    p = resolver_parameters(bench_sensors({"sensors.resolver_offset": 2e-4}))
    assert p[RES_OFFSET] == pytest.approx(2e-4 * 2 * math.pi)  # 4.32 arcmin
    theta = np.random.default_rng(10).uniform(0.0, 2 * math.pi, 20000)
    err = _readings(p, theta) - theta
    assert err.mean() == pytest.approx(2e-4 * 2 * math.pi, abs=0.02 * ARCMIN)


def test_out_of_bound_accuracy_is_rejected_by_name():
    with pytest.raises(ValueError, match="sensors.resolver_accuracy"):
        resolver_parameters(bench_sensors({"sensors.resolver_accuracy": 11 * ARCMIN}))
    with pytest.raises(ValueError, match="sensors.resolver_error_harmonic"):
        resolver_parameters(bench_sensors({"sensors.resolver_error_harmonic": 2.5}))
    with pytest.raises(ValueError, match="sensors.resolver_mounting_angle"):
        resolver_parameters(bench_sensors({"sensors.resolver_mounting_angle": 7.0}))


# --- mounting angle (issue 33) ------------------------------------------------------------------------------
def test_the_accuracy_error_follows_the_rotor_not_the_test():
    """With the rotor at phi at the start, the twice-per-revolution error along the test is A sin(2 (theta + phi)):
    at phi = pi/4 the error at the test's start is +A (the crest), at phi = 0 it is 0."""
    phi = math.pi / 4
    p = resolver_parameters(bench_sensors({"sensors.resolver_accuracy": 10 * ARCMIN,
                                           "sensors.resolver_mounting_angle": phi}))
    assert p[RES_MOUNTING_ANGLE] == phi
    theta = np.linspace(0.0, 2 * math.pi, 4001)
    err = _readings(p, theta) - theta
    np.testing.assert_allclose(err, 10 * ARCMIN * np.sin(2 * (theta + phi)), atol=0.4 * ARCMIN * (1 + 1e-9))
    assert err[0] == pytest.approx(10 * ARCMIN, abs=0.4 * ARCMIN)


def test_the_quantisation_grid_is_fixed_to_the_rotor():
    """An ideal resolver (no accuracy or offset error) mounted at phi reads the angle since the start to within half a
    step, and its readings are grid points of the rotor's absolute angle less phi: the drive's speed difference
    between two readings is a whole number of 0.8' steps."""
    step = 0.8 * ARCMIN
    phi = 0.37 * step + 2.0  # not a whole number of steps
    p = resolver_parameters(bench_sensors({"sensors.resolver_mounting_angle": phi}))
    theta = np.random.default_rng(12).uniform(-20.0, 20.0, 3000)
    reading = _readings(p, theta)
    assert np.max(np.abs(reading - theta)) <= 0.5 * step * (1 + 1e-9)
    steps = (reading + phi) / step
    np.testing.assert_allclose(steps, np.round(steps), rtol=0, atol=1e-9)
    # the grid is the rotor's: the same angles read by a resolver mounted at 0 fall on other grid points
    unmounted = _readings(resolver_parameters(bench_sensors()), theta)
    assert np.mean(np.abs(unmounted - reading) > 1e-12) > 0.3


def test_mounting_angle_zero_is_the_resolver_without_it():
    p = resolver_parameters(bench_sensors({"sensors.resolver_accuracy": 7 * ARCMIN, "sensors.resolver_offset": 1e-4}))
    assert p[RES_MOUNTING_ANGLE] == 0.0
    theta = np.random.default_rng(13).uniform(-50.0, 50.0, 2000)
    step = p[RES_RESOLUTION]
    expected = step * np.floor((theta + p[RES_OFFSET] + 7 * ARCMIN * np.sin(2 * theta)) / step + 0.5)
    np.testing.assert_array_equal(_readings(p, theta), expected)
