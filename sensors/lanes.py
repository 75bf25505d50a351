"""The lane layout of the instruments: parameters and state as ``[row, lane]`` arrays.

A lane is one Monte Carlo sample; a group of ``L`` lanes advances in lock-step (issue 32). Each instrument's
parameters and state are 2-D C-contiguous float64 arrays, one row per quantity of its layout (``ENC_*``,
``AN_*``, ``AS_*``, ``RES_*``) and one column per lane, so that a loop over the lanes reads consecutive memory
and can be vectorised. The compiled step and read functions take ``(state, params, lane, ...)`` and act on
column ``lane`` only: a lane's numbers never depend on its lane mates or on ``L``.

The builders (``linear_encoder_parameters``, ``torque_meter_parameters``, ...) return one lane's parameter
vector; :func:`lane_group` stacks such vectors into a group, :func:`one_lane` views a single vector (or a
single state row of the scalar engine) as a one-lane column.
"""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np

from numerics.jit import SCALAR


def lane_group(columns: Sequence[np.ndarray]) -> np.ndarray:
    """Stack per-lane vectors (each of the same layout, e.g. from a parameter builder) into a C-contiguous
    ``[row, lane]`` array whose column ``i`` is ``columns[i]``."""
    if len(columns) == 0:
        raise ValueError("columns: a lane group needs at least one lane")
    return np.ascontiguousarray(np.stack([np.asarray(c, dtype=np.float64) for c in columns], axis=1))


@numba.njit(**SCALAR)
def one_lane(vector):
    """A 1-D C-contiguous vector as a ``[row, 1]`` view (the same memory): lane 0 of a one-lane group."""
    return vector.reshape((vector.shape[0], 1))
