"""Quadrature encoder: edge pattern, path-independent counting, counters on reversals, mounting phase.

The compiled functions are in lane form (``sensors.lanes``): one lane's parameter vector ``p`` from a builder is
stepped as the one-lane group ``p[:, None]`` (lane 0) with a ``[ENC_STATE_SIZE, 1]`` state."""

import math

import numba
import numpy as np
import pytest
from bench_helpers import bench_sensors

from sensors.encoder import (
    ENC_EDGE,
    ENC_MOUNTING_OFFSET,
    ENC_PERIOD,
    ENC_PRECISION_AMPLITUDE,
    ENC_S_BACKWARD,
    ENC_S_COUNT,
    ENC_S_COUNT0,
    ENC_S_EDGE_DIR,
    ENC_S_EDGE_T,
    ENC_S_FORWARD,
    ENC_STATE_SIZE,
    encoder_count,
    encoder_init,
    encoder_overspeed,
    encoder_parameters,
    encoder_position,
    encoder_reading,
    encoder_step,
    linear_encoder_parameters,
    scale_position,
    torque_meter_encoder_parameters,
)

RES = 1.0e-6  # Table B.4
PERIOD = 4.0 * RES
TICK = 2.5e-8


def _params(**kw):
    kw.setdefault("resolution", RES)
    kw.setdefault("timer_period", TICK)
    return encoder_parameters(**kw)


def _lane(p):
    """One lane's parameter vector as a one-lane group (lane 0)."""
    return np.ascontiguousarray(p.reshape(-1, 1))


def _state():
    return np.zeros((ENC_STATE_SIZE, 1))


def _find_edge(p, lo, hi):
    """Bisect the position in [lo, hi] where the count changes (one edge inside)."""
    c_lo = encoder_count(lo, p)
    assert encoder_count(hi, p) == c_lo + 1
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        if encoder_count(mid, p) == c_lo:
            lo = mid
        else:
            hi = mid
    return hi


@pytest.mark.parametrize("fidelity", [1, 2])
def test_ideal_reference_equals_floor_quantisation_at_every_sample(fidelity):
    # All errors zero: the count must be floor(x / res) exactly, the zeroed
    # reading floor(x/res) - floor(x0/res), at every step of a random walk.
    rng = np.random.default_rng(1)
    p = _params(fidelity=fidelity)
    lane = _lane(p)
    x0 = 3.3e-6
    x = x0 + np.cumsum(rng.normal(0.0, 0.7 * RES, 20000))
    state = _state()
    encoder_init(state, lane, 0, x0, 0.0)
    n0 = math.floor(x0 / RES)
    for k, xk in enumerate(x):
        encoder_step(state, lane, 0, xk, (k + 1) * 1e-5)
        assert state[ENC_S_COUNT, 0] == math.floor(xk / RES)
        assert encoder_reading(state, lane, 0) == (math.floor(xk / RES) - n0) * RES
        assert encoder_position(xk, p) == math.floor(xk / RES) * RES


def test_fidelity_zero_returns_true_position():
    p = _params(fidelity=0, phase_error=0.3)
    for x in (-1.234567e-3, 0.0, 7.77e-6):
        assert encoder_position(x, p) == x


@pytest.mark.parametrize("delta_deg", [30.0, -45.0, 12.5])
def test_phase_error_shifts_only_the_b_edges_by_delta_over_360_of_the_period(delta_deg):
    delta = math.radians(delta_deg)
    p = _params(phase_error=delta)
    shift = delta / (2.0 * math.pi) * PERIOD
    for j in range(-3, 4):
        for k, nominal in enumerate((0.0, 0.25, 0.5, 0.75)):
            expected = (j + nominal) * PERIOD + (shift if k % 2 else 0.0)
            edge = _find_edge(p, expected - 0.1 * PERIOD, expected + 0.1 * PERIOD)
            assert edge == pytest.approx(expected, abs=1e-9 * PERIOD)


