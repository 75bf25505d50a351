"""Physics tests of the pneumatic load system (Bertolino 2020, Eqs. 9.9-9.11, Tables B.11-B.13)."""

import math
import tomllib
from pathlib import Path

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from twin.control.discrete import pi_step
from twin.control.force_loop_design import NutFixedPlant, design_force_loop
from twin.physics import pneumatics as pn

PARAMETER_FILE = Path(__file__).resolve().parents[2] / "twin/parameters/bench/pneumatics.toml"
with PARAMETER_FILE.open("rb") as _f:
    TOML = tomllib.load(_f)
PARAMS = {f"pneumatics.{key}": entry["value"] for key, entry in TOML.items()}


def par(key):
    return float(PARAMS["pneumatics." + key])


# Flow-law test constants: a valve-sized conductance [m^3/(s Pa)] and the defaults.
C = 8.0e-8
B = par("critical_pressure_ratio")
RHO0 = par("reference_density")
T0 = par("reference_temperature")
LAM = par("laminar_ratio")
T_UP = 310.0
T_DOWN = 280.0


def flow(p_up, p_down, t_up=T_UP, t_down=T_DOWN):
    return pn.mass_flow(p_up, p_down, C, B, RHO0, T0, t_up, t_down, LAM)


def choked(p_up, t_up=T_UP):
    return C * RHO0 * p_up * math.sqrt(T0 / t_up)


# --------------------------------------------------------------------------- #
# Eq. 9.9 / ISO 6358 mass flow
# --------------------------------------------------------------------------- #
@pytest.mark.parametrize("ratio", [0.0, 0.05, 0.2, B])
def test_flow_equals_choked_value_at_and_below_critical_ratio(ratio):
    p_up = 7.0e5
    assert flow(p_up, ratio * p_up) == pytest.approx(choked(p_up), rel=1e-12)


def test_flow_follows_iso6358_subsonic_law():
    p_up, ratio = 7.0e5, 0.8
    expected = choked(p_up) * math.sqrt(1.0 - ((ratio - B) / (1.0 - B)) ** 2)
    assert flow(p_up, ratio * p_up) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("ratio", [B, LAM])
def test_flow_continuous_at_regime_boundaries(ratio):
    # Relative jump across the boundary below 1e-6 of the choked flow for a
    # 1e-10 step in pressure ratio (sqrt terms vary by < 1e-5 over it).
    p_up = 7.0e5
    below = flow(p_up, (ratio - 1e-10) * p_up)
    above = flow(p_up, (ratio + 1e-10) * p_up)
    assert abs(above - below) < 1e-6 * choked(p_up)


def test_flow_zero_and_continuous_at_equal_pressures():
    p = 5.0e5
    assert flow(p, p) == 0.0
    assert flow(0.0, 0.0) == 0.0  # two evacuated ports: nothing to flow (and no division by p_up)
    eps = 1e-9
    forward, backward = flow(p, p * (1.0 - eps)), flow(p, p * (1.0 + eps))
    assert forward > 0.0 > backward
    # Laminar band slope phi(r_lam)/(1 - r_lam) ~ 53: |G| ~ 53 eps G_choked.
    assert abs(forward) < 100.0 * eps * choked(p)
    assert abs(backward) < 100.0 * eps * choked(p)


def test_flow_laminar_band_is_linear_in_pressure_difference():
    p_up = 6.0e5
    g1 = flow(p_up, p_up - 100.0)
    g2 = flow(p_up, p_up - 200.0)
    assert g2 == pytest.approx(2.0 * g1, rel=1e-12)


def test_flow_antisymmetric_under_port_reversal():
    rng = np.random.default_rng(1)
    for p_a, p_b, t_a, t_b in zip(rng.uniform(1e5, 8e5, 200), rng.uniform(1e5, 8e5, 200),
                                  rng.uniform(280, 320, 200), rng.uniform(280, 320, 200), strict=False):
        assert pn.mass_flow(p_a, p_b, C, B, RHO0, T0, t_a, t_b, LAM) == \
            -pn.mass_flow(p_b, p_a, C, B, RHO0, T0, t_b, t_a, LAM)


