"""The lane engine: runs in lock-step lanes give each run's own numbers, and the quasi-static screw-axial level.

Bit identity (issue 32, decision 4): a run's features and status do not depend on which runs share its group, on
the lane count or on the order of the batch (twin.engine.group, twin.simulation.simulate_batch): the compiled code
never mixes lanes, and a failed lane is retired without touching its mates. The quasi-static screw-axial level
(twin.engine.plant.screw_axial_balance): the shaft's axial displacement solves the elastic balance of bearing and
contacts at every evaluation, its speed is the balance's time derivative, and the Eq. 9.12 feature it gives agrees
with the dynamic level's.
"""

import math

import numpy as np
import pytest
from lane_helpers import OneLane

import twin
from twin.engine.codes import CONTACT, SCREW_AXIAL, SCREW_AXIAL_DYNAMIC
from twin.engine.group import group_key
from twin.engine.instrumentation import build_instruments, group_timing
from twin.engine.integrators import RK4
from twin.engine.model import build_model
from twin.engine.plant import BALANCE_TOLERANCE, W
from twin.fidelity import resolve_fidelity
from twin.layout import K, S
from twin.physics.ball_screw import nut_elastic_force
from twin.simulation import simulate, simulate_batch

DURATION = 1.2  # s: the first move of the nominal profile with its reversal, enough for every feature to be finite

#: Sampled-looking parameter changes (Table 9.5 uncertainties and a few plant parameters), one set per run in turn:
#: factors on the nominal value, and the values of sensor errors whose nominal value is zero.
FACTORS = ({}, {"motor.torque_constant": 1.03, "reducer.backlash": 0.9},
           {"sled.guide_friction_dynamic": 1.1, "motor.inertia": 0.95},
           {"ball_screw.contact_damping_coefficient": 1.2, "motor.speed_constant": 0.98},
           {"reducer.torsional_stiffness": 1.04, "sensors.electrical_noise_half_width": 0.8})
ERRORS = ({}, {"sensors.linear_encoder_phase_error": 0.21}, {"sensors.resolver_offset": 1.3e-4},
          {"sensors.torque_meter_sensitivity_error_range1": 1.5e-3}, {"sensors.linear_encoder_precision": 2.0e-7})


def _runs():
    """Runs of several data sets (three group configurations: the preloaded sets with the quasi-static screw axial,
    the free-nut sets with the dynamic one, and ds3 with its force step), room temperatures and supply pressures as
    a campaign samples them, parameter changes and noise generators of their own."""
    params = twin.load_parameters()
    runs = []
    for k, scene_name in enumerate(["ds1", "ds2", "ds4", "ds5", "ds7", "ds2", "ds5", "ds3", "ds3", "ds6", "ds1"]):
        scene = twin.load_scene(scene_name).with_duration(DURATION).with_conditions(
            {"room_temperature": 288.15 + 2.0 * k, "supply_pressure": 7.0e5 * (1.0 - 0.01 * k)})
        factors, errors = FACTORS[k % len(FACTORS)], ERRORS[k % len(ERRORS)]
        changed = params.with_values({**{name: factor * params.value(name) for name, factor in factors.items()},
                                      **errors})
        runs.append((scene, changed, np.random.default_rng(1000 + k)))
    return runs


def _same(a, b) -> bool:
    """Two summaries equal bit for bit: status, reason, time reached, fidelity and every feature (NaN == NaN)."""
    return ((a.status, a.failure_reason, a.t_reached, a.fidelity, a.integrator, a.dt)
            == (b.status, b.failure_reason, b.t_reached, b.fidelity, b.integrator, b.dt)
            and a.features.keys() == b.features.keys()
            and all(np.array_equal(a.features[f], b.features[f], equal_nan=True) for f in a.features))


def _alone(scene, params, seed):
    return simulate(scene, params, save="features", rng=np.random.default_rng(seed), throw=False)


