"""The measured signals: its entries in the model's vocabulary (:mod:`twin.layout`)."""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e

DECLARATION = Component("instruments", signals=(
    # measured signals, held at their last acquisition sample (twin.engine.instrumentation)
    _e("LINEAR_ENCODER_POSITION", "m", "sled position read by the linear encoder (zeroed at t = 0)"),
    _e("SCREW_ANGLE_MEASURED", "rad", "screw angle read by the torque-meter encoder (zeroed at t = 0)"),
    _e("NUT_SPEED_MEASURED", "m/s", "sled speed from the linear encoder (period/frequency method)"),
    _e("MOTOR_SPEED_MEASURED", "rad/s", "motor speed estimated by the drive from the resolver"),
    _e("MOTOR_CURRENT_MEASURED", "A", "motor current acquired through the current monitor"),
    _e("TORQUE_MEASURED", "N m", "torque-meter reading"),
    _e("PRELOAD_FORCE_MEASURED", "N", "preload load-cell reading"),
    _e("EXTERNAL_FORCE_MEASURED", "N", "external-force load-cell reading"),
))
