"""Static equilibria of the closed-loop bench: holding a force, preload balance and redistribution."""

import math

import numpy as np
import pytest
from bench_helpers import plant_fidelity

import twin
from twin.engine.codes import CONTACT
from twin.engine.model import build_model, contact_position_for_force
from twin.fidelity import resolve_fidelity
from twin.layout import K
from twin.physics.ball_groove_friction import rolling_coefficient
from twin.physics.ball_screw import helix_angle

SETTLE = 0.3  # s averaged at the end of each run, after the transients (loop bandwidths >= 6 Hz)


def _final(ds, name):
    """Mean of a signal over the last SETTLE seconds (removes the position loop's limit cycle)."""
    return float(ds[name].where(ds.time >= ds.time[-1] - SETTLE, drop=True).mean())


@pytest.mark.parametrize("force", [2000.0, -3000.0])
def test_static_hold_screw_torque_and_motor_current(bench, scene_factory, force):
    """Holding a constant external force at rest: T = F p / (2 pi) and i = T / (tau eta k_t), within friction."""
    scene = scene_factory(1.5, force=[{"kind": "hold", "end": 0.1}, {"kind": "smooth_step", "end": 0.3, "to": force}])
    ds = twin.simulate(scene, bench, fidelity=plant_fidelity(scene))
    p = bench.values()
    arm = p["ball_screw.lead"] / (2 * math.pi)
    # The screw resists the force: with +theta_s advancing the nut along +x the torque is -F p/2pi.
    expected_torque = -force * arm
    torque = _final(ds, "transmitted_torque")
    assert abs(torque - expected_torque) <= p["ball_screw.bearing_friction_static_torque"] + 1e-3 * abs(expected_torque)
    # Motor current: the reducer output torque reflected through ratio and efficiency (Eq. 9.3).
    ratio, eta, kt = p["reducer.ratio"], p["reducer.efficiency"], p["motor.torque_constant"]
    expected_current = expected_torque / (ratio * eta * kt)
    current_tolerance = ((p["motor.friction_static_torque"] + p["ball_screw.bearing_friction_static_torque"])
                         / (ratio * eta * kt))
    assert abs(_final(ds, "motor_current") - expected_current) <= current_tolerance
    # and it is at rest
    assert abs(_final(ds, "nut1_speed")) < 1e-5


@pytest.mark.parametrize("configuration, sign", [("O", 1.0), ("X", -1.0)])
def test_preload_balanced_by_both_nuts(bench, scene_factory, configuration, sign):
    """1000 N preload, no external force: each nut's contact carries the preload, in opposite directions."""
    scene = scene_factory(0.5, preload=1000.0, configuration=configuration)
    ds = twin.simulate(scene, bench, fidelity=plant_fidelity(scene))
    assert _final(ds, "preload_force") == pytest.approx(1000.0, rel=1e-3)
    assert _final(ds, "nut1_contact_force") == pytest.approx(sign * 1000.0, rel=1e-3)
    assert _final(ds, "nut2_contact_force") == pytest.approx(-sign * 1000.0, rel=1e-3)


def _groove_friction_axial_bound(bench, force):
    """Largest axial share of one nut's ball-groove friction at the axial load ``force`` [N]: the helix force
    2 Z P (g_1 + g_4 + f_v) (Stribeck peak, Eq. 5.16; rolling at rest, Eq. 5.20) times sin(alpha_e), with
    P = |force| / (Z sin(alpha_0) cos(alpha_e)); Z cancels."""
    p = bench.values()
    alpha_e = helix_angle(p["ball_screw.lead"], p["ball_screw.pitch_radius"])
    per_ball = abs(force) / (math.floor(0.65 * p["ball_screw.total_balls"]) * math.sin(p["ball_screw.contact_angle"])
                             * math.cos(alpha_e))
    rolling = rolling_coefficient(per_ball, 0.0, p["ball_screw.rolling_friction_load_coefficient"],
                                  p["ball_screw.rolling_friction_multiplier"], 0.0, p["ball_screw.ball_radius"])
    peak = p["ball_screw.sliding_friction_g1"] + p["ball_screw.sliding_friction_g4"] + rolling
    return 2.0 * abs(force) * peak * math.tan(alpha_e) / math.sin(p["ball_screw.contact_angle"])


