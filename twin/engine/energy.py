"""Stored and kinetic energy of the mechanical chain, for energy-balance checks."""

from __future__ import annotations

import numpy as np
from scipy.integrate import quad

from twin.components import COMPONENTS
from twin.engine.codes import CONTACT
from twin.engine.model import contact_force
from twin.engine.plant import W, internal_forces, work_rows
from twin.layout import K, S


def contact_energy(c: np.ndarray, contact_model: int, relative_position: float) -> float:
    """Elastic energy of one nut's contact: the integral of its static axial force over ``dx`` [J]."""
    half_gap = 0.5 * c[K.BACKLASH]
    if abs(relative_position) <= half_gap:
        return 0.0
    side = np.sign(relative_position)
    value, _ = quad(lambda d: side * contact_force(c, contact_model, side * d), half_gap, abs(relative_position),
                    epsabs=1e-14, epsrel=1e-11, limit=200)
    return value


def mechanical_energy(x: np.ndarray, model) -> float:
    """Kinetic plus elastic energy of the drivetrain, screw, nuts and preload spring of one run [J].

    Covers every spring of :func:`twin.engine.plant.rhs` (torsional elasto-backlash,
    screw axial support and shaft twist, ball-groove contacts, guides' roll stiffness, preload set).
    The preload damping/saturation and the external force are not included:
    use it with those inactive. ``x`` is the run's full state.
    """
    c = model.constants
    lane_x = np.array(x, dtype=float).reshape(-1, 1)
    w = work_rows(1)
    internal_forces(0.0, lane_x, c.reshape(-1, 1), w, 1, model.levels, model.force_table)
    kinetic = 0.5 * (
        c[K.J_SCREW_SIDE] * x[S.SCREW_SPEED] ** 2
        + c[K.SCREW_MASS] * x[S.SCREW_AXIAL_SPEED] ** 2
        + c[K.NUT1_MASS] * x[S.NUT1_SPEED] ** 2
        + c[K.NUT2_MASS] * x[S.NUT2_SPEED] ** 2
        + c[K.J_NUT] * (x[S.NUT1_ANGULAR_SPEED] ** 2 + x[S.NUT2_ANGULAR_SPEED] ** 2)
    )
    elastic = 0.5 * w[W.AXIAL_STIFFNESS, 0] * lane_x[S.SCREW_AXIAL, 0] ** 2
    contact_model = int(model.levels[CONTACT])
    for nut in (0, 1):
        elastic += contact_energy(c, contact_model, w[W.NUT_DX + nut, 0])
    for component in COMPONENTS:
        component_kinetic, component_elastic = component.energy(x, c)
        kinetic += component_kinetic
        elastic += component_elastic
    return float(kinetic + elastic)
