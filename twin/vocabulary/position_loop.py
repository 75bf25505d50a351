"""The position loop and the encoders' zero: its entries in the model's vocabulary (:mod:`twin.layout`)."""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e

DECLARATION = Component("position_loop", constants=(
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
))
