"""The elasto-plastic seal-friction level (issue 41): the bristle law of twin.physics.bristle_friction in the engine.

The elasto-plastic law is the full level, so ``"full"`` and ``"auto"`` requests get it (issue 41); the regularised law
is the cheaper ``seal_friction = "regularised"`` level. At the elasto-plastic level the seals' deflection is a state,
the piston's friction is the bristle force, and a piston at rest under a force below breakaway is held by it (no
creep); runs complete, and lanes give each run its own numbers bit for bit.
"""

import math
import subprocess
import sys

import numpy as np
import pytest
from lane_helpers import OneLane

import twin
from twin.engine.model import build_model
from twin.engine.plant import W
from twin.fidelity import resolve_fidelity
from twin.fidelity.requests import full_plant
from twin.layout import K, S
from twin.levels import SUBSYSTEMS
from twin.physics import pneumatics as pn
from twin.physics.friction import stribeck_friction
from twin.simulation import simulate, simulate_batch

ELASTO_PLASTIC = {"seal_friction": "elasto_plastic"}
REGULARISED = {"seal_friction": "regularised"}
DURATION = 1.2  # s: the first move of the nominal profile with its reversal, enough for every feature to be finite


def _one_lane(scene_name, level):
    bench = twin.load_parameters()
    scene = twin.load_scene(scene_name)
    request = full_plant("full", seal_friction=level)
    return OneLane(build_model(scene, bench, resolve_fidelity(scene, bench, request)))


def test_the_elasto_plastic_law_is_what_a_request_gets_unless_it_asks():
    bench = twin.load_parameters()
    scene = twin.load_scene("ds4")
    for request in ("auto", "full"):
        fidelity = resolve_fidelity(scene, bench, request)
        assert fidelity.level("seal_friction") == "elasto_plastic"
        assert S.SEAL_DEFLECTION in fidelity.active_states
    assert S.SEAL_DEFLECTION not in resolve_fidelity(scene, bench, REGULARISED).active_states
    # without the cylinder there is no seal to deflect, whatever the seal level
    detached = resolve_fidelity(scene, bench, {**ELASTO_PLASTIC, "pneumatics": "absent"})
    assert S.SEAL_DEFLECTION not in detached.active_states
    assert SUBSYSTEMS["seal_friction"].level_names == ("elasto_plastic", "regularised")


def test_the_cli_lists_the_level():
    listing = subprocess.run([sys.executable, "-m", "app.cli", "fidelity", "levels"], capture_output=True,
                             text=True, check=False, timeout=600)
    assert listing.returncode == 0, listing.stderr
    assert "seal_friction" in listing.stdout and "elasto_plastic" in listing.stdout


def test_the_regularised_level_is_eq_9_11_with_the_regularised_law():
    """The piston's right-hand side at the default level is :func:`twin.physics.pneumatics.piston_acceleration`
    (the regularised Eq. 7.63) exactly: the level split left its arithmetic as it was."""
    lane = _one_lane("ds4", "regularised")
    x = lane.model.initial_state.copy()
    x[S.PISTON_SPEED] = 3.0e-3
    dxdt = lane.rhs(0.0, x)
    c, w = lane.model.constants, lane.w[:, 0]
    expected = pn.piston_acceleration(
        x[S.CHAMBER1_PRESSURE], x[S.CHAMBER2_PRESSURE], x[S.PISTON_POSITION], x[S.PISTON_SPEED], w[W.EXTERNAL],
        c[K.AREA1], c[K.AREA2], c[K.P_ATMOSPHERE], c[K.PISTON_MASS], c[K.PISTON_DAMPING],
        c[K.CYLINDER_FRICTION_STATIC], c[K.CYLINDER_FRICTION_DYNAMIC], c[K.CYLINDER_FRICTION_RATE],
        c[K.CYLINDER_FRICTION_VISCOUS], c[K.CYLINDER_V_THRESHOLD], c[K.STROKE], c[K.DAMPER_TRAVEL],
        c[K.DAMPER_STIFFNESS], c[K.DAMPER_DAMPING], c[K.END_STOP_STIFFNESS])
    assert dxdt[S.PISTON_SPEED] == expected
    assert dxdt[S.SEAL_DEFLECTION] == 0.0  # not integrated at this level


