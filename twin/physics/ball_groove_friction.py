"""Ball-groove friction of the reduced ball screw (Ch. 5, Eqs. 5.16-5.24), catalogue drag torque (Eq. 7.85).

What Ch. 5 resolves and what the reduced bench model keeps
----------------------------------------------------------
The Ch. 5 model (Sec. 5.2) integrates one representative sphere per nut: its translation
along the contact line and the helix tangent ``t`` and its rotation ``theta_b``. The sliding
friction forces ``H_A``, ``H_B`` at the nut and screw contacts follow the sliding speed of
the sphere's surface on each groove through the continuous law of Eq. 5.16, and the rolling
friction is an extra tangential force on the screw (Eqs. 5.17-5.18) whose coefficient depends
on the contact load and on the sphere's rolling speed (Eqs. 5.19-5.24).

The bench model (Sec. 9.3) has no sphere states: the contact law already reduces the spheres
of a nut to one normal load ``P`` per sphere (Eqs. 9.4-9.6, ``Z_eff`` loaded spheres, Eq. 5.5).
The friction is reduced accordingly:

* **Load.** The sphere's inertia and the centrifugal force are neglected (Sec. 5.5 finds the
  centrifugal force ~2 N on this screw size, Sec. 7.9.5), so the screw-side and nut-side normal
  loads are equal, ``P' = P``, the load the contact model computes.
* **Rolling speed.** The sphere rolls without slip between the screw and the nut grooves, as
  in the revolution-speed estimate of Eq. 5.27: its centre moves at half the grooves' relative
  speed along the helix, ``v_t``, and it turns at ``theta_b' = v_t / (2 r_b)``.
* **Rolling friction** (Eqs. 5.19-5.24): per contact the tangential force is ``P f_v`` with
  ``f_v = u / r_b = (k_gc k_rf P^0.26 + f_v1 r_b theta_b'^2) / r_b``, in the direction of ``v_t``
  regularised by ``tanh(v_t / v_roll)`` (the thesis's own regularisation of the rolling moments,
  Sec. 7.4.1), both contacts of the sphere counted, as Eq. 5.18 does.
* **Sliding friction** (Eq. 5.16): without sphere states the micro-slip of each sphere is not
  resolved. The sliding part is lumped into one equivalent coefficient per contact,
  ``mu(v_t)`` of Eq. 5.16 evaluated at the grooves' relative speed: zero at rest, a static peak
  at the speeds of a reversal, the dynamic level ``g_4`` in steady motion and a viscous rise.
  In steady motion this is the Coulomb part of the drag (linear in the load), which the Ch. 5
  model gets from the sphere's slip; at reversals it gives the stick-slip shape of Fig. 5.17.
  What is lost: the separate slip of the screw and nut contacts, the sphere's bouncing in an
  open gap (Fig. 5.17 points 2-3) and the centrifugal load shift.

So each nut carries one tangential friction force along the helix,
``F_t = 2 Z_eff P [mu(v_t) + f_v(P, v_t) tanh(v_t / v_roll)]``, opposing the relative motion of
the screw grooves on the nut grooves. Its generalised forces (:func:`friction_generalised_forces`)
are the partial derivatives of the dissipated power ``F_t v_t``, so the energy balance closes
exactly with the friction dissipation (tests/engine/test_ball_screw_friction_energy.py).
"""

import math

import numba

from numerics import elementary
from numerics.jit import SCALAR
from twin.physics.friction import sech_squared

#: Exponent of the load dependence of the rolling friction (Eqs. 5.20, 5.22): "an average exponent
#: ... equal to 0.26" between the low-load ``P^0.2`` and the Gerstner-Coriolis ``P^(1/3)`` laws.
ROLLING_LOAD_EXPONENT = 0.26


@numba.njit(**SCALAR)
def sliding_coefficient(v, g1, g2, g3, g4, g5, g6):
    """Sliding friction coefficient of Eq. 5.16 (Makkar et al. 2005), odd in ``v``.

    ``mu = g1 [tanh(g2 v) - tanh(g3 v)] + g4 tanh(g5 v) + g6 v``.

    Parameters
    ----------
    v : float
        Sliding speed [m/s].
    g1, g4 : float
        Stribeck hump and dynamic (Coulomb) levels [1].
    g2, g3, g5 : float
        Speed scales of the hump's rise and decay and of the Coulomb term [s/m].
    g6 : float
        Viscous slope [s/m].
    """
    return (g1 * (elementary.tanh(g2 * v) - elementary.tanh(g3 * v)) + g4 * elementary.tanh(g5 * v)
            + g6 * v)


@numba.njit(**SCALAR)
def rolling_coefficient(normal_load, ball_speed, k_gc, k_rf, f_v1, ball_radius):
    """Rolling friction coefficient ``f_v = u / r_b`` of one contact (Eqs. 5.19-5.24) [1].

    Parameters
    ----------
    normal_load : float
        ``P >= 0`` [N].
    ball_speed : float
        Sphere rolling speed ``theta_b'`` [rad/s].
    k_gc : float
        Load coefficient [m N^-0.26] (``u = k_gc k_rf P^0.26`` at rest, Eq. 5.23).
    k_rf : float
        Friction multiplier of the sensitivity analysis (1 nominal; Fig. 5.8).
    f_v1 : float
        Speed coefficient [s^2] (Eq. 5.19).
    ball_radius : float
        ``r_b`` [m].
    """
    # x^0.26 of numerics.elementary (the exponent ROLLING_LOAD_EXPONENT is built into it); 0 for P <= 0
    load_term = k_gc * k_rf * elementary.pow026(max(normal_load, 0.0)) / ball_radius
    return load_term + f_v1 * ball_speed * ball_speed


