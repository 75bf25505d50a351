"""Jacobian of the bench's right-hand side, its highest natural frequency and the step limits they set."""

from __future__ import annotations

import numpy as np

from twin.engine.plant import rhs, work_rows
from twin.layout import N_INPUTS


def jacobian(model, y: np.ndarray, t: float = 0.0, u: np.ndarray | None = None) -> np.ndarray:
    """Central-difference Jacobian ``df/dy`` of the integrated states ``y`` (``model.active``) at ``t``
    with held inputs ``u`` (default zero), one run as a one-lane group."""
    u = np.zeros((N_INPUTS, 1)) if u is None else np.asarray(u, dtype=float).reshape(N_INPUTS, 1)
    active = model.active
    c = model.constants.reshape(-1, 1)
    probe = model.full_state(y).reshape(-1, 1)
    plus, minus = np.zeros_like(probe), np.zeros_like(probe)
    w = work_rows(1)
    matrix = np.zeros((active.size, active.size))
    for j, state in enumerate(active):
        delta = 1e-7 * max(abs(y[j]), 1e-5)
        probe[state, 0] = y[j] + delta
        rhs(t, probe, c, u, model.levels, model.force_table, plus, w)
        probe[state, 0] = y[j] - delta
        rhs(t, probe, c, u, model.levels, model.force_table, minus, w)
        probe[state, 0] = y[j]
        matrix[:, j] = (plus[active, 0] - minus[active, 0]) / (2 * delta)
    return matrix


def highest_frequency(matrix: np.ndarray) -> float:
    """Largest eigenvalue modulus ``|lambda|max`` [rad/s]: what limits an explicit step."""
    return float(np.max(np.abs(np.linalg.eigvals(matrix))))


#: Stability function of the classical RK4 step, ``R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24`` (Hairer & Wanner,
#: *Solving ODEs II*, Sec. IV.2): one step maps ``y' = lambda y`` to ``R(lambda h) y``.
RK4_STABILITY = np.polynomial.Polynomial([1.0, 1.0, 1.0 / 2.0, 1.0 / 6.0, 1.0 / 24.0])


def largest_stable_step(eigenvalues, stability=RK4_STABILITY, rtol: float = 1e-12) -> float:
    """Largest step ``h`` [s] with ``|R(lambda h')| <= 1`` for every ``h' <= h`` and every eigenvalue.

    Zero eigenvalues (rigid-body modes) and modes the physics itself lets grow (real part above ``1e-6 |lambda|``)
    set no step limit and are skipped; ``inf`` if none is left. An oscillation whose finite-difference real part
    is positive but below that is judged on the imaginary axis. Bisection along each ray ``lambda h`` (all rays at
    once) to ``rtol``: e.g. ``2 sqrt(2) / |lambda|`` on the imaginary axis and ``2.7853 / |lambda|`` on the
    negative real axis for RK4.
    """
    lam = np.asarray(eigenvalues, dtype=complex).ravel()
    lam = lam[(lam != 0.0) & (lam.real <= 1e-6 * np.abs(lam))]
    if lam.size == 0:
        return float(np.inf)
    lam = np.minimum(lam.real, 0.0) + 1j * lam.imag
    unstable = 1.0 / np.abs(lam)
    while np.any(grow := _stable_up_to(stability, lam, unstable)):
        unstable = np.where(grow, 2.0 * unstable, unstable)  # every polynomial leaves its region far enough out
    stable = np.zeros_like(unstable)
    while np.any(unstable - stable > rtol * unstable):
        middle = 0.5 * (stable + unstable)
        kept = _stable_up_to(stability, lam, middle)
        stable, unstable = np.where(kept, middle, stable), np.where(kept, unstable, middle)
    return float(stable.min())


def _stable_up_to(stability, lam: np.ndarray, h: np.ndarray, samples: int = 64) -> np.ndarray:
    """Per ray, whether ``|R(lambda h')| <= 1`` (to rounding) on ``0 < h' <= h``, checked at ``samples`` points: the
    region may be left and re-entered along a ray, and the first exit is the limit."""
    z = lam[:, None] * h[:, None] * np.linspace(1.0 / samples, 1.0, samples)[None, :]
    return np.all(np.abs(stability(z)) <= 1.0 + 1e-12, axis=1)
