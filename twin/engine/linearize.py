"""Jacobian of the bench's right-hand side and its highest natural frequency (stability limits)."""

from __future__ import annotations

import numpy as np

from twin.engine.plant import rhs
from twin.layout import N_INPUTS


def jacobian(model, y: np.ndarray, t: float = 0.0, u: np.ndarray | None = None) -> np.ndarray:
    """Central-difference Jacobian ``df/dy`` of the integrated states ``y`` (``model.active``) at ``t``
    with held inputs ``u`` (default zero)."""
    u = np.zeros(N_INPUTS) if u is None else u
    active = model.active
    probe = model.full_state(y)
    plus, minus = np.zeros(probe.size), np.zeros(probe.size)
    matrix = np.zeros((active.size, active.size))
    for j, state in enumerate(active):
        delta = 1e-7 * max(abs(y[j]), 1e-5)
        probe[state] = y[j] + delta
        rhs(t, probe, model.constants, u, model.force_table, model.stiffness_poly, plus)
        probe[state] = y[j] - delta
        rhs(t, probe, model.constants, u, model.force_table, model.stiffness_poly, minus)
        probe[state] = y[j]
        matrix[:, j] = (plus[active] - minus[active]) / (2 * delta)
    return matrix


def highest_frequency(matrix: np.ndarray) -> float:
    """Largest eigenvalue modulus ``|lambda|max`` [rad/s]: what limits an explicit step."""
    return float(np.max(np.abs(np.linalg.eigvals(matrix))))
