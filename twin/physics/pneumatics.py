"""Pneumatic load system: proportional flow valve, cylinder chambers, piston, load cell.

Lumped-parameter model of Bertolino (2020), Sec. 9.3.1 "Pneumatic load system",
Eqs. 9.9-9.11, with the component data of Appendix B: Table B.11 (Angst+Pfister
end-stroke damper), Table B.12 (FESTO MPYE-3/8 proportional flow valve) and
Table B.13 (HBM K-U9C-20K load cell).  The cylinder is a FESTO DSBG, bore 160 mm
(Table 9.2).

All functions except :func:`validate_pneumatics` are ``numba.njit`` scalar
functions meant for the compiled simulation loop: float arguments, SI units,
pressures absolute [Pa], temperatures [K].

Conventions
-----------
* Piston position ``x`` [m] is measured from the cap-end head: ``x = 0`` fully
  retracted, ``x = stroke`` fully extended.  Chamber 1 is the cap (full-bore)
  side, chamber 2 the rod (annulus) side.  Positive force and velocity extend
  the rod.
* Spool position is normalised, dimensionless, in ``[-1, 1]``: ``0`` is the
  closed centre (command at mid voltage), ``+1`` fully opens
  supply -> chamber 1 and chamber 2 -> exhaust (rod extends), ``-1`` the
  opposite pair.  This is a wiring assumption: the MPYE working port that is
  pressurised above 5 V is plumbed to the cap side.
* ``load_cell_spring_force`` is positive in compression, i.e. the force the rod
  exerts on the master nut along ``+x``.

State added to the bench
------------------------
Continuous: spool position [-] and velocity [1/s] (:func:`spool_derivative`),
chamber pressures ``p1``, ``p2`` [Pa] (:func:`chamber_pressure_derivative`),
piston position [m] and velocity [m/s] (:func:`piston_acceleration`).
Discrete, updated at the force-controller sample: the effective valve command
after the hysteresis play [V] (:func:`hysteresis_play`) and the force-PI
integral.

Step size for explicit integrators: the fastest modes are the load cell on the
piston mass (``sqrt(k/m)`` = 1.2e4 rad/s with the defaults), the friction
regularisation (``F_s / (v_th m)`` = 1.1e4 1/s) and the laminar band of a fully
open port into the smallest chamber (about 2.6e3 1/s); RK4 needs
``dt <= 1e-4 s``.
"""

import math

import numba

from numerics.jit import SCALAR
from twin.errors import ParameterError
from twin.physics.bristle_friction import dissipation_bound_holds
from twin.physics.friction import stribeck_friction

__all__ = [
    "mass_flow",
    "conductance_from_nominal_flow",
    "hysteresis_play",
    "spool_derivative",
    "port_conductances",
    "chamber_mass_flows",
    "piston_areas",
    "chamber_volumes",
    "chamber_pressure_derivative",
    "piston_force",
    "end_stroke_damper_force",
    "piston_acceleration",
    "load_cell_spring_force",
    "validate_pneumatics",
    "REQUIRED_KEYS",
]


# --------------------------------------------------------------------------- #
# Eq. 9.9 / ISO 6358: mass flow through a valve port
# --------------------------------------------------------------------------- #
@numba.njit(**SCALAR)
def _subsonic_factor(ratio, b_crit):
    """ISO 6358 subsonic flow factor ``sqrt(1 - ((r - b) / (1 - b))**2)``, for ``b <= r <= 1``."""
    z = (ratio - b_crit) / (1.0 - b_crit)
    return math.sqrt(max(1.0 - z * z, 0.0))


@numba.njit(**SCALAR)
def _forward_flow(p_up, p_down, conductance, b_crit, rho0, t_ref, t_up, laminar_ratio):
    """ISO 6358 mass flow for ``p_up >= p_down`` (see :func:`mass_flow`); the three regimes are each computed and
    one is selected (branch-free)."""
    choked = conductance * rho0 * p_up * math.sqrt(t_ref / t_up)
    # a select between scalars (both sides computed under numba's numpy error model); no division by an empty
    # chamber's zero where the functions run as plain Python (NUMBA_DISABLE_JIT, benchmarks/mutation_score.py)
    ratio = p_down / p_up if p_up > 0.0 else 1.0
    subsonic = choked * _subsonic_factor(ratio, b_crit)
    # Laminar band: linear in (p_up - p_down), matching value at laminar_ratio.
    laminar = choked * _subsonic_factor(laminar_ratio, b_crit) * (1.0 - ratio) / (1.0 - laminar_ratio)
    flow = laminar if ratio > laminar_ratio else subsonic
    flow = choked if ratio <= b_crit else flow
    return flow if p_up > 0.0 else 0.0


