"""Design of the external-force PI loop of the pneumatic load system.

Bertolino (2020), Sec. 9.3.2 / Fig. 9.7: a PI controller on the external-force
load-cell reading commands the MPYE valve voltage.  The plant is the valve
spool, the two chambers and the piston of ``twin.physics.pneumatics``
(Eqs. 9.9-9.11) with the load cell (Table B.13) reacting on a master nut held
fixed -- the sled is position-controlled through the stiff ball screw, so over
the force-loop bandwidth it is an almost immovable abutment.

The plant is linearised numerically around the working point (piston at mid
stroke, 4 kN on the load cell as in the Fig. 9.7 force step, valve flows in
balance), the PI gains are chosen for a target crossover with the integral
corner a fixed fraction below it, and the loop is evaluated in discrete time:
plant discretised with a zero-order hold (the controller's D/A output), PI
with forward-Euler integration as run by ``twin.control.discrete.pi_step``:
``u_k = kp e_k + I_k``, ``I_{k+1} = I_k + ki T e_k``, i.e.
``C(z) = kp + ki T / (z - 1)``, the command being ``u_mid + u_k`` with
``pi_step``'s limit ``(u_max - u_min) / 2``.  As in ``twin.engine.loop`` the
command is applied in the tick it is computed (no computation delay beyond
the hold).  The valve hysteresis play (0.4 %) is left out of the linear
model.
"""

import math

import numpy as np
from scipy.optimize import brentq

from twin.physics import pneumatics as pn

__all__ = ["NutFixedPlant", "operating_point", "linearised_matrices", "linearised_plant", "design_force_loop"]

STATE_NAMES = ("x_spool", "v_spool", "p1", "p2", "x_piston", "v_piston")
# Typical magnitudes of the states [-, 1/s, Pa, Pa, m, m/s]: the linear model is
# built in states divided by these so its matrices are well conditioned.
_STATE_SCALE = np.array([1.0, 1.0e3, 1.0e5, 1.0e5, 1.0e-6, 1.0e-3])
# Central-difference steps [-, 1/s, Pa, Pa, m, m/s] and for the command [V]:
# small against each state's range yet far above round-off.  The spool step
# must stay below the working spool opening (the metering-edge kink at 0).
_STATE_STEP = np.array([1.0e-8, 1.0e-4, 1.0, 1.0, 1.0e-10, 1.0e-7])
_COMMAND_STEP = 1.0e-6


