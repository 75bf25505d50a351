"""Continuous-time right-hand side of the bench (Eqs. 9.1-9.8), compiled with numba.

The digital controllers are outside: the speed loop's current demand enters as
a held input (zero-order hold between drive samples).
"""

import cmath
import math

import numba
import numpy as np

from twin.layout import (
    BALL_GROOVE_FRICTION_CHAPTER5,
    PNEUMATICS_FULL,
    PNEUMATICS_IDEAL,
    K,
    S,
    U,
)
from twin.physics import pneumatics as pn
from twin.physics.ball_groove_friction import (
    friction_generalised_forces,
    nut_friction_force,
    nut_friction_slope,
    tangential_speed,
)
from twin.physics.ball_screw import nut_axial_force, nut_axial_tangent
from twin.physics.coupling import elasto_backlash
from twin.physics.friction import stribeck_friction, stribeck_slope
from twin.physics.motor import current_derivative, winding_resistance, winding_temperature_derivative
from twin.physics.preload import preload_force
from twin.scenes.profiles import profile_value


@numba.njit(cache=True)
def transmitted_torque(x, c):
    """``T_tm`` through couplings and torque meter (Sec. 9.3, elasto-backlash) [N m]."""
    return elasto_backlash(
        x[S.REDUCER_ANGLE] - x[S.SCREW_ANGLE], x[S.REDUCER_SPEED] - x[S.SCREW_SPEED],
        c[K.TORSION_STIFFNESS], c[K.TORSION_DAMPING], c[K.REDUCER_BACKLASH],
    )


@numba.njit(cache=True)
def preload_between_nuts(x, c):
    """Preload force magnitude between the nuts (Secs. 9.2-9.3) [N]."""
    return preload_force(
        x[S.NUT2_POSITION] - x[S.NUT1_POSITION], x[S.NUT2_SPEED] - x[S.NUT1_SPEED],
        c[K.PRELOAD_COMPRESSION], c[K.PRELOAD_STIFFNESS], c[K.PRELOAD_DAMPING], c[K.PRELOAD_ORIENTATION],
    )


@numba.njit(cache=True)
def nut_relative_position(x, c, nut):
    """``dx_i = x_s + p (theta_s - theta_ni) / (2 pi) - x_ni`` of nut ``nut`` (0 master, 1 slave), Eq. 9.5
    in the sign convention of :mod:`twin.physics.ball_screw`."""
    position, angle = (S.NUT1_POSITION, S.NUT1_ANGLE) if nut == 0 else (S.NUT2_POSITION, S.NUT2_ANGLE)
    return x[S.SCREW_AXIAL] + c[K.LEAD_ARM] * (x[S.SCREW_ANGLE] - x[angle]) - x[position]


@numba.njit(cache=True)
def nut_interference(x, c, nut):
    """Axial interference of nut ``nut`` with its flank, ``|dx_i| - b/2`` [m] (Eq. 9.5): positive when the
    contact is closed."""
    return abs(nut_relative_position(x, c, nut)) - 0.5 * c[K.BACKLASH]


@numba.njit(cache=True)
def nut_relative_velocity(x, c, nut):
    """Time derivative of :func:`nut_relative_position` (Eq. 9.5, second line)."""
    speed, angular = (S.NUT1_SPEED, S.NUT1_ANGULAR_SPEED) if nut == 0 else (S.NUT2_SPEED, S.NUT2_ANGULAR_SPEED)
    return x[S.SCREW_AXIAL_SPEED] + c[K.LEAD_ARM] * (x[S.SCREW_SPEED] - x[angular]) - x[speed]


@numba.njit(cache=True)
def nut_contact(x, c, stiffness_poly, nut):
    """Axial force on nut ``nut`` and its per-sphere normal load (Eqs. 9.4-9.6) at the contact fidelity
    ``K.CONTACT_MODEL``."""
    force, normal, _ = nut_axial_force(
        nut_relative_position(x, c, nut), nut_relative_velocity(x, c, nut), c[K.BACKLASH], c[K.COS_HELIX],
        c[K.CENTRE_DISTANCE], c[K.CONTACT_RADIAL_0], c[K.CONTACT_AXIAL_0], c[K.SIN_ALPHA_0],
        stiffness_poly, c[K.SIN_ALPHA_MIN], c[K.SIN_ALPHA_SPAN],
        c[K.CONTACT_DAMPING], c[K.LOADED_BALLS], int(c[K.CONTACT_MODEL]), c[K.LINEAR_CONTACT_STIFFNESS])
    return force, normal


@numba.njit(cache=True)
def nut_groove_speed(x, c, nut):
    """``v_t`` of nut ``nut``: the screw grooves' speed relative to its grooves along the helix [m/s]."""
    speed, angular = (S.NUT1_SPEED, S.NUT1_ANGULAR_SPEED) if nut == 0 else (S.NUT2_SPEED, S.NUT2_ANGULAR_SPEED)
    return tangential_speed(x[S.SCREW_SPEED], x[angular], x[S.SCREW_AXIAL_SPEED], x[speed], c[K.PITCH_RADIUS],
                            c[K.COS_HELIX], c[K.SIN_HELIX])


