"""The stiff elements' tangent systems of the linearly implicit step (:func:`twin.engine.integrators.imex_euler_step`).

For one lane of a group: the mechanical velocity increment system ``(M + h D + h^2 K) dv = h (M a - h K v)`` over
the mechanical degrees of freedom (``DOF_*``), with ``K`` and ``D`` the analytic tangent stiffness and damping of
the stiff elements, and the full current loop's Jacobian. The step needs the screw's axial mass (the ``dynamic``
screw-axial level): it integrates that mode implicitly (docs/accuracy.md).
"""

import numba
import numpy as np

from numerics.jit import SCALAR
from twin.components import guides, preload, reducer, seal
from twin.engine.codes import (
    BALL_GROOVE_FRICTION,
    BALL_GROOVE_FRICTION_CHAPTER5,
    CONTACT,
    NUT_ROTATION,
    NUT_ROTATION_ON,
    PNEUMATICS,
    PNEUMATICS_FULL,
)
from twin.engine.plant import W, _stiffness
from twin.layout import NUT_STATE_STRIDE, K, S, U
from twin.physics.ball_groove_friction import nut_friction_slope, tangential_speed
from twin.physics.ball_screw import nut_axial_tangent
from twin.physics.friction import stribeck_slope
from twin.physics.motor import winding_resistance

# Mechanical degrees of freedom of the linearly implicit integrator. The DOFs coupled to one other only
# (reducer, piston, nut rolls) come first, so Gaussian elimination in this order creates no fill-in
# beyond the screw-axial-nuts block, which the contacts make dense anyway.
DOF_REDUCER, DOF_PISTON, DOF_NUT1_ROLL, DOF_NUT2_ROLL, DOF_NUT1, DOF_NUT2, DOF_AXIAL, DOF_SCREW = range(8)
N_DOFS = 8
#: Position state of each DOF; its velocity is the next state (twin.layout.POSITION_VELOCITY_PAIRS).
DOF_POSITIONS = np.array([S.REDUCER_ANGLE, S.PISTON_POSITION, S.NUT1_ANGLE, S.NUT2_ANGLE, S.NUT1_POSITION,
                          S.NUT2_POSITION, S.SCREW_AXIAL, S.SCREW_ANGLE], dtype=np.int64)
#: The full current loop's states (winding current, Hall output, PI integrator), in the order of its Jacobian.
CURRENT_LOOP_STATES = (S.CURRENT, S.HALL_CURRENT, S.CURRENT_PI)


@numba.njit(**SCALAR)
def dof_active(levels, dof):
    """Whether mechanical DOF ``dof`` is integrated at the group's levels (the others are held)."""
    if dof == DOF_NUT1_ROLL or dof == DOF_NUT2_ROLL:
        return levels[NUT_ROTATION] == NUT_ROTATION_ON
    if dof == DOF_PISTON:
        return levels[PNEUMATICS] == PNEUMATICS_FULL
    return True


@numba.njit(**SCALAR)
def _mass_diagonal(c, lane, levels, matrix):
    """``M`` on the diagonal of ``matrix`` (inertias of Eqs. 9.3, 9.7, 9.8 and the piston of Eq. 9.11)."""
    for i in range(N_DOFS):
        for j in range(N_DOFS):
            matrix[i, j] = 0.0
    matrix[DOF_REDUCER, DOF_REDUCER] = c[K.J_MOTOR_SIDE, lane]
    matrix[DOF_SCREW, DOF_SCREW] = c[K.J_SCREW_SIDE, lane]
    matrix[DOF_AXIAL, DOF_AXIAL] = c[K.SCREW_MASS, lane]
    matrix[DOF_NUT1, DOF_NUT1] = c[K.NUT1_MASS, lane]
    matrix[DOF_NUT1_ROLL, DOF_NUT1_ROLL] = c[K.J_NUT, lane]
    matrix[DOF_NUT2, DOF_NUT2] = c[K.NUT2_MASS, lane]
    matrix[DOF_NUT2_ROLL, DOF_NUT2_ROLL] = c[K.J_NUT, lane]
    matrix[DOF_PISTON, DOF_PISTON] = c[K.PISTON_MASS, lane] if levels[PNEUMATICS] == PNEUMATICS_FULL else 1.0


@numba.njit(**SCALAR)
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


