"""Torque meter, load cells, preload conditioner and Hall sensor readings.

The channel functions are in lane form (``sensors.lanes``): one lane's parameter vector from a builder, completed
for the integration step (``with_integration_step``), is stepped as lane 0 of a one-lane group."""

import math

import numpy as np
import pytest
from bench_helpers import bench_sensors

from sensors.acquisition import convert
from sensors.analog import (
    AN_DAQ_BITS,
    AN_FULL_SCALE,
    AN_GAIN,
    AN_NOISE_HALF_WIDTH,
    AN_OFFSET,
    AN_REFRESH_PERIOD,
    AN_TAU,
    AS_FILTERED,
    AS_SIZE,
    analog_init,
    analog_parameters,
    analog_read,
    analog_step,
    transducer_voltage,
    with_integration_step,
)
from sensors.load_cell import load_cell_parameters, preload_load_cell_parameters
from sensors.torque_meter import torque_meter_parameters
from twin.parameters import load_parameters

T25 = 298.15  # K, the nominal 25 degC of Sec. 9.4
FINE_DAQ = {"sensors.daq_bits": 32.0}  # isolates the sensor model from DAQ quantisation


def _lane(p, dt):
    """One lane's channel vector completed for the fixed step ``dt``, as a one-lane group (lane 0)."""
    return np.ascontiguousarray(with_integration_step(p, dt).reshape(-1, 1))


def _state():
    return np.zeros((AS_SIZE, 1))


def _read_series(p, t, x):
    """Noise-free readings after each step of the measurand series x(t), stepped from t = 0 at the fixed step t[0]."""
    lane = _lane(p, t[0])
    state = _state()
    analog_init(state, lane, 0, x[0], 0.0)
    out = np.empty(t.size)
    for k in range(t.size):
        analog_step(state, lane, 0, x[k], t[k])
        out[k] = analog_read(state, lane, 0, 0.0)
    return out


def test_torque_meter_misses_a_peak_between_refreshes_and_holds_one_it_samples():
    p = torque_meter_parameters(bench_sensors(), room_temperature=T25)
    assert p[AN_REFRESH_PERIOD] == pytest.approx(1e-3)  # 1 kHz, Table B.5
    dt = 1e-5
    t = np.arange(1, 1001) * dt  # 10 ms
    torque = np.zeros_like(t)
    torque[(t > 1.2e-3) & (t < 1.7e-3)] = 10.0  # 0.5 ms pulse between the 1 and 2 ms refreshes
    torque[(t > 2.8e-3) & (t < 3.3e-3)] = 10.0  # 0.5 ms pulse across the 3 ms refresh
    half_sine = (t > 6.7e-3) & (t < 7.5e-3)  # 0.8 ms half sine peaking at 7.1 ms
    torque[half_sine] = 10.0 * np.sin(np.pi * (t[half_sine] - 6.7e-3) / 0.8e-3)
    reading = _read_series(p, t, torque)
    lsb = 2 * 50.0 / 2**16  # D/A and DAQ, 16 bit over ±50 N*m

    assert np.all(np.abs(reading[t < 2.9e-3]) <= lsb)  # first pulse entirely lost
    held = (t >= 3.0e-3 + dt / 2) & (t < 4.0e-3 - dt / 2)
    np.testing.assert_allclose(reading[held], 10.0, atol=2 * lsb)  # held for a full period,
    assert np.all(np.abs(reading[(t > 4.0e-3 + dt / 2) & (t < 7.0e-3 - dt / 2)]) <= lsb)  # twice the pulse
    peak_read = reading[(t >= 7.0e-3 + dt / 2) & (t < 8.0e-3 - dt / 2)]
    sampled = 10.0 * math.sin(math.pi * 0.3 / 0.8)  # value at the 7 ms refresh
    np.testing.assert_allclose(peak_read, sampled, atol=2 * lsb + 2e-3)  # + interpolation error
    assert peak_read.max() < 10.0 - 0.5  # the 10 N*m peak is attenuated