@numba.njit(**SCALAR)
def mass_flow(p_up, p_down, conductance, b_crit, rho0, t_ref, t_up, t_down, laminar_ratio):
    """Mass flow rate through a pneumatic restriction, Eq. 9.9 in ISO 6358 form.

    With ``r = p_down / p_up`` and ``p_up >= p_down``:

    * choked (sonic), ``r <= b``:
      ``G = C rho0 p_up sqrt(T0 / T_up)``
    * subsonic, ``b < r <= r_lam``:
      ``G = C rho0 p_up sqrt(T0 / T_up) sqrt(1 - ((r - b) / (1 - b))**2)``
    * laminar band, ``r_lam < r <= 1``:
      ``G = G(r_lam) (1 - r) / (1 - r_lam)``

    For ``p_down > p_up`` the flow reverses (Eq. 9.9 branches 3 and 4):
    ``G(p_up, p_down, T_up, T_down) = -G(p_down, p_up, T_down, T_up)``, i.e. the
    roles of the ports and of their temperatures are swapped.

    Parameters
    ----------
    p_up, p_down : float
        Absolute pressures at the nominal upstream and downstream ports [Pa].
    conductance : float
        Sonic conductance ``C`` of the restriction [m^3/(s Pa)] (ANR volume).
    b_crit : float
        Critical pressure ratio ``b`` [-], ``0 <= b < 1``.
    rho0 : float
        Air density at the ISO 8778 reference atmosphere [kg/m^3].
    t_ref : float
        Reference temperature ``T0`` of ``rho0`` and ``C`` [K].
    t_up, t_down : float
        Stagnation temperatures at the upstream / downstream ports [K]; the
        one on the side the air actually comes from enters ``sqrt(T0/T)``.
    laminar_ratio : float
        Pressure ratio ``r_lam`` (``b < r_lam < 1``) above which the flow is
        linearised (e.g. 0.999).

    Returns
    -------
    float
        Mass flow rate from ``p_up`` port to ``p_down`` port [kg/s]; negative
        when the air flows the other way.

    Notes
    -----
    * Eq. 9.9 as printed in the thesis gives the subsonic branch as
      ``sqrt(1 - Pd/Pu - b**2)``: this is an OCR/typesetting corruption of the
      ISO 6358 law ``sqrt(1 - ((Pd/Pu - b) / (1 - b))**2)`` used here (ISO
      6358:1989, Eq. 1; ISO 6358-1:2013 with subsonic index m = 0.5).  The
      printed reverse-flow branches keep ``P_u`` as prefactor; physically the
      prefactor is the pressure of the port the air comes from (``P_d`` when
      ``P_d > P_u``), which the antisymmetric form implements.  The thesis
      text also calls ``rho0`` a pressure: it is the reference density.
    * ISO 6358 scales the flow by ``sqrt(T0 / T_up)``; Eq. 9.9 omits it
      (``T_up = T0``).  It is kept so that the Table 9.5 room-temperature
      range acts on the valve.
    * ``dG/dp_down`` of the subsonic law is infinite at ``r = 1``, which makes
      the chamber equations arbitrarily stiff near equal pressures.  Inside
      the band ``r > r_lam`` the flow is replaced by the secant from
      ``(r_lam, G(r_lam))`` to ``(1, 0)``, i.e. a laminar law
      ``G = C rho0 sqrt(T0/T_up) phi(r_lam) (p_up - p_down) / (1 - r_lam)``
      that is linear in the pressure difference.  The result is continuous
      at ``r = b``, at ``r = r_lam`` and at ``r = 1`` (where it is zero from
      both sides), is exactly antisymmetric under port reversal, and has a
      finite slope ``C rho0 sqrt(T0/T_up) phi(r_lam) / (1 - r_lam)``
      (about 53 C rho0 for b = 0.3, r_lam = 0.999).  The band only covers
      pressure differences below ``(1 - r_lam) p_up`` (0.1 %, about 700 Pa at
      the 7 bar supply), where both laws are below ``G(r_lam)`` (5.3 % of the
      choked flow for the defaults).
    """
    forward = p_up >= p_down  # the port reversal by selects (branch-free)
    flow = _forward_flow(p_up if forward else p_down, p_down if forward else p_up, conductance, b_crit, rho0, t_ref,
                         t_up if forward else t_down, laminar_ratio)
    return flow if forward else -flow


