"""Fixed-step integrators for the compiled loop.

Each advances the plant of :mod:`twin.engine.plant` by one step ``h`` with the
controller outputs held (zero-order hold). Selected by integer code so the
compiled loop can branch without Python objects.
"""

import numba
import numpy as np

from twin.engine.layout import POSITION_VELOCITY_PAIRS
from twin.engine.plant import rhs

RK4 = 0
SEMI_IMPLICIT_EULER = 1
INTEGRATORS = {"rk4": RK4, "semi_implicit_euler": SEMI_IMPLICIT_EULER}
ORDER = {"rk4": 4, "semi_implicit_euler": 1}

_POSITIONS = np.array([p for p, _ in POSITION_VELOCITY_PAIRS], dtype=np.int64)
_VELOCITIES = np.array([v for _, v in POSITION_VELOCITY_PAIRS], dtype=np.int64)


@numba.njit(cache=True)
def rk4_step(t, x, h, c, u, force_table, stiffness_poly, work):
    """Classical 4th-order Runge-Kutta (Hairer, Norsett & Wanner, *Solving ODEs I*, Table 1.2).

    ``work`` is a (5, n) scratch array: k1..k4 and the stage state.
    """
    k1, k2, k3, k4, xs = work[0], work[1], work[2], work[3], work[4]
    rhs(t, x, c, u, force_table, stiffness_poly, k1)
    for j in range(x.shape[0]):
        xs[j] = x[j] + 0.5 * h * k1[j]
    rhs(t + 0.5 * h, xs, c, u, force_table, stiffness_poly, k2)
    for j in range(x.shape[0]):
        xs[j] = x[j] + 0.5 * h * k2[j]
    rhs(t + 0.5 * h, xs, c, u, force_table, stiffness_poly, k3)
    for j in range(x.shape[0]):
        xs[j] = x[j] + h * k3[j]
    rhs(t + h, xs, c, u, force_table, stiffness_poly, k4)
    for j in range(x.shape[0]):
        x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])


@numba.njit(cache=True)
def semi_implicit_euler_step(t, x, h, c, u, force_table, stiffness_poly, work):
    """Symplectic (semi-implicit) Euler: velocities and first-order states explicit,
    then positions with the *new* velocities (Hairer, Lubich & Wanner, *Geometric
    Numerical Integration*, Thm. VI.3.3). First order; for undamped mechanics it
    conserves a modified energy, so oscillations neither grow nor decay spuriously.
    """
    k1 = work[0]
    rhs(t, x, c, u, force_table, stiffness_poly, k1)
    for j in range(x.shape[0]):
        x[j] += h * k1[j]
    for m in range(_POSITIONS.shape[0]):
        # undo the explicit position update and redo it with the updated velocity
        p = _POSITIONS[m]
        if p >= x.shape[0]:
            continue  # subsystem not present at this fidelity
        v = _VELOCITIES[m]
        x[p] += h * (x[v] - k1[p])


@numba.njit(cache=True)
def step(method, t, x, h, c, u, force_table, stiffness_poly, work):
    if method == RK4:
        rk4_step(t, x, h, c, u, force_table, stiffness_poly, work)
    else:
        semi_implicit_euler_step(t, x, h, c, u, force_table, stiffness_poly, work)