@pytest.fixture(scope="module")
def alone():
    """Every run of :func:`_runs` by itself (its noise generator seeded alike)."""
    return [_alone(scene, params, 1000 + k) for k, (scene, params, _) in enumerate(_runs())]


def test_the_runs_share_groups(alone):
    """The premise of the bit-identity tests: the preloaded data sets resolve to one configuration (they share
    lanes), the free-nut sets without force demand to another, ds3 to a third; every run succeeds and its features
    are finite. The free-nut sets and ds3 share their fidelity levels (the full model: their rules' levels buy no
    speed, twin/fidelity/speed.toml) and ds3's force demand parts its group from theirs."""
    runs = _runs()
    kinds = [("ds3" if scene.name == "ds3" else "preloaded" if scene.condition("preload") > 0 else "free")
             for scene, _, _ in runs]
    fidelities = {kind: {alone[k].fidelity for k in range(len(runs)) if kinds[k] == kind} for kind in set(kinds)}
    assert all(len(found) == 1 for found in fidelities.values()) and len(set.union(*fidelities.values())) == 2
    keys = []
    for scene, params, _ in runs:  # what simulate_batch groups by (besides the options, common to all)
        fidelity = resolve_fidelity(scene, params)
        instruments = build_instruments(params.values(), scene.condition("room_temperature"), fidelity.levels,
                                        np.random.default_rng(0), 2, alone[0].dt)
        keys.append((group_key(build_model(scene, params, fidelity)), group_timing(instruments)))
    assert len(set(keys)) == 3 and all(keys[i] == keys[j] for i in range(len(runs)) for j in range(len(runs))
                                       if kinds[i] == kinds[j])
    for summary in alone:
        assert summary.status == "ok"
        assert math.isfinite(summary.features["backlash_feature"])
        assert math.isfinite(summary.features["backlash_feature_true"])
    # and the parameter changes and generators do change the numbers (the lanes hold different runs)
    assert len({s.features["backlash_feature"] for s in alone}) == len(alone)


@pytest.mark.parametrize("lanes", [1, 3, 8, 16])
def test_a_batch_gives_every_run_its_own_numbers_whatever_the_lane_count(alone, lanes):
    batch = simulate_batch(_runs(), solver=twin.Solver(lanes=lanes), throw=False)
    assert len(batch) == len(alone)
    for k, (summary, reference) in enumerate(zip(batch, alone, strict=True)):
        assert _same(summary, reference), f"run {k} at {lanes} lanes: {summary} != {reference}"


def test_a_batch_in_another_order_gives_the_same_numbers(alone):
    """Shuffled: each run gets other lane mates and another lane; results come back in the order given."""
    order = np.random.default_rng(5).permutation(len(alone))
    runs = _runs()
    batch = simulate_batch([runs[k] for k in order], solver=twin.Solver(lanes=4), throw=False)
    for summary, k in zip(batch, order, strict=True):
        assert _same(summary, alone[k]), f"run {k}"


def test_a_failed_lane_keeps_its_reason_and_leaves_its_mates_alone(alone):
    """Two runs of a group fail at their own times: stroke limits (guard code 2) of 10 um and of 2 mm, which the
    sled crosses early and late in its first move. Each is recorded as diverged with its reason and the time it
    reached, alone or in the batch, bit for bit, and is retired; its lane mates' results are those they have alone.
    With ``throw`` the batch raises for the failed run."""
    runs = _runs()
    early = runs[1][1].with_values({"sled.stroke_limit": 1.0e-5})
    late = runs[3][1].with_values({"sled.stroke_limit": 2.0e-3})
    failing = [(runs[1][0], early, 2001), (runs[3][0], late, 2003)]
    failing_alone = [_alone(scene, params, seed) for scene, params, seed in failing]
    for summary in failing_alone:
        assert summary.status == "diverged"
        assert summary.failure_reason == "sled beyond the stroke limit"
        assert all(math.isnan(value) for value in summary.features.values())
    assert 0.0 < failing_alone[0].t_reached < failing_alone[1].t_reached < DURATION
    mixed = [runs[0], (failing[0][0], failing[0][1], np.random.default_rng(2001)), runs[2],
             (failing[1][0], failing[1][1], np.random.default_rng(2003)), runs[4], runs[5]]
    batch = simulate_batch(mixed, solver=twin.Solver(lanes=8), throw=False)
    assert _same(batch[1], failing_alone[0]) and _same(batch[3], failing_alone[1])
    for position, k in ((0, 0), (2, 2), (4, 4), (5, 5)):
        assert _same(batch[position], alone[k]), f"run {k}"
    with pytest.raises(twin.SimulationFailed, match="stroke limit"):
        simulate_batch(mixed, solver=twin.Solver(lanes=8))


