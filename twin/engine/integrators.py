"""Fixed-step integrators for the compiled loop.

Each advances the plant of :mod:`twin.engine.plant` by one step ``h`` with the
controller outputs held (zero-order hold). Selected by integer code so the
compiled loop can branch without Python objects. Only the states listed in
``active`` are integrated (the model's fidelity removes the others); the rest
of ``x`` holds fixed values the right-hand side reads.
"""

import numba
import numpy as np

from twin.engine.plant import rhs

RK4 = 0
SEMI_IMPLICIT_EULER = 1
ROSENBROCK_W2 = 2
INTEGRATORS = {"rk4": RK4, "semi_implicit_euler": SEMI_IMPLICIT_EULER, "rosenbrock_w2": ROSENBROCK_W2}
ORDER = {"rk4": 4, "semi_implicit_euler": 1, "rosenbrock_w2": 2}
EXPLICIT = ("rk4", "semi_implicit_euler")
ROS2_GAMMA = 1.0 + 1.0 / np.sqrt(2.0)
WORK_VECTORS = 6  # scratch vectors in front of the W-method's matrix in the work array


def work_array(n_states: int) -> np.ndarray:
    """Scratch space of :func:`step`: ``WORK_VECTORS`` vectors, then the W-method's ``n x n`` matrix."""
    return np.zeros((WORK_VECTORS + n_states, n_states))


@numba.njit(cache=True)
def rk4_step(t, x, h, c, u, force_table, stiffness_poly, work, active):
    """Classical 4th-order Runge-Kutta (Hairer, Norsett & Wanner, *Solving ODEs I*, Table 1.2).

    ``work`` is the scratch array of :func:`work_array`: k1..k4 and the stage state.
    """
    k1, k2, k3, k4, xs = work[0], work[1], work[2], work[3], work[4]
    xs[:] = x
    rhs(t, x, c, u, force_table, stiffness_poly, k1)
    for j in active:
        xs[j] = x[j] + 0.5 * h * k1[j]
    rhs(t + 0.5 * h, xs, c, u, force_table, stiffness_poly, k2)
    for j in active:
        xs[j] = x[j] + 0.5 * h * k2[j]
    rhs(t + 0.5 * h, xs, c, u, force_table, stiffness_poly, k3)
    for j in active:
        xs[j] = x[j] + h * k3[j]
    rhs(t + h, xs, c, u, force_table, stiffness_poly, k4)
    for j in active:
        x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])


@numba.njit(cache=True)
def semi_implicit_euler_step(t, x, h, c, u, force_table, stiffness_poly, work, active, pairs):
    """Symplectic (semi-implicit) Euler: velocities and first-order states explicit,
    then positions with the *new* velocities (Hairer, Lubich & Wanner, *Geometric
    Numerical Integration*, Thm. VI.3.3). First order; for undamped mechanics it
    conserves a modified energy, so oscillations neither grow nor decay spuriously.
    """
    k1 = work[0]
    rhs(t, x, c, u, force_table, stiffness_poly, k1)
    for j in active:
        x[j] += h * k1[j]
    for m in range(pairs.shape[0]):
        # undo the explicit position update and redo it with the updated velocity
        p, v = pairs[m, 0], pairs[m, 1]
        x[p] += h * (x[v] - k1[p])


@numba.njit(cache=True)
def w_matrix(t, x, h, c, u, force_table, stiffness_poly, work, active):
    """``(I - gamma h J)^-1`` with ``J`` by forward differences of the right-hand side,
    over the integrated states ``active`` (matrix index ``i`` is state ``active[i]``).

    Each perturbation is ``sqrt(eps)`` relative to the state's magnitude, with a
    floor of 1e-12 absolute: the ball-groove deflections are micrometres, so the
    floor must sit far below them.
    """
    n = active.shape[0]
    f0 = work[5]
    matrix = work[WORK_VECTORS:WORK_VECTORS + n, :n]
    rhs(t, x, c, u, force_table, stiffness_poly, f0)
    column = work[4]
    for j in range(n):
        state = active[j]
        saved = x[state]
        delta = 1.5e-8 * max(abs(saved), 1e-4)
        x[state] = saved + delta
        rhs(t, x, c, u, force_table, stiffness_poly, column)
        x[state] = saved
        for i in range(n):
            matrix[i, j] = -ROS2_GAMMA * h * (column[active[i]] - f0[active[i]]) / delta
        matrix[j, j] += 1.0
    matrix[:, :] = np.linalg.inv(matrix)


@numba.njit(cache=True)
def _matvec(matrix, vector, out, active):
    """``out[active] = matrix @ vector[active]`` without allocating (the W-method's stages)."""
    n = active.shape[0]
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += matrix[i, j] * vector[active[j]]
        out[active[i]] = acc


@numba.njit(cache=True)
def rosenbrock_w2_step(t, x, h, c, u, force_table, stiffness_poly, work, active):
    """Two-stage Rosenbrock W-method ROS2 (Verwer, Spee, Blom & Hundsdorfer, SIAM J. Sci. Comput. 20, 1999):

        (I - gamma h J) k1 = f(x),   (I - gamma h J) k2 = f(x + h k1) - 2 k1,
        x+ = x + h (3/2 k1 + 1/2 k2),   gamma = 1 + 1/sqrt(2).

    Second order for *any* matrix ``J`` (a W-method), L-stable with the exact
    Jacobian: the stiff contact, load-cell, Hall-filter and friction-regularisation
    modes are damped instead of limiting the step. The matrix
    ``(I - gamma h J)^-1`` is refreshed by :func:`w_matrix` when the loop asks.
    """
    n = active.shape[0]
    k1, k2, xs, f = work[0], work[1], work[2], work[3]
    matrix = work[WORK_VECTORS:WORK_VECTORS + n, :n]
    rhs(t, x, c, u, force_table, stiffness_poly, f)
    _matvec(matrix, f, k1, active)
    xs[:] = x
    for i in active:
        xs[i] = x[i] + h * k1[i]
    rhs(t + h, xs, c, u, force_table, stiffness_poly, f)
    for i in active:
        f[i] -= 2.0 * k1[i]
    _matvec(matrix, f, k2, active)
    for i in active:
        x[i] += h * (1.5 * k1[i] + 0.5 * k2[i])


@numba.njit(cache=True)
def step(method, t, x, h, c, u, force_table, stiffness_poly, work, refresh, active, pairs):
    """Advance the ``active`` states of ``x`` by one step ``h``; ``refresh`` asks the W-method to
    rebuild its matrix; ``pairs`` are the (position, velocity) pairs of the semi-implicit Euler step."""
    if method == RK4:
        rk4_step(t, x, h, c, u, force_table, stiffness_poly, work, active)
    elif method == SEMI_IMPLICIT_EULER:
        semi_implicit_euler_step(t, x, h, c, u, force_table, stiffness_poly, work, active, pairs)
    else:
        if refresh:
            w_matrix(t, x, h, c, u, force_table, stiffness_poly, work, active)
        rosenbrock_w2_step(t, x, h, c, u, force_table, stiffness_poly, work, active)
