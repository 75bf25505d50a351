"""The pneumatic load system in the closed-loop bench (Eqs. 9.9-9.11 with the force loop)."""

import control
import numpy as np
import pytest

import twin
from twin.control.force_loop_design import design_force_loop
from twin.errors import OptionError
from twin.scenes.profiles import profile_value

SUPPLY = 7.0e5  # Pa absolute, the scenes' nominal supply


# The loop's own dynamics: the load cell without its electrical noise (see test_load_cell_noise_in_force_loop).
QUIET = "quantized"  # analog sensors without noise


def _run(scene_factory, force, supply=SUPPLY, duration=2.5, position=(), analog=QUIET):
    scene = scene_factory(duration, position=position, force=force).with_conditions({"supply_pressure": supply})
    return twin.simulate(scene, fidelity={"default": "full", "analog_sensors": analog}, output_dt=1.25e-4)


STEP = [{"kind": "hold", "end": 1.0}, {"kind": "smooth_step", "end": 1.05, "to": 4000.0}]


@pytest.fixture(scope="module")
def force_step(scene_factory):
    return _run(scene_factory, STEP)


@pytest.fixture(scope="module")
def designed_loop(bench):
    """The force loop as designed (twin.control.force_loop_design): discrete closed loop at 4 kN, 1 kHz."""
    design = design_force_loop(bench.values())
    assert bench.value("controller.force_kp") == pytest.approx(design["kp"], rel=1e-5)
    return design["closed_loop"]


def _design_response(closed_loop, scene, t0, times, offset):
    """The designed linear loop's response to the scene's force demand after ``t0`` (deviation from ``offset``)."""
    demand = np.array([profile_value(scene.force_table(), t0 + t) for t in times]) - offset
    return control.forced_response(closed_loop, T=times, U=demand).outputs.ravel()


def test_small_force_step_follows_the_design(scene_factory, designed_loop):
    """A 400 N step about the 4 kN working point (a 2 ms smooth step, 1 kHz samples): rise time, settling time
    (2 %), overshoot and peak time of the twin's loop within 20 % of the linearised design's (design: 18 ms,
    0.19 s, 14 %, 59 ms; twin: 17 ms, 0.20 s, 15 %, 53 ms). Smaller steps are dominated by the piston seal's
    stick-slip, larger ones by valve saturation, where the linear design does not apply."""
    force = STEP + [{"kind": "hold", "end": 1.5}, {"kind": "smooth_step", "end": 1.502, "to": 4400.0}]
    scene = scene_factory(2.5, force=force).with_conditions({"supply_pressure": SUPPLY})
    # The design's plant has a lossless ball screw; with the Ch. 5 ball-groove friction (issue 18) the master nut's
    # stiction under 4 kN stretches the 2 % settling time to 0.29 s (design 0.19 s; the rise time stays within
    # 20 %): compare the loop with the plant the design assumes. The design (twin.control.force_loop_design)
    # linearises the regularised seal law, so that is the seal level compared here; under the default
    # elasto-plastic seal the rise time is 22 ms against the design's 18 ms (docs/model.md, "Friction that holds").
    ds = twin.simulate(scene, fidelity={"default": "full", "analog_sensors": QUIET, "ball_groove_friction": "lumped",
                                        "seal_friction": "regularised"})
    seg = ds.sel(time=slice(1.5, None))
    times = seg.time.values - 1.5
    twin_info = control.step_info(seg.external_force.values - 4000.0, T=times, SettlingTimeThreshold=0.02)
    design_info = control.step_info(_design_response(designed_loop, scene, 1.5, times, 4000.0), T=times,
                                    SettlingTimeThreshold=0.02)
    for key in ("RiseTime", "SettlingTime", "Overshoot", "PeakTime"):
        assert twin_info[key] == pytest.approx(design_info[key], rel=0.20), key


def test_force_step_tracking(force_step, designed_loop, scene_factory):
    """4 kN step from zero (Fig. 9.7). The twin: rise time 64 ms, overshoot 2.1 %, settling (2 %) 0.14 s,
    steady error < 4 N. The valve saturates on this large step, so the loop is slower than the linear design
    (rise 32 ms, overshoot 13 % on the same demand) and overshoots less; integral action removes the error."""
    seg = force_step.sel(time=slice(1.0, None))
    times = seg.time.values - 1.0
    info = control.step_info(seg.external_force.values, T=times, SettlingTimeThreshold=0.02)
    samples = np.arange(0.0, times[-1], designed_loop.dt)
    scene = scene_factory(2.5, force=STEP)
    design = control.step_info(_design_response(designed_loop, scene, 1.0, samples, 0.0), T=samples,
                               SettlingTimeThreshold=0.02)
    assert design["RiseTime"] < info["RiseTime"] < 0.1
    assert info["Overshoot"] < design["Overshoot"]
    assert info["SettlingTime"] < 0.3
    steady = float(force_step.external_force.sel(time=slice(2.0, None)).mean())
    assert abs(steady - 4000.0) < 4.0


def test_pressures_between_exhaust_and_supply(force_step, bench):
    p_atm = bench.value("pneumatics.atmospheric_pressure")
    for chamber in ("chamber1_pressure", "chamber2_pressure"):
        assert float(force_step[chamber].min()) >= p_atm
        assert float(force_step[chamber].max()) <= SUPPLY