def test_torque_meter_saturates_at_the_dac_full_scale():
    p = torque_meter_parameters(bench_sensors(), room_temperature=T25)
    reading = _read_series(p, np.array([1e-3, 2e-3]), np.array([80.0, -80.0]))
    assert reading[0] == pytest.approx(50.0 * (1 - 2**-15))
    assert reading[1] == pytest.approx(-50.0)


@pytest.mark.parametrize(
    "builder, force, overrides, gain_tcs, offset_tcs",
    [
        (
            load_cell_parameters,
            12e3,
            {"sensors.load_cell_sensitivity_tempco": 1.0e-4, "sensors.load_cell_offset_tempco": -2.5e-4},
            [1.0e-4],
            [-2.5e-4],
        ),
        (
            preload_load_cell_parameters,
            4e3,
            {
                "sensors.preload_load_cell_sensitivity_tempco_range2": 1.5e-4,
                "sensors.preload_conditioner_sensitivity_tempco_range2": -1.0e-5,
                "sensors.preload_load_cell_offset_tempco_range2": 2.0e-4,
                "sensors.preload_conditioner_offset_tempco": 1.2e-5,
            },
            [1.5e-4, -1.0e-5],
            [2.0e-4, 1.2e-5],
        ),
        (
            torque_meter_parameters,
            20.0,
            {"sensors.torque_meter_sensitivity_tempco_range1": -1.2e-4,
             "sensors.torque_meter_offset_tempco_range1": 0.8e-4},
            [-1.2e-4],
            [0.8e-4],
        ),
    ],
)
@pytest.mark.parametrize("delta_t", [10.0, -10.0])
def test_temperature_shift_is_sensitivity_times_dt_plus_offset_times_dt(builder, force, overrides, gain_tcs, offset_tcs,
                                                                        delta_t):
    cold = builder(bench_sensors({**overrides, **FINE_DAQ}), room_temperature=T25)
    warm = builder(bench_sensors({**overrides, **FINE_DAQ}), room_temperature=T25 + delta_t)
    full_scale = cold[AN_FULL_SCALE]
    expected = force * sum(gain_tcs) * delta_t + full_scale * sum(offset_tcs) * delta_t
    # transducer voltage, no quantisation: exact to rounding
    shift_v = transducer_voltage(_lane(warm, 1e-3), 0, force) - transducer_voltage(_lane(cold, 1e-3), 0, force)
    assert shift_v * full_scale / 10.0 == pytest.approx(expected, rel=1e-9)
    # full chain through a fine DAQ (16-bit torque-meter D/A: within its lsb)
    t = np.array([1e-3, 2e-3, 3e-3])
    x = np.full(3, force)
    lsb = 2 * full_scale / 2**16
    shift = _read_series(warm, t, x)[-1] - _read_series(cold, t, x)[-1]
    assert shift == pytest.approx(expected, abs=lsb)


def test_static_errors_act_on_gain_and_offset():
    p = load_cell_parameters(
        bench_sensors({
            "sensors.load_cell_sensitivity_error": 1e-3,
            "sensors.load_cell_repeatability_error": -5e-4,
            "sensors.load_cell_offset": 2e-4,
        }),
        room_temperature=T25,
    )
    assert p[AN_GAIN] == pytest.approx(1.0 + 1e-3 - 5e-4)
    assert p[AN_OFFSET] == pytest.approx(2e-4)
    assert p[AN_REFRESH_PERIOD] == pytest.approx(1 / 19200)  # Table B.13
    q = preload_load_cell_parameters(bench_sensors({"sensors.preload_load_cell_accuracy_error": 2e-3}),
                                     room_temperature=T25)
    assert q[AN_FULL_SCALE] == 10e3 and q[AN_OFFSET] == pytest.approx(2e-3)  # 20 N on the 10 kN range


