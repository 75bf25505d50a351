"""The branch-free lane functions against the branchy scalar laws they replace, on the edge cases where a select
could differ from an ``if``: an edge exactly on a step's end, reversals between and inside steps, steps of zero
length, several edges or refresh instants in one step, refresh instants tying with step ends, saturated converters.

The reference is ``sensor_branchy_reference`` (the pre-lane code transcribed in plain Python, libm included).
Where both compute with the same operations the comparison is bit for bit (the whole state after every step);
where the lane code uses :mod:`numerics.elementary` instead of libm (the precision error's sine, the conditioner's
expm1, the resolver's sine), the two differ by at most an ulp or so of the transcendental's result, and the
comparison says which tolerance it allows and why.
"""

import math

import numpy as np
import pytest
import sensor_branchy_reference as ref

from sensors.acquisition import convert, first_order_lag, quantize
from sensors.analog import AS_SIZE, analog_init, analog_parameters, analog_read, analog_step, with_integration_step
from sensors.encoder import (
    ENC_EDGE,
    ENC_PERIOD,
    ENC_S_COUNT,
    ENC_S_U,
    ENC_STATE_SIZE,
    encoder_init,
    encoder_parameters,
    encoder_reading,
    encoder_speed,
    encoder_step,
)
from sensors.resolver import resolver_angle

RES = 1.0e-6
DT = 2.0**-14        # ~61 us; a dyadic step, so t_k - t_(k-1) is exactly DT and refresh instants tie exactly


def _lane(p):
    return np.ascontiguousarray(np.asarray(p, dtype=np.float64).reshape(-1, 1))


def _same_bits(a, b):
    bits = [np.ascontiguousarray(v, dtype=np.float64).view(np.int64) for v in (a, b)]
    return np.array_equal(*bits)


def _edge(p, n):
    """Scale position of edge ``n`` of the pattern (reference formula)."""
    j = math.floor(n / 4)
    return p[ENC_EDGE + int(n - 4 * j)] + j * p[ENC_PERIOD]


class _Pair:
    """One encoder stepped by the lane function (lane 0 of a one-lane group) and by the reference, side by side."""

    def __init__(self, p, x0, t0):
        self.p, self.lane = p, _lane(p)
        self.new, self.old = np.zeros((ENC_STATE_SIZE, 1)), np.zeros(ENC_STATE_SIZE)
        encoder_init(self.new, self.lane, 0, x0, t0)
        ref.encoder_init(self.old, x0, t0, p)
        self.check()

    def step(self, x, t):
        encoder_step(self.new, self.lane, 0, x, t)
        ref.encoder_step(self.old, x, t, self.p)
        self.check()

    def sample(self, t):
        assert encoder_reading(self.new, self.lane, 0) == ref.encoder_reading(self.old, self.p)
        assert _same_bits(encoder_speed(self.new, self.lane, 0, t), ref.encoder_speed(self.old, t, self.p))
        self.check()

    def check(self):
        assert _same_bits(self.new[:, 0], self.old), (self.new[:, 0], self.old)


ERRORS = dict(phase_error=math.radians(35.0), asymmetry_a=math.radians(-12.0), asymmetry_b=math.radians(8.0))


@pytest.mark.parametrize("fidelity", [0, 1, 2])
def test_steps_ending_exactly_on_edges_forward_and_back(fidelity):
    """Each step ends exactly on an edge's position (the count is then the edge's own number: floor of an exact
    multiple), one or several edges at a time, then the same positions backwards: the whole state bit for bit."""
    p = encoder_parameters(resolution=RES, timer_period=2.5e-8, fidelity=fidelity, **ERRORS)
    edges = [_edge(p, n) for n in range(-3, 14)]
    pair = _Pair(p, edges[0], 0.0)
    t = 0.0
    for e in edges[1::1] + edges[::-2] + edges[::3]:
        t += DT
        pair.step(e, t)
        pair.sample(t)


@pytest.mark.parametrize("fidelity", [1, 2])
def test_reversals_between_and_inside_steps(fidelity):
    """Forward across two edges then back across three in the next step (a reversal between steps: dn = +2, -3);
    a step that ends where it started (an excursion inside the step, invisible: dn = 0); single-edge dithers; a
    step of zero length (t == t0: the peak frequency is not updated). The whole state bit for bit after each."""
    p = encoder_parameters(resolution=RES, timer_period=2.5e-8, fidelity=fidelity, **ERRORS)
    e = [_edge(p, n) for n in range(8)]
    x = 0.5 * (e[2] + e[3])
    pair = _Pair(p, x, 1.0)
    t = 1.0
    path = [0.5 * (e[4] + e[5]),            # +2 edges
            0.5 * (e[1] + e[2]),            # -3 edges
            0.5 * (e[1] + e[2]),            # no motion
            e[2] + 1e-12, e[2] - 1e-12,     # dither across edge 2
            e[2] + 1e-12, e[2] + 1e-12,
            0.5 * (e[6] + e[7])]            # +4 edges
    for k, xk in enumerate(path):
        t += DT
        pair.step(xk, t)
        if k == 2:
            pair.step(0.5 * (e[3] + e[4]), t)  # zero-length step: same t, one edge
        pair.sample(t)
    pair.sample(t)  # an empty window: frequency method, 0