def test_simulate_saving_signals_and_features_agree_on_a_lane_of_one():
    """``simulate`` saving the signals (the Dataset, one lane, recording) and saving the features alone (no
    recording) give the same features and status, bit for bit, for a sampled run."""
    scene, params, _ = _runs()[3]
    ds = twin.simulate(scene, params, rng=np.random.default_rng(7), throw=False)
    summary = simulate(scene, params, save="features", rng=np.random.default_rng(7), throw=False)
    assert (summary.status, summary.failure_reason, summary.t_reached, summary.fidelity) == (
        ds.attrs["status"], ds.attrs["failure_reason"], ds.attrs["t_reached"], ds.attrs["fidelity"])
    assert (summary.integrator, summary.dt) == (ds.attrs["integrator"], ds.attrs["dt"])
    for name, value in summary.features.items():
        assert np.array_equal(value, ds[name].values, equal_nan=True), name


# --- the quasi-static screw-axial level ---------------------------------------------------------------------------


def _quasi_static_model(bench, scene, contact=None):
    """The full plant of ``scene`` at the quasi-static screw-axial level (ideal instruments; the contact level
    ``contact`` if given)."""
    request = twin.fidelity.full_plant("full" if scene.has_force_demand else "absent", screw_axial="quasi_static")
    if contact is not None:
        request["contact"] = contact
    model = build_model(scene, bench, resolve_fidelity(scene, bench, request))
    assert model.levels[SCREW_AXIAL] != SCREW_AXIAL_DYNAMIC
    assert S.SCREW_AXIAL not in model.active and S.SCREW_AXIAL_SPEED not in model.active
    return model


def _elastic(c, contact_model, relative_position):
    """The contact's elastic force and its tangent (:func:`nut_elastic_force`) at ``dx``."""
    return nut_elastic_force(relative_position, c[K.BACKLASH], c[K.COS_HELIX], c[K.CENTRE_DISTANCE],
                             c[K.CONTACT_RADIAL_0], c[K.CONTACT_AXIAL_0], c[K.SIN_ALPHA_0],
                             c[K.STIFFNESS_C0:K.STIFFNESS_C0 + 7], c[K.SIN_ALPHA_MIN], c[K.SIN_ALPHA_SPAN],
                             c[K.LOADED_BALLS], contact_model, c[K.LINEAR_CONTACT_STIFFNESS])


def _kicked_trajectory(model, h, n, every):
    """A preloaded chain kicked into motion (no current demand), RK4 steps of ``h``; the state every ``every``
    steps. The contacts load and unload, so the balance moves."""
    lane = OneLane(model)
    x = model.initial_state.copy()
    x[S.SCREW_SPEED], x[S.REDUCER_SPEED], x[S.NUT1_SPEED], x[S.NUT2_SPEED] = 3.0, 2.0, 2e-3, -1e-3
    states = []
    for k in range(n):
        lane.step(RK4, k * h, x, h)
        if (k + 1) % every == 0:
            states.append(x.copy())
    return lane, states