@numba.njit(cache=True)
def ball_groove_friction(x, c, normal_load, nut):
    """Helix friction force of nut ``nut`` [N, along ``+v_t`` on the nut] from its per-sphere normal load,
    at the ``ball_groove_friction`` fidelity (zero at ``lumped``; :mod:`twin.physics.ball_groove_friction`)."""
    if int(c[K.BALL_GROOVE_FRICTION]) != BALL_GROOVE_FRICTION_CHAPTER5:
        return 0.0
    return nut_friction_force(normal_load, nut_groove_speed(x, c, nut), c[K.LOADED_BALLS], c[K.BALL_RADIUS],
                              c[K.FRICTION_G1], c[K.FRICTION_G2], c[K.FRICTION_G3], c[K.FRICTION_G4],
                              c[K.FRICTION_G5], c[K.FRICTION_G6], c[K.ROLLING_K_GC], c[K.ROLLING_K_RF],
                              c[K.ROLLING_F_V1], c[K.ROLLING_THRESHOLD])


@numba.njit(cache=True)
def screw_axial_stiffness(x, c):
    """Axial stiffness of the screw seen by the nuts [N/m] and its energy-gradient force on the sled [N].

    The rear bearing in series with the shaft ``E A / (l0 + x_n1)`` (Sec. 9.3) and, at the ``static``
    ``screw_torsion`` fidelity, the shaft's torsion between the coupling and the nuts. The coupling
    sits at the rear-bearing end (assumption, docs/model.md), so the twisted length is the same
    ``l = l0 + x_n1``; the shaft carries the nuts' torque ``(p/2pi)(f_1 + f_2)``, whose twist
    ``(p/2pi)(f_1 + f_2) l / (G J_p)`` moves both nuts' relative position (Eq. 9.5) exactly as an axial
    compliance ``(p/2pi)^2 l / (G J_p)`` in series with the shaft's (a static compliance: the shaft's
    own inertia, 3 % of the screw-side inertia, stays with the coupling's). The stiffness depends on the
    sled position, so the spring energy ``k(x_n1) x_s^2 / 2`` also pushes the sled with
    ``-dE/dx_n1 = k^2 x_s^2 (1/(E A) + (p/2pi)^2/(G J_p)) / 2``: tiny, but it keeps the model conservative.
    """
    # written so that a rigid shaft (zero twist compliance) gives the torsion-free model to the last bit
    length = c[K.SHAFT_LENGTH_0] + x[S.NUT1_POSITION]
    twist = c[K.SHAFT_TWIST_COMPLIANCE]
    stiffness = 1.0 / (1.0 / c[K.BEARING_STIFFNESS] + length / c[K.SHAFT_EA] + length * twist)
    half_squared = 0.5 * stiffness**2 * x[S.SCREW_AXIAL] ** 2
    return stiffness, half_squared / c[K.SHAFT_EA] + half_squared * twist


EFFICIENCY_POWER_FLOOR = 1.0e-3  # W: below this input power the efficiency is reported as 0 (at rest)


@numba.njit(cache=True)
def ball_screw_outputs(x, c, f1, f2, p1, p2):
    """Ball-screw output signals at state ``x`` from the nuts' axial forces and per-sphere normal loads.

    Returns
    -------
    (friction_torque, efficiency, twist, axial_displacement)
        Ball-groove friction torque opposing the screw rotation, both nuts [N m] (Eqs. 5.17-5.18 in the
        reduced form; without external force, the drag torque of Eq. 7.85); the efficiency of Eq. 5.25
        (below); the shaft twist between the coupling and the nuts [rad]; the screw's axial
        displacement without the twist's share of ``x_s`` [m] (:func:`screw_axial_stiffness`).

    Notes
    -----
    Eq. 5.25 excludes the inertial terms: the input is the torque the screw puts into the ball-groove
    contacts (the nuts' reaction ``(p/2pi)(f_1+f_2)`` plus the friction torque) times the screw speed, the
    output the axial force of the contacts on the nuts (friction included) times the nuts' speeds.
    Driving (both powers positive), ``eta = P_out / P_in`` in (0, 1). Back-driving (the load drives the
    screw, both negative), ``eta = -P_in / P_out``: the magnitude is the inverse efficiency, the negative
    sign the reversed power flow ("when the motor brakes the action of the external force, it assumes a
    negative sign", Sec. 5.5). Powers of opposite signs (both enter the screw: a reversal, a gap
    crossing) or an input below ``EFFICIENCY_POWER_FLOOR`` give 0, where Fig. 5.18 drops to zero.
    """
    fr1 = ball_groove_friction(x, c, p1, 0)
    fr2 = ball_groove_friction(x, c, p2, 1)
    screw_torque_1, _, _, nut_axial_1 = friction_generalised_forces(fr1, c[K.PITCH_RADIUS], c[K.COS_HELIX],
                                                                     c[K.SIN_HELIX])
    screw_torque_2, _, _, nut_axial_2 = friction_generalised_forces(fr2, c[K.PITCH_RADIUS], c[K.COS_HELIX],
                                                                     c[K.SIN_HELIX])
    friction_torque = -(screw_torque_1 + screw_torque_2)
    power_in = (c[K.LEAD_ARM] * (f1 + f2) + friction_torque) * x[S.SCREW_SPEED]
    power_out = (f1 + nut_axial_1) * x[S.NUT1_SPEED] + (f2 + nut_axial_2) * x[S.NUT2_SPEED]
    efficiency = 0.0
    if power_in > EFFICIENCY_POWER_FLOOR and power_out >= 0.0:
        efficiency = power_out / power_in
    elif power_in < -EFFICIENCY_POWER_FLOOR and power_out < 0.0:
        efficiency = -power_in / power_out
    stiffness, _ = screw_axial_stiffness(x, c)
    length = c[K.SHAFT_LENGTH_0] + x[S.NUT1_POSITION]
    # series springs carry the same force -k x_s: each share of x_s is its compliance times that force
    twist = -stiffness * x[S.SCREW_AXIAL] * length * c[K.SHAFT_TWIST_COMPLIANCE] / c[K.LEAD_ARM]
    axial = stiffness * x[S.SCREW_AXIAL] * (1.0 / c[K.BEARING_STIFFNESS] + length / c[K.SHAFT_EA])
    return friction_torque, efficiency, twist, axial


