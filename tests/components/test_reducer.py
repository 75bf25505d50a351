"""The reducer as one component (twin/components/reducer.py): the engine and the loop design read the same
constants, its tangent and energy are those of its law, and the table registers it."""

from __future__ import annotations

import numpy as np
import pytest

import twin
from twin.components import COMPONENTS, reducer
from twin.control.design import two_mass_speed_plant
from twin.engine.model import build_model
from twin.engine.reference import absolute_tolerance
from twin.fidelity import resolve_fidelity
from twin.layout import COMPONENTS as LAYOUT_COMPONENTS
from twin.layout import N_CONSTANTS, N_STATES, K, S


def _constants(params):
    scene = twin.load_scene("nominal")
    return build_model(scene, params, resolve_fidelity(scene, params)).constants


@pytest.mark.parametrize("values", [{}, {"motor.inertia": 1.65e-4, "reducer.ratio": 4.0}])
def test_the_engine_and_the_loop_design_read_one_reflected_inertia(values):
    params = twin.load_parameters("bench").with_values(values) if values else twin.load_parameters("bench")
    p = params.values()
    inertia = _constants(params)[K.J_MOTOR_SIDE]
    assert inertia == (p["motor.inertia"] + p["reducer.inertia"]) * p["reducer.ratio"] ** 2
    # the design's two-mass plant: den = [j1 j2, c (j1 + j2), k (j1 + j2), 0], num = gain [j2, c, k]
    num, den = two_mass_speed_plant(p)
    j2 = num[0] / (p["reducer.ratio"] ** 2 * p["reducer.efficiency"])
    assert den[0] / j2 == pytest.approx(inertia, rel=1e-14)  # one division's round-off


def _state(deflection, rate):
    x = np.zeros((N_STATES, 1))
    x[S.REDUCER_ANGLE, 0], x[S.REDUCER_SPEED, 0] = deflection, rate
    return x


def _reducer_constants():
    return _constants(twin.load_parameters("bench")).reshape(-1, 1).copy()


def test_the_tangent_is_the_slope_of_the_torque_law_and_zero_in_the_play():
    c = _reducer_constants()
    c[K.REDUCER_BACKLASH, 0] = 2e-4
    half = 0.5 * c[K.REDUCER_BACKLASH, 0]
    engaged, stiffness, damping = reducer.torsion_tangent_at(_state(0.5 * half, 0.0), c, 0)
    assert (engaged, stiffness, damping) == (False, 0.0, 0.0)
    deflection, step = 3.0 * half, 1e-7 * half
    engaged, stiffness, damping = reducer.torsion_tangent_at(_state(deflection, 1e-3), c, 0)
    assert engaged and damping == c[K.TORSION_DAMPING, 0]
    slope = (reducer.transmitted_torque_at(_state(deflection + step, 0.0), c, 0)
             - reducer.transmitted_torque_at(_state(deflection - step, 0.0), c, 0)) / (2.0 * step)
    assert slope == pytest.approx(stiffness, rel=1e-6)  # a linear spring: only the difference's round-off


def test_the_elastic_energy_is_the_integral_of_the_elastic_torque():
    c = _reducer_constants()
    c[K.REDUCER_BACKLASH, 0] = 2e-4
    deflections = np.linspace(0.0, 5e-4, 2001)
    torques = [reducer.transmitted_torque_at(_state(d, 0.0), c, 0) for d in deflections]
    work = float(np.sum(0.5 * (np.array(torques[1:]) + torques[:-1]) * np.diff(deflections)))
    x = _state(deflections[-1], 2.0)[:, 0]
    kinetic, elastic = reducer.energy(x, c[:, 0])
    assert kinetic == 0.5 * c[K.J_MOTOR_SIDE, 0] * 4.0
    # the trapezoid rule is exact on the linear pieces; the kink at the play's edge costs one panel's share
    assert elastic == pytest.approx(work, rel=1e-5)


def test_the_table_registers_each_component_once_with_every_part():
    names = [component.NAME for component in COMPONENTS]
    layout_names = [component.name for component in LAYOUT_COMPONENTS]
    assert len(set(names)) == len(names) and set(names) <= set(layout_names)
    assert names == [name for name in layout_names if name in names]  # in the layout's order
    for component in COMPONENTS:
        for part in ("LEVELS", "ABSOLUTE_TOLERANCES", "derive_constants", "energy"):
            assert hasattr(component, part), f"{component.NAME} lacks {part}"


def test_the_reference_integrator_takes_the_reducers_tolerances():
    tolerance = absolute_tolerance(1.0)
    for state, value in reducer.ABSOLUTE_TOLERANCES.items():
        assert tolerance[state] == value


def test_the_derived_constants_are_the_only_ones_the_reducer_writes():
    c = np.full(N_CONSTANTS, np.nan)
    reducer.derive_constants(c, twin.load_parameters("bench").values(), twin.load_scene("nominal"))
    assert sorted(np.flatnonzero(np.isfinite(c))) == sorted([K.J_MOTOR_SIDE, K.TORSION_STIFFNESS])


def test_the_motor_turns_ratio_times_faster_than_the_reducer_output():
    p = twin.load_parameters("bench").values()
    x = _state(0.0, 3.0)
    c = _reducer_constants()
    assert reducer.motor_speed(3.0, p) == reducer.motor_speed_at(x, c, 0) == 3.0 * p["reducer.ratio"]
