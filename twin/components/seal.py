"""The friction of the pneumatic cylinder's piston and rod seals (Eq. 9.11 with Eq. 7.63), the whole component in one
module: the elasto-plastic presliding law (Dupont et al. 2002, :mod:`twin.physics.bristle_friction`) with Eq. 7.63
as its sliding level, or Eq. 7.63 regularised (:func:`twin.physics.friction.stribeck_friction`), by its fidelity
level ``seal_friction`` (:mod:`twin.levels`).

What it holds, and who reads it:

* the derivation of its constants from its parameters (:func:`derive_constants`: the deflection up to which the
  seals are purely elastic; the others copy a parameter, their ``Entry.parameter``);
* its laws (:func:`friction_at`): the friction force on the piston and, at the elasto-plastic level, the rate of
  the seals' presliding deflection ``z``;
* no stage of its own: the piston's Eq. 9.11 calls its law (:func:`friction_at`, one lane,
  :data:`numerics.jit.SCALAR`) in the load system's stage (:mod:`twin.engine.plant`), as the nuts take the preload's
  share, so it runs with the full pneumatic load system only;
* its contribution to the linearly implicit step's tangent (:func:`tangent_at`: the friction's slope on the piston,
  placed by :mod:`twin.engine.implicit`);
* its energy (:func:`energy`: the seals' stored ``sigma_0 z^2 / 2``) and the reference integrator's tolerance of its
  state (:data:`ABSOLUTE_TOLERANCES`).

Its state and constants are declared in its leaf module, :mod:`twin.vocabulary.seal`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numba
import numpy as np

from numerics.elementary import exp
from numerics.jit import SCALAR
from twin.components.conditions import Conditions
from twin.layout import K, S
from twin.levels import level_code, subsystem_index
from twin.physics.bristle_friction import bristle_force, elastoplastic_deflection_rate
from twin.physics.friction import stribeck_friction, stribeck_level, stribeck_slope

NAME = "seal"
#: The seal's fidelity levels (subsystems of :mod:`twin.levels`).
LEVELS: tuple[str, ...] = ("seal_friction",)
#: Absolute tolerance of its state on the reference path (:mod:`twin.engine.reference`): the deflection to 1e-13 m,
#: as the other positions (1e-7 of a micrometre feature).
ABSOLUTE_TOLERANCES = {S.SEAL_DEFLECTION: 1e-13}

#: The engine's codes of its level: its index in an array of level codes and the elasto-plastic level's code
#: (:func:`twin.levels.subsystem_index`, :func:`twin.levels.level_code`).
SEAL_FRICTION = subsystem_index("seal_friction")
ELASTO_PLASTIC = level_code("seal_friction", "elasto_plastic")


def derive_constants(c: np.ndarray, p: Mapping[str, float], scene: Conditions) -> None:
    """Fill the seal's derived constant into ``c`` (layout :class:`twin.layout.K`): ``z_ba``, the deflection up to
    which the seals are purely elastic, the fraction ``pneumatics.friction_elastic_fraction`` of the smallest steady
    deflection ``F_d / sigma_0`` (Dupont et al. 2002, Eq. 9). The scene's conditions do not enter."""
    c[K.SEAL_ELASTIC_DEFLECTION] = (p["pneumatics.friction_elastic_fraction"] * p["pneumatics.friction_dynamic"]
                                    / p["pneumatics.friction_presliding_stiffness"])


@numba.njit(**SCALAR)
def friction_at(x, c, dxdt, lane, level):
    """The seals' friction force on the piston [N] (opposing positive piston speed) of lane ``lane`` at the
    seal-friction ``level``; at the elasto-plastic level also the deflection rate ``dz/dt`` into ``dxdt``.

    Elasto-plastic: :func:`twin.physics.bristle_friction.bristle_force` with the rate of
    :func:`~twin.physics.bristle_friction.elastoplastic_deflection_rate` and Eq. 7.63's sliding level without its
    regularisation (:func:`twin.physics.friction.stribeck_level`). Regularised: Eq. 7.63 with ``sign(v)`` as
    ``tanh(v / v_th)`` (:func:`twin.physics.friction.stribeck_friction`)."""
    v = x[S.PISTON_SPEED, lane]
    if level == ELASTO_PLASTIC:
        z = x[S.SEAL_DEFLECTION, lane]
        sliding = stribeck_level(v, c[K.CYLINDER_FRICTION_STATIC, lane], c[K.CYLINDER_FRICTION_DYNAMIC, lane],
                                 c[K.CYLINDER_FRICTION_RATE, lane])
        rate = elastoplastic_deflection_rate(v, z, sliding, c[K.SEAL_STIFFNESS, lane],
                                             c[K.SEAL_ELASTIC_DEFLECTION, lane])
        dxdt[S.SEAL_DEFLECTION, lane] = rate
        return bristle_force(v, z, rate, c[K.SEAL_STIFFNESS, lane], c[K.SEAL_DAMPING, lane],
                             c[K.SEAL_DAMPING_SPEED, lane], c[K.CYLINDER_FRICTION_VISCOUS, lane])
    return stribeck_friction(v, c[K.CYLINDER_FRICTION_STATIC, lane], c[K.CYLINDER_FRICTION_DYNAMIC, lane],
                             c[K.CYLINDER_FRICTION_RATE, lane], c[K.CYLINDER_FRICTION_VISCOUS, lane],
                             c[K.CYLINDER_V_THRESHOLD, lane])


@numba.njit(**SCALAR)
def tangent_at(x, c, lane, level, damping):
    """``damping`` (the piston's own viscous damping [N s/m]) plus the slope of the seals' friction on the piston
    [N s/m], in the linearly implicit step's tangent. Elasto-plastic: the bristle law's slope in presliding
    (``dz/dt = v``), ``sigma_1 exp(-(v/v_d)^2) + sigma_2``; the deflection itself stays explicit (its mode is far
    below the step's limit, docs/accuracy.md). Regularised: :func:`twin.physics.friction.stribeck_slope`."""
    if level == ELASTO_PLASTIC:
        u_d = x[S.PISTON_SPEED, lane] / c[K.SEAL_DAMPING_SPEED, lane]
        return damping + c[K.CYLINDER_FRICTION_VISCOUS, lane] + c[K.SEAL_DAMPING, lane] * exp(-u_d * u_d)
    return damping + stribeck_slope(x[S.PISTON_SPEED, lane], c[K.CYLINDER_FRICTION_STATIC, lane],
                                    c[K.CYLINDER_FRICTION_DYNAMIC, lane], c[K.CYLINDER_FRICTION_VISCOUS, lane],
                                    c[K.CYLINDER_V_THRESHOLD, lane])


def energy(x: np.ndarray, c: np.ndarray) -> tuple[float, float]:
    """Kinetic (none: the seals move with the piston) and elastic energy of the seals of one run ``(kinetic,
    elastic)`` [J]: the presliding deflection's ``sigma_0 z^2 / 2`` (the stored energy of the bristle laws,
    :mod:`twin.physics.bristle_friction`)."""
    return 0.0, 0.5 * c[K.SEAL_STIFFNESS] * x[S.SEAL_DEFLECTION] ** 2
