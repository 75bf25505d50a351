"""Assemble the compiled model: constants array, tables and initial state from parameters and scene."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Protocol

import numpy as np
from scipy.optimize import brentq

from numerics.elementary import sin
from numerics.linalg import lstsq
from twin.components import COMPONENTS
from twin.components.preload import assembled_compression
from twin.control.force_loop_design import operating_point
from twin.errors import ParameterError, SceneError
from twin.layout import N_CONSTANTS, N_STATES, PARAMETER_CONSTANTS, POSITION_VELOCITY_PAIRS, K, S
from twin.levels import level_code, level_codes
from twin.parameters import ParameterSet
from twin.physics import hertz
from twin.physics import pneumatics as pn
from twin.physics.ball_screw import (
    CONTACT_LINEAR,
    STIFFNESS_FIT_DEGREE,
    ball_angular_pitch,
    ball_averaging_factor,
    effective_loaded_balls,
    groove_centre_distance,
    helix_angle,
    nut_axial_force,
    stiffness_at,
    travel_deviation,
)
from twin.physics.drivetrain import screw_inertia, screw_mass
from twin.physics.guides import abbe_reading_gain
from twin.physics.motor import equivalent_inductance, equivalent_resistance, equivalent_voltage_limit
from twin.scenes import Scene

CURVATURE_FORMULAS = {"thesis": hertz.FORMULA_THESIS, "iso": hertz.FORMULA_ISO}
STIFFNESS_FIT_POINTS = 200
STIFFNESS_FIT_TOLERANCE = 1e-5  # relative; far below the 2 % error of the curvature fits (Sec. 3.5.5)
# sin(70 deg): upper validity limit of the fitted curvature formulas (Eqs. 3.20, 3.27); far beyond any load the screw
# can carry
SIN_ALPHA_MAX = 0.9397

# Numerical choices (not physics parameters): the friction laws' sign regularisation
# and the divergence guard's bounds. Documented in docs/model.md.
LINEAR_VELOCITY_THRESHOLD = 1.0e-4   # m/s: well below the slowest commanded motion (~1 mm/s)
ANGULAR_VELOCITY_THRESHOLD = 1.0e-2  # rad/s: 8 um/s of nut travel through p/(2 pi), the scale of the linear threshold
MAX_MOTOR_SPEED_FACTOR = 2.0         # guard: twice the motor's maximum permissible 7000 rpm (Table B.1)
MOTOR_MAX_PERMISSIBLE_SPEED = 7000.0 * 2.0 * math.pi / 60.0
MAX_WINDING_TEMPERATURE = 473.15     # K: 200 degC, beyond the insulation class of any servo winding
MAX_NORMAL_APPROACH = 60.0e-6        # m: ~3x the Hertz approach at the screw's static load C0 = 13 kN


@dataclass(frozen=True)
class Model:
    """Everything the compiled loop needs for one run.

    The lanes of a group share ``levels``, ``active``, ``pairs`` and the two demand tables (one scene and one
    model configuration); ``constants`` and ``initial_state`` are the run's own (:mod:`twin.engine.group`)."""

    constants: np.ndarray
    initial_state: np.ndarray
    position_table: np.ndarray
    force_table: np.ndarray
    levels: np.ndarray   # level code of every subsystem (twin.levels.level_codes)
    active: np.ndarray   # indices (layout S) of the integrated states; the others hold their initial value
    pairs: np.ndarray    # (m, 2) integrated (position, velocity) index pairs, for the semi-implicit Euler step

    @property
    def stiffness_poly(self) -> np.ndarray:
        """The coefficients of the series Hertz stiffness fit (``K.STIFFNESS_C0`` ...), lowest power first."""
        return self.constants[K.STIFFNESS_C0:K.STIFFNESS_C0 + STIFFNESS_FIT_DEGREE + 1]

    def full_state(self, integrated: np.ndarray) -> np.ndarray:
        """The full-layout state with the integrated states set to ``integrated``."""
        x = self.initial_state.copy()
        x[self.active] = integrated
        return x


class Levels(Protocol):
    """What building the model needs of a resolved fidelity (:class:`twin.fidelity.Fidelity` provides it).

    The engine states its need here rather than importing the fidelity package, which sits above the
    engine: its rules evaluate the model's own contact physics (``docs/architecture.md``).
    """

    peak_contact_load: float
    active_states: np.ndarray

    def level(self, subsystem: str) -> str: ...


