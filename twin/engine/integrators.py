"""Fixed-step integrators of the compiled loop, over a group of lanes.

Each advances the plant of :mod:`twin.engine.plant` by one step ``h`` with the controller outputs held
(zero-order hold). Selected by integer code so the compiled loop can branch without Python objects. Only the
states listed in ``active`` are integrated (the model's fidelity removes the others); the rest of ``x`` holds
values the right-hand side reads (or, at the quasi-static screw-axial level, writes).

Every array is ``[row, lane]`` (:mod:`twin.engine.plant`). RK4 and the semi-implicit Euler step update each lane
with loops over the lanes (vectorised); the W-method and the linearly implicit step solve a small linear system
per lane, lane after lane. Either way a lane's numbers depend only on its own rows.
"""

import numba
import numpy as np

from numerics.jit import KERNEL, SCALAR
from numerics.linalg import inverse_into
from twin.engine.codes import CURRENT_LOOP, CURRENT_LOOP_FULL, PNEUMATICS, PNEUMATICS_FULL
from twin.engine.implicit import (
    CURRENT_LOOP_STATES,
    DOF_POSITIONS,
    N_DOFS,
    current_loop_jacobian,
    dof_active,
    stiff_velocity_system,
)
from twin.engine.plant import FUSED_LANES, N_WORK, has_lead_error, held_input_propagators, rhs, rhs_at
from twin.layout import N_INPUTS, K, S

RK4 = 0
SEMI_IMPLICIT_EULER = 1
ROSENBROCK_W2 = 2
IMEX_EULER = 3
INTEGRATORS = {"rk4": RK4, "semi_implicit_euler": SEMI_IMPLICIT_EULER, "rosenbrock_w2": ROSENBROCK_W2,
               "imex_euler": IMEX_EULER}
ORDER = {"rk4": 4, "semi_implicit_euler": 1, "rosenbrock_w2": 2, "imex_euler": 1}
EXPLICIT = ("rk4", "semi_implicit_euler")
ROS2_GAMMA = 1.0 + 1.0 / np.sqrt(2.0)
#: Scratch state vectors of a step (RK4's four slopes and stage state, the W-method's, the step-doubling check's).
WORK_VECTORS = 8
#: Rows of the per-lane cache of the held-input propagators (:func:`twin.engine.plant.held_input_propagators`).
CACHE_ROWS = 9
#: Rows under the W-method's matrices: the state :func:`w_matrix` perturbs and its perturbation, per lane.
PERTURBATION_ROWS = 2


class Workspace:
    """The scratch arrays of a group of ``lanes`` lanes of ``n_states`` states, allocated once per run: the compiled
    loop allocates nothing (it also runs as a CUDA kernel, :mod:`twin.engine.cuda`, where it cannot).

    ``slots`` holds one lane's small systems at a time (the implicit step's, the W-matrix's copy and inverse): one
    slot on the CPU, which solves them lane after lane (``small`` is that slot), one per lane where every lane runs
    on its own thread.
    """

    def __init__(self, n_states: int, lanes: int, slots: int = 1):
        self.vectors = np.zeros((WORK_VECTORS, n_states, lanes))
        self.work = np.zeros((N_WORK, lanes))
        # the W-method's (I - gamma h J)^-1 per lane, and under it the perturbed state and its perturbation
        self.matrices = np.zeros((n_states + PERTURBATION_ROWS, n_states, lanes))
        self.cache = np.zeros((CACHE_ROWS, lanes))
        self.slots = np.zeros((slots, max(N_DOFS + 5, 2 * n_states), max(N_DOFS, n_states)))
        self.small = self.slots[0]
        # the run loop's held inputs, live lanes, local-error streak and estimate, initial states
        self.inputs = np.zeros((N_INPUTS, lanes))
        self.alive = np.ones(lanes, dtype=np.bool_)
        self.guard = np.zeros((2, lanes))
        self.initial = np.zeros((n_states, lanes))

    def arrays(self) -> tuple:
        """What a step takes: ``vectors, work, matrices, cache, small``."""
        return self.vectors, self.work, self.matrices, self.cache, self.small

    def loop_arrays(self) -> tuple:
        """What the run loop adds: ``inputs, alive, guard, initial``."""
        return self.inputs, self.alive, self.guard, self.initial