def test_flow_decreases_monotonically_with_downstream_pressure():
    p_up = 5.0e5
    downstream = np.linspace(0.0, 5.0e5 / B * 1.2, 20001)
    g = np.array([flow(p_up, p) for p in downstream])
    assert np.all(np.diff(g) <= 0.0)
    # Reverse choked flow is set by the (now upstream) downstream port.
    assert g[-1] == pytest.approx(-choked(downstream[-1], T_DOWN), rel=1e-12)


def test_conductance_reproduces_standard_nominal_flow():
    c_max = pn.conductance_from_nominal_flow(
        par("nominal_flow_rate"), par("nominal_flow_upstream_pressure"),
        par("nominal_flow_downstream_pressure"), B, LAM)
    g = pn.mass_flow(par("nominal_flow_upstream_pressure"), par("nominal_flow_downstream_pressure"),
                     c_max, B, RHO0, T0, T0, T0, LAM)
    assert g / RHO0 * 60e3 == pytest.approx(2000.0, rel=1e-12)  # l/min ANR, Table B.12


# --------------------------------------------------------------------------- #
# Valve: spool dynamics, hysteresis, conductances
# --------------------------------------------------------------------------- #
SPOOL_ARGS = (par("valve_mid_voltage"), par("valve_command_min"), par("valve_command_max"),
              par("valve_critical_frequency"), par("valve_damping_ratio"))


@pytest.mark.parametrize("command, target", [(5.0, 0.0), (10.0, 1.0), (0.0, -1.0), (7.5, 0.5),
                                             (12.0, 1.0), (-3.0, -1.0)])
def test_spool_steady_state_maps_command_to_opening(command, target):
    assert pn.spool_derivative(target, 0.0, command, *SPOOL_ARGS) == (0.0, pytest.approx(0.0, abs=1e-9))


def test_spool_response_is_3db_down_at_critical_frequency():
    # The spool ODE is linear inside the command range: read (A, b) off it.
    a = np.array([[0.0, 1.0],
                  [pn.spool_derivative(1.0, 0.0, 5.0, *SPOOL_ARGS)[1],
                   pn.spool_derivative(0.0, 1.0, 5.0, *SPOOL_ARGS)[1]]])
    b = np.array([0.0, pn.spool_derivative(0.0, 0.0, 6.0, *SPOOL_ARGS)[1]])  # per volt
    w = 2.0 * math.pi * 70.0
    # Opening per volt is 1/5 V: scale so the static gain is 1.
    h = np.linalg.solve(1j * w * np.eye(2) - a, b)[0] * 5.0
    assert abs(h) == pytest.approx(1.0 / math.sqrt(2.0), rel=1e-9)


def test_hysteresis_play_band_is_04_percent_of_span():
    h, lo, hi = par("valve_hysteresis"), par("valve_command_min"), par("valve_command_max")
    held = 5.0
    for u in np.linspace(5.0, 7.0, 201):
        held = pn.hysteresis_play(u, held, h, lo, hi)
    up_branch = held
    held = pn.hysteresis_play(7.0 - 0.039, held, h, lo, hi)
    assert held == up_branch  # reversal inside the band: spool target does not move
    for u in np.linspace(7.0, 6.0, 101):
        held = pn.hysteresis_play(u, held, h, lo, hi)
    down_branch = held
    assert up_branch - (7.0 - 0.02) == pytest.approx(0.0, abs=1e-12)
    assert (6.0 + 0.02) - down_branch == pytest.approx(0.0, abs=1e-12)
    assert h * (hi - lo) == pytest.approx(0.04, rel=1e-12)


