"""Index layouts shared by the model builder and the compiled loop.

numba treats ``IntEnum`` members as compile-time integer constants, so the
compiled right-hand side reads ``x[S.NUT1_POSITION]`` at no cost.
"""

from enum import IntEnum

from twin.features import FEATURES as FEATURE_TABLE
from twin.features import N_ACCUMULATORS


class S(IntEnum):
    """Continuous state vector (SI units)."""

    CURRENT = 0            # motor current i [A] (Eq. 9.1)
    WINDING_TEMP = 1       # T_w [K] (Eq. 9.2)
    REDUCER_ANGLE = 2      # theta_r [rad] (Eq. 9.3)
    REDUCER_SPEED = 3
    SCREW_ANGLE = 4        # theta_s [rad] (Eq. 9.7)
    SCREW_SPEED = 5
    SCREW_AXIAL = 6        # x_s [m]
    SCREW_AXIAL_SPEED = 7
    NUT1_POSITION = 8      # x_n1 [m] (Eq. 9.8, master)
    NUT1_SPEED = 9
    NUT1_ANGLE = 10        # theta_n1 [rad]
    NUT1_ANGULAR_SPEED = 11
    NUT2_POSITION = 12     # x_n2 [m] (slave)
    NUT2_SPEED = 13
    NUT2_ANGLE = 14
    NUT2_ANGULAR_SPEED = 15
    HALL_CURRENT = 16      # first-order Hall sensor output [A]
    CURRENT_PI = 17        # analog current-PI integrator [V]
    # pneumatic load system (Eqs. 9.9-9.11), integrated only at the "full" pneumatics fidelity
    SPOOL_POSITION = 18    # normalised valve spool position [-1, 1]
    SPOOL_SPEED = 19
    CHAMBER1_PRESSURE = 20  # cap side [Pa, absolute]
    CHAMBER2_PRESSURE = 21  # rod side
    PISTON_POSITION = 22   # from the cap-end stop [m]
    PISTON_SPEED = 23


N_STATES = len(S)
# A fidelity level can remove states (twin.fidelity): the integrators then advance only the
# model's ``active`` indices; the others hold a fixed value (the frozen temperature, a rigid
# guide's zero roll angle) and the right-hand side does not compute their derivatives.

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

# Pneumatics fidelity codes (constant K.PNEUMATICS).
PNEUMATICS_ABSENT = 0      # no external force at all
PNEUMATICS_IDEAL = 1       # ideal force source following the scene's force demand
PNEUMATICS_FULL = 2        # valve, chambers, piston and load cell under the force loop
PNEUMATICS_LEVELS = {"absent": PNEUMATICS_ABSENT, "ideal": PNEUMATICS_IDEAL, "full": PNEUMATICS_FULL}


