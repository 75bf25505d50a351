"""The preload set as one component (twin/components/preload.py): its constants from the scene's preload, its force,
tangent and energy consistent, its share on each nut equal and opposite."""

from __future__ import annotations

import numpy as np
import pytest

import twin
from twin.components import preload
from twin.layout import N_CONSTANTS, N_STATES, K, S


def _constants(conditions):
    c = np.zeros(N_CONSTANTS)
    preload.derive_constants(c, twin.load_parameters("bench").values(),
                             twin.load_scene("nominal").with_conditions(conditions))
    return c


def _state(separation, rate=0.0):
    x = np.zeros((N_STATES, 1))
    x[S.NUT2_POSITION, 0], x[S.NUT2_SPEED, 0] = separation, rate
    return x


def test_without_a_preload_the_set_is_not_mounted():
    c = _constants({"preload": 0.0})
    assert c[K.PRELOAD_STIFFNESS] == c[K.PRELOAD_DAMPING] == 0.0
    assert preload.assembled_compression(c, 0.0, 1e-6) == 0.0


@pytest.mark.parametrize("configuration, orientation", [("O", 1.0), ("X", -1.0)])
def test_the_assembled_compression_gives_the_preload_at_the_equilibrium_separation(configuration, orientation):
    c = _constants({"preload": 1500.0, "preload_configuration": configuration})
    assert c[K.PRELOAD_ORIENTATION] == orientation and c[K.PRELOAD_STIFFNESS] > 0.0
    separation = 3e-6
    c[K.PRELOAD_COMPRESSION] = preload.assembled_compression(c, 1500.0, separation)
    lane_c = c.reshape(-1, 1)
    assert preload.force_at(_state(separation), lane_c, 0) == pytest.approx(1500.0, rel=1e-12)  # round-off only
    master = preload.nut_share_at(lane_c, 1500.0, 0, 1.0)
    slave = preload.nut_share_at(lane_c, 1500.0, 0, 0.0)
    assert master == -slave == -orientation * 1500.0  # O pushes the nuts apart: the master (nut 1) along -x


def test_the_tangent_is_the_slope_of_the_force_and_the_energy_its_integral():
    c = _constants({"preload": 1500.0, "preload_configuration": "O"})
    c[K.PRELOAD_COMPRESSION] = preload.assembled_compression(c, 1500.0)
    lane_c = c.reshape(-1, 1)
    engaged, stiffness, damping = preload.tangent_at(_state(0.0, 1e-4), lane_c, 0)
    assert engaged and stiffness == c[K.PRELOAD_STIFFNESS] and damping == c[K.PRELOAD_DAMPING]
    step = 1e-9
    slope = (preload.force_at(_state(step), lane_c, 0) - preload.force_at(_state(-step), lane_c, 0)) / (2.0 * step)
    assert slope == pytest.approx(-stiffness, rel=1e-6)  # a linear spring: only the difference's round-off
    _, e_plus = preload.energy(_state(step)[:, 0], c)
    _, e_minus = preload.energy(_state(-step)[:, 0], c)
    assert -(e_plus - e_minus) / (2.0 * step) == pytest.approx(preload.force_at(_state(0.0), lane_c, 0), rel=1e-6)
    unloaded = 2.0 * c[K.PRELOAD_COMPRESSION]  # the O set opened beyond its compression: no force, no tangent
    assert preload.tangent_at(_state(unloaded), lane_c, 0) == (False, 0.0, 0.0)
    assert preload.force_at(_state(unloaded), lane_c, 0) == 0.0 == preload.energy(_state(unloaded)[:, 0], c)[1]
