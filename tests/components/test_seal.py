"""The cylinder's seal friction as one component (twin/components/seal.py): its constants from its parameters, its
tangent the slope of its law at rest, its stored energy the integral of its elastic force, each level writing only
what it integrates, and the table registering it."""

from __future__ import annotations

import numpy as np
import pytest

import twin
from twin.components import COMPONENTS, seal
from twin.engine.model import build_model
from twin.engine.reference import absolute_tolerance
from twin.fidelity import resolve_fidelity
from twin.layout import N_CONSTANTS, N_STATES, PARAMETER_CONSTANTS, K, S
from twin.levels import SUBSYSTEMS, level_code

ELASTO_PLASTIC = level_code("seal_friction", "elasto_plastic")
REGULARISED = level_code("seal_friction", "regularised")
SEAL_PARAMETERS = {K.CYLINDER_FRICTION_STATIC: "pneumatics.friction_static",
                   K.CYLINDER_FRICTION_DYNAMIC: "pneumatics.friction_dynamic",
                   K.CYLINDER_FRICTION_RATE: "pneumatics.friction_stribeck_coefficient",
                   K.CYLINDER_FRICTION_VISCOUS: "pneumatics.friction_viscous",
                   K.CYLINDER_V_THRESHOLD: "pneumatics.friction_velocity_threshold",
                   K.SEAL_STIFFNESS: "pneumatics.friction_presliding_stiffness",
                   K.SEAL_DAMPING: "pneumatics.friction_bristle_damping",
                   K.SEAL_DAMPING_SPEED: "pneumatics.friction_bristle_damping_speed"}


def _constants(values=None):
    params = twin.load_parameters("bench")
    params = params.with_values(values) if values else params
    scene = twin.load_scene("ds2")
    return build_model(scene, params, resolve_fidelity(scene, params)).constants.reshape(-1, 1).copy(), params


def _state(speed, deflection=0.0):
    x = np.zeros((N_STATES, 1))
    x[S.PISTON_SPEED, 0], x[S.SEAL_DEFLECTION, 0] = speed, deflection
    return x


def _friction(c, speed, deflection, level):
    return seal.friction_at(_state(speed, deflection), c, np.zeros((N_STATES, 1)), 0, level)


@pytest.mark.parametrize("values", [None, {"pneumatics.friction_dynamic": 180.0,
                                           "pneumatics.friction_presliding_stiffness": 4.0e6}])
def test_the_constants_copy_the_parameters_and_the_elastic_deflection_is_its_fraction_of_fd_over_sigma0(values):
    c, params = _constants(values)
    p = params.values()
    for constant, name in SEAL_PARAMETERS.items():
        assert PARAMETER_CONSTANTS[constant] == name and c[constant, 0] == p[name]
    assert c[K.SEAL_ELASTIC_DEFLECTION, 0] == (p["pneumatics.friction_elastic_fraction"]
                                               * p["pneumatics.friction_dynamic"]
                                               / p["pneumatics.friction_presliding_stiffness"])


def test_the_derived_constant_is_the_only_one_the_seal_writes():
    c = np.full(N_CONSTANTS, np.nan)
    seal.derive_constants(c, twin.load_parameters("bench").values(), twin.load_scene("ds2"))
    assert list(np.flatnonzero(np.isfinite(c))) == [K.SEAL_ELASTIC_DEFLECTION]


@pytest.mark.parametrize("level", [ELASTO_PLASTIC, REGULARISED])
def test_the_tangent_is_the_slope_of_the_friction_law_at_rest(level):
    # at v = 0 the laws' slopes are exactly what the tangent takes: sigma_1 + sigma_2 in presliding (dz/dt = v, the
    # fading factor's own slope vanishes at rest), F_s / v_th + b regularised (the Stribeck decay is multiplied by
    # tanh(0) = 0); a central difference of 1e-9 m/s is exact to its round-off
    c, _ = _constants()
    deflection = 0.3 * c[K.SEAL_ELASTIC_DEFLECTION, 0] if level == ELASTO_PLASTIC else 0.0
    step = 1e-9
    slope = (_friction(c, step, deflection, level) - _friction(c, -step, deflection, level)) / (2.0 * step)
    assert seal.tangent_at(_state(0.0, deflection), c, 0, level, 0.0) == pytest.approx(slope, rel=1e-6)
    damping = 55.0  # the piston's own damping comes first in the sum
    assert seal.tangent_at(_state(0.0, deflection), c, 0, level, damping) == pytest.approx(damping + slope, rel=1e-6)


def test_the_stored_energy_is_the_integral_of_the_elastic_force():
    c, _ = _constants()
    deflections = np.linspace(0.0, c[K.SEAL_ELASTIC_DEFLECTION, 0], 101)
    # at rest the elasto-plastic force is the bristles' elastic sigma_0 z alone (no rate, no viscous term)
    forces = np.array([_friction(c, 0.0, z, ELASTO_PLASTIC) for z in deflections])
    assert forces == pytest.approx(c[K.SEAL_STIFFNESS, 0] * deflections, rel=1e-15, abs=0.0)
    work = float(np.sum(0.5 * (forces[1:] + forces[:-1]) * np.diff(deflections)))  # exact for a linear force
    kinetic, elastic = seal.energy(_state(0.2, deflections[-1])[:, 0], c[:, 0])
    assert kinetic == 0.0 and elastic == pytest.approx(work, rel=1e-12)


def test_each_level_writes_only_the_derivative_it_integrates():
    c, _ = _constants()
    speed, deflection = 1e-4, 0.2 * c[K.SEAL_ELASTIC_DEFLECTION, 0]
    dxdt = np.zeros((N_STATES, 1))
    seal.friction_at(_state(speed, deflection), c, dxdt, 0, ELASTO_PLASTIC)
    assert dxdt[S.SEAL_DEFLECTION, 0] == speed  # purely elastic below z_ba: the seals follow the piston
    assert np.count_nonzero(dxdt) == 1
    dxdt[:] = 0.0
    seal.friction_at(_state(speed, deflection), c, dxdt, 0, REGULARISED)
    assert not dxdt.any()
    assert SUBSYSTEMS["seal_friction"].level("regularised").removes_states == (S.SEAL_DEFLECTION,)


def test_the_table_registers_the_seal_with_its_level_and_its_tolerance():
    assert seal in COMPONENTS and seal.LEVELS == ("seal_friction",) and set(seal.LEVELS) <= set(SUBSYSTEMS)
    assert seal.SEAL_FRICTION == list(SUBSYSTEMS).index("seal_friction") and seal.ELASTO_PLASTIC == ELASTO_PLASTIC
    tolerance = absolute_tolerance(1.0)
    for state, value in seal.ABSOLUTE_TOLERANCES.items():
        assert tolerance[state] == value
