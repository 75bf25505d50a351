"""Incremental quadrature encoder: edge pattern, counters and speed estimation.

Used for the sled's linear encoder (ELCIS RV1846, Table B.4: 1 um resolution
after x4 decoding, i.e. a 4 um signal period; ±5 um precision; phase tolerance
±45 deg; phase symmetry ±15 deg; 50 kHz) and for the torque meter's encoder
(Table B.5: 2000 pulses/turn, x4 decoded to 8000 counts/turn). Sec. 9.3
("Linear and rotary encoders") models the A/B pulse trains, forward and
backward counters, and speed by the period or the frequency method after the
thesis's ref. [250] (I. I. Incze, A. Negrea, M. Imecs, C. Szabó, "Incremental
encoder based position and speed identification: modeling and simulation",
Acta Univ. Sapientiae, Electr. Mech. Eng. 2, 2010); error bounds and switch
after R. Petrella, M. Tursini, L. Peretti, M. Zigliotto, "Speed measurement
algorithms for low-resolution incremental encoder equipped drives: a
comparative analysis", IEEE ACEMP 2007.

Edge pattern
------------
Within one signal period ``P`` the four edges (A rise, B rise, A fall, B fall)
nominally sit at 0, P/4, P/2, 3P/4. The phase error ``delta`` delays both B
edges by ``delta / 2pi * P``; the duty asymmetry ``eps`` of a phase widens its
high half-period symmetrically about its crest (a comparator threshold offset
on a sinusoidal track), moving its rise by ``-eps/2`` and its fall by
``+eps/2`` (angles in rad of the signal period). The precision error is a
smooth deterministic function of position applied to the scale itself,
``u(x) = x + e_p sin(2 pi x / lambda_p)``, so edges sit at fixed positions of
``u``. The count is then a pure function of ``u`` (a decoder that never loses
counts is path independent):

    N(u) = 3 + sum_k floor((u - o_k) / P),     o_k = k P / 4 + d_k,

which is ``floor(u / res)`` when every ``d_k = 0`` and jumps from ``n - 1`` to
``n`` at ``u = o_(n mod 4) + floor(n / 4) P``.

Mounting phase (issue 33; an extension of Table 9.5, the thesis is silent):
where the test's zero falls within a signal period depends on how the scale
(or the torque meter's disc) is mounted against the moving part, which no test
procedure sets. The parameter ``phase`` in [0, 1] (a fraction of the signal
period) shifts the whole pattern along the scale, ``o_k -> o_k + phase P``
(:func:`encoder_parameters`); at the quantised level the ideal edges shift
alike, ``N(u) = floor((u - phase P) / res)``. ``phase = 0`` puts a nominal
A-rise edge at ``u = 0``, the behaviour before the parameter existed.

Fidelity levels: 0 ideal (position = x, speed = exact window average),
1 quantised (``floor((x - phase P) / res)`` counts, ideal edges), 2
edge-accurate with the errors above.

Lane form (``sensors.lanes``): parameters and state are ``[row, lane]`` arrays
(rows below, one column per lane). The compiled functions take
``(state, params, lane, ...)``, act on column ``lane`` and are branch-free in the
data: every case (fidelity level, edge crossed or not, direction, speed
method) is computed and the answer chosen by selects, with
:func:`numerics.elementary.sin` for the precision error, so a loop over lanes
vectorises and each lane gets the same bits whatever its lane mates.

Parameter rows (float64, ``ENC_SIZE``), one lane's vector from :func:`encoder_parameters`:

=============================  =================================================
``ENC_FIDELITY``               0, 1 or 2
``ENC_RESOLUTION``             count resolution res = P / 4 [m or rad]
``ENC_PERIOD``                 signal period P [m or rad]
``ENC_EDGE`` .. ``ENC_EDGE+3`` edge offsets o_0..o_3 within a period, mounting
                               phase included [m or rad]
``ENC_PRECISION_AMPLITUDE``    e_p [m or rad]
``ENC_PRECISION_WAVENUMBER``   2 pi / lambda_p [1/m or 1/rad]
``ENC_TIMER_PERIOD``           tick of the edge-timestamp timer [s]
``ENC_MOUNTING_OFFSET``        phase * P: the shift of the ideal edges of the
                               quantised level [m or rad]
=============================  =================================================

State rows (float64, ``ENC_STATE_SIZE``), from :func:`encoder_init`:

=============================  =================================================
``ENC_S_T``                    time of the last step [s]
``ENC_S_U``                    scale position u at the last step
``ENC_S_COUNT``                count N(u) at the last step (integer-valued)
``ENC_S_COUNT0``               count at zeroing (start of the test)
``ENC_S_FORWARD``              forward (clockwise) counter
``ENC_S_BACKWARD``             backward (counter-clockwise) counter
``ENC_S_EDGE_T``               time of the last edge [s] (-inf: none yet)
``ENC_S_EDGE_DIR``             direction of the last edge (+1, -1, 0: none)
``ENC_S_PREV_EDGE_T``          time of the edge before it [s]
``ENC_S_PREV_EDGE_DIR``        its direction
``ENC_S_SAMPLE_T``             time of the last speed sample [s]
``ENC_S_SAMPLE_COUNT``         count at the last speed sample
``ENC_S_PEAK_FREQUENCY``       highest signal frequency seen [Hz]
=============================  =================================================
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numba
import numpy as np

from numerics.elementary import sin
from numerics.jit import SCALAR
from sensors.lanes import one_lane
from sensors.parameters import sensor_values

ENC_FIDELITY = 0
ENC_RESOLUTION = 1
ENC_PERIOD = 2
ENC_EDGE = 3
ENC_PRECISION_AMPLITUDE = 7
ENC_PRECISION_WAVENUMBER = 8
ENC_TIMER_PERIOD = 9
ENC_MOUNTING_OFFSET = 10
ENC_SIZE = 11

ENC_S_T = 0
ENC_S_U = 1
ENC_S_COUNT = 2
ENC_S_COUNT0 = 3
ENC_S_FORWARD = 4
ENC_S_BACKWARD = 5
ENC_S_EDGE_T = 6
ENC_S_EDGE_DIR = 7
ENC_S_PREV_EDGE_T = 8
ENC_S_PREV_EDGE_DIR = 9
ENC_S_SAMPLE_T = 10
ENC_S_SAMPLE_COUNT = 11
ENC_S_PEAK_FREQUENCY = 12
ENC_STATE_SIZE = 13

#: Nominal edge angles (A rise, B rise, A fall, B fall) within a signal period [rad].
_NOMINAL_EDGE_ANGLES = np.array([0.0, 0.5, 1.0, 1.5]) * math.pi


def edge_angles(phase_error: float, asymmetry_a: float, asymmetry_b: float) -> np.ndarray:
    """Angles of the four edges within a signal period [rad] (A rise, B rise, A fall, B fall).

    See the module docstring for the model.
    """
    return _NOMINAL_EDGE_ANGLES + np.array(
        [-asymmetry_a / 2.0, phase_error - asymmetry_b / 2.0, asymmetry_a / 2.0, phase_error + asymmetry_b / 2.0]
    )


def validate_encoder(
    *,
    resolution: float,
    phase_error: float,
    asymmetry_a: float,
    asymmetry_b: float,
    precision_amplitude: float,
    precision_wavelength: float,
    timer_period: float,
    fidelity: int,
    mounting_phase: float = 0.0,
) -> None:
    """Reject encoder parameters a quadrature decoder cannot work with.

    Raises
    ------
    ValueError
        Naming the field: non-positive resolution, wavelength or timer period;
        fidelity not in {0, 1, 2}; an edge pattern whose four edges are not in
        strict quadrature order (the decoder would count backwards); a
        precision error steep enough to make the scale non-monotonic; a
        mounting phase outside [0, 1] of a signal period.
    """
    for name, value in (
        ("resolution", resolution),
        ("precision_wavelength", precision_wavelength),
        ("timer_period", timer_period),
    ):
        if not value > 0.0:
            raise ValueError(f"{name}: must be > 0, got {value!r}")
    if fidelity not in (0, 1, 2):
        raise ValueError(f"fidelity: must be 0 (ideal), 1 (quantised) or 2 (edge-accurate), got {fidelity!r}")
    angles = edge_angles(phase_error, asymmetry_a, asymmetry_b)
    gaps = np.diff(np.append(angles, angles[0] + 2.0 * math.pi))
    if not np.all(gaps > 0.0):
        raise ValueError(
            "phase_error/asymmetry_a/asymmetry_b: edges out of quadrature order "
            f"(gaps {np.degrees(gaps).round(3).tolist()} deg must all be > 0)"
        )
    if not abs(precision_amplitude) * 2.0 * math.pi / precision_wavelength < 1.0:
        raise ValueError(
            f"precision_amplitude: |{precision_amplitude!r}| * 2 pi / wavelength must be < 1 "
            "or the scale position is not monotonic"
        )
    if not 0.0 <= mounting_phase <= 1.0:
        raise ValueError(f"mounting_phase: must be a fraction of a signal period in [0, 1], got {mounting_phase!r}")


def encoder_parameters(
    *,
    resolution: float,
    phase_error: float = 0.0,
    asymmetry_a: float = 0.0,
    asymmetry_b: float = 0.0,
    precision_amplitude: float = 0.0,
    precision_wavelength: float = 1.0,
    timer_period: float,
    fidelity: int = 2,
    mounting_phase: float = 0.0,
) -> np.ndarray:
    """Validate and pack one lane's encoder parameter vector (rows in the module docstring).

    Parameters
    ----------
    resolution : float
        Count resolution after x4 decoding [m or rad]; the signal period is 4x.
    phase_error : float
        A/B phase error [rad of the signal period]; delays the B edges.
    asymmetry_a, asymmetry_b : float
        Duty asymmetry of each phase [rad of the signal period].
    precision_amplitude : float
        Amplitude of the sinusoidal precision error along the scale [m or rad].
    precision_wavelength : float
        Wavelength of the precision error [m or rad].
    timer_period : float
        Tick of the timer that timestamps edges for the period method [s].
    fidelity : int
        0 ideal, 1 quantised, 2 edge-accurate.
    mounting_phase : float
        Fraction of the signal period, in [0, 1], by which the edge pattern is
        shifted along the scale: every edge offset becomes ``o_k + phase * P``
        (module docstring). 0 puts a nominal A-rise edge at ``u = 0``.
    """
    validate_encoder(
        resolution=resolution,
        phase_error=phase_error,
        asymmetry_a=asymmetry_a,
        asymmetry_b=asymmetry_b,
        precision_amplitude=precision_amplitude,
        precision_wavelength=precision_wavelength,
        timer_period=timer_period,
        fidelity=fidelity,
        mounting_phase=mounting_phase,
    )
    period = 4.0 * resolution
    shift = mounting_phase * period
    p = np.zeros(ENC_SIZE)
    p[ENC_FIDELITY] = fidelity
    p[ENC_RESOLUTION] = resolution
    p[ENC_PERIOD] = period
    p[ENC_EDGE : ENC_EDGE + 4] = edge_angles(phase_error, asymmetry_a, asymmetry_b) / (2.0 * math.pi) * period + shift
    p[ENC_PRECISION_AMPLITUDE] = precision_amplitude
    p[ENC_PRECISION_WAVENUMBER] = 2.0 * math.pi / precision_wavelength
    p[ENC_TIMER_PERIOD] = timer_period
    p[ENC_MOUNTING_OFFSET] = shift
    return p


def linear_encoder_parameters(params: Mapping[str, float], *, fidelity: int = 2) -> np.ndarray:
    """One lane's parameter vector of the sled's linear encoder (Table B.4) from the ``sensors`` group.

    One Table 9.5 row ("Asymmetry in each phase") drives both phases; the mounting phase is
    ``sensors.linear_encoder_mounting_phase`` (an extension of Table 9.5).
    """
    v = sensor_values(params)
    return encoder_parameters(
        resolution=v["sensors.linear_encoder_resolution"],
        phase_error=v["sensors.linear_encoder_phase_error"],
        asymmetry_a=v["sensors.linear_encoder_phase_asymmetry"],
        asymmetry_b=v["sensors.linear_encoder_phase_asymmetry"],
        precision_amplitude=v["sensors.linear_encoder_precision"],
        precision_wavelength=v["sensors.linear_encoder_precision_wavelength"],
        timer_period=v["sensors.encoder_timer_period"],
        fidelity=fidelity,
        mounting_phase=v["sensors.linear_encoder_mounting_phase"],
    )


def torque_meter_encoder_parameters(params: Mapping[str, float], *, fidelity: int = 2) -> np.ndarray:
    """One lane's parameter vector of the torque meter's rotary encoder (Table B.5), angles in rad.

    ``pulses_per_turn`` signal periods per revolution, x4 decoded. No
    precision error: Table 9.5 gives none for this encoder. The mounting
    phase is ``sensors.torque_meter_encoder_mounting_phase`` (an extension of
    Table 9.5).
    """
    v = sensor_values(params)
    pulses = v["sensors.torque_meter_encoder_pulses_per_turn"]
    if not float(pulses).is_integer():
        raise ValueError(f"sensors.torque_meter_encoder_pulses_per_turn: must be an integer, got {pulses!r}")
    return encoder_parameters(
        resolution=2.0 * math.pi / (4.0 * pulses),
        phase_error=v["sensors.torque_meter_encoder_phase_error"],
        asymmetry_a=v["sensors.torque_meter_encoder_phase_asymmetry"],
        asymmetry_b=v["sensors.torque_meter_encoder_phase_asymmetry"],
        timer_period=v["sensors.encoder_timer_period"],
        fidelity=fidelity,
        mounting_phase=v["sensors.torque_meter_encoder_mounting_phase"],
    )


# ---------------------------------------------------------------------------------------------------------
# compiled laws, lane form: (params, lane, ...) or (state, params, lane, ...), one column, branch-free
# ---------------------------------------------------------------------------------------------------------
@numba.njit(**SCALAR)
def scale_position(params, lane, x):
    """Scale position ``u(x) = x + e_p sin(2 pi x / lambda_p)`` at which column ``lane`` reads its edge pattern.

    The precision error is read at fidelity 2 only; elsewhere, and with ``e_p = 0``, ``u = x`` exactly.
    """
    amplitude = params[ENC_PRECISION_AMPLITUDE, lane]
    fidelity = params[ENC_FIDELITY, lane]
    u = x + amplitude * sin(params[ENC_PRECISION_WAVENUMBER, lane] * x)
    return u if (fidelity == 2.0) & (amplitude != 0.0) else x


@numba.njit(**SCALAR)
def decoder_count(params, lane, u):
    """Decoder count N(u) of column ``lane`` at scale position ``u`` (module docstring).

    Fidelity 0: the continuous ``u / res``; 1: ``floor((u - phase P) / res)`` (ideal edges);
    2: ``3 + sum_k floor((u - o_k) / P)`` over the four edges of the erroneous pattern.
    """
    res = params[ENC_RESOLUTION, lane]
    period = params[ENC_PERIOD, lane]
    fidelity = params[ENC_FIDELITY, lane]
    shift = params[ENC_MOUNTING_OFFSET, lane]
    edges = 3.0
    for k in range(4):
        edges += np.floor((u - params[ENC_EDGE + k, lane]) / period)
    ideal = np.floor((u - shift) / res)
    continuous = u / res
    count = ideal if fidelity == 1.0 else edges
    return continuous if fidelity == 0.0 else count


@numba.njit(**SCALAR)
def edge_position(params, lane, n):
    """Scale position of column ``lane``'s edge where the count changes from ``n - 1`` to ``n`` (fidelity >= 1).

    Edge ``n`` is edge ``k = n mod 4`` of signal period ``j = floor(n / 4)``: ``o_k + j P`` (chosen by selects,
    no float->int conversion); at the quantised level ``n res + phase P``.
    """
    o0, o1 = params[ENC_EDGE, lane], params[ENC_EDGE + 1, lane]
    o2, o3 = params[ENC_EDGE + 2, lane], params[ENC_EDGE + 3, lane]
    fidelity = params[ENC_FIDELITY, lane]
    j = np.floor(n / 4.0)
    k = n - 4.0 * j
    offset = o2 if k == 2.0 else o3
    offset = o1 if k == 1.0 else offset
    offset = o0 if k == 0.0 else offset
    pattern = offset + j * params[ENC_PERIOD, lane]
    ideal = n * params[ENC_RESOLUTION, lane] + params[ENC_MOUNTING_OFFSET, lane]
    return ideal if fidelity == 1.0 else pattern


@numba.njit(**SCALAR)
def edge_time(params, lane, n, u0, u1, t0, t1):
    """Time column ``lane``'s scale crosses edge ``n`` in a step from ``(t0, u0)`` to ``(t1, u1)``, linear in ``u``.

    Rounding can put an edge a few ulps outside the step it was counted in: the fraction is clamped to [0, 1].
    """
    frac = (edge_position(params, lane, n) - u0) / (u1 - u0)
    return t0 + min(max(frac, 0.0), 1.0) * (t1 - t0)


@numba.njit(**SCALAR)
def encoder_init(state, params, lane, x0, t0):
    """Initialise column ``lane`` of ``state`` at ``t0`` and zero the encoder at position ``x0``.

    An incremental encoder reads zero where it is zeroed (start of the test,
    Eq. 9.12 feature); counters start at zero, no edge has been seen yet.
    """
    u = scale_position(params, lane, x0)
    count = decoder_count(params, lane, u)
    state[ENC_S_T, lane] = t0
    state[ENC_S_U, lane] = u
    state[ENC_S_COUNT, lane] = count
    state[ENC_S_COUNT0, lane] = count
    state[ENC_S_FORWARD, lane] = 0.0
    state[ENC_S_BACKWARD, lane] = 0.0
    state[ENC_S_EDGE_T, lane] = -math.inf
    state[ENC_S_EDGE_DIR, lane] = 0.0
    state[ENC_S_PREV_EDGE_T, lane] = -math.inf
    state[ENC_S_PREV_EDGE_DIR, lane] = 0.0
    state[ENC_S_SAMPLE_T, lane] = t0
    state[ENC_S_SAMPLE_COUNT, lane] = count
    state[ENC_S_PEAK_FREQUENCY, lane] = 0.0


@numba.njit(**SCALAR)
def encoder_step(state, params, lane, x, t):
    """Advance column ``lane`` of the encoder to time ``t`` where the true position is ``x`` (call pattern (a)).

    The count is recomputed from ``x`` (path independent), so no count is
    ever lost or added on reversals, however the steps dither around an edge;
    the forward/backward counters receive the positive/negative count change,
    so ``forward - backward == count - count0`` after every step. The motion
    inside a step is taken monotonic: an excursion that crosses an edge and
    returns within one step is invisible, as it would be to the integrator.

    The last two edge times are interpolated linearly inside the step (for the
    period method): forward the last edge crossed is ``count``, backward
    ``count + 1``; a step that crosses two or more edges times the one before
    it too, a step that crosses one keeps the previous last edge as the edge
    before it. The peak signal frequency is tracked for comparison with the
    datasheet maximum (:func:`encoder_overspeed`).

    Branch-free: both edge times and both directions are computed at every
    step and kept by selects only when an edge was crossed (and the fidelity
    counts edges). Call it at every integration step.

    Parameters
    ----------
    state : numpy.ndarray
        Encoder states ``[ENC_STATE_SIZE, L]``, column ``lane`` updated in place.
    params : numpy.ndarray
        Encoder parameters ``[ENC_SIZE, L]``.
    lane : int
        Lane: the column of ``state`` and ``params`` this call reads and writes.
    x : float
        True position at ``t`` [m or rad].
    t : float
        Time at the end of the step [s].
    """
    # every value is loaded and computed first, the selects choose between scalars (a select between array
    # loads or calls would stay a branch: LLVM cannot speculate it, and the lane loop would not vectorise)
    t0 = state[ENC_S_T, lane]
    u0 = state[ENC_S_U, lane]
    peak_before = state[ENC_S_PEAK_FREQUENCY, lane]
    edge_t, edge_dir = state[ENC_S_EDGE_T, lane], state[ENC_S_EDGE_DIR, lane]
    prev_edge_t, prev_edge_dir = state[ENC_S_PREV_EDGE_T, lane], state[ENC_S_PREV_EDGE_DIR, lane]
    counts_edges = params[ENC_FIDELITY, lane] > 0.0
    u1 = scale_position(params, lane, x)
    count = decoder_count(params, lane, u1)
    dn = count - state[ENC_S_COUNT, lane]

    frequency = abs(u1 - u0) / (params[ENC_PERIOD, lane] * (t - t0))
    peak = max(peak_before, frequency)
    state[ENC_S_PEAK_FREQUENCY, lane] = peak if t > t0 else peak_before
    state[ENC_S_FORWARD, lane] += max(dn, 0.0)
    state[ENC_S_BACKWARD, lane] += max(-dn, 0.0)

    forward = dn > 0.0
    direction = 1.0 if forward else -1.0
    last = count if forward else count + 1.0
    last_t = edge_time(params, lane, last, u0, u1, t0, t)
    before_t = edge_time(params, lane, last - direction, u0, u1, t0, t)
    several = abs(dn) >= 2.0
    new_prev_t = before_t if several else edge_t
    new_prev_dir = direction if several else edge_dir
    crossed = (dn != 0.0) & counts_edges
    state[ENC_S_PREV_EDGE_T, lane] = new_prev_t if crossed else prev_edge_t
    state[ENC_S_PREV_EDGE_DIR, lane] = new_prev_dir if crossed else prev_edge_dir
    state[ENC_S_EDGE_T, lane] = last_t if crossed else edge_t
    state[ENC_S_EDGE_DIR, lane] = direction if crossed else edge_dir
    state[ENC_S_T, lane] = t
    state[ENC_S_U, lane] = u1
    state[ENC_S_COUNT, lane] = count


@numba.njit(**SCALAR)
def encoder_reading(state, params, lane):
    """Zeroed position reading of column ``lane`` [m or rad]: (count - count0) * res."""
    return (state[ENC_S_COUNT, lane] - state[ENC_S_COUNT0, lane]) * params[ENC_RESOLUTION, lane]


@numba.njit(**SCALAR)
def speed_switch_threshold(resolution, timer_period, window):
    """Speed above which the frequency method beats the period method.

    Period method: an edge interval ``res / v`` timed with a tick ``T_clk``
    has an error below one tick, hence a speed error ``|dv| <= v^2 T_clk /
    (res - v T_clk) ~ v^2 T_clk / res``. Frequency method: counting over a
    window ``T_w`` has an error below one count, ``|dv| < res / T_w``. The
    bounds cross at ``v_sw = res / sqrt(T_clk T_w)`` (Petrella et al. 2007).
    """
    return resolution / np.sqrt(timer_period * window)


@numba.njit(**SCALAR)
def frequency_method_speed(count, sample_count, resolution, window):
    """Frequency-method speed: the counts in the window over its length, ``(N - N_s) res / T_w`` (ref. [250]).

    Error below ``res / T_w``; the exact mean speed when the count is continuous (fidelity 0). 0 for an empty
    window.
    """
    return (count - sample_count) * resolution / window if window > 0.0 else 0.0


@numba.njit(**SCALAR)
def period_method_speed(edge_t, edge_dir, prev_edge_t, prev_edge_dir, resolution, tick, t):
    """Period-method speed at time ``t`` from the last two edges (ref. [250]; Petrella et al. 2007).

    The edge interval and the time since the last edge are counted in timer
    ticks (``floor(t / T_clk)``, a free-running counter); the speed is
    ``res / max(interval, elapsed)``, so it decays towards zero once edges
    stop arriving instead of holding the last value. Two consecutive edges in
    opposite directions are the same edge crossed twice (dither): the net
    displacement is zero and so is the estimate. Intervals below one tick read
    as one tick. Fewer than two edges read 0.
    """
    t_last = np.floor(edge_t / tick)
    interval = max(t_last - np.floor(prev_edge_t / tick), 1.0)
    elapsed = np.floor(t / tick) - t_last
    speed = edge_dir * resolution / (max(interval, elapsed) * tick)
    two_edges_one_way = (edge_dir != 0.0) & (prev_edge_dir == edge_dir)
    return speed if two_edges_one_way else 0.0


@numba.njit(**SCALAR)
def encoder_frequency_speed(state, params, lane, t):
    """Frequency-method speed of column ``lane`` at ``t`` over the window since its last speed sample
    (:func:`frequency_method_speed`). Does not modify ``state``."""
    return frequency_method_speed(state[ENC_S_COUNT, lane], state[ENC_S_SAMPLE_COUNT, lane],
                                  params[ENC_RESOLUTION, lane], t - state[ENC_S_SAMPLE_T, lane])


@numba.njit(**SCALAR)
def encoder_period_speed(state, params, lane, t):
    """Period-method speed of column ``lane`` at ``t`` from its last two edges (:func:`period_method_speed`).
    Does not modify ``state``."""
    return period_method_speed(state[ENC_S_EDGE_T, lane], state[ENC_S_EDGE_DIR, lane], state[ENC_S_PREV_EDGE_T, lane],
                               state[ENC_S_PREV_EDGE_DIR, lane], params[ENC_RESOLUTION, lane],
                               params[ENC_TIMER_PERIOD, lane], t)


@numba.njit(**SCALAR)
def encoder_speed(state, params, lane, t):
    """Measured speed of column ``lane`` at sample instant ``t`` (call pattern (b)); starts a new window.

    Fidelity 0 returns the exact window-mean speed. Otherwise the frequency
    estimate ``v_f`` over the window since the previous call selects the
    method: period method if ``|v_f| < v_sw`` (:func:`speed_switch_threshold`),
    frequency method otherwise, i.e. whichever has the smaller error bound.
    Deciding on ``v_f`` is safe: its error ``res / T_w`` is a fraction
    ``sqrt(T_clk / T_w)`` of ``v_sw``, and at the crossover both methods are
    equally good. Both estimates are computed and one is selected.

    Parameters
    ----------
    state : numpy.ndarray
        Encoder states ``[ENC_STATE_SIZE, L]``, already stepped to ``t``; column ``lane``'s sample slots are updated.
    params : numpy.ndarray
        Encoder parameters ``[ENC_SIZE, L]``.
    lane : int
        Lane: the column of ``state`` and ``params`` this call reads and writes.
    t : float
        Sample instant [s]; the window is ``t`` minus the previous call's ``t``.

    Returns
    -------
    float
        Speed [m/s or rad/s].
    """
    count = state[ENC_S_COUNT, lane]
    window = t - state[ENC_S_SAMPLE_T, lane]
    resolution, tick = params[ENC_RESOLUTION, lane], params[ENC_TIMER_PERIOD, lane]
    ideal = params[ENC_FIDELITY, lane] == 0.0
    frequency_speed = frequency_method_speed(count, state[ENC_S_SAMPLE_COUNT, lane], resolution, window)
    period_speed = period_method_speed(state[ENC_S_EDGE_T, lane], state[ENC_S_EDGE_DIR, lane],
                                       state[ENC_S_PREV_EDGE_T, lane], state[ENC_S_PREV_EDGE_DIR, lane], resolution,
                                       tick, t)
    state[ENC_S_SAMPLE_T, lane] = t
    state[ENC_S_SAMPLE_COUNT, lane] = count
    threshold = speed_switch_threshold(resolution, tick, window)
    frequency_method = ideal | (window <= 0.0) | (abs(frequency_speed) >= threshold)
    return frequency_speed if frequency_method else period_speed


# ---------------------------------------------------------------------------------------------------------
# one-lane conveniences (Python callers holding one lane's parameter vector) and diagnostics
# ---------------------------------------------------------------------------------------------------------
@numba.njit(**SCALAR)
def encoder_count(x, p):
    """Absolute decoder count at true position ``x`` [m or rad] for one lane's parameter vector ``p``.

    Path independent, so it is exact without stepping at the pulse rate.
    Fidelity 0 returns the continuous ``x / res``; 1 returns ``floor((x - phase P) / res)``;
    2 counts the edges of the erroneous pattern (module docstring).
    """
    params = one_lane(p)
    return decoder_count(params, 0, scale_position(params, 0, x))


@numba.njit(**SCALAR)
def encoder_position(x, p):
    """Absolute position reading [m or rad] for one lane's parameter vector ``p``: ``x`` (fidelity 0) or
    count * res."""
    reading = encoder_count(x, p) * p[ENC_RESOLUTION]
    return x if p[ENC_FIDELITY] == 0.0 else reading


def encoder_overspeed(state: np.ndarray, max_frequency: float) -> np.ndarray:
    """Per lane: True if the encoder's signal ran faster than its datasheet maximum (Table B.4: 50 kHz).

    The twin's decoder never loses counts; a real one may above this limit,
    so a run that exceeds it should be flagged. ``state`` is ``[ENC_STATE_SIZE, L]``.
    """
    return np.asarray(state)[ENC_S_PEAK_FREQUENCY] > max_frequency
