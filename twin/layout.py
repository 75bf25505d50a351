"""The bench's vocabulary: every component's states, constants and signals, declared once.

Each component lists what it contributes (:class:`Component`): its continuous states, the model constants it reads
(with the parameter each copies, when it is one as it stands) and the signals it records, each with its SI unit
and meaning. A component with several instances (the two nuts) declares its entries once with ``{n}`` in the
name. The index layouts the compiled engine uses, :class:`S` (states), :class:`K` (constants) and :class:`Signal`,
are generated from these tables in declaration order; numba treats ``IntEnum`` members as compile-time constants,
so the compiled code reads ``x[S.NUT1_POSITION]`` at no cost. ``docs/architecture.md`` shows what adding a
component touches.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

from twin.features import FEATURES as FEATURE_TABLE
from twin.features import N_ACCUMULATORS


@dataclass(frozen=True)
class Entry:
    """A state, constant or signal: identifier (``{n}``: the instance number), SI unit, meaning (one per instance
    where there are several, so each has its own ``long_name``), and for a constant the parameter(s) it copies (one
    per instance; empty when it is derived by :func:`twin.engine.model.build_model`)."""

    name: str
    unit: str
    description: str | tuple[str, ...]
    parameter: str | tuple[str, ...] = ""

    def meaning(self, n: int) -> str:
        """The description of instance ``n`` (0-based)."""
        return self.description if isinstance(self.description, str) else self.description[n]


@dataclass(frozen=True)
class Component:
    """A part of the bench and what it contributes to the layouts."""

    name: str
    states: tuple[Entry, ...] = ()
    constants: tuple[Entry, ...] = ()
    signals: tuple[Entry, ...] = ()
    instances: int = 1


def _e(name: str, unit: str, description: str | tuple[str, ...], parameter: str | tuple[str, ...] = "") -> Entry:
    return Entry(name, unit, description, parameter)


COMPONENTS: tuple[Component, ...] = (
    Component("motor", states=(
        _e("CURRENT", "A", "motor current i (Eq. 9.1)"),
        _e("WINDING_TEMP", "K", "winding temperature T_w (Eq. 9.2)"),
    ), constants=(
        _e("R20", "ohm", "resistance of the power-consistent equivalent circuit at 20 degC, 1.5 R_UV (Eq. 9.1, "
                         "twin.physics.motor.equivalent_resistance)"),
        _e("R_TEMP_COEF", "1/K", "resistance temperature coefficient", "motor.resistance_temperature_coefficient"),
        _e("INDUCTANCE", "H", "inductance of the power-consistent equivalent circuit, 1.5 L_UV (Eq. 9.1, "
                              "twin.physics.motor.equivalent_inductance)"),
        _e("TORQUE_CONSTANT", "N m/A", "torque constant k_t, also the equivalent circuit's back-EMF constant",
           "motor.torque_constant"),
        _e("MOTOR_VISCOUS", "N m s/rad", "viscous damping b_mr on the motor shaft", "motor.viscous_damping"),
        _e("MR_FRICTION_STATIC", "N m", "motor-reducer breakaway friction", "motor.friction_static_torque"),
        _e("MR_FRICTION_DYNAMIC", "N m", "motor-reducer Coulomb friction", "motor.friction_dynamic_torque"),
        _e("MR_FRICTION_RATE", "s/rad", "motor-reducer Stribeck rate", "motor.friction_stribeck_rate"),
        _e("THERMAL_RESISTANCE", "K/W", "winding thermal resistance", "motor.thermal_resistance"),
        _e("THERMAL_TAU", "s", "winding thermal time constant", "motor.thermal_time_constant"),
        _e("HEAT_TRANSFER", "W/(m2 K)", "convective heat-transfer coefficient", "motor.heat_transfer_coefficient"),
        _e("MOTOR_AREA", "m2", "motor surface area", "motor.surface_area"),
        _e("EMISSIVITY", "1", "motor surface emissivity", "motor.emissivity"),
        _e("AMBIENT", "K", "room temperature (scene condition)"),
        _e("MAX_CURRENT", "A", "drive/motor maximum current", "motor.max_current"),
    ), signals=(
        _e("MOTOR_CURRENT", "A", "motor current (Eq. 9.1)"),
        _e("MOTOR_TORQUE", "N m", "motor electromagnetic torque k_t*i"),
        _e("MOTOR_SPEED", "rad/s", "motor shaft speed"),
        _e("WINDING_TEMPERATURE", "K", "winding temperature (Eq. 9.2)"),
    )),
    Component("reducer", states=(
        _e("REDUCER_ANGLE", "rad", "reducer output angle theta_r (Eq. 9.3)"),
        _e("REDUCER_SPEED", "rad/s", "reducer output speed"),
    ), constants=(
        _e("RATIO", "1", "reduction ratio tau_mr", "reducer.ratio"),
        _e("EFFICIENCY", "1", "reducer efficiency", "reducer.efficiency"),
        _e("J_MOTOR_SIDE", "kg m2", "motor and reducer inertia about the reducer output, (J_m + J_r) tau^2"),
        _e("REDUCER_BACKLASH", "rad", "torsional play of the reducer", "reducer.backlash"),
        _e("TORSION_STIFFNESS", "N m/rad", "series torsional stiffness of reducer, couplings and torque meter"),
        _e("TORSION_DAMPING", "N m s/rad", "torsional damping of the chain", "drivetrain.damping"),
    ), signals=(
        _e("TRANSMITTED_TORQUE", "N m", "torque through couplings and torque meter T_tm"),
    )),
    Component("screw", states=(
        _e("SCREW_ANGLE", "rad", "screw angle theta_s (Eq. 9.7)"),
        _e("SCREW_SPEED", "rad/s", "screw speed"),
        _e("SCREW_AXIAL", "m", "screw axial displacement x_s"),
        _e("SCREW_AXIAL_SPEED", "m/s", "screw axial speed"),
    ), constants=(
        _e("J_SCREW_SIDE", "kg m2", "screw-side inertia J_s + J_tm + 2 J_tc (Eq. 9.7)"),
        _e("SCREW_DAMPING", "N m s/rad", "screw rotational damping", "ball_screw.screw_rotational_damping"),
        _e("SCREW_FRICTION_STATIC", "N m", "support bearings' breakaway friction",
           "ball_screw.bearing_friction_static_torque"),
        _e("SCREW_FRICTION_DYNAMIC", "N m", "support bearings' Coulomb friction",
           "ball_screw.bearing_friction_dynamic_torque"),
        _e("SCREW_FRICTION_RATE", "s/rad", "support bearings' Stribeck rate",
           "ball_screw.bearing_friction_stribeck_rate"),
        _e("SCREW_FRICTION_VISCOUS", "N m s/rad", "support bearings' viscous friction",
           "ball_screw.bearing_viscous_friction"),
        _e("SCREW_MASS", "kg", "screw shaft mass"),
        _e("BEARING_STIFFNESS", "N/m", "rear bearing axial stiffness", "ball_screw.rear_bearing_axial_stiffness"),
        _e("SHAFT_EA", "N", "shaft axial rigidity E A"),
        _e("SHAFT_LENGTH_0", "m", "rear bearing to nut distance at zero stroke", "ball_screw.bearing_to_nut_distance"),
        _e("SCREW_AXIAL_DAMPING", "N s/m", "screw axial damping", "ball_screw.screw_axial_damping"),
        _e("SHAFT_TWIST_COMPLIANCE", "1/N", "(p/2pi)^2 / (G J_p): the shaft twist as an axial compliance per length"),
    ), signals=(
        _e("SCREW_ANGLE", "rad", "screw shaft angle"),
        _e("SCREW_EQUIVALENT_POSITION", "m", "screw equivalent linear position p*theta_s/(2*pi) (Eq. 9.12)"),
        _e("SCREW_AXIAL_POSITION", "m", "screw shaft axial displacement"),
        _e("SCREW_TWIST", "rad", "torsion of the screw shaft between the coupling and the master nut"),
    )),
    Component("nut", instances=2, states=(
        _e("NUT{n}_POSITION", "m", ("master nut (nut 1, the sled) translation x_n1 (Eq. 9.8)",
                                    "slave nut (nut 2) translation x_n2 (Eq. 9.8)")),
        _e("NUT{n}_SPEED", "m/s", ("master nut (nut 1) speed", "slave nut (nut 2) speed")),
        _e("NUT{n}_ANGLE", "rad", ("master nut (nut 1) roll angle on the guides theta_n1",
                                   "slave nut (nut 2) roll angle on the guides theta_n2")),
        _e("NUT{n}_ANGULAR_SPEED", "rad/s", ("master nut (nut 1) roll speed", "slave nut (nut 2) roll speed")),
    ), constants=(
        _e("NUT{n}_MASS", "kg", ("translating mass of the master nut (nut 1) and the sled it carries",
                                 "translating mass of the slave nut (nut 2)"),
           ("sled.master_mass", "sled.slave_mass")),
        _e("NUT{n}_GUIDE_FRICTION_SHARE", "1", ("share of the guide friction law the master nut carries (1)",
                                               "share of the guide friction law the slave nut carries")),
    ), signals=(
        _e("NUT{n}_POSITION", "m", ("master nut (nut 1, the sled) position", "slave nut (nut 2) position")),
        _e("NUT{n}_CONTACT_FORCE", "N", ("axial contact force of the screw on the master nut (nut 1)",
                                         "axial contact force of the screw on the slave nut (nut 2)")),
    )),
    Component("guides", constants=(
        _e("J_NUT", "kg m2", "nut rotational inertia", "sled.nut_rotational_inertia"),
        _e("GUIDE_ROLL_STIFFNESS", "N m/rad", "guides' roll stiffness", "sled.guide_roll_stiffness"),
        _e("GUIDE_ROLL_DAMPING", "N m s/rad", "guides' roll damping", "sled.guide_roll_damping"),
        _e("GUIDE_FRICTION_STATIC", "N", "guide breakaway friction", "sled.guide_friction_static"),
        _e("GUIDE_FRICTION_DYNAMIC", "N", "guide Coulomb friction", "sled.guide_friction_dynamic"),
        _e("GUIDE_FRICTION_RATE", "s/m", "guide Stribeck rate", "sled.guide_friction_stribeck_rate"),
        _e("GUIDE_FRICTION_VISCOUS", "N s/m", "guide viscous friction", "sled.guide_viscous_friction"),
        _e("STROKE_LIMIT", "m", "sled stroke limit (divergence guard)", "sled.stroke_limit"),
    ), signals=(
        _e("NUT1_SPEED", "m/s", "master nut (sled) speed"),
    )),
    Component("ball_screw_contact", constants=(
        _e("LEAD_ARM", "m/rad", "p(T) / (2 pi): the lead of the screw at the room temperature (Eq. 7.72)"),
        _e("LEAD_ARM_NOMINAL", "m/rad", "p / (2 pi) of the nominal lead: Eq. 9.12's screw equivalent position"),
        _e("COS_HELIX", "1", "cos(alpha_e)"),
        _e("SIN_HELIX", "1", "sin(alpha_e)"),
        _e("CENTRE_DISTANCE", "m", "A0, distance of the groove curvature centres at first contact (Eq. 9.4)"),
        _e("CONTACT_ANGLE_0", "rad", "design contact angle alpha_0", "ball_screw.contact_angle"),
        _e("CONTACT_RADIAL_0", "m", "A0 cos(alpha_0)"),
        _e("CONTACT_AXIAL_0", "m", "A0 sin(alpha_0)"),
        _e("SIN_ALPHA_0", "1", "sin(alpha_0)"),
        _e("SIN_ALPHA_MIN", "1", "lower end of the stiffness fit's sin(alpha) range"),
        _e("SIN_ALPHA_SPAN", "1", "width of the stiffness fit's sin(alpha) range"),
        *(_e(f"STIFFNESS_C{k}", "N/m^1.5", f"coefficient {k} of the series Hertz stiffness fit K(sin alpha)")
          for k in range(7)),
        _e("CONTACT_DAMPING", "s/m^0.25", "contact damping b_h (Eq. 7.54)", "ball_screw.contact_damping_coefficient"),
        _e("LOADED_BALLS", "1", "loaded spheres Z_eff (Eq. 5.5)"),
        _e("BACKLASH", "m", "axial backlash of each nut (scene condition)"),
        _e("LINEAR_CONTACT_STIFFNESS", "N/m", "normal stiffness per sphere of the linear contact level"),
        _e("MAX_NORMAL_APPROACH", "m", "Hertzian validity bound of the normal approach (divergence guard)"),
    )),
    Component("lead_error", constants=(
        # the screw's travel deviation e(phi) of ISO 3408-3 (twin.physics.ball_screw.travel_deviation)
        _e("LEAD_SLOPE", "1", "mean travel deviation per unit travel s", "ball_screw.lead_mean_deviation_slope"),
        _e("LEAD_WAVE_AMPLITUDE", "m", "amplitude a_u of the long-wave travel variation",
           "ball_screw.lead_travel_variation_amplitude"),
        _e("LEAD_WAVE_NUMBER", "1/rad", "phase of the long-wave variation per rad of screw angle, p / lambda_u"),
        _e("LEAD_WAVE_PHASE", "rad", "phase phi_u of the long-wave variation at the test zero",
           "ball_screw.lead_travel_variation_phase"),
        _e("LEAD_WAVE_AT_ZERO", "1", "sin(phi_u): the long-wave term at the test zero, subtracted"),
        _e("LEAD_REVOLUTION_AMPLITUDE", "m", "amplitude of the nut's travel variation within one revolution: a_2pi "
                                             "averaged over the nut's balls (twin.engine.model.lead_constants)"),
        _e("LEAD_REVOLUTION_PHASE", "rad", "phase phi_2pi of the per-revolution variation at the test zero",
           "ball_screw.lead_per_revolution_phase"),
        _e("LEAD_REVOLUTION_AT_ZERO", "1", "sin(phi_2pi): the per-revolution term at the test zero, subtracted"),
    )),
    Component("ball_groove_friction", constants=(
        *(_e(f"FRICTION_G{k}", unit, f"Eq. 5.16 coefficient g_{k}", f"ball_screw.sliding_friction_g{k}")
          for k, unit in ((1, "1"), (2, "s/m"), (3, "s/m"), (4, "1"), (5, "s/m"), (6, "s/m"))),
        _e("ROLLING_K_GC", "m/N^0.26", "rolling load coefficient (Eqs. 5.20-5.23)",
           "ball_screw.rolling_friction_load_coefficient"),
        _e("ROLLING_K_RF", "1", "rolling friction multiplier k_rf", "ball_screw.rolling_friction_multiplier"),
        _e("ROLLING_F_V1", "s2", "rolling speed coefficient (Eqs. 5.19/5.21)",
           "ball_screw.rolling_friction_speed_coefficient"),
        _e("ROLLING_THRESHOLD", "m/s", "direction regularisation of the rolling term",
           "ball_screw.rolling_friction_direction_threshold"),
        _e("BALL_RADIUS", "m", "ball radius r_b", "ball_screw.ball_radius"),
        _e("PITCH_RADIUS", "m", "pitch radius r_m", "ball_screw.pitch_radius"),
    ), signals=(
        _e("BALL_GROOVE_FRICTION_TORQUE", "N m", "ball-groove friction torque opposing the screw rotation, both nuts "
                                                 "(Eqs. 5.16-5.24; the drag torque, Eq. 7.85, without external force)"),
        _e("BALL_SCREW_EFFICIENCY", "1", "ball-screw mechanical efficiency (Eq. 5.25): P_out/P_in driving, "
                                         "-P_in/P_out back-driving, 0 at rest or when both powers enter"),
    )),
    Component("preload", constants=(
        _e("PRELOAD_STIFFNESS", "N/m", "disc springs in series with the preload load cell"),
        _e("PRELOAD_DAMPING", "N s/m", "preload damping"),
        _e("PRELOAD_COMPRESSION", "m", "spring-set compression at the assembled position"),
        _e("PRELOAD_ORIENTATION", "1", "+1: O configuration (nuts pushed apart), -1: X"),
    ), signals=(
        _e("PRELOAD_FORCE", "N", "preload force between the nuts"),
    )),
    Component("drive", states=(
        _e("HALL_CURRENT", "A", "first-order Hall sensor output"),
        _e("CURRENT_PI", "V", "analog current-PI integrator"),
    ), constants=(
        _e("VOLTAGE_LIMIT", "V", "largest voltage the inverter applies to the equivalent circuit, "
                                 "(3/sqrt 2) m_max V_DC (twin.physics.motor.equivalent_voltage_limit)"),
        _e("HALL_TAU", "s", "Hall sensor time constant", "drive.hall_time_constant"),
        _e("CURRENT_AW_TIME", "s", "current-PI anti-windup time", "drive.current_antiwindup_time"),
        _e("CURRENT_KP", "V/A", "current-PI proportional gain", "controller.current_kp"),
        _e("CURRENT_KI", "V/(A s)", "current-PI integral gain", "controller.current_ki"),
        _e("CURRENT_LOOP_TAU", "s", "time constant of the ideal current loop, 1 / (2 pi bandwidth)"),
        _e("SPEED_KP", "A s/rad", "speed-PI proportional gain", "controller.speed_kp"),
        _e("SPEED_KI", "A/rad", "speed-PI integral gain", "controller.speed_ki"),
        _e("SPEED_FULL_SCALE", "rad/s", "speed command full scale", "drive.speed_command_full_scale"),
        _e("SPEED_COMMAND_BITS", "1", "word length (sign incl.) of the drive's analog speed input; 0 = not quantised"),
        _e("MAX_MOTOR_SPEED", "rad/s", "guard: twice the motor's maximum permissible speed"),
        _e("MAX_TEMPERATURE", "K", "guard: winding temperature limit"),
    ), signals=(
        _e("SPEED_COMMAND", "rad/s", "motor speed command after the drive's analog input"),
        _e("CURRENT_DEMAND", "A", "current demand of the speed loop"),
    )),
    Component("position_loop", constants=(
        _e("POSITION_KP", "rad/(s m)", "position-PI proportional gain", "controller.position_kp"),
        _e("POSITION_KI", "rad/(s2 m)", "position-PI integral gain", "controller.position_ki"),
        _e("NUT1_ZERO", "m", "sled position at which the encoders are zeroed"),
        _e("SCREW_ANGLE_ZERO", "rad", "screw angle at which the encoders are zeroed"),
        _e("ENCODER_SCALE_ORIGIN", "m", "scale position of the sled at t = 0", "sensors.linear_encoder_scale_origin"),
        _e("SCALE_READING_GAIN", "1", "scale travel per metre of sled travel: the Abbe error of the guides' angular "
                                      "errors over the thermal expansion of the scale (twin.engine.model)"),
        _e("LINEAR_V_THRESHOLD", "m/s", "sign regularisation of the linear friction laws"),
        _e("ANGULAR_V_THRESHOLD", "rad/s", "sign regularisation of the angular friction laws"),
    ), signals=(
        _e("POSITION_DEMAND", "m", "sled position demand"),
    )),
    Component("valve", states=(
        _e("SPOOL_POSITION", "1", "normalised valve spool position [-1, 1]"),
        _e("SPOOL_SPEED", "1/s", "spool speed"),
    ), constants=(
        _e("VALVE_MID", "V", "valve mid-position command", "pneumatics.valve_mid_voltage"),
        _e("VALVE_MIN", "V", "lowest valve command"),
        _e("VALVE_MAX", "V", "highest valve command"),
        _e("VALVE_FREQUENCY", "Hz", "spool critical frequency"),
        _e("VALVE_DAMPING", "1", "spool damping ratio"),
        _e("VALVE_HYSTERESIS", "1", "valve hysteresis, fraction of the command span"),
        _e("VALVE_COMMAND_BITS", "1", "word length (sign incl.) of the valve-command D/A; 0 = not quantised"),
        _e("FORCE_KP", "V/N", "force-PI proportional gain", "controller.force_kp"),
        _e("FORCE_KI", "V/(N s)", "force-PI integral gain", "controller.force_ki"),
        _e("FORCE_FEEDBACK_NOISE", "1", "1: the force loop reads the load cell with its electrical noise "
                                        "(scene noise_path = feedback); 0: without it (recorded)"),
    ), signals=(
        _e("FORCE_DEMAND", "N", "external force demand"),
        _e("VALVE_COMMAND", "V", "effective proportional-valve command"),
    )),
    Component("cylinder", states=(
        _e("CHAMBER1_PRESSURE", "Pa", "cap-side chamber pressure, absolute"),
        _e("CHAMBER2_PRESSURE", "Pa", "rod-side chamber pressure, absolute"),
        _e("PISTON_POSITION", "m", "piston position from the cap-end stop"),
        _e("PISTON_SPEED", "m/s", "piston speed"),
    ), constants=(
        *(_e(name, unit, description) for name, unit, description in (
            ("P_SUPPLY", "Pa", "supply pressure (scene condition)"), ("P_ATMOSPHERE", "Pa", "exhaust pressure"),
            ("AIR_TEMPERATURE", "K", "air temperature (the room's)"), ("GAS_CONSTANT", "J/(kg K)", "air gas constant"),
            ("POLYTROPIC_EXPONENT", "1", "polytropic exponent"), ("REFERENCE_DENSITY", "kg/m3", "ISO 6358 rho_0"),
            ("REFERENCE_TEMPERATURE", "K", "ISO 6358 T_0"), ("MAX_CONDUCTANCE", "m3/(s Pa)", "fully open conductance"),
            ("LEAKAGE_FRACTION", "1", "centre leakage fraction"), ("CRITICAL_RATIO", "1", "critical pressure ratio b"),
            ("LAMINAR_RATIO", "1", "laminar band ratio"), ("AREA1", "m2", "cap-side area"),
            ("AREA2", "m2", "rod-side area"),
            ("DEAD_VOLUME1", "m3", "cap-side dead volume"), ("DEAD_VOLUME2", "m3", "rod-side dead volume"),
            ("STROKE", "m", "cylinder stroke"), ("PISTON_MASS", "kg", "piston, rod, rod end and load cell"),
            ("PISTON_DAMPING", "N s/m", "piston damping"), ("CYLINDER_FRICTION_STATIC", "N", "seal breakaway friction"),
            ("CYLINDER_FRICTION_DYNAMIC", "N", "seal Coulomb friction"),
            ("CYLINDER_FRICTION_RATE", "s/m", "seal Stribeck rate"),
            ("CYLINDER_FRICTION_VISCOUS", "N s/m", "seal viscous friction"),
            ("CYLINDER_V_THRESHOLD", "m/s", "seal friction sign regularisation"),
            ("DAMPER_STIFFNESS", "N/m", "end-stroke damper stiffness"), ("DAMPER_TRAVEL", "m", "damper travel"),
            ("DAMPER_DAMPING", "N s/m", "damper damping"), ("END_STOP_STIFFNESS", "N/m", "end-stop stiffness"),
            ("LOAD_CELL_STIFFNESS", "N/m", "external load cell stiffness"),
            ("LOAD_CELL_DAMPING", "N s/m", "external load cell damping"),
            ("LINK_OFFSET", "m", "piston position minus sled position at zero load-cell force"))),
    ), signals=(
        _e("EXTERNAL_FORCE", "N", "external force on the master nut"),
        _e("CHAMBER1_PRESSURE", "Pa", "cylinder cap-side chamber pressure (absolute)"),
        _e("CHAMBER2_PRESSURE", "Pa", "cylinder rod-side chamber pressure (absolute)"),
        _e("PISTON_POSITION", "m", "piston position from the cap-end stop"),
    )),
    Component("seal", states=(
        _e("SEAL_DEFLECTION", "m", "presliding deflection z of the cylinder seals (the elasto-plastic seal-friction "
                                   "level, twin.physics.bristle_friction)"),
    ), constants=(
        _e("SEAL_STIFFNESS", "N/m", "seals' presliding stiffness sigma_0", "pneumatics.friction_presliding_stiffness"),
        _e("SEAL_DAMPING", "N s/m", "seals' presliding damping sigma_1", "pneumatics.friction_bristle_damping"),
        _e("SEAL_DAMPING_SPEED", "m/s", "speed v_d above which the presliding damping fades",
           "pneumatics.friction_bristle_damping_speed"),
        _e("SEAL_ELASTIC_DEFLECTION", "m", "z_ba: deflection up to which the seals are purely elastic, "
                                           "friction_elastic_fraction F_d / sigma_0"),
    )),
    Component("instruments", signals=(
        # measured signals, held at their last acquisition sample (twin.engine.instrumentation)
        _e("LINEAR_ENCODER_POSITION", "m", "sled position read by the linear encoder (zeroed at t = 0)"),
        _e("SCREW_ANGLE_MEASURED", "rad", "screw angle read by the torque-meter encoder (zeroed at t = 0)"),
        _e("NUT_SPEED_MEASURED", "m/s", "sled speed from the linear encoder (period/frequency method)"),
        _e("MOTOR_SPEED_MEASURED", "rad/s", "motor speed estimated by the drive from the resolver"),
        _e("MOTOR_CURRENT_MEASURED", "A", "motor current acquired through the current monitor"),
        _e("TORQUE_MEASURED", "N m", "torque-meter reading"),
        _e("PRELOAD_FORCE_MEASURED", "N", "preload load-cell reading"),
        _e("EXTERNAL_FORCE_MEASURED", "N", "external-force load-cell reading"),
    )),
)


def _expanded(kind: str) -> list[tuple[Entry, int]]:
    """Every entry of ``kind`` ("states", "constants", "signals") with its instance (0-based), in declaration order."""
    return [(entry, n) for component in COMPONENTS for n in range(component.instances)
            for entry in getattr(component, kind)]


def _layout(name: str, kind: str) -> type[IntEnum]:
    names = [entry.name.format(n=n + 1) for entry, n in _expanded(kind)]
    duplicates = sorted({x for x in names if names.count(x) > 1})
    if duplicates:
        raise ImportError(f"twin.layout: {kind} declared twice: {', '.join(duplicates)}")
    return IntEnum(name, {entry: k for k, entry in enumerate(names)})


S = _layout("S", "states")
S.__doc__ = "Continuous state vector (SI units), generated from :data:`COMPONENTS`."
K = _layout("K", "constants")
K.__doc__ = "Model constants (SI units), generated from :data:`COMPONENTS`; built by twin.engine.model."
Signal = _layout("Signal", "signals")
Signal.__doc__ = "Recorded output signals (one column each in the output buffer), generated from :data:`COMPONENTS`."

N_STATES = len(S)
N_CONSTANTS = len(K)
N_SIGNALS = len(Signal)

#: Unit and meaning of every state, constant and signal (``{layout member: (unit, description)}``).
STATE_META = {S[entry.name.format(n=n + 1)]: (entry.unit, entry.meaning(n)) for entry, n in _expanded("states")}
CONSTANT_META = {K[entry.name.format(n=n + 1)]: (entry.unit, entry.meaning(n)) for entry, n in _expanded("constants")}
SIGNAL_META = {Signal[entry.name.format(n=n + 1)]: (entry.unit, entry.meaning(n)) for entry, n in _expanded("signals")}

#: The model constants that are a parameter's value as it stands (``{K member: parameter name}``): the plain part of
#: the parameter -> model mapping, derived from the declarations. The others are computed by
#: :func:`twin.engine.model.build_model` (formulas, fidelity levels, scene conditions).
PARAMETER_CONSTANTS: dict = {
    K[entry.name.format(n=n + 1)]: (entry.parameter if isinstance(entry.parameter, str) else entry.parameter[n])
    for entry, n in _expanded("constants") if entry.parameter}

#: Per-nut strides: nut ``i``'s state (constant) is its first nut's member plus ``i * NUT_STATE_STRIDE``
#: (``i * NUT_CONSTANT_STRIDE``).
NUT_STATE_STRIDE = S.NUT2_POSITION - S.NUT1_POSITION
NUT_CONSTANT_STRIDE = K.NUT2_MASS - K.NUT1_MASS

# (position, velocity) pairs: the semi-implicit Euler integrator updates the
# velocity first and moves the position with the new velocity.
POSITION_VELOCITY_PAIRS = (
    (S.REDUCER_ANGLE, S.REDUCER_SPEED),
    (S.SCREW_ANGLE, S.SCREW_SPEED),
    (S.SCREW_AXIAL, S.SCREW_AXIAL_SPEED),
    (S.NUT1_POSITION, S.NUT1_SPEED),
    (S.NUT1_ANGLE, S.NUT1_ANGULAR_SPEED),
    (S.NUT2_POSITION, S.NUT2_SPEED),
    (S.NUT2_ANGLE, S.NUT2_ANGULAR_SPEED),
    (S.PISTON_POSITION, S.PISTON_SPEED),
)


class U(IntEnum):
    """Inputs held between controller samples (zero-order hold)."""

    CURRENT_DEMAND = 0     # speed-loop output [A]
    VALVE_COMMAND = 1      # effective valve command after D/A and hysteresis [V]


N_INPUTS = len(U)

# Scalar features of a run (twin.features), computed by the loop alongside the signals.
FEATURES = tuple(FEATURE_TABLE)
# Everything a scene or a campaign may ask a run to produce.
OUTPUT_NAMES = tuple(signal.name.lower() for signal in Signal) + FEATURES


class M(IntEnum):
    """Memory of the digital loops and the acquisition between samples."""

    POSITION_INTEGRAL = 0
    SPEED_INTEGRAL = 1
    FORCE_INTEGRAL = 2
    SPEED_COMMAND = 3       # after the drive's analog input [rad/s]
    PREVIOUS_ANGLE = 4      # resolver reading at the previous speed sample [rad]
    DEMAND = 5              # position demand at the last acquisition [m]
    SAMPLES = 6             # acquisition samples taken
    # last acquired readings, in the order of Signal.LINEAR_ENCODER_POSITION ...
    SLED = 7
    SCREW_ANGLE = 8
    SLED_SPEED = 9
    MOTOR_SPEED = 10
    CURRENT = 11
    TORQUE = 12
    PRELOAD = 13
    EXTERNAL = 14
    FORCE_FEEDBACK = 15     # the load-cell reading the force loop acts on [N] (scene condition noise_path)
    LOCAL_ERROR = 16        # largest step-doubling local-error estimate so far, in tolerance units
    LOCAL_ERROR_STREAK = 17  # consecutive acquisition instants with the estimate above tolerance
    # feature accumulators (layout twin.features.A), from true and from measured signals
    FEATURES_TRUE = 18
    FEATURES_MEASURED = 18 + N_ACCUMULATORS


N_MEMORY = M.FEATURES_MEASURED + N_ACCUMULATORS
N_MEASURED = M.EXTERNAL - M.SLED + 1

# Run status codes returned by the compiled loop.
STATUS_OK = 0
STATUS_NONFINITE = 1
STATUS_OUT_OF_BOUNDS = 2
STATUS_SOLVER_FAILED = 3  # the scipy reference path's solver gave up
STATUS_TEXT = {STATUS_OK: "ok", STATUS_NONFINITE: "diverged", STATUS_OUT_OF_BOUNDS: "diverged",
               STATUS_SOLVER_FAILED: "failed"}

# Bound codes (which physical bound the guard tripped on).
BOUND_REASONS = {
    0: "",
    1: "non-finite state (NaN/inf)",
    2: "sled beyond the stroke limit",
    3: "motor speed beyond twice the maximum permissible speed",
    4: "motor current beyond five times the drive/motor maximum",
    5: "winding temperature beyond 200 degC",
    6: "ball-groove normal approach beyond the Hertzian validity bound",
    7: "chamber pressure outside [0, 2 x supply] (absolute)",
    8: "finite but wrong: the step-doubling local-error estimate exceeds its tolerance (step beyond stability)",
    9: "the quasi-static screw-axial balance did not converge",
}
