"""Gain design of the three cascaded motion loops with python-control.

The gains used by the simulation live in ``twin/parameters/bench/controller.toml``;
this module is the documented procedure that produced them, and
``tests/control/test_design.py`` checks that the file still matches the design
and that the margins hold at nominal parameters. Run ``python -m twin.control.design``
to print the design table (reproduced in ``docs/control_design.md``).

Design rules (classic cascade tuning, each loop ~5-10x slower than the inner one):

* **Current loop** (analog PI, Sec. 9.3): plant ``1/(H_m s + R_m)`` of Eq. 9.1
  in its power-consistent equivalent circuit (``H_m = 1.5 L_UV``, ``R_m = 1.5 R_UV``,
  :mod:`twin.physics.motor`) with back-EMF treated as a disturbance, Hall sensor ``1/(tau_h s + 1)``.
  The PI zero cancels the electrical pole (``T_i = H_m/R_m``) and the gain sets
  the crossover ``f_c``: ``K_p = 2 pi f_c H_m``.
* **Speed loop** (digital PI in the drive, resolver feedback): two-mass torsional
  plant (motor-reducer | couplings+torque meter | screw+nuts) of Eqs. 9.3 and 9.7
  with the closed current loop, discretised with ZOH (``control.c2d``) plus one
  sample of computation delay. Crossover placed well below the torsional mode.
* **Position loop** (digital PI in the controller, linear-encoder feedback):
  the closed speed loop followed by the screw kinematics ``p/(2 pi tau_mr)``
  and an integrator, discretised likewise.

The PI zero of each digital loop sits a factor ``ZERO_RATIO`` below crossover so
the integral action costs ~ ``atan(1/ZERO_RATIO)`` of phase.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import asdict, dataclass

import numpy as np

from twin.components import reducer
from twin.parameters import load_parameters
from twin.physics.drivetrain import screw_inertia, torsional_stiffness
from twin.physics.motor import equivalent_inductance, equivalent_resistance

ZERO_RATIO = 5.0
CURRENT_CROSSOVER_HZ = 1000.0
SPEED_CROSSOVER_HZ = 60.0
POSITION_CROSSOVER_HZ = 6.0


@dataclass(frozen=True)
class LoopDesign:
    """Gains and nominal loop figures of one control loop."""

    name: str
    kp: float
    ki: float
    sample_time: float
    crossover_hz: float
    bandwidth_hz: float
    gain_margin_db: float
    phase_margin_deg: float


def _reflected_inertias(p: dict[str, float]) -> tuple[float, float]:
    """Motor-side and screw-side inertias about the reducer output (Eqs. 9.3, 9.7) [kg m^2]."""
    j_motor_side = reducer.reflected_inertia(p)
    screw_j = screw_inertia(p)
    lead_arm = p["ball_screw.lead"] / (2.0 * math.pi)
    sled = (p["sled.master_mass"] + p["sled.slave_mass"]) * lead_arm**2
    j_screw_side = screw_j + p["drivetrain.torque_meter_inertia"] + 2.0 * p["drivetrain.coupling_inertia"] + sled
    return j_motor_side, j_screw_side


def winding_admittance(p: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """Winding current per voltage ``1/(L_eq s + R_eq)`` of Eq. 9.1 (the power-consistent equivalent circuit,
    :mod:`twin.physics.motor`, at 20 degC), back-EMF as a disturbance: ``(num, den)`` in s."""
    return np.array([1.0]), np.array([equivalent_inductance(p["motor.inductance"]),
                                      equivalent_resistance(p["motor.winding_resistance_20C"])])


def hall_sensor(p: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """First-order Hall current sensor ``1/(tau_h s + 1)`` (Sec. 9.3, ``drive.hall_time_constant``): ``(num, den)``."""
    return np.array([1.0]), np.array([p["drive.hall_time_constant"], 1.0])


def current_closed_loop(p: dict[str, float], kp: float, ki: float) -> tuple[np.ndarray, np.ndarray]:
    """Closed analog current loop ``i/i_ref = C P / (1 + C P H)``, ``C = kp + ki/s`` (Sec. 9.3): ``(num, den)``.

    ``P`` is :func:`winding_admittance`, ``H`` :func:`hall_sensor`; polynomials in s, highest power first.
    """
    p_num, p_den = winding_admittance(p)
    h_num, h_den = hall_sensor(p)
    c_num, c_den = np.array([kp, ki]), np.array([1.0, 0.0])
    forward_num, forward_den = polymul(c_num, p_num), polymul(c_den, p_den)
    num = polymul(forward_num, h_den)
    den = np.polyadd(polymul(forward_den, h_den), polymul(forward_num, h_num))
    return num, den


def polymul(a, b) -> np.ndarray:
    """Product of two polynomials (highest power first), each coefficient summed in index order: the same bits on
    every machine (``np.polymul`` convolves through BLAS dot products, whose order depends on the CPU's kernel)."""
    out = [0.0] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        for j, y in enumerate(b):
            out[i + j] += float(x) * float(y)
    return np.array(out)


def two_mass_speed_plant(p: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """Motor torque -> motor speed of the two-mass torsional chain (Eqs. 9.3, 9.7): ``(num, den)`` in s.

    Output-side speed per output-side torque of two inertias ``j1``, ``j2`` joined by the series
    stiffness ``k`` and damping ``c``, referred to the motor shaft by ``ratio^2`` and the reducer efficiency.
    """
    ratio = p["reducer.ratio"]
    j1, j2 = _reflected_inertias(p)
    k = torsional_stiffness(p)
    c = p["drivetrain.damping"]
    gain = ratio**2 * p["reducer.efficiency"]
    num = gain * np.array([j2, c, k])
    den = np.array([j1 * j2, c * (j1 + j2), k * (j1 + j2), 0.0])
    return num, den


def screw_kinematics_gain(p: dict[str, float]) -> float:
    """Sled travel per motor angle ``p / (2 pi tau_mr)`` [m/rad] (rigid screw and reducer)."""
    return p["ball_screw.lead"] / (2 * math.pi * p["reducer.ratio"])


def _figures(name, kp, ki, ts, open_loop, closed_loop) -> LoopDesign:
    import control  # lazy: python-control costs start-up time; only designs/margins need it

    with warnings.catch_warnings():
        # python-control warns when it falls back from the ill-conditioned
        # polynomial method to its frequency-response method: that fallback is wanted.
        warnings.filterwarnings("ignore", message="stability_margins: Falling back", category=UserWarning)
        gm, pm, _, wc = control.margin(open_loop)
    omega = np.logspace(-1, 6, 4000)
    if ts:
        omega = omega[omega < math.pi / ts]
    mag = np.abs(closed_loop(1j * omega if not ts else np.exp(1j * omega * ts)))
    below = np.nonzero(mag < mag[0] / math.sqrt(2.0))[0]
    bandwidth = omega[below[0]] / (2 * math.pi) if below.size else float("nan")
    return LoopDesign(
        name=name,
        kp=float(kp),
        ki=float(ki),
        sample_time=float(ts),
        crossover_hz=float(wc / (2 * math.pi)),
        bandwidth_hz=float(bandwidth),
        gain_margin_db=float(20 * math.log10(gm)) if np.isfinite(gm) else float("inf"),
        phase_margin_deg=float(pm),
    )


def design_current_loop(p: dict[str, float]):
    """Analog PI of the current loop; returns the design and its closed loop i/i_ref (``control.TransferFunction``)."""
    import control  # lazy: python-control costs start-up time; only designs/margins need it

    inductance = equivalent_inductance(p["motor.inductance"])
    resistance = equivalent_resistance(p["motor.winding_resistance_20C"])
    kp = 2 * math.pi * CURRENT_CROSSOVER_HZ * inductance
    ki = kp * resistance / inductance
    pi = control.tf([kp, ki], [1.0, 0.0])
    open_loop = pi * control.tf(*winding_admittance(p)) * control.tf(*hall_sensor(p))
    closed = control.tf(*current_closed_loop(p, kp, ki))
    return _figures("current", kp, ki, 0.0, open_loop, closed), closed


def design_speed_loop(p: dict[str, float], current_closed):
    """Digital PI of the drive speed loop on resolver feedback."""
    import control  # lazy: python-control costs start-up time; only designs/margins need it

    ts = p["drive.speed_loop_sample_time"]
    j1, j2 = _reflected_inertias(p)
    j_motor = (j1 + j2) / p["reducer.ratio"] ** 2
    wc = 2 * math.pi * SPEED_CROSSOVER_HZ
    kp = wc * j_motor / p["motor.torque_constant"]
    ki = kp * wc / ZERO_RATIO
    plant_c = current_closed * p["motor.torque_constant"] * control.tf(*two_mass_speed_plant(p))
    plant_d = control.c2d(control.minreal(plant_c, verbose=False), ts, method="zoh")
    z = control.tf([1, 0], [1], ts)
    pi = kp + ki * ts * z / (z - 1)
    delay = 1 / z
    open_loop = pi * plant_d * delay
    closed = control.feedback(pi * plant_d, delay)
    # Continuous equivalent for the slower position-loop design: PI plus the
    # sample-and-hold and computation delay (1.5 samples) as a Pade approximant.
    s = control.tf("s")
    pade = control.tf(*control.pade(1.5 * ts, 2))
    closed_equivalent = control.feedback((kp + ki / s) * plant_c * pade, 1)
    return _figures("speed", kp, ki, ts, open_loop, closed), closed_equivalent


def design_position_loop(p: dict[str, float], speed_closed) -> LoopDesign:
    """Digital PI of the controller position loop on the linear encoder.

    ``speed_closed`` is the continuous equivalent of the closed speed loop.
    """
    import control  # lazy: python-control costs start-up time; only designs/margins need it

    ts = p["controller.position_loop_sample_time"]
    gain = screw_kinematics_gain(p)
    wc = 2 * math.pi * POSITION_CROSSOVER_HZ
    kp = wc / gain
    ki = kp * wc / ZERO_RATIO
    speed_slow = control.c2d(control.minreal(speed_closed, verbose=False), ts, method="zoh")
    z = control.tf([1, 0], [1], ts)
    integrator = gain * ts / (z - 1)
    pi = kp + ki * ts * z / (z - 1)
    delay = 1 / z
    open_loop = pi * speed_slow * integrator * delay
    closed = control.feedback(pi * speed_slow * integrator, delay)
    return _figures("position", kp, ki, ts, open_loop, closed)


def design_loops(p: dict[str, float]) -> dict[str, LoopDesign]:
    """Design all three loops at the given (nominal) parameter values.

    Parameters
    ----------
    p : dict
        ``{parameter name: value}`` in SI units, e.g. ``load_parameters().values()``.

    Returns
    -------
    dict
        ``{"current": LoopDesign, "speed": ..., "position": ...}``.
    """
    current, current_closed = design_current_loop(p)
    speed, speed_closed = design_speed_loop(p, current_closed)
    position = design_position_loop(p, speed_closed)
    return {"current": current, "speed": speed, "position": position}


def main() -> None:
    designs = design_loops(load_parameters("bench").values())
    print(f"{'loop':10s} {'Kp':>12s} {'Ki':>12s} {'Ts [s]':>10s} {'fc [Hz]':>9s} {'BW [Hz]':>9s} {'GM [dB]':>8s} "
          f"{'PM [deg]':>8s}")
    for d in designs.values():
        row = asdict(d)
        print(f"{row['name']:10s} {row['kp']:12.6g} {row['ki']:12.6g} {row['sample_time']:10.3g} "
              f"{row['crossover_hz']:9.2f} "
              f"{row['bandwidth_hz']:9.2f} {row['gain_margin_db']:8.2f} {row['phase_margin_deg']:8.2f}")


if __name__ == "__main__":
    main()
