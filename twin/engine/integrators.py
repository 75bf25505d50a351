"""Fixed-step integrators for the compiled loop.

Each advances the plant of :mod:`twin.engine.plant` by one step ``h`` with the
controller outputs held (zero-order hold). Selected by integer code so the
compiled loop can branch without Python objects. Only the states listed in
``active`` are integrated (the model's fidelity removes the others); the rest
of ``x`` holds fixed values the right-hand side reads.
"""

import numba
import numpy as np

from numerics.linalg import inverse
from twin.engine.plant import (
    CURRENT_LOOP_STATES,
    DOF_POSITIONS,
    N_DOFS,
    current_loop_jacobian,
    dof_active,
    held_input_propagators,
    rhs,
    stiff_velocity_system,
)
from twin.layout import PNEUMATICS_FULL, K, S, U

RK4 = 0
SEMI_IMPLICIT_EULER = 1
ROSENBROCK_W2 = 2
IMEX_EULER = 3
INTEGRATORS = {"rk4": RK4, "semi_implicit_euler": SEMI_IMPLICIT_EULER, "rosenbrock_w2": ROSENBROCK_W2,
               "imex_euler": IMEX_EULER}
ORDER = {"rk4": 4, "semi_implicit_euler": 1, "rosenbrock_w2": 2, "imex_euler": 1}
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
    matrix[:, :] = inverse(matrix)  # fixed operation order: not LAPACK, whose bits depend on the BLAS kernel


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
def solve_in_place(matrix, b, n):
    """Solve ``matrix[:n, :n] y = b[:n]`` by Gaussian elimination without pivoting; ``y`` replaces ``b``
    and ``matrix`` is overwritten. For the small systems of :func:`imex_euler_step`: symmetric positive
    definite (mechanics) or ``I - h J`` of the current loop, both safe without pivoting (Golub & Van Loan,
    *Matrix Computations*, 4th ed., Sec. 4.2), and no allocation inside the compiled loop."""
    for k in range(n):
        pivot = matrix[k, k]
        for i in range(k + 1, n):
            factor = matrix[i, k] / pivot
            if factor != 0.0:
                for j in range(k + 1, n):
                    matrix[i, j] -= factor * matrix[k, j]
                b[i] -= factor * b[k]
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, n):
            acc -= matrix[i, j] * b[j]
        b[i] = acc / matrix[i, i]