@numba.njit(**SCALAR)
def _stage_at(x, k, h, out, j, lane):
    """``out = x + h k`` of state ``j`` in lane ``lane`` (a Runge-Kutta stage state)."""
    out[j, lane] = x[j, lane] + h * k[j, lane]


@numba.njit(**SCALAR)
def _rk4_update_at(x, k1, k2, k3, k4, h, j, lane):
    """RK4's update of state ``j`` in lane ``lane`` from its four slopes."""
    x[j, lane] += h / 6.0 * (k1[j, lane] + 2.0 * k2[j, lane] + 2.0 * k3[j, lane] + k4[j, lane])


@numba.njit(**KERNEL)
def _stage(x, k, h, out, active):
    """``out[active] = x[active] + h k[active]`` in every lane (the other rows of ``out`` are left as they are)."""
    lanes = x.shape[1]
    for j in active:
        for lane in range(lanes):
            _stage_at(x, k, h, out, j, lane)


@numba.njit(**KERNEL)
def _rk4_update(x, k1, k2, k3, k4, h, active):
    lanes = x.shape[1]
    for j in active:
        for lane in range(lanes):
            _rk4_update_at(x, k1, k2, k3, k4, h, j, lane)


@numba.njit(**KERNEL)
def _copy(source, target):
    for j in range(source.shape[0]):
        for lane in range(source.shape[1]):
            target[j, lane] = source[j, lane]


@numba.njit(**SCALAR)
def _rk4_at(t, x, h, c, u, levels, force_table, k1, k2, k3, k4, xs, w, active, lane, errors):
    """:func:`rk4_step` of lane ``lane`` alone, fused: its four right-hand sides (:func:`twin.engine.plant.rhs_at`)
    and stage states one after the other (``errors``: :func:`twin.engine.plant.has_lead_error` of its group)."""
    for j in range(x.shape[0]):
        xs[j, lane] = x[j, lane]
    rhs_at(t, x, c, u, levels, force_table, k1, w, lane, errors)
    for j in active:
        _stage_at(x, k1, 0.5 * h, xs, j, lane)
    rhs_at(t + 0.5 * h, xs, c, u, levels, force_table, k2, w, lane, errors)
    for j in active:
        _stage_at(x, k2, 0.5 * h, xs, j, lane)
    rhs_at(t + 0.5 * h, xs, c, u, levels, force_table, k3, w, lane, errors)
    for j in active:
        _stage_at(x, k3, h, xs, j, lane)
    rhs_at(t + h, xs, c, u, levels, force_table, k4, w, lane, errors)
    for j in active:
        _rk4_update_at(x, k1, k2, k3, k4, h, j, lane)


@numba.njit(**KERNEL)
def rk4_step(t, x, h, c, u, levels, force_table, vectors, w, active):
    """Classical 4th-order Runge-Kutta (Hairer, Norsett & Wanner, *Solving ODEs I*, Table 1.2).

    ``vectors[0:4]`` receive k1..k4, ``vectors[4]`` the stage state. The stage state starts as a copy of ``x``
    (the rows the fidelity holds, and at the quasi-static screw-axial level the balance's warm start, carried from
    stage to stage). A group of at most :data:`twin.engine.plant.FUSED_LANES` lanes takes the fused form
    (:func:`_rk4_at` lane by lane), a larger one the split form, stage by stage over the lanes: the same operations
    of each lane in the same order, so the same bits.
    """
    k1, k2, k3, k4, xs = vectors[0], vectors[1], vectors[2], vectors[3], vectors[4]
    lanes = x.shape[1]
    if lanes <= FUSED_LANES:
        errors = has_lead_error(c, lanes)
        for lane in range(lanes):
            _rk4_at(t, x, h, c, u, levels, force_table, k1, k2, k3, k4, xs, w, active, lane, errors)
        return
    _copy(x, xs)
    rhs(t, x, c, u, levels, force_table, k1, w)
    _stage(x, k1, 0.5 * h, xs, active)
    rhs(t + 0.5 * h, xs, c, u, levels, force_table, k2, w)
    _stage(x, k2, 0.5 * h, xs, active)
    rhs(t + 0.5 * h, xs, c, u, levels, force_table, k3, w)
    _stage(x, k3, h, xs, active)
    rhs(t + h, xs, c, u, levels, force_table, k4, w)
    _rk4_update(x, k1, k2, k3, k4, h, active)