@pytest.mark.parametrize("fidelity", [0, 1, 2])
def test_random_paths_with_multi_edge_steps_dither_and_stops(fidelity):
    """A random path (strokes of up to 6 edges per step, dither of a few ulps around an edge, stops), sampled
    every 16 steps through the speed-method switch: the whole state bit for bit at every step."""
    rng = np.random.default_rng(31)
    p = encoder_parameters(resolution=RES, timer_period=2.5e-8, fidelity=fidelity, **ERRORS)
    pair = _Pair(p, 0.3 * RES, 0.0)
    x, t = 0.3 * RES, 0.0
    for k in range(1, 3001):
        t = k * DT
        mode = (k // 200) % 3
        if mode == 0:
            x += rng.normal(0.0, 2.0 * RES)
        elif mode == 1:
            x = _edge(p, 5) + rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-18, -13)
        pair.step(x, t)
        if k % 16 == 0:
            pair.sample(t)


def test_precision_error_moves_the_scale_by_ulps_at_most_and_the_counts_not_at_all():
    """With a precision error the scale position u = x + e_p sin(k x) uses numerics.elementary.sin instead of libm's
    (both < 1 ulp from the true sine): u may differ in its last bit, counts and readings do not (a count could
    differ only for u within an ulp of an edge)."""
    rng = np.random.default_rng(32)
    p = encoder_parameters(resolution=RES, timer_period=2.5e-8, fidelity=2, precision_amplitude=4e-6,
                           precision_wavelength=1e-3, **ERRORS)
    lane = _lane(p)
    new, old = np.zeros((ENC_STATE_SIZE, 1)), np.zeros(ENC_STATE_SIZE)
    encoder_init(new, lane, 0, 0.0, 0.0)
    ref.encoder_init(old, 0.0, 0.0, p)
    x = 0.0
    for k in range(1, 5001):
        x += rng.normal(0.0, 3.0 * RES)
        encoder_step(new, lane, 0, x, k * DT)
        ref.encoder_step(old, x, k * DT, p)
        assert new[ENC_S_COUNT, 0] == old[ENC_S_COUNT]
        assert new[ENC_S_U, 0] == pytest.approx(old[ENC_S_U], rel=0, abs=4 * np.spacing(abs(old[ENC_S_U]) + 1e-6))


# --- analog channel -----------------------------------------------------------------------------------------
CHANNEL = dict(full_scale=100.0, output_full_scale=10.0, gain=1.002, offset=-3e-3, tau=0.0, refresh_period=0.0,
               output_bits=0.0, daq_full_scale=10.0, daq_bits=16.0, noise_half_width=0.25)


def _run_channel(p, times, x, noise):
    """States and readings after every step, lane function and reference side by side."""
    lane = _lane(with_integration_step(p, DT))
    new, old = np.zeros((AS_SIZE, 1)), np.zeros(AS_SIZE)
    analog_init(new, lane, 0, x[0], times[0])
    ref.analog_init(old, x[0], times[0], p)
    out = []
    for k in range(1, times.size):
        analog_step(new, lane, 0, x[k], times[k])
        ref.analog_step(old, x[k], times[k], p)
        readings = analog_read(new, lane, 0, noise[k]), ref.analog_read(old, noise[k], p)
        out.append((new[:, 0].copy(), old.copy(), *readings))
    return out


@pytest.mark.parametrize("refresh_steps", [16.0, 2.5, 0.75])
@pytest.mark.parametrize("output_bits", [0.0, 16.0, 5.0])
def test_sample_and_hold_ties_several_refreshes_and_saturation_bit_for_bit(refresh_steps, output_bits):
    """A hold whose refresh instants tie exactly with step ends (16 steps), fall two or three to a step (2.5 steps
    or 0.75 of a step), with and without the sensor's D/A; a measurand that overshoots both converters' full scale
    (+-180 on a 100 range) and steps of zero length: state and reading bit for bit (no conditioner: the same
    operations on both sides)."""
    p = analog_parameters(**{**CHANNEL, "refresh_period": refresh_steps * DT, "output_bits": output_bits})
    rng = np.random.default_rng(33)
    times = np.arange(400) * DT
    times = np.sort(np.concatenate([times, times[50:60]]))  # ten steps of zero length
    x = 180.0 * np.sin(2 * math.pi * 200.0 * times) + rng.normal(0.0, 5.0, times.size)
    noise = rng.uniform(-0.25, 0.25, times.size)
    saturated = 0
    for new, old, read_new, read_old in _run_channel(p, times, x, noise):
        assert _same_bits(new, old)
        assert _same_bits(read_new, read_old)
        saturated += abs(read_new) >= 100.0 * (1 - 2**-14)
    assert saturated > 10