def test_port_conductances_closed_centre_and_full_opening():
    c_max, leak = 1.0e-7, par("valve_leakage_fraction")
    assert pn.port_conductances(0.0, c_max, leak) == pytest.approx((leak * c_max,) * 4, rel=1e-12)
    assert pn.port_conductances(0.0, c_max, 0.0) == (0.0, 0.0, 0.0, 0.0)
    s1, e1, s2, e2 = pn.port_conductances(1.0, c_max, leak)
    assert (s1, e2) == pytest.approx((c_max, c_max), rel=1e-12)
    assert (e1, s2) == pytest.approx((leak * c_max,) * 2, rel=1e-12)
    # Opposite spool stroke = the same valve with the chambers swapped.
    s1, e1, s2, e2 = pn.port_conductances(0.4, c_max, leak)
    assert pn.port_conductances(-0.4, c_max, leak) == (s2, e2, s1, e1)
    assert pn.port_conductances(1.05, c_max, leak) == pn.port_conductances(1.0, c_max, leak)


# --------------------------------------------------------------------------- #
# Eq. 9.10: chamber continuity
# --------------------------------------------------------------------------- #
A1, A2 = pn.piston_areas(par("bore_diameter"), par("rod_diameter"))
STROKE = par("stroke")
R_GAS = par("gas_constant")
T_GAS = par("air_temperature")


def piston_motion(t):
    """Prescribed piston motion: 100 mm amplitude, 1 Hz, around mid stroke [m, m/s]."""
    w = 2.0 * math.pi
    return 0.5 * STROKE + 0.1 * math.sin(w * t), 0.1 * w * math.cos(w * t)


def chamber_rhs(n, x_spool, leakage_fraction):
    c_max = 1.0e-7

    def rhs(t, y):
        p1, p2 = y[0], y[1]
        x, v = piston_motion(t)
        g1, g2 = pn.chamber_mass_flows(x_spool, p1, p2, par("supply_pressure"),
                                       par("atmospheric_pressure"), c_max, leakage_fraction, B,
                                       RHO0, T0, T_GAS, T_GAS, LAM)
        v1, dv1, v2, dv2 = pn.chamber_volumes(x, v, A1, A2, par("dead_volume_1"),
                                              par("dead_volume_2"), STROKE)
        return [pn.chamber_pressure_derivative(p1, g1, v1, dv1, T_GAS, R_GAS, n),
                pn.chamber_pressure_derivative(p2, g2, v2, dv2, T_GAS, R_GAS, n),
                g1, g2]

    return rhs


def volumes(t):
    x, v = piston_motion(t)
    v1, _, v2, _ = pn.chamber_volumes(x, v, A1, A2, par("dead_volume_1"), par("dead_volume_2"),
                                      STROKE)
    return np.array([v1, v2])


@pytest.mark.parametrize("n", [1.0, par("polytropic_exponent"), 1.4])
def test_closed_valve_conserves_mass_and_polytropic_invariant(n):
    p0 = np.array([4.0e5, 3.0e5])
    t_eval = np.linspace(0.0, 2.0, 41)
    sol = solve_ivp(chamber_rhs(n, 0.0, 0.0), (0.0, 2.0), [*p0, 0.0, 0.0], t_eval=t_eval,
                    rtol=1e-11, atol=1e-6)
    assert sol.success
    vol = np.array([volumes(t) for t in sol.t]).T
    p = sol.y[:2]
    assert np.all(sol.y[2:] == 0.0)  # closed centre without leakage: no flow at all
    invariant = p * vol ** n
    np.testing.assert_allclose(invariant / invariant[:, :1], 1.0, rtol=1e-8)
    # Gas mass PV/(R T) with the polytropic temperature T = T_i (P/P_i)^((n-1)/n)
    # (the constant chamber temperature itself when n = 1).
    t_gas = T_GAS * (p / p0[:, None]) ** ((n - 1.0) / n)
    mass = p * vol / (R_GAS * t_gas)
    np.testing.assert_allclose(mass / mass[:, :1], 1.0, rtol=1e-8)
    assert np.ptp(p[0]) > 1.0e5  # the motion really compressed the gas