@pytest.mark.parametrize("delta_deg", [30.0, -20.0])
def test_phase_error_gives_the_expected_periodic_position_error(delta_deg):
    # Delaying both B edges by s (s > 0) makes the reading one count low over
    # an interval s after each B edge: error in {-res, 0}, on a fraction
    # 2|s|/P of the period, mean -s/2; negative s gives +res before B edges.
    s = math.radians(delta_deg) / (2.0 * math.pi) * PERIOD
    p = _params(phase_error=math.radians(delta_deg))
    m = 4000  # grid points per period
    x = (np.arange(10 * m) + 0.5) / m * PERIOD - 5 * PERIOD
    error_counts = np.array([encoder_count(xi, p) for xi in x]) - np.floor(x / RES)
    assert set(error_counts) == ({-1.0, 0.0} if s > 0 else {0.0, 1.0})
    assert np.mean(error_counts != 0.0) == pytest.approx(2.0 * abs(s) / PERIOD, abs=2.0 / m)
    assert RES * error_counts.mean() == pytest.approx(-s / 2.0, abs=2.0 * RES / m)
    np.testing.assert_array_equal(error_counts[:-m], error_counts[m:])  # periodic in the signal period


def test_duty_asymmetry_moves_each_phase_rise_and_fall_symmetrically():
    eps_a, eps_b, delta = math.radians(15.0), math.radians(-10.0), math.radians(20.0)
    p = _params(phase_error=delta, asymmetry_a=eps_a, asymmetry_b=eps_b)
    frac = np.array([-eps_a / 2, delta - eps_b / 2, eps_a / 2, delta + eps_b / 2]) / (2.0 * math.pi)
    expected = (np.array([0.0, 0.25, 0.5, 0.75]) + frac) * PERIOD
    np.testing.assert_allclose(p[ENC_EDGE : ENC_EDGE + 4], expected, rtol=0, atol=1e-20)
    for e in expected + 2.0 * PERIOD:
        assert _find_edge(p, e - PERIOD / 10.0, e + PERIOD / 10.0) == pytest.approx(e, abs=1e-9 * PERIOD)


def test_precision_error_follows_the_sinusoid_along_the_stroke():
    amplitude, wavelength = 5.0e-6, 0.32
    p = _params(precision_amplitude=amplitude, precision_wavelength=wavelength)
    x = np.random.default_rng(2).uniform(-0.16, 0.16, 5000)
    u = x + amplitude * np.sin(2.0 * np.pi * x / wavelength)
    reading = np.array([encoder_position(xi, p) for xi in x])
    # floor quantisation of the scale position: u - res < reading <= u
    assert np.all(reading <= u + 1e-15) and np.all(reading > u - RES - 1e-15)
    assert np.max(reading - x) > amplitude - RES and np.min(reading - x) < -amplitude


@numba.njit
def _run(state, p, t, x, fwd, bwd, count):
    for k in range(x.size):
        encoder_step(state, p, 0, x[k], t[k])
        fwd[k] = state[ENC_S_FORWARD, 0]
        bwd[k] = state[ENC_S_BACKWARD, 0]
        count[k] = state[ENC_S_COUNT, 0] - state[ENC_S_COUNT0, 0]


def _reversal_trajectory(p, rng, n):
    """Random walk with frequent reversals, half the time dithering within 1e-6 res of an edge."""
    x = np.empty(n)
    pos = 0.0
    k = 0
    while k < n:
        m = min(int(rng.integers(50, 500)), n - k)
        if rng.random() < 0.5:
            steps = rng.uniform(0.0, 3.0 * RES, m) * rng.choice([-1.0, 1.0], m)
            x[k : k + m] = np.clip(pos + np.cumsum(steps), -40 * RES, 40 * RES)
        else:
            n_edge = float(rng.integers(-150, 150))
            j = math.floor(n_edge / 4.0)
            edge = p[ENC_EDGE + int(n_edge - 4 * j)] + j * p[ENC_PERIOD]
            # 1e-18 m is ~40 ulps of these positions: closer than that the edge
            # location itself is only defined to rounding.
            x[k : k + m] = edge + rng.choice([-1.0, 1.0], m) * 10.0 ** rng.uniform(-18, -12, m)
        pos = x[k + m - 1]
        k += m
    return x


