"""Motor-reducer: power-consistent single-phase equivalent circuit, winding thermal model (Eqs. 9.1, 9.2).

Sec. 9.3.1 models the three-phase brushless motor "with an equivalent mono-phase circuit" (Eq. 9.1) whose
constants are Table B.1's: the terminal (line-to-line) resistance ``R_UV`` and inductance ``L_UV``, the torque
constant ``k_t`` per ampere rms of line current and the speed constant ``k_e`` (line-to-line rms EMF). Taken as
printed they do not conserve energy: the circuit absorbs ``k_e w i``, 54 % of the mechanical power ``k_t w i``
that Eq. 9.3 receives, and ``R_UV i^2`` is two thirds of the copper loss. The circuit here is the one whose power
balance is the machine's (non-salient PMSM, field-oriented with ``i_d = 0``, amplitude-invariant dq transform:
Krause, Wasynczuk, Sudhoff & Pekarek, *Analysis of Electric Machinery and Drive Systems*, 3rd ed., Wiley 2013,
Secs. 3.6 and 15.3), in the current ``i`` [A rms of line current] that ``k_t`` refers to, ``i_q = sqrt(2) i``:

* electrical power ``(3/2) v_q i_q`` = ``v i`` defines the equivalent voltage ``v = (3/2) sqrt(2) v_q``;
* copper loss ``(3/2) R_s i_q^2 = 3 R_s i^2 = (3/2) R_UV i^2`` (star: ``R_UV = 2 R_s``; a delta winding gives the
  same 3/2): ``R_eq = 1.5 R_UV``;
* magnetic energy ``(3/2) L_s i_q^2 / 2 = (1/2) (1.5 L_UV) i^2`` (``L_UV = 2 L_s``): ``L_eq = 1.5 L_UV``;
* back-EMF power ``(3/2) w_e psi_pm i_q = k_t w_m i`` by the definition of ``k_t``: the back-EMF constant is
  ``k_t``, so the circuit absorbs exactly the power the mechanics receive.

Hence ``L_eq di/dt = v - R_eq(T_w) i - k_t w_m`` and ``v i = R_eq i^2 + d/dt(L_eq i^2 / 2) + k_t w_m i``
(tests/engine/test_motor_energy_balance.py). The electrical time constant ``L/R`` is the datasheet's; the current
loop designed on the equivalent circuit has 1.5 times the gains and the same closed loop (twin.control.design).
"""

import math

import numba

from numerics.jit import SCALAR

STEFAN_BOLTZMANN = 5.670374419e-8  # W/(m^2 K^4), CODATA 2018
T_RESISTANCE_REFERENCE = 293.15  # K, the 20 degC of the datasheet resistance (Table B.1)
#: Terminal (line-to-line) resistance and inductance of a balanced three-phase winding -> the single-phase equivalent
#: in the rms line current: the copper loss and the magnetic energy of the three phases (module docstring).
THREE_PHASE_EQUIVALENCE = 1.5


def equivalent_resistance(terminal_resistance: float) -> float:
    """``R_eq = 1.5 R_UV`` [Ohm]: the resistance whose ``R_eq i^2`` is the three phases' copper loss."""
    return THREE_PHASE_EQUIVALENCE * terminal_resistance


def equivalent_inductance(terminal_inductance: float) -> float:
    """``L_eq = 1.5 L_UV`` [H]: the inductance whose ``L_eq i^2 / 2`` is the three phases' magnetic energy."""
    return THREE_PHASE_EQUIVALENCE * terminal_inductance


def equivalent_voltage_limit(dc_bus_voltage: float, phase_amplitude_limit: float) -> float:
    """Largest equivalent-circuit voltage ``(3/2) sqrt(2) v_q,max`` [V] the inverter applies.

    ``phase_amplitude_limit`` is the largest phase-voltage amplitude as a fraction of ``V_DC`` in the modulation's
    linear range (1/sqrt(3) for space-vector PWM: ``sqrt(3/2) V_DC``, 692 V at 565 V). The d-axis voltage the
    q-current needs at speed, ``w_e L_s i_q``, shares the same amplitude; at the tests' currents (a few A) it takes
    about 1 % of it and is neglected: the limit is the q-axis maximum (docs/model.md, "Motor circuit").
    """
    return 1.5 * math.sqrt(2.0) * phase_amplitude_limit * dc_bus_voltage


@numba.njit(**SCALAR)
def winding_resistance(temperature, r_20c, temperature_coefficient):
    """Resistance at the winding temperature, linear through the two Table B.1 points (``R_m(T_w)`` of Eq. 9.1)
    [Ohm]; ``r_20c`` is the equivalent circuit's value at 20 degC."""
    return r_20c * (1.0 + temperature_coefficient * (temperature - T_RESISTANCE_REFERENCE))


@numba.njit(**SCALAR)
def current_derivative(voltage, current, output_speed, resistance, inductance, back_emf_constant, ratio):
    """Eq. 9.1, power-consistent (module docstring): ``L_eq di/dt = v - k_t tau_mr theta_r' - R_eq(T_w) i``.

    Parameters
    ----------
    voltage : float
        Applied equivalent voltage ``v`` [V].
    current : float
        Motor current ``i`` [A rms of line current].
    output_speed : float
        Reducer output speed ``theta_r'`` [rad/s].
    resistance, inductance : float
        ``R_eq(T_w)`` [Ohm], ``L_eq`` [H].
    back_emf_constant : float
        The torque constant ``k_t`` [V s/rad = N m/A].
    ratio : float
        Reduction ratio ``tau_mr``.
    """
    return (voltage - back_emf_constant * ratio * output_speed - resistance * current) / inductance


@numba.njit(**SCALAR)
def winding_temperature_derivative(temperature, ambient, joule_power, thermal_resistance, time_constant,
                                   heat_transfer_coefficient, area, emissivity):
    """Eq. 9.2: ``tau_w dT_w/dt = R_th [R i^2 - h A (T_w - T_rif) - eps sigma A (T_w^4 - T_rif^4)]``.

    The radiative term carries the area ``A_m`` for dimensional consistency
    (the printed Eq. 9.2 omits it). Temperatures in K, power in W.
    """
    convection = heat_transfer_coefficient * area * (temperature - ambient)
    radiation = emissivity * STEFAN_BOLTZMANN * area * (temperature**4 - ambient**4)
    return thermal_resistance * (joule_power - convection - radiation) / time_constant