@numba.njit(**KERNEL)
def semi_implicit_euler_step(t, x, h, c, u, levels, force_table, vectors, w, active, pairs):
    """Symplectic (semi-implicit) Euler: velocities and first-order states explicit,
    then positions with the *new* velocities (Hairer, Lubich & Wanner, *Geometric
    Numerical Integration*, Thm. VI.3.3). First order; for undamped mechanics it
    conserves a modified energy, so oscillations neither grow nor decay spuriously.
    """
    k1 = vectors[0]
    rhs(t, x, c, u, levels, force_table, k1, w)
    lanes = x.shape[1]
    for j in active:
        for lane in range(lanes):
            x[j, lane] += h * k1[j, lane]
    for m in range(pairs.shape[0]):
        # undo the explicit position update and redo it with the updated velocity
        p, v = pairs[m, 0], pairs[m, 1]
        for lane in range(lanes):
            x[p, lane] += h * (x[v, lane] - k1[p, lane])


@numba.njit(**KERNEL)
def w_matrix(t, x, h, c, u, levels, force_table, vectors, w, matrices, small, active):
    """``(I - gamma h J)^-1`` of every lane with ``J`` by forward differences of the right-hand side, over the
    integrated states ``active`` (matrix index ``i`` is state ``active[i]``), into ``matrices[:n, :n, lane]``.

    Each perturbation is ``sqrt(eps)`` relative to the state's magnitude in its lane, with a floor of 1e-12
    absolute: the ball-groove deflections are micrometres, so the floor must sit far below them. Every lane's
    state ``j`` is perturbed at once (one right-hand side for all lanes). The right-hand sides go to ``vectors[4:6]``
    (free before the step, :func:`rosenbrock_w2_step` uses ``vectors[0:4]``), each lane's matrix is copied to and
    inverted in ``small`` (:class:`Workspace`). A singular matrix leaves the lane's matrices NaN, so its step turns
    non-finite and the loop's guard stops it.
    """
    n = active.shape[0]
    lanes = x.shape[1]
    size = matrices.shape[1]
    f0, column = vectors[5], vectors[4]
    saved, delta = matrices[size, 0], matrices[size + 1, 0]
    rhs(t, x, c, u, levels, force_table, f0, w)
    for jj in range(n):
        state = active[jj]
        for lane in range(lanes):
            saved[lane] = x[state, lane]
            delta[lane] = 1.5e-8 * max(abs(saved[lane]), 1e-4)
            x[state, lane] = saved[lane] + delta[lane]
        rhs(t, x, c, u, levels, force_table, column, w)
        for lane in range(lanes):
            x[state, lane] = saved[lane]
            for ii in range(n):
                matrices[ii, jj, lane] = (-ROS2_GAMMA * h * (column[active[ii], lane] - f0[active[ii], lane])
                                          / delta[lane])
            matrices[jj, jj, lane] += 1.0
    single, inverted = small[:n, :n], small[size:size + n, :n]
    for lane in range(lanes):
        for ii in range(n):
            for jj in range(n):
                single[ii, jj] = matrices[ii, jj, lane]
        # fixed operation order (numerics.linalg): not LAPACK, whose bits depend on the BLAS kernel
        inverse_into(single, inverted)
        for ii in range(n):
            for jj in range(n):
                matrices[ii, jj, lane] = inverted[ii, jj]


