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
    arguments = loop_arguments(models, instruments, n_steps=n_steps, dt=dt, speed_every=speed_every,
                               position_every=position_every, output_every=output_every,
                               jacobian_every=jacobian_every, method=method, tolerance=tolerance)
    run_loop(*arguments.values())
    return solved(arguments)


def loop_arguments(models: Sequence[Model], instruments: Sequence[Instruments], *, n_steps: int, dt: float,
                   speed_every: int, position_every: int, output_every: int, jacobian_every: int, method: int,
                   tolerance: np.ndarray, slot_per_lane: bool = False) -> dict:
    """:func:`twin.engine.loop.run_loop`'s arguments for the runs ``models`` (with their ``instruments``), by name
    in its order: the runs' arrays stacked as lanes, the workspace and the output arrays. ``small`` is the
    workspace's one slot (the CPU's), or with ``slot_per_lane`` all its slots, lane first (:class:`Workspace`: the
    CUDA kernel hands thread ``i`` slot ``i``).

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
    rows = n_steps // output_every + 1 if output_every > 0 else 0
    workspace = Workspace(N_STATES, lanes, lanes if slot_per_lane else 1)
    vectors, work, matrices, cache, small = workspace.arrays()
    inputs, alive, guard_memory, initial = workspace.loop_arrays()
    return dict(
        x=np.ascontiguousarray(np.stack([m.initial_state for m in models], axis=1)),
        c=np.ascontiguousarray(np.stack([m.constants for m in models], axis=1)),
        levels=first.levels, position_table=first.position_table, force_table=first.force_table,
        active=first.active, pairs=first.pairs, n_steps=n_steps, dt=dt, speed_every=speed_every,
        position_every=position_every, output_every=output_every, jacobian_every=jacobian_every, method=method,
        parameters=np.ascontiguousarray(np.stack([i.parameters for i in instruments], axis=2)),
        states=np.zeros((N_INSTRUMENTS, STATE_ROW, lanes)),
        noise=np.ascontiguousarray(np.stack([i.noise for i in instruments], axis=2)),
        memory=np.zeros((N_MEMORY, lanes)), output=np.full((rows, N_SIGNALS, lanes), np.nan), tolerance=tolerance,
        vectors=vectors, w=work, matrices=matrices, cache=cache, small=workspace.slots if slot_per_lane else small,
        inputs=inputs, alive=alive, guard_memory=guard_memory, initial=initial,
        status=np.zeros(lanes, dtype=np.int64), bound=np.zeros(lanes, dtype=np.int64),
        steps_done=np.zeros(lanes, dtype=np.int64), rows_written=np.zeros(lanes, dtype=np.int64))


def solved(arguments: dict) -> Solved:
    """The results :func:`twin.engine.loop.run_loop` left in its ``arguments`` (:func:`loop_arguments`)."""
    return Solved(arguments["x"], arguments["memory"], arguments["output"], arguments["status"], arguments["bound"],
                  arguments["steps_done"], arguments["rows_written"])
