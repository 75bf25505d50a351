"""The linear guides of the sled: its entries in the model's vocabulary (:mod:`twin.layout`)."""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e

DECLARATION = Component("guides", constants=(
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
))