def build_model(scene: Scene, params: ParameterSet, fidelity: Levels, *, curvature: str = "thesis") -> Model:
    """Derive the model constants (layout :class:`K`) and the initial equilibrium state.

    Parameters
    ----------
    scene : Scene
        Test procedure (conditions and demand profiles).
    params : ParameterSet
        Component parameters.
    fidelity : Levels
        Level of every subsystem (:func:`twin.fidelity.resolve_fidelity`).
    curvature : {"thesis", "iso"}
        Groove curvature formulas: Eqs. 3.20/3.27 (thesis) or Eqs. 3.21/3.28 (ISO 3408-4).
    """
    p = params.values()
    c = np.zeros(N_CONSTANTS)
    for constant, name in PARAMETER_CONSTANTS.items():
        c[constant] = p[name]
    room_temperature = scene.condition("room_temperature")
    # motor and drive (Eqs. 9.1-9.3, Table B.1-B.3): the power-consistent equivalent circuit (twin.physics.motor)
    c[K.R20] = equivalent_resistance(p["motor.winding_resistance_20C"])
    c[K.INDUCTANCE] = equivalent_inductance(p["motor.inductance"])
    c[K.VOLTAGE_LIMIT] = equivalent_voltage_limit(p["drive.dc_bus_voltage"], p["drive.phase_voltage_amplitude_limit"])
    c[K.CURRENT_LOOP_TAU] = 1.0 / (2.0 * math.pi * p["controller.current_loop_bandwidth"])
    c[K.AMBIENT] = room_temperature
    # the components of twin.components (the reducer, the guides, the preload set, the seals)
    for component in COMPONENTS:
        component.derive_constants(c, p, scene)
    c[K.J_SCREW_SIDE] = screw_inertia(p) + p["drivetrain.torque_meter_inertia"] + 2.0 * p["drivetrain.coupling_inertia"]
    # screw axial: rear bearing in series with the shaft (Table B.9)
    c[K.SCREW_MASS] = screw_mass(p)
    c[K.SHAFT_EA] = p["ball_screw.elastic_modulus"] * math.pi * p["ball_screw.screw_root_diameter"] ** 2 / 4.0
    # ball-screw contact (Eqs. 9.4-9.6, 5.5, Sec. 7.3)
    stiffness_poly = contact_constants(c, p, curvature)
    lead_constants(c, p, room_temperature)
    levels = level_codes(fidelity.levels)
    contact_model = level_code("contact", fidelity.level("contact"))
    if contact_model == CONTACT_LINEAR:
        c[K.LINEAR_CONTACT_STIFFNESS] = secant_contact_stiffness(c, stiffness_poly, fidelity.peak_contact_load)
    c[K.BACKLASH] = scene.condition("backlash")
    ball_groove_friction_constants(c, p, fidelity)
    preload = scene.condition("preload")  # the preload set's constants: twin.components.preload
    c[K.LINEAR_V_THRESHOLD] = LINEAR_VELOCITY_THRESHOLD
    c[K.ANGULAR_V_THRESHOLD] = ANGULAR_VELOCITY_THRESHOLD
    c[K.SCALE_READING_GAIN] = scale_reading_gain(p, room_temperature)
    # digital loops (Table B.3, controller.toml)
    converters = fidelity.level("output_converters") == "quantized"
    if converters:
        c[K.SPEED_COMMAND_BITS] = p["drive.analog_input_bits"] + 1.0  # 11 bits + sign (Table B.3)
    # divergence guard
    c[K.MAX_MOTOR_SPEED] = MAX_MOTOR_SPEED_FACTOR * MOTOR_MAX_PERMISSIBLE_SPEED
    c[K.MAX_TEMPERATURE] = MAX_WINDING_TEMPERATURE
    c[K.MAX_NORMAL_APPROACH] = MAX_NORMAL_APPROACH

    if converters:
        c[K.VALVE_COMMAND_BITS] = p["controller.valve_command_dac_bits"]
    c[K.FORCE_FEEDBACK_NOISE] = 1.0 if scene.condition("noise_path") == "feedback" else 0.0

    x0 = initial_state(c, contact_model, preload, scene.condition("zero_procedure"), fidelity.level("nut_rotation"))
    # The encoders are zeroed on the initial state, whatever the procedure (docs/model.md).
    c[K.NUT1_ZERO] = x0[S.NUT1_POSITION]
    c[K.SCREW_ANGLE_ZERO] = x0[S.SCREW_ANGLE]
    if fidelity.level("pneumatics") == "full":
        # the seals start undeflected (SEAL_DEFLECTION 0): the force loop's start holds zero force
        x0[S.SPOOL_POSITION:S.PISTON_SPEED + 1] = pneumatic_constants(c, p, scene)
    active = fidelity.active_states
    pairs = np.array([pair for pair in POSITION_VELOCITY_PAIRS if pair[0] in active], dtype=np.int64).reshape(-1, 2)
    return Model(c, x0, scene.position_table(), scene.force_table(), levels, active, pairs)