@numba.njit(**SCALAR)
def conductance_from_nominal_flow(nominal_flow, p_up, p_down, b_crit, laminar_ratio):
    """Sonic conductance that reproduces a catalogue nominal flow rate.

    FESTO's "standard nominal flow rate" ``q_nN`` (Table B.12: 2000 l/min) is
    the flow, in ANR litres (ISO 8778 reference atmosphere), of one fully
    open flow path at 6 bar gauge upstream and 5 bar gauge downstream
    (1 bar drop).  Inverting the ISO 6358 law of :func:`mass_flow` at the
    reference temperature, ``q_nN = G / rho0``, gives
    ``C = q_nN / (p_up phi(p_down / p_up))``.

    Parameters
    ----------
    nominal_flow : float
        Standard nominal flow rate [m^3/s ANR].
    p_up, p_down : float
        Absolute test pressures of the nominal-flow convention [Pa].
    b_crit : float
        Critical pressure ratio [-].
    laminar_ratio : float
        Laminar-band pressure ratio of :func:`mass_flow` [-].

    Returns
    -------
    float
        Sonic conductance ``C`` [m^3/(s Pa)].
    """
    # Unit density/temperature: G/rho0 is independent of both at T_up = T0.
    return nominal_flow / mass_flow(p_up, p_down, 1.0, b_crit, 1.0, 1.0, 1.0, 1.0, laminar_ratio)


# --------------------------------------------------------------------------- #
# Valve: command hysteresis, spool dynamics, port conductances
# --------------------------------------------------------------------------- #
@numba.njit(**SCALAR)
def hysteresis_play(command_voltage, held_command, hysteresis, command_min, command_max):
    """Play (backlash) operator modelling the valve hysteresis on the command.

    The spool follows an effective command that only moves once the applied
    command leaves a band of total width ``h (u_max - u_min)`` centred on it;
    Table B.12 gives the maximum hysteresis ``h = 0.4 %`` of the full
    command span (0.04 V over 0-10 V).  A play band is the standard
    rate-independent hysteresis model for a proportional valve with internal
    spool position control, where the residual hysteresis comes from
    friction and magnetic effects ahead of the spool loop.

    The valve command is the zero-order-held D/A output of the force
    controller, so the play output changes only when the command changes:
    evaluating this operator once per controller update is exact, and its
    output is a discrete state of the bench (not an ODE state).

    Parameters
    ----------
    command_voltage : float
        Command just written to the valve [V].
    held_command : float
        Effective command after the previous update [V] (initialise to the
        valve mid voltage).
    hysteresis : float
        Total hysteresis width as a fraction of the command span [-].
    command_min, command_max : float
        Command range [V] (0 and 10 V for the MPYE).

    Returns
    -------
    float
        New effective command [V].
    """
    half_band = 0.5 * hysteresis * (command_max - command_min)
    if command_voltage > held_command + half_band:
        return command_voltage - half_band
    if command_voltage < held_command - half_band:
        return command_voltage + half_band
    return held_command


@numba.njit(**SCALAR)
def spool_derivative(x_spool, v_spool, command_voltage, mid_voltage, command_min, command_max,
                     critical_frequency, damping_ratio):
    """Second-order command-to-spool dynamics of the MPYE proportional valve.

    ``x'' = wn**2 (s_cmd - x) - 2 zeta wn x'`` with
    ``s_cmd = clip((clip(u, u_min, u_max) - u_mid) / ((u_max - u_min) / 2), -1, 1)``
    and ``wn = 2 pi f_c``.

    Table B.12 gives the critical frequency ``f_c = 70 Hz`` and the
    mid-position voltage 5 V (command 0-10 V).  The MPYE closes a spool
    position loop in its own electronics around a solenoid-driven spool
    (mass + return spring + current lag), whose closed-loop response is
    dominated by a complex pole pair; a second-order model reproduces both
    the -40 dB/decade roll-off and the phase lag near 70 Hz that set the
    force-loop gain margin, which a first-order lag would understate
    (about 90 deg vs 45 deg at f_c).  With ``zeta = 1/sqrt(2)`` the -3 dB
    frequency equals ``wn``, so ``f_c`` is read as the -3 dB bandwidth of the
    spool response.

    Parameters
    ----------
    x_spool : float
        Normalised spool position [-].
    v_spool : float
        Normalised spool velocity [1/s].
    command_voltage : float
        Effective valve command [V] (after :func:`hysteresis_play`).
    mid_voltage : float
        Command giving the closed centre [V].
    command_min, command_max : float
        Command range [V]; commands outside are saturated.
    critical_frequency : float
        Spool response -3 dB frequency [Hz].
    damping_ratio : float
        Damping ratio of the spool pole pair [-].

    Returns
    -------
    tuple of float
        ``(dx_spool/dt [1/s], dv_spool/dt [1/s^2])``.
    """
    u = min(max(command_voltage, command_min), command_max)
    target = (u - mid_voltage) / (0.5 * (command_max - command_min))
    target = min(max(target, -1.0), 1.0)
    wn = 2.0 * math.pi * critical_frequency
    return v_spool, wn * wn * (target - x_spool) - 2.0 * damping_ratio * wn * v_spool


