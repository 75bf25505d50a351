"""The right-hand side and the RK4 step composed two ways from the same per-lane stages (twin.engine.plant): split
over the lanes (a group of several) and fused per sample (a group of one). A lane's numbers must be the same bits in
both, at every fidelity configuration that changes which stages run."""

from __future__ import annotations

import numpy as np
import pytest

import twin
from twin.engine.integrators import RK4, Workspace, step
from twin.engine.model import build_model
from twin.engine.plant import FUSED_LANES, rhs, work_rows
from twin.fidelity import resolve_fidelity
from twin.layout import N_INPUTS, N_STATES, S, U

LANES = 3  # a split group (more than FUSED_LANES), each lane then alone, fused

CONFIGURATIONS = {
    "automatic (quasi-static screw axial, full pneumatics)": ("nominal", "auto", {}),
    "dynamic screw axial": ("nominal", {"screw_axial": "dynamic"}, {}),
    "ideal load, no nut roll": ("ds2", {"pneumatics": "ideal", "nut_rotation": "off"}, {}),
    "with a lead error": ("ds2", "auto", {"ball_screw.lead_travel_variation_amplitude": 2e-6}),
}


def _group(scene_name, fidelity, values):
    """``LANES`` runs of one group: the same levels, each lane its own state near the initial one and its own held
    inputs (seeded), so that every stage has work to do (contacts loaded, motor running)."""
    scene = twin.load_scene(scene_name)
    params = twin.load_parameters("bench").with_values(values) if values else twin.load_parameters("bench")
    model = build_model(scene, params, resolve_fidelity(scene, params, fidelity))
    rng = np.random.default_rng(7)
    x = np.repeat(model.initial_state[:, None], LANES, axis=1)
    for lane in range(LANES):
        x[S.CURRENT, lane] = rng.uniform(-2.0, 2.0)
        x[S.REDUCER_SPEED, lane] = x[S.SCREW_SPEED, lane] = rng.uniform(-50.0, 50.0)
        x[S.REDUCER_ANGLE, lane] = rng.choice([-1.0, 1.0]) * rng.uniform(1e-2, 2e-2)  # beyond the play
        x[S.NUT1_POSITION, lane] += rng.uniform(-3e-6, 3e-6)
        x[S.NUT2_POSITION, lane] += rng.uniform(-3e-6, 3e-6)
        x[S.NUT1_SPEED, lane] = x[S.NUT2_SPEED, lane] = rng.uniform(-1e-2, 1e-2)
    u = np.zeros((N_INPUTS, LANES))
    u[U.CURRENT_DEMAND] = rng.uniform(-2.0, 2.0, LANES)
    u[U.VALVE_COMMAND] = model.constants[twin.layout.K.VALVE_MID]
    c = np.ascontiguousarray(np.repeat(model.constants[:, None], LANES, axis=1))
    return model, np.ascontiguousarray(x), c, u


def _lane(array, lane):
    """Lane ``lane`` of a group's array as a group of one (a contiguous copy)."""
    return np.ascontiguousarray(array[:, lane:lane + 1])


def _rhs(model, x, c, u):
    dxdt = np.zeros_like(x)
    w = work_rows(x.shape[1])
    rhs(0.25, x, c, u, model.levels, model.force_table, dxdt, w)
    return dxdt, w


def _step(model, x, c, u, h):
    vectors, w, matrices, cache, small = Workspace(N_STATES, x.shape[1]).arrays()
    step(RK4, 0.25, x, h, c, u, model.levels, model.force_table, vectors[:6], w, matrices, cache, small, False,
         model.active, model.pairs)
    return w


def test_a_group_of_several_lanes_is_split_and_one_lane_fused():
    assert 1 <= FUSED_LANES < LANES


@pytest.mark.parametrize("configuration", list(CONFIGURATIONS))
def test_the_fused_right_hand_side_gives_each_lane_the_bits_of_the_split_one(configuration):
    model, x, c, u = _group(*CONFIGURATIONS[configuration])
    split_x = x.copy()
    split_dxdt, split_w = _rhs(model, split_x, c, u)
    assert np.all(np.isfinite(split_dxdt)) and np.any(split_w[0] != 0.0)
    for lane in range(LANES):
        lane_x = _lane(x, lane)
        dxdt, w = _rhs(model, lane_x, _lane(c, lane), _lane(u, lane))
        # exact: the same operations in the same order (tolerance 0: a difference is a bug, not round-off)
        np.testing.assert_array_equal(dxdt[:, 0], split_dxdt[:, lane])
        np.testing.assert_array_equal(w[:, 0], split_w[:, lane])
        np.testing.assert_array_equal(lane_x[:, 0], split_x[:, lane])  # the quasi-static balance writes x


@pytest.mark.parametrize("configuration", list(CONFIGURATIONS))
def test_the_fused_rk4_step_gives_each_lane_the_bits_of_the_split_one(configuration):
    model, x, c, u = _group(*CONFIGURATIONS[configuration])
    h = 6.25e-5
    split_x = x.copy()
    split_w = _step(model, split_x, c, u, h)
    assert not np.array_equal(split_x, x)
    for lane in range(LANES):
        lane_x = _lane(x, lane)
        w = _step(model, lane_x, _lane(c, lane), _lane(u, lane), h)
        np.testing.assert_array_equal(lane_x[:, 0], split_x[:, lane])
        np.testing.assert_array_equal(w[:, 0], split_w[:, lane])
