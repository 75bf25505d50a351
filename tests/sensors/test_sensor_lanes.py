"""Bit identity of the lane form: a lane's readings never depend on its lane mates or on the lane count.

Each instrument runs in a lane kernel (``numerics.jit.KERNEL``, loops
``for lane in range(L): f(state, params, lane, ...)`` over ``[row, lane]`` arrays) as the lock-step engine runs
it (issue 32). Sixteen lanes with different parameters and trajectories (every fidelity level, errors, mounting
phases, refresh periods, conditioners, converters) are run each alone (L = 1) and in groups of 4, 8 and 16 with
their lane mates permuted: every reading and the final state of every lane must be the same bits. A vectorised
loop computes a group's lanes in vector registers and a lone lane (or a remainder) in scalar ones; the sensor
functions are branch-free and use ``numerics.elementary`` instead of libm, so both give the same bits.
"""

import math

import numba
import numpy as np
import pytest
from bench_helpers import bench_sensors

from numerics.jit import KERNEL
from sensors.acquisition import draw_uniform_noise
from sensors.analog import (
    AN_NOISE_HALF_WIDTH,
    AN_REFRESH_PERIOD,
    AS_SIZE,
    analog_init,
    analog_parameters,
    analog_read,
    analog_step,
    with_integration_step,
)
from sensors.encoder import (
    ENC_STATE_SIZE,
    encoder_init,
    encoder_parameters,
    encoder_reading,
    encoder_speed,
    encoder_step,
)
from sensors.lanes import lane_group, one_lane
from sensors.load_cell import load_cell_parameters, preload_load_cell_parameters
from sensors.resolver import resolver_angle, resolver_parameters
from sensors.torque_meter import torque_meter_parameters

N_LANES = 16
DT = 6.25e-5        # the default RK4 step
EVERY = 16          # 1 ms acquisition
STEPS = 40 * EVERY  # 40 ms
GROUPS = [1, 4, 8, 16]


@numba.njit(**KERNEL)
def _encoder_group(state, params, x, times, readings, speeds):
    lanes = params.shape[1]
    for lane in range(lanes):
        encoder_init(state, params, lane, x[0, lane], times[0])
    for k in range(1, times.shape[0]):
        t = times[k]
        for lane in range(lanes):
            encoder_step(state, params, lane, x[k, lane], t)
        if k % EVERY == 0:
            j = k // EVERY
            for lane in range(lanes):
                readings[j, lane] = encoder_reading(state, params, lane)
            for lane in range(lanes):
                speeds[j, lane] = encoder_speed(state, params, lane, t)


@numba.njit(**KERNEL)
def _analog_group(state, params, x, times, noise, readings):
    lanes = params.shape[1]
    for lane in range(lanes):
        analog_init(state, params, lane, x[0, lane], times[0])
    for k in range(1, times.shape[0]):
        t = times[k]
        for lane in range(lanes):
            analog_step(state, params, lane, x[k, lane], t)
        if k % EVERY == 0:
            j = k // EVERY
            for lane in range(lanes):
                readings[j, lane] = analog_read(state, params, lane, noise[j, lane])


@numba.njit(**KERNEL)
def _resolver_group(params, theta, readings):
    lanes = params.shape[1]
    for k in range(theta.shape[0]):
        for lane in range(lanes):
            readings[k, lane] = resolver_angle(params, lane, theta[k, lane])


def _columns(arrays, lanes):
    """Stack per-lane 1-D series into a C-contiguous ``[step, lane]`` array."""
    return np.ascontiguousarray(np.stack([arrays[lane] for lane in lanes], axis=1))


def _bits(a):
    return np.ascontiguousarray(a).view(np.int64)


def _times():
    return np.arange(STEPS + 1) * DT


def _encoder_lanes():
    """Sixteen encoders: linear and rotary, fidelity 0/1/2, random errors and mounting phases; each with its own
    trajectory (strokes with reversals, fast sweeps across many edges per step, dither around an edge)."""
    rng = np.random.default_rng(21)
    t = _times()
    params, paths = [], []
    for lane in range(N_LANES):
        linear = lane % 2 == 0
        resolution = 1e-6 if linear else 2 * math.pi / 8000
        params.append(encoder_parameters(
            resolution=resolution, timer_period=2.5e-8, fidelity=(2, 2, 1, 2, 0, 2, 1, 2)[lane % 8],
            phase_error=rng.uniform(-0.7, 0.7), asymmetry_a=rng.uniform(-0.25, 0.25),
            asymmetry_b=rng.uniform(-0.25, 0.25), precision_amplitude=rng.uniform(-4e-6, 4e-6) if linear else 0.0,
            precision_wavelength=1e-3, mounting_phase=rng.uniform(0.0, 1.0)))
        amplitude = resolution * rng.uniform(2.0, 400.0)
        frequency = rng.uniform(5.0, 60.0)
        path = amplitude * np.sin(2 * math.pi * frequency * t + rng.uniform(0, 2 * math.pi))
        path += resolution * rng.uniform(-0.3, 0.3, t.size) * (lane % 3 == 0)  # dither on some lanes
        paths.append(0.16 * linear + path)
    return params, paths


