"""A lane group: the runs that advance together through one compiled loop, and the call that solves them.

Runs share a group when they share everything the compiled loop branches on or steps by: the fidelity levels
(hence the integrated states), the scene's demand tables, the integrator and its steps. Their constants,
initial states, instruments and noise are their own, stacked as the columns (lanes) of ``[row, lane]`` arrays.
A run's numbers do not depend on which runs share its group, on how many, or in which order
(tests/engine/test_lanes.py): the compiled code never mixes lanes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from twin.engine.instrumentation import N_INSTRUMENTS, STATE_ROW, Instruments, group_timing
from twin.engine.integrators import Workspace
from twin.engine.loop import run_loop
from twin.engine.model import Model
from twin.layout import N_MEMORY, N_SIGNALS, N_STATES


@dataclass(frozen=True)
class Solved:
    """The loop's results for every lane of a group (lane ``l`` is the ``l``-th run given)."""

    state: np.ndarray        # (N_STATES, L) at the end (or, for a failed lane, its initial state)
    memory: np.ndarray       # (N_MEMORY, L): the loops' memory and the feature accumulators
    output: np.ndarray       # (rows, N_SIGNALS, L), NaN where a lane recorded nothing
    status: np.ndarray       # (L,) twin.layout.STATUS_*
    bound: np.ndarray        # (L,) guard code
    steps_done: np.ndarray   # (L,)
    rows_written: np.ndarray  # (L,)


def group_key(model: Model) -> tuple:
    """What runs must share to share a group: the fidelity levels, the integrated states and the demand tables
    (the integrator and its steps are the caller's, shared by construction)."""
    return (model.levels.tobytes(), model.active.tobytes(), model.position_table.tobytes(),
            model.force_table.tobytes())


def solve_group(models: Sequence[Model], instruments: Sequence[Instruments], *, n_steps: int, dt: float,
                speed_every: int, position_every: int, output_every: int, jacobian_every: int, method: int,
                tolerance: np.ndarray) -> Solved:
    """Integrate the runs ``models`` (with their ``instruments``) in lock-step, one lane each.

    Raises
    ------
    ValueError
        If the models do not share a group (:func:`group_key`).
    """
    if not models or len(models) != len(instruments):
        raise ValueError("solve_group: one Instruments per Model, at least one run")
    key = (group_key(models[0]), group_timing(instruments[0]))
    if any((group_key(m), group_timing(i)) != key for m, i in zip(models[1:], instruments[1:], strict=True)):
        raise ValueError("solve_group: the runs differ in fidelity levels, integrated states, demand tables or their "
                         "analog channels' timing")
    lanes = len(models)
    first = models[0]
    x = np.ascontiguousarray(np.stack([m.initial_state for m in models], axis=1))
    c = np.ascontiguousarray(np.stack([m.constants for m in models], axis=1))
    parameters = np.ascontiguousarray(np.stack([i.parameters for i in instruments], axis=2))
    noise = np.ascontiguousarray(np.stack([i.noise for i in instruments], axis=2))
    states = np.zeros((N_INSTRUMENTS, STATE_ROW, lanes))
    memory = np.zeros((N_MEMORY, lanes))
    rows = n_steps // output_every + 1 if output_every > 0 else 0
    output = np.full((rows, N_SIGNALS, lanes), np.nan)
    workspace = Workspace(N_STATES, lanes)
    status = np.zeros(lanes, dtype=np.int64)
    bound = np.zeros(lanes, dtype=np.int64)
    steps_done = np.zeros(lanes, dtype=np.int64)
    rows_written = np.zeros(lanes, dtype=np.int64)
    run_loop(x, c, first.levels, first.position_table, first.force_table, first.active, first.pairs, n_steps, dt,
             speed_every, position_every, output_every, jacobian_every, method, parameters, states, noise, memory,
             output, tolerance, *workspace.arrays(), status, bound, steps_done, rows_written)
    return Solved(x, memory, output, status, bound, steps_done, rows_written)
