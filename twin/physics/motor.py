"""Motor-reducer: equivalent single-phase circuit, winding thermal model (Eqs. 9.1, 9.2)."""

import numba

from numerics.jit import SCALAR

STEFAN_BOLTZMANN = 5.670374419e-8  # W/(m^2 K^4), CODATA 2018
T_RESISTANCE_REFERENCE = 293.15  # K, the 20 degC of the datasheet resistance (Table B.1)


@numba.njit(**SCALAR)
def winding_resistance(temperature, r_20c, temperature_coefficient):
    """Winding resistance ``R_m(T_w)`` of Eq. 9.1, linear through the Table B.1 points [Ohm]."""
    return r_20c * (1.0 + temperature_coefficient * (temperature - T_RESISTANCE_REFERENCE))


@numba.njit(**SCALAR)
def current_derivative(voltage, current, output_speed, resistance, inductance, speed_constant, ratio):
    """Eq. 9.1: ``H_m di/dt = alpha_DC V_s - k_e tau_mr theta_r' - R_m(T_w) i``.

    Parameters
    ----------
    voltage : float
        Applied voltage ``alpha_DC V_s`` [V].
    current : float
        Motor current ``i`` [A].
    output_speed : float
        Reducer output speed ``theta_r'`` [rad/s].
    resistance, inductance : float
        ``R_m(T_w)`` [Ohm], ``H_m`` [H].
    speed_constant : float
        ``k_e`` [V s/rad].
    ratio : float
        Reduction ratio ``tau_mr``.
    """
    return (voltage - speed_constant * ratio * output_speed - resistance * current) / inductance


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