def contact_constants(c: np.ndarray, p: dict[str, float], curvature: str) -> np.ndarray:
    """Fill the ball-groove contact constants (Eqs. 9.4-9.6, 5.5, Sec. 7.3) into ``c`` and
    return the polynomial fit of the Hertz stiffness ``K(sin alpha)``."""
    lead = p["ball_screw.lead"]
    ball_radius = p["ball_screw.ball_radius"]
    pitch_radius = p["ball_screw.pitch_radius"]
    alpha_e = helix_angle(lead, pitch_radius)
    alpha_0 = p["ball_screw.contact_angle"]
    c[K.LEAD_ARM_NOMINAL] = lead / (2.0 * math.pi)
    c[K.COS_HELIX] = math.cos(alpha_e)
    c[K.CENTRE_DISTANCE] = groove_centre_distance(ball_radius, p["ball_screw.conformity"])
    c[K.CONTACT_ANGLE_0] = alpha_0
    c[K.CONTACT_RADIAL_0] = c[K.CENTRE_DISTANCE] * math.cos(alpha_0)
    c[K.CONTACT_AXIAL_0] = c[K.CENTRE_DISTANCE] * math.sin(alpha_0)
    c[K.SIN_ALPHA_0] = math.sin(alpha_0)
    sin_min = math.sin(alpha_0)
    stiffness_poly = _hertz_stiffness_fit(ball_radius, pitch_radius, alpha_e, sin_min, p["ball_screw.conformity"],
                                          p["ball_screw.elastic_modulus"], p["ball_screw.poisson_ratio"],
                                          p["ball_screw.ogival_offset"], curvature).copy()
    c[K.SIN_ALPHA_MIN] = sin_min
    c[K.SIN_ALPHA_SPAN] = SIN_ALPHA_MAX - sin_min
    c[K.STIFFNESS_C0:K.STIFFNESS_C0 + STIFFNESS_FIT_DEGREE + 1] = stiffness_poly
    c[K.CONTACT_DAMPING] = p["ball_screw.contact_damping_coefficient"]
    c[K.LOADED_BALLS] = effective_loaded_balls(p["ball_screw.total_balls"], p["ball_screw.loaded_ball_fraction"])
    return stiffness_poly


def lead_constants(c: np.ndarray, p: dict[str, float], room_temperature: float) -> None:
    """Fill the screw's lead at the room temperature and its travel deviation (:mod:`twin.physics.ball_screw`) into
    ``c`` (after :func:`contact_constants`, which sets the nominal lead).

    ``p(T) = p (1 + alpha (T - T_ref))``: Sec. 7.7, Eq. 7.72 in its dimensionally consistent form, with the screw at
    the room temperature of the test (friction heats it by less than 0.4 K in a 10 s test: ``ball_screw.toml``).
    The travel deviation's offsets at the test zero are computed with the same ``sin`` as the compiled law, so
    that ``e(0) = 0`` exactly. The per-revolution amplitude is the nut's: ``a_2pi`` averaged over
    ``ball_screw.lead_per_revolution_averaged_balls`` balls (:func:`twin.physics.ball_screw.ball_averaging_factor`;
    one ball, the nominal, leaves it bit for bit).

    Raises
    ------
    ParameterError
        When more balls are averaged than the nut holds (``ball_screw.total_balls``).
    """
    balls = p["ball_screw.lead_per_revolution_averaged_balls"]
    if balls > p["ball_screw.total_balls"]:
        raise ParameterError([f"ball_screw.lead_per_revolution_averaged_balls: {balls:g} balls averaged, but the nut "
                              f"holds {p['ball_screw.total_balls']:g} (ball_screw.total_balls); allowed: a whole "
                              "number from 1 to that"])
    pitch = ball_angular_pitch(p["ball_screw.ball_radius"], p["ball_screw.pitch_radius"], p["ball_screw.lead"])
    c[K.LEAD_REVOLUTION_AMPLITUDE] = p["ball_screw.lead_per_revolution_amplitude"] * ball_averaging_factor(
        int(balls), pitch)
    expansion = p["ball_screw.thermal_expansion_coefficient"] * (
        room_temperature - p["ball_screw.thermal_reference_temperature"])
    c[K.LEAD_ARM] = c[K.LEAD_ARM_NOMINAL] * (1.0 + expansion)
    c[K.LEAD_WAVE_NUMBER] = p["ball_screw.lead"] / p["ball_screw.lead_travel_variation_wavelength"]
    c[K.LEAD_WAVE_AT_ZERO] = sin(c[K.LEAD_WAVE_PHASE])
    c[K.LEAD_REVOLUTION_AT_ZERO] = sin(c[K.LEAD_REVOLUTION_PHASE])


