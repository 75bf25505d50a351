"""The automatic integrator (``integrator="auto"``, opt-in): one implicit step per drive period where both nuts
are held on a flank, explicit RK4 where a nut can move in its gap, at the drive period where that is stable.

``imex_euler`` (:func:`twin.engine.integrators.imex_euler_step`) at the 125 us drive period costs about a
third of RK4 at 62.5 us and agrees with it within 0.02 um on the Eq. 9.12 feature as long as both ball-groove
contacts stay loaded; once a nut unloads, the feature depends on the 3.8 kHz contact mode, which the implicit
step damps at that period (errors of 0.08-2.7 um: docs/accuracy.md, "The automatic integrator"). So the
choice is made *along the run*, not guessed from the scene: the implicit step is tried with the held-contact
premise checked after every step (:func:`twin.engine.loop.contacts_held`); once the nuts have spent more than
:data:`RELEASE_BUDGET` in all with a contact load below :data:`HELD_CONTACT_LOAD`, the attempt ends there and
the scene is solved again from the start by RK4 (same noise draws).

RK4 is tried first at the drive period, 125 us, unless the linearised bench at its initial state already has a
mode beyond RK4's reach at that step (:func:`rk4_limit_at_start`: the full-fidelity analog current loop), and is
kept only if the run ends ``ok`` (divergence guard silent, the local-error guard on whatever the caller asked
for) and its step-doubling local-error estimate (:func:`twin.engine.loop.local_error`, every 4 ms) never exceeded
the tolerance, not even once (the guard itself stops a run only after three checks in a row); else the
scene is solved once more at RK4's default 62.5 us, bit-identical to a plain RK4 run. Why this can pay: with a nut
free in its gap the ball-groove/screw-axial mode has one contact instead of two, and RK4's stability limit along
the free-nut data sets' runs is 137-153 us (``benchmarks/speed_floor.py``: the Jacobian's eigenvalues at 200
instants of each run), against 109-121 us with both nuts loaded, where the 125 us attempt diverges within ~1 s of
simulated time. Its accuracy on the thesis data sets is in docs/accuracy.md ("The automatic integrator").
Each run says which method and step solved it and why (``attrs["integrator_choice"]``).

Why it is not the default: a held contact can still carry a self-excited vibration of the contact mode, which the
implicit step damps like the free nut's. Under the preloaded zero procedure (ds1, ds5) the Eq. 9.12 feature
(about 1 um there) is made of that vibration: RK4 at any step spreads between ~0.99 and ~1.13 um, the implicit
step gives 0.97 um at every step, and over the 2 x 200 preloaded study the paired shift is -0.10 um with the
run-to-run sigma halved (docs/accuracy.md). The premise, judged on the implicit trajectory, cannot see it.
"""

from __future__ import annotations

import numpy as np

from twin.engine.linearize import jacobian, largest_stable_step
from twin.engine.model import Model, contact_position_for_force
from twin.engine.reference import METHODS as REFERENCE_METHODS
from twin.layout import BOUND_CONTACT_RELEASED, K

#: Per-nut axial contact load [N] below which a nut counts as released. Numerical choice, from the preload
#: sweep of docs/accuracy.md ("The automatic integrator"). The load is judged on the implicit step's own
#: trajectory, which damps the dynamics that unload a nut: where RK4 shows a nut's load dipping to 73-82 N
#: (preload 700 N) the implicit run's smallest load is 247-323 N. So the threshold sits well above zero. With it
#: (and :data:`RELEASE_BUDGET`) the sweep hands to RK4 every run at preload <= 600 N without backlash and <= 700 N
#: with 80 um of it (the implicit step alone would err by up to 0.075 um there), and keeps the implicit step at
#: 650-1000 N without backlash (worst 0.031 um, at 650 N) and 750-1000 N with it (worst 0.010 um).
HELD_CONTACT_LOAD = 300.0

#: Time [s] a run may spend, in all, with a nut below :data:`HELD_CONTACT_LOAD` and still be trusted to the
#: implicit step. Numerical choice, from the same evidence: a one-off release such as the nominal scene's at its
#: 4 kN force step (10 ms below 300 N, feature within 0.0013 um of RK4) is harmless; a release at every reversal
#: adds up to 35-64 ms over the 10 s test (preload 600-700 N). The free-nut data sets pass 20 ms within their
#: first 0.05 s, so their wasted attempt is short.
RELEASE_BUDGET = 0.020

#: The implicit branch, run at the drive period (``drive.speed_loop_sample_time``, over which its inputs are
#: held); the explicit branch is the default method (:mod:`twin.simulation`), at the drive period, then at its
#: default step.
IMPLICIT_METHOD = "imex_euler"


def held_interference(model: Model, load: float = HELD_CONTACT_LOAD) -> float:
    """Axial interference [m] (``|dx| - b/2``, Eq. 9.5) at which one nut's static contact carries ``load``."""
    c = model.constants
    return abs(contact_position_for_force(c, model.stiffness_poly, load)) - 0.5 * c[K.BACKLASH]


def rk4_limit_at_start(model: Model) -> float:
    """RK4's largest stable step [s] for the linearised bench at its initial state (the Jacobian's eigenvalues,
    :mod:`twin.engine.linearize`). Where it is below the drive period a mode is beyond reach from the start, such
    as the full-fidelity analog current loop's -2.28e4 1/s (limit 122 us), and the drive-period attempt would
    fail once that mode is excited, so it is not tried; a mode that appears only under load (the ball-groove
    contacts) is left to the attempt's guards."""
    return largest_stable_step(np.linalg.eigvals(jacobian(model, model.initial_state[model.active])), rtol=1e-6)


def solver_label(integrator: str, dt: float) -> str:
    """How results, reports and statements name the solver of a run: the method and, for a fixed-step method of the
    compiled loop, its step (``"rk4 at 62.5 us"``); an adaptive reference method by its name alone."""
    return integrator if integrator in REFERENCE_METHODS or not integrator else f"{integrator} at {dt * 1e6:g} us"


def choice_statement(method: str, dt: float, stopped=()) -> str:
    """Why the automatic integrator solved a run with ``method`` at ``dt`` [s]: the line of
    ``attrs["integrator_choice"]``. ``stopped``: the attempts before it, each ``(method, dt, t_reached, bound code,
    reason)`` of where and why it ended, ``t_reached`` None for an attempt not tried (empty: the implicit step
    solved the run)."""
    if not stopped:
        return (f"auto: {solver_label(method, dt)}; both nuts' contact loads stayed >= {HELD_CONTACT_LOAD:g} N "
                f"except for <= {RELEASE_BUDGET * 1e3:g} ms in all")
    ends = []
    for tried, step, stopped_at, bound, reason in stopped:
        if stopped_at is None:
            ends.append(f"{solver_label(tried, step)} not tried: {reason}")
            continue
        why = (f"a nut's contact load having been below {HELD_CONTACT_LOAD:g} N for more than "
               f"{RELEASE_BUDGET * 1e3:g} ms in all" if bound == BOUND_CONTACT_RELEASED else f"failed: {reason}")
        ends.append(f"{solver_label(tried, step)} stopped at t = {stopped_at:.6f} s, {why}")
    return f"auto: {solver_label(method, dt)}; " + "; ".join(ends)
