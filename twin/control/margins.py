"""Stability margins of the bench's control loops for one parameter set, as the twin runs them.

The loop gains are fixed (``controller.*``, designed once at nominal by :mod:`twin.control.design` and
:mod:`twin.control.force_loop_design`); a Monte Carlo sample changes the plant under them. For each loop
this module builds the linearised loop transfer function ``L`` at the given parameters -- the plant
models are those of the designs (:func:`twin.control.design.current_closed_loop`,
:func:`~twin.control.design.two_mass_speed_plant`, :func:`~twin.control.force_loop_design.linearised_matrices`),
the sampling and delays those of the compiled loop (:mod:`twin.engine.loop`) -- and returns the gain
margin, the phase margin, the gain-crossover frequency and the peak sensitivity ``|S|max = max |1/(1+L)|``
(the inverse of the modulus margin; Skogestad & Postlethwaite, *Multivariable Feedback Control*, 2005,
Sec. 2.4.3).

Loops, each broken at the controller output:

``current`` (analog, continuous)
    ``L(s) = (kp + ki/s) / (H_m s + R_m) / (tau_h s + 1)``: the drive's analog PI on the Hall sensor
    (Eq. 9.1, back-EMF a disturbance as in the design), winding resistance at 20 degC.
``speed`` (drive, ``Ts = drive.speed_loop_sample_time``)
    Current demand held by a zero-order hold over ``Ts``; closed analog current loop, torque constant and
    two-mass torsional chain (Eqs. 9.3, 9.7) to the motor angle, discretised exactly (ZOH). The twin's
    drive measures the speed as the backward difference of the resolver angle, ``(1 - z^-1)/Ts``, and
    applies the PI output in the sample it is computed (no computation delay): ``pi_step`` is
    ``C(z) = kp + ki Ts / (z - 1)`` (forward-Euler integral). ``L(z) = C(z) (1 - z^-1)/Ts G_theta(z)``.
``position`` (cRIO, ``T = controller.position_loop_sample_time``, an integer multiple of ``Ts``)
    The speed command is held over ``T`` (= ``T/Ts`` drive samples) and read by the drive in the same
    tick; the closed speed loop above, lifted exactly to ``T`` (``A^N``, ``sum A^i B``), then the screw
    kinematics ``p/(2 pi tau_mr)`` to the linear-encoder position, sampled at ``T``; PI as above.
``force`` (cRIO, ``T``; only with the cylinder attached)
    Valve command held over ``T``; the valve-chambers-piston-load-cell plant linearised at the working
    force (:func:`twin.control.force_loop_design.linearised_matrices`), discretised with ZOH; the load
    cell's conditioner refreshes its output at ``sensors.load_cell_measuring_rate`` (a sample-and-hold
    asynchronous to ``T``), taken as its mean delay of half a refresh period, ``exp(-j w T_r/2)``.

The design (:mod:`twin.control.design`) assumed one sample of computation delay and a backward-Euler
integral in the digital motion loops; the twin has neither, so the margins here differ from the design
figures by the phase of that delay (``docs/control_design.md`` lists both).

Method: each ``L`` is evaluated on a fixed logarithmic frequency grid (up to the Nyquist frequency for the
digital loops, which is always included: ``L(-1)`` is real); gain crossings and phase crossings are located
between grid points by interpolation in ``log w``;
``tests/control/test_margins.py`` cross-checks it against python-control's ``stability_margins`` on the same
loops (:func:`loop_systems`).

The margins are stored per run (``results.nc``), so they must be the same bits on every machine: the matrix
algebra goes through :mod:`numerics.linalg` (fixed operation order) instead of BLAS/LAPACK, and the complex
arithmetic is compiled scalar code (numba without fastmath: no fused multiply-adds) with the C library's elementary
functions, instead of numpy's CPU-dispatched array kernels (tests/campaigns/test_same_numbers_everywhere.py runs
them under other kernels).
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass

import numba
import numpy as np

from numerics.linalg import expm, matmul, state_space_response
from twin.control.design import (
    current_closed_loop,
    hall_sensor,
    screw_kinematics_gain,
    two_mass_speed_plant,
    winding_admittance,
)
from twin.control.force_loop_design import linearised_matrices

__all__ = ["LOOPS", "METRICS", "LoopMargins", "frequency_grid", "loop_margins", "loop_responses", "loop_systems",
           "margins_from_response"]

#: Loops in cascade order (the force loop exists only with the cylinder attached).
LOOPS = ("current", "speed", "position", "force")
#: Figure of merit -> (CF unit, long name).
METRICS = {
    "gain_margin": ("dB", "gain margin"),
    "phase_margin": ("degree", "phase margin"),
    "crossover_frequency": ("Hz", "gain-crossover frequency"),
    "peak_sensitivity": ("1", "peak sensitivity |S|max (inverse modulus margin)"),
}
#: Points of the frequency grid per decade: |S|max between two points is under-read by < 0.1 % for
#: the loops' resonance widths (checked against python-control in the tests).
POINTS_PER_DECADE = 100
#: Lowest frequency of the grid [Hz], far below every crossover (the force loop's ~10 Hz is the lowest
#: besides the position loop's 6 Hz).
LOWEST_HZ = 0.05
#: Highest frequency of the continuous current loop's grid [Hz]: a decade above the Hall sensor pole.
CURRENT_LOOP_HIGHEST_HZ = 5.0e4


@dataclass(frozen=True)
class LoopMargins:
    """Margins of one loop. ``gain_margin`` is ``inf`` when the phase never reaches -180 deg."""

    loop: str
    sample_time: float          # [s], 0 for the analog current loop
    gain_margin: float          # [dB]
    phase_margin: float         # [deg]
    crossover_frequency: float  # [Hz]
    peak_sensitivity: float     # [-]

    def as_dict(self) -> dict:
        return asdict(self)


@functools.lru_cache(maxsize=16)
def frequency_grid(sample_time: float) -> np.ndarray:
    """Angular frequencies [rad/s] from :data:`LOWEST_HZ` to the Nyquist frequency (included), or to
    :data:`CURRENT_LOOP_HIGHEST_HZ` for a continuous loop (``sample_time == 0``): geometrically spaced, both ends
    exact, each point from its index by the C library's ``exp`` (no CPU-dispatched array kernel). Kept per sample
    time (every run of a campaign shares it), so the array is read-only."""
    top = 0.5 / sample_time if sample_time > 0 else CURRENT_LOOP_HIGHEST_HZ
    n = int(math.ceil(POINTS_PER_DECADE * math.log10(top / LOWEST_HZ))) + 1
    span = math.log(top / LOWEST_HZ)
    hz = [LOWEST_HZ * math.exp(span * i / (n - 1)) for i in range(n)]
    hz[0], hz[-1] = LOWEST_HZ, top
    grid = np.array([2.0 * math.pi * f for f in hz])
    grid.flags.writeable = False
    return grid


# ---------------------------------------------------------------- state-space helpers (fixed operation order)

def _ss(num, den):
    """Controllable canonical form ``(A, B, C, D)`` of a proper transfer function (polynomials in s, highest
    power first): the realisation of ``scipy.signal.tf2ss``, built element by element."""
    num = np.atleast_1d(np.asarray(num, dtype=float))
    den = np.atleast_1d(np.asarray(den, dtype=float))
    n = den.size - 1
    lead = den[0]
    den = den / lead
    num = np.concatenate([np.zeros(den.size - num.size), num / lead])
    a = np.zeros((n, n))
    a[0, :] = -den[1:]
    for i in range(1, n):
        a[i, i - 1] = 1.0
    b = np.zeros((n, 1))
    if n:
        b[0, 0] = 1.0
    d = num[0]
    c = (num[1:] - d * den[1:]).reshape(1, n)
    return a, b, c, np.array([[d]])


def _series(first, second):
    """State space of ``second(first(u))`` (both SISO)."""
    a1, b1, c1, d1 = first
    a2, b2, c2, d2 = second
    n1, n2 = a1.shape[0], a2.shape[0]
    a = np.zeros((n1 + n2, n1 + n2))
    a[:n1, :n1] = a1
    a[n1:, :n1] = matmul(b2, c1)
    a[n1:, n1:] = a2
    b = np.concatenate([b1, matmul(b2, d1)])
    c = np.concatenate([matmul(d2, c1), c2], axis=1)
    return a, b, c, matmul(d2, d1)


def _zoh(a, b, sample_time):
    """Exact zero-order-hold discretisation ``(A_d, B_d)`` (matrix exponential of the augmented matrix)."""
    n, m = b.shape
    block = np.zeros((n + m, n + m))
    block[:n, :n] = a * sample_time
    block[:n, n:] = b * sample_time
    e = expm(block)
    return e[:n, :n], e[:n, n:]


def _response(a, b, c, d, points):
    """``C (pI - A)^-1 B + D`` at complex ``points`` (s or z) for a SISO system."""
    return state_space_response(np.ascontiguousarray(a, dtype=float), np.ascontiguousarray(b, dtype=float),
                                np.ascontiguousarray(c, dtype=float), np.ascontiguousarray(d, dtype=float),
                                np.asarray(points, dtype=np.complex128))


# Complex arithmetic on the frequency grid: compiled loops over scalars (numba without fastmath keeps every
# multiply and add apart, as Python does; numpy's complex array kernels may fuse them on some CPUs), the elementary
# functions from the C library.

@numba.njit(cache=True)
def _polyval(coefficients, x):
    """A polynomial (highest power first) at the complex ``x`` by Horner's rule."""
    value = 0j
    for coefficient in coefficients:
        value = value * x + coefficient
    return value


