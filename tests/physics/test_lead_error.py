"""The screw's travel deviation (ISO 3408-3 terms: mean slope, long wave, per revolution) as a law of the angle."""

import math

import numpy as np
import pytest

from numerics.elementary import sin
from twin.physics.ball_screw import ball_angular_pitch, ball_averaging_factor, travel_deviation

ARM = 5.0e-3 / (2.0 * math.pi)  # the bench screw's p / 2 pi [m/rad]
WAVE_NUMBER = 5.0e-3 / 0.32     # p / lambda_u: one wave over the 320 mm stroke


def _deviation(angle, slope=0.0, wave=0.0, wave_phase=0.0, revolution=0.0, revolution_phase=0.0):
    # the offsets at the zero with the law's own sine, as twin.engine.model.lead_constants computes them
    return travel_deviation(angle, ARM, slope, wave, WAVE_NUMBER, wave_phase, sin(wave_phase), revolution,
                            revolution_phase, sin(revolution_phase))


def test_zero_at_the_test_zero_and_exactly_zero_without_amplitudes():
    assert _deviation(0.0, 7e-5, 11e-6, 0.7, 4e-6, 2.1) == (0.0, pytest.approx(7e-5 * ARM + 11e-6 * WAVE_NUMBER
                                                                                * math.cos(0.7) + 4e-6 * math.cos(2.1)))
    for angle in (-12.5, -0.3, 0.0, 1e-7, 25.1):
        deviation, rate = _deviation(angle, wave_phase=1.3, revolution_phase=4.0)
        assert deviation == 0.0 and rate == 0.0  # phases alone change nothing: the model before the error


def test_each_term_is_its_closed_form():
    """The three ISO 3408-3 terms superpose: a slope times the nominal travel, one sine over the travel, one sine per
    revolution; relative 1e-12 (the elementary sine's 0.8 ulp against math.sin)."""
    angles = np.linspace(-4.0 * math.pi, 4.0 * math.pi, 97)  # +/-10 mm of travel, the tests' range
    s, a_u, phi_u, a_r, phi_r = 7.3e-5, 11.5e-6, 0.4, 4.0e-6, 2.5
    for angle in angles:
        expected = (s * ARM * angle + a_u * (math.sin(WAVE_NUMBER * angle + phi_u) - math.sin(phi_u))
                    + a_r * (math.sin(angle + phi_r) - math.sin(phi_r)))
        assert _deviation(angle, s, a_u, phi_u, a_r, phi_r)[0] == pytest.approx(expected, rel=1e-12, abs=1e-20)


def test_the_rate_is_the_derivative_of_the_deviation():
    """Central differences of e(phi) (truncation ~h^2 e''' / 6 ~ 1e-14 m/rad at h = 1e-4 rad) match e'(phi)."""
    h = 1e-4
    for angle in (-9.0, -1.0, 0.5, 3.3, 11.0):
        args = (7.3e-5, 11.5e-6, 0.4, 4.0e-6, 2.5)
        numeric = (_deviation(angle + h, *args)[0] - _deviation(angle - h, *args)[0]) / (2.0 * h)
        assert _deviation(angle, *args)[1] == pytest.approx(numeric, rel=1e-6)


def test_the_per_revolution_term_repeats_every_revolution_and_stays_in_its_band():
    a_r, phi_r = 4.0e-6, 1.1
    angles = np.linspace(0, 2 * math.pi, 9)
    one_turn = [_deviation(angle, revolution=a_r, revolution_phase=phi_r)[0] for angle in angles]
    next_turn = [_deviation(angle + 2 * math.pi, revolution=a_r, revolution_phase=phi_r)[0] for angle in angles]
    np.testing.assert_allclose(next_turn, one_turn, rtol=0, atol=1e-18)
    band = [_deviation(angle, revolution=a_r, revolution_phase=phi_r)[0] for angle in np.linspace(0, 2 * math.pi, 721)]
    assert max(band) - min(band) == pytest.approx(2 * a_r, rel=1e-4)  # v_2pi: the peak-to-peak variation


def test_ball_angular_pitch_is_one_ball_diameter_along_the_helix():
    """Closed forms: with no lead the helix is the pitch circle, so the angle is the diameter over the radius
    (arc = r d); with a lead the turn lengthens to sqrt((2 pi r)^2 + p^2) and the angle shrinks by that ratio."""
    assert math.isclose(ball_angular_pitch(0.003, 0.02, 0.0), 2 * 0.003 / 0.02, rel_tol=1e-15)
    turn = math.hypot(2 * math.pi * 0.02, 0.01)
    assert math.isclose(ball_angular_pitch(0.003, 0.02, 0.01), 2 * math.pi * 0.006 / turn, rel_tol=1e-15)


def test_ball_averaging_factor_known_answers():
    """One ball: 1; N balls spanning one whole period (N d = 2 pi): the sines cancel, 0; small spread: 1 - (N^2 - 1)
    d^2 / 24 to second order (the Dirichlet kernel's expansion)."""
    assert ball_averaging_factor(1, 0.395) == 1.0
    assert abs(ball_averaging_factor(8, 2 * math.pi / 8)) < 1e-15
    d = 1e-3
    assert math.isclose(ball_averaging_factor(5, d), 1 - (25 - 1) * d**2 / 24, rel_tol=1e-9)