@numba.njit(cache=True)
def sensed_current(x, c):
    """Current seen by the Hall sensor [A]: its filter state, or the current itself when the ideal
    current loop has no sensor dynamics."""
    return x[S.HALL_CURRENT] if c[K.CURRENT_LOOP_FULL] > 0.5 else x[S.CURRENT]


@numba.njit(cache=True)
def internal_forces(t, x, c, force_table, stiffness_poly):
    """Coupling forces of the mechanical chain at state ``x``.

    Returns
    -------
    (transmitted_torque, f_nut1, f_nut2, preload, external, p_nut1, p_nut2)
        ``T_tm`` [N m] (Sec. 9.3), screw-on-nut axial forces [N] (Eqs. 9.4-9.6),
        preload magnitude [N], external force [N], per-sphere normal loads [N].
    """
    f1, p1 = nut_contact(x, c, stiffness_poly, 0)
    f2, p2 = nut_contact(x, c, stiffness_poly, 1)
    return (transmitted_torque(x, c), f1, f2, preload_between_nuts(x, c), external_force(t, x, c, force_table),
            p1, p2)


@numba.njit(cache=True)
def external_force(t, x, c, force_table):
    """External force on the master nut [N, +x]: the load cell's spring force (full pneumatics),
    the scene's force demand (ideal source) or nothing (absent)."""
    level = int(c[K.PNEUMATICS])
    if level == PNEUMATICS_FULL:
        return pn.load_cell_spring_force(x[S.PISTON_POSITION] - c[K.LINK_OFFSET], x[S.NUT1_POSITION],
                                         x[S.PISTON_SPEED], x[S.NUT1_SPEED],
                                         c[K.LOAD_CELL_STIFFNESS], c[K.LOAD_CELL_DAMPING])
    if level == PNEUMATICS_IDEAL:
        return profile_value(force_table, t)
    return 0.0


@numba.njit(cache=True)
def pneumatics_rhs(x, c, valve_command, load_cell_force, dxdt):
    """Valve spool, chamber pressures and piston of the load system (Eqs. 9.9-9.11)."""
    dxdt[S.SPOOL_POSITION], dxdt[S.SPOOL_SPEED] = pn.spool_derivative(
        x[S.SPOOL_POSITION], x[S.SPOOL_SPEED], valve_command, c[K.VALVE_MID], c[K.VALVE_MIN], c[K.VALVE_MAX],
        c[K.VALVE_FREQUENCY], c[K.VALVE_DAMPING])
    p1 = x[S.CHAMBER1_PRESSURE]
    p2 = x[S.CHAMBER2_PRESSURE]
    temperature = c[K.AIR_TEMPERATURE]
    g1, g2 = pn.chamber_mass_flows(
        x[S.SPOOL_POSITION], p1, p2, c[K.P_SUPPLY], c[K.P_ATMOSPHERE], c[K.MAX_CONDUCTANCE], c[K.LEAKAGE_FRACTION],
        c[K.CRITICAL_RATIO], c[K.REFERENCE_DENSITY], c[K.REFERENCE_TEMPERATURE], temperature, temperature,
        c[K.LAMINAR_RATIO])
    v1, dv1, v2, dv2 = pn.chamber_volumes(x[S.PISTON_POSITION], x[S.PISTON_SPEED], c[K.AREA1], c[K.AREA2],
                                          c[K.DEAD_VOLUME1], c[K.DEAD_VOLUME2], c[K.STROKE])
    dxdt[S.CHAMBER1_PRESSURE] = pn.chamber_pressure_derivative(p1, g1, v1, dv1, temperature, c[K.GAS_CONSTANT],
                                                               c[K.POLYTROPIC_EXPONENT])
    dxdt[S.CHAMBER2_PRESSURE] = pn.chamber_pressure_derivative(p2, g2, v2, dv2, temperature, c[K.GAS_CONSTANT],
                                                               c[K.POLYTROPIC_EXPONENT])
    dxdt[S.PISTON_POSITION] = x[S.PISTON_SPEED]
    dxdt[S.PISTON_SPEED] = pn.piston_acceleration(
        p1, p2, x[S.PISTON_POSITION], x[S.PISTON_SPEED], load_cell_force, c[K.AREA1], c[K.AREA2],
        c[K.P_ATMOSPHERE], c[K.PISTON_MASS], c[K.PISTON_DAMPING], c[K.CYLINDER_FRICTION_STATIC],
        c[K.CYLINDER_FRICTION_DYNAMIC], c[K.CYLINDER_FRICTION_RATE], c[K.CYLINDER_FRICTION_VISCOUS],
        c[K.CYLINDER_V_THRESHOLD], c[K.STROKE], c[K.DAMPER_TRAVEL], c[K.DAMPER_STIFFNESS], c[K.DAMPER_DAMPING],
        c[K.END_STOP_STIFFNESS])