@numba.njit(**SCALAR)
def port_conductances(x_spool, max_conductance, leakage_fraction):
    """Sonic conductances of the four flow paths of a 5/3 closed-centre valve.

    Critically lapped spool: the open area of a metering edge grows linearly
    with the spool stroke from its closing point, so for ``s = clip(x, -1, 1)``

    * supply -> chamber 1 and chamber 2 -> exhaust:
      ``C_leak + (C_max - C_leak) max(s, 0)``
    * supply -> chamber 2 and chamber 1 -> exhaust:
      ``C_leak + (C_max - C_leak) max(-s, 0)``

    ``C_max`` is the conductance of one fully open path, calibrated on the
    standard nominal flow rate (:func:`conductance_from_nominal_flow`).
    ``C_leak = leakage_fraction * C_max`` is the radial-clearance leakage of
    every metering edge.  It is kept non-zero on purpose: with a perfectly
    closed centre the chamber pressures are neutrally stable (any pair of
    pressures is an equilibrium at ``s = 0``), while the real MPYE at mid
    position bleeds each chamber to both supply and exhaust and the chambers
    settle at an intermediate pressure.  Set it to zero to model an ideal
    closed centre (then the valve is exactly closed at ``s = 0``).

    Parameters
    ----------
    x_spool : float
        Normalised spool position [-]; values beyond +-1 (spool overshoot)
        are clipped because the metering edges are fully open there.
    max_conductance : float
        Conductance of a fully open flow path [m^3/(s Pa)].
    leakage_fraction : float
        Centre leakage conductance as a fraction of ``max_conductance`` [-].

    Returns
    -------
    tuple of float
        ``(C_supply_1, C_1_exhaust, C_supply_2, C_2_exhaust)`` [m^3/(s Pa)].
    """
    s = min(max(x_spool, -1.0), 1.0)
    leak = leakage_fraction * max_conductance
    span = max_conductance - leak
    positive = leak + span * max(s, 0.0)
    negative = leak + span * max(-s, 0.0)
    return positive, negative, negative, positive


@numba.njit(**SCALAR)
def chamber_mass_flows(x_spool, p1, p2, p_supply, p_exhaust, max_conductance, leakage_fraction,
                       b_crit, rho0, t_ref, t_supply, t_chamber, laminar_ratio):
    """Net mass flow into each cylinder chamber through the valve, Eq. 9.9.

    ``G_i = G(p_supply -> p_i, C_supply_i) - G(p_i -> p_exhaust, C_i_exhaust)``
    with :func:`mass_flow` for each path and :func:`port_conductances` for the
    spool-dependent conductances.

    Parameters
    ----------
    x_spool : float
        Normalised spool position [-].
    p1, p2 : float
        Chamber absolute pressures [Pa].
    p_supply, p_exhaust : float
        Supply and exhaust absolute pressures [Pa].
    max_conductance, leakage_fraction : float
        See :func:`port_conductances`.
    b_crit, rho0, t_ref, laminar_ratio : float
        See :func:`mass_flow`.
    t_supply, t_chamber : float
        Supply-air and chamber-air temperatures [K] (exhaust air is at the
        chamber temperature when it flows back in).

    Returns
    -------
    tuple of float
        ``(G1, G2)`` net mass flow into chamber 1 and chamber 2 [kg/s].
    """
    c_s1, c_1e, c_s2, c_2e = port_conductances(x_spool, max_conductance, leakage_fraction)
    g1 = (mass_flow(p_supply, p1, c_s1, b_crit, rho0, t_ref, t_supply, t_chamber, laminar_ratio)
          - mass_flow(p1, p_exhaust, c_1e, b_crit, rho0, t_ref, t_chamber, t_chamber, laminar_ratio))
    g2 = (mass_flow(p_supply, p2, c_s2, b_crit, rho0, t_ref, t_supply, t_chamber, laminar_ratio)
          - mass_flow(p2, p_exhaust, c_2e, b_crit, rho0, t_ref, t_chamber, t_chamber, laminar_ratio))
    return g1, g2