def test_reduced_supply_still_reaches_force(scene_factory):
    """Supply at -10 % (Table 9.5): 4 kN is well inside the areas' reach and is still held."""
    ds = _run(scene_factory, STEP, supply=0.9 * SUPPLY)
    assert float(ds.external_force.sel(time=slice(2.0, None)).mean()) == pytest.approx(4000.0, abs=4.0)


def test_unreachable_force_saturates_without_windup(scene_factory, bench):
    """14 kN at -10 % supply is beyond (p_s - p_atm) A1: the force saturates at the cylinder's reach,
    the valve at full command; when the demand returns to 4 kN the loop recovers at once (no wind-up)."""
    force = [{"kind": "hold", "end": 0.5}, {"kind": "smooth_step", "end": 0.55, "to": 14000.0},
             {"kind": "hold", "end": 2.0}, {"kind": "smooth_step", "end": 2.05, "to": 4000.0}]
    ds = _run(scene_factory, force, supply=0.9 * SUPPLY, duration=3.5)
    bore = bench.value("pneumatics.bore_diameter")
    reach = (0.9 * SUPPLY - bench.value("pneumatics.atmospheric_pressure")) * np.pi * bore**2 / 4
    saturated = ds.sel(time=slice(1.5, 2.0))
    assert float(saturated.external_force.mean()) < reach
    assert float(saturated.external_force.mean()) > 0.9 * reach
    assert float(saturated.valve_command.min()) >= bench.value("pneumatics.valve_command_max") - 0.05
    t, f = ds.time.values, ds.external_force.values
    outside = (t > 2.05) & (np.abs(f - 4000.0) > 200.0)
    assert t[outside].max() < 2.3  # back within 5 % in < 0.25 s of the demand drop


def test_moving_nut_force_error_bounded(scene_factory):
    """While the sled follows the Fig. 9.6a profile with 4 kN applied, the force error stays below
    10 % of the demand (measured: 275 N peak, from the piston seal friction at speed reversals) under the
    regularised seal law the loop was designed on. Under the default elasto-plastic seal the seals stick at each
    reversal until breakaway and the peak is 492 N (rms within the bound): a property of the loop against
    stiction, recorded in docs/model.md ("Friction that holds"), not a bound the design promises."""
    ds = twin.simulate("nominal", fidelity={"default": "full", "analog_sensors": QUIET, "seal_friction": "regularised"})
    error = (ds.force_demand - ds.external_force).sel(time=slice(1.5, None))
    assert float(np.abs(error).max()) < 400.0
    assert float(np.sqrt((error**2).mean())) < 100.0


def test_load_cell_noise_in_force_loop(scene_factory, bench, designed_loop):
    """The load cell's electrical noise (Table 9.5, +/-2.5 %FS uniform on the 20 kN channel, one draw per 1 ms
    sample) enters the force loop: the true force fluctuates by sigma_noise times the designed closed loop's
    noise gain ||T||_2 = sqrt(sum h_k^2) (white noise through the discrete loop), added in quadrature to the
    noise-free loop's own 2 N; within 30 % (measured +5 %, seed 7, 2.5 s of steady state). Its mean holds the demand."""
    scene = scene_factory(4.5, force=STEP).with_conditions({"supply_pressure": SUPPLY})
    noisy = twin.simulate(scene, fidelity={"default": "full", "analog_sensors": "full"}, output_dt=1.25e-4, rng=7)
    quiet = twin.simulate(scene, fidelity={"default": "full", "analog_sensors": QUIET}, output_dt=1.25e-4)
    steady = slice(2.0, None)
    sigma_noise = bench.value("sensors.electrical_noise_half_width") * bench.value(
        "sensors.load_cell_nominal_force") / 3**0.5
    dt = designed_loop.dt
    impulse = control.impulse_response(designed_loop, T=np.arange(0.0, 3.0, dt)).outputs.ravel() * dt  # per unit pulse
    noise_gain = float(np.sqrt(np.sum(impulse**2)))
    assert 0.1 < noise_gain < 1.0  # the loop passes a fifth of the noise (10 Hz loop, 500 Hz Nyquist)
    expected = float(np.hypot(sigma_noise * noise_gain, quiet.external_force.sel(time=steady).std()))
    measured = noisy.external_force.sel(time=steady)
    assert float(measured.std()) == pytest.approx(expected, rel=0.30)
    assert float(measured.mean()) == pytest.approx(4000.0, abs=expected / 3)


def test_absent_pneumatics_with_force_demand_is_an_error():
    with pytest.raises(OptionError, match="fidelity.pneumatics"):
        twin.simulate("nominal", fidelity={"pneumatics": "absent"})


def test_supply_below_exhaust_is_a_scene_error():
    scene = twin.load_scene("nominal").with_conditions({"supply_pressure": 5.0e4})
    with pytest.raises(twin.SceneError, match="conditions.supply_pressure"):
        twin.simulate(scene)


def test_zero_area_or_negative_pressure_parameters_are_rejected(bench):
    with pytest.raises(twin.ParameterError) as info:
        bench.with_values({"pneumatics.bore_diameter": 0.0, "pneumatics.atmospheric_pressure": -1.0})
    assert "pneumatics.bore_diameter" in str(info.value) and "pneumatics.atmospheric_pressure" in str(info.value)