class K(IntEnum):
    """Model constants, derived from the parameter set and the scene (SI units)."""

    # motor and drive
    R20 = 0
    R_TEMP_COEF = 1
    INDUCTANCE = 2
    TORQUE_CONSTANT = 3
    SPEED_CONSTANT = 4
    RATIO = 5
    EFFICIENCY = 6
    J_MOTOR_SIDE = 7          # J_mr tau^2, about the reducer output [kg m^2]
    MOTOR_VISCOUS = 8         # b_mr on the motor shaft
    MR_FRICTION_STATIC = 9
    MR_FRICTION_DYNAMIC = 10
    MR_FRICTION_RATE = 11
    DC_BUS = 12
    HALL_TAU = 13
    CURRENT_KP = 14
    CURRENT_KI = 15
    CURRENT_AW_TIME = 16
    THERMAL_RESISTANCE = 17
    THERMAL_TAU = 18
    HEAT_TRANSFER = 19
    MOTOR_AREA = 20
    EMISSIVITY = 21
    AMBIENT = 22
    # torsional chain
    TORSION_STIFFNESS = 23
    TORSION_DAMPING = 24
    REDUCER_BACKLASH = 25
    J_SCREW_SIDE = 26         # J_s + J_tm + 2 J_tc (Eq. 9.7)
    SCREW_DAMPING = 27
    SCREW_FRICTION_STATIC = 28
    SCREW_FRICTION_DYNAMIC = 29
    SCREW_FRICTION_RATE = 30
    SCREW_FRICTION_VISCOUS = 31
    # screw axial
    SCREW_MASS = 32
    BEARING_STIFFNESS = 33
    SHAFT_EA = 34
    SHAFT_LENGTH_0 = 35
    SCREW_AXIAL_DAMPING = 36
    # ball screw contact
    LEAD_ARM = 37             # p / (2 pi)
    COS_HELIX = 38
    CENTRE_DISTANCE = 39
    CONTACT_ANGLE_0 = 40
    SIN_ALPHA_MIN = 41
    SIN_ALPHA_SPAN = 42
    CONTACT_DAMPING = 43
    LOADED_BALLS = 44
    BACKLASH = 45
    CONTACT_MODEL = 46        # CONTACT_* code below (fidelity "contact")
    # nuts and guides
    MASS_NUT1 = 47
    MASS_NUT2 = 48
    J_NUT = 49
    GUIDE_ROLL_STIFFNESS = 50
    GUIDE_ROLL_DAMPING = 51
    GUIDE_FRICTION_STATIC = 52
    GUIDE_FRICTION_DYNAMIC = 53
    GUIDE_FRICTION_RATE = 54
    GUIDE_FRICTION_VISCOUS = 55
    SLAVE_FRICTION_FRACTION = 56
    # preload
    PRELOAD_STIFFNESS = 57
    PRELOAD_DAMPING = 58
    PRELOAD_COMPRESSION = 59
    PRELOAD_ORIENTATION = 60
    # friction regularisation
    LINEAR_V_THRESHOLD = 61
    ANGULAR_V_THRESHOLD = 62
    # digital loops
    SPEED_KP = 63
    SPEED_KI = 64
    MAX_CURRENT = 65
    POSITION_KP = 66
    POSITION_KI = 67
    SPEED_FULL_SCALE = 68
    SPEED_COMMAND_BITS = 69   # word length (sign incl.) of the drive's analog speed input; 0 = not quantised
    VALVE_COMMAND_BITS = 70   # word length (sign incl.) of the valve-command D/A; 0 = not quantised
    # divergence guard
    STROKE_LIMIT = 71
    MAX_MOTOR_SPEED = 72
    MAX_TEMPERATURE = 73
    MAX_NORMAL_APPROACH = 74
    # feature zeroing
    NUT1_ZERO = 75
    SCREW_ANGLE_ZERO = 76
    # pneumatic load system (Eqs. 9.9-9.11, Tables B.11-B.13, pneumatics.toml)
    PNEUMATICS = 77
    P_SUPPLY = 78
    P_ATMOSPHERE = 79
    AIR_TEMPERATURE = 80
    GAS_CONSTANT = 81
    POLYTROPIC_EXPONENT = 82
    REFERENCE_DENSITY = 83
    REFERENCE_TEMPERATURE = 84
    MAX_CONDUCTANCE = 85
    LEAKAGE_FRACTION = 86
    CRITICAL_RATIO = 87
    LAMINAR_RATIO = 88
    VALVE_MID = 89
    VALVE_MIN = 90
    VALVE_MAX = 91
    VALVE_FREQUENCY = 92
    VALVE_DAMPING = 93
    VALVE_HYSTERESIS = 94
    AREA1 = 95
    AREA2 = 96
    DEAD_VOLUME1 = 97
    DEAD_VOLUME2 = 98
    STROKE = 99
    PISTON_MASS = 100
    PISTON_DAMPING = 101
    CYLINDER_FRICTION_STATIC = 102
    CYLINDER_FRICTION_DYNAMIC = 103
    CYLINDER_FRICTION_RATE = 104
    CYLINDER_FRICTION_VISCOUS = 105
    CYLINDER_V_THRESHOLD = 106
    DAMPER_STIFFNESS = 107
    DAMPER_TRAVEL = 108
    DAMPER_DAMPING = 109
    END_STOP_STIFFNESS = 110
    LOAD_CELL_STIFFNESS = 111
    LOAD_CELL_DAMPING = 112
    LINK_OFFSET = 113         # piston position minus sled position at zero load-cell force [m]
    FORCE_KP = 114
    FORCE_KI = 115

    ENCODER_SCALE_ORIGIN = 116  # m, scale position of the sled at t = 0 (sensors.linear_encoder_scale_origin)
    # fidelity levels of the plant (twin.fidelity)
    THERMAL_DYNAMIC = 117     # 1.0 = Eq. 9.2 integrated, 0.0 = winding frozen at the start temperature
    CURRENT_LOOP_FULL = 118   # 1.0 = RL winding, Hall sensor and analog PI; 0.0 = ideal torque source
    CURRENT_LOOP_TAU = 119    # s, time constant of the ideal current loop (1 / (2 pi bandwidth))
    NUT_ROTATION = 120        # 1.0 = nut roll on the guides integrated, 0.0 = rigid guides
    LINEAR_CONTACT_STIFFNESS = 121  # N/m per sphere along the normal, the "linear" contact level
    # ball-groove friction of the reduced Ch. 5 model (twin.physics.ball_groove_friction)
    BALL_GROOVE_FRICTION = 122  # BALL_GROOVE_FRICTION_* code below (fidelity "ball_groove_friction")
    FRICTION_G1 = 123         # Eq. 5.16 coefficients g_1 ... g_6
    FRICTION_G2 = 124
    FRICTION_G3 = 125
    FRICTION_G4 = 126
    FRICTION_G5 = 127
    FRICTION_G6 = 128
    ROLLING_K_GC = 129        # m/N^0.26, Eqs. 5.20-5.23
    ROLLING_K_RF = 130        # friction multiplier k_rf
    ROLLING_F_V1 = 131        # s^2, Eqs. 5.19/5.21
    ROLLING_THRESHOLD = 132   # m/s, direction regularisation of the rolling term
    BALL_RADIUS = 133         # r_b [m]
    PITCH_RADIUS = 134        # r_m [m]
    SIN_HELIX = 135           # sin(alpha_e)
    # screw torsion between the coupling and the nuts (fidelity "screw_torsion")
    SHAFT_TWIST_COMPLIANCE = 136  # (p/2pi)^2 / (G J_p) [1/N]: the shaft twist as an axial compliance per length
    # the design contact angle's trigonometry, computed once (twin.physics.ball_screw.contact_geometry)
    CONTACT_RADIAL_0 = 137    # A0 cos(alpha_0) [m]
    CONTACT_AXIAL_0 = 138     # A0 sin(alpha_0) [m]
    SIN_ALPHA_0 = 139         # sin(alpha_0)