@numba.njit(cache=True)
def current_loop_voltage(x, c, current_demand):
    """Analog PI output (unsaturated) and the voltage after the DC-bus duty-cycle limit."""
    demand_voltage = c[K.CURRENT_KP] * (current_demand - x[S.HALL_CURRENT]) + x[S.CURRENT_PI]
    bus = c[K.DC_BUS]
    return demand_voltage, min(max(demand_voltage, -bus), bus)


@numba.njit(cache=True)
def drive_electronics_rhs(x, c, current_demand, dxdt):
    """Full current loop: winding current (Eq. 9.1), Hall sensor and analog PI with back-calculation anti-windup."""
    demand_voltage, voltage = current_loop_voltage(x, c, current_demand)
    resistance = winding_resistance(x[S.WINDING_TEMP], c[K.R20], c[K.R_TEMP_COEF])
    dxdt[S.CURRENT] = current_derivative(voltage, x[S.CURRENT], x[S.REDUCER_SPEED], resistance,
                                         c[K.INDUCTANCE], c[K.SPEED_CONSTANT], c[K.RATIO])
    dxdt[S.CURRENT_PI] = (c[K.CURRENT_KI] * (current_demand - x[S.HALL_CURRENT])
                          + (voltage - demand_voltage) / c[K.CURRENT_AW_TIME])
    dxdt[S.HALL_CURRENT] = (x[S.CURRENT] - x[S.HALL_CURRENT]) / c[K.HALL_TAU]