@pytest.mark.parametrize("contact", ["variable_angle", "constant_angle", "linear"])
def test_quasi_static_balance_holds_after_a_right_hand_side(bench, scene_factory, contact):
    """After a right-hand side the shaft's axial displacement balances the bearing against both contacts,
    ``k x_s + f_1^el + f_2^el = 0`` (the work rows' stiffness and ``dx_i``, :func:`nut_elastic_force`), along
    trajectories where both nuts are loaded (1 kN preload) and where the nuts hit and leave their flanks (no
    preload). Tolerance: the solver's own promise, a last Newton correction below BALANCE_TOLERANCE (a femtometre,
    1e-9 of the micrometre features), i.e. a residual below the balance's slope ``k + k_1 + k_2`` times that
    (1e-7 to 5e-7 N here). The iteration leaves far less: measured, a residual of 1e-21 m in displacement at most,
    and at round-off (at most 10 ulps of the terms) wherever both contacts are loaded."""
    counts = {"both loaded": 0, "one loaded": 0}
    for preload in (1000.0, 0.0):
        model = _quasi_static_model(bench, scene_factory(0.05, preload=preload, backlash=4e-6), contact)
        c, contact_model = model.constants, int(model.levels[CONTACT])
        lane, states = _kicked_trajectory(model, 5e-6, 400, 20)
        for x in states:
            lane.rhs(0.0, x)
            w = lane.w[:, 0]
            f1, k1 = _elastic(c, contact_model, w[W.NUT_DX])
            f2, k2 = _elastic(c, contact_model, w[W.NUT_DX + 1])
            stiffness = w[W.AXIAL_STIFFNESS]
            residual = stiffness * x[S.SCREW_AXIAL] + f1 + f2
            assert abs(residual) <= (stiffness + k1 + k2) * BALANCE_TOLERANCE
            assert w[W.BALANCE_FAILED] == 0.0
            # dx_i is the kinematic part plus the balance's displacement (Eq. 9.5)
            assert w[W.NUT_DX] == x[S.SCREW_AXIAL] + w[W.NUT_KINEMATIC]
            assert w[W.NUT_DX + 1] == x[S.SCREW_AXIAL] + w[W.NUT_KINEMATIC + 1]
            if f1 != 0.0 and f2 != 0.0:
                counts["both loaded"] += 1
            elif f1 != 0.0 or f2 != 0.0:
                counts["one loaded"] += 1
    assert counts["both loaded"] > 0 and counts["one loaded"] > 0, counts


def _balance_along(model, h, duration):
    """The balance's displacement and speed at every step of a kicked preloaded trajectory (RK4 steps of ``h``),
    each from a right-hand side at that state (a step leaves the rows of its first stage's balance in ``x``)."""
    lane = OneLane(model)
    x = model.initial_state.copy()
    x[S.SCREW_SPEED], x[S.REDUCER_SPEED], x[S.NUT1_SPEED], x[S.NUT2_SPEED] = 3.0, 2.0, 2e-3, -1e-3
    displacement, speed, tangent_error = [], [], 0.0
    c, contact_model = model.constants, int(model.levels[CONTACT])
    for k in range(int(round(duration / h))):
        lane.rhs(k * h, x)
        displacement.append(x[S.SCREW_AXIAL])
        speed.append(x[S.SCREW_AXIAL_SPEED])
        for nut in range(2):
            # the tangent the balance uses against central differences of the elastic force
            dx = lane.w[W.NUT_DX + nut, 0]
            _, tangent = _elastic(c, contact_model, dx)
            delta = 1e-4 * abs(dx)
            exact = (_elastic(c, contact_model, dx + delta)[0]
                     - _elastic(c, contact_model, dx - delta)[0]) / (2 * delta)
            tangent_error = max(tangent_error, abs(exact / tangent - 1.0))
        lane.step(RK4, k * h, x, h)
    displacement, speed = np.array(displacement), np.array(speed)
    return (displacement[2:] - displacement[:-2]) / (2 * h), speed[1:-1], tangent_error