# --------------------------------------------------------------------------- #
# Eq. 9.10: chamber continuity
# --------------------------------------------------------------------------- #
@numba.njit(**SCALAR)
def piston_areas(bore_diameter, rod_diameter):
    """Active piston areas of a single-rod cylinder (Eq. 9.11 ``A1``, ``A2``).

    Parameters
    ----------
    bore_diameter, rod_diameter : float
        Cylinder bore and piston-rod diameters [m].

    Returns
    -------
    tuple of float
        ``(A1, A2)``: cap-side full-bore area and rod-side annulus area [m^2].
    """
    a1 = 0.25 * math.pi * bore_diameter * bore_diameter
    return a1, a1 - 0.25 * math.pi * rod_diameter * rod_diameter


@numba.njit(**SCALAR)
def chamber_volumes(x, v, area1, area2, dead_volume1, dead_volume2, stroke):
    """Chamber volumes and their rates, geometry of Eq. 9.10.

    ``V1 = V_d1 + A1 x``, ``V2 = V_d2 + A2 (stroke - x)``.  The dead volumes
    (end-cap clearance, ports and valve-to-cylinder tubing) are the thesis'
    dead-volume coordinates times the area, ``V_di = A_i x_di``.  The printed
    Eq. 9.10 writes ``A2 (x_d2 + x)`` for chamber 2; its sign of ``dx/dt``
    (``+P2 n`` term) is only consistent with ``V2`` shrinking as ``x`` grows,
    i.e. with the ``stroke - x`` used here.

    Parameters
    ----------
    x, v : float
        Piston position [m] and velocity [m/s].
    area1, area2 : float
        Cap-side and rod-side areas [m^2].
    dead_volume1, dead_volume2 : float
        Dead volumes of chambers 1 and 2 [m^3].
    stroke : float
        Cylinder stroke [m].

    Returns
    -------
    tuple of float
        ``(V1 [m^3], dV1/dt [m^3/s], V2 [m^3], dV2/dt [m^3/s])``.
    """
    return (dead_volume1 + area1 * x, area1 * v,
            dead_volume2 + area2 * (stroke - x), -area2 * v)


@numba.njit(**SCALAR)
def chamber_pressure_derivative(p, mass_flow_in, volume, volume_rate, temperature, gas_constant,
                                polytropic_exponent):
    """Chamber pressure rate from mass continuity, Eq. 9.10.

    ``dP/dt = n R T G / V - n P (dV/dt) / V``

    Derivation.  For a polytropic change of the chamber gas,
    ``P / rho**n`` is constant along the process, with ``rho = m / V``; hence
    ``P = K (m / V)**n`` and ``dP/dt = n P (dm/dt / m - dV/dt / V)``.
    Substituting ``dm/dt = G`` and the ideal-gas mass ``m = P V / (R T)``
    gives the expression above.  ``T`` is taken as the chamber temperature
    parameter (the thesis' ``T_i``): the model tracks no energy equation.

    With the valve closed (``G = 0``) the equation integrates to
    ``P V**n = const``; the gas mass ``P V / (R T_gas)`` is then conserved when
    ``T_gas = T_i (P / P_i)**((n - 1) / n)`` is the polytropic temperature
    (exactly, with ``T_gas = T_i``, for ``n = 1``).  The printed Eq. 9.10
    divides the flow term by ``P/P_i`` instead of using
    ``(P/P_i)**((n-1)/n)``; with ``n`` between 1 and 1.4 that factor mixes an
    isothermal and a polytropic temperature law, and it is not reproduced.
    The thesis calls ``R`` the universal gas constant; it must be the specific
    gas constant of air (287 J/(kg K)) for ``G`` in kg/s.

    Parameters
    ----------
    p : float
        Chamber absolute pressure [Pa].
    mass_flow_in : float
        Net mass flow into the chamber [kg/s].
    volume, volume_rate : float
        Chamber volume [m^3] and its time derivative [m^3/s].
    temperature : float
        Chamber gas temperature [K].
    gas_constant : float
        Specific gas constant of air [J/(kg K)].
    polytropic_exponent : float
        Polytropic exponent ``n`` [-] (1 isothermal, 1.4 adiabatic).

    Returns
    -------
    float
        ``dP/dt`` [Pa/s].
    """
    return polytropic_exponent * (gas_constant * temperature * mass_flow_in - p * volume_rate) / volume


