"""Speed against accuracy: closed-loop convergence order, the divergence guard's failure modes,
the reference path and the work-precision data round trip (the stability limits: test_study_drivers)."""

import numpy as np
import pytest
import xarray as xr
from bench_helpers import plant_fidelity
from scipy.stats import linregress

import twin
from app.studies.accuracy import replot
from app.studies.work_precision import DEFAULT_POINT, errors, run_study
from twin.engine.integrators import ORDER

SMOOTH = {"reducer.backlash": 0.0}  # no contact transitions: the torsional joint never opens


@pytest.fixture(scope="module")
def smooth_scene(scene_factory):
    """Preloaded nuts (contacts always closed), no backlash, a raised-cosine move: a smooth closed loop."""
    return scene_factory(0.3, position=[{"kind": "hold", "end": 0.05},
                                        {"kind": "sinusoid", "end": 0.3, "amplitude": 1e-3, "frequency": 4.0,
                                         "phase": -1.5707963267948966}], preload=1000.0)


def _final_error(ds, reference, exclude=()):
    error = np.abs(ds.final_state - reference.final_state) / (np.abs(reference.final_state) + 1e-3)
    kept = [str(name) for name in error[error.dims[0]].values if str(name) not in exclude]
    return float(error.sel({error.dims[0]: kept}).max())


@pytest.mark.parametrize("method, steps", [("rk4", (1.5625e-5, 7.8125e-6)),
                                           ("semi_implicit_euler", (7.8125e-6, 3.90625e-6, 1.953125e-6)),
                                           ("rosenbrock_w2", (1.953125e-6, 9.765625e-7, 4.8828125e-7))])
def test_closed_loop_order_on_smooth_scene(bench, smooth_scene, method, steps):
    """The sampled-data loop keeps each method's order: its inputs are held between samples, on
    sample instants shared by every step size, so the plant ODE is smooth between them.
    Measured slopes: RK4 4.2 (4.5 at 31 us, pre-asymptotic), semi-implicit Euler 1.01, W-method 1.98. RK4 is
    measured between 15.6 and 7.8 us: at 3.9 us its error (1e-8 relative, in the screw's axial speed, ~1e-11 m/s)
    reaches the level of the reference run's rounding over its 1.2 million steps (session 6)."""
    params = bench.with_values(SMOOTH)
    reference = twin.simulate(smooth_scene, params, solver=twin.Solver("rk4", dt=2.44140625e-7),
                              fidelity=plant_fidelity(smooth_scene))
    errs = [
        _final_error(twin.simulate(smooth_scene, params, solver=twin.Solver(method, dt=h),
                                   fidelity=plant_fidelity(smooth_scene)), reference)
            for h in steps]
    slope = linregress(np.log(steps), np.log(errs)).slope
    assert slope == pytest.approx(ORDER[method], abs=0.3)


def test_observed_order_on_full_scene():
    """The full nominal scene (reducer play, pneumatics with the valve's hysteresis, sampled loops):
    RK4's error on the final state falls at order >= 4 down to ~16 us (measured 5.6), then sits on a
    floor of ~1e-6 (relative) set by discrete decisions: the valve's hysteresis play and the
    torsional play switch at slightly different instants for different steps. Asserted: a drop of
    at least 2^3 over the first halving, and the floor below 1e-5. Started at the preloaded
    equilibrium: under the thesis procedure (the scene's own) the springs load the nuts through
    the Hertz contact from zero load at t = 0 (F ~ delta^1.5, not smooth there), which puts the
    error on the floor already at 31 us (1.8e-6 at 31 us, 3.8e-6 at 16 us). Without the ball-groove friction
    (issue 18): its Stribeck hump at the reversals (Eq. 5.16) is another such switch and also puts the error on
    the floor at 31 us (1.6e-6 at 31 us, 6.4e-7 at 16 us), so the order is measured on the lossless screw."""
    scene = twin.load_scene("nominal").with_duration(1.2).with_conditions({"zero_procedure": "preloaded"})
    fidelity = {**plant_fidelity(scene), "ball_groove_friction": "lumped"}
    reference = twin.simulate(scene, solver=twin.Solver("rk4", dt=9.765625e-7), fidelity=fidelity)
    # the valve spool's hysteresis play is a discrete switch (order 1-2 on its own states: 1.05e-5, 3.9e-6, 1.2e-6
    # in spool speed at 31, 16, 8 us since the power-consistent motor, measured); the order is read on the others
    spool = ("spool_position", "spool_speed")
    errs = [_final_error(twin.simulate(scene, solver=twin.Solver("rk4", dt=h), fidelity=fidelity), reference, spool)
            for h in (3.125e-5, 1.5625e-5, 7.8125e-6)]
    assert errs[0] / errs[1] > 8.0
    assert max(errs[1:]) < 1e-5


def test_guard_catches_nan_blow_up():
    """RK4 at the 125 us drive period exceeds its stability limit (~1e-4 s): without the local-error
    check the state goes to NaN, and the guard stops the run there with that reason."""
    ds = twin.simulate("ds2", solver=twin.Solver("rk4", dt=1.25e-4, local_error_guard=False),
                       fidelity=plant_fidelity("ds2"), throw=False)
    assert ds.attrs["status"] == "diverged" and "non-finite" in ds.attrs["failure_reason"]
    guarded = twin.simulate("ds2", solver=twin.Solver("rk4", dt=1.25e-4), fidelity=plant_fidelity("ds2"), throw=False)
    assert "finite but wrong" in guarded.attrs["failure_reason"]
    assert guarded.attrs["t_reached"] < ds.attrs["t_reached"]  # caught before the NaN


