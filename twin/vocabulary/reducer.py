"""The reducer and the torsional chain it drives (Eq. 9.3, Sec. 9.3):
its entries in the model's vocabulary (:mod:`twin.layout`).
"""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e
from twin.vocabulary.entries import work as _w

DECLARATION = Component("reducer", states=(
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
), work=(
    _w("TORQUE", "N m", "T_tm through couplings and torque meter"),
))
