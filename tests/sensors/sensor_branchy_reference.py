"""The scalar, branchy sensor laws as they were before the lane form (commit f873c55), transcribed in plain Python.

The reference for the branch-free lane functions: the same equations written with ``if``/``elif`` and libm
(``math.sin``, ``math.expm1``), one instrument per 1-D state/parameter vector of the same row layouts. Only
what the tests compare is transcribed; the mounting phase (added with the lane form) is not in here, so the
comparisons use phase 0.
"""

from __future__ import annotations

import math

from sensors.analog import (
    AN_DAQ_BITS,
    AN_DAQ_FULL_SCALE,
    AN_FULL_SCALE,
    AN_GAIN,
    AN_OFFSET,
    AN_OUTPUT_BITS,
    AN_OUTPUT_FULL_SCALE,
    AN_REFRESH_PERIOD,
    AN_TAU,
    AS_FILTERED,
    AS_INPUT,
    AS_NEXT_REFRESH,
    AS_OUTPUT,
    AS_REFRESH_ORIGIN,
    AS_T,
)
from sensors.encoder import (
    ENC_EDGE,
    ENC_FIDELITY,
    ENC_PERIOD,
    ENC_PRECISION_AMPLITUDE,
    ENC_PRECISION_WAVENUMBER,
    ENC_RESOLUTION,
    ENC_S_BACKWARD,
    ENC_S_COUNT,
    ENC_S_COUNT0,
    ENC_S_EDGE_DIR,
    ENC_S_EDGE_T,
    ENC_S_FORWARD,
    ENC_S_PEAK_FREQUENCY,
    ENC_S_PREV_EDGE_DIR,
    ENC_S_PREV_EDGE_T,
    ENC_S_SAMPLE_COUNT,
    ENC_S_SAMPLE_T,
    ENC_S_T,
    ENC_S_U,
    ENC_TIMER_PERIOD,
)


# --- acquisition ------------------------------------------------------------------------------------------
def quantize(value, lsb):
    return lsb * math.floor(value / lsb + 0.5)


def convert(value, full_scale, bits):
    lsb = full_scale / 2.0 ** (bits - 1.0)
    return min(max(quantize(value, lsb), -full_scale), full_scale - lsb)


def first_order_lag(y0, u0, u1, dt, tau):
    if dt <= 0.0:
        return y0
    one_minus_a = -math.expm1(-dt / tau)
    return u1 + (1.0 - one_minus_a) * (y0 - u0) - (u1 - u0) * (tau / dt) * one_minus_a


# --- encoder ----------------------------------------------------------------------------------------------
def scale_position(x, p):
    amplitude = p[ENC_PRECISION_AMPLITUDE]
    if p[ENC_FIDELITY] < 2.0 or (amplitude == 0.0 and 0.0 < abs(x) < math.inf):
        return x
    return x + amplitude * math.sin(p[ENC_PRECISION_WAVENUMBER] * x)


def count_at(u, p):
    res = p[ENC_RESOLUTION]
    if p[ENC_FIDELITY] == 0.0:
        return u / res
    if p[ENC_FIDELITY] == 1.0:
        return float(math.floor(u / res))
    n = 3.0
    for k in range(4):
        n += math.floor((u - p[ENC_EDGE + k]) / p[ENC_PERIOD])
    return n


def edge_position(n, p):
    if p[ENC_FIDELITY] == 1.0:
        return n * p[ENC_RESOLUTION]
    j = math.floor(n / 4.0)
    return p[ENC_EDGE + int(n - 4.0 * j)] + j * p[ENC_PERIOD]


def encoder_init(state, x0, t0, p):
    u = scale_position(x0, p)
    count = count_at(u, p)
    state[:] = 0.0
    state[ENC_S_T] = t0
    state[ENC_S_U] = u
    state[ENC_S_COUNT] = count
    state[ENC_S_COUNT0] = count
    state[ENC_S_EDGE_T] = -math.inf
    state[ENC_S_PREV_EDGE_T] = -math.inf
    state[ENC_S_SAMPLE_T] = t0
    state[ENC_S_SAMPLE_COUNT] = count


def _edge_time(n, u0, u1, t0, t1, p):
    frac = (edge_position(n, p) - u0) / (u1 - u0)
    return t0 + min(max(frac, 0.0), 1.0) * (t1 - t0)


