"""The linear guides as one component (twin/components/guides.py): each nut's share of their friction law, the law's
levels checked, the tangent the slope of the law at rest and the roll springs' energy consistent with their torque."""

from __future__ import annotations

import numpy as np
import pytest

import twin
from twin.components import COMPONENTS, guides
from twin.engine.model import build_model
from twin.fidelity import resolve_fidelity
from twin.layout import N_CONSTANTS, N_STATES, K, S


def _constants(values=None):
    params = twin.load_parameters("bench")
    params = params.with_values(values) if values else params
    scene = twin.load_scene("nominal")
    return build_model(scene, params, resolve_fidelity(scene, params)).constants.reshape(-1, 1).copy(), params.values()


def _state(speed=0.0, angle=0.0):
    x = np.zeros((N_STATES, 1))
    x[S.NUT1_SPEED, 0] = x[S.NUT2_SPEED, 0] = speed
    x[S.NUT1_ANGLE, 0], x[S.NUT2_ANGLE, 0] = angle, -0.5 * angle
    return x


def test_the_master_carries_the_law_and_the_slave_its_fraction():
    c = np.full(N_CONSTANTS, np.nan)
    p = twin.load_parameters("bench").values()
    guides.derive_constants(c, p, twin.load_scene("nominal"))
    assert sorted(np.flatnonzero(np.isfinite(c))) == sorted([K.NUT1_GUIDE_FRICTION_SHARE, K.NUT2_GUIDE_FRICTION_SHARE])
    assert c[K.NUT1_GUIDE_FRICTION_SHARE] == 1.0 and c[K.NUT2_GUIDE_FRICTION_SHARE] == p["sled.slave_friction_fraction"]
    lane_c, _ = _constants()
    master = guides.friction_at(_state(3e-3), lane_c, 0, 0)
    assert master > 0.0  # opposing the motion
    assert guides.friction_at(_state(3e-3), lane_c, 0, 1) == p["sled.slave_friction_fraction"] * master  # x 0.5: exact


def test_a_breakaway_below_the_coulomb_level_is_refused_naming_the_field():
    with pytest.raises(twin.ParameterError, match="sled.guide_friction_static"):
        _constants({"sled.guide_friction_static": 1.0, "sled.guide_friction_dynamic": 5.0})


@pytest.mark.parametrize("nut", [0, 1])
def test_the_tangent_is_the_slope_of_the_friction_law_at_rest(nut):
    # at v = 0 the regularised law's slope is F_s / v_th + b exactly (the Stribeck decay is multiplied by tanh(0)):
    # what the tangent takes; a central difference of 1e-9 m/s is exact to its round-off
    c, _ = _constants()
    step = 1e-9
    slope = (guides.friction_at(_state(step), c, 0, nut) - guides.friction_at(_state(-step), c, 0, nut)) / (2 * step)
    h = 1.25e-4
    assert guides.friction_slope_at(_state(0.0), c, 0, nut, h) == pytest.approx(h * slope, rel=1e-6)


def test_the_roll_springs_energy_is_the_integral_of_their_torque():
    c, _ = _constants()
    angle, step = 4e-6, 1e-10
    _, e_plus = guides.energy(_state(angle=angle + step)[:, 0], c[:, 0])
    _, e_minus = guides.energy(_state(angle=angle - step)[:, 0], c[:, 0])
    # d/dtheta_1 of k (theta_1^2 + (theta_1 / 2)^2) / 2 along this path: k theta_1 (1 + 1/4)
    torque = 1.25 * c[K.GUIDE_ROLL_STIFFNESS, 0] * angle
    assert (e_plus - e_minus) / (2.0 * step) == pytest.approx(torque, rel=1e-6)
    assert guides.energy(_state(speed=1.0)[:, 0], c[:, 0]) == (0.0, 0.0)  # no kinetic energy of its own


def test_the_table_registers_the_guides():
    assert guides in COMPONENTS and guides.LEVELS == ("nut_rotation",) and guides.ABSOLUTE_TOLERANCES == {}