N_CONSTANTS = len(K)

# Contact-model codes (constant K.CONTACT_MODEL).
CONTACT_CONSTANT_ANGLE = 0  # Hertz at the design angle alpha_0
CONTACT_VARIABLE_ANGLE = 1  # Hertz with the Eq. 9.4 load-dependent angle
CONTACT_LINEAR = 2          # linear normal stiffness at the design angle (elasto-backlash of Ch. 5)
CONTACT_LEVELS = {"constant_angle": CONTACT_CONSTANT_ANGLE, "variable_angle": CONTACT_VARIABLE_ANGLE,
                  "linear": CONTACT_LINEAR}

# Ball-groove friction codes (constant K.BALL_GROOVE_FRICTION).
BALL_GROOVE_FRICTION_LUMPED = 0     # no ball-groove friction; the support bearings' lumped term only
BALL_GROOVE_FRICTION_CHAPTER5 = 1   # sliding (Eq. 5.16) and rolling (Eqs. 5.17-5.24) friction on both nuts
BALL_GROOVE_FRICTION_LEVELS = {"lumped": BALL_GROOVE_FRICTION_LUMPED, "chapter5": BALL_GROOVE_FRICTION_CHAPTER5}


class Signal(IntEnum):
    """Recorded output signals (one column each in the output buffer)."""

    POSITION_DEMAND = 0
    NUT1_POSITION = 1
    NUT2_POSITION = 2
    SCREW_ANGLE = 3
    SCREW_EQUIVALENT_POSITION = 4
    SCREW_AXIAL_POSITION = 5
    MOTOR_CURRENT = 6
    MOTOR_TORQUE = 7
    MOTOR_SPEED = 8
    WINDING_TEMPERATURE = 9
    PRELOAD_FORCE = 10
    EXTERNAL_FORCE = 11
    TRANSMITTED_TORQUE = 12
    NUT1_CONTACT_FORCE = 13
    NUT2_CONTACT_FORCE = 14
    SPEED_COMMAND = 15
    CURRENT_DEMAND = 16
    NUT1_SPEED = 17
    FORCE_DEMAND = 18
    CHAMBER1_PRESSURE = 19
    CHAMBER2_PRESSURE = 20
    VALVE_COMMAND = 21
    PISTON_POSITION = 22
    # measured signals (sensors), held at their last acquisition sample
    LINEAR_ENCODER_POSITION = 23
    SCREW_ANGLE_MEASURED = 24
    NUT_SPEED_MEASURED = 25
    MOTOR_SPEED_MEASURED = 26
    MOTOR_CURRENT_MEASURED = 27
    TORQUE_MEASURED = 28
    PRELOAD_FORCE_MEASURED = 29
    EXTERNAL_FORCE_MEASURED = 30
    # reduced Ch. 5 ball screw outputs (twin.physics.ball_groove_friction)
    BALL_GROOVE_FRICTION_TORQUE = 31
    BALL_SCREW_EFFICIENCY = 32
    SCREW_TWIST = 33


N_SIGNALS = len(Signal)