@numba.njit(**SCALAR)
def stiff_velocity_system(x, c, w, lane, levels, f, h, matrix, b, velocity):
    """The velocity increment system ``(M + h D + h^2 K) dv = h (M a - h K v)`` of one linearly implicit
    step (:func:`twin.engine.integrators.imex_euler_step`) over the mechanical DOFs (``DOF_*``), for lane ``lane``.

    ``K`` and ``D`` are the analytic tangent stiffness and damping of the stiff elements only, each a
    rank-one spring-damper ``k g g^T`` along the coordinate ``g . q`` it deforms: the two ball-groove
    contacts along ``dx_i`` (Eq. 9.5; :func:`twin.physics.ball_screw.nut_axial_tangent`), their
    helix friction along ``v_t`` (reduced Ch. 5), the screw's axial bearing and shaft (Sec. 9.3), the
    torsional elasto-backlash, the preload springs, the guides' roll springs, the load cell (Sec. 9.3.1),
    and on the diagonal the viscous and regularised Coulomb slopes of the Stribeck laws (Eqs. 7.63-7.64).
    The rest of the model (pneumatic chambers, the varying shaft length, the nuts' friction torques) is
    explicit. ``f`` holds ``dx/dt`` at ``x`` (:func:`twin.engine.plant.rhs`, which left the relative motions and
    the axial stiffness in the work rows ``w``); ``velocity`` receives the DOF velocities.
    """
    _mass_diagonal(c, lane, levels, matrix)
    for i in range(N_DOFS):
        position = DOF_POSITIONS[i]
        if dof_active(levels, i):
            velocity[i] = x[position + 1, lane]
            b[i] = h * matrix[i, i] * f[position + 1, lane]
        else:
            velocity[i] = 0.0
            b[i] = 0.0
    rotation = levels[NUT_ROTATION] == NUT_ROTATION_ON
    arm = c[K.LEAD_ARM, lane]
    roll_arm = arm if rotation else 0.0
    # ball-groove contacts and their helix friction
    tangent_arm = c[K.PITCH_RADIUS, lane] * c[K.COS_HELIX, lane]
    for nut in range(2):
        position, roll = (DOF_NUT1, DOF_NUT1_ROLL) if nut == 0 else (DOF_NUT2, DOF_NUT2_ROLL)
        stiffness, damping, load = nut_axial_tangent(
            w[W.NUT_DX + nut, lane], w[W.NUT_DV + nut, lane], c[K.BACKLASH, lane], c[K.COS_HELIX, lane],
            c[K.CENTRE_DISTANCE, lane], c[K.CONTACT_RADIAL_0, lane], c[K.CONTACT_AXIAL_0, lane],
            c[K.SIN_ALPHA_0, lane], _stiffness(c, lane), c[K.SIN_ALPHA_MIN, lane], c[K.SIN_ALPHA_SPAN, lane],
            c[K.CONTACT_DAMPING, lane], c[K.LOADED_BALLS, lane], levels[CONTACT], c[K.LINEAR_CONTACT_STIFFNESS, lane])
        if stiffness > 0.0:
            _add_element(matrix, b, velocity, h, stiffness, damping, DOF_AXIAL, 1.0, DOF_SCREW, arm, roll,
                         -roll_arm, position, -1.0)
            if levels[BALL_GROOVE_FRICTION] == BALL_GROOVE_FRICTION_CHAPTER5:
                state = S.NUT1_POSITION + NUT_STATE_STRIDE * nut
                speed = tangential_speed(x[S.SCREW_SPEED, lane], x[state + 3, lane], x[S.SCREW_AXIAL_SPEED, lane],
                                         x[state + 1, lane], c[K.PITCH_RADIUS, lane], c[K.COS_HELIX, lane],
                                         c[K.SIN_HELIX, lane])
                slope = nut_friction_slope(
                    load, speed, c[K.LOADED_BALLS, lane], c[K.BALL_RADIUS, lane], c[K.FRICTION_G1, lane],
                    c[K.FRICTION_G2, lane], c[K.FRICTION_G3, lane], c[K.FRICTION_G4, lane], c[K.FRICTION_G5, lane],
                    c[K.FRICTION_G6, lane], c[K.ROLLING_K_GC, lane], c[K.ROLLING_K_RF, lane],
                    c[K.ROLLING_F_V1, lane], c[K.ROLLING_THRESHOLD, lane])
                if slope > 0.0:
                    _add_element(matrix, b, velocity, h, 0.0, slope, DOF_SCREW, tangent_arm, roll,
                                 -tangent_arm if rotation else 0.0, DOF_AXIAL, -c[K.SIN_HELIX, lane], position,
                                 c[K.SIN_HELIX, lane])
    # torsional elasto-backlash between reducer and screw
    engaged, stiffness, damping = reducer.torsion_tangent_at(x, c, lane)
    if engaged:
        _add_element(matrix, b, velocity, h, stiffness, damping, DOF_REDUCER, 1.0, DOF_SCREW, -1.0, DOF_REDUCER, 0.0,
                     DOF_REDUCER, 0.0)
    # preload springs between the nuts
    engaged, spring, damping = preload.tangent_at(x, c, lane)
    if engaged:
        _add_element(matrix, b, velocity, h, spring, damping, DOF_NUT2, 1.0, DOF_NUT1, -1.0, DOF_NUT1, 0.0,
                     DOF_NUT1, 0.0)
    # screw axial bearing + shaft; guides' roll springs; load cell
    _add_element(matrix, b, velocity, h, w[W.AXIAL_STIFFNESS, lane], c[K.SCREW_AXIAL_DAMPING, lane], DOF_AXIAL, 1.0,
                 DOF_AXIAL, 0.0, DOF_AXIAL, 0.0, DOF_AXIAL, 0.0)
    if rotation:
        for roll in (DOF_NUT1_ROLL, DOF_NUT2_ROLL):
            _add_element(matrix, b, velocity, h, c[K.GUIDE_ROLL_STIFFNESS, lane], c[K.GUIDE_ROLL_DAMPING, lane], roll,
                         1.0, roll, 0.0, roll, 0.0, roll, 0.0)
    if levels[PNEUMATICS] == PNEUMATICS_FULL:
        _add_element(matrix, b, velocity, h, c[K.LOAD_CELL_STIFFNESS, lane], c[K.LOAD_CELL_DAMPING, lane],
                     DOF_PISTON, 1.0, DOF_NUT1, -1.0, DOF_PISTON, 0.0, DOF_PISTON, 0.0)
        # the piston's damping and the seals' friction slope (twin.components.seal)
        matrix[DOF_PISTON, DOF_PISTON] += h * seal.tangent_at(x, c, lane, levels[seal.SEAL_FRICTION],
                                                              c[K.PISTON_DAMPING, lane])
    # viscous and regularised Coulomb slopes of the supports' friction
    matrix[DOF_REDUCER, DOF_REDUCER] += h * reducer.friction_slope_at(x, c, lane)
    matrix[DOF_SCREW, DOF_SCREW] += h * (c[K.SCREW_DAMPING, lane] + stribeck_slope(
        x[S.SCREW_SPEED, lane], c[K.SCREW_FRICTION_STATIC, lane], c[K.SCREW_FRICTION_DYNAMIC, lane],
        c[K.SCREW_FRICTION_VISCOUS, lane], c[K.ANGULAR_V_THRESHOLD, lane]))
    for nut in range(2):
        dof = DOF_NUT1 if nut == 0 else DOF_NUT2
        matrix[dof, dof] += guides.friction_slope_at(x, c, lane, nut, h)