def test_a_piston_at_rest_is_held_by_the_seals_deflection():
    """At rest the bristle law's friction is the elastic ``sigma_0 z`` and the deflection does not move
    (``dz/dt = v = 0``): a force below breakaway is held, where the regularised law gives no friction at rest
    and the piston creeps. Moving, inside the elastic range ``dz/dt = v``."""
    held = _one_lane("ds4", "elasto_plastic")
    regularised = _one_lane("ds4", "regularised")
    c = held.model.constants
    x = held.model.initial_state.copy()
    z = 0.9 * c[K.SEAL_ELASTIC_DEFLECTION]
    x[S.SEAL_DEFLECTION] = z
    a_held = held.rhs(0.0, x)
    a_free = regularised.rhs(0.0, x)
    assert a_held[S.SEAL_DEFLECTION] == 0.0
    # the difference of the two accelerations is the elastic friction over the piston mass
    assert math.isclose((a_free[S.PISTON_SPEED] - a_held[S.PISTON_SPEED]) * c[K.PISTON_MASS],
                        c[K.SEAL_STIFFNESS] * z, rel_tol=1e-9)
    x[S.PISTON_SPEED] = 1.0e-4
    assert held.rhs(0.0, x)[S.SEAL_DEFLECTION] == 1.0e-4
    # the regularised law at rest: no friction at all
    assert stribeck_friction(0.0, c[K.CYLINDER_FRICTION_STATIC], c[K.CYLINDER_FRICTION_DYNAMIC],
                             c[K.CYLINDER_FRICTION_RATE], c[K.CYLINDER_FRICTION_VISCOUS],
                             c[K.CYLINDER_V_THRESHOLD]) == 0.0


@pytest.mark.slow
def test_a_free_nut_run_completes_at_the_drive_period():
    """ds4 (free nut, the seals holding the sled through the piston) at RK4 125 us: the presliding mode,
    sqrt(sigma_0 / m_p) = 1.2e3 rad/s, is far inside RK4's stability limit at that step (h w = 0.14). At the rules'
    levels (their ideal current loop: the full analog loop's mode is beyond RK4 at 125 us; ds4's "auto" keeps the full
    model, twin/fidelity/speed.toml)."""
    rules = dict(resolve_fidelity(twin.load_scene("ds4"), twin.load_parameters(), speed_file=None).levels)
    run = simulate("ds4", solver=twin.Solver(dt=125e-6), save="features", fidelity=rules | ELASTO_PLASTIC, rng=0)
    assert run.status == "ok" and "seal_friction=elasto_plastic" in run.fidelity
    assert all(math.isfinite(value) for value in run.features.values())
    # the rules' levels take this seal level by default: the same run to the bit; the regularised law reads otherwise
    default = simulate("ds4", solver=twin.Solver(dt=125e-6), save="features", fidelity=rules, rng=0)
    assert run.features["backlash_feature"] == default.features["backlash_feature"]
    regularised = simulate("ds4", solver=twin.Solver(dt=125e-6), save="features", fidelity=rules | REGULARISED,
                           rng=0)
    assert run.features["backlash_feature"] != regularised.features["backlash_feature"]


def _runs():
    params = twin.load_parameters()
    runs = []
    for k, name in enumerate(["ds4", "ds2", "ds7", "ds6"]):
        scene = twin.load_scene(name).with_duration(DURATION).with_conditions(
            {"room_temperature": 290.15 + k, "supply_pressure": 7.0e5 * (1.0 - 0.01 * k)})
        runs.append((scene, params.with_values({"pneumatics.friction_static": 400.0 + 20.0 * k}),
                     np.random.default_rng(3000 + k)))
    return runs


@pytest.mark.slow
@pytest.mark.parametrize("lanes", [1, 4])
def test_lanes_give_each_run_its_own_numbers_at_the_elasto_plastic_level(lanes):
    runs = _runs()
    alone = [simulate(scene, params, save="features", fidelity=ELASTO_PLASTIC, rng=np.random.default_rng(3000 + k),
                      throw=False) for k, (scene, params, _) in enumerate(runs)]
    batch = simulate_batch(runs, solver=twin.Solver(lanes=lanes), fidelity=ELASTO_PLASTIC, throw=False)
    for k, (summary, reference) in enumerate(zip(batch, alone, strict=True)):
        assert summary.status == reference.status == "ok", f"run {k}"
        assert summary.features.keys() == reference.features.keys()
        assert all(np.array_equal(summary.features[f], reference.features[f], equal_nan=True)
                   for f in summary.features), f"run {k} at {lanes} lanes"