# --------------------------------------------------------------------------- #
# Eq. 9.11: piston equilibrium
# --------------------------------------------------------------------------- #
@numba.njit(**SCALAR)
def piston_force(p1, p2, a1, a2, p_atm):
    """Net pneumatic force on the piston-rod assembly, Eq. 9.11.

    ``F = P1 A1 - P2 A2 - P_atm (A1 - A2)``.  Eq. 9.11 reads ``P1 A1 - P2 A2``,
    which holds for gauge pressures; with absolute pressures the rod
    cross-section ``A1 - A2`` outside the cylinder is loaded by the
    atmosphere, hence the last term.

    Parameters
    ----------
    p1, p2 : float
        Chamber absolute pressures [Pa].
    a1, a2 : float
        Cap-side and rod-side areas [m^2].
    p_atm : float
        Ambient absolute pressure [Pa].

    Returns
    -------
    float
        Force along ``+x`` (rod extension) [N].
    """
    return p1 * a1 - p2 * a2 - p_atm * (a1 - a2)


@numba.njit(**SCALAR)
def end_stroke_damper_force(x, v, stroke, travel, stiffness, damping, end_stop_stiffness):
    """End-stroke damper force on the piston (Table B.11), at both stroke ends.

    A damper is in contact only within its travel ``s_z`` from either head:
    compression ``delta = s_z - x`` at the cap end, ``delta = x - (stroke - s_z)``
    at the rod end, zero elsewhere.  While in contact the elastomer pushes
    back with ``k delta + c d(delta)/dt`` (never pulling, so the total is
    clipped at zero).  Beyond full deflection (``delta > s_z``, i.e. past a
    head) the solid damper and the head add a stiff end stop
    ``k_stop (delta - s_z)``; it keeps the chamber volumes positive if the
    piston is driven into a head (the pneumatic force, up to 12 kN at 6 bar,
    exceeds the damper's 4 kN rating at full deflection).

    Table B.11: ``k = 250 kN/m``, ``s_z = 16 mm`` (``k s_z = 4 kN``, matching the
    rated compression force).  The rated absorbed energy, 20 J, is below the
    elastic energy ``k s_z**2 / 2 = 32 J``: the catalogue stiffness is a
    secant value of a progressive elastomer, represented here linearly.

    Parameters
    ----------
    x, v : float
        Piston position [m] and velocity [m/s].
    stroke : float
        Cylinder stroke [m].
    travel : float
        Damper deflection ``s_z`` [m].
    stiffness : float
        Damper stiffness [N/m].
    damping : float
        Damper viscous coefficient while in contact [N s/m].
    end_stop_stiffness : float
        Stiffness of the head beyond full damper deflection [N/m].

    Returns
    -------
    float
        Force on the piston along ``+x`` [N]: positive at the cap end,
        negative at the rod end.
    """
    cap_delta = travel - x
    cap = max(stiffness * cap_delta - damping * v + end_stop_stiffness * max(cap_delta - travel, 0.0), 0.0)
    rod_delta = x - (stroke - travel)
    rod = -max(stiffness * rod_delta + damping * v + end_stop_stiffness * max(rod_delta - travel, 0.0), 0.0)
    return cap if x < travel else (rod if x > stroke - travel else 0.0)


