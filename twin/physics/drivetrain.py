"""Lumped properties of the drivetrain derived from the component parameters (Sec. 9.3).

One home for the screw-shaft mass and inertia and the series torsional stiffness: the simulation model
(:mod:`twin.engine.model`) and the loop design (:mod:`twin.control.design`) both take them from here.
"""

from __future__ import annotations

import math
from collections.abc import Mapping


def screw_mass(p: Mapping[str, float]) -> float:
    """Screw-shaft mass, a solid steel cylinder of the pitch diameter over the screw length [kg].

    ``m_s = rho pi r_p^2 L`` (Sec. 9.3; the shaft of Table B.9 modelled as a solid cylinder, an assumption of
    ``twin/parameters/bench/ball_screw.toml``).
    """
    return p["ball_screw.screw_density"] * math.pi * p["ball_screw.pitch_radius"] ** 2 * p["ball_screw.screw_length"]


def screw_inertia(p: Mapping[str, float]) -> float:
    """Screw-shaft polar inertia, solid cylinder of the pitch diameter (J_s of Eq. 9.7) [kg m^2]: ``m_s r_p^2 / 2``."""
    return 0.5 * screw_mass(p) * p["ball_screw.pitch_radius"] ** 2


def torsional_stiffness(p: Mapping[str, float]) -> float:
    """Series stiffness of reducer, two couplings and torque meter (Sec. 9.3) [N m/rad]."""
    compliance = (
        1.0 / p["reducer.torsional_stiffness"]
        + 2.0 / p["drivetrain.coupling_stiffness"]
        + 1.0 / p["drivetrain.torque_meter_stiffness"]
    )
    return 1.0 / compliance