@numba.njit(cache=True)
def _continuous_pi_response(kp, ki, numerators, denominators, omega):
    """``(kp + ki/s) prod_k num_k(s)/den_k(s)`` at ``s = j w`` (the blocks' polynomials as rows, highest power
    first, zero-padded in front)."""
    out = np.empty(omega.shape[0], dtype=np.complex128)
    for q in range(omega.shape[0]):
        s = complex(0.0, omega[q])
        value = kp + ki / s
        for k in range(numerators.shape[0]):
            value *= _polyval(numerators[k], s) / _polyval(denominators[k], s)
        out[q] = value
    return out


@numba.njit(cache=True)
def _unit_circle(omega, sample_time):
    """``exp(j w T)`` at each frequency, from the C library's cosine and sine."""
    out = np.empty(omega.shape[0], dtype=np.complex128)
    for q in range(omega.shape[0]):
        out[q] = complex(math.cos(omega[q] * sample_time), math.sin(omega[q] * sample_time))
    return out


@numba.njit(cache=True)
def _pi(kp, ki, sample_time, z):
    """``pi_step`` as a transfer function: ``kp + ki T / (z - 1)`` (forward-Euler integral), at each point."""
    out = np.empty(z.shape[0], dtype=np.complex128)
    for q in range(z.shape[0]):
        out[q] = kp + ki * sample_time / (z[q] - 1.0)
    return out


