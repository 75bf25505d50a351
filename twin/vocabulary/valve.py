"""The proportional valve and the force loop (Eq. 9.9): its entries in the model's vocabulary (:mod:`twin.layout`)."""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e

DECLARATION = Component("valve", states=(
    _e("SPOOL_POSITION", "1", "normalised valve spool position [-1, 1]"),
    _e("SPOOL_SPEED", "1/s", "spool speed"),
), constants=(
    _e("VALVE_MID", "V", "valve mid-position command", "pneumatics.valve_mid_voltage"),
    _e("VALVE_MIN", "V", "lowest valve command"),
    _e("VALVE_MAX", "V", "highest valve command"),
    _e("VALVE_FREQUENCY", "Hz", "spool critical frequency"),
    _e("VALVE_DAMPING", "1", "spool damping ratio"),
    _e("VALVE_HYSTERESIS", "1", "valve hysteresis, fraction of the command span"),
    _e("VALVE_COMMAND_BITS", "1", "word length (sign incl.) of the valve-command D/A; 0 = not quantised"),
    _e("FORCE_KP", "V/N", "force-PI proportional gain", "controller.force_kp"),
    _e("FORCE_KI", "V/(N s)", "force-PI integral gain", "controller.force_ki"),
    _e("FORCE_FEEDBACK_NOISE", "1", "1: the force loop reads the load cell with its electrical noise "
                                    "(scene noise_path = feedback); 0: without it (recorded)"),
), signals=(
    _e("FORCE_DEMAND", "N", "external force demand"),
    _e("VALVE_COMMAND", "V", "effective proportional-valve command"),
))