def test_no_lost_or_extra_counts_over_1e5_random_reversals():
    p = _params(phase_error=math.radians(40.0), asymmetry_a=math.radians(-12.0), asymmetry_b=math.radians(9.0))
    rng = np.random.default_rng(3)
    n = 300_000
    x = _reversal_trajectory(p, rng, n)
    dx = np.diff(x)
    moving = dx[dx != 0.0]
    reversals = np.count_nonzero(np.sign(moving[1:]) != np.sign(moving[:-1]))
    assert reversals >= 100_000

    # Independent reference: the sorted list of edge positions.
    edges = np.sort((p[ENC_EDGE : ENC_EDGE + 4][None, :] + np.arange(-60, 61)[:, None] * PERIOD).ravel())
    x0 = 0.0
    ref = np.searchsorted(edges, x, side="right") - np.searchsorted(edges, x0, side="right")

    state = _state()
    encoder_init(state, _lane(p), 0, x0, 0.0)
    fwd, bwd, count = np.empty(n), np.empty(n), np.empty(n)
    _run(state, _lane(p), np.arange(1, n + 1) * 1e-6, x, fwd, bwd, count)

    np.testing.assert_array_equal(count, ref)  # path independent: count = edges below x
    np.testing.assert_array_equal(fwd - bwd, count)  # every step
    # Each step adds exactly the edges it crossed to the counter of its direction.
    crossed = np.diff(np.concatenate([[0], ref]))
    np.testing.assert_array_equal(np.diff(np.concatenate([[0.0], fwd])), np.maximum(crossed, 0))
    np.testing.assert_array_equal(np.diff(np.concatenate([[0.0], bwd])), np.maximum(-crossed, 0))


def test_edge_time_is_interpolated_inside_the_step():
    p = _params(phase_error=math.radians(25.0))
    lane = _lane(p)
    v = 0.013
    state = _state()
    encoder_init(state, lane, 0, 0.1e-6, 0.0)
    t1 = 2.5e-4  # crosses a few edges in one step
    encoder_step(state, lane, 0, 0.1e-6 + v * t1, t1)
    last = state[ENC_S_COUNT, 0]
    j = math.floor(last / 4)
    edge = p[ENC_EDGE + int(last - 4 * j)] + j * PERIOD
    assert state[ENC_S_EDGE_T, 0] == pytest.approx((edge - 0.1e-6) / v, rel=1e-12)
    assert state[ENC_S_EDGE_DIR, 0] == 1.0
    # backward through the same edges: the last one crossed is count + 1
    encoder_step(state, lane, 0, 0.1e-6, 2 * t1)
    first_back = state[ENC_S_COUNT, 0] + 1
    j = math.floor(first_back / 4)
    edge = p[ENC_EDGE + int(first_back - 4 * j)] + j * PERIOD
    assert state[ENC_S_EDGE_T, 0] == pytest.approx(t1 + (0.1e-6 + v * t1 - edge) / v, rel=1e-12)
    assert state[ENC_S_EDGE_DIR, 0] == -1.0


def test_overspeed_flag_against_the_datasheet_maximum_frequency():
    lane = _lane(linear_encoder_parameters(bench_sensors()))
    for v, expected in ((0.1, False), (0.3, True)):  # 25 kHz and 75 kHz signal
        state = _state()
        encoder_init(state, lane, 0, 0.0, 0.0)
        for k in range(1, 101):
            encoder_step(state, lane, 0, v * k * 1e-5, k * 1e-5)
        assert encoder_overspeed(state, 50e3).tolist() == [expected]


def test_bench_encoders_use_the_datasheet_resolutions():
    assert linear_encoder_parameters(bench_sensors())[ENC_PERIOD] == pytest.approx(4e-6)
    p = torque_meter_encoder_parameters(bench_sensors())
    assert p[ENC_PERIOD] == pytest.approx(2 * math.pi / 2000)  # 2000 pulses/turn
    assert encoder_count(2 * math.pi + 1e-9, p) == 8000.0  # x4 decoding
    assert scale_position(_lane(p), 0, 0.5) == 0.5  # no precision error on the torque meter encoder


