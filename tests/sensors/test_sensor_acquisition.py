"""Converters, electrical noise and the Table 9.5 range -> sigma convention."""

import math

import numpy as np
import pytest

from sensors.acquisition import (
    convert,
    converter_lsb,
    draw_uniform_noise,
    first_order_lag,
    lag_gain,
    lag_step,
    power_of_two,
    quantize,
    sigma_from_range,
    validate_converter,
)


def test_quantize_is_mid_tread_with_half_lsb_error():
    lsb = 0.01
    assert quantize(0.0, lsb) == 0.0
    assert quantize(0.0049, lsb) == 0.0 and quantize(-0.0049, lsb) == 0.0
    assert quantize(0.005, lsb) == pytest.approx(lsb)  # ties round up
    assert quantize(-0.0051, lsb) == pytest.approx(-lsb)
    x = np.random.default_rng(5).uniform(-3.0, 3.0, 10000)
    err = np.array([quantize(v, lsb) for v in x]) - x
    assert np.max(np.abs(err)) <= lsb / 2 * (1 + 1e-9)


def test_convert_11_bits_plus_sign_saturates_at_the_extreme_codes():
    lsb = 10.0 / 2048  # Table B.3: 11 bits + sign over ±10 V
    assert convert(10.0, 10.0, 12) == pytest.approx(10.0 - lsb)
    assert convert(25.0, 10.0, 12) == pytest.approx(10.0 - lsb)
    assert convert(-10.0, 10.0, 12) == pytest.approx(-10.0)
    assert convert(-25.0, 10.0, 12) == pytest.approx(-10.0)
    assert convert(0.4 * lsb, 10.0, 12) == 0.0
    assert convert(0.6 * lsb, 10.0, 12) == pytest.approx(lsb)
    x = np.random.default_rng(6).uniform(-9.99, 9.99, 5000)
    err = np.array([convert(v, 10.0, 12) for v in x]) - x
    assert np.max(np.abs(err)) <= lsb / 2 * (1 + 1e-9)


def test_validate_converter_names_the_field():
    with pytest.raises(ValueError, match="daq"):
        validate_converter("daq", -10.0, 16)
    with pytest.raises(ValueError, match="daq"):
        validate_converter("daq", 10.0, 15.5)


def test_uniform_noise_bounds_mean_and_variance():
    n, h = 1_000_000, 0.25  # ±2.5 %FS of a 10 V channel
    noise = draw_uniform_noise(np.random.default_rng(7), n, h)
    assert noise.shape == (n,) and noise.dtype == np.float64
    assert np.all(np.abs(noise) <= h)
    # P(max < h (1 - 40/n)) = (1 - 20/n)^n ~ e^-20: the support is filled.
    assert noise.max() > h * (1 - 40 / n) and noise.min() < -h * (1 - 40 / n)
    # mean: sigma_mean = h / sqrt(3 n); 5 sigma tolerance (false failure 6e-7)
    assert abs(noise.mean()) < 5 * h / math.sqrt(3 * n)
    # variance h^2/3; Var(s^2) = (mu4 - sigma^4)/n = (h^4/5 - h^4/9)/n = 4 h^4 / (45 n); 5 sigma
    assert abs(noise.var() - h * h / 3) < 5 * math.sqrt(4 / (45 * n)) * h * h


def test_noise_is_reproducible_from_the_seed():
    a = draw_uniform_noise(np.random.default_rng(42), 1000, 0.25)
    b = draw_uniform_noise(np.random.default_rng(42), 1000, 0.25)
    c = draw_uniform_noise(np.random.default_rng(43), 1000, 0.25)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_noise_rejects_bad_arguments():
    with pytest.raises(ValueError, match="half_width"):
        draw_uniform_noise(np.random.default_rng(0), 10, -0.1)
    with pytest.raises(ValueError, match="rng"):
        draw_uniform_noise(np.random.RandomState(0), 10, 0.1)
    for n in (-1, -3, 2.5):
        with pytest.raises(ValueError, match="n: number of noise samples"):
            draw_uniform_noise(np.random.default_rng(0), n, 0.1)


def test_range_is_three_sigma():
    assert sigma_from_range(0.006) == pytest.approx(0.002)
    with pytest.raises(ValueError, match="half_range"):
        sigma_from_range(-1.0)


def test_first_order_lag_is_the_exact_discretisation():
    """tau dy/dt + y = u: a step input decays as exp(-dt/tau); a ramp settles to the lag u - tau du/dt, whatever
    dt is against tau; dt <= 0 leaves the output as it was."""
    tau = 2e-3
    for dt in (1e-4, 2e-3, 5e-2):
        assert first_order_lag(1.0, 3.0, 3.0, dt, tau) == pytest.approx(3.0 - 2.0 * math.exp(-dt / tau), rel=1e-12)
        # on the ramp u = 10 t, starting on its steady lag y = u - tau * 10, the output stays on it
        u0, u1 = 10.0 * 0.5, 10.0 * (0.5 + dt)
        assert first_order_lag(u0 - 10.0 * tau, u0, u1, dt, tau) == pytest.approx(u1 - 10.0 * tau, rel=1e-12)
    assert first_order_lag(0.7, 1.0, 5.0, 0.0, tau) == 0.7


def test_converter_step_is_full_scale_over_two_to_the_bits_less_one_exactly():
    """lsb = FS / 2^(bits - 1), the power of two built from its exponent bits (no pow call): exact for every word
    length, e.g. 10 V / 2^15 for the 16-bit DAQ and 10 V / 2^11 for the drive's 11 bits + sign."""
    for n in range(-1022, 1024, 7):
        assert power_of_two(float(n)) == 2.0**n
    assert converter_lsb(10.0, 16.0) == 10.0 / 32768.0 and converter_lsb(10.0, 12.0) == 10.0 / 2048.0
    for bits in range(2, 54):
        assert converter_lsb(10.0, float(bits)) == 10.0 / 2.0 ** (bits - 1)


def test_lag_from_precomputed_coefficients_is_the_lag():
    """first_order_lag is lag_step with its coefficients 1 - exp(-dt/tau) and tau/dt computed per call: the same
    bits as computing them once for a fixed step (what the analog channels do)."""
    tau, dt = 1.59e-5, 6.25e-5
    gain, tau_over_dt = lag_gain(dt, tau), tau / dt
    assert gain == pytest.approx(1.0 - math.exp(-dt / tau), rel=1e-15)
    for y0, u0, u1 in ((0.0, 1.0, 1.0), (2.5, -1.0, 3.0), (-7.0, 4.0, 4.5)):
        assert lag_step(y0, u0, u1, gain, tau_over_dt) == first_order_lag(y0, u0, u1, dt, tau)
