"""Known answers of the bristle friction laws (twin.physics.bristle_friction; issue 41, item 3).

A body of mass m on the friction law, integrated with the fixed-step RK4 of app.studies.friction_laws (compiled,
so that stick-slip cycles of a few seconds cost milliseconds): dragged through a spring at constant speed
(stick-slip against the closed form for Coulomb static/kinetic friction), pushed by a slow force ramp (breakaway at
F_s), shaken below breakaway (elastic hold, no drift for the elasto-plastic law; LuGre drifts), moved kinematically
(presliding hysteresis), slid at constant speed (the Stribeck curve), and the dissipation and energy balance.
"""

import math

import numpy as np
import pytest

from app.studies import friction_laws as fl
from twin.parameters import load_parameters
from twin.physics import bristle_friction as bf
from twin.physics import pneumatics as pn
from twin.physics.friction import stribeck_level

LUGRE, ELASTOPLASTIC = fl.LUGRE, fl.ELASTOPLASTIC
LAWS = (LUGRE, ELASTOPLASTIC)

# A test body: 1 kg, Coulomb static 10 N / kinetic 6 N; a Stribeck drop within 1/a = 1 mm/s (the slips reach
# 40 mm/s) so that the law is the static/kinetic Coulomb law of the closed form; stiff bristles (z_ss = 0.1 um
# against the spring's 0.8 mm of travel per stick). The breakaway of a bristle law under a force rising at F' falls
# below F_s by about 2 sqrt(F_s a (F_s - F_d) F' / sigma_0) (the creep speed F' / sigma_0 meets the Stribeck slope
# at zero speed): 0.13 N here, 1.3 %.
MASS, STATIC, KINETIC, RATE = 1.0, 10.0, 6.0, 1.0e3
SIGMA0, SIGMA1, DAMPING_SPEED, SIGMA2 = 1.0e8, 1.0e4, 1.0e-3, 0.0
Z_BA = 0.5 * KINETIC / SIGMA0


TEST_BODY = fl.law_parameters(MASS, STATIC, KINETIC, RATE, SIGMA0, SIGMA1, DAMPING_SPEED, SIGMA2, Z_BA, 0.0)


def _integrate(law, duration, dt, spring, speed, force0, amplitude, frequency, ramp):
    return fl.integrate(law, TEST_BODY, duration, dt, fl.drive(spring, speed, force0, amplitude, frequency, ramp))


# --------------------------------------------------------------------------- #
# Stick-slip of a body dragged through a spring
# --------------------------------------------------------------------------- #
SPRING, DRAG_SPEED = 1.0e4, 1.0e-3


def stick_slip_closed_form(mass, spring, speed, static, kinetic):
    """Period and spring-force extremes of Coulomb stick-slip (static F_s, kinetic F_k): stick from the spring force
    ``2 F_k - F_s`` up to ``F_s`` at the rate ``k V``; slip as a harmonic oscillation about ``F_k / k`` of
    ``u = e - F_k / k`` from ``(u, du/dt) = ((F_s - F_k) / k, V)`` to ``(-(F_s - F_k) / k, V)``: a phase of
    ``pi + 2 atan(k V / (omega (F_s - F_k)))``, ``omega = sqrt(k / m)``."""
    omega = math.sqrt(spring / mass)
    stick = 2.0 * (static - kinetic) / (spring * speed)
    slip = (math.pi + 2.0 * math.atan(spring * speed / (omega * (static - kinetic)))) / omega
    return stick + slip, static, 2.0 * kinetic - static


@pytest.mark.parametrize("law", LAWS)
def test_stick_slip_period_and_amplitude_match_the_coulomb_closed_form(law):
    period, high, low = stick_slip_closed_form(MASS, SPRING, DRAG_SPEED, STATIC, KINETIC)
    t, y = _integrate(law, 5.0, 1.0e-6, SPRING, DRAG_SPEED, 0.0, 0.0, 0.0, 0.0)
    force = SPRING * (DRAG_SPEED * t - y[:, 0])
    # slip onsets: the body's speed rising through twice the drag speed
    fast = y[:, 1] > 2.0 * DRAG_SPEED
    onsets = t[1:][fast[1:] & ~fast[:-1]]
    assert len(onsets) >= 5
    periods = np.diff(onsets[1:])              # the first stick starts from rest, not from 2 F_k - F_s
    settled = t > onsets[1]
    # 2 %: the early breakaway (1.3 %, above) and the Stribeck drop's 1 mm/s are not in the closed form
    assert periods == pytest.approx(period, rel=0.02)
    # the early breakaway takes 1.3 % off the peak and off the slip's energy, hence ~2 % off the swing
    assert force[settled].max() == pytest.approx(high, rel=0.015)
    assert force[settled].max() - force[settled].min() == pytest.approx(high - low, rel=0.025)