def lead_travel(c: np.ndarray, angle: float) -> tuple[float, float]:
    """Travel of a nut along the screw at the screw angle ``angle`` relative to it, ``p(T) phi / 2 pi + e(phi)``
    [m], and its rate per angle, the local lead arm ``p(T) / 2 pi + e'(phi)`` [m/rad] (the kinematics of
    :func:`twin.engine.plant._nut_kinematics` for the initial state)."""
    deviation, rate = travel_deviation(angle, c[K.LEAD_ARM_NOMINAL], c[K.LEAD_SLOPE], c[K.LEAD_WAVE_AMPLITUDE],
                                       c[K.LEAD_WAVE_NUMBER], c[K.LEAD_WAVE_PHASE], c[K.LEAD_WAVE_AT_ZERO],
                                       c[K.LEAD_REVOLUTION_AMPLITUDE], c[K.LEAD_REVOLUTION_PHASE],
                                       c[K.LEAD_REVOLUTION_AT_ZERO])
    return c[K.LEAD_ARM] * angle + deviation, c[K.LEAD_ARM] + rate


def scale_reading_gain(p: dict[str, float], room_temperature: float) -> float:
    """Travel on the linear scale per metre of sled travel: the Abbe error of the guides' angular errors
    (:func:`twin.physics.guides.abbe_reading_gain`) read on a scale expanded by the room temperature.

    A warm scale has wider graduations: ``u - u_0 = (1 + h_z kappa_p - h_y kappa_y) (x - x_0) / (1 + alpha_s (T -
    T_ref))``, with the zero at the test's start (the mounting phase, ``sensors.linear_encoder_mounting_phase``,
    places that zero within a signal period). Exactly 1 without angular errors at the reference temperature or
    with a non-expanding scale.
    """
    expansion = p["sensors.linear_encoder_thermal_expansion"] * (
        room_temperature - p["sensors.linear_encoder_reference_temperature"])
    abbe = abbe_reading_gain(p["sled.encoder_abbe_offset_vertical"], p["sled.encoder_abbe_offset_lateral"],
                             p["sled.guide_pitch_rate"], p["sled.guide_yaw_rate"])
    return abbe / (1.0 + expansion)


@lru_cache(maxsize=64)
def _hertz_stiffness_fit(ball_radius: float, pitch_radius: float, alpha_e: float, sin_min: float, conformity: float,
                         elastic_modulus: float, poisson_ratio: float, ogival_offset: float,
                         curvature: str) -> np.ndarray:
    """:func:`fit_stiffness` of the Hertz stiffness table of one screw geometry (Sec. 7.3), computed once per
    process and geometry: every run of a campaign shares it (copy before modifying)."""
    sin_grid = np.linspace(sin_min, SIN_ALPHA_MAX, STIFFNESS_FIT_POINTS)
    groove_radius = 2.0 * conformity * ball_radius
    e_star = hertz.equivalent_modulus(elastic_modulus, poisson_ratio, elastic_modulus, poisson_ratio)
    # the C library's asin, not numpy's CPU-dispatched array kernel (numerics.linalg: the same bits on every machine)
    alpha_grid = np.array([math.asin(value) for value in sin_grid.tolist()])
    stiffness = hertz.stiffness_table(alpha_grid, pitch_radius, ball_radius, groove_radius, groove_radius,
                                      alpha_e, ogival_offset, e_star, CURVATURE_FORMULAS[curvature])
    return fit_stiffness(sin_grid, stiffness)