@numba.njit(cache=True)
def rhs(t, x, c, u, force_table, stiffness_poly, dxdt):
    """Write ``dx/dt`` of the bench into ``dxdt``.

    Only the derivatives of the states the fidelity levels keep (``K.CURRENT_LOOP_FULL``,
    ``K.THERMAL_DYNAMIC``, ``K.NUT_ROTATION``, ``K.PNEUMATICS``) are written; the
    integrators advance only those (:attr:`twin.engine.model.Model.active`).

    Parameters
    ----------
    t : float
        Time [s].
    x : 1-D array
        State (layout :class:`twin.layout.S`).
    c : 1-D array
        Model constants (layout :class:`twin.layout.K`).
    u : 1-D array
        Inputs held by the digital loops (layout :class:`twin.layout.U`).
    force_table, stiffness_poly : arrays
        Compiled external-force profile and the contact stiffness table.
    dxdt : 1-D array
        Output.
    """
    ratio = c[K.RATIO]
    if c[K.CURRENT_LOOP_FULL] > 0.5:
        drive_electronics_rhs(x, c, u[U.CURRENT_DEMAND], dxdt)
    else:
        # ideal torque source: a first-order lag at the loop's closed-loop bandwidth
        dxdt[S.CURRENT] = (u[U.CURRENT_DEMAND] - x[S.CURRENT]) / c[K.CURRENT_LOOP_TAU]
    if c[K.THERMAL_DYNAMIC] > 0.5:
        resistance = winding_resistance(x[S.WINDING_TEMP], c[K.R20], c[K.R_TEMP_COEF])
        dxdt[S.WINDING_TEMP] = winding_temperature_derivative(
            x[S.WINDING_TEMP], c[K.AMBIENT], resistance * x[S.CURRENT] ** 2, c[K.THERMAL_RESISTANCE],
            c[K.THERMAL_TAU], c[K.HEAT_TRANSFER], c[K.MOTOR_AREA], c[K.EMISSIVITY],
        )

    torque, f1, f2, preload, external, p1, p2 = internal_forces(t, x, c, force_table, stiffness_poly)
    # ball-groove friction of each nut along the helix (reduced Ch. 5) and its generalised forces
    screw_fr_1, nut_fr_torque_1, screw_fr_axial_1, nut_fr_axial_1 = friction_generalised_forces(
        ball_groove_friction(x, c, p1, 0), c[K.PITCH_RADIUS], c[K.COS_HELIX], c[K.SIN_HELIX])
    screw_fr_2, nut_fr_torque_2, screw_fr_axial_2, nut_fr_axial_2 = friction_generalised_forces(
        ball_groove_friction(x, c, p2, 1), c[K.PITCH_RADIUS], c[K.COS_HELIX], c[K.SIN_HELIX])

    # --- motor-reducer mechanics (Eq. 9.3), written for the reducer output angle
    w_r = x[S.REDUCER_SPEED]
    friction_mr = stribeck_friction(w_r, c[K.MR_FRICTION_STATIC], c[K.MR_FRICTION_DYNAMIC],
                                    c[K.MR_FRICTION_RATE], 0.0, c[K.ANGULAR_V_THRESHOLD])
    drive = (c[K.TORQUE_CONSTANT] * x[S.CURRENT] * c[K.EFFICIENCY] - c[K.MOTOR_VISCOUS] * ratio * w_r) * ratio
    dxdt[S.REDUCER_ANGLE] = w_r
    dxdt[S.REDUCER_SPEED] = (drive - friction_mr - torque) / c[K.J_MOTOR_SIDE]

    # --- screw rotation (Eq. 9.7): the nuts' reaction is -(p/2pi) * sum of their axial forces
    arm = c[K.LEAD_ARM]
    w_s = x[S.SCREW_SPEED]
    friction_s = stribeck_friction(w_s, c[K.SCREW_FRICTION_STATIC], c[K.SCREW_FRICTION_DYNAMIC],
                                   c[K.SCREW_FRICTION_RATE], c[K.SCREW_FRICTION_VISCOUS], c[K.ANGULAR_V_THRESHOLD])
    dxdt[S.SCREW_ANGLE] = w_s
    dxdt[S.SCREW_SPEED] = (torque - c[K.SCREW_DAMPING] * w_s - friction_s - arm * (f1 + f2) + screw_fr_1 + screw_fr_2
                           ) / c[K.J_SCREW_SIDE]

    # --- screw axial motion: rear bearing in series with the shaft (and its twist) to the sled (Sec. 9.3)
    axial_stiffness, stiffness_gradient_force = screw_axial_stiffness(x, c)
    dxdt[S.SCREW_AXIAL] = x[S.SCREW_AXIAL_SPEED]
    dxdt[S.SCREW_AXIAL_SPEED] = (-(f1 + f2) - axial_stiffness * x[S.SCREW_AXIAL] + screw_fr_axial_1 + screw_fr_axial_2
                                 - c[K.SCREW_AXIAL_DAMPING] * x[S.SCREW_AXIAL_SPEED]) / c[K.SCREW_MASS]

    # --- nuts (Eq. 9.8): master carries the external force, preload acts between the nuts
    orientation = c[K.PRELOAD_ORIENTATION]
    guide_1 = stribeck_friction(x[S.NUT1_SPEED], c[K.GUIDE_FRICTION_STATIC], c[K.GUIDE_FRICTION_DYNAMIC],
                                c[K.GUIDE_FRICTION_RATE], c[K.GUIDE_FRICTION_VISCOUS], c[K.LINEAR_V_THRESHOLD])
    guide_2 = c[K.SLAVE_FRICTION_FRACTION] * stribeck_friction(
        x[S.NUT2_SPEED], c[K.GUIDE_FRICTION_STATIC], c[K.GUIDE_FRICTION_DYNAMIC],
        c[K.GUIDE_FRICTION_RATE], c[K.GUIDE_FRICTION_VISCOUS], c[K.LINEAR_V_THRESHOLD])
    dxdt[S.NUT1_POSITION] = x[S.NUT1_SPEED]
    dxdt[S.NUT1_SPEED] = (f1 + nut_fr_axial_1 - guide_1 - orientation * preload + external + stiffness_gradient_force
                          ) / c[K.MASS_NUT1]
    dxdt[S.NUT2_POSITION] = x[S.NUT2_SPEED]
    dxdt[S.NUT2_SPEED] = (f2 + nut_fr_axial_2 - guide_2 + orientation * preload) / c[K.MASS_NUT2]

    # --- nut rotation restrained by the linear guides (Sec. 9.3): contact torque (p/2pi) f_i
    if c[K.NUT_ROTATION] > 0.5:
        k_roll = c[K.GUIDE_ROLL_STIFFNESS]
        c_roll = c[K.GUIDE_ROLL_DAMPING]
        dxdt[S.NUT1_ANGLE] = x[S.NUT1_ANGULAR_SPEED]
        dxdt[S.NUT1_ANGULAR_SPEED] = (arm * f1 + nut_fr_torque_1 - k_roll * x[S.NUT1_ANGLE]
                                      - c_roll * x[S.NUT1_ANGULAR_SPEED]) / c[K.J_NUT]
        dxdt[S.NUT2_ANGLE] = x[S.NUT2_ANGULAR_SPEED]
        dxdt[S.NUT2_ANGULAR_SPEED] = (arm * f2 + nut_fr_torque_2 - k_roll * x[S.NUT2_ANGLE]
                                      - c_roll * x[S.NUT2_ANGULAR_SPEED]) / c[K.J_NUT]

    if int(c[K.PNEUMATICS]) == PNEUMATICS_FULL:
        pneumatics_rhs(x, c, u[U.VALVE_COMMAND], external, dxdt)



# Mechanical degrees of freedom of the linearly implicit integrator. The DOFs coupled to one other only
# (reducer, piston, nut rolls) come first, so Gaussian elimination in this order creates no fill-in
# beyond the screw-axial-nuts block, which the contacts make dense anyway.
DOF_REDUCER, DOF_PISTON, DOF_NUT1_ROLL, DOF_NUT2_ROLL, DOF_NUT1, DOF_NUT2, DOF_AXIAL, DOF_SCREW = range(8)
N_DOFS = 8
#: Position state of each DOF; its velocity is the next state (twin.layout.POSITION_VELOCITY_PAIRS).
DOF_POSITIONS = np.array([S.REDUCER_ANGLE, S.PISTON_POSITION, S.NUT1_ANGLE, S.NUT2_ANGLE, S.NUT1_POSITION,
                          S.NUT2_POSITION, S.SCREW_AXIAL, S.SCREW_ANGLE], dtype=np.int64)