@pytest.mark.parametrize("external", [500.0, -500.0, 3000.0, -3000.0])
def test_external_force_redistributes_preload(bench, scene_factory, external):
    """Eq. 9.8 at rest: the master nut carries s F_pr - F_ext, the slave nut -s F_pr.

    The two regimes of Fig. 5.13: with F_pr > F_ext/2 (|F_ext| = 500 N) the master
    nut keeps its contact side; with F_pr < F_ext/2 (3000 N) the load exceeds the
    preload on one side and that nut's contact changes side. Because the bench applies
    the force to the master nut only and the preload comes from a soft disc-spring set
    (not the equal split of the Ch. 5 model), the side change happens on the master
    nut when F_ext opposes the preload on it, and the slave keeps the preload.
    """
    preload = 1000.0
    scene = scene_factory(1.2,
                          force=[{"kind": "hold", "end": 0.1}, {"kind": "smooth_step", "end": 0.3, "to": external}],
                          preload=preload)
    ds = twin.simulate(scene, bench, fidelity=plant_fidelity(scene))
    f_pr = _final(ds, "preload_force")
    f1, f2 = _final(ds, "nut1_contact_force"), _final(ds, "nut2_contact_force")
    assert f_pr == pytest.approx(preload, rel=0.05)  # soft spring: the preload barely changes
    # 1 N, plus the axial share of the ball-groove friction the position loop's dither leaves on each nut
    assert f1 == pytest.approx(f_pr - external, abs=1.0 + _groove_friction_axial_bound(bench, f_pr - external))
    assert f2 == pytest.approx(-f_pr, abs=1.0 + _groove_friction_axial_bound(bench, f_pr))
    master_keeps_side = np.sign(f1) == 1.0
    assert master_keeps_side == (external < preload)


def test_backlash_hysteresis_width_and_nut_dwell(bench, scene_factory):
    """No preload, no force, slow sinusoid: the nut-versus-screw loop is as wide as the axial backlash
    plus elastic deformation, and the nut stands still while the gap is open (Figs. 5.11, 5.12)."""
    backlash = 20e-6
    scene = scene_factory(4.5, position=[{"kind": "hold", "end": 0.25},
                                         {"kind": "sinusoid", "end": 4.25, "amplitude": 1e-3, "frequency": 0.5,
                                          "phase": 0.0}],
                          backlash=backlash)
    ds = twin.simulate(scene, bench, fidelity=plant_fidelity(scene), output_dt=1.25e-4)
    # the contacts' relative position: the screw's axial displacement and its twist at the nut (docs/model.md), at
    # the lead of the room temperature (screw_equivalent_position takes the nominal lead, as Eq. 9.12 does)
    model = build_model(scene, bench, resolve_fidelity(scene, bench, plant_fidelity(scene)))
    arm = model.constants[K.LEAD_ARM]
    nominal = bench.value("ball_screw.lead") / (2 * math.pi)
    screw_at_nut = ds.screw_equivalent_position * (arm / nominal) + ds.screw_axial_position - arm * ds.screw_twist
    relative = (ds.nut1_position - screw_at_nut).sel(time=slice(1.0, None))
    width = float(relative.max() - relative.min())
    # Elastic part: the Hertz deflection (soft at low load) under the largest contact force on each
    # side of the loop, which arises when the screw re-engages the dwelling nut. The damping share of
    # that force makes the deflection slightly smaller, never larger.
    force = ds.nut1_contact_force.sel(time=slice(1.0, None))
    elastic = sum(abs(contact_position_for_force(model.constants, int(model.levels[CONTACT]), f)) - backlash / 2
                  for f in (float(force.max()), float(force.min())))
    assert backlash < width <= backlash + elastic
    assert elastic < 0.1 * backlash
    late = ds.sel(time=slice(1.0, None))
    gap_open = late.nut1_contact_force == 0.0
    assert int(gap_open.sum()) > 50, "the gap must open at each reversal"
    nut_speed_in_gap = np.abs(late.nut1_speed.where(gap_open, drop=True))
    peak_speed = float(np.abs(late.nut1_speed).max())
    # the guides' friction stops the nut within ~1 ms of the gap opening: median speed tiny against the stroke speed
    assert float(nut_speed_in_gap.median()) < 0.02 * peak_speed
