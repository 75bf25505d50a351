"""The linear guides the nuts ride on (Sec. 9.3): their friction on each nut (Eq. 7.63) and their roll stiffness
against the nuts' roll, the whole component in one module.

What it holds, and who reads it:

* the derivation of its constants from its parameters (:func:`derive_constants`: the check of its Eq. 7.63 levels
  and each nut's share of the friction law; the others copy a parameter, their ``Entry.parameter``);
* its law: the regularised Eq. 7.63 on a nut (:func:`friction_at`), which the nuts' Eq. 9.8 takes in their stage
  (:mod:`twin.engine.plant`), as it takes the preload's share: no stage of its own;
* its contribution to the linearly implicit step's tangent (:func:`friction_slope_at`, placed by
  :mod:`twin.engine.implicit` on each nut; the roll springs' stiffness and damping are its constants);
* its energy terms (:func:`energy`: the roll springs' ``k theta^2 / 2``); it has no states
  (:data:`ABSOLUTE_TOLERANCES` empty);
* its fidelity level: the nuts' roll on it, ``nut_rotation`` (:mod:`twin.levels`).

Its constants and signal are declared in its leaf module, :mod:`twin.vocabulary.guides` (each nut's share with the
nut, :mod:`twin.vocabulary.nut`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numba
import numpy as np

from numerics.jit import SCALAR
from twin.components.conditions import Conditions
from twin.errors import ParameterError
from twin.layout import NUT_CONSTANT_STRIDE, NUT_STATE_STRIDE, K, S
from twin.physics.friction import level_problems, stribeck_friction, stribeck_slope

NAME = "guides"
#: The guides' fidelity levels (subsystems of :mod:`twin.levels`): the nuts' roll on them.
LEVELS: tuple[str, ...] = ("nut_rotation",)
#: It has no states of its own.
ABSOLUTE_TOLERANCES: dict = {}


def derive_constants(c: np.ndarray, p: Mapping[str, float], scene: Conditions) -> None:
    """Check the guides' Eq. 7.63 levels and fill each nut's share of the friction law into ``c`` (layout
    :class:`twin.layout.K`): the master nut carries the law (1), the slave ``sled.slave_friction_fraction`` of it.
    The scene's conditions do not enter.

    Raises
    ------
    ParameterError
        If the levels are not finite and >= 0, or the breakaway is below the Coulomb level
        (:func:`twin.physics.friction.level_problems`).
    """
    problems = level_problems("sled.guide_friction_static", p["sled.guide_friction_static"],
                              "sled.guide_friction_dynamic", p["sled.guide_friction_dynamic"])
    if problems:
        raise ParameterError(problems)
    c[K.NUT1_GUIDE_FRICTION_SHARE] = 1.0
    c[K.NUT2_GUIDE_FRICTION_SHARE] = p["sled.slave_friction_fraction"]


@numba.njit(**SCALAR)
def friction_at(x, c, lane, nut):
    """The guides' friction on nut ``nut`` (0: master, 1: slave) [N], opposing its speed: its share of the
    regularised Eq. 7.63 (:func:`twin.physics.friction.stribeck_friction`)."""
    return c[K.NUT1_GUIDE_FRICTION_SHARE + NUT_CONSTANT_STRIDE * nut, lane] * stribeck_friction(
        x[S.NUT1_SPEED + NUT_STATE_STRIDE * nut, lane], c[K.GUIDE_FRICTION_STATIC, lane],
        c[K.GUIDE_FRICTION_DYNAMIC, lane], c[K.GUIDE_FRICTION_RATE, lane], c[K.GUIDE_FRICTION_VISCOUS, lane],
        c[K.LINEAR_V_THRESHOLD, lane])


@numba.njit(**SCALAR)
def friction_slope_at(x, c, lane, nut, h):
    """``h`` [s] times the slope of :func:`friction_at` on nut ``nut`` [N s/m] (its share of
    :func:`twin.physics.friction.stribeck_slope`, the dissipative part): what the implicit step's tangent adds on the
    nut's diagonal, the step first as the matrix takes it."""
    return h * c[K.NUT1_GUIDE_FRICTION_SHARE + NUT_CONSTANT_STRIDE * nut, lane] * stribeck_slope(
        x[S.NUT1_SPEED + NUT_STATE_STRIDE * nut, lane], c[K.GUIDE_FRICTION_STATIC, lane],
        c[K.GUIDE_FRICTION_DYNAMIC, lane], c[K.GUIDE_FRICTION_VISCOUS, lane], c[K.LINEAR_V_THRESHOLD, lane])


def energy(x: np.ndarray, c: np.ndarray) -> tuple[float, float]:
    """Kinetic (none: the nuts carry their own) and elastic energy of the guides of one run ``(kinetic, elastic)``
    [J]: the roll springs' ``k (theta_n1^2 + theta_n2^2) / 2``."""
    return 0.0, 0.5 * c[K.GUIDE_ROLL_STIFFNESS] * (x[S.NUT1_ANGLE] ** 2 + x[S.NUT2_ANGLE] ** 2)