@numba.njit(cache=True)
def _backward_difference(z, sample_time):
    """The drive's speed estimate ``(1 - z^-1)/T`` at each point."""
    out = np.empty(z.shape[0], dtype=np.complex128)
    for q in range(z.shape[0]):
        out[q] = (1.0 - 1.0 / z[q]) / sample_time
    return out


@numba.njit(cache=True)
def _product(first, second):
    """Elementwise product of two complex arrays."""
    out = np.empty(first.shape[0], dtype=np.complex128)
    for q in range(first.shape[0]):
        out[q] = first[q] * second[q]
    return out


def _padded(polynomials) -> np.ndarray:
    """Polynomials (highest power first) as the rows of one array, zero-padded in front."""
    width = max(len(p) for p in polynomials)
    rows = np.zeros((len(polynomials), width))
    for k, polynomial in enumerate(polynomials):
        rows[k, width - len(polynomial):] = polynomial
    return rows


# ---------------------------------------------------------------- the loops

def _current_closed(p):
    return _ss(*current_closed_loop(p, p["controller.current_kp"], p["controller.current_ki"]))


def _motor_angle_plant(p):
    """Current demand -> motor angle, continuous: closed current loop, k_t, two-mass chain, integrator."""
    torque = _series(_current_closed(p), (np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)),
                                          np.array([[p["motor.torque_constant"]]])))
    speed = _series(torque, _ss(*two_mass_speed_plant(p)))
    return _series(speed, (np.zeros((1, 1)), np.ones((1, 1)), np.ones((1, 1)), np.zeros((1, 1))))


