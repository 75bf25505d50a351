"""The default step (twin.Solver.step): RK4 at the 125 us drive period at the automatic fidelity, 62.5 us
where a mode beyond RK4's reach at the drive period is modelled, and why.

RK4's stability limit is ``2.785 / |lambda|`` on a real mode and ``2 sqrt(2) / |lambda|`` on an undamped
oscillation (twin.engine.linearize). Two modes of the full model lie beyond it at 125 us: the screw's axial mass
between the bearing and the loaded contacts (the ``dynamic`` screw-axial level) and the analog current loop's real
mode (the ``full`` current loop). The automatic fidelity of the thesis campaign models neither (the quasi-static
screw axial, the ideal current loop), which is what lets its runs take the drive period. (This replaces the tests
of the retired opt-in ``integrator="auto"``, twin.engine.solver_choice: the facts about the drive period that it
used are checked here on the methods and levels directly.)
"""

import numpy as np
import pytest
from lane_helpers import column

import twin
from twin.engine.implicit import current_loop_jacobian
from twin.engine.linearize import jacobian, largest_stable_step
from twin.engine.model import build_model
from twin.errors import OptionError
from twin.fidelity import resolve_fidelity
from twin.layout import N_INPUTS
from twin.solver import DEFAULT_DT, solver_label

DRIVE_PERIOD = twin.load_parameters().value("drive.speed_loop_sample_time")


def _model(scene, fidelity):
    params = twin.load_parameters()
    scene = twin.load_scene(scene)
    return build_model(scene, params, resolve_fidelity(scene, params, fidelity))


def _rk4_limit(model):
    """RK4's stability limit at the model's initial state (finite-difference Jacobian of the integrated states)."""
    return largest_stable_step(np.linalg.eigvals(jacobian(model, model.initial_state[model.active])))


def test_default_step_by_fidelity():
    """RK4 at the drive period at the automatic fidelity of a preloaded scene (quasi-static screw axial, ideal
    current loop), else DEFAULT_DT (62.5 us, half the drive period): where either mode beyond it is modelled, and
    without preload (the quasi-static level's condition); the method and step are reported with the run and named
    by solver_label."""
    assert DRIVE_PERIOD == 1.25e-4 and DEFAULT_DT == 0.5 * DRIVE_PERIOD
    auto = twin.simulate("ds1", save="features", duration=0.05)
    assert "screw_axial=quasi_static" in auto.fidelity and "current_loop=ideal" in auto.fidelity
    assert (auto.integrator, auto.dt) == ("rk4", DRIVE_PERIOD)
    assert solver_label(auto.integrator, auto.dt) == "rk4 at 125 us"
    for fidelity in ("full", {"screw_axial": "dynamic"}, {"current_loop": "full"}):
        summary = twin.simulate("ds1", save="features", duration=0.05, fidelity=fidelity)
        assert (summary.integrator, summary.dt) == ("rk4", DEFAULT_DT), fidelity
    assert solver_label("rk4", DEFAULT_DT) == "rk4 at 62.5 us"
    assert solver_label("scipy_lsoda", DRIVE_PERIOD) == "scipy_lsoda"  # an adaptive method has no step of its own
    ds = twin.simulate("ds1", duration=0.05, fidelity={"screw_axial": "dynamic"})
    unpreloaded = twin.simulate("ds2", save="features", duration=0.05)  # the quasi-static level only under preload
    assert "screw_axial=dynamic" in unpreloaded.fidelity and unpreloaded.dt == DEFAULT_DT
    assert (ds.attrs["integrator"], ds.attrs["dt"]) == ("rk4", DEFAULT_DT)