def test_isothermal_chamber_mass_changes_by_integrated_flow():
    # With n = 1 the chamber mass is PV/(RT) at the chamber temperature, so its
    # change must equal the integrated valve flow while the piston moves.
    p0 = np.array([4.0e5, 3.0e5])
    sol = solve_ivp(chamber_rhs(1.0, 0.3, par("valve_leakage_fraction")), (0.0, 1.0),
                    [*p0, 0.0, 0.0], t_eval=[0.0, 0.25, 0.5, 1.0], rtol=1e-11, atol=1e-9)
    assert sol.success
    vol = np.array([volumes(t) for t in sol.t]).T
    mass = sol.y[:2] * vol / (R_GAS * T_GAS)
    np.testing.assert_allclose(mass - mass[:, :1], sol.y[2:], rtol=1e-7, atol=1e-10)
    assert abs(sol.y[2, -1]) > 1e-3  # kg: a real flow went through


# --------------------------------------------------------------------------- #
# Eq. 9.11: piston forces
# --------------------------------------------------------------------------- #
DAMPER = (STROKE, par("damper_travel"), par("damper_stiffness"), par("damper_damping"),
          par("end_stop_stiffness"))


def test_piston_force_zero_at_ambient_and_area_weighted():
    p_atm = par("atmospheric_pressure")
    assert pn.piston_force(p_atm, p_atm, A1, A2, p_atm) == pytest.approx(0.0, abs=1e-9)
    assert pn.piston_force(p_atm + 1e5, p_atm, A1, A2, p_atm) == pytest.approx(1e5 * A1, rel=1e-12)
    assert A1 - A2 == pytest.approx(math.pi * 0.02 ** 2, rel=1e-12)  # 40 mm rod


def piston_acc(p1, p2, x, v, load_cell_force):
    return pn.piston_acceleration(
        p1, p2, x, v, load_cell_force, A1, A2, par("atmospheric_pressure"), par("piston_mass"),
        par("piston_damping"), par("friction_static"), par("friction_dynamic"),
        par("friction_stribeck_coefficient"), par("friction_viscous"),
        par("friction_velocity_threshold"), *DAMPER)


def test_piston_at_rest_in_equilibrium_with_load_cell():
    p1, p2 = 6.0e5, 4.0e5
    f_lc = pn.piston_force(p1, p2, A1, A2, par("atmospheric_pressure"))
    assert piston_acc(p1, p2, 0.5 * STROKE, 0.0, f_lc) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("v", [0.07, -0.07, 0.5])
def test_moving_piston_decelerated_by_seal_friction_and_damping(v):
    # Eq. 9.11 with balanced pressure and load-cell forces: m a = -F_fr(v) - c_p v,
    # F_fr in Eq. 7.63 form; at |v| >= 14 v_th the tanh is 1 to 1e-12.
    p1, p2 = 6.0e5, 4.0e5
    f_lc = pn.piston_force(p1, p2, A1, A2, par("atmospheric_pressure"))
    f_s, f_d = par("friction_static"), par("friction_dynamic")
    friction = math.copysign(f_d + (f_s - f_d) * math.exp(-par("friction_stribeck_coefficient") * abs(v)), v)
    expected = -(friction + (par("friction_viscous") + par("piston_damping")) * v) / par("piston_mass")
    assert piston_acc(p1, p2, 0.5 * STROKE, v, f_lc) == pytest.approx(expected, rel=1e-10)


def test_end_stroke_damper_acts_only_within_its_travel():
    travel, k = par("damper_travel"), par("damper_stiffness")
    for x in np.linspace(travel, STROKE - travel, 101):
        assert pn.end_stroke_damper_force(x, 0.3, *DAMPER) == 0.0
    # Static force k * compression, pushing away from the head, at both ends.
    assert pn.end_stroke_damper_force(0.006, 0.0, *DAMPER) == pytest.approx(k * 0.010, rel=1e-12)
    assert pn.end_stroke_damper_force(STROKE - 0.006, 0.0, *DAMPER) == \
        pytest.approx(-k * 0.010, rel=1e-12)
    # Full deflection gives the rated 4 kN (Table B.11), continuous at the contact point.
    assert pn.end_stroke_damper_force(0.0, 0.0, *DAMPER) == pytest.approx(4000.0, rel=1e-12)
    assert abs(pn.end_stroke_damper_force(travel - 1e-9, 0.0, *DAMPER)) < 1e-3
    # An elastomer cannot pull a receding piston.
    assert pn.end_stroke_damper_force(0.015, 5.0, *DAMPER) == 0.0
    # Beyond full deflection the head stop takes over.
    assert pn.end_stroke_damper_force(-1e-4, 0.0, *DAMPER) > 4000.0 + 0.5 * par("end_stop_stiffness") * 1e-4
    # Not yet touching at x = travel, even while approaching the head.
    assert pn.end_stroke_damper_force(travel, -0.3, *DAMPER) == 0.0
    assert pn.end_stroke_damper_force(STROKE - travel, 0.3, *DAMPER) == 0.0