@pytest.mark.parametrize("law", LAWS)
def test_energy_balance_closes_and_dissipation_is_never_negative(law):
    t, y = _integrate(law, 2.0, 1.0e-6, SPRING, DRAG_SPEED, 0.0, 0.0, 0.0, 0.0)
    x, v, z, work, dissipated = y.T
    stored = 0.5 * MASS * v ** 2 + 0.5 * SPRING * (DRAG_SPEED * t - x) ** 2 + 0.5 * SIGMA0 * z ** 2
    # RK4 at 1 us integrates the balance to ~1e-9 of the work; 1e-6 leaves room for the slip transients
    assert np.max(np.abs(work - stored - dissipated)) < 1.0e-6 * work[-1]
    assert np.all(np.diff(dissipated) >= -1.0e-12 * work[-1])


# --------------------------------------------------------------------------- #
# Breakaway, holding, presliding hysteresis
# --------------------------------------------------------------------------- #
@pytest.mark.parametrize("law", LAWS)
def test_breakaway_at_the_static_force(law):
    ramp = 5.0  # N/s: quasi-static against the presliding mode (1e3 rad/s)
    t, y = _integrate(law, 3.0, 1.0e-5, 0.0, 0.0, 0.0, 0.0, 0.0, ramp)
    sliding = np.argmax(y[:, 1] > 1.0e-3)      # gross sliding: 1 mm/s, ten times the Stribeck speed
    assert sliding > 0
    # breakaway: where the presliding displacement leaves the elastic range, i.e. the force at gross sliding
    assert ramp * t[sliding] == pytest.approx(STATIC, rel=0.02)


def test_elastoplastic_holds_a_force_below_breakaway_without_drift_and_lugre_drifts():
    """Dupont et al. (2002), Sec. II: an oscillating force below breakaway makes LuGre drift, not the elasto-plastic
    law, which is elastic below z_ba (here 3 N): 0.5 N + 2 N sin(2 pi 20 t) for 1 s."""
    _, ep = _integrate(ELASTOPLASTIC, 1.0, 1.0e-5, 0.0, 0.0, 0.5, 2.0, 20.0, 0.0)
    _, lugre = _integrate(LUGRE, 1.0, 1.0e-5, 0.0, 0.0, 0.5, 2.0, 20.0, 0.0)
    cycle = int(round(1.0 / 20.0 / 1.0e-5))
    ep_drift = ep[-1, 0] - ep[-1 - cycle, 0]
    lugre_drift = lugre[-1, 0] - lugre[-1 - cycle, 0]
    assert abs(ep_drift) < 1.0e-12                 # m per cycle: elastic, the position returns
    assert lugre_drift > 1.0e-9                    # m per cycle: creeps in the direction of the mean force
    assert np.max(np.abs(ep[:, 0])) < 2.5 / SIGMA0 + 1.0e-9   # a spring sigma_0 under at most 2.5 N


def _kinematic_loop(law, amplitude, frequency, cycles, dt):
    return fl.kinematic_loop(law, TEST_BODY, amplitude, frequency, cycles, dt)


def _loop_area(x, f):
    return abs(0.5 * np.sum((f[1:] + f[:-1]) * np.diff(x)))


@pytest.mark.parametrize("law", LAWS)
def test_presliding_hysteresis_loop(law):
    """A slow (0.1 Hz: the damping term is negligible) imposed oscillation of twice the steady deflection: a closed
    hysteresis loop within +/- F_s that dissipates, and the loop repeats from the second cycle on."""
    amplitude = 2.0 * STATIC / SIGMA0
    x, f = _kinematic_loop(law, amplitude, 0.1, 3, 1.0e-4)
    per = len(x) // 3
    second, third = slice(per, 2 * per), slice(2 * per, 3 * per)
    area = _loop_area(x[third], f[third])
    assert 0.1 * 4 * KINETIC * amplitude < area < 4 * STATIC * amplitude
    assert np.max(np.abs(f)) <= STATIC * (1 + 1e-9)
    # the loop repeats: the second and third cycles agree to 0.02 % of F_s (z relaxes onto the loop at the
    # relaxation rate sigma_0 |v| / g, slow at these micrometre-per-second speeds)
    assert np.max(np.abs(f[second] - f[third])) < 1e-3 * STATIC


