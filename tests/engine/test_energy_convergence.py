"""Integrator checks on the mechanical chain: energy balance without losses, and convergence order."""

import numpy as np
import pytest
from bench_helpers import plant_fidelity
from lane_helpers import OneLane
from scipy.stats import linregress

from twin.engine.energy import mechanical_energy
from twin.engine.integrators import INTEGRATORS, ORDER
from twin.engine.model import build_model
from twin.fidelity import resolve_fidelity
from twin.layout import S

#: The ball-groove friction of the reduced Ch. 5 model (twin.physics.ball_groove_friction), off.
BALL_GROOVE_FRICTION_OFF = {
    "ball_screw.sliding_friction_g1": 0.0, "ball_screw.sliding_friction_g4": 0.0, "ball_screw.sliding_friction_g6": 0.0,
    "ball_screw.rolling_friction_load_coefficient": 0.0, "ball_screw.rolling_friction_speed_coefficient": 0.0,
}
#: Every mechanical loss off (also the motor's energy balance, test_motor_energy_balance.py).
MECHANICAL_LOSSES_OFF = {
    **BALL_GROOVE_FRICTION_OFF,
    "motor.viscous_damping": 0.0, "motor.friction_static_torque": 0.0, "motor.friction_dynamic_torque": 0.0,
    "reducer.efficiency": 1.0, "drivetrain.damping": 0.0, "ball_screw.contact_damping_coefficient": 0.0,
    "ball_screw.screw_axial_damping": 0.0, "ball_screw.screw_rotational_damping": 0.0,
    "ball_screw.bearing_friction_static_torque": 0.0, "ball_screw.bearing_friction_dynamic_torque": 0.0,
    "ball_screw.bearing_viscous_friction": 0.0, "sled.guide_roll_damping": 0.0,
    "sled.guide_friction_static": 0.0, "sled.guide_friction_dynamic": 0.0, "sled.guide_viscous_friction": 0.0,
    "preload.damping": 0.0,
}
LOSSLESS = {
    **MECHANICAL_LOSSES_OFF,
    # decouple the electrical circuit: no torque from current, no back-EMF into it
    "motor.torque_constant": 1e-300, "motor.speed_constant": 1e-300,
    # a smooth chain: the reducer's play would make the torsional force only C0
    "reducer.backlash": 0.0,
}
DURATION = 0.02  # s: several periods of the slowest mechanical mode (~350 Hz torsion)


def _free_motion(bench, scene_factory, method, dt, energy_history=None):
    """Integrate the plant alone from a preloaded equilibrium kicked by initial velocities; append the energy
    after every 8th step to ``energy_history`` if given."""
    params = bench.with_values(LOSSLESS)
    scene = scene_factory(DURATION, preload=1000.0)
    model = build_model(scene, params, resolve_fidelity(scene, params, plant_fidelity(scene)))
    x = model.initial_state.copy()
    x[S.SCREW_SPEED] = 2.0
    x[S.NUT1_SPEED] = 2e-3
    x[S.NUT2_SPEED] = -1e-3
    x[S.REDUCER_SPEED] = -1.0
    energy_0 = mechanical_energy(x, model)
    lane = OneLane(model)  # held inputs zero: no current demand; the load system is absent
    code = INTEGRATORS[method]
    for k in range(int(round(DURATION / dt))):
        lane.step(code, k * dt, x, dt, refresh=k % 4 == 0)
        if energy_history is not None and k % 8 == 7:
            energy_history.append(mechanical_energy(x, model))
    return x, energy_0, mechanical_energy(x, model)


def test_energy_balance_closes_without_losses(bench, scene_factory):
    """RK4 at 5 us: the energy drifts by far less than its own truncation bound would allow at 4x the step."""
    _, e0, e1 = _free_motion(bench, scene_factory, "rk4", 5e-6)
    _, _, e1_coarse = _free_motion(bench, scene_factory, "rk4", 2e-5)
    assert abs(e1 - e0) / e0 < 1e-8
    # The drift is the integrator's: it shrinks with the step (RK4 energy error ~ h^4).
    assert abs(e1 - e0) < abs(e1_coarse - e0) / 20


@pytest.mark.parametrize("method", sorted(INTEGRATORS))
def test_convergence_order_on_smooth_chain(bench, scene_factory, method):
    """Fitted slope of log(error) vs log(step) matches the method's order (no contact transitions)."""
    # Steps in each method's asymptotic range. Near its stability limit (4e-5 s) RK4 is not yet at
    # order 4; the L-stable W-method has a large phase error on the undamped 2.4e4 rad/s screw-axial
    # mode (its error is not monotone in h) until h * omega < 0.03, i.e. h < ~1.2e-6 s.
    steps = {"rk4": np.array([1e-5, 5e-6, 2.5e-6]), "rosenbrock_w2": np.array([1.25e-6, 6.25e-7, 3.125e-7]),
             "semi_implicit_euler": np.array([4e-6, 2e-6, 1e-6, 5e-7]),
             "imex_euler": np.array([4e-6, 2e-6, 1e-6, 5e-7])}[method]
    reference, _, _ = _free_motion(bench, scene_factory, "rk4", 1.5625e-7)
    scale = np.abs(reference) + 1e-3 * np.max(np.abs(reference))
    errors = [np.max(np.abs(_free_motion(bench, scene_factory, method, h)[0] - reference) / scale) for h in steps]
    slope = linregress(np.log(steps), np.log(errors)).slope
    assert slope == pytest.approx(ORDER[method], abs=0.25)


def test_symplectic_euler_bounded_energy_error(bench, scene_factory):
    """Semi-implicit Euler is first order but symplectic: its energy error stays bounded and is O(h), so the
    largest error over the run halves with the step (ratio 2 within 10 %; measured 1.9998) and stays small."""
    worst = {}
    for dt in (4e-6, 2e-6):
        history = []
        _, e0, _ = _free_motion(bench, scene_factory, "semi_implicit_euler", dt, history)
        worst[dt] = np.max(np.abs(np.array(history) - e0)) / e0
    assert worst[4e-6] / worst[2e-6] == pytest.approx(2.0, rel=0.1)
    assert worst[2e-6] < 1e-2