def _run_encoders(params, paths, lanes):
    group = lane_group([params[lane] for lane in lanes])
    state = np.zeros((ENC_STATE_SIZE, len(lanes)))
    readings, speeds = np.zeros((STEPS // EVERY + 1, len(lanes))), np.zeros((STEPS // EVERY + 1, len(lanes)))
    _encoder_group(state, group, _columns(paths, lanes), _times(), readings, speeds)
    return readings, speeds, state


def _analog_lanes():
    """Sixteen channels: torque meters (1 kHz hold, 16-bit D/A), load cells (19.2 kHz hold), preload cells (10 kHz
    conditioner), and generic channels with a coarse D/A, a hold incommensurate with the step or a slow lag; random
    sensitivity/offset errors and room temperatures; measurands that saturate the converters on some lanes."""
    rng = np.random.default_rng(22)
    t = _times()
    params, paths = [], []
    for lane in range(N_LANES):
        room = rng.uniform(288.15, 308.15)
        kind = lane % 4
        if kind == 0:
            p = torque_meter_parameters(bench_sensors({"sensors.torque_meter_sensitivity_error_range1":
                                                       rng.uniform(-2e-3, 2e-3)}), room_temperature=room)
            scale = 60.0  # beyond the 50 N*m range: saturates
        elif kind == 1:
            p = load_cell_parameters(bench_sensors({"sensors.load_cell_offset": rng.uniform(-2e-4, 2e-4)}),
                                     room_temperature=room)
            scale = 8e3
        elif kind == 2:
            p = preload_load_cell_parameters(bench_sensors(), room_temperature=room)
            scale = 4e3
        else:
            p = analog_parameters(full_scale=100.0, output_full_scale=10.0, gain=1.0 + rng.uniform(-0.01, 0.01),
                                  offset=rng.uniform(-0.01, 0.01), tau=rng.choice([0.0, 1e-3]),
                                  refresh_period=rng.choice([0.0, 7.071e-4]), output_bits=rng.choice([0.0, 6.0]),
                                  daq_full_scale=10.0, daq_bits=16.0, noise_half_width=0.25)
            scale = 150.0
        params.append(with_integration_step(p, DT))
        paths.append(scale * np.sin(2 * math.pi * rng.uniform(20.0, 300.0) * t) + rng.normal(0, 0.01 * scale, t.size))
    samples = STEPS // EVERY + 1
    noise = [draw_uniform_noise(np.random.default_rng(100 + lane), samples, params[lane][AN_NOISE_HALF_WIDTH])
             for lane in range(N_LANES)]
    return params, paths, noise


def _run_analog(params, paths, noise, lanes):
    group = lane_group([params[lane] for lane in lanes])
    state = np.zeros((AS_SIZE, len(lanes)))
    readings = np.zeros((STEPS // EVERY + 1, len(lanes)))
    _analog_group(state, group, _columns(paths, lanes), _times(), _columns(noise, lanes), readings)
    return readings, state


def _resolver_lanes():
    rng = np.random.default_rng(23)
    params, angles = [], []
    for _ in range(N_LANES):
        params.append(resolver_parameters(bench_sensors({
            "sensors.resolver_accuracy": rng.uniform(-2.9e-3, 2.9e-3),
            "sensors.resolver_offset": rng.uniform(-2e-4, 2e-4),
            "sensors.resolver_mounting_angle": rng.uniform(0.0, 2 * math.pi)})))
        angles.append(np.cumsum(rng.normal(0.0, 0.05, 2000)) * rng.uniform(1.0, 50.0))
    return params, angles


def _run_resolvers(params, angles, lanes):
    readings = np.zeros((angles[0].size, len(lanes)))
    _resolver_group(lane_group([params[lane] for lane in lanes]), _columns(angles, lanes), readings)
    return (readings,)


def _groups():
    """For each group size, the lanes it holds: a random choice of lane mates, in a random order."""
    rng = np.random.default_rng(24)
    return [rng.permutation(N_LANES)[:size] for size in GROUPS for _ in range(2)]


def _assert_each_lane_reads_as_alone(run):
    alone = [run([lane]) for lane in range(N_LANES)]
    for lanes in _groups():
        together = run(list(lanes))
        for i, lane in enumerate(lanes):
            for name, (a, b) in enumerate(zip(together, alone[lane], strict=True)):
                assert np.array_equal(_bits(a[..., i]), _bits(b[..., 0])), (
                    f"lane {lane} in the group {list(lanes)}: output {name} differs from the lane alone")


def test_encoder_lanes_read_as_each_lane_alone():
    params, paths = _encoder_lanes()
    _assert_each_lane_reads_as_alone(lambda lanes: _run_encoders(params, paths, lanes))
    readings, speeds, _ = _run_encoders(params, paths, list(range(N_LANES)))
    assert np.count_nonzero(readings) > 0.5 * readings.size and np.count_nonzero(speeds) > 0.3 * speeds.size


def test_analog_lanes_read_as_each_lane_alone():
    params, paths, noise = _analog_lanes()
    assert {p[AN_REFRESH_PERIOD] for p in params} >= {0.0, 1e-3}
    _assert_each_lane_reads_as_alone(lambda lanes: _run_analog(params, paths, noise, lanes))


def test_resolver_lanes_read_as_each_lane_alone():
    params, angles = _resolver_lanes()
    _assert_each_lane_reads_as_alone(lambda lanes: _run_resolvers(params, angles, lanes))


@pytest.mark.parametrize("size", GROUPS)
def test_a_group_of_copies_of_one_lane_reads_the_same_in_every_lane(size):
    """One lane's parameters and trajectory copied into every lane of a group: every column is the same bits
    (the vector loop's lanes and its scalar remainder agree)."""
    params, paths = _encoder_lanes()
    readings, speeds, state = _run_encoders([params[3]] * size, [paths[3]] * size, list(range(size)))
    for out in (readings, speeds, state):
        assert all(np.array_equal(_bits(out[..., i]), _bits(out[..., 0])) for i in range(size))


@numba.njit(**{**KERNEL, "cache": False})
def _encoder_steps(state, params, x, t):
    for lane in range(params.shape[1]):
        encoder_step(state, params, lane, x[lane], t)


@numba.njit(**{**KERNEL, "cache": False})
def _analog_steps(state, params, x, t):
    for lane in range(params.shape[1]):
        analog_step(state, params, lane, x[lane], t)


@numba.njit(**{**KERNEL, "cache": False})
def _analog_reads(state, params, noise, out):
    for lane in range(params.shape[1]):
        out[lane] = analog_read(state, params, lane, noise[lane])


@numba.njit(**{**KERNEL, "cache": False})
def _resolver_reads(params, theta, out):
    for lane in range(params.shape[1]):
        out[lane] = resolver_angle(params, lane, theta[lane])


def test_the_per_step_lane_loops_vectorise():
    """What the branch-free form is for: LLVM's loop vectoriser vectorises a loop over lanes of ``encoder_step``,
    ``analog_step``, ``analog_read`` and ``resolver_angle`` (it marks the loop ``llvm.loop.isvectorized``, whatever
    the CPU's vector width). A data branch, a libm call, an int(...) of a float or a select between array loads or
    calls would stop it. (Not cached: numba inspects only code it compiled in this process.) ``encoder_speed``, at
    sample instants only, is not vectorised by LLVM although each of its parts is: it is not asserted."""
    lanes = 8
    encoders = lane_group(_encoder_lanes()[0][:lanes])
    channels = lane_group(_analog_lanes()[0][:lanes])
    resolvers = lane_group(_resolver_lanes()[0][:lanes])
    x, out = np.zeros(lanes), np.zeros(lanes)
    _encoder_steps(np.zeros((ENC_STATE_SIZE, lanes)), encoders, x, 1e-4)
    _analog_steps(np.zeros((AS_SIZE, lanes)), channels, x, 1e-4)
    _analog_reads(np.zeros((AS_SIZE, lanes)), channels, x, out)
    _resolver_reads(resolvers, x, out)
    for kernel in (_encoder_steps, _analog_steps, _analog_reads, _resolver_reads):
        ir = kernel.inspect_llvm(kernel.signatures[0])
        assert "llvm.loop.isvectorized" in ir, f"{kernel.__name__}: the lane loop is not vectorised"


def test_lane_group_and_one_lane_views():
    """``lane_group`` puts lane i's vector in column i of a C-contiguous array; ``one_lane`` views a vector as a
    one-lane group sharing its memory (what the scalar engine passes: a state written through it is the row)."""
    a, b = np.arange(5.0), np.arange(5.0) + 10.0
    group = lane_group([a, b])
    assert group.shape == (5, 2) and group.flags["C_CONTIGUOUS"]
    np.testing.assert_array_equal(group[:, 1], b)
    row = np.zeros((3, ENC_STATE_SIZE))[1]
    view = one_lane(row)
    params = lane_group([_encoder_lanes()[0][0]])
    encoder_init(view, params, 0, 0.16, 2.0)
    assert view.shape == (ENC_STATE_SIZE, 1) and row[0] == 2.0
    with pytest.raises(ValueError, match="at least one lane"):
        lane_group([])


def test_integration_step_of_a_group_is_that_of_each_lane():
    """``with_integration_step`` on a whole group gives each column the bits it gives that lane's vector."""
    channels = _analog_lanes()[0]
    group = with_integration_step(lane_group(channels), 1e-4)
    assert np.array_equal(_bits(group), _bits(lane_group([with_integration_step(p, 1e-4) for p in channels])))