@numba.njit(**KERNEL)
def _matvec(matrices, vector, out, active):
    """``out[active] = matrix @ vector[active]`` in every lane (the W-method's stages)."""
    n = active.shape[0]
    lanes = vector.shape[1]
    for lane in range(lanes):
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += matrices[i, j, lane] * vector[active[j], lane]
            out[active[i], lane] = acc


@numba.njit(**KERNEL)
def rosenbrock_w2_step(t, x, h, c, u, levels, force_table, vectors, w, matrices, active):
    """Two-stage Rosenbrock W-method ROS2 (Verwer, Spee, Blom & Hundsdorfer, SIAM J. Sci. Comput. 20, 1999):

        (I - gamma h J) k1 = f(x),   (I - gamma h J) k2 = f(x + h k1) - 2 k1,
        x+ = x + h (3/2 k1 + 1/2 k2),   gamma = 1 + 1/sqrt(2).

    Second order for *any* matrix ``J`` (a W-method), L-stable with the exact
    Jacobian: the stiff contact, load-cell, Hall-filter and friction-regularisation
    modes are damped instead of limiting the step. The matrices
    ``(I - gamma h J)^-1`` are refreshed by :func:`w_matrix` when the loop asks.
    """
    k1, k2, xs, f = vectors[0], vectors[1], vectors[2], vectors[3]
    lanes = x.shape[1]
    rhs(t, x, c, u, levels, force_table, f, w)
    _matvec(matrices, f, k1, active)
    _copy(x, xs)
    _stage(x, k1, h, xs, active)
    rhs(t + h, xs, c, u, levels, force_table, f, w)
    for i in active:
        for lane in range(lanes):
            f[i, lane] -= 2.0 * k1[i, lane]
    _matvec(matrices, f, k2, active)
    for i in active:
        for lane in range(lanes):
            x[i, lane] += h * (1.5 * k1[i, lane] + 0.5 * k2[i, lane])


@numba.njit(**KERNEL)
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


