"""A body on a friction law, integrated alone: the known answers of the laws (tests/physics/test_bristle_friction.py)
and the measurement that chooses between them (benchmarks/friction_laws.py; issue 41, item 2).

The body (mass ``m``, position ``x``, speed ``v``) is driven by a spring ``k`` pulled at constant speed ``V`` and by
a force ``F_0 + A sin(w t) + r t``; the friction is one of :data:`LAWS`. States ``(x, v, z, W, D)``: the bristle
deflection ``z`` (unused by the regularised law), the drive's work ``W`` and the energy the friction dissipated
``D = int (F v - sigma_0 z dz/dt) dt`` (twin.physics.bristle_friction, "Dissipation"). Fixed-step RK4, compiled.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from twin.physics import bristle_friction as bf
from twin.physics.friction import stribeck_friction, stribeck_level

LUGRE, ELASTOPLASTIC, REGULARISED = 0, 1, 2
LAWS = {"lugre": LUGRE, "elastoplastic": ELASTOPLASTIC, "regularised": REGULARISED}
# layout of the law's parameter vector
MASS, STATIC, DYNAMIC, RATE, STIFFNESS, DAMPING, DAMPING_SPEED, VISCOUS, ELASTIC_DEFLECTION, V_THRESHOLD = range(10)
N_PARAMETERS = 10


def law_parameters(mass, static, dynamic, stribeck_rate, stiffness, damping, damping_speed, viscous,
                   elastic_deflection, v_threshold) -> np.ndarray:
    """The parameter vector of :func:`integrate` (SI units; ``v_threshold`` only for the regularised law)."""
    return np.array([mass, static, dynamic, stribeck_rate, stiffness, damping, damping_speed, viscous,
                     elastic_deflection, v_threshold], dtype=float)


@numba.njit(cache=True)
def friction(law, p, v, z):
    """Friction force [N] and bristle rate [m/s] of ``law`` at speed ``v`` and deflection ``z``."""
    if law == REGULARISED:
        return stribeck_friction(v, p[STATIC], p[DYNAMIC], p[RATE], p[VISCOUS], p[V_THRESHOLD]), 0.0
    level = stribeck_level(v, p[STATIC], p[DYNAMIC], p[RATE])
    if law == LUGRE:
        rate = bf.lugre_deflection_rate(v, z, level, p[STIFFNESS])
    else:
        rate = bf.elastoplastic_deflection_rate(v, z, level, p[STIFFNESS], p[ELASTIC_DEFLECTION])
    return bf.bristle_force(v, z, rate, p[STIFFNESS], p[DAMPING], p[DAMPING_SPEED], p[VISCOUS]), rate


@numba.njit(cache=True)
def _rhs(law, p, t, y, drive):
    spring, speed, force0, amplitude, omega, ramp = drive[0], drive[1], drive[2], drive[3], drive[4], drive[5]
    force, rate = friction(law, p, y[1], y[2])
    extension = speed * t - y[0]
    applied = force0 + amplitude * math.sin(omega * t) + ramp * t
    out = np.empty(5)
    out[0] = y[1]
    out[1] = (spring * extension + applied - force) / p[MASS]
    out[2] = rate
    out[3] = spring * extension * speed + applied * y[1]
    out[4] = force * y[1] - p[STIFFNESS] * y[2] * rate if law != REGULARISED else force * y[1]
    return out


@numba.njit(cache=True)
def integrate(law, p, duration, dt, drive):
    """RK4 at the fixed step ``dt`` from rest; ``drive = (k, V, F_0, A, w, r)``. Returns the times and the states
    ``(x, v, z, W, D)`` at every step."""
    n = int(round(duration / dt))
    ys = np.zeros((n + 1, 5))
    ts = np.arange(n + 1) * dt
    y = np.zeros(5)
    for i in range(n):
        t = ts[i]
        k1 = _rhs(law, p, t, y, drive)
        k2 = _rhs(law, p, t + dt / 2, y + dt / 2 * k1, drive)
        k3 = _rhs(law, p, t + dt / 2, y + dt / 2 * k2, drive)
        k4 = _rhs(law, p, t + dt, y + dt * k3, drive)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        ys[i + 1] = y
    return ts, ys


def drive(spring=0.0, speed=0.0, force0=0.0, amplitude=0.0, frequency=0.0, ramp=0.0) -> np.ndarray:
    """The drive vector of :func:`integrate` (``frequency`` in Hz)."""
    return np.array([spring, speed, force0, amplitude, 2.0 * math.pi * frequency, ramp], dtype=float)


@numba.njit(cache=True)
def kinematic_loop(law, p, amplitude, frequency, cycles, dt):
    """Friction force against an imposed position ``X sin(2 pi f t)`` (``z`` by RK4): positions and forces."""
    n = int(round(cycles / frequency / dt))
    w = 2.0 * math.pi * frequency
    xs, fs = np.empty(n), np.empty(n)
    z = 0.0
    for i in range(n):
        t = i * dt
        v0, vh, v1 = (amplitude * w * math.cos(w * t), amplitude * w * math.cos(w * (t + dt / 2)),
                      amplitude * w * math.cos(w * (t + dt)))
        k1 = friction(law, p, v0, z)[1]
        k2 = friction(law, p, vh, z + dt / 2 * k1)[1]
        k3 = friction(law, p, vh, z + dt / 2 * k2)[1]
        k4 = friction(law, p, v1, z + dt * k3)[1]
        z += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        xs[i] = amplitude * math.sin(w * (t + dt))
        fs[i] = friction(law, p, v1, z)[0]
    return xs, fs