def test_end_stroke_damper_damping_resists_the_approach_at_both_ends():
    """k delta + c |v| while the piston moves into the damper, at the cap end (v < 0) and the rod end (v > 0)."""
    k, c = par("damper_stiffness"), par("damper_damping")
    assert c > 0.0
    assert pn.end_stroke_damper_force(0.006, -0.01, *DAMPER) == pytest.approx(k * 0.010 + c * 0.01, rel=1e-12)
    assert pn.end_stroke_damper_force(STROKE - 0.006, 0.01, *DAMPER) == \
        pytest.approx(-(k * 0.010 + c * 0.01), rel=1e-12)


def test_load_cell_deflection_at_nominal_force():
    k = par("load_cell_stiffness")
    assert pn.load_cell_spring_force(0.018e-3, 0.0, 0.0, 0.0, k, 0.0) == pytest.approx(20e3, rel=1e-12)
    assert pn.load_cell_spring_force(0.0, 0.0, 0.1, 0.1, k, par("load_cell_damping")) == 0.0


# --------------------------------------------------------------------------- #
# Force loop design
# --------------------------------------------------------------------------- #
@pytest.fixture(scope="module")
def design():
    return design_force_loop(PARAMS, 1e-3)


def test_operating_point_balances_flows_and_force(design):
    op = design["operating_point"]
    plant = NutFixedPlant(PARAMS)
    g1, g2 = plant.mass_flows(op["x_spool"], op["p1"], op["p2"])
    assert abs(g1) < 1e-12 and abs(g2) < 1e-12  # kg/s
    assert plant.pneumatic_force(op["p1"], op["p2"]) == pytest.approx(4000.0, rel=1e-9)
    dz, f_lc = plant.derivatives(op["state"], op["command"], op["x_nut"])
    assert f_lc == pytest.approx(4000.0, rel=1e-9)
    assert np.all(np.abs(dz) < [1e-9, 1e-6, 1e-3, 1e-3, 1e-12, 1e-3])


def test_force_loop_design_meets_stated_margins(design):
    assert design["closed_loop_stable"]
    assert design["kp"] > 0.0 and design["ki"] > 0.0
    assert design["crossover_hz"] == pytest.approx(10.0, rel=1e-3)
    assert design["phase_margin_deg"] > 45.0
    assert design["gain_margin_db"] > 6.0


def simulate_force_step(design, force_step, samples):
    """The bench's discrete PI (``pi_step``) on the nonlinear nut-fixed plant.

    The plant is integrated with RK4 at 50 us (below the 1e-4 s explicit
    limit of the load-cell mode); the command is applied in the tick it is
    computed, as in ``twin.engine.loop``.  Returns the load-cell force read at
    each controller sample [N].
    """
    plant = NutFixedPlant(PARAMS)
    op = design["operating_point"]
    kp, ki, ts = design["kp"], design["ki"], design["sample_time"]
    mid = par("valve_mid_voltage")
    limit = 0.5 * (par("valve_command_max") - par("valve_command_min"))
    z, integral = op["state"].copy(), op["command"] - mid
    substeps = 20
    dt = ts / substeps
    target = 4000.0 + force_step
    forces = np.empty(samples)
    for i in range(samples):
        forces[i] = plant.derivatives(z, 0.0, op["x_nut"])[1]
        output, integral = pi_step(target - forces[i], integral, kp, ki, ts, limit)
        command = mid + output
        for _ in range(substeps):
            k1 = plant.derivatives(z, command, op["x_nut"])[0]
            k2 = plant.derivatives(z + 0.5 * dt * k1, command, op["x_nut"])[0]
            k3 = plant.derivatives(z + 0.5 * dt * k2, command, op["x_nut"])[0]
            k4 = plant.derivatives(z + dt * k3, command, op["x_nut"])[0]
            z = z + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return forces