@numba.njit(cache=True)
def dof_active(c, dof):
    """Whether mechanical DOF ``dof`` is integrated at the model's fidelity (the others are held)."""
    if dof == DOF_NUT1_ROLL or dof == DOF_NUT2_ROLL:
        return c[K.NUT_ROTATION] > 0.5
    if dof == DOF_PISTON:
        return int(c[K.PNEUMATICS]) == PNEUMATICS_FULL
    return True


@numba.njit(cache=True)
def _mass_diagonal(c, matrix):
    """``M`` on the diagonal of ``matrix`` (inertias of Eqs. 9.3, 9.7, 9.8 and the piston of Eq. 9.11)."""
    for i in range(N_DOFS):
        for j in range(N_DOFS):
            matrix[i, j] = 0.0
    matrix[DOF_REDUCER, DOF_REDUCER] = c[K.J_MOTOR_SIDE]
    matrix[DOF_SCREW, DOF_SCREW] = c[K.J_SCREW_SIDE]
    matrix[DOF_AXIAL, DOF_AXIAL] = c[K.SCREW_MASS]
    matrix[DOF_NUT1, DOF_NUT1] = c[K.MASS_NUT1]
    matrix[DOF_NUT1_ROLL, DOF_NUT1_ROLL] = c[K.J_NUT]
    matrix[DOF_NUT2, DOF_NUT2] = c[K.MASS_NUT2]
    matrix[DOF_NUT2_ROLL, DOF_NUT2_ROLL] = c[K.J_NUT]
    matrix[DOF_PISTON, DOF_PISTON] = c[K.PISTON_MASS] if int(c[K.PNEUMATICS]) == PNEUMATICS_FULL else 1.0


@numba.njit(cache=True)
def _add_element(matrix, b, velocity, h, stiffness, damping, i0, g0, i1, g1, i2, g2, i3, g3):
    """Add one spring-damper along ``g . q`` (up to four DOFs; unused ones with coefficient 0) to the
    velocity system of :func:`stiff_velocity_system`: ``(h d + h^2 k) g g^T`` and ``-h^2 k (g . v) g``."""
    weight = h * damping + h * h * stiffness
    rate = h * h * stiffness * (g0 * velocity[i0] + g1 * velocity[i1] + g2 * velocity[i2] + g3 * velocity[i3])
    index = (i0, i1, i2, i3)
    grad = (g0, g1, g2, g3)
    for a in range(4):
        b[index[a]] -= rate * grad[a]
        for e in range(4):
            matrix[index[a], index[e]] += weight * grad[a] * grad[e]