def test_continuous_channel_without_hold_bit_for_bit():
    p = analog_parameters(**CHANNEL)
    times = np.arange(200) * DT
    x = np.linspace(-150.0, 150.0, times.size)
    for new, old, read_new, read_old in _run_channel(p, times, x, np.zeros(times.size)):
        assert _same_bits(new, old) and _same_bits(read_new, read_old)


def test_conditioner_lag_differs_from_the_per_step_libm_lag_by_rounding_only():
    """With a conditioner the lane code takes 1 - exp(-dt/tau) computed once (numerics.elementary.expm1, < 1 ulp)
    where the reference called libm's expm1 at every step: the filtered voltage agrees to a few ulps of the
    signal (relative 1e-13 over 400 steps of accumulation), the held output and the reading bit for bit unless a
    converter threshold falls in between (not on this path)."""
    p = analog_parameters(**{**CHANNEL, "tau": 1.0 / (2 * math.pi * 10e3), "refresh_period": 16 * DT,
                             "output_bits": 16.0})
    times = np.arange(400) * DT
    x = 80.0 * np.sin(2 * math.pi * 150.0 * times)
    for new, old, read_new, read_old in _run_channel(p, times, x, np.zeros(times.size)):
        np.testing.assert_allclose(new, old, rtol=1e-13, atol=1e-15)
        assert read_new == read_old


# --- converters, lag, resolver ------------------------------------------------------------------------------
def test_quantizer_and_converter_on_ties_codes_and_saturation():
    """Ties (n + 1/2) lsb round up, the extreme codes, inputs beyond the range, infinities and inputs beyond 2^63
    lsb (numba's math.floor would turn those into INT_MIN and read +1e300 as -full scale): as the reference."""
    lsb = 10.0 / 2**15
    values = [0.0, -0.0, 0.5 * lsb, -0.5 * lsb, 1.5 * lsb, -1.5 * lsb, 10.0, 10.0 - lsb, 10.0 - 0.5 * lsb, -10.0,
              -10.0 - 0.5 * lsb, 12.0, -12.0, 1e30, -1e30, 3.3, -7.77]
    for v in values:
        assert _same_bits(quantize(v, lsb), ref.quantize(v, lsb)), v
        for bits in (2.0, 12.0, 16.0, 32.0):
            assert _same_bits(convert(v, 10.0, bits), ref.convert(v, 10.0, bits)), (v, bits)
    # beyond what the reference's Python int can take (inf / lsb): the extreme codes
    for bits in (2.0, 16.0, 32.0):
        top = 10.0 - 10.0 / 2.0 ** (bits - 1)
        assert convert(1e300, 10.0, bits) == top and convert(math.inf, 10.0, bits) == top
        assert convert(-1e300, 10.0, bits) == -10.0 and convert(-math.inf, 10.0, bits) == -10.0
    assert math.isnan(convert(math.nan, 10.0, 16.0))  # a diverged signal is not saturated into a code


def test_first_order_lag_agrees_with_the_libm_form_to_rounding():
    """numerics.elementary.expm1 (< 1 ulp) instead of libm's: relative 1e-15 (a few ulps after the two products);
    dt <= 0 returns y0 exactly, as the branch did."""
    rng = np.random.default_rng(34)
    for _ in range(2000):
        y0, u0, u1 = rng.normal(0.0, 10.0, 3)
        dt, tau = 10.0 ** rng.uniform(-8, -2), 10.0 ** rng.uniform(-6, -3)
        assert first_order_lag(y0, u0, u1, dt, tau) == pytest.approx(ref.first_order_lag(y0, u0, u1, dt, tau),
                                                                     rel=1e-14, abs=1e-14)
    assert first_order_lag(0.7, 1.0, 5.0, 0.0, 1e-3) == 0.7 and first_order_lag(0.7, 1.0, 5.0, -1e-6, 1e-3) == 0.7


def test_resolver_reading_as_the_libm_sine_reading():
    """numerics.elementary.sin instead of libm's changes the error term by an ulp at most (~4e-19 rad on a 10'
    amplitude), which moves a 0.8' quantisation step only within that distance of a threshold: on 20000 random
    angles the readings are identical."""
    step, accuracy, offset = 0.8 * math.pi / 10800, 2.9e-3, 1.2e-3
    params = _lane([step, accuracy, offset, 2.0, 0.0])
    theta = np.random.default_rng(35).uniform(-300.0, 300.0, 20000)
    new = np.array([resolver_angle(params, 0, th) for th in theta])
    old = np.array([ref.resolver_angle(th, step, accuracy, offset, 2.0) for th in theta])
    np.testing.assert_array_equal(new, old)