def test_small_force_step_matches_linear_design(design):
    # 100 N keeps the valve unsaturated: the nonlinear response must follow
    # the discrete closed loop of the design within 2 % of the step.
    samples = 300
    linear = control.step_response(design["closed_loop"],
                                   np.arange(samples) * design["sample_time"]).outputs.ravel()
    forces = simulate_force_step(design, 100.0, samples)
    assert np.max(np.abs(forces - 4000.0 - 100.0 * linear)) < 2.0


def test_large_force_step_settles_despite_valve_saturation(design):
    # 1 kN step: kp * 1 kN = 7 V saturates the command at 10 V at first.
    forces = simulate_force_step(design, 1000.0, 300)
    assert forces.max() < 5000.0 + 0.25 * 1000.0  # overshoot < 25 %
    assert np.all(np.abs(forces[-10:] - 5000.0) < 10.0)  # within 1 % of the step after 0.3 s


# --------------------------------------------------------------------------- #
# Parameter file and validation
# --------------------------------------------------------------------------- #
def test_parameter_file_complete_and_well_formed():
    assert set(TOML) == set(pn.REQUIRED_KEYS)
    for key, entry in TOML.items():
        assert isinstance(entry["value"], float), key
        assert entry["unit"], key
        assert ("source" in entry) != ("assumption" in entry), key
        assert entry["value"] >= entry.get("min", -math.inf), key
        assert entry["value"] <= entry.get("max", math.inf), key
        assert entry["value"] > entry.get("gt", -math.inf), key
    assert pn.validate_pneumatics(PARAMS) == []


@pytest.mark.parametrize("changes, fields", [
    ({"supply_pressure": -1.0}, ["pneumatics.supply_pressure"]),
    ({"atmospheric_pressure": 0.0}, ["pneumatics.atmospheric_pressure"]),
    ({"supply_pressure": 9.0e4}, ["pneumatics.supply_pressure", "pneumatics.atmospheric_pressure"]),
    ({"rod_diameter": 0.16}, ["pneumatics.rod_diameter"]),
    ({"bore_diameter": 0.0}, ["pneumatics.bore_diameter"]),
    ({"laminar_ratio": 0.2}, ["pneumatics.laminar_ratio"]),
])
def test_validation_rejects_bad_input_naming_the_field(changes, fields):
    bad = dict(PARAMS, **{"pneumatics." + k: v for k, v in changes.items()})
    with pytest.raises(ValueError) as info:
        pn.validate_pneumatics(bad)
    for field in fields:
        assert field in str(info.value)


@pytest.mark.parametrize("key, value, other", [
    ("valve_leakage_fraction", -0.5, None),                                   # non-negative, even above -1
    ("nominal_flow_downstream_pressure", "nominal_flow_upstream_pressure", None),  # equal pressures: no flow
    ("valve_mid_voltage", "valve_command_min", None),                        # the range's edge is outside
    ("damper_travel", 0.6, "stroke"),                                        # two travels of 0.6 stroke overlap
])
def test_validation_boundaries(key, value, other):
    if isinstance(value, str):
        value = PARAMS["pneumatics." + value]
    elif other is not None:
        value *= PARAMS["pneumatics." + other]
    bad = dict(PARAMS, **{"pneumatics." + key: value})
    with pytest.raises(ValueError, match="pneumatics." + key):
        pn.validate_pneumatics(bad)


def test_validation_lists_every_problem_at_once():
    bad = dict(PARAMS, **{"pneumatics.supply_pressure": -1.0, "pneumatics.bore_diameter": 0.0,
                          "pneumatics.piston_mass": -2.0})
    del bad["pneumatics.stroke"]
    with pytest.raises(ValueError) as info:
        pn.validate_pneumatics(bad)
    message = str(info.value)
    for field in ("supply_pressure", "bore_diameter", "piston_mass", "stroke"):
        assert f"pneumatics.{field}" in message
