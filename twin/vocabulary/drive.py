"""The drive: Hall sensor, current and speed loops: its entries in the model's vocabulary (:mod:`twin.layout`)."""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e

DECLARATION = Component("drive", states=(
    _e("HALL_CURRENT", "A", "first-order Hall sensor output"),
    _e("CURRENT_PI", "V", "analog current-PI integrator"),
), constants=(
    _e("VOLTAGE_LIMIT", "V", "largest voltage the inverter applies to the equivalent circuit, "
                             "(3/sqrt 2) m_max V_DC (twin.physics.motor.equivalent_voltage_limit)"),
    _e("HALL_TAU", "s", "Hall sensor time constant", "drive.hall_time_constant"),
    _e("CURRENT_AW_TIME", "s", "current-PI anti-windup time", "drive.current_antiwindup_time"),
    _e("CURRENT_KP", "V/A", "current-PI proportional gain", "controller.current_kp"),
    _e("CURRENT_KI", "V/(A s)", "current-PI integral gain", "controller.current_ki"),
    _e("CURRENT_LOOP_TAU", "s", "time constant of the ideal current loop, 1 / (2 pi bandwidth)"),
    _e("SPEED_KP", "A s/rad", "speed-PI proportional gain", "controller.speed_kp"),
    _e("SPEED_KI", "A/rad", "speed-PI integral gain", "controller.speed_ki"),
    _e("SPEED_FULL_SCALE", "rad/s", "speed command full scale", "drive.speed_command_full_scale"),
    _e("SPEED_COMMAND_BITS", "1", "word length (sign incl.) of the drive's analog speed input; 0 = not quantised"),
    _e("MAX_MOTOR_SPEED", "rad/s", "guard: twice the motor's maximum permissible speed"),
    _e("MAX_TEMPERATURE", "K", "guard: winding temperature limit"),
), signals=(
    _e("SPEED_COMMAND", "rad/s", "motor speed command after the drive's analog input"),
    _e("CURRENT_DEMAND", "A", "current demand of the speed loop"),
))