@numba.njit(**KERNEL)
def imex_euler_step(t, x, h, c, u, levels, force_table, vectors, w, cache, small, active):
    """Linearly implicit (IMEX) symplectic Euler: one right-hand side per step, the stiff springs implicit.

    With ``F`` the mechanical generalised forces at the current state and ``K``, ``D`` the analytic
    tangent stiffness and damping of the stiff elements only (:func:`twin.engine.implicit.stiff_velocity_system`:
    ball-groove contacts, springs, friction slopes), the velocities of the mechanical DOFs take

        (M + h D + h^2 K) dv = h (F - h K v),   v+ = v + dv,   q+ = q + h v+,

    i.e. implicit Euler on the linearised stiff forces at the new positions ``q + h v+`` and velocities
    ``v+``, and the symplectic Euler of :func:`semi_implicit_euler_step` on everything else. The other
    blocks:

    * the full current loop (winding, Hall filter, analog PI: linear, with a -2.3e4 1/s mode) takes one
      linearly implicit Euler step ``(I - h J) dy = h f`` with its exact Jacobian
      (:func:`twin.engine.implicit.current_loop_jacobian`);
    * the ideal current loop's lag and the valve spool are linear with a held input: exact propagators
      (:func:`twin.engine.plant.held_input_propagators`);
    * the chamber pressures and the winding temperature: explicit Euler.

    The whole is a W-method: first order for any ``K``, ``D``, ``J`` (Hairer & Wanner, *Solving ODEs II*,
    Sec. IV.7: the linearly implicit Euler with an approximate Jacobian; Sec. IV.9 for mechanical
    systems); the matrices decide only stability. On a linear spring-mass-damper it is implicit Euler on
    the velocity with the symplectic position update: stable for any ``h``, never adding energy
    (tests/engine/test_imex_euler.py). The price is numerical damping, about ``h w^2 / 2`` [1/s] on a
    mode ``w``: on the contact mode at 125 us it suppresses a self-excited 255 Hz oscillation that the
    model has on some data sets (docs/accuracy.md). It needs the ``dynamic`` screw-axial level (the simulation
    refuses it otherwise).

    ``small`` holds one lane's 8 x 8 mechanical and 3 x 3 current-loop systems at a time (:class:`Workspace`),
    ``cache`` the propagators of every lane.
    """
    f = vectors[0]
    lanes = x.shape[1]
    rhs(t, x, c, u, levels, force_table, f, w)
    matrix = small[:N_DOFS, :N_DOFS]
    b, velocity = small[N_DOFS], small[N_DOFS + 1]
    loop = small[N_DOFS + 2:N_DOFS + 5, :3]
    current = small[N_DOFS + 4, 3:6]
    full_loop = levels[CURRENT_LOOP] == CURRENT_LOOP_FULL
    for lane in range(lanes):
        held_input_propagators(c, h, lane, cache)
        stiff_velocity_system(x, c, w, lane, levels, f, h, matrix, b, velocity)
        solve_in_place(matrix, b, N_DOFS)
        if full_loop:
            current_loop_jacobian(x, c, u, lane, loop)
            for i in range(3):
                for j in range(3):
                    loop[i, j] = (1.0 if i == j else 0.0) - h * loop[i, j]
                current[i] = h * f[CURRENT_LOOP_STATES[i], lane]
            solve_in_place(loop, current, 3)
        for j in active:
            x[j, lane] += h * f[j, lane]
        # replace the explicit update of the implicit states; f still holds the old velocities for the positions
        for i in range(N_DOFS):
            if dof_active(levels, i):
                p = DOF_POSITIONS[i]
                x[p + 1, lane] += b[i] - h * f[p + 1, lane]
                x[p, lane] += h * (x[p + 1, lane] - f[p, lane])
        if full_loop:
            for i in range(3):
                x[CURRENT_LOOP_STATES[i], lane] += current[i] - h * f[CURRENT_LOOP_STATES[i], lane]
        else:
            # dx/dt = (demand - x) / tau: the exact step moves the fraction cache[8] of the way to the demand
            x[S.CURRENT, lane] += (f[S.CURRENT, lane] * c[K.CURRENT_LOOP_TAU, lane] * cache[8, lane]
                                   - h * f[S.CURRENT, lane])
        if levels[PNEUMATICS] == PNEUMATICS_FULL:
            # spool: y = (x - s, v) with the held target s = x + (a + 2 zeta w v) / w^2 follows y+ = Phi y
            omega, zeta = cache[1, lane], cache[2, lane]
            position = x[S.SPOOL_POSITION, lane] - h * f[S.SPOOL_POSITION, lane]
            speed = x[S.SPOOL_SPEED, lane] - h * f[S.SPOOL_SPEED, lane]
            offset = -(f[S.SPOOL_SPEED, lane] + 2.0 * zeta * omega * speed) / (omega * omega)
            x[S.SPOOL_POSITION, lane] = position + (cache[4, lane] - 1.0) * offset + cache[5, lane] * speed
            x[S.SPOOL_SPEED, lane] = cache[6, lane] * offset + cache[7, lane] * speed


@numba.njit(**KERNEL)
def step(method, t, x, h, c, u, levels, force_table, vectors, w, matrices, cache, small, refresh, active, pairs):
    """Advance the ``active`` states of every lane of ``x`` by one step ``h``; ``refresh`` asks the W-method to
    rebuild its matrices; ``pairs`` are the (position, velocity) pairs of the semi-implicit Euler step."""
    if method == RK4:
        rk4_step(t, x, h, c, u, levels, force_table, vectors, w, active)
    elif method == SEMI_IMPLICIT_EULER:
        semi_implicit_euler_step(t, x, h, c, u, levels, force_table, vectors, w, active, pairs)
    elif method == IMEX_EULER:
        imex_euler_step(t, x, h, c, u, levels, force_table, vectors, w, cache, small, active)
    else:
        if refresh:
            w_matrix(t, x, h, c, u, levels, force_table, vectors, w, matrices, small, active)
        rosenbrock_w2_step(t, x, h, c, u, levels, force_table, vectors, w, matrices, active)