@numba.njit(cache=True)
def stiff_velocity_system(x, c, stiffness_poly, f, h, matrix, b, velocity):
    """The velocity increment system ``(M + h D + h^2 K) dv = h (M a - h K v)`` of one linearly implicit
    step (:func:`twin.engine.integrators.imex_euler_step`) over the mechanical DOFs (``DOF_*``).

    ``K`` and ``D`` are the analytic tangent stiffness and damping of the stiff elements only, each a
    rank-one spring-damper ``k g g^T`` along the coordinate ``g . q`` it deforms: the two ball-groove
    contacts along ``dx_i`` (Eq. 9.5; :func:`twin.physics.ball_screw.nut_axial_tangent`), their
    helix friction along ``v_t`` (reduced Ch. 5), the screw's axial bearing and shaft (Sec. 9.3), the
    torsional elasto-backlash, the preload springs, the guides' roll springs, the load cell (Sec. 9.3.1),
    and on the diagonal the viscous and regularised Coulomb slopes of the Stribeck laws (Eqs. 7.63-7.64).
    The rest of the model (pneumatic chambers, the varying shaft length, the nuts' friction torques) is
    explicit. ``f`` holds ``dx/dt`` at ``x`` (:func:`rhs`); ``velocity`` receives the DOF velocities.
    """
    _mass_diagonal(c, matrix)
    for i in range(N_DOFS):
        position = DOF_POSITIONS[i]
        if dof_active(c, i):
            velocity[i] = x[position + 1]
            b[i] = h * matrix[i, i] * f[position + 1]
        else:
            velocity[i] = 0.0
            b[i] = 0.0
    rotation = c[K.NUT_ROTATION] > 0.5
    arm = c[K.LEAD_ARM]
    roll_arm = arm if rotation else 0.0
    # ball-groove contacts and their helix friction
    tangent_arm = c[K.PITCH_RADIUS] * c[K.COS_HELIX]
    for nut in range(2):
        position, roll = (DOF_NUT1, DOF_NUT1_ROLL) if nut == 0 else (DOF_NUT2, DOF_NUT2_ROLL)
        stiffness, damping, load = nut_axial_tangent(
            nut_relative_position(x, c, nut), nut_relative_velocity(x, c, nut), c[K.BACKLASH], c[K.COS_HELIX],
            c[K.CENTRE_DISTANCE], c[K.CONTACT_RADIAL_0], c[K.CONTACT_AXIAL_0], c[K.SIN_ALPHA_0],
        stiffness_poly, c[K.SIN_ALPHA_MIN], c[K.SIN_ALPHA_SPAN],
            c[K.CONTACT_DAMPING], c[K.LOADED_BALLS], int(c[K.CONTACT_MODEL]), c[K.LINEAR_CONTACT_STIFFNESS])
        if stiffness > 0.0:
            _add_element(matrix, b, velocity, h, stiffness, damping, DOF_AXIAL, 1.0, DOF_SCREW, arm, roll,
                         -roll_arm, position, -1.0)
            if int(c[K.BALL_GROOVE_FRICTION]) == BALL_GROOVE_FRICTION_CHAPTER5:
                slope = nut_friction_slope(
                    load, nut_groove_speed(x, c, nut), c[K.LOADED_BALLS], c[K.BALL_RADIUS], c[K.FRICTION_G1],
                    c[K.FRICTION_G2], c[K.FRICTION_G3], c[K.FRICTION_G4], c[K.FRICTION_G5], c[K.FRICTION_G6],
                    c[K.ROLLING_K_GC], c[K.ROLLING_K_RF], c[K.ROLLING_F_V1], c[K.ROLLING_THRESHOLD])
                if slope > 0.0:
                    _add_element(matrix, b, velocity, h, 0.0, slope, DOF_SCREW, tangent_arm, roll,
                                 -tangent_arm if rotation else 0.0, DOF_AXIAL, -c[K.SIN_HELIX], position,
                                 c[K.SIN_HELIX])
    # torsional elasto-backlash between reducer and screw
    deflection = x[S.REDUCER_ANGLE] - x[S.SCREW_ANGLE]
    if abs(deflection) > 0.5 * c[K.REDUCER_BACKLASH]:
        elastic = c[K.TORSION_STIFFNESS] * (abs(deflection) - 0.5 * c[K.REDUCER_BACKLASH])
        rate = x[S.REDUCER_SPEED] - x[S.SCREW_SPEED]
        damping = c[K.TORSION_DAMPING] if c[K.TORSION_DAMPING] * abs(rate) < elastic else 0.0
        _add_element(matrix, b, velocity, h, c[K.TORSION_STIFFNESS], damping, DOF_REDUCER, 1.0, DOF_SCREW, -1.0,
                     DOF_REDUCER, 0.0, DOF_REDUCER, 0.0)
    # preload springs between the nuts
    orientation = c[K.PRELOAD_ORIENTATION]
    compression = c[K.PRELOAD_COMPRESSION] - orientation * (x[S.NUT2_POSITION] - x[S.NUT1_POSITION])
    if compression > 0.0:
        rate = x[S.NUT2_SPEED] - x[S.NUT1_SPEED]
        damping = c[K.PRELOAD_DAMPING] if c[K.PRELOAD_DAMPING] * abs(rate) < c[K.PRELOAD_STIFFNESS] * compression \
            else 0.0
        _add_element(matrix, b, velocity, h, c[K.PRELOAD_STIFFNESS], damping, DOF_NUT2, 1.0, DOF_NUT1, -1.0,
                     DOF_NUT1, 0.0, DOF_NUT1, 0.0)
    # screw axial bearing + shaft; guides' roll springs; load cell
    axial_stiffness, _ = screw_axial_stiffness(x, c)
    _add_element(matrix, b, velocity, h, axial_stiffness, c[K.SCREW_AXIAL_DAMPING], DOF_AXIAL, 1.0, DOF_AXIAL, 0.0,
                 DOF_AXIAL, 0.0, DOF_AXIAL, 0.0)
    if rotation:
        for roll in (DOF_NUT1_ROLL, DOF_NUT2_ROLL):
            _add_element(matrix, b, velocity, h, c[K.GUIDE_ROLL_STIFFNESS], c[K.GUIDE_ROLL_DAMPING], roll, 1.0,
                         roll, 0.0, roll, 0.0, roll, 0.0)
    if int(c[K.PNEUMATICS]) == PNEUMATICS_FULL:
        _add_element(matrix, b, velocity, h, c[K.LOAD_CELL_STIFFNESS], c[K.LOAD_CELL_DAMPING], DOF_PISTON, 1.0,
                     DOF_NUT1, -1.0, DOF_PISTON, 0.0, DOF_PISTON, 0.0)
        matrix[DOF_PISTON, DOF_PISTON] += h * (c[K.PISTON_DAMPING] + stribeck_slope(
            x[S.PISTON_SPEED], c[K.CYLINDER_FRICTION_STATIC], c[K.CYLINDER_FRICTION_DYNAMIC],
            c[K.CYLINDER_FRICTION_VISCOUS], c[K.CYLINDER_V_THRESHOLD]))
    # viscous and regularised Coulomb slopes of the supports' friction
    ratio = c[K.RATIO]
    matrix[DOF_REDUCER, DOF_REDUCER] += h * (c[K.MOTOR_VISCOUS] * ratio * ratio + stribeck_slope(
        x[S.REDUCER_SPEED], c[K.MR_FRICTION_STATIC], c[K.MR_FRICTION_DYNAMIC], 0.0, c[K.ANGULAR_V_THRESHOLD]))
    matrix[DOF_SCREW, DOF_SCREW] += h * (c[K.SCREW_DAMPING] + stribeck_slope(
        x[S.SCREW_SPEED], c[K.SCREW_FRICTION_STATIC], c[K.SCREW_FRICTION_DYNAMIC], c[K.SCREW_FRICTION_VISCOUS],
        c[K.ANGULAR_V_THRESHOLD]))
    guide = (c[K.GUIDE_FRICTION_STATIC], c[K.GUIDE_FRICTION_DYNAMIC], c[K.GUIDE_FRICTION_VISCOUS])
    matrix[DOF_NUT1, DOF_NUT1] += h * stribeck_slope(x[S.NUT1_SPEED], guide[0], guide[1], guide[2],
                                                     c[K.LINEAR_V_THRESHOLD])
    matrix[DOF_NUT2, DOF_NUT2] += h * c[K.SLAVE_FRICTION_FRACTION] * stribeck_slope(
        x[S.NUT2_SPEED], guide[0], guide[1], guide[2], c[K.LINEAR_V_THRESHOLD])