@numba.njit(**SCALAR)
def piston_acceleration(p1, p2, x, v, load_cell_force, a1, a2, p_atm, mass, damping,
                        f_static, f_dynamic, stribeck_coefficient, viscous_coefficient,
                        velocity_threshold, stroke, damper_travel, damper_stiffness,
                        damper_damping, end_stop_stiffness):
    """Piston-rod-load-cell acceleration, Eq. 9.11.

    ``m_p x'' = F_p - F_fr,cyl - c_p x' + F_damper - F_lc``

    with ``F_p`` from :func:`piston_force`, ``F_fr,cyl`` the seal friction
    in Eq. 7.63 form (Eq. 9.11 cites Eq. 7.64, the torque version of the same
    law), ``[F_d + (F_s - F_d) exp(-a|v|)] tanh(v/v_th) + b v``, computed by
    ``twin.physics.friction.stribeck_friction`` (``sign(v)`` regularised as
    ``tanh(v/v_th)``: a piston at rest feels a viscous-like slope
    ``F_s/v_th``, and the static level is reached only for ``|v| >> v_th``),
    ``F_damper`` from
    :func:`end_stroke_damper_force` and ``F_lc`` the load-cell force
    (:func:`load_cell_spring_force`, positive when the rod pushes the nut,
    hence a reaction ``-F_lc`` on the rod).  The thesis keeps a separate
    damping ``c_p`` besides the viscous friction ``b``; both act as
    ``(b + c_p) v`` and are kept apart so each can be varied.

    Parameters
    ----------
    p1, p2 : float
        Chamber absolute pressures [Pa].
    x, v : float
        Piston position [m] and velocity [m/s].
    load_cell_force : float
        Load-cell force, positive in compression [N].
    a1, a2 : float
        Cap-side and rod-side areas [m^2].
    p_atm : float
        Ambient absolute pressure [Pa].
    mass : float
        Translating mass: piston, rod, rod end and load cell [kg].
    damping : float
        Damping coefficient ``c_p`` [N s/m].
    f_static, f_dynamic : float
        Static (breakaway) and dynamic Coulomb seal friction [N].
    stribeck_coefficient : float
        Stribeck decay coefficient ``a`` [s/m].
    viscous_coefficient : float
        Viscous seal friction ``b`` [N s/m].
    velocity_threshold : float
        Regularisation velocity ``v_th`` of ``sign(v)`` [m/s].
    stroke, damper_travel, damper_stiffness, damper_damping, end_stop_stiffness : float
        End-stroke dampers, see :func:`end_stroke_damper_force`.

    Returns
    -------
    float
        Piston acceleration [m/s^2].
    """
    return piston_acceleration_under_friction(
        p1, p2, x, v, load_cell_force, a1, a2, p_atm, mass, damping,
        stribeck_friction(v, f_static, f_dynamic, stribeck_coefficient, viscous_coefficient, velocity_threshold),
        stroke, damper_travel, damper_stiffness, damper_damping, end_stop_stiffness)


@numba.njit(**SCALAR)
def piston_acceleration_under_friction(p1, p2, x, v, load_cell_force, a1, a2, p_atm, mass, damping, friction,
                                       stroke, damper_travel, damper_stiffness, damper_damping,
                                       end_stop_stiffness):
    """Eq. 9.11 with the seal friction ``F_fr,cyl`` given [N] (opposing positive ``v``): the one home of the piston's
    balance, shared by the regularised law (:func:`piston_acceleration`) and the bristle law of
    :mod:`twin.physics.bristle_friction` (the elasto-plastic seal level). Other arguments as in
    :func:`piston_acceleration`."""
    force = (piston_force(p1, p2, a1, a2, p_atm)
             - friction
             - damping * v
             + end_stroke_damper_force(x, v, stroke, damper_travel, damper_stiffness,
                                       damper_damping, end_stop_stiffness)
             - load_cell_force)
    return force / mass


@numba.njit(**SCALAR)
def load_cell_spring_force(x_rod, x_nut, v_rod, v_nut, k, c):
    """External-force load cell between rod end and master nut (spring-damper).

    ``F_lc = k (x_rod - x_nut) + c (v_rod - v_nut)``.  Sec. 9.3.1 models all
    force sensors as spring-damper elements; the stiffness follows from
    Table B.13, ``k = 20 kN / 0.018 mm = 1.11e9 N/m``.

    Parameters
    ----------
    x_rod, x_nut : float
        Rod-end and master-nut positions on a common axis, with zero
        difference when the load cell is unloaded [m].
    v_rod, v_nut : float
        Rod-end and master-nut velocities [m/s].
    k : float
        Load-cell stiffness [N/m].
    c : float
        Load-cell damping [N s/m].

    Returns
    -------
    float
        Force, positive in compression: pushes the nut along ``+x`` and the
        rod along ``-x`` [N].  Eq. 9.8 uses ``F_ext = -F_lc`` on the master nut
        with its resisting-force sign.
    """
    return k * (x_rod - x_nut) + c * (v_rod - v_nut)


