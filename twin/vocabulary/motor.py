"""The motor (Eqs. 9.1-9.2): its entries in the model's vocabulary (:mod:`twin.layout`)."""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e

DECLARATION = Component("motor", states=(
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
))