@pytest.mark.parametrize("dt", [1e-7, 3e-6, 2e-5, 1e-4])
def test_preload_conditioner_is_an_exact_first_order_lag_for_any_step(dt):
    """A ramp of 4e6 N/s, then a hold from t_hold (a step ends at the ramp's corner), through the 10 kHz conditioner
    (tau = 15.9 us) stepped at a fixed dt from 1e-7 s (<< tau) to 1e-4 s (>> tau): the filtered voltage is the
    exact ramp response, then the exact decay, at every step (the lag's coefficients computed once for dt)."""
    p = preload_load_cell_parameters(bench_sensors(), room_temperature=T25)
    tau = p[AN_TAU]
    assert tau == pytest.approx(1 / (2 * math.pi * 10e3))  # 10 kHz cut-off, Table B.8
    rate = 4e6  # N/s ramp, then hold from t_hold
    t_hold = 1e-3
    steps = round(min(2.5e-3, 400 * dt) / dt)
    t = np.arange(1, steps + 1) * dt
    t_hold = min(t_hold, t[steps // 2])  # a step ends at the corner

    def exact(tt):  # ramp response, then the decay after the corner
        ramp = rate * (tt - tau * (1.0 - np.exp(-tt / tau)))
        at_hold = rate * (t_hold - tau * (1.0 - np.exp(-t_hold / tau)))
        hold = rate * t_hold + (at_hold - rate * t_hold) * np.exp(-(tt - t_hold) / tau)
        return np.where(tt <= t_hold, ramp, hold)

    lane = _lane(p, dt)
    state = _state()
    analog_init(state, lane, 0, 0.0, 0.0)
    volts_per_newton = 10.0 / 10e3
    for tk in t:
        analog_step(state, lane, 0, rate * min(tk, t_hold), tk)
        assert state[AS_FILTERED, 0] / volts_per_newton == pytest.approx(exact(tk), rel=1e-9, abs=1e-9)


def test_a_channel_stepped_before_its_step_is_set_reads_nan():
    """The conditioner's coefficients depend on the integration step: until ``with_integration_step`` they are NaN,
    so a forgotten call shows as NaN readings, never as a silently wrong lag."""
    p = preload_load_cell_parameters(bench_sensors(), room_temperature=T25)
    lane = np.ascontiguousarray(p.reshape(-1, 1))
    state = _state()
    analog_init(state, lane, 0, 500.0, 0.0)
    analog_step(state, lane, 0, 600.0, 1e-4)
    assert math.isnan(analog_read(state, lane, 0, 0.0))
    with pytest.raises(ValueError, match="dt"):
        with_integration_step(p, 0.0)


def test_noise_sample_adds_to_the_reading_in_volts():
    p = load_cell_parameters(bench_sensors(FINE_DAQ), room_temperature=T25)
    assert p[AN_NOISE_HALF_WIDTH] == pytest.approx(0.25)  # ±2.5 %FS of 10 V
    assert p[AN_DAQ_BITS] == 32.0
    lane = _lane(p, 1e-4)
    state = _state()
    analog_init(state, lane, 0, 5e3, 0.0)
    assert analog_read(state, lane, 0, 0.1) - analog_read(state, lane, 0, 0.0) == pytest.approx(0.1 * 20e3 / 10.0)


def test_bad_inputs_name_the_field():
    with pytest.raises(ValueError, match="room_temperature"):
        load_cell_parameters(bench_sensors(), room_temperature=-5.0)
    with pytest.raises(ValueError, match="sensors.torque_meter_range"):
        torque_meter_parameters(bench_sensors({"sensors.torque_meter_range": 1.5}), room_temperature=T25)
    with pytest.raises(ValueError, match="sensors.load_cell_sensitivity_error"):  # beyond ±0.1 %Nom
        load_cell_parameters(bench_sensors({"sensors.load_cell_sensitivity_error": 0.01}), room_temperature=T25)
    with pytest.raises(ValueError, match="sensors.preload_load_cell_sensitivty_error_range1"):
        preload_load_cell_parameters(bench_sensors({"sensors.preload_load_cell_sensitivty_error_range1": 0.0}),
                                     room_temperature=T25)


@pytest.mark.parametrize(
    "builder, selector, full_scale, error_name",
    [
        (torque_meter_parameters, "sensors.torque_meter_range", {1: 50.0, 2: 5.0},
         "sensors.torque_meter_sensitivity_error_range"),
        (preload_load_cell_parameters, "sensors.preload_load_cell_range", {1: 1e3, 2: 10e3},
         "sensors.preload_load_cell_sensitivity_error_range"),
    ],
)
@pytest.mark.parametrize("selected", [1, 2])
def test_range_selection_picks_the_range_full_scale_and_errors(builder, selector, full_scale, error_name, selected):
    other = 3 - selected
    p = builder(bench_sensors({selector: float(selected), f"{error_name}{selected}": 0.002,
                               f"{error_name}{other}": -0.002}),
                room_temperature=T25)
    assert p[AN_FULL_SCALE] == full_scale[selected]
    assert p[AN_GAIN] == pytest.approx(1.002)


def test_a_step_spanning_several_refreshes_shows_the_last_one():
    p = torque_meter_parameters(bench_sensors({"sensors.torque_meter_dac_bits": 32.0, **FINE_DAQ}),
                                room_temperature=T25)
    lane = _lane(p, 2.5e-3)
    state = _state()
    analog_init(state, lane, 0, 0.0, 0.0)
    analog_step(state, lane, 0, 25.0, 2.5e-3)  # ramp 0 -> 25 N*m over one 2.5 ms step; refreshes at 1 and 2 ms
    assert analog_read(state, lane, 0, 0.0) == pytest.approx(20.0, rel=1e-9)
    analog_step(state, lane, 0, 25.0, 2.9e-3)  # no refresh until 3 ms
    assert analog_read(state, lane, 0, 0.0) == pytest.approx(20.0, rel=1e-9)


CHANNEL = dict(full_scale=100.0, output_full_scale=10.0, gain=1.0, offset=0.0, tau=0.0, refresh_period=0.0,
               output_bits=0.0, daq_full_scale=10.0, daq_bits=16.0, noise_half_width=0.0)


def test_sensor_output_converter_quantises_before_the_daq():
    """A sensor with its own D/A (the torque meter's) reads the D/A code, converted again by the DAQ: with a
    coarse 4-bit output the reading falls on the D/A's grid, not on the 16-bit DAQ's."""
    coarse = _lane(analog_parameters(**{**CHANNEL, "output_bits": 4.0}), 1e-4)
    state = _state()
    analog_init(state, coarse, 0, 33.0, 0.0)
    volts = convert(convert(3.3, 10.0, 4.0), 10.0, 16.0)
    assert analog_read(state, coarse, 0, 0.0) == pytest.approx(volts * 100.0 / 10.0, rel=1e-12)
    assert abs(analog_read(state, coarse, 0, 0.0) - 33.0) > 1.0  # the 4-bit step is 1.25 V = 12.5 units
    smooth = _lane(analog_parameters(**CHANNEL), 1e-4)
    analog_init(state, smooth, 0, 33.0, 0.0)
    assert analog_read(state, smooth, 0, 0.0) == pytest.approx(33.0, abs=100.0 / 2**15)


@pytest.mark.parametrize("field, value", [("gain", -0.5), ("full_scale", -0.5), ("tau", -0.5),
                                          ("refresh_period", -0.5), ("noise_half_width", -0.5)])
def test_channel_rejects_out_of_range_values_naming_them(field, value):
    with pytest.raises(ValueError, match=rf"^{field}: must be"):
        analog_parameters(**{**CHANNEL, field: value})


def test_each_channel_holds_its_output_at_its_own_rate():
    """Torque meter: 1 kHz refresh (Table B.5); load cell: its measuring rate (Table B.13); the preload cell's
    analog conditioner has no hold at all (its 10 kHz filter is the only dynamics)."""
    room = 298.15
    rate = load_parameters("bench").value("sensors.load_cell_measuring_rate")
    assert torque_meter_parameters(bench_sensors(), room_temperature=room)[AN_REFRESH_PERIOD] == pytest.approx(1e-3)
    assert load_cell_parameters(bench_sensors(), room_temperature=room)[AN_REFRESH_PERIOD] == pytest.approx(1.0 / rate)
    assert preload_load_cell_parameters(bench_sensors(), room_temperature=room)[AN_REFRESH_PERIOD] == 0.0