# Scalar features of a run (twin.features), computed by the loop alongside the signals.
FEATURES = tuple(FEATURE_TABLE)
# Everything a scene or a campaign may ask a run to produce.
OUTPUT_NAMES = tuple(signal.name.lower() for signal in Signal) + FEATURES

# name -> (units, long name) for the xarray Dataset (CF-style attributes).
SIGNAL_META = {
    Signal.POSITION_DEMAND: ("m", "sled position demand"),
    Signal.NUT1_POSITION: ("m", "master nut (sled) position"),
    Signal.NUT2_POSITION: ("m", "slave nut position"),
    Signal.SCREW_ANGLE: ("rad", "screw shaft angle"),
    Signal.SCREW_EQUIVALENT_POSITION: ("m", "screw equivalent linear position p*theta_s/(2*pi) (Eq. 9.12)"),
    Signal.SCREW_AXIAL_POSITION: ("m", "screw shaft axial displacement"),
    Signal.MOTOR_CURRENT: ("A", "motor current (Eq. 9.1)"),
    Signal.MOTOR_TORQUE: ("N m", "motor electromagnetic torque k_t*i"),
    Signal.MOTOR_SPEED: ("rad/s", "motor shaft speed"),
    Signal.WINDING_TEMPERATURE: ("K", "winding temperature (Eq. 9.2)"),
    Signal.PRELOAD_FORCE: ("N", "preload force between the nuts"),
    Signal.EXTERNAL_FORCE: ("N", "external force on the master nut"),
    Signal.TRANSMITTED_TORQUE: ("N m", "torque through couplings and torque meter T_tm"),
    Signal.NUT1_CONTACT_FORCE: ("N", "axial contact force of the screw on the master nut"),
    Signal.NUT2_CONTACT_FORCE: ("N", "axial contact force of the screw on the slave nut"),
    Signal.SPEED_COMMAND: ("rad/s", "motor speed command after the drive's analog input"),
    Signal.CURRENT_DEMAND: ("A", "current demand of the speed loop"),
    Signal.NUT1_SPEED: ("m/s", "master nut (sled) speed"),
    Signal.FORCE_DEMAND: ("N", "external force demand"),
    Signal.CHAMBER1_PRESSURE: ("Pa", "cylinder cap-side chamber pressure (absolute)"),
    Signal.CHAMBER2_PRESSURE: ("Pa", "cylinder rod-side chamber pressure (absolute)"),
    Signal.VALVE_COMMAND: ("V", "effective proportional-valve command"),
    Signal.PISTON_POSITION: ("m", "piston position from the cap-end stop"),
    Signal.LINEAR_ENCODER_POSITION: ("m", "sled position read by the linear encoder (zeroed at t = 0)"),
    Signal.SCREW_ANGLE_MEASURED: ("rad", "screw angle read by the torque-meter encoder (zeroed at t = 0)"),
    Signal.NUT_SPEED_MEASURED: ("m/s", "sled speed from the linear encoder (period/frequency method)"),
    Signal.MOTOR_SPEED_MEASURED: ("rad/s", "motor speed estimated by the drive from the resolver"),
    Signal.MOTOR_CURRENT_MEASURED: ("A", "motor current acquired through the current monitor"),
    Signal.TORQUE_MEASURED: ("N m", "torque-meter reading"),
    Signal.PRELOAD_FORCE_MEASURED: ("N", "preload load-cell reading"),
    Signal.EXTERNAL_FORCE_MEASURED: ("N", "external-force load-cell reading"),
    Signal.BALL_GROOVE_FRICTION_TORQUE: ("N m", "ball-groove friction torque opposing the screw rotation, both nuts "
                                                "(Eqs. 5.16-5.24; the drag torque, Eq. 7.85, without external force)"),
    Signal.BALL_SCREW_EFFICIENCY: ("1", "ball-screw mechanical efficiency (Eq. 5.25): P_out/P_in driving, "
                                        "-P_in/P_out back-driving, 0 at rest or when both powers enter"),
    Signal.SCREW_TWIST: ("rad", "torsion of the screw shaft between the coupling and the master nut"),
}


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
    LOCAL_ERROR = 15        # largest step-doubling local-error estimate so far, in tolerance units
    LOCAL_ERROR_STREAK = 16  # consecutive acquisition instants with the estimate above tolerance
    # feature accumulators (layout twin.features.A), from true and from measured signals
    FEATURES_TRUE = 17
    FEATURES_MEASURED = 17 + N_ACCUMULATORS


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
    9: "a nut's contact load fell below the held-contact premise of the implicit drive-period step",
}
#: Bound code of a broken held-contact premise (twin.engine.solver_choice): not a failure of the run, the
#: automatic integrator's signal to solve the scene again with the explicit method.
BOUND_CONTACT_RELEASED = 9