def test_the_current_loop_mode_is_beyond_rk4_at_the_drive_period():
    """At full fidelity the analog current loop (winding, Hall filter, PI) has a real mode near -2.28e4 1/s whatever
    the load: RK4's limit 2.785 / |lambda| is 122 us, below the drive period. Cross-check of two Jacobians: the
    current-loop block's analytic one (twin.engine.implicit.current_loop_jacobian) against the finite-difference
    one of the whole bench at the initial state (nothing else is that fast with the nuts unloaded), to 1e-3: the
    block leaves out the back-EMF and temperature couplings (measured 3.5e-4). With the ideal current loop the rules
    choose the whole bench's limit is above the drive period (the rules alone: ds4's stored speedup keeps "auto" on
    the full model, twin/fidelity/speed.toml)."""
    model = _model("ds4", "full")
    block = np.zeros((3, 3))
    current_loop_jacobian(column(model.initial_state.copy()), column(model.constants), np.zeros((N_INPUTS, 1)), 0,
                          block)
    analytic = largest_stable_step(np.linalg.eigvals(block))
    assert 120e-6 < analytic < DRIVE_PERIOD
    assert _rk4_limit(model) == pytest.approx(analytic, rel=1e-3)
    scene, params = twin.load_scene("ds4"), twin.load_parameters()
    rules = resolve_fidelity(scene, params, speed_file=None)
    assert rules.level("current_loop") == "ideal"
    assert _rk4_limit(build_model(scene, params, rules)) > DRIVE_PERIOD


def test_the_axial_mode_with_loaded_contacts_is_beyond_rk4_at_the_drive_period():
    """ds5 at its preloaded equilibrium (both contacts carrying 1 kN): with the screw's axial mass (the dynamic
    level) the fastest oscillation is the axial mode (|lambda| 2.4e4 1/s) and RK4's limit is 121 us, below the
    drive period; the quasi-static level removes the mode and the limit rises to 156 us (the next modes,
    1.7e4 1/s), above it. Everything else as the automatic fidelity chooses."""
    params = twin.load_parameters()
    scene = twin.load_scene("ds5").with_conditions({"zero_procedure": "preloaded"})
    limits = {}
    for level in ("dynamic", "quasi_static"):
        model = build_model(scene, params, resolve_fidelity(scene, params, {"screw_axial": level}))
        limits[level] = _rk4_limit(model)
    assert limits["dynamic"] < DRIVE_PERIOD < limits["quasi_static"]
    assert limits["dynamic"] == pytest.approx(121e-6, rel=0.02)


@pytest.mark.parametrize("scene_name", ["ds1", "ds5"])
def test_the_default_step_agrees_with_half_of_it(scene_name):
    """Cross-check of two steps at the automatic fidelity of the preloaded sets (the quasi-static screw axial, RK4 at
    the drive period): the Eq. 9.12 feature on true signals within 0.01 um of RK4 at 62.5 us over 5 s, with a gap
    (ds1) and without (ds5). Measured 0.0001 um on both; with a free nut in a small gap (ds6, before the quasi-static
    level was restricted to preloaded scenes) 0.002 um, whose five times is the bound."""
    default = twin.simulate(scene_name, save="features", duration=5.0)
    assert default.dt == DRIVE_PERIOD
    half = twin.simulate(scene_name, solver=twin.Solver(dt=DEFAULT_DT), save="features", duration=5.0)
    difference = default.features["backlash_feature_true"] - half.features["backlash_feature_true"]
    assert abs(difference) < 0.01e-6


def test_retired_and_restricted_integrators_are_refused_before_running():
    """The opt-in ``integrator="auto"`` is retired: an unknown method, named as such; ``imex_euler`` integrates the
    screw's axial mode implicitly and is refused at the quasi-static level, naming the fidelity it needs."""
    with pytest.raises(OptionError, match="integrator: 'auto' is not one of rk4"):
        twin.simulate("ds5", solver=twin.Solver("auto"), duration=0.01)
    with pytest.raises(OptionError, match="needs fidelity screw_axial = 'dynamic'"):
        twin.simulate("ds5", solver=twin.Solver("imex_euler"), duration=0.01)
    ok = twin.simulate("ds5", solver=twin.Solver("imex_euler"), save="features", duration=0.01,
                       fidelity={"screw_axial": "dynamic"})
    assert ok.status == "ok" and ok.dt == DEFAULT_DT