@numba.njit(cache=True)
def imex_euler_step(t, x, h, c, u, force_table, stiffness_poly, work, active):
    """Linearly implicit (IMEX) symplectic Euler: one right-hand side per step, the stiff springs implicit.

    With ``F`` the mechanical generalised forces at the current state and ``K``, ``D`` the analytic
    tangent stiffness and damping of the stiff elements only (:func:`twin.engine.plant.stiff_velocity_system`:
    ball-groove contacts, springs, friction slopes), the velocities of the mechanical DOFs take

        (M + h D + h^2 K) dv = h (F - h K v),   v+ = v + dv,   q+ = q + h v+,

    i.e. implicit Euler on the linearised stiff forces at the new positions ``q + h v+`` and velocities
    ``v+``, and the symplectic Euler of :func:`semi_implicit_euler_step` on everything else. The other
    blocks:

    * the full current loop (winding, Hall filter, analog PI: linear, with a -2.3e4 1/s mode) takes one
      linearly implicit Euler step ``(I - h J) dy = h f`` with its exact Jacobian
      (:func:`twin.engine.plant.current_loop_jacobian`);
    * the ideal current loop's lag and the valve spool are linear with a held input: exact propagators
      (:func:`twin.engine.plant.held_input_propagators`);
    * the chamber pressures and the winding temperature: explicit Euler.

    The whole is a W-method: first order for any ``K``, ``D``, ``J`` (Hairer & Wanner, *Solving ODEs II*,
    Sec. IV.7: the linearly implicit Euler with an approximate Jacobian; Sec. IV.9 for mechanical
    systems); the matrices decide only stability. On a linear spring-mass-damper it is implicit Euler on
    the velocity with the symplectic position update: stable for any ``h``, never adding energy
    (tests/engine/test_imex_euler.py). The price is numerical damping, about ``h w^2 / 2`` [1/s] on a
    mode ``w``: on the contact mode at 125 us it suppresses a self-excited 255 Hz oscillation that the
    model has on some data sets (docs/accuracy.md).

    ``work``: rows 0-3 scratch vectors, row 5 the propagators' cache, the 8 x 8 and 3 x 3 matrices from
    row ``WORK_VECTORS`` on (:func:`work_array`).
    """
    f, b, velocity, cache = work[0], work[1], work[2], work[5]
    held_input_propagators(c, h, cache)
    matrix = work[WORK_VECTORS:WORK_VECTORS + N_DOFS, :N_DOFS]
    rhs(t, x, c, u, force_table, stiffness_poly, f)
    stiff_velocity_system(x, c, stiffness_poly, f, h, matrix, b, velocity)
    solve_in_place(matrix, b, N_DOFS)
    loop = work[WORK_VECTORS + N_DOFS:WORK_VECTORS + N_DOFS + 3, :3]
    current = work[3]
    full_loop = c[K.CURRENT_LOOP_FULL] > 0.5
    if full_loop:
        current_loop_jacobian(x, c, u[U.CURRENT_DEMAND], loop)
        for i in range(3):
            for j in range(3):
                loop[i, j] = (1.0 if i == j else 0.0) - h * loop[i, j]
            current[i] = h * f[CURRENT_LOOP_STATES[i]]
        solve_in_place(loop, current, 3)
    for j in active:
        x[j] += h * f[j]
    # replace the explicit update of the implicit states; f still holds the old velocities for the positions
    for i in range(N_DOFS):
        if dof_active(c, i):
            p = DOF_POSITIONS[i]
            x[p + 1] += b[i] - h * f[p + 1]
            x[p] += h * (x[p + 1] - f[p])
    if full_loop:
        for i in range(3):
            x[CURRENT_LOOP_STATES[i]] += current[i] - h * f[CURRENT_LOOP_STATES[i]]
    else:
        # dx/dt = (demand - x) / tau: the exact step moves the fraction cache[8] of the way to the demand
        x[S.CURRENT] += f[S.CURRENT] * c[K.CURRENT_LOOP_TAU] * cache[8] - h * f[S.CURRENT]
    if int(c[K.PNEUMATICS]) == PNEUMATICS_FULL:
        # spool: y = (x - s, v) with the held target s = x + (a + 2 zeta w v) / w^2 follows y+ = Phi y
        omega, zeta = cache[1], cache[2]
        position, speed = x[S.SPOOL_POSITION] - h * f[S.SPOOL_POSITION], x[S.SPOOL_SPEED] - h * f[S.SPOOL_SPEED]
        offset = -(f[S.SPOOL_SPEED] + 2.0 * zeta * omega * speed) / (omega * omega)
        x[S.SPOOL_POSITION] = position + (cache[4] - 1.0) * offset + cache[5] * speed
        x[S.SPOOL_SPEED] = cache[6] * offset + cache[7] * speed


@numba.njit(cache=True)
def step(method, t, x, h, c, u, force_table, stiffness_poly, work, refresh, active, pairs):
    """Advance the ``active`` states of ``x`` by one step ``h``; ``refresh`` asks the W-method to
    rebuild its matrix; ``pairs`` are the (position, velocity) pairs of the semi-implicit Euler step."""
    if method == RK4:
        rk4_step(t, x, h, c, u, force_table, stiffness_poly, work, active)
    elif method == SEMI_IMPLICIT_EULER:
        semi_implicit_euler_step(t, x, h, c, u, force_table, stiffness_poly, work, active, pairs)
    elif method == IMEX_EULER:
        imex_euler_step(t, x, h, c, u, force_table, stiffness_poly, work, active)
    else:
        if refresh:
            w_matrix(t, x, h, c, u, force_table, stiffness_poly, work, active)
        rosenbrock_w2_step(t, x, h, c, u, force_table, stiffness_poly, work, active)
