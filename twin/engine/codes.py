"""The integer codes the compiled engine branches on, derived from the one table of fidelity levels.

numba reads a module-level integer as a compile-time constant, so the kernels write
``levels[PNEUMATICS] == PNEUMATICS_FULL`` at no cost. Each name here is derived from :data:`twin.levels.SUBSYSTEMS`
(:func:`twin.levels.subsystem_index`, :func:`twin.levels.level_code`): a level is declared there and nowhere
else. A group of lanes shares its levels (one model configuration), so a branch on them takes the same side in
every lane.
"""

from twin.levels import level_code, subsystem_index
from twin.physics import ball_screw

PNEUMATICS = subsystem_index("pneumatics")
PNEUMATICS_FULL = level_code("pneumatics", "full")
PNEUMATICS_IDEAL = level_code("pneumatics", "ideal")

# the seal friction's codes: twin.components.seal

CURRENT_LOOP = subsystem_index("current_loop")
CURRENT_LOOP_FULL = level_code("current_loop", "full")

MOTOR_THERMAL = subsystem_index("motor_thermal")
THERMAL_DYNAMIC = level_code("motor_thermal", "dynamic")

CONTACT = subsystem_index("contact")

BALL_GROOVE_FRICTION = subsystem_index("ball_groove_friction")
BALL_GROOVE_FRICTION_CHAPTER5 = level_code("ball_groove_friction", "chapter5")

SCREW_AXIAL = subsystem_index("screw_axial")
SCREW_AXIAL_DYNAMIC = level_code("screw_axial", "dynamic")

NUT_ROTATION = subsystem_index("nut_rotation")
NUT_ROTATION_ON = level_code("nut_rotation", "on")

ENCODERS = subsystem_index("encoders")
ANALOG_SENSORS = subsystem_index("analog_sensors")
TORQUE_METER_REFRESH = subsystem_index("torque_meter_refresh")
OUTPUT_CONVERTERS = subsystem_index("output_converters")

# The contact law's own codes (twin.physics.ball_screw) are the contact levels' codes.
if (level_code("contact", "variable_angle"), level_code("contact", "constant_angle"), level_code("contact", "linear")) \
        != (ball_screw.CONTACT_VARIABLE_ANGLE, ball_screw.CONTACT_CONSTANT_ANGLE, ball_screw.CONTACT_LINEAR):
    raise ImportError("twin.levels' contact levels and twin.physics.ball_screw's CONTACT_* codes disagree")
