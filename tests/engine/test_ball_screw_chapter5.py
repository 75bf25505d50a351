"""The reduced Ch. 5 ball screw in the plant: energy balance with the friction dissipation, and the loading
regimes of Fig. 5.13 at their closed-form transition load."""

import numpy as np
import pytest
from bench_helpers import plant_fidelity
from lane_helpers import OneLane
from scipy.optimize import brentq, root
from test_energy_convergence import BALL_GROOVE_FRICTION_OFF, LOSSLESS

from twin.engine.codes import BALL_GROOVE_FRICTION, BALL_GROOVE_FRICTION_CHAPTER5, CONTACT
from twin.engine.energy import mechanical_energy
from twin.engine.integrators import INTEGRATORS
from twin.engine.model import build_model, contact_position_for_force
from twin.engine.plant import W
from twin.features import MOTION_SPEED_THRESHOLD, N_ACCUMULATORS, accumulate, finish
from twin.fidelity import full_plant, resolve_fidelity
from twin.layout import NUT_STATE_STRIDE, K, S
from twin.physics.ball_groove_friction import tangential_speed

DURATION = 0.02  # s: several periods of the chain's modes, many velocity reversals of the nuts
DT = 2.0e-6


def _friction_power(lane, x):
    """Power dissipated by the ball-groove friction of both nuts, sum of F_t v_t [W]: the helix friction force of
    each nut (work rows ``W.NUT_FRICTION``) times its groove speed along the helix."""
    w, c = lane.forces(0.0, x), lane.model.constants
    power = 0.0
    for nut in range(2):
        position = S.NUT1_POSITION + NUT_STATE_STRIDE * nut
        speed = tangential_speed(x[S.SCREW_SPEED], x[position + 3], x[S.SCREW_AXIAL_SPEED], x[position + 1],
                                 c[K.PITCH_RADIUS], c[K.COS_HELIX], c[K.SIN_HELIX])
        power += w[W.NUT_FRICTION + nut] * speed
    return power


def test_energy_balance_closes_with_ball_groove_friction(bench, scene_factory):
    """Every other loss off, a preloaded chain kicked into motion: the mechanical energy lost equals the
    integral of the friction power F_t v_t of both nuts (trapezoid at every 2 us step), to 1e-4 of it."""
    params = bench.with_values({k: v for k, v in LOSSLESS.items() if k not in BALL_GROOVE_FRICTION_OFF})
    scene = scene_factory(DURATION, preload=1000.0)
    model = build_model(scene, params, resolve_fidelity(scene, params, plant_fidelity(scene)))
    # the full plant has both
    assert model.levels[BALL_GROOVE_FRICTION] == BALL_GROOVE_FRICTION_CHAPTER5
    assert model.constants[K.SHAFT_TWIST_COMPLIANCE] > 0.0
    x = model.initial_state.copy()
    x[S.SCREW_SPEED] = 20.0
    x[S.NUT1_SPEED] = 2e-3
    x[S.NUT2_SPEED] = -1e-3
    x[S.REDUCER_SPEED] = -1.0
    energy_0 = mechanical_energy(x, model)
    lane = OneLane(model)
    dissipated, power = 0.0, _friction_power(lane, x)
    for k in range(int(round(DURATION / DT))):
        lane.step(INTEGRATORS["rk4"], k * DT, x, DT)
        new_power = _friction_power(lane, x)
        dissipated += 0.5 * DT * (power + new_power)
        power = new_power
    lost = energy_0 - mechanical_energy(x, model)
    assert dissipated > 0.02 * energy_0  # the friction does dissipate a share (3 % in 20 ms)
    assert lost == pytest.approx(dissipated, rel=1e-4)


def _static_contact_forces(bench, scene_factory, force, preload=1000.0):
    """Nut contact forces at the static equilibrium of the plant (screw angle held at 0, ideal external force
    ``force`` on the master nut, no backlash): the root of the axial force balances of the rhs."""
    scene = scene_factory(1.0, force=[{"kind": "smooth_step", "end": 0.01, "to": force}], preload=preload)
    fidelity = resolve_fidelity(scene, bench, full_plant("ideal", nut_rotation="off"))
    model = build_model(scene, bench, fidelity)
    c, lane = model.constants, OneLane(model)
    unknowns = (S.SCREW_AXIAL, S.NUT1_POSITION, S.NUT2_POSITION)
    accelerations = (S.SCREW_AXIAL_SPEED, S.NUT1_SPEED, S.NUT2_SPEED)

    def balance(values):
        x = model.initial_state.copy()
        x[list(unknowns)] = values * 1e-6
        dxdt = lane.rhs(0.5, x)
        return dxdt[list(accelerations)] * np.array([c[K.SCREW_MASS], c[K.NUT1_MASS], c[K.NUT2_MASS]])

    result = root(balance, model.initial_state[list(unknowns)] * 1e6, method="hybr", options={"xtol": 1e-11})
    solution = result.x
    assert np.max(np.abs(balance(solution))) < 1e-6 * preload, result.message
    x = model.initial_state.copy()
    x[list(unknowns)] = solution * 1e-6
    w = lane.forces(0.5, x)
    return w[W.NUT_FORCE], w[W.NUT_FORCE + 1], w[W.PRELOAD], model