def encoder_step(state, x, t, p):
    t0 = state[ENC_S_T]
    u0 = state[ENC_S_U]
    u1 = scale_position(x, p)
    count = count_at(u1, p)
    dn = count - state[ENC_S_COUNT]
    if t > t0:
        frequency = abs(u1 - u0) / (p[ENC_PERIOD] * (t - t0))
        state[ENC_S_PEAK_FREQUENCY] = max(state[ENC_S_PEAK_FREQUENCY], frequency)
    if dn > 0.0:
        state[ENC_S_FORWARD] += dn
    elif dn < 0.0:
        state[ENC_S_BACKWARD] -= dn
    if dn != 0.0 and p[ENC_FIDELITY] > 0.0:
        direction = 1.0 if dn > 0.0 else -1.0
        last = count if dn > 0.0 else count + 1.0
        if abs(dn) >= 2.0:
            state[ENC_S_PREV_EDGE_T] = _edge_time(last - direction, u0, u1, t0, t, p)
            state[ENC_S_PREV_EDGE_DIR] = direction
        else:
            state[ENC_S_PREV_EDGE_T] = state[ENC_S_EDGE_T]
            state[ENC_S_PREV_EDGE_DIR] = state[ENC_S_EDGE_DIR]
        state[ENC_S_EDGE_T] = _edge_time(last, u0, u1, t0, t, p)
        state[ENC_S_EDGE_DIR] = direction
    state[ENC_S_T] = t
    state[ENC_S_U] = u1
    state[ENC_S_COUNT] = count


def encoder_reading(state, p):
    return (state[ENC_S_COUNT] - state[ENC_S_COUNT0]) * p[ENC_RESOLUTION]


def encoder_frequency_speed(state, t, p):
    window = t - state[ENC_S_SAMPLE_T]
    if window <= 0.0:
        return 0.0
    return (state[ENC_S_COUNT] - state[ENC_S_SAMPLE_COUNT]) * p[ENC_RESOLUTION] / window


def encoder_period_speed(state, t, p):
    direction = state[ENC_S_EDGE_DIR]
    if direction == 0.0 or state[ENC_S_PREV_EDGE_DIR] != direction:
        return 0.0
    tick = p[ENC_TIMER_PERIOD]
    t_last = math.floor(state[ENC_S_EDGE_T] / tick)
    interval = max(t_last - math.floor(state[ENC_S_PREV_EDGE_T] / tick), 1.0)
    elapsed = math.floor(t / tick) - t_last
    return direction * p[ENC_RESOLUTION] / (max(interval, elapsed) * tick)


def encoder_speed(state, t, p):
    window = t - state[ENC_S_SAMPLE_T]
    v_f = encoder_frequency_speed(state, t, p)
    state[ENC_S_SAMPLE_T] = t
    state[ENC_S_SAMPLE_COUNT] = state[ENC_S_COUNT]
    if p[ENC_FIDELITY] == 0.0 or window <= 0.0:
        return v_f
    if abs(v_f) >= p[ENC_RESOLUTION] / math.sqrt(p[ENC_TIMER_PERIOD] * window):
        return v_f
    return encoder_period_speed(state, t, p)


# --- analog channel ---------------------------------------------------------------------------------------
def transducer_voltage(x, p):
    return p[AN_OUTPUT_FULL_SCALE] * (p[AN_GAIN] * x / p[AN_FULL_SCALE] + p[AN_OFFSET])


def _output(v, p):
    if p[AN_OUTPUT_BITS] > 0.0:
        return convert(v, p[AN_OUTPUT_FULL_SCALE], p[AN_OUTPUT_BITS])
    return v


def analog_init(state, x0, t0, p):
    v = transducer_voltage(x0, p)
    state[AS_T] = t0
    state[AS_INPUT] = v
    state[AS_FILTERED] = v
    state[AS_REFRESH_ORIGIN] = t0
    state[AS_NEXT_REFRESH] = 1.0
    state[AS_OUTPUT] = _output(v, p)


def analog_step(state, x, t, p):
    t_prev = state[AS_T]
    dt = t - t_prev
    u = transducer_voltage(x, p)
    y_prev = state[AS_FILTERED]
    if p[AN_TAU] > 0.0:
        y = first_order_lag(y_prev, state[AS_INPUT], u, dt, p[AN_TAU])
    else:
        y = u
    period = p[AN_REFRESH_PERIOD]
    if period > 0.0:
        origin = state[AS_REFRESH_ORIGIN]
        last = math.floor((t - origin) / period)
        if origin + (last + 1.0) * period <= t:
            last += 1.0
        if origin + last * period > t:
            last -= 1.0
        if last >= state[AS_NEXT_REFRESH]:
            t_refresh = origin + last * period
            y_refresh = y_prev + (y - y_prev) * (t_refresh - t_prev) / dt if dt > 0.0 else y
            state[AS_OUTPUT] = _output(y_refresh, p)
            state[AS_NEXT_REFRESH] = last + 1.0
    else:
        state[AS_OUTPUT] = _output(y, p)
    state[AS_T] = t
    state[AS_INPUT] = u
    state[AS_FILTERED] = y


def analog_read(state, noise, p):
    v = convert(state[AS_OUTPUT] + noise, p[AN_DAQ_FULL_SCALE], p[AN_DAQ_BITS])
    return v * p[AN_FULL_SCALE] / p[AN_OUTPUT_FULL_SCALE]


# --- resolver ---------------------------------------------------------------------------------------------
def resolver_angle(theta, resolution, accuracy, offset, harmonic):
    return quantize(theta + offset + accuracy * math.sin(harmonic * theta), resolution)