CURRENT_LOOP_STATES = (S.CURRENT, S.HALL_CURRENT, S.CURRENT_PI)


@numba.njit(cache=True)
def current_loop_jacobian(x, c, current_demand, jacobian):
    """Jacobian of :func:`drive_electronics_rhs` over ``CURRENT_LOOP_STATES`` (winding current, Hall output,
    PI integrator) into ``jacobian[:3, :3]``: the loop is linear (Eq. 9.1, the Hall sensor's first-order
    lag, the analog PI) between the DC-bus limits; on the limit the voltage is constant and only the
    anti-windup feedback remains. The back-EMF and temperature couplings are left explicit."""
    demand_voltage, voltage = current_loop_voltage(x, c, current_demand)
    inductance = c[K.INDUCTANCE]
    saturated = voltage != demand_voltage
    jacobian[0, 0] = -winding_resistance(x[S.WINDING_TEMP], c[K.R20], c[K.R_TEMP_COEF]) / inductance
    jacobian[0, 1] = 0.0 if saturated else -c[K.CURRENT_KP] / inductance
    jacobian[0, 2] = 0.0 if saturated else 1.0 / inductance
    jacobian[1, 0] = 1.0 / c[K.HALL_TAU]
    jacobian[1, 1] = -1.0 / c[K.HALL_TAU]
    jacobian[1, 2] = 0.0
    jacobian[2, 0] = 0.0
    jacobian[2, 1] = -c[K.CURRENT_KI] + (c[K.CURRENT_KP] / c[K.CURRENT_AW_TIME] if saturated else 0.0)
    jacobian[2, 2] = -1.0 / c[K.CURRENT_AW_TIME] if saturated else 0.0


@numba.njit(cache=True)
def held_input_propagators(c, h, cache):
    """Exact one-step propagators of the two linear blocks driven by a held input: the valve spool
    (second order, Table B.12: ``x'' = w^2 (s - x) - 2 zeta w x'``) and the ideal current loop's lag.

    ``cache[:8]`` holds ``(h, w, zeta, tau, Phi00, Phi01, Phi10, Phi11)`` and is refreshed only when a key
    changes: the matrix exponential ``Phi = exp(A h)`` of the spool (Moler & Van Loan, SIAM Review 45, 2003,
    Method 1 (Lagrange/Sylvester form) for a 2 x 2 matrix, with the double-eigenvalue limit at ``zeta = 1``)
    and ``cache[8] = 1 - exp(-h / tau)``. Exact under the zero-order hold because the steps divide both
    controllers' periods; the exponential Euler of Hochbruck & Ostermann (Acta Numerica 19, 2010, Sec. 2.1).
    """
    omega = 2.0 * math.pi * c[K.VALVE_FREQUENCY]
    zeta = c[K.VALVE_DAMPING]
    tau = c[K.CURRENT_LOOP_TAU]
    if cache[0] == h and cache[1] == omega and cache[2] == zeta and cache[3] == tau:
        return
    cache[0], cache[1], cache[2], cache[3] = h, omega, zeta, tau
    root = cmath.sqrt(complex(zeta * zeta - 1.0, 0.0)) * omega
    first, second = -zeta * omega + root, -zeta * omega - root
    if abs(first - second) > 1e-9 * omega:
        e1, e2 = cmath.exp(first * h), cmath.exp(second * h)
        identity_part = ((first * e2 - second * e1) / (first - second)).real
        a_part = ((e1 - e2) / (first - second)).real
    else:
        decay = math.exp(-omega * h)
        identity_part = decay * (1.0 + omega * h)
        a_part = decay * h
    # Phi = identity_part I + a_part A, A = [[0, 1], [-w^2, -2 zeta w]]
    cache[4] = identity_part
    cache[5] = a_part
    cache[6] = -a_part * omega * omega
    cache[7] = identity_part - 2.0 * zeta * omega * a_part
    cache[8] = -math.expm1(-h / tau)