def test_guard_catches_finite_but_wrong():
    """Semi-implicit Euler at 62.5 us on the loaded nominal scene is past its ~55 us limit: the run stays
    finite and ends 'ok' with a feature 5 um off (50.2 instead of 55.4 um). The step-doubling guard
    flags it."""
    unguarded = twin.simulate("nominal", solver=twin.Solver("semi_implicit_euler", dt=6.25e-5, local_error_guard=False),
                              fidelity=plant_fidelity("nominal"), throw=False)
    right = twin.simulate("nominal", solver=twin.Solver("rk4", dt=3.125e-5), fidelity=plant_fidelity("nominal"))
    assert unguarded.attrs["status"] == "ok"
    assert abs(float(unguarded.backlash_feature - right.backlash_feature)) > 1e-6
    guarded = twin.simulate("nominal", solver=twin.Solver("semi_implicit_euler", dt=6.25e-5),
                            fidelity=plant_fidelity("nominal"), throw=False)
    assert guarded.attrs["status"] == "diverged" and "finite but wrong" in guarded.attrs["failure_reason"]


def test_guard_quiet_on_stable_runs():
    for integrator, dt in (("rk4", 3.125e-5), ("semi_implicit_euler", 3.125e-5), ("rosenbrock_w2", 1.25e-4)):
        ds = twin.simulate("ds1", solver=twin.Solver(integrator, dt=dt), duration=2.0)
        assert ds.attrs["status"] == "ok" and ds.attrs["max_local_error"] < 1.0


def test_reference_path_matches_compiled_loop():
    """scipy Radau with the same sampled-data logic and RK4 agree on the feature to 1e-4 um."""
    reference = twin.simulate("ds7", solver=twin.Solver("scipy_lsoda", rtol=1e-9), duration=0.6,
                              fidelity=plant_fidelity("ds7"))
    compiled = twin.simulate("ds7", solver=twin.Solver("rk4"), duration=0.6, fidelity=plant_fidelity("ds7"))
    assert float(compiled.backlash_feature) == pytest.approx(float(reference.backlash_feature), abs=1e-10)
    assert reference.attrs["solver_nfev"] > 0 and reference.attrs["solver_steps"] > 0


def test_work_precision_round_trip_and_replot(tmp_path):
    study = run_study("ds4", 0.1, steps=(6.25e-5, 3.125e-5), methods=("rk4",), tolerances=(1e-6,),
                      baselines=("scipy_lsoda",), repeats=1, progress=lambda line: None)
    assert set(study.panel.values) == {"quantizers_off", "quantizers_on"}
    assert np.all(study.wall_time > 0)
    # the default configuration (RK4, the quasi-static screw axial, its default step) is one point per panel, at
    # 62.5 us: the full plant's analog current loop (real mode -2.28e4 1/s, RK4 limit 122 us) rules out the drive
    # period (twin.Solver.step; tests/engine/test_default_step.py)
    default = study.where(study.method == f"{DEFAULT_POINT} (rk4, quasi-static screw axial)", drop=True)
    assert default.sizes["run"] == 2 and np.all(default.dt == 6.25e-5)
    study.to_netcdf(tmp_path / "work_precision.nc", engine="netcdf4")
    with xr.open_dataset(tmp_path / "work_precision.nc") as back:
        xr.testing.assert_identical(back.load(), study)
    paths = replot(tmp_path)
    assert paths["work_precision"].stat().st_size > 10_000
    assert (tmp_path / "work_precision.svg").exists()


def test_error_metrics_against_a_shifted_copy():
    """Each metric reads its own signal: against a copy shifted by a known delta per signal, each error equals its
    delta (feature |df|, max |dx|, rms of a constant di, the larger chamber shift), and only its own."""
    ds = twin.simulate("ds3", duration=0.2, fidelity={"default": "full"})
    assert "chamber1_pressure" in ds
    deltas = {"backlash_feature": 2e-7, "nut1_position": -3e-6, "motor_current": 0.05,
              "chamber1_pressure": 150.0, "chamber2_pressure": -400.0}
    metric_of = {"backlash_feature": "feature_error", "nut1_position": "nut_position_error",
                 "motor_current": "current_rms_error", "chamber1_pressure": "pressure_error",
                 "chamber2_pressure": "pressure_error"}
    shifted = ds.copy(deep=True)
    for name, delta in deltas.items():
        shifted[name] = ds[name] + delta
    result = errors(shifted, ds)
    assert result == pytest.approx({"feature_error": 2e-7, "nut_position_error": 3e-6, "current_rms_error": 0.05,
                                    "pressure_error": 400.0}, rel=1e-9)
    for name, delta in deltas.items():
        one = ds.copy(deep=True)
        one[name] = ds[name] + delta
        alone = errors(one, ds)
        assert alone[metric_of[name]] == pytest.approx(abs(delta), rel=1e-9), name
        assert all(v == 0 for k, v in alone.items() if k != metric_of[name]), name
    without_pneumatics = twin.simulate("ds4", duration=0.2, fidelity={"pneumatics": "absent"})
    assert np.isnan(errors(without_pneumatics, without_pneumatics)["pressure_error"])
    failed = shifted.assign_attrs(status="diverged")
    assert all(np.isnan(v) for v in errors(failed, ds).values())