def test_validation_names_the_field():
    with pytest.raises(ValueError, match="resolution"):
        encoder_parameters(resolution=-1e-6, timer_period=TICK)
    with pytest.raises(ValueError, match="timer_period"):
        encoder_parameters(resolution=1e-6, timer_period=0.0)
    with pytest.raises(ValueError, match="fidelity"):
        encoder_parameters(resolution=1e-6, timer_period=TICK, fidelity=3)
    with pytest.raises(ValueError, match="phase_error"):  # B rise would pass A fall
        encoder_parameters(resolution=1e-6, timer_period=TICK, phase_error=math.radians(95.0))
    with pytest.raises(ValueError, match="precision_amplitude"):
        encoder_parameters(resolution=1e-6, timer_period=TICK, precision_amplitude=0.1, precision_wavelength=0.32)
    with pytest.raises(ValueError, match="sensors.linear_encoder_phase_error"):  # beyond ±45 deg
        linear_encoder_parameters(bench_sensors({"sensors.linear_encoder_phase_error": math.radians(50.0)}))
    with pytest.raises(ValueError, match="sensors.linear_encoder_resolution"):
        linear_encoder_parameters(bench_sensors({"sensors.linear_encoder_resolution": -1e-6}))
    with pytest.raises(ValueError, match="sensors.linear_encoder_phase_eror"):
        linear_encoder_parameters(bench_sensors({"sensors.linear_encoder_phase_eror": 0.1}))
    with pytest.raises(ValueError, match="sensors.torque_meter_encoder_pulses_per_turn"):
        torque_meter_encoder_parameters(bench_sensors({"sensors.torque_meter_encoder_pulses_per_turn": 2000.5}))


def test_precision_error_only_at_the_edge_accurate_level():
    """The scale's precision error e_p sin(2 pi x / lambda_p) is read at fidelity 2 only; the quantised and ideal
    levels read the true position."""
    worn = {"sensors.linear_encoder_precision": 3e-6, "sensors.linear_encoder_precision_wavelength": 0.02}
    x = 0.007
    for fidelity in (0, 1):
        assert scale_position(_lane(linear_encoder_parameters(bench_sensors(worn), fidelity=fidelity)), 0, x) == x
    p = linear_encoder_parameters(bench_sensors(worn), fidelity=2)
    amplitude = p[ENC_PRECISION_AMPLITUDE]
    assert amplitude != 0.0
    # numerics.elementary.sin is within 1 ulp of libm's: the same to 1e-12
    assert scale_position(_lane(p), 0, x) == pytest.approx(x + amplitude * math.sin(2 * math.pi * x / 0.02), rel=1e-12,
                                                           abs=1e-15)


# --- mounting phase (issue 33) -----------------------------------------------------------------------------
@pytest.mark.parametrize("phase", [0.125, 0.3, 0.9])
def test_mounting_phase_shifts_every_edge_by_phase_times_the_period(phase):
    """o_k -> o_k + phase P: the four edges of the erroneous pattern (fidelity 2), found by bisection on the count,
    and the ideal edges of the quantised level, all move by phase P along the scale."""
    errors = dict(phase_error=math.radians(20.0), asymmetry_a=math.radians(-10.0), asymmetry_b=math.radians(-10.0))
    reference, shifted = _params(**errors), _params(mounting_phase=phase, **errors)
    np.testing.assert_allclose(shifted[ENC_EDGE : ENC_EDGE + 4], reference[ENC_EDGE : ENC_EDGE + 4] + phase * PERIOD,
                               rtol=0, atol=1e-21)
    assert shifted[ENC_MOUNTING_OFFSET] == phase * PERIOD
    for e in reference[ENC_EDGE : ENC_EDGE + 4] + 3.0 * PERIOD:
        assert _find_edge(shifted, e + phase * PERIOD - 0.1 * PERIOD, e + phase * PERIOD + 0.1 * PERIOD) == (
            pytest.approx(e + phase * PERIOD, abs=1e-9 * PERIOD))
    quantised = _params(fidelity=1, mounting_phase=phase)
    for n in range(-6, 7):  # ideal edges at n res + phase P
        edge = n * RES + phase * PERIOD
        assert _find_edge(quantised, edge - 0.4 * RES, edge + 0.4 * RES) == pytest.approx(edge, abs=1e-9 * RES)