def _speed_loop_discrete(p):
    """The drive's side of the speed loop at ``Ts``: ``(A_d, B_d, C)`` current demand -> motor angle."""
    a, b, c, _ = _motor_angle_plant(p)
    ad, bd = _zoh(a, b, p["drive.speed_loop_sample_time"])
    return ad, bd, c


def _closed_speed_loop(p, speed_plant):
    """Closed speed loop at ``Ts``: speed command -> motor angle, states ``[plant, previous angle, integral]``.

    Per drive sample (``twin.engine.loop.speed_sample``): ``w_meas = (theta - theta_prev)/Ts``,
    ``e = r - w_meas``, ``u = kp e + I``; then ``I += ki Ts e``, ``theta_prev = theta``, the plant steps with ``u``.
    """
    ts = p["drive.speed_loop_sample_time"]
    kp, ki = p["controller.speed_kp"], p["controller.speed_ki"]
    ad, bd, c = speed_plant
    n = ad.shape[0]
    a = np.zeros((n + 2, n + 2))
    a[:n, :n] = ad - (kp / ts) * matmul(bd, c)
    a[:n, n:n + 1] = (kp / ts) * bd
    a[:n, n + 1:] = bd
    a[n, :n] = c[0]
    a[n + 1, :n] = -ki * c[0]
    a[n + 1, n] = ki
    a[n + 1, n + 1] = 1.0
    b = np.zeros((n + 2, 1))
    b[:n] = kp * bd
    b[n + 1, 0] = ki * ts
    out = np.zeros((1, n + 2))
    out[0, :n] = c[0]
    return a, b, out


def _position_plant(p, speed_plant):
    """Speed command held over ``T`` -> linear-encoder position at ``T``: the closed speed loop lifted to ``T``."""
    ts, t = p["drive.speed_loop_sample_time"], p["controller.position_loop_sample_time"]
    steps = round(t / ts)
    if steps < 1 or abs(steps * ts - t) > 1e-9 * t:
        raise ValueError(f"controller.position_loop_sample_time ({t!r} s) must be an integer multiple of "
                         f"drive.speed_loop_sample_time ({ts!r} s), as in the compiled loop")
    a, b, c = _closed_speed_loop(p, speed_plant)
    lifted_b = np.zeros_like(b)
    power = np.eye(a.shape[0])
    for _ in range(steps):
        lifted_b += matmul(power, b)
        power = matmul(power, a)
    return power, lifted_b, screw_kinematics_gain(p) * c


def _force_plant(p, load_system, force):
    a, b, c, _ = linearised_matrices(load_system, force)
    ad, bd = _zoh(a, b, p["controller.position_loop_sample_time"])
    return ad, bd, c


def loop_responses(p: dict[str, float], load_system: dict[str, float] | None = None, force: float = 0.0, *,
                   loops=LOOPS, load_cell_refresh: bool = True) -> dict[str, tuple[float, np.ndarray, np.ndarray]]:
    """Loop transfer functions ``L`` on :func:`frequency_grid`, as the twin runs the loops.

    Parameters
    ----------
    p : dict
        ``{parameter: value}`` (SI), e.g. ``ParameterSet.values()`` of the run.
    load_system : dict, optional
        The parameters with the scene's supply pressure and air temperature
        (:func:`twin.engine.model.load_system_parameters`); ``None``: no cylinder, no force loop.
    force : float
        Load-cell force the force loop holds (its working point) [N].
    loops : sequence of str
        The loops wanted (of :data:`LOOPS`; the speed loop is computed for the position loop anyway).
    load_cell_refresh : bool
        Include the load-cell conditioner's mean refresh delay in the force loop (False: the loop of
        :func:`loop_systems`, for cross-checks).

    Returns
    -------
    dict
        ``{loop: (sample_time [s], omega [rad/s], L(omega))}`` for the loops present.
    """
    out = {}
    if "current" in loops:
        w = frequency_grid(0.0)
        blocks = (winding_admittance(p), hall_sensor(p))
        out["current"] = (0.0, w, _continuous_pi_response(
            p["controller.current_kp"], p["controller.current_ki"], _padded([num for num, _ in blocks]),
            _padded([den for _, den in blocks]), w))

    t = p["controller.position_loop_sample_time"]
    if "speed" in loops or "position" in loops:
        ts = p["drive.speed_loop_sample_time"]
        speed_plant = _speed_loop_discrete(p)
    if "speed" in loops:
        w = frequency_grid(ts)
        z = _unit_circle(w, ts)
        angle = _response(*speed_plant, np.zeros((1, 1)), z)
        out["speed"] = (ts, w, _product(_product(_pi(p["controller.speed_kp"], p["controller.speed_ki"], ts, z),
                                                 _backward_difference(z, ts)), angle))
    w = frequency_grid(t)
    z = _unit_circle(w, t)
    if "position" in loops:
        a, b, c = _position_plant(p, speed_plant)
        position = _response(a, b, c, np.zeros((1, 1)), z)
        out["position"] = (t, w, _product(_pi(p["controller.position_kp"], p["controller.position_ki"], t, z),
                                          position))

    if load_system is not None and "force" in loops:
        ad, bd, c = _force_plant(p, load_system, force)
        refresh_delay = 0.5 / p["sensors.load_cell_measuring_rate"] if load_cell_refresh else 0.0
        delay = _unit_circle(w, -refresh_delay)
        out["force"] = (t, w, _product(_product(_pi(p["controller.force_kp"], p["controller.force_ki"], t, z),
                                                _response(ad, bd, c, np.zeros((1, 1)), z)), delay))
    return out