def test_fig_5_13_regimes_and_closed_form_transition_load(bench, scene_factory):
    """O preload 1 kN, force on the master nut (Eq. 9.8). Regimes of Fig. 5.13: f) no force, both nuts carry the
    preload in opposite directions; c) a force opposing the preload on the master lightens it (SL), the slave
    keeps the spring force; d) at the transition the master carries nothing (NL); e) beyond it the master's
    contact changes side; a force along the preload loads the master more (HL). Closed form of the transition:
    the master leaves its flank when F equals the spring force, and the spring, now compressed by the master's
    released deflection, pushes with F_t = k_pr (C_0 - delta(F_t)), delta the slave's contact deflection at
    F_t (contact_position_for_force). The disc springs are soft, so F_t is the preload plus k_pr delta(F_pr),
    not the 2 F_pr of the Ch. 5 model (external force split equally, constant preload) nor the 2^1.5 F_pr of a
    rigid spacer."""
    f1, f2, spring, model = _static_contact_forces(bench, scene_factory, 0.0)
    assert f1 == pytest.approx(1000.0, rel=1e-6) and f2 == pytest.approx(-1000.0, rel=1e-6)  # f)
    c, contact_model = model.constants, int(model.levels[CONTACT])

    def closed_form(f):
        return f - c[K.PRELOAD_STIFFNESS] * (c[K.PRELOAD_COMPRESSION]
                                             - contact_position_for_force(c, contact_model, f))

    transition = brentq(closed_form, 500.0, 3000.0, xtol=1e-9)
    assert 1000.0 < transition < 1100.0
    f1, f2, spring, _ = _static_contact_forces(bench, scene_factory, 0.5 * transition)  # c)
    assert 0.0 < f1 < 1000.0 and f2 == pytest.approx(-spring, rel=1e-9)
    f1, _, _, _ = _static_contact_forces(bench, scene_factory, -0.5 * transition)  # the other side of c): HL
    assert f1 > 1000.0
    f1, f2, _, _ = _static_contact_forces(bench, scene_factory, 2.0 * transition)  # e)
    assert f1 < 0.0 and f2 < 0.0
    # d): the master's contact force crosses zero at the closed-form load
    crossing = brentq(lambda f: _static_contact_forces(bench, scene_factory, f)[0], 0.9 * transition,
                      1.1 * transition, xtol=1e-6)
    # 1e-4: the shaft-stiffness gradient force on the sled (k^2 x_s^2 / 2 (1/EA + twist), 0.02 N at 1 kN) is not
    # in the closed form
    assert crossing == pytest.approx(transition, rel=1e-4)


def test_drag_torque_feature_known_answer():
    """drag_torque_feature on a synthetic record: a sinusoidal screw motion with plateaus of constant speed, the
    torque = friction 0.15 N m opposing the motion + an inertial term + a load torque 0.4 N m + an offset
    0.02 N m: the half hysteresis width at constant speed returns the friction alone."""
    dt = 1e-3
    t = np.arange(0.0, 8.0, dt)
    speed = 0.02 * np.clip(1.5 * np.sin(2 * np.pi * t / 4.0), -1.0, 1.0)  # m/s, flat tops of constant speed
    screw = np.cumsum(speed) * dt
    acceleration = np.gradient(speed, dt)
    torque = 0.15 * np.sign(speed) + 5.0 * acceleration + 0.4 + 0.02
    acc = np.zeros(N_ACCUMULATORS)
    for k in range(t.size):
        accumulate(acc, 0.0, screw[k], torque[k], k == 0, MOTION_SPEED_THRESHOLD * dt)
    assert finish(acc, t.size)["drag_torque_feature"] == pytest.approx(0.15, rel=1e-9)
    # never at constant speed both ways: NaN
    acc = np.zeros(N_ACCUMULATORS)
    for k in range(2000):
        accumulate(acc, 0.0, screw[k], torque[k], k == 0, MOTION_SPEED_THRESHOLD * dt)
    assert np.isnan(finish(acc, 2000)["drag_torque_feature"])