def ball_groove_friction_constants(c: np.ndarray, p: dict[str, float], fidelity: Levels) -> None:
    """Fill the derived constants of the ball-groove friction (Eqs. 5.16-5.24, reduced:
    :mod:`twin.physics.ball_groove_friction`; its coefficients are rows of :data:`PARAMETER_CONSTANTS`) and of
    the screw's torsion between the coupling and the nuts (:func:`twin.engine.plant.screw_axial_stiffness`) at
    their fidelity levels."""
    c[K.SIN_HELIX] = math.sin(helix_angle(p["ball_screw.lead"], p["ball_screw.pitch_radius"]))
    polar_moment = math.pi * p["ball_screw.screw_root_diameter"] ** 4 / 32.0
    torsion = fidelity.level("screw_torsion") == "static"
    torsional_rigidity = p["ball_screw.shear_modulus"] * polar_moment
    c[K.SHAFT_TWIST_COMPLIANCE] = c[K.LEAD_ARM] ** 2 / torsional_rigidity if torsion else 0.0


def secant_contact_stiffness(c: np.ndarray, stiffness_poly: np.ndarray, load: float) -> float:
    """Linear normal stiffness per sphere [N/m] that gives the Hertz deflection at the axial nut load
    ``load`` [N] at the design angle: ``P / delta`` with ``delta = (P / K)^(2/3)`` (Eq. 7.28), so the
    linear contact (the elasto-backlash law of Ch. 5) is exact at the scene's peak load."""
    sin_alpha = math.sin(c[K.CONTACT_ANGLE_0])
    normal_load = load / (c[K.LOADED_BALLS] * sin_alpha * c[K.COS_HELIX])
    hertz_stiffness = stiffness_at(stiffness_poly, c[K.SIN_ALPHA_MIN], c[K.SIN_ALPHA_SPAN], sin_alpha)
    return normal_load / (normal_load / hertz_stiffness) ** (2.0 / 3.0)


def load_system_parameters(p: dict[str, float], scene: Scene) -> dict[str, float]:
    """The parameters with the load system's scene conditions: supply pressure and air (room) temperature.

    Raises
    ------
    SceneError
        If the supply pressure does not exceed the atmospheric pressure.
    """
    supply = scene.condition("supply_pressure")
    if supply <= p["pneumatics.atmospheric_pressure"]:
        raise SceneError([f"conditions.supply_pressure: {supply:g} Pa must exceed the exhaust (atmospheric) "
                          f"pressure pneumatics.atmospheric_pressure = {p['pneumatics.atmospheric_pressure']:g} Pa"])
    q = {**p, "pneumatics.supply_pressure": supply, "pneumatics.air_temperature": scene.condition("room_temperature")}
    pn.validate_pneumatics(q)
    return q