@numba.njit(cache=True)
def _interpolate(x0, x1, y0, y1, target):
    """``x`` at which the line through ``(x0, y0)``, ``(x1, y1)`` reaches ``target``."""
    return x0 + (x1 - x0) * (target - y0) / (y1 - y0)


@numba.njit(cache=True)
def _phase_degrees(value):
    return math.degrees(math.atan2(value.imag, value.real))


@numba.njit(cache=True)
def _margins(sample_time, omega, values):
    """``(gain margin [dB], phase margin [deg], crossover [Hz], |S|max)`` of :func:`margins_from_response`."""
    n = omega.shape[0]
    log_w = np.empty(n)
    log_mag = np.empty(n)
    for i in range(n):
        log_w[i] = math.log(omega[i])
        log_mag[i] = math.log(abs(values[i]))
    crossover, phase_margin = math.nan, math.nan
    for i in range(n - 1):
        if (log_mag[i] >= 0.0) == (log_mag[i + 1] >= 0.0):
            continue
        lw = _interpolate(log_w[i], log_w[i + 1], log_mag[i], log_mag[i + 1], 0.0)
        fraction = (lw - log_w[i]) / (log_w[i + 1] - log_w[i])
        # the phase of values[i] (values[i + 1] / values[i]) ** fraction: rotate by fraction of the step's angle
        ratio = values[i + 1] / values[i]
        turn = fraction * math.atan2(ratio.imag, ratio.real)
        phase = _phase_degrees(values[i] * complex(math.cos(turn), math.sin(turn)))
        margin = (phase + 180.0) % 360.0
        margin = margin - 360.0 if margin > 180.0 else margin
        if math.isnan(phase_margin) or margin < phase_margin:
            crossover, phase_margin = math.exp(lw) / (2 * math.pi), margin
    gain_margin = math.inf
    for i in range(n - 1):
        if (values[i].imag > 0.0) == (values[i + 1].imag > 0.0):
            continue
        lw = _interpolate(log_w[i], log_w[i + 1], values[i].imag, values[i + 1].imag, 0.0)
        fraction = (lw - log_w[i]) / (log_w[i + 1] - log_w[i])
        value = values[i] + (values[i + 1] - values[i]) * fraction
        if value.real < 0.0:
            gain_margin = min(gain_margin, -20.0 * math.log10(abs(value.real)))
    if sample_time > 0 and values[n - 1].real < 0.0 and abs(omega[n - 1] * sample_time - math.pi) < 1e-9:
        gain_margin = min(gain_margin, -20.0 * math.log10(abs(values[n - 1].real)))  # Nyquist: L(-1) is real
    peak = 0.0
    for i in range(n):
        peak = max(peak, 1.0 / abs(1.0 + values[i]))
    return gain_margin, phase_margin, crossover, peak