# --------------------------------------------------------------------------- #
# Parameter validation (plain Python)
# --------------------------------------------------------------------------- #
_POSITIVE = (
    "supply_pressure", "atmospheric_pressure", "nominal_flow_upstream_pressure",
    "nominal_flow_downstream_pressure", "air_temperature", "gas_constant", "reference_density",
    "reference_temperature", "nominal_flow_rate", "valve_critical_frequency",
    "valve_damping_ratio", "bore_diameter", "stroke", "dead_volume_1", "dead_volume_2",
    "piston_mass", "friction_velocity_threshold", "damper_stiffness", "damper_travel",
    "end_stop_stiffness", "load_cell_stiffness", "friction_presliding_stiffness", "friction_bristle_damping_speed",
)
_NON_NEGATIVE = (
    "valve_leakage_fraction", "valve_hysteresis", "rod_diameter", "friction_static",
    "friction_dynamic", "friction_stribeck_coefficient", "friction_viscous", "piston_damping",
    "damper_damping", "load_cell_damping", "friction_bristle_damping",
)
_OTHER = (
    "polytropic_exponent", "critical_pressure_ratio", "laminar_ratio", "valve_mid_voltage",
    "valve_command_min", "valve_command_max", "friction_elastic_fraction",
)
REQUIRED_KEYS = _POSITIVE + _NON_NEGATIVE + _OTHER


def validate_pneumatics(params):
    """Check a pneumatic parameter set for physically impossible values.

    Every problem is collected before raising, so one call reports them all.

    Parameters
    ----------
    params : dict
        ``{"pneumatics.<key>": value}`` (SI, absolute pressures).

    Returns
    -------
    list of str
        Empty list when the set is valid.

    Raises
    ------
    ValueError
        If any check fails; the message lists every problem, one per line,
        each naming the field ``pneumatics.<key>``.
    """
    problems = []
    values = {}
    for key in REQUIRED_KEYS:
        name = "pneumatics." + key
        if name not in params:
            problems.append(f"{name}: missing")
            continue
        value = float(params[name])
        if not math.isfinite(value):
            problems.append(f"{name}: must be finite, got {value!r}")
            continue
        values[key] = value
    for key in _POSITIVE:
        if key in values and values[key] <= 0.0:
            problems.append(f"pneumatics.{key}: must be > 0, got {values[key]!r}")
    for key in _NON_NEGATIVE:
        if key in values and values[key] < 0.0:
            problems.append(f"pneumatics.{key}: must be >= 0, got {values[key]!r}")

    def check(keys, ok, message):
        if all(k in values for k in keys) and not ok(*(values[k] for k in keys)):
            shown = ", ".join(f"pneumatics.{k}={values[k]!r}" for k in keys)
            problems.append(f"pneumatics.{keys[0]}: {message} ({shown})")

    check(("supply_pressure", "atmospheric_pressure"), lambda ps, pa: ps > pa,
          "supply must exceed the exhaust (atmospheric) pressure")
    check(("nominal_flow_upstream_pressure", "nominal_flow_downstream_pressure"),
          lambda pu, pd: pu > pd, "nominal-flow upstream pressure must exceed downstream")
    check(("rod_diameter", "bore_diameter"), lambda d, bore: d < bore,
          "rod must be thinner than the bore (rod-side area would be <= 0)")
    check(("polytropic_exponent",), lambda n: 1.0 <= n <= 1.4,
          "polytropic exponent must lie in [1, 1.4]")
    check(("critical_pressure_ratio",), lambda b: 0.0 <= b < 1.0,
          "critical pressure ratio must lie in [0, 1)")
    check(("laminar_ratio", "critical_pressure_ratio"), lambda r, b: b < r < 1.0,
          "laminar ratio must lie between the critical ratio and 1")
    check(("valve_leakage_fraction",), lambda f: f < 1.0, "leakage fraction must be < 1")
    check(("valve_hysteresis",), lambda h: h < 1.0, "hysteresis must be < 1 (fraction of span)")
    check(("valve_mid_voltage", "valve_command_min", "valve_command_max"),
          lambda mid, lo, hi: lo < mid < hi, "mid voltage must lie inside the command range")
    check(("friction_dynamic", "friction_static"), lambda fd, fs: fd <= fs,
          "dynamic friction must not exceed static friction")
    check(("friction_elastic_fraction",), lambda f: 0.0 <= f < 1.0,
          "the elastic share of the bristle deflection must lie in [0, 1)")
    check(("friction_bristle_damping", "friction_bristle_damping_speed", "friction_dynamic"),
          dissipation_bound_holds, "bristle damping too large for the law to dissipate at every speed: "
          "sigma_1 v_d / sqrt(2 e) must not exceed 4 F_d (twin.physics.bristle_friction)")
    check(("damper_travel", "stroke"), lambda s, stroke: 2.0 * s < stroke,
          "the two damper travels must fit in the stroke")
    if problems:
        raise ParameterError(problems)
    return problems
