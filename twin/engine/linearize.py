"""Jacobian of the bench's right-hand side and its highest natural frequency (stability limits)."""

from __future__ import annotations

import numpy as np

from twin.engine.layout import N_INPUTS
from twin.engine.plant import rhs


def jacobian(model, x: np.ndarray, t: float = 0.0, u: np.ndarray | None = None) -> np.ndarray:
    """Central-difference Jacobian ``df/dx`` at ``(t, x)`` with held inputs ``u`` (default zero)."""
    u = np.zeros(N_INPUTS) if u is None else u
    n = x.size
    plus, minus = np.zeros(n), np.zeros(n)
    matrix = np.zeros((n, n))
    probe = x.copy()
    for j in range(n):
        delta = 1e-7 * max(abs(x[j]), 1e-5)
        probe[j] = x[j] + delta
        rhs(t, probe, model.constants, u, model.force_table, model.stiffness_poly, plus)
        probe[j] = x[j] - delta
        rhs(t, probe, model.constants, u, model.force_table, model.stiffness_poly, minus)
        probe[j] = x[j]
        matrix[:, j] = (plus - minus) / (2 * delta)
    return matrix


def highest_frequency(matrix: np.ndarray) -> float:
    """Largest eigenvalue modulus ``|lambda|max`` [rad/s]: what limits an explicit step."""
    return float(np.max(np.abs(np.linalg.eigvals(matrix))))