class NutFixedPlant:
    """Valve, chambers and piston with the load cell reacting on a fixed master nut.

    Composes the ``twin.physics.pneumatics`` functions (Eqs. 9.9-9.11) into
    the state derivative used for linearisation, in ``STATE_NAMES`` order.
    Hysteresis is left out (the command is taken as the effective command).

    Parameters
    ----------
    params : dict
        ``{"pneumatics.<key>": value}``; validated on construction.
    """

    def __init__(self, params):
        pn.validate_pneumatics(params)
        q = {key: float(params["pneumatics." + key]) for key in pn.REQUIRED_KEYS}
        self.q = q
        self.a1, self.a2 = pn.piston_areas(q["bore_diameter"], q["rod_diameter"])
        self.c_max = pn.conductance_from_nominal_flow(
            q["nominal_flow_rate"], q["nominal_flow_upstream_pressure"],
            q["nominal_flow_downstream_pressure"], q["critical_pressure_ratio"], q["laminar_ratio"])

    def mass_flows(self, x_spool, p1, p2):
        """Net mass flows into chambers 1 and 2 [kg/s] (Eq. 9.9, both ports of each chamber)."""
        q = self.q
        return pn.chamber_mass_flows(
            x_spool, p1, p2, q["supply_pressure"], q["atmospheric_pressure"], self.c_max,
            q["valve_leakage_fraction"], q["critical_pressure_ratio"], q["reference_density"],
            q["reference_temperature"], q["air_temperature"], q["air_temperature"],
            q["laminar_ratio"])

    def pneumatic_force(self, p1, p2):
        """Net pressure force on the piston along +x [N] (Eq. 9.11)."""
        return pn.piston_force(p1, p2, self.a1, self.a2, self.q["atmospheric_pressure"])

    def derivatives(self, z, command, x_nut):
        """State derivative and load-cell force.

        Parameters
        ----------
        z : array_like
            State in ``STATE_NAMES`` order [-, 1/s, Pa, Pa, m, m/s].
        command : float
            Effective valve command [V].
        x_nut : float
            Fixed master-nut position (unloaded load cell at ``x = x_nut``) [m].

        Returns
        -------
        tuple
            ``(dz/dt as ndarray, load-cell force [N])``.
        """
        q = self.q
        x_spool, v_spool, p1, p2, x, v = z
        dx_spool, dv_spool = pn.spool_derivative(
            x_spool, v_spool, command, q["valve_mid_voltage"], q["valve_command_min"],
            q["valve_command_max"], q["valve_critical_frequency"], q["valve_damping_ratio"])
        g1, g2 = self.mass_flows(x_spool, p1, p2)
        vol1, dvol1, vol2, dvol2 = pn.chamber_volumes(
            x, v, self.a1, self.a2, q["dead_volume_1"], q["dead_volume_2"], q["stroke"])
        t, r, n = q["air_temperature"], q["gas_constant"], q["polytropic_exponent"]
        dp1 = pn.chamber_pressure_derivative(p1, g1, vol1, dvol1, t, r, n)
        dp2 = pn.chamber_pressure_derivative(p2, g2, vol2, dvol2, t, r, n)
        f_lc = pn.load_cell_spring_force(x, x_nut, v, 0.0, q["load_cell_stiffness"],
                                         q["load_cell_damping"])
        acc = pn.piston_acceleration(
            p1, p2, x, v, f_lc, self.a1, self.a2, q["atmospheric_pressure"], q["piston_mass"],
            q["piston_damping"], q["friction_static"], q["friction_dynamic"],
            q["friction_stribeck_coefficient"], q["friction_viscous"],
            q["friction_velocity_threshold"], q["stroke"], q["damper_travel"],
            q["damper_stiffness"], q["damper_damping"], q["end_stop_stiffness"])
        return np.array([dx_spool, dv_spool, dp1, dp2, v, acc]), f_lc


def _balanced_pressure(plant, x_spool, chamber):
    """Chamber pressure at which supply inflow equals exhaust outflow for a spool position."""
    q = plant.q

    def net_flow(p):
        return plant.mass_flows(x_spool, p, p)[chamber]

    return brentq(net_flow, q["atmospheric_pressure"], q["supply_pressure"], xtol=1e-6, rtol=1e-14)


