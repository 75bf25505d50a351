"""The cylinder's seal friction (Eq. 9.11 with Eq. 7.63, the elasto-plastic presliding law):
its entries in the model's vocabulary (:mod:`twin.layout`).
"""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e

DECLARATION = Component("seal", states=(
    _e("SEAL_DEFLECTION", "m", "presliding deflection z of the cylinder seals (the elasto-plastic seal-friction "
                               "level, twin.physics.bristle_friction)"),
), constants=(
    _e("CYLINDER_FRICTION_STATIC", "N", "seals' breakaway friction F_s (Eq. 7.63)", "pneumatics.friction_static"),
    _e("CYLINDER_FRICTION_DYNAMIC", "N", "seals' Coulomb friction F_d (Eq. 7.63)", "pneumatics.friction_dynamic"),
    _e("CYLINDER_FRICTION_RATE", "s/m", "seals' Stribeck rate a (Eq. 7.63)",
       "pneumatics.friction_stribeck_coefficient"),
    _e("CYLINDER_FRICTION_VISCOUS", "N s/m", "seals' viscous friction sigma_2 = b (Eq. 7.63)",
       "pneumatics.friction_viscous"),
    _e("CYLINDER_V_THRESHOLD", "m/s", "sign regularisation v_th of the regularised level",
       "pneumatics.friction_velocity_threshold"),
    _e("SEAL_STIFFNESS", "N/m", "seals' presliding stiffness sigma_0", "pneumatics.friction_presliding_stiffness"),
    _e("SEAL_DAMPING", "N s/m", "seals' presliding damping sigma_1", "pneumatics.friction_bristle_damping"),
    _e("SEAL_DAMPING_SPEED", "m/s", "speed v_d above which the presliding damping fades",
       "pneumatics.friction_bristle_damping_speed"),
    _e("SEAL_ELASTIC_DEFLECTION", "m", "z_ba: deflection up to which the seals are purely elastic, "
                                       "friction_elastic_fraction F_d / sigma_0"),
))
