"""Lane kernels over :mod:`numerics.elementary` for the tests: one small ``KERNEL`` per function.

Each kernel evaluates its function over a group-by-lane array ``x[group, lane]`` with the lane loop innermost, as
the engine's lane kernels do: LLVM vectorises that loop (4 doubles per ymm register on AVX2, 2 per xmm register on
the SSE2 ``generic`` target) and runs a scalar remainder for ``lanes % VF`` lanes, so a lane count of 1 or 3 runs
the scalar code and 4, 8, 16, 17 the vector code (17: vector loop and remainder).

Run as a script, it is the child process of ``test_elementary.py``'s other-target test: it reads the arguments
from an ``.npz`` file, evaluates every function at the lane counts given, and writes the results to another.
"""

from __future__ import annotations

import sys

import numba
import numpy as np

from numerics import elementary
from numerics.jit import KERNEL


@numba.njit(**KERNEL)
def exp_lanes(x, y):
    for group in range(x.shape[0]):
        for lane in range(x.shape[1]):
            y[group, lane] = elementary.exp(x[group, lane])


@numba.njit(**KERNEL)
def expm1_lanes(x, y):
    for group in range(x.shape[0]):
        for lane in range(x.shape[1]):
            y[group, lane] = elementary.expm1(x[group, lane])


@numba.njit(**KERNEL)
def log_lanes(x, y):
    for group in range(x.shape[0]):
        for lane in range(x.shape[1]):
            y[group, lane] = elementary.log(x[group, lane])


@numba.njit(**KERNEL)
def tanh_lanes(x, y):
    for group in range(x.shape[0]):
        for lane in range(x.shape[1]):
            y[group, lane] = elementary.tanh(x[group, lane])


@numba.njit(**KERNEL)
def sin_lanes(x, y):
    for group in range(x.shape[0]):
        for lane in range(x.shape[1]):
            y[group, lane] = elementary.sin(x[group, lane])


@numba.njit(**KERNEL)
def cos_lanes(x, y):
    for group in range(x.shape[0]):
        for lane in range(x.shape[1]):
            y[group, lane] = elementary.cos(x[group, lane])


@numba.njit(**KERNEL)
def pow026_lanes(x, y):
    for group in range(x.shape[0]):
        for lane in range(x.shape[1]):
            y[group, lane] = elementary.pow026(x[group, lane])


#: name -> (scalar function, its lane kernel)
FUNCTIONS = {
    "exp": (elementary.exp, exp_lanes),
    "expm1": (elementary.expm1, expm1_lanes),
    "log": (elementary.log, log_lanes),
    "tanh": (elementary.tanh, tanh_lanes),
    "sin": (elementary.sin, sin_lanes),
    "cos": (elementary.cos, cos_lanes),
    "pow026": (elementary.pow026, pow026_lanes),
}


def in_lanes(name: str, x: np.ndarray, lanes: int, permutation: np.ndarray | None = None) -> np.ndarray:
    """``name`` at every ``x`` evaluated by its lane kernel, ``lanes`` samples per group.

    ``permutation`` (of ``range(len(x))``) chooses which samples share a group: sample ``permutation[j]`` goes
    to group ``j // lanes``, lane ``j % lanes``. The last group is padded with copies of the first samples
    (computed and dropped). Returns the results in the order of ``x``.
    """
    x = np.asarray(x, dtype=np.float64)
    order = np.arange(x.size) if permutation is None else np.asarray(permutation)
    padded = np.concatenate([x[order], x[: (-x.size) % lanes]])
    grid = np.ascontiguousarray(padded.reshape(-1, lanes))
    out = np.empty_like(grid)
    FUNCTIONS[name][1](grid, out)
    result = np.empty_like(x)
    result[order] = out.ravel()[: x.size]
    return result


def child(arguments_path: str, results_path: str, lanes: list[int]) -> None:
    """Every function at every lane count in ``lanes`` (a fixed permutation each); results to ``results_path``."""
    arguments = np.load(arguments_path)
    results = {}
    for name in FUNCTIONS:
        x = arguments[name]
        for count in lanes:
            permutation = np.random.default_rng(count).permutation(x.size)
            results[f"{name}|{count}"] = in_lanes(name, x, count, permutation)
    np.savez(results_path, **results)


if __name__ == "__main__":
    child(sys.argv[1], sys.argv[2], [int(v) for v in sys.argv[3].split(",")])