def operating_point(params, force=4000.0, position=None):
    """Static working point of the valve-cylinder-load-cell system.

    Solves, at rest (``v = 0``, so friction and damping vanish), for the spool
    position at which both chambers have zero net flow (Eq. 9.9 supply inflow
    = exhaust outflow) and the pneumatic force (Eq. 9.11) equals the
    requested load-cell force.

    Parameters
    ----------
    params : dict
        ``{"pneumatics.<key>": value}``.
    force : float
        Load-cell force (compression positive) [N].
    position : float, optional
        Piston position [m]; default mid stroke.

    Returns
    -------
    dict
        ``state`` (array in ``STATE_NAMES`` order), ``command`` [V],
        ``x_nut`` [m] (nut position giving ``force`` on the load cell),
        ``p1``, ``p2`` [Pa], ``x_spool`` [-].

    Raises
    ------
    ValueError
        If the valve has no centre leakage (the working point is then not
        isolated) or the force is beyond what the supply can produce.
    """
    plant = NutFixedPlant(params)
    q = plant.q
    if q["valve_leakage_fraction"] <= 0.0:
        raise ValueError("pneumatics.valve_leakage_fraction: must be > 0 for a force-loop "
                         "working point (an ideal closed centre balances any pressure pair)")
    x = 0.5 * q["stroke"] if position is None else float(position)

    def force_error(x_spool):
        p1 = _balanced_pressure(plant, x_spool, 0)
        p2 = _balanced_pressure(plant, x_spool, 1)
        return plant.pneumatic_force(p1, p2) - force

    if force_error(-1.0) * force_error(1.0) > 0.0:
        raise ValueError(f"force {force!r} N is outside the cylinder's range at "
                         f"pneumatics.supply_pressure={q['supply_pressure']!r} Pa")
    x_spool = brentq(force_error, -1.0, 1.0, xtol=1e-14, rtol=1e-12)
    p1 = _balanced_pressure(plant, x_spool, 0)
    p2 = _balanced_pressure(plant, x_spool, 1)
    half_span = 0.5 * (q["valve_command_max"] - q["valve_command_min"])
    command = q["valve_mid_voltage"] + x_spool * half_span
    x_nut = x - plant.pneumatic_force(p1, p2) / q["load_cell_stiffness"]
    return {"state": np.array([x_spool, 0.0, p1, p2, x, 0.0]), "command": command,
            "x_nut": x_nut, "p1": p1, "p2": p2, "x_spool": x_spool}


def linearised_matrices(params, force=4000.0, position=None):
    """State-space matrices from valve command [V] to load-cell force [N], without python-control.

    Central-difference Jacobian of the nonlinear plant (``STATE_NAMES`` order)
    around :func:`operating_point`, in scaled states ``z / _STATE_SCALE`` (a
    similarity transform: the transfer function is unchanged).

    Parameters
    ----------
    params : dict
        ``{"pneumatics.<key>": value}``.
    force : float
        Working load-cell force [N].
    position : float, optional
        Piston position [m]; default mid stroke.

    Returns
    -------
    tuple
        ``(a, b, c, operating point dict)``; ``a`` is 6 x 6, ``b`` 6 x 1, ``c`` 1 x 6 (no feed-through).
    """

    plant = NutFixedPlant(params)
    op = operating_point(params, force, position)
    z0, u0, x_nut = op["state"], op["command"], op["x_nut"]
    if abs(op["x_spool"]) < 100.0 * _STATE_STEP[0]:
        raise ValueError("spool working opening too close to the centre kink for the "
                         "finite-difference step; the linearisation would straddle it")
    n = len(z0)
    a = np.zeros((n, n))
    c = np.zeros((1, n))
    for j in range(n):
        dz = np.zeros(n)
        dz[j] = _STATE_STEP[j]
        f_plus, y_plus = plant.derivatives(z0 + dz, u0, x_nut)
        f_minus, y_minus = plant.derivatives(z0 - dz, u0, x_nut)
        a[:, j] = (f_plus - f_minus) / (2.0 * dz[j])
        c[0, j] = (y_plus - y_minus) / (2.0 * dz[j])
    f_plus, _ = plant.derivatives(z0, u0 + _COMMAND_STEP, x_nut)
    f_minus, _ = plant.derivatives(z0, u0 - _COMMAND_STEP, x_nut)
    b = ((f_plus - f_minus) / (2.0 * _COMMAND_STEP)).reshape(n, 1)
    scale = _STATE_SCALE
    return (a * scale[np.newaxis, :] / scale[:, np.newaxis], b / scale[:, np.newaxis], c * scale[np.newaxis, :],
            op)


def linearised_plant(params, force=4000.0, position=None):
    """Linear model from valve command [V] to load-cell force [N] (:func:`linearised_matrices`).

    Returns
    -------
    tuple
        ``(control.StateSpace, operating point dict)``.
    """
    import control  # lazy: python-control costs start-up time; only designs/margins need it

    a, b, c, op = linearised_matrices(params, force, position)
    return control.ss(a, b, c, 0.0), op


