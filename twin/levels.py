"""Fidelity levels of the bench's subsystems: the one table of what each level models, removes and is coded as.

Every subsystem lists its levels from the most detailed (the "full" model) to
the cheapest. A level that removes states takes them out of the integrated
state vector (:data:`Level.removes_states`); a level that makes a signal
meaningless takes it out of the simulation's output (:data:`Level.removes_signals`),
so a reduced model never returns a number it did not compute.

The compiled engine branches on integer codes: a subsystem's index in :data:`SUBSYSTEMS` and a level's index in
its subsystem (0 = full). :func:`level_code` derives them from this table, and the engine's named codes
(:data:`twin.engine.levels`) are built from it, so a level is declared here and nowhere else. Which levels the
automatic fidelity may choose, and why, is :mod:`twin.fidelity` (rules.toml).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from twin.layout import S

PNEUMATIC_STATES = (S.SPOOL_POSITION, S.SPOOL_SPEED, S.CHAMBER1_PRESSURE, S.CHAMBER2_PRESSURE, S.PISTON_POSITION,
                    S.PISTON_SPEED, S.SEAL_DEFLECTION)
PNEUMATIC_SIGNALS = ("chamber1_pressure", "chamber2_pressure", "valve_command", "piston_position")


@dataclass(frozen=True)
class Level:
    """One fidelity level of a subsystem."""

    name: str
    description: str
    removes_states: tuple[S, ...] = ()
    removes_signals: tuple[str, ...] = ()


@dataclass(frozen=True)
class Subsystem:
    """A subsystem and its levels, most detailed first."""

    name: str
    description: str
    levels: tuple[Level, ...]

    @property
    def full(self) -> str:
        return self.levels[0].name

    @property
    def level_names(self) -> tuple[str, ...]:
        return tuple(level.name for level in self.levels)

    def level(self, name: str) -> Level:
        return next(level for level in self.levels if level.name == name)


SUBSYSTEMS: dict[str, Subsystem] = {s.name: s for s in (
    Subsystem("pneumatics", "external-force system on the master nut (Eqs. 9.9-9.11)", (
        Level("full", "proportional valve, cylinder chambers, piston with seal friction and the load cell, "
                      "under the cRIO's digital force loop"),
        Level("ideal", "ideal force source: the external force is the scene's force demand",
              PNEUMATIC_STATES, PNEUMATIC_SIGNALS),
        Level("absent", "no external force", PNEUMATIC_STATES, PNEUMATIC_SIGNALS),
    )),
    # The elasto-plastic law is the full level: its acceptance (docs/accuracy.md, "Acceptance of the elasto-plastic
    # seal") shows the free-nut results converged under it (step halved: f_b within +/-0.05 um on ds2/4/6/7) where
    # the regularised law's smoothing speed moves them by more than the 1 um requirement (issue 41). The regularised
    # law stays as the cheaper level, for scenes whose audit shows it accurate.
    Subsystem("seal_friction", "friction of the cylinder's piston and rod seals (Eq. 9.11 with Eq. 7.63)", (
        Level("elasto_plastic", "elasto-plastic presliding law (Dupont et al. 2002) with Eq. 7.63 as its sliding "
                                "level: the seals hold the piston below breakaway, no smoothing speed"),
        Level("regularised", "Eq. 7.63 with sign(v) regularised as tanh(v / v_th): below v_th a viscous damper, "
                             "a force below breakaway makes the piston creep",
              (S.SEAL_DEFLECTION,)),
    )),
    Subsystem("current_loop", "drive current loop and motor winding (Eq. 9.1)", (
        Level("full", "power-consistent RL equivalent circuit with back-EMF, Hall current sensor and analog PI "
                      "with the inverter's voltage limit"),
        Level("ideal", "ideal torque source: the current follows the speed loop's demand through a first-order "
                       "lag at the designed loop bandwidth (controller.current_loop_bandwidth)",
              (S.HALL_CURRENT, S.CURRENT_PI)),
    )),
    Subsystem("motor_thermal", "winding temperature (Eq. 9.2)", (
        Level("dynamic", "winding temperature integrated from Joule losses, convection and radiation"),
        Level("frozen", "winding held at the start (room) temperature; the resistance stays at its start value",
              (S.WINDING_TEMP,), ("winding_temperature",)),
    )),
    Subsystem("contact", "ball-groove contact of the two nuts (Eqs. 9.4-9.6, 7.28, 7.29)", (
        Level("variable_angle", "Hertzian contact with the load-dependent contact angle of Eq. 9.4"),
        Level("constant_angle", "Hertzian contact at the design angle alpha_0"),
        Level("linear", "linear normal stiffness at the design angle, secant to the Hertz curve at the scene's "
                        "peak contact load (the elasto-backlash contact of Ch. 5)"),
    )),
    Subsystem("ball_groove_friction", "friction of the spheres on the screw and nut grooves (Eqs. 5.16-5.24)", (
        Level("chapter5", "reduced Ch. 5 friction on both nuts: sliding (Eq. 5.16) and load- and speed-dependent "
                          "rolling (Eqs. 5.19-5.24) at the contact loads, with the drag torque and efficiency"),
        Level("lumped", "lossless screw-nut conversion: the support bearings' lumped friction only",
              removes_signals=("ball_groove_friction_torque", "ball_screw_efficiency")),
    )),
    Subsystem("screw_torsion", "torsion of the screw shaft between the coupling and the nuts", (
        Level("static", "static torsional compliance of the shaft core under the nuts' torque, in series with its "
                        "axial compliance"),
        Level("rigid", "torsionally rigid shaft", removes_signals=("screw_twist",)),
    )),
    Subsystem("screw_axial", "the screw shaft's axial displacement between the rear bearing and the ball contacts", (
        Level("dynamic", "the shaft's axial mass integrated between the bearing (in series with the shaft) and the two "
                         "ball-groove contacts: a 3.8-4.8 kHz mode (Sec. 9.3)"),
        Level("quasi_static", "massless: its displacement solves the elastic balance of bearing and contacts at every "
                              "evaluation (Newton), its speed the balance's time derivative",
              (S.SCREW_AXIAL, S.SCREW_AXIAL_SPEED)),
    )),
    Subsystem("nut_rotation", "nut roll on the linear guides (Sec. 9.3)", (
        Level("on", "each nut's roll angle integrated against the guides' roll stiffness"),
        Level("off", "rigid guides: the nuts do not roll",
              (S.NUT1_ANGLE, S.NUT1_ANGULAR_SPEED, S.NUT2_ANGLE, S.NUT2_ANGULAR_SPEED)),
    )),
    Subsystem("encoders", "linear encoder, torque-meter encoder and resolver (twin.engine.instrumentation)", (
        Level("full", "edge-accurate quadrature counts with phase, asymmetry and precision errors"),
        Level("quantized", "resolution only, no errors"),
        Level("ideal", "true positions and angles"),
    )),
    Subsystem("analog_sensors", "torque meter, load cells and current monitor (twin.engine.instrumentation)", (
        Level("full",
              "sensitivity, offset and temperature errors, electrical noise (Table 9.5), converters and filters"),
        Level("quantized", "converters and filters only, no errors and no noise"),
        Level("ideal", "true forces, torque and current"),
    )),
    Subsystem("torque_meter_refresh", "torque meter's rotor-to-stator streaming (Table B.5)", (
        Level("modelled", "sample-and-hold at the 1 kHz refresh"),
        Level("ideal", "continuous output"),
    )),
    Subsystem("output_converters", "controller output converters (drive speed input, valve-command D/A)", (
        Level("quantized", "word lengths of Table B.3 and controller.valve_command_dac_bits"),
        Level("ideal", "no quantisation"),
    )),
)}


def level_code(subsystem: str, level: str) -> int:
    """The engine's integer code of a level: its index in its subsystem (0 = the full level)."""
    return SUBSYSTEMS[subsystem].level_names.index(level)


def subsystem_index(subsystem: str) -> int:
    """The engine's index of a subsystem in an array of level codes (:func:`level_codes`)."""
    return list(SUBSYSTEMS).index(subsystem)


def level_codes(levels) -> np.ndarray:
    """``{subsystem: level}`` (every subsystem) as the int64 array of codes the compiled engine reads."""
    return np.array([level_code(name, levels[name]) for name in SUBSYSTEMS], dtype=np.int64)