@numba.njit(**SCALAR)
def nut_friction_force(normal_load, tangential_speed, loaded_balls, ball_radius, g1, g2, g3, g4, g5, g6,
                       k_gc, k_rf, f_v1, rolling_threshold):
    """Tangential friction force of one nut along the helix [N], positive along ``v_t`` (reduced Ch. 5).

    ``F_t = 2 Z P [mu(v_t) + f_v(P, v_t / (2 r_b)) tanh(v_t / v_roll)]``: both contacts of each of
    the ``Z`` loaded spheres (Eq. 5.18), sliding (Eq. 5.16) and rolling (Eqs. 5.19-5.24) parts (module
    docstring for the reduction). It acts on the nut along ``+t`` and on the screw along ``-t``.

    Parameters
    ----------
    normal_load : float
        Normal load per sphere ``P`` [N] (zero in the backlash gap).
    tangential_speed : float
        ``v_t``, speed of the screw grooves relative to the nut grooves along the helix [m/s].
    loaded_balls : float
        ``Z_eff`` (Eq. 5.5).
    ball_radius : float
        ``r_b`` [m].
    g1 ... g6 : float
        Eq. 5.16 (:func:`sliding_coefficient`).
    k_gc, k_rf, f_v1 : float
        Eqs. 5.19-5.24 (:func:`rolling_coefficient`).
    rolling_threshold : float
        ``v_roll`` of the rolling term's direction, ``tanh(v_t / v_roll)`` [m/s].
    """
    ball_speed = 0.5 * tangential_speed / ball_radius
    sliding = sliding_coefficient(tangential_speed, g1, g2, g3, g4, g5, g6)
    rolling = rolling_coefficient(normal_load, ball_speed, k_gc, k_rf, f_v1, ball_radius)
    direction = elementary.tanh(tangential_speed / rolling_threshold)
    force = 2.0 * loaded_balls * normal_load * (sliding + rolling * direction)
    return force if normal_load > 0.0 else 0.0


@numba.njit(**SCALAR)
def tangential_speed(screw_speed, nut_angular_speed, screw_axial_speed, nut_speed, pitch_radius, cos_helix,
                     sin_helix):
    """``v_t``: speed of the screw's groove relative to the nut's along the helix tangent [m/s].

    The helix tangent in (circumferential, axial) coordinates of the screw relative to the nut is
    ``(cos alpha_e, -sin alpha_e)`` in the sign convention of :mod:`twin.physics.ball_screw` (a
    positive screw rotation advances the nut along ``+x``), so
    ``v_t = r_m cos(alpha_e) (theta_s' - theta_n') - sin(alpha_e) (x_s' - x_n')``; for a nut following the
    screw, ``x_n' = p theta_s' / (2 pi)``, it is ``r_m theta_s' / cos(alpha_e)`` (``y_up'`` of Eq. 5.15).
    """
    return (pitch_radius * cos_helix * (screw_speed - nut_angular_speed)
            - sin_helix * (screw_axial_speed - nut_speed))


@numba.njit(**SCALAR)
def friction_generalised_forces(force, pitch_radius, cos_helix, sin_helix):
    """Generalised forces of a nut's helix friction ``force`` (from :func:`nut_friction_force`).

    ``Q_k = -F_t dv_t/dq_k'``, so that their power is ``-F_t v_t`` (the dissipation).

    Returns
    -------
    (screw_torque, nut_torque, screw_axial_force, nut_axial_force)
        [N m, N m, N, N]: the friction torque on the screw is ``-F_t r_m cos(alpha_e)``.
    """
    torque = force * pitch_radius * cos_helix
    axial = force * sin_helix
    return -torque, torque, axial, -axial


def catalogue_drag_torque(lead: float, preload: float, helix_angle: float) -> float:
    """No-load drag torque of a preloaded ball screw from the manufacturers' formula, Eq. 7.85 [N m].

    ``T_drag0 = 0.05 p F_pr / (2 pi sqrt(tan(alpha_e)))``; linear in the preload.
    """
    return 0.05 * lead * preload / (2.0 * math.pi * math.sqrt(math.tan(helix_angle)))


@numba.njit(**SCALAR)
def nut_friction_slope(normal_load, tangential_speed, loaded_balls, ball_radius, g1, g2, g3, g4, g5, g6,
                       k_gc, k_rf, f_v1, rolling_threshold):
    """Stiff part of ``dF_t/dv_t`` of :func:`nut_friction_force` [N s/m], load held, floored at zero (same
    arguments): the slopes of the ``tanh`` terms, exactly zero away from a reversal.

    The viscous ``g6`` and the speed dependence of the rolling coefficient are left out (not stiff) and the
    Stribeck decay may make the exact slope negative: the linearly implicit integrators use this only for the stability
    of sticking (a W-method is consistent for any matrix; Hairer & Wanner, *Solving ODEs II*, Sec. IV.7).
    """
    v = tangential_speed
    slope = g1 * (g2 * sech_squared(g2 * v) - g3 * sech_squared(g3 * v)) + g4 * g5 * sech_squared(g5 * v)
    rolling_direction = sech_squared(v / rolling_threshold)  # exactly 0 away from a reversal
    slope += (rolling_coefficient(normal_load, 0.5 * v / ball_radius, k_gc, k_rf, f_v1, ball_radius)
              * rolling_direction / rolling_threshold)
    return max(2.0 * loaded_balls * normal_load * slope, 0.0) if normal_load > 0.0 else 0.0
