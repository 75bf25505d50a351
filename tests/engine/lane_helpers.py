"""One run as a one-lane group of the lane engine: what the physics and integrator tests drive directly.

The engine's arrays are ``[row, lane]`` (twin.engine.plant); a test that follows one run keeps its state as a
1-D vector and hands the engine the ``(rows, 1)`` view of it, so the state the test reads is the one the engine
wrote. Importable by the tests of tests/engine (conftest modules are not).
"""

from __future__ import annotations

import numpy as np

from twin.engine.integrators import Workspace, step
from twin.engine.plant import internal_forces, rhs, work_rows
from twin.layout import N_INPUTS, N_STATES


def column(vector: np.ndarray) -> np.ndarray:
    """The ``(rows, 1)`` lane view of a contiguous 1-D array (writes go through to ``vector``)."""
    view = vector.reshape(-1, 1)
    assert np.shares_memory(view, vector)
    return view


class OneLane:
    """A model's constants, held inputs and integrator workspace as a group of one lane.

    ``constants`` is the model's own array (an edit of ``model.constants`` reaches the engine); ``u`` the held
    inputs (:class:`twin.layout.U`), zero unless the test sets them.
    """

    def __init__(self, model):
        self.model = model
        self.c = column(model.constants)
        self.u = np.zeros((N_INPUTS, 1))
        self.vectors, self.w, self.matrices, self.cache, self.small = Workspace(N_STATES, 1).arrays()

    def step(self, method: int, t: float, x: np.ndarray, h: float, refresh: bool = False) -> None:
        """One integrator step of ``x`` (1-D, full layout, in place)."""
        m = self.model
        step(method, t, column(x), h, self.c, self.u, m.levels, m.force_table, self.vectors[:6], self.w,
             self.matrices, self.cache, self.small, refresh, m.active, m.pairs)

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        """``dx/dt`` at ``x`` (1-D); the work rows of the evaluation stay in :attr:`w`. States the fidelity removes
        get a zero derivative. At the quasi-static screw-axial level the balance writes ``x``'s screw-axial rows."""
        dxdt = np.zeros((N_STATES, 1))
        rhs(t, column(x), self.c, self.u, self.model.levels, self.model.force_table, dxdt, self.w)
        return dxdt[:, 0]

    def forces(self, t: float, x: np.ndarray) -> np.ndarray:
        """The work rows (:class:`twin.engine.plant.W`) of :func:`internal_forces` at ``x``, as a 1-D copy."""
        w = work_rows(1)
        internal_forces(t, column(x), self.c, w, 1, self.model.levels, self.model.force_table)
        return w[:, 0].copy()
