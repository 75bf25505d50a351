"""The divergence guard's short cuts decide exactly like the plain checks they replace."""

import math

import numpy as np
import pytest
from lane_helpers import OneLane, column

import twin
from twin.engine.codes import PNEUMATICS, PNEUMATICS_FULL
from twin.engine.loop import guard
from twin.engine.model import build_model
from twin.engine.plant import W, work_rows
from twin.fidelity import full_plant, resolve_fidelity
from twin.layout import K, S
from twin.physics.ball_screw import contact_geometry

#: States the guard bounds by nothing but finiteness at a fidelity without the load system (its chamber pressures
#: are bounded only where the pneumatics are modelled): the values of the first test go there.
UNBOUNDED = (S.HALL_CURRENT, S.CURRENT_PI, S.SCREW_SPEED, S.SCREW_AXIAL_SPEED, S.NUT1_SPEED, S.NUT2_SPEED,
             S.NUT1_ANGULAR_SPEED, S.NUT2_ANGULAR_SPEED, S.SPOOL_POSITION, S.SPOOL_SPEED, S.CHAMBER1_PRESSURE,
             S.CHAMBER2_PRESSURE, S.PISTON_POSITION, S.PISTON_SPEED)


@pytest.fixture(scope="module")
def plant_model(bench):
    """The full plant of ds4 without the load system (its chamber pressures unbounded by the guard)."""
    scene = twin.load_scene("ds4")
    model = build_model(scene, bench, resolve_fidelity(scene, bench, full_plant("absent")))
    assert model.levels[PNEUMATICS] != PNEUMATICS_FULL
    return model


@pytest.mark.parametrize("values", [
    [0.0, -1.5, 3e5], [math.inf, 0.0], [-math.inf, 1.0], [math.nan], [1e308, 1e308], [-1e308, 1e308],
    [1.7e308, -1e300, 1e2], [2.0 ** 977, 2.0 ** 977], [5e-324, -0.0], [math.inf, -math.inf],
])
def test_finite_check_is_the_finiteness_of_the_sum(plant_model, values):
    """The guard's first check sums the lane's state once instead of testing every state: it trips (code 1)
    exactly when that sum is not finite (any NaN or infinity, or finite states whose sum overflows: far beyond
    every physical bound anyway), and otherwise leaves the state to the bound checks."""
    x = np.zeros(plant_model.initial_state.size)
    x[list(UNBOUNDED[:3 * len(values)])] = values * 3
    code = guard(column(x), column(plant_model.constants), work_rows(1), 0, plant_model.levels)
    assert code == (0 if math.isfinite(sum(x.tolist())) else 1)


def test_approach_limit_decided_by_the_exact_contact_geometry(bench):
    """Interferences up to and past the normal-approach limit: code 6 exactly where Eq. 9.4 exceeds it."""
    scene = twin.load_scene("ds2")
    model = build_model(scene, bench, resolve_fidelity(scene, bench, "full", None, "thesis"))
    lane = OneLane(model)
    c = model.constants
    limit = c[K.MAX_NORMAL_APPROACH]
    codes = []
    for interference in np.linspace(0.5, 1.5, 2001) * limit * 1.4:
        x = model.initial_state.copy()
        x[S.SCREW_AXIAL] = 0.0
        base = lane.forces(0.0, x)[W.NUT_DX]  # the dynamic screw-axial level: dx_1 at x_s = 0
        x[S.SCREW_AXIAL] = interference / c[K.COS_HELIX] + 0.5 * c[K.BACKLASH] - base
        gap = abs(lane.forces(0.0, x)[W.NUT_DX]) - 0.5 * c[K.BACKLASH]
        approach, _ = contact_geometry(gap * c[K.COS_HELIX], c[K.CENTRE_DISTANCE], c[K.CONTACT_RADIAL_0],
                                       c[K.CONTACT_AXIAL_0])
        code = guard(column(x), lane.c, work_rows(1), 0, model.levels)
        assert code in (0, 6)
        assert (code == 6) == (approach > limit)
        codes.append(code)
    assert 0 < codes.count(6) < len(codes)  # both sides of the limit were tried


def test_a_failed_quasi_static_balance_is_a_bound(plant_model):
    """A lane whose quasi-static screw-axial balance ran out of iterations (``W.BALANCE_FAILED``) is stopped with
    its own code, whatever its state."""
    w = work_rows(1)
    x = plant_model.initial_state.copy()
    c = column(plant_model.constants)
    assert guard(column(x), c, w, 0, plant_model.levels) == 0
    w[W.BALANCE_FAILED, 0] = 1.0
    assert guard(column(x), c, w, 0, plant_model.levels) == 9
    assert "quasi-static screw-axial balance" in twin.layout.BOUND_REASONS[9]