@pytest.mark.parametrize("contact", ["variable_angle", "constant_angle", "linear"])
def test_quasi_static_speed_is_the_derivative_of_the_balance(bench, scene_factory, contact):
    """``S.SCREW_AXIAL_SPEED`` is the time derivative of the balance's displacement: against central differences of
    the displacement along a kicked, preloaded trajectory (both contacts loaded, the speed up to 1.5 mm/s).

    At the constant-angle and linear contacts the contacts' tangents are exact, and the differences converge to the
    speed as h^2 (halving the step divides the largest difference by 4; measured 4.0) down to 3e-8 of the largest
    speed at 0.1 us. At the variable angle the balance's tangents leave out the variation of K(alpha) with the angle
    (:func:`nut_elastic_force`; Newton needs only a positive slope), which misses the exact tangent by a relative
    ``e`` (measured here 4.2e-5 by central differences of the force): the speed ``-(k_1 b_1 + k_2 b_2 + ...) /
    (k + k_1 + k_2)`` then misses the derivative by at most ``2 e`` of the largest speed (measured 7.7e-6, the
    same at both steps)."""
    model = _quasi_static_model(bench, scene_factory(0.05, preload=1000.0, backlash=4e-6), contact)
    worst = {}
    for h in (2e-7, 1e-7):
        derivative, speed, tangent_error = _balance_along(model, h, 4e-4)
        largest = np.max(np.abs(speed))
        assert largest > 1e-3  # the balance does move
        worst[h] = np.max(np.abs(derivative - speed)) / largest
    if contact == "variable_angle":
        assert 1e-6 < tangent_error < 1e-3
        assert worst[1e-7] <= 2.0 * tangent_error
    else:
        assert tangent_error < 1e-6
        assert worst[2e-7] / worst[1e-7] > 3.0
        assert worst[1e-7] < 1e-7


@pytest.mark.slow
@pytest.mark.parametrize("scene_name", ["ds1", "ds4"])
def test_quasi_static_feature_agrees_with_the_dynamic_level(scene_name):
    """The Eq. 9.12 feature (true signals) of the quasi-static level against the dynamic level, both RK4 at a small
    step (31.25 us: a third of RK4's limit on the axial mode), over the first 5 s of ds1 (preloaded, 80 um gap) and
    ds4 (no gap, no preload): within 0.01 um.

    What the quasi-static level removes is the shaft's axial inertia (0.947 kg) between the bearing and the
    contacts, a 3.8-4.8 kHz mode. Below a mode the response is the static one to within (f / f_mode)^2, and the
    motions f_b is made of (the 1 Hz profile, the loops' 1-10 Hz) are hundreds of times slower: what is left is the
    inertia force itself, m_s a ~ 0.2 N at the profile's 0.2 m/s^2, against axial stiffnesses of 1e8-1e9 N/m, a few
    nanometres. Measured: 0.0030 um on both sets, the same to 0.0005 um at 62.5, 31.25 and 15.6 us (so it is the
    level's, not the step's); the bound is three times that, a fifth of the campaign accuracy rule's +/-0.05 um
    (docs/accuracy.md). Beyond ~6 s ds4's dynamic level grows a self-excited 255 Hz oscillation in which the axial
    mode takes part (docs/accuracy.md), which the massless shaft cannot have: there the levels part by ~0.2 um at
    10 s, a difference of model, not of numerics, which the fidelity audit judges."""
    features = {level: simulate(scene_name, solver=twin.Solver(dt=3.125e-5), save="features", duration=5.0, rng=1,
                                fidelity={"screw_axial": level}).features["backlash_feature_true"]
                for level in ("dynamic", "quasi_static")}
    assert abs(features["dynamic"] - features["quasi_static"]) < 0.01e-6
    assert features["dynamic"] != features["quasi_static"]  # the levels are different models