@numba.njit(**SCALAR)
def current_loop_jacobian(x, c, u, lane, jacobian):
    """Jacobian of the full current loop (:func:`twin.engine.plant._drive_current_at`) over
    :data:`CURRENT_LOOP_STATES` of lane ``lane`` into ``jacobian[:3, :3]``: the loop is linear (Eq. 9.1, the Hall
    sensor's first-order lag, the analog PI) between the inverter's voltage limits; on the limit the voltage is
    constant and only the anti-windup feedback remains. The back-EMF and temperature couplings are left explicit."""
    demand_voltage = (c[K.CURRENT_KP, lane] * (u[U.CURRENT_DEMAND, lane] - x[S.HALL_CURRENT, lane])
                      + x[S.CURRENT_PI, lane])
    limit = c[K.VOLTAGE_LIMIT, lane]
    saturated = min(max(demand_voltage, -limit), limit) != demand_voltage
    inductance = c[K.INDUCTANCE, lane]
    jacobian[0, 0] = -winding_resistance(x[S.WINDING_TEMP, lane], c[K.R20, lane], c[K.R_TEMP_COEF, lane]) / inductance
    jacobian[0, 1] = 0.0 if saturated else -c[K.CURRENT_KP, lane] / inductance
    jacobian[0, 2] = 0.0 if saturated else 1.0 / inductance
    jacobian[1, 0] = 1.0 / c[K.HALL_TAU, lane]
    jacobian[1, 1] = -1.0 / c[K.HALL_TAU, lane]
    jacobian[1, 2] = 0.0
    jacobian[2, 0] = 0.0
    jacobian[2, 1] = -c[K.CURRENT_KI, lane] + (c[K.CURRENT_KP, lane] / c[K.CURRENT_AW_TIME, lane] if saturated else 0.0)
    jacobian[2, 2] = -1.0 / c[K.CURRENT_AW_TIME, lane] if saturated else 0.0
