"""The preload set between the two nuts: disc springs in series with the preload load cell (Secs. 9.2-9.3), the
whole component in one module.

What it holds, and who reads it:

* the derivation of its constants from its parameters and the scene's preload condition (:func:`derive_constants`,
  :func:`assembled_compression`: :func:`twin.engine.model.build_model` and its initial equilibrium);
* its law: the one-directional spring-damper of :func:`twin.physics.preload.preload_force` (:func:`force_at`) and
  its action on each nut (:func:`nut_share_at`, Eq. 9.8);
* its lane stage, one lane at a time (``*_at``, :data:`numerics.jit.SCALAR`), composed split or fused by
  :mod:`twin.engine.plant`;
* its contribution to the linearly implicit step's tangent (:func:`tangent_at`, placed by :mod:`twin.engine.implicit`
  between the two nuts);
* its energy terms (:func:`energy`, :mod:`twin.engine.energy`); it has no states (:data:`ABSOLUTE_TOLERANCES` empty)
  and no fidelity levels (:data:`LEVELS`).

Its constants, signal and work row are declared in its leaf module, :mod:`twin.vocabulary.preload`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numba
import numpy as np

from numerics.jit import SCALAR
from twin.components.conditions import Conditions
from twin.layout import K, S, W
from twin.physics.preload import preload_force, series_stiffness

NAME = "preload"
#: The preload's fidelity levels (subsystems of :mod:`twin.levels`): none.
LEVELS: tuple[str, ...] = ()
#: It has no states of its own.
ABSOLUTE_TOLERANCES: dict = {}


def derive_constants(c: np.ndarray, p: Mapping[str, float], scene: Conditions) -> None:
    """Fill the preload's constants into ``c`` (layout :class:`twin.layout.K`): the series stiffness of the disc
    springs and the load cell and the damping (both zero without a preload: the set is then not mounted) and the
    orientation, +1 for the O configuration (nuts pushed apart), -1 for X. Its compression at the assembled position
    follows from the initial equilibrium (:func:`assembled_compression`)."""
    preload = scene.condition("preload")
    c[K.PRELOAD_STIFFNESS] = (series_stiffness(p["preload.spring_stiffness"], p["preload.load_cell_stiffness"])
                              if preload > 0 else 0.0)
    c[K.PRELOAD_DAMPING] = p["preload.damping"] if preload > 0 else 0.0
    c[K.PRELOAD_ORIENTATION] = 1.0 if scene.condition("preload_configuration") == "O" else -1.0


def assembled_compression(c: np.ndarray, preload: float, separation: float = 0.0) -> float:
    """Spring-set compression [m] at the assembled position that makes the set push with ``preload`` [N] when the
    nuts sit ``separation = x_n2 - x_n1`` [m] from it (0 for the unloaded start of the thesis procedure); 0 without a
    preload."""
    if preload <= 0.0:
        return 0.0
    return preload / c[K.PRELOAD_STIFFNESS] + c[K.PRELOAD_ORIENTATION] * separation


@numba.njit(**SCALAR)
def force_at(x, c, lane):
    """Preload magnitude ``F_pr >= 0`` [N] of lane ``lane`` (:func:`twin.physics.preload.preload_force`)."""
    return preload_force(
        x[S.NUT2_POSITION, lane] - x[S.NUT1_POSITION, lane], x[S.NUT2_SPEED, lane] - x[S.NUT1_SPEED, lane],
        c[K.PRELOAD_COMPRESSION, lane], c[K.PRELOAD_STIFFNESS, lane], c[K.PRELOAD_DAMPING, lane],
        c[K.PRELOAD_ORIENTATION, lane])


@numba.njit(**SCALAR)
def nut_share_at(c, force, lane, master):
    """The preload ``force`` on a nut along +x [N]: it pushes the nuts apart (O, orientation +1) or draws them
    together (X, -1); ``master`` is 1.0 for the master nut (nut 1), 0.0 for the slave."""
    return (1.0 - 2.0 * master) * c[K.PRELOAD_ORIENTATION, lane] * force


@numba.njit(**SCALAR)
def tangent_at(x, c, lane):
    """The preload set's contribution to the implicit step's tangent: ``(engaged, stiffness, damping)`` of the spring
    between the slave nut (+1) and the master (-1); not engaged once the set is unloaded, and without its damping
    where the damping force would exceed the elastic one (the law then saturates it)."""
    orientation = c[K.PRELOAD_ORIENTATION, lane]
    compression = c[K.PRELOAD_COMPRESSION, lane] - orientation * (x[S.NUT2_POSITION, lane] - x[S.NUT1_POSITION, lane])
    if compression > 0.0:
        rate = x[S.NUT2_SPEED, lane] - x[S.NUT1_SPEED, lane]
        spring = c[K.PRELOAD_STIFFNESS, lane]
        damping = c[K.PRELOAD_DAMPING, lane] if c[K.PRELOAD_DAMPING, lane] * abs(rate) < spring * compression else 0.0
        return True, spring, damping
    return False, 0.0, 0.0


def energy(x: np.ndarray, c: np.ndarray) -> tuple[float, float]:
    """Kinetic (none: the set's mass is the nuts') and elastic energy of the preload set of one run ``(kinetic,
    elastic)`` [J]."""
    compression = c[K.PRELOAD_COMPRESSION] - c[K.PRELOAD_ORIENTATION] * (x[S.NUT2_POSITION] - x[S.NUT1_POSITION])
    return 0.0, 0.5 * c[K.PRELOAD_STIFFNESS] * max(compression, 0.0) ** 2


@numba.njit(**SCALAR)
def active(levels):
    """The set is always modelled (unmounted, its stiffness is zero)."""
    return True


@numba.njit(**SCALAR)
def forces_at(x, c, w, lane):
    """Its work row: the preload magnitude (:func:`force_at`) into ``W.PRELOAD``; the nuts take their shares
    (:func:`nut_share_at`)."""
    w[W.PRELOAD, lane] = force_at(x, c, lane)

