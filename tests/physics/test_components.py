"""Closed forms and limits of the small component laws: support friction (Eqs. 7.63-7.64), the motor circuit and
winding thermal model (Eqs. 9.1-9.2), the one-directional preload spring (Sec. 9.3) and the torsional
elasto-backlash joint (Eq. 5.9 form)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from twin.physics.coupling import elasto_backlash, elasto_backlash_energy
from twin.physics.friction import stribeck_friction
from twin.physics.motor import (
    STEFAN_BOLTZMANN,
    T_RESISTANCE_REFERENCE,
    current_derivative,
    winding_resistance,
    winding_temperature_derivative,
)
from twin.physics.preload import preload_force, series_stiffness

# friction: breakaway 3 N, Coulomb 2 N, Stribeck rate 50 s/m, viscous 10 N s/m, regularisation 1e-4 m/s
STATIC, DYNAMIC, RATE, VISCOUS, V_TH = 3.0, 2.0, 50.0, 10.0, 1e-4


def friction(v):
    return stribeck_friction(v, STATIC, DYNAMIC, RATE, VISCOUS, V_TH)


def test_friction_limits():
    assert friction(0.0) == 0.0
    # just past the regularisation (tanh(20) = 1 to 1e-17) and before the Stribeck decay: the breakaway level
    v = 20 * V_TH
    assert friction(v) == pytest.approx(DYNAMIC + (STATIC - DYNAMIC) * math.exp(-RATE * v) + VISCOUS * v, rel=1e-12)
    assert friction(v) == pytest.approx(STATIC, rel=0.11)
    # far along the Stribeck curve: Coulomb plus viscous
    assert friction(2.0) == pytest.approx(DYNAMIC + VISCOUS * 2.0, rel=1e-12)
    # inside the regularisation: linear through zero with slope F_s / v_th
    assert friction(1e-3 * V_TH) == pytest.approx((STATIC / V_TH + VISCOUS) * 1e-3 * V_TH, rel=1e-5)


@pytest.mark.parametrize("v", [1e-6, 3e-4, 0.01, 0.2, 5.0])
def test_friction_is_odd_and_opposes_motion(v):
    assert friction(-v) == -friction(v)
    assert friction(v) > 0.0


def test_friction_stribeck_dip_between_breakaway_and_viscous_rise():
    v = np.linspace(20 * V_TH, 1.0, 2001)
    f = np.array([friction(x) for x in v])
    # d/dv = -a (F_s - F_d) e^{-a v} + b: minimum where e^{-a v} = b / (a (F_s - F_d))
    v_min = math.log(RATE * (STATIC - DYNAMIC) / VISCOUS) / RATE
    assert v[np.argmin(f)] == pytest.approx(v_min, abs=1e-3)


def test_winding_resistance_is_linear_through_the_datasheet_point():
    """R(T) = R_20 (1 + alpha (T - 20 degC)), the datasheet resistance at 20 degC (Table B.1)."""
    assert T_RESISTANCE_REFERENCE == 293.15
    assert winding_resistance(293.15, 5.2, 0.0039) == 5.2
    assert winding_resistance(393.15, 5.2, 0.0039) == pytest.approx(5.2 * 1.39, rel=1e-12)
    assert winding_resistance(273.15, 5.2, 0.0039) == pytest.approx(5.2 * (1 - 0.078), rel=1e-12)


def test_current_derivative_equilibrium_and_time_constant():
    """Eq. 9.1: zero at i = (V - k_e tau omega) / R; the deviation decays at R / H."""
    voltage, speed, r, h, k_e, ratio = 24.0, 30.0, 5.2, 1.1e-3, 0.05, 0.1
    steady = (voltage - k_e * ratio * speed) / r
    assert current_derivative(voltage, steady, speed, r, h, k_e, ratio) == pytest.approx(0.0, abs=1e-12)
    assert current_derivative(voltage, steady + 0.5, speed, r, h, k_e, ratio) == pytest.approx(-0.5 * r / h, rel=1e-12)
    # back-EMF acts through the reduction ratio: the output speed raises the EMF by k_e tau per rad/s
    delta = (current_derivative(voltage, 0.0, speed + 1.0, r, h, k_e, ratio)
             - current_derivative(voltage, 0.0, speed, r, h, k_e, ratio))
    assert delta == pytest.approx(-k_e * ratio / h, rel=1e-9)


THERMAL = dict(thermal_resistance=2.5, time_constant=120.0, area=0.05)


def _integrate_temperature(power, h, emissivity, duration, ambient=298.15):
    def rhs(t, y):
        return [winding_temperature_derivative(y[0], ambient, power, THERMAL["thermal_resistance"],
                                               THERMAL["time_constant"], h, THERMAL["area"], emissivity)]
    return solve_ivp(rhs, (0.0, duration), [ambient], rtol=1e-10, atol=1e-10, dense_output=True)


def test_thermal_first_order_closed_form():
    """Eq. 9.2 with R_th = 1 / (h A) (the bench's choice: R_th is the inverse of the total heat conductance) is the
    first-order law dT = P R_th (1 - exp(-t / tau_w))."""
    h = 1.0 / (THERMAL["thermal_resistance"] * THERMAL["area"])
    sol = _integrate_temperature(10.0, h, 0.0, 600.0)
    t = np.array([30.0, 120.0, 600.0])
    expected = 10.0 * 2.5 * (1.0 - np.exp(-t / 120.0))
    np.testing.assert_allclose(sol.sol(t)[0] - 298.15, expected, rtol=1e-6)


def test_thermal_rise_and_time_constant_follow_the_conductance():
    """In general dT_inf = P / (h A) and tau_eff = tau_w / (R_th h A); without losses the rise is a ramp P R_th t /
    tau_w."""
    h = 20.0
    g = THERMAL["thermal_resistance"] * h * THERMAL["area"]
    sol = _integrate_temperature(10.0, h, 0.0, 600.0)
    t = np.array([60.0, 600.0])
    expected = 10.0 / (h * THERMAL["area"]) * (1.0 - np.exp(-t * g / 120.0))
    np.testing.assert_allclose(sol.sol(t)[0] - 298.15, expected, rtol=1e-6)
    ramp = _integrate_temperature(10.0, 0.0, 0.0, 60.0)
    assert ramp.sol(60.0)[0] - 298.15 == pytest.approx(10.0 * 2.5 * 60.0 / 120.0, rel=1e-8)


def test_thermal_radiation_term():
    ambient, hot = 298.15, 350.0
    rate = winding_temperature_derivative(hot, ambient, 0.0, 2.5, 120.0, 0.0, 0.05, 0.9)
    assert rate == pytest.approx(-2.5 * 0.9 * STEFAN_BOLTZMANN * 0.05 * (hot**4 - ambient**4) / 120.0, rel=1e-12)
    assert winding_temperature_derivative(ambient, ambient, 0.0, 2.5, 120.0, 20.0, 0.05, 0.9) == 0.0


K_PRELOAD, C_PRELOAD = 2.0e7, 1.0e4


def test_series_stiffness():
    assert series_stiffness(2.0e7, 2.0e7) == pytest.approx(1.0e7, rel=1e-15)
    assert series_stiffness(1.0e7, 4.0e7) == pytest.approx(8.0e6, rel=1e-15)


@pytest.mark.parametrize("orientation", [1.0, -1.0])
def test_preload_force_is_a_spring_that_only_pushes(orientation):
    """F = k (c0 - o s) while compressed, zero once the spring set is free (O: o = +1, X: o = -1)."""
    c0 = 5e-5  # 1000 N at 2e7 N/m
    assert preload_force(0.0, 0.0, c0, K_PRELOAD, C_PRELOAD, orientation) == pytest.approx(1000.0, rel=1e-12)
    s = orientation * 1e-5  # nuts moving the way that relaxes the spring
    assert preload_force(s, 0.0, c0, K_PRELOAD, C_PRELOAD, orientation) == pytest.approx(800.0, rel=1e-12)
    assert preload_force(-s, 0.0, c0, K_PRELOAD, C_PRELOAD, orientation) == pytest.approx(1200.0, rel=1e-12)
    assert preload_force(orientation * 6e-5, 0.0, c0, K_PRELOAD, C_PRELOAD, orientation) == 0.0
    # damping adds c * compression rate, saturated to the elastic force: never a pull, never more than 2x
    compressing = -orientation * 0.01
    assert preload_force(0.0, compressing, c0, K_PRELOAD, C_PRELOAD, orientation) == pytest.approx(1100.0, rel=1e-12)
    assert preload_force(0.0, -compressing * 1e3, c0, K_PRELOAD, C_PRELOAD, orientation) == 0.0
    assert preload_force(0.0, compressing * 1e3, c0, K_PRELOAD, C_PRELOAD, orientation) == pytest.approx(2000.0)


K_JOINT, C_JOINT, PLAY = 1.0e4, 2.0, 2e-3


def test_elasto_backlash_gap_and_springs():
    assert elasto_backlash(0.0, 5.0, K_JOINT, C_JOINT, PLAY) == 0.0
    assert elasto_backlash(0.999e-3, 5.0, K_JOINT, C_JOINT, PLAY) == 0.0
    assert elasto_backlash(-0.999e-3, -5.0, K_JOINT, C_JOINT, PLAY) == 0.0
    assert elasto_backlash(1.5e-3, 0.0, K_JOINT, C_JOINT, PLAY) == pytest.approx(5.0, rel=1e-12)
    assert elasto_backlash(-1.5e-3, 0.0, K_JOINT, C_JOINT, PLAY) == pytest.approx(-5.0, rel=1e-12)
    assert elasto_backlash(1.5e-3, 0.0, K_JOINT, C_JOINT, 0.0) == pytest.approx(15.0, rel=1e-12)


def test_elasto_backlash_damping_is_saturated():
    assert elasto_backlash(1.5e-3, 1.0, K_JOINT, C_JOINT, PLAY) == pytest.approx(7.0, rel=1e-12)
    assert elasto_backlash(1.5e-3, -1.0, K_JOINT, C_JOINT, PLAY) == pytest.approx(3.0, rel=1e-12)
    assert elasto_backlash(1.5e-3, -100.0, K_JOINT, C_JOINT, PLAY) == 0.0  # separating fast: no pull
    assert elasto_backlash(1.5e-3, 100.0, K_JOINT, C_JOINT, PLAY) == pytest.approx(10.0, rel=1e-12)
    assert elasto_backlash(-1.5e-3, -1.0, K_JOINT, C_JOINT, PLAY) == pytest.approx(-7.0, rel=1e-12)
    assert elasto_backlash(-1.5e-3, 100.0, K_JOINT, C_JOINT, PLAY) == 0.0


@pytest.mark.parametrize("deflection", [-3e-3, -1.2e-3, -0.5e-3, 0.0, 0.7e-3, 1.01e-3, 2.5e-3])
def test_elasto_backlash_energy_is_the_potential_of_the_force(deflection):
    h = 1e-7
    gradient = (elasto_backlash_energy(deflection + h, K_JOINT, PLAY)
                - elasto_backlash_energy(deflection - h, K_JOINT, PLAY)) / (2 * h)
    assert gradient == pytest.approx(elasto_backlash(deflection, 0.0, K_JOINT, C_JOINT, PLAY), rel=1e-6, abs=1e-9)
