"""The screw shaft: rotation (Eq. 9.7) and axial displacement (Sec. 9.3):
its entries in the model's vocabulary (:mod:`twin.layout`).
"""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e
from twin.vocabulary.entries import work as _w

DECLARATION = Component("screw", states=(
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
), work=(
    _w("AXIAL_STIFFNESS", "N/m", "screw axial stiffness seen by the nuts"),
    _w("AXIAL_GRADIENT", "N", "the axial spring energy's push on the sled"),
    _w("NUT_KINEMATIC", "m", "dx_i without the screw's axial displacement (quasi-static balance)", rows=2),
    _w("NUT_RATE", "m/s", "its rate", rows=2),
    _w("BALANCE_DONE", "1", "1.0 once the lane's quasi-static balance has converged in this evaluation"),
    _w("BALANCE_FAILED", "1", "1.0 if a balance of this run ever ran out of iterations (the guard reads it)"),
))