def design_force_loop(params, sample_time=1e-3, *, crossover_hz=10.0, integral_ratio=0.2,
                      force=4000.0):
    """PI gains of the force loop and its discrete-time stability margins.

    ``C(s) = kp + ki / s`` with ``ki = integral_ratio * 2 pi f_c * kp`` (the PI
    zero a fifth of the crossover costs about 11 deg of phase there) and
    ``kp`` such that the discrete loop ``C(z) P(z)`` has unit gain at ``f_c``.
    The plant is nearly an integrator above the slow leakage pole (pressure
    builds up with the flow), so the open loop falls at -20 dB/decade through
    the crossover and the phase margin is set by the integral corner, the
    valve spool lag (Table B.12, 70 Hz) and the hold.  10 Hz is well below
    the spool bandwidth and the 500 Hz Nyquist frequency of the 1 kHz
    controller, and fast enough to hold the force while the sled moves at
    its nominal speed.

    Parameters
    ----------
    params : dict
        ``{"pneumatics.<key>": value}``.
    sample_time : float
        Controller sample time [s].  Default 1 ms: assumed loop rate of the
        NI cRIO-9047 real-time force loop (not stated in the thesis).
    crossover_hz : float
        Target gain-crossover frequency [Hz].
    integral_ratio : float
        PI zero frequency as a fraction of the crossover [-].
    force : float
        Working load-cell force [N] (4 kN step of Fig. 9.7).

    Returns
    -------
    dict
        ``kp`` [V/N], ``ki`` [V/(N s)], ``crossover_hz`` (achieved gain
        crossover), ``phase_margin_deg``, ``gain_margin_db``,
        ``phase_crossover_hz``, ``sample_time`` [s], ``closed_loop_stable``
        (bool), ``closed_loop`` (discrete ``control.StateSpace`` from force
        set-point deviation [N] to load-cell force deviation [N]) and
        ``operating_point`` (see :func:`operating_point`).
    """
    import control  # lazy: python-control costs start-up time; only designs/margins need it

    plant_c, op = linearised_plant(params, force)
    plant_d = control.c2d(plant_c, sample_time, method="zoh")
    w_c = 2.0 * math.pi * crossover_hz
    w_i = integral_ratio * w_c
    unit_pi = control.c2d(control.tf([1.0, w_i], [1.0, 0.0]), sample_time, method="euler")
    gain_at_wc = abs(complex((unit_pi * plant_d)(np.exp(1j * w_c * sample_time))))
    kp = 1.0 / gain_at_wc
    ki = kp * w_i
    controller = control.c2d(control.ss(control.tf([kp, ki], [1.0, 0.0])), sample_time,
                             method="euler")
    # Kept in state space: the slow leakage poles sit at z = 1 - 3e-5 and a
    # polynomial (transfer-function) form loses them to round-off, which is
    # why margin() is fed a dense frequency response rather than the system.
    loop = controller * plant_d
    omega = np.logspace(-3.0, math.log10(0.999 * math.pi / sample_time), 4000)
    response = control.frequency_response(loop, omega)
    phase_deg = np.degrees(np.unwrap(np.angle(response.complex.ravel())))
    gm, pm, w_pc, w_gc = control.margin(np.abs(response.complex.ravel()), phase_deg, omega)
    closed = control.feedback(loop, 1)
    stable = bool(np.all(np.abs(closed.poles()) < 1.0))
    return {
        "kp": kp,
        "ki": ki,
        "crossover_hz": float(w_gc) / (2.0 * math.pi),
        "phase_margin_deg": float(pm),
        "gain_margin_db": 20.0 * math.log10(gm) if np.isfinite(gm) else math.inf,
        "phase_crossover_hz": float(w_pc) / (2.0 * math.pi),
        "sample_time": sample_time,
        "closed_loop_stable": stable,
        "closed_loop": closed,
        "operating_point": op,
    }