def margins_from_response(loop: str, sample_time: float, omega: np.ndarray, response: np.ndarray) -> LoopMargins:
    """Gain margin, phase margin, crossover and ``|S|max`` of a loop from its frequency response.

    Gain crossings (``|L|`` through 1) and phase crossings (``Im L`` through 0 with ``Re L < 0``) are
    interpolated in ``log w`` between grid points; the reported phase margin and crossover are those of
    the crossing with the smallest phase margin, the gain margin the smallest ``1/|L|`` over the phase
    crossings (``inf`` without one). A loop that never crosses unit gain has ``nan`` phase margin and
    crossover. Compiled scalar arithmetic and the C library's functions (module docstring: the same bits on
    every machine).
    """
    gain_margin, phase_margin, crossover, peak = _margins(
        float(sample_time), np.ascontiguousarray(omega, dtype=float), np.ascontiguousarray(response, dtype=complex))
    return LoopMargins(loop, float(sample_time), float(gain_margin), float(phase_margin), float(crossover),
                       float(peak))


def loop_margins(p: dict[str, float], load_system: dict[str, float] | None = None, force: float = 0.0, *,
                 loops=LOOPS) -> dict[str, LoopMargins]:
    """Margins of every loop present (see :func:`loop_responses` for the arguments)."""
    responses = loop_responses(p, load_system, force, loops=loops)
    return {loop: margins_from_response(loop, ts, w, response) for loop, (ts, w, response) in responses.items()}


def loop_systems(p: dict[str, float], load_system: dict[str, float] | None = None, force: float = 0.0) -> dict:
    """The same loops as python-control systems (``{loop: L}``), for cross-checks and step responses.

    Also returns the closed loops from reference to measured output under the key ``"<loop>_closed"``
    (unity feedback of the measured output, as the twin's PI controllers see it).
    """
    import control  # lazy: python-control costs start-up time; only designs/margins need it

    out = {}
    out["current"] = (control.tf([p["controller.current_kp"], p["controller.current_ki"]], [1.0, 0.0])
                      * control.tf(*winding_admittance(p)) * control.tf(*hall_sensor(p)))
    ts = p["drive.speed_loop_sample_time"]
    speed_plant = _speed_loop_discrete(p)
    z = control.tf([1.0, 0.0], [1.0], ts)
    angle = control.ss(*speed_plant, 0.0, ts)
    speed_pi = p["controller.speed_kp"] + p["controller.speed_ki"] * ts / (z - 1)
    out["speed"] = speed_pi * (1 - 1 / z) / ts * angle
    t = p["controller.position_loop_sample_time"]
    a, b, c = _position_plant(p, speed_plant)
    z = control.tf([1.0, 0.0], [1.0], t)
    position_pi = p["controller.position_kp"] + p["controller.position_ki"] * t / (z - 1)
    out["position"] = position_pi * control.ss(a, b, c, 0.0, t)
    if load_system is not None:
        ad, bd, c = _force_plant(p, load_system, force)
        out["force"] = ((p["controller.force_kp"] + p["controller.force_ki"] * t / (z - 1))
                        * control.ss(ad, bd, c, 0.0, t))
    for loop in list(out):
        out[f"{loop}_closed"] = control.feedback(out[loop], 1)
    return out


def nominal_table(parameters: str = "bench", *, force: float = 0.0, supply_pressure: float = 7.0e5,
                  air_temperature: float = 298.15) -> list[LoopMargins]:
    """Margins of every loop at a parameter set's nominal values (the table of ``docs/control_design.md``).

    The force loop at ``force`` with the nominal scene's supply pressure and room temperature.
    """
    from twin.parameters import load_parameters

    p = load_parameters(parameters).values()
    load_system = {**p, "pneumatics.supply_pressure": supply_pressure, "pneumatics.air_temperature": air_temperature}
    return list(loop_margins(p, load_system, force).values())


def main() -> None:
    print(f"{'loop':10s} {'Ts [s]':>10s} {'fc [Hz]':>9s} {'GM [dB]':>8s} {'PM [deg]':>8s} {'|S|max':>7s}")
    for force in (0.0, 4000.0):
        print(f"(force loop at {force:g} N)")
        for m in nominal_table(force=force):
            print(f"{m.loop:10s} {m.sample_time:10.3g} {m.crossover_frequency:9.2f} {m.gain_margin:8.2f} "
                  f"{m.phase_margin:8.2f} {m.peak_sensitivity:7.3f}")


if __name__ == "__main__":
    main()