def test_elastoplastic_is_elastic_below_its_elastic_deflection():
    amplitude = 0.9 * Z_BA
    x, f = _kinematic_loop(ELASTOPLASTIC, amplitude, 0.1, 2, 1.0e-4)
    # F = sigma_0 x plus the bristle damping's sigma_1 dx/dt (0.6 um/s here): no plastic loop
    assert np.max(np.abs(f - SIGMA0 * x)) < SIGMA1 * amplitude * 2 * math.pi * 0.1 * 1.01


# --------------------------------------------------------------------------- #
# Steady sliding, dissipation with the bench's seal parameters, validation
# --------------------------------------------------------------------------- #
SEAL = {k.removeprefix("pneumatics."): v for k, v in load_parameters().values().items() if k.startswith("pneumatics.")}


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("v", [-0.3, -0.07, -0.02, -1e-3, 1e-4, 5e-3, 0.02, 0.07, 0.3])
def test_steady_sliding_follows_the_stribeck_curve_of_eq_7_63(law, v):
    s = SEAL
    level = stribeck_level(v, s["friction_static"], s["friction_dynamic"], s["friction_stribeck_coefficient"])
    z = math.copysign(level / s["friction_presliding_stiffness"], v)   # the steady deflection
    rate = (bf.lugre_deflection_rate(v, z, level, s["friction_presliding_stiffness"]) if law == LUGRE else
            bf.elastoplastic_deflection_rate(v, z, level, s["friction_presliding_stiffness"],
                                             s["friction_elastic_fraction"] * s["friction_dynamic"]
                                             / s["friction_presliding_stiffness"]))
    assert abs(rate) < 1e-12 * abs(v)
    force = bf.bristle_force(v, z, rate, s["friction_presliding_stiffness"], s["friction_bristle_damping"],
                             s["friction_bristle_damping_speed"], s["friction_viscous"])
    assert force == pytest.approx(math.copysign(level, v) + s["friction_viscous"] * v, rel=1e-12)


@pytest.mark.parametrize("law", LAWS)
def test_dissipation_is_never_negative_at_any_state_with_the_seal_parameters(law):
    s = SEAL
    sigma0 = s["friction_presliding_stiffness"]
    z_ba = s["friction_elastic_fraction"] * s["friction_dynamic"] / sigma0
    for v in np.concatenate([-np.logspace(-6, 0, 61), np.logspace(-6, 0, 61)]):
        level = stribeck_level(v, s["friction_static"], s["friction_dynamic"], s["friction_stribeck_coefficient"])
        for z in np.linspace(-3, 3, 121) * s["friction_static"] / sigma0:
            rate = (bf.lugre_deflection_rate(v, z, level, sigma0) if law == LUGRE
                    else bf.elastoplastic_deflection_rate(v, z, level, sigma0, z_ba))
            force = bf.bristle_force(v, z, rate, sigma0, s["friction_bristle_damping"],
                                     s["friction_bristle_damping_speed"], s["friction_viscous"])
            assert force * v - sigma0 * z * rate >= -1e-9 * abs(force * v), (v, z)


def test_bad_bristle_parameters_get_one_line_each_naming_the_field():
    params = {k: v for k, v in load_parameters().values().items() if k.startswith("pneumatics.")}
    bad = dict(params, **{"pneumatics.friction_presliding_stiffness": -1.0,
                          "pneumatics.friction_elastic_fraction": 1.0,
                          "pneumatics.friction_bristle_damping": 1.0e6})
    with pytest.raises(ValueError) as info:
        pn.validate_pneumatics(bad)
    message = str(info.value)
    for field in ("friction_presliding_stiffness", "friction_elastic_fraction", "friction_bristle_damping"):
        assert f"pneumatics.{field}" in message