def pneumatic_constants(c: np.ndarray, p: dict[str, float], scene: Scene) -> np.ndarray:
    """Fill the load-system constants (Eqs. 9.9-9.11) and return its initial state.

    The supply pressure and the air temperature are the scene's conditions (Table 9.5 varies
    the supply from test to test); the system starts at rest at mid stroke with the valve in the
    spool position that holds zero force (the static working point of
    :func:`twin.control.force_loop_design.operating_point`).
    """
    q = load_system_parameters(p, scene)
    c[K.P_SUPPLY] = q["pneumatics.supply_pressure"]
    c[K.P_ATMOSPHERE] = q["pneumatics.atmospheric_pressure"]
    c[K.AIR_TEMPERATURE] = q["pneumatics.air_temperature"]
    c[K.GAS_CONSTANT] = q["pneumatics.gas_constant"]
    c[K.POLYTROPIC_EXPONENT] = q["pneumatics.polytropic_exponent"]
    c[K.REFERENCE_DENSITY] = q["pneumatics.reference_density"]
    c[K.REFERENCE_TEMPERATURE] = q["pneumatics.reference_temperature"]
    c[K.CRITICAL_RATIO] = q["pneumatics.critical_pressure_ratio"]
    c[K.LAMINAR_RATIO] = q["pneumatics.laminar_ratio"]
    c[K.MAX_CONDUCTANCE] = pn.conductance_from_nominal_flow(
        q["pneumatics.nominal_flow_rate"], q["pneumatics.nominal_flow_upstream_pressure"],
        q["pneumatics.nominal_flow_downstream_pressure"], c[K.CRITICAL_RATIO], c[K.LAMINAR_RATIO])
    c[K.LEAKAGE_FRACTION] = q["pneumatics.valve_leakage_fraction"]
    c[K.VALVE_MID] = q["pneumatics.valve_mid_voltage"]
    c[K.VALVE_MIN] = q["pneumatics.valve_command_min"]
    c[K.VALVE_MAX] = q["pneumatics.valve_command_max"]
    c[K.VALVE_FREQUENCY] = q["pneumatics.valve_critical_frequency"]
    c[K.VALVE_DAMPING] = q["pneumatics.valve_damping_ratio"]
    c[K.VALVE_HYSTERESIS] = q["pneumatics.valve_hysteresis"]
    c[K.AREA1], c[K.AREA2] = pn.piston_areas(q["pneumatics.bore_diameter"], q["pneumatics.rod_diameter"])
    c[K.DEAD_VOLUME1] = q["pneumatics.dead_volume_1"]
    c[K.DEAD_VOLUME2] = q["pneumatics.dead_volume_2"]
    c[K.STROKE] = q["pneumatics.stroke"]
    c[K.PISTON_MASS] = q["pneumatics.piston_mass"]
    c[K.PISTON_DAMPING] = q["pneumatics.piston_damping"]
    c[K.DAMPER_STIFFNESS] = q["pneumatics.damper_stiffness"]
    c[K.DAMPER_TRAVEL] = q["pneumatics.damper_travel"]
    c[K.DAMPER_DAMPING] = q["pneumatics.damper_damping"]
    c[K.END_STOP_STIFFNESS] = q["pneumatics.end_stop_stiffness"]
    c[K.LOAD_CELL_STIFFNESS] = q["pneumatics.load_cell_stiffness"]
    c[K.LOAD_CELL_DAMPING] = q["pneumatics.load_cell_damping"]
    c[K.FORCE_KP] = p["controller.force_kp"]
    c[K.FORCE_KI] = p["controller.force_ki"]
    working_point = operating_point(q, force=0.0)
    state = working_point["state"]
    # Zero load-cell force at the start: the rod end sits where the sled is.
    c[K.LINK_OFFSET] = state[4] - c[K.NUT1_ZERO]
    return state


