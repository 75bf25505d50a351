"""The lane engine on an NVIDIA GPU: one run per CUDA thread, each thread the CPU's run loop at one lane.

Thread ``i`` calls :func:`twin.engine.loop.run_loop` on the column views ``x[:, i:i+1]``, ``c[:, i:i+1]``, ... of
its run: a group of one lane. numba compiles the loop and every ``@njit`` function it reaches as CUDA device
functions from the same source (:mod:`numerics.cuda_target` sets the target up), so the GPU path holds no physics
of its own. The host builds every array as :func:`twin.engine.group.solve_group` does (the same models,
parameters and pre-drawn noise, hence the same ``SeedSequence`` streams), copies them in, launches, and copies the
state, loop memory (the feature accumulators), output and status out.

What agrees with the CPU (docs/gpu.md): the same operations in the same order, with no FMA contraction, where no
libm call is reached; libdevice's ``sin``/``exp``/``cos``/``expm1`` are not glibc's, so a run through a sine demand
segment (:func:`twin.scenes.profiles.profile_value`) or the IMEX step's held-input propagators
(:func:`twin.engine.plant.held_input_propagators`) agrees within the numerical floor per feature instead.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numba import cuda

from numerics import cuda_target
from twin.engine.group import Solved, loop_arguments, solved
from twin.engine.instrumentation import Instruments
from twin.engine.loop import run_loop
from twin.engine.model import Model

#: Threads per block. Not tuned: the kernel is large (every law inlined), so its registers, not the block size,
#: bound the occupancy; two warps keep a block's scheduling simple (docs/gpu.md: nothing has been timed on a GPU).
THREADS_PER_BLOCK = 64
#: Share of the device's free memory one launch may fill (the rest: the kernel's local memory, other users).
MEMORY_SHARE = 0.5
#: Arguments of ``run_loop`` shared by every lane of a group (the others have one column, or slot, per lane).
SHARED = ("levels", "position_table", "force_table", "active", "pairs", "tolerance")
#: The per-lane arrays whose lane axis comes first (the workspace's slots); every other one has it last.
LANE_FIRST = ("small",)
#: What comes back from the device (:class:`twin.engine.group.Solved`).
RESULTS = ("x", "memory", "output", "status", "bound", "steps_done", "rows_written")


def unavailable() -> str:
    """Why the CUDA engine cannot run here, in one line (``""`` if it can)."""
    if cuda_target.simulator():
        import numba

        return ("" if numba.config.DISABLE_JIT else "the CUDA simulator runs the engine's plain Python functions: "
                "set NUMBA_DISABLE_JIT=1 with NUMBA_ENABLE_CUDASIM=1")
    reason = cuda_target.unavailable()
    return f"no usable NVIDIA GPU: {reason}" if reason else ""


@cuda.jit(cache=True)
def _kernel(x, c, levels, position_table, force_table, active, pairs, n_steps, dt, speed_every, position_every,
            output_every, jacobian_every, method, parameters, states, noise, memory, output, tolerance, vectors, w,
            matrices, cache, small, inputs, alive, guard_memory, initial, status, bound, steps_done, rows_written):
    """``run_loop`` of lane ``i`` on thread ``i``, on its own columns (and its own slot of ``small``)."""
    i = cuda.grid(1)
    if i < x.shape[1]:
        run_loop(x[:, i:i + 1], c[:, i:i + 1], levels, position_table, force_table, active, pairs, n_steps, dt,
                 speed_every, position_every, output_every, jacobian_every, method, parameters[:, :, i:i + 1],
                 states[:, :, i:i + 1], noise[:, :, i:i + 1], memory[:, i:i + 1], output[:, :, i:i + 1], tolerance,
                 vectors[:, :, i:i + 1], w[:, i:i + 1], matrices[:, :, i:i + 1], cache[:, i:i + 1], small[i],
                 inputs[:, i:i + 1], alive[i:i + 1], guard_memory[:, i:i + 1], initial[:, i:i + 1], status[i:i + 1],
                 bound[i:i + 1], steps_done[i:i + 1], rows_written[i:i + 1])


def solve_group_cuda(models: Sequence[Model], instruments: Sequence[Instruments], *, n_steps: int, dt: float,
                     speed_every: int, position_every: int, output_every: int, jacobian_every: int, method: int,
                     tolerance: np.ndarray) -> Solved:
    """:func:`twin.engine.group.solve_group` on the GPU: one thread per run, as many runs per launch as the device's
    free memory holds (:data:`MEMORY_SHARE`).

    Raises
    ------
    ValueError
        If the models do not share a group (:func:`twin.engine.group.group_key`).
    RuntimeError
        If no GPU can run the kernel here (:func:`unavailable`).
    """
    reason = unavailable()
    if reason:
        raise RuntimeError(f"engine 'cuda': {reason}")
    cuda_target.prepare()
    arguments = loop_arguments(models, instruments, n_steps=n_steps, dt=dt, speed_every=speed_every,
                               position_every=position_every, output_every=output_every, jacobian_every=jacobian_every,
                               method=method, tolerance=tolerance, slot_per_lane=True)
    lanes = len(models)
    per_launch = runs_per_launch(arguments, lanes)
    shared = {name: cuda.to_device(arguments[name]) for name in SHARED}
    for first in range(0, lanes, per_launch):
        _launch(arguments, shared, slice(first, min(first + per_launch, lanes)))
    return solved(arguments)


def runs_per_launch(arguments: dict, lanes: int) -> int:
    """Runs one launch takes: :data:`MEMORY_SHARE` of the device's free memory over a run's bytes (at least one)."""
    per_run = sum(a.nbytes for name, a in arguments.items()
                  if isinstance(a, np.ndarray) and name not in SHARED) / lanes
    free, _ = cuda.current_context().get_memory_info()
    if not math.isfinite(free):  # the simulator's
        return lanes
    return max(1, min(lanes, int(MEMORY_SHARE * free / per_run)))


def _launch(arguments: dict, shared: dict, lanes: slice) -> None:
    """Copy the runs ``lanes`` in, run them, copy their results out into ``arguments``."""
    device = {}
    for name, value in arguments.items():
        if name in shared:
            device[name] = shared[name]
        elif isinstance(value, np.ndarray):
            part = value[lanes] if name in LANE_FIRST else value[..., lanes]
            device[name] = cuda.to_device(np.ascontiguousarray(part))
        else:
            device[name] = value
    count = lanes.stop - lanes.start
    _kernel[(count + THREADS_PER_BLOCK - 1) // THREADS_PER_BLOCK, THREADS_PER_BLOCK](*device.values())
    cuda.synchronize()
    for name in RESULTS:
        arguments[name][..., lanes] = device[name].copy_to_host()