def test_mounting_phase_zero_is_the_pattern_without_it_and_one_period_reads_the_same():
    """Phase 0 is the model before the parameter (same vector); phase 1 shifts the pattern by a whole period, which
    the zeroing removes: every zeroed reading is the same."""
    assert np.array_equal(_params(mounting_phase=0.0), _params())
    x = np.random.default_rng(11).uniform(-20 * RES, 20 * RES, 400)
    for fidelity in (1, 2):
        readings = []
        for phase in (0.0, 1.0):
            lane = _lane(_params(fidelity=fidelity, mounting_phase=phase, phase_error=0.3, asymmetry_a=0.1,
                                 asymmetry_b=-0.1))
            state = _state()
            encoder_init(state, lane, 0, 0.37 * RES, 0.0)
            out = []
            for k, xk in enumerate(x):
                encoder_step(state, lane, 0, xk, (k + 1) * 1e-4)
                out.append(encoder_reading(state, lane, 0))
            readings.append(out)
        assert readings[0] == readings[1]


@pytest.mark.parametrize("fidelity", [1, 2])
def test_a_hold_at_the_zero_reads_by_where_the_zero_falls_within_a_count(fidelity):
    """Issue 33's mechanism, known answers: a sled held at its start position with a dither of +-0.1 res. With
    phase 0 the zero sits on an A-rise edge: the reading flickers between -1 and 0 counts (mean -0.5 res for a
    symmetric dither). With phase 0.125 (half a count) the zero sits mid-way between two edges: it reads 0 steadily.
    """
    dither = 0.1 * RES * np.where(np.arange(200) % 2 == 0, 1.0, -1.0)
    means = {}
    for phase in (0.0, 0.125):
        lane = _lane(_params(fidelity=fidelity, mounting_phase=phase))
        state = _state()
        encoder_init(state, lane, 0, 0.0, 0.0)
        readings = []
        for k, xk in enumerate(dither):
            encoder_step(state, lane, 0, xk, (k + 1) * 1e-3)
            readings.append(encoder_reading(state, lane, 0))
        means[phase] = np.mean(readings)
        if phase == 0.0:
            assert set(readings) == {-RES, 0.0}
        else:
            assert set(readings) == {0.0}
    assert means[0.0] == pytest.approx(-0.5 * RES) and means[0.125] == 0.0


def test_mounting_phase_outside_one_period_is_rejected_by_name():
    for phase in (-0.1, 1.5):
        with pytest.raises(ValueError, match="mounting_phase"):
            _params(mounting_phase=phase)
    with pytest.raises(ValueError, match="sensors.linear_encoder_mounting_phase"):
        linear_encoder_parameters(bench_sensors({"sensors.linear_encoder_mounting_phase": 1.2}))


def test_bench_builders_read_the_mounting_phases():
    values = bench_sensors({"sensors.linear_encoder_mounting_phase": 0.25,
                            "sensors.torque_meter_encoder_mounting_phase": 0.5})
    assert linear_encoder_parameters(values)[ENC_MOUNTING_OFFSET] == pytest.approx(0.25 * 4e-6)
    assert torque_meter_encoder_parameters(values)[ENC_MOUNTING_OFFSET] == pytest.approx(0.5 * 2 * math.pi / 2000)
    nominal = bench_sensors()
    assert linear_encoder_parameters(nominal)[ENC_MOUNTING_OFFSET] == 0.0
    assert torque_meter_encoder_parameters(nominal)[ENC_MOUNTING_OFFSET] == 0.0