def fit_stiffness(sin_grid: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """Power-series coefficients (in the normalised variable of ``stiffness_at``) of ``K(sin alpha)``.

    A least-squares fit in the Chebyshev basis (well conditioned on the grid), converted to powers. The fit is
    :func:`numerics.linalg.lstsq` rather than ``chebfit``, whose LAPACK call gives other last bits under another
    BLAS kernel: the coefficients are model constants of every run and must not depend on the machine.

    Raises
    ------
    RuntimeError
        If the fit misses any grid value by more than ``STIFFNESS_FIT_TOLERANCE``.
    """
    u = 2.0 * (sin_grid - sin_grid[0]) / (sin_grid[-1] - sin_grid[0]) - 1.0
    vander = np.polynomial.chebyshev.chebvander(u, STIFFNESS_FIT_DEGREE)
    coefficients = np.polynomial.chebyshev.cheb2poly(lstsq(np.ascontiguousarray(vander), stiffness))
    error = np.max(np.abs(np.polynomial.polynomial.polyval(u, coefficients) / stiffness - 1.0))
    if error > STIFFNESS_FIT_TOLERANCE:
        raise RuntimeError(f"contact stiffness fit error {error:.2e} exceeds {STIFFNESS_FIT_TOLERANCE:.0e}")
    return coefficients


def contact_force(c: np.ndarray, contact_model: int, relative_position: float) -> float:
    """Static axial force of the screw on one nut at relative position ``dx`` (no damping) [N], with the contact
    law ``contact_model`` (:data:`twin.physics.ball_screw.CONTACT_VARIABLE_ANGLE` ...)."""
    return nut_axial_force(relative_position, 0.0, c[K.BACKLASH], c[K.COS_HELIX], c[K.CENTRE_DISTANCE],
                           c[K.CONTACT_RADIAL_0], c[K.CONTACT_AXIAL_0], c[K.SIN_ALPHA_0],
                           c[K.STIFFNESS_C0:K.STIFFNESS_C0 + STIFFNESS_FIT_DEGREE + 1], c[K.SIN_ALPHA_MIN],
                           c[K.SIN_ALPHA_SPAN], 0.0, c[K.LOADED_BALLS], contact_model,
                           c[K.LINEAR_CONTACT_STIFFNESS])[0]


def contact_position_for_force(c: np.ndarray, contact_model: int, force: float) -> float:
    """Relative position ``dx`` at which the static contact force equals ``force`` (brentq)."""
    if force == 0.0:
        return 0.0
    side = math.copysign(1.0, force)
    half_gap = 0.5 * c[K.BACKLASH]
    upper = half_gap + 1e-6
    while abs(contact_force(c, contact_model, side * upper)) < abs(force):
        upper = half_gap + 2.0 * (upper - half_gap)
    return side * brentq(lambda d: abs(contact_force(c, contact_model, side * d)) - abs(force), half_gap, upper,
                         xtol=1e-15, rtol=1e-13)


def initial_state(c: np.ndarray, contact_model: int, preload: float, zero_procedure: str,
                  nut_rotation: str) -> np.ndarray:
    """State at t = 0 under the scene's zero procedure (:data:`twin.scenes.ZERO_PROCEDURES`); sets
    ``K.PRELOAD_COMPRESSION``.

    ``"thesis"`` (Sec. 9.3.2, "the initial conditions of the simulation consider all the elements
    unloaded"): every body at rest at its assembled position, the nuts centred in their backlash
    (the symmetric dead zone of Eqs. 5.9-5.10, ``dx_i = 0``), the disc-spring set compressed so that
    it pushes with the scene's preload at that position; the nuts are loaded during the run and the
    preload "decreases a little as the elastic deformations arise" (Fig. 9.7b), by
    ``k_pr (b + deflections)``. ``"preloaded"``: :func:`preload_equilibrium`.
    """
    if zero_procedure == "preloaded":
        return preload_equilibrium(c, contact_model, preload, nut_rotation)
    x = np.zeros(N_STATES)
    x[S.WINDING_TEMP] = c[K.AMBIENT]
    c[K.PRELOAD_COMPRESSION] = assembled_compression(c, preload)
    return x


def preload_equilibrium(c: np.ndarray, contact_model: int, preload: float, nut_rotation: str) -> np.ndarray:
    """Static equilibrium at rest with the scene's preload and no external force.

    The spring-set compression is chosen so that the preload *at equilibrium*
    equals the scene value (Secs. 9.2-9.3: the preload is set by tightening the
    caps and read on the load cell). Master nut: ``f_1 = s F_pr``; slave:
    ``f_2 = -s F_pr`` (Eq. 9.8 with ``s = +1`` for O, ``-1`` for X); screw axial
    force ``f_1 + f_2 = 0``; nut rotations balance the guides' roll stiffness (zero with rigid guides,
    the ``nut_rotation = "off"`` fidelity).
    """
    x = np.zeros(N_STATES)
    x[S.WINDING_TEMP] = c[K.AMBIENT]
    if preload <= 0.0:
        return x
    orientation = c[K.PRELOAD_ORIENTATION]
    for force, pos, ang in ((orientation * preload, S.NUT1_POSITION, S.NUT1_ANGLE),
                            (-orientation * preload, S.NUT2_POSITION, S.NUT2_ANGLE)):
        # the roll balances the contact torque through the local lead arm at the roll angle it causes: two
        # substitutions (the arm changes by e'' theta, 1e-8 of itself for the ~3 urad roll at 1 kN; 1e-16 after two)
        angle = 0.0
        if nut_rotation == "on":
            for _ in range(2):
                angle = lead_travel(c, -angle)[1] * force / c[K.GUIDE_ROLL_STIFFNESS]
        x[ang] = angle
        x[pos] = lead_travel(c, -x[ang])[0] - contact_position_for_force(c, contact_model, force)
    c[K.PRELOAD_COMPRESSION] = assembled_compression(c, preload, x[S.NUT2_POSITION] - x[S.NUT1_POSITION])
    return x
