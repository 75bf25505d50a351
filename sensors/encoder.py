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

Fidelity levels: 0 ideal (position = x, speed = exact window average),
1 quantised (``floor(x / res)`` counts, ideal edges), 2 edge-accurate with the
errors above.

Parameter array (float64, length ``ENC_SIZE``), from :func:`encoder_parameters`:

=============================  =================================================
``ENC_FIDELITY``               0, 1 or 2
``ENC_RESOLUTION``             count resolution res = P / 4 [m or rad]
``ENC_PERIOD``                 signal period P [m or rad]
``ENC_EDGE`` .. ``ENC_EDGE+3`` edge offsets o_0..o_3 within a period [m or rad]
``ENC_PRECISION_AMPLITUDE``    e_p [m or rad]
``ENC_PRECISION_WAVENUMBER``   2 pi / lambda_p [1/m or 1/rad]
``ENC_TIMER_PERIOD``           tick of the edge-timestamp timer [s]
=============================  =================================================

State array (float64, length ``ENC_STATE_SIZE``), from :func:`encoder_init`:

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
``ENC_S_X``                    true position at the last step (:func:`encoder_advance`)
``ENC_S_U_STALE``              1 if ``ENC_S_U`` lags ``ENC_S_X`` (steps skipped)
``ENC_S_QUIET_CENTRE``         position about which no edge can be crossed ...
``ENC_S_QUIET_RADIUS``         ... within this distance (negative: none)
=============================  =================================================
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numba
import numpy as np

from sensors.parameters import sensor_values

ENC_FIDELITY = 0
ENC_RESOLUTION = 1
ENC_PERIOD = 2
ENC_EDGE = 3
ENC_PRECISION_AMPLITUDE = 7
ENC_PRECISION_WAVENUMBER = 8
ENC_TIMER_PERIOD = 9
ENC_SIZE = 10

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
ENC_S_X = 13
ENC_S_U_STALE = 14
ENC_S_QUIET_CENTRE = 15
ENC_S_QUIET_RADIUS = 16
ENC_STATE_SIZE = 17

#: Margin kept from an edge by :func:`encoder_advance`'s skip, in counts: far above the rounding of
#: ``_count_at`` (a few ulps of ``u / P``) while ``|u| < _QUIET_RANGE`` signal periods.
_QUIET_MARGIN = 1e-6
_QUIET_RANGE = 1e7

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
) -> None:
    """Reject encoder parameters a quadrature decoder cannot work with.

    Raises
    ------
    ValueError
        Naming the field: non-positive resolution, wavelength or timer period;
        fidelity not in {0, 1, 2}; an edge pattern whose four edges are not in
        strict quadrature order (the decoder would count backwards); a
        precision error steep enough to make the scale non-monotonic.
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
) -> np.ndarray:
    """Validate and pack an encoder's parameter array (layout in the module docstring).

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
    )
    period = 4.0 * resolution
    p = np.zeros(ENC_SIZE)
    p[ENC_FIDELITY] = fidelity
    p[ENC_RESOLUTION] = resolution
    p[ENC_PERIOD] = period
    p[ENC_EDGE : ENC_EDGE + 4] = edge_angles(phase_error, asymmetry_a, asymmetry_b) / (2.0 * math.pi) * period
    p[ENC_PRECISION_AMPLITUDE] = precision_amplitude
    p[ENC_PRECISION_WAVENUMBER] = 2.0 * math.pi / precision_wavelength
    p[ENC_TIMER_PERIOD] = timer_period
    return p


def linear_encoder_parameters(params: Mapping[str, float], *, fidelity: int = 2) -> np.ndarray:
    """Parameter array of the sled's linear encoder (Table B.4) from the ``sensors`` group.

    One Table 9.5 row ("Asymmetry in each phase") drives both phases.
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
    )


def torque_meter_encoder_parameters(params: Mapping[str, float], *, fidelity: int = 2) -> np.ndarray:
    """Parameter array of the torque meter's rotary encoder (Table B.5), angles in rad.

    ``pulses_per_turn`` signal periods per revolution, x4 decoded. No
    precision error: Table 9.5 gives none for this encoder.
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
    )


@numba.njit(cache=True)
def scale_position(x, p):
    """Scale position ``u(x)`` at which the edge pattern is read (precision error at fidelity 2)."""
    amplitude = p[ENC_PRECISION_AMPLITUDE]
    # x + 0 * sin(...) is x for finite x != 0 (at -0.0 the sign of the sine's zero decides, at inf it is NaN)
    if p[ENC_FIDELITY] < 2.0 or (amplitude == 0.0 and 0.0 < abs(x) < math.inf):
        return x
    return x + amplitude * math.sin(p[ENC_PRECISION_WAVENUMBER] * x)


@numba.njit(cache=True)
def _count_at(u, p):
    """Decoder count N(u) at scale position ``u`` (continuous ``u / res`` at fidelity 0)."""
    res = p[ENC_RESOLUTION]
    fidelity = p[ENC_FIDELITY]
    if fidelity == 0.0:
        return u / res
    if fidelity == 1.0:
        return math.floor(u / res)
    period = p[ENC_PERIOD]
    n = 3.0
    for k in range(4):
        n += math.floor((u - p[ENC_EDGE + k]) / period)
    return n


@numba.njit(cache=True)
def _edge_position(n, p):
    """Scale position of the edge where the count changes from ``n - 1`` to ``n`` (fidelity >= 1)."""
    if p[ENC_FIDELITY] == 1.0:
        return n * p[ENC_RESOLUTION]
    j = math.floor(n / 4.0)
    return p[ENC_EDGE + int(n - 4.0 * j)] + j * p[ENC_PERIOD]


@numba.njit(cache=True)
def encoder_count(x, p):
    """Absolute decoder count at true position ``x`` [m or rad].

    Path independent, so it is exact without stepping at the pulse rate.
    Fidelity 0 returns the continuous ``x / res``; 1 returns ``floor(x / res)``;
    2 counts the edges of the erroneous pattern (module docstring).
    """
    return _count_at(scale_position(x, p), p)


@numba.njit(cache=True)
def encoder_position(x, p):
    """Absolute position reading [m or rad]: ``x`` (fidelity 0) or count * res."""
    if p[ENC_FIDELITY] == 0.0:
        return x
    return encoder_count(x, p) * p[ENC_RESOLUTION]


@numba.njit(cache=True)
def encoder_init(state, x0, t0, p):
    """Initialise ``state`` at ``t0`` and zero the encoder at position ``x0``.

    An incremental encoder reads zero where it is zeroed (start of the test,
    Eq. 9.12 feature); counters start at zero, no edge has been seen yet.
    """
    u = scale_position(x0, p)
    count = _count_at(u, p)
    state[ENC_S_T] = t0
    state[ENC_S_U] = u
    state[ENC_S_COUNT] = count
    state[ENC_S_COUNT0] = count
    state[ENC_S_FORWARD] = 0.0
    state[ENC_S_BACKWARD] = 0.0
    state[ENC_S_EDGE_T] = -np.inf
    state[ENC_S_EDGE_DIR] = 0.0
    state[ENC_S_PREV_EDGE_T] = -np.inf
    state[ENC_S_PREV_EDGE_DIR] = 0.0
    state[ENC_S_SAMPLE_T] = t0
    state[ENC_S_SAMPLE_COUNT] = count
    state[ENC_S_PEAK_FREQUENCY] = 0.0
    state[ENC_S_X] = x0
    state[ENC_S_U_STALE] = 0.0
    _set_quiet_region(state, x0, p)


@numba.njit(cache=True)
def _edge_time(n, u0, u1, t0, t1, p):
    """Time the scale crosses edge ``n``, linear in ``u`` inside the step."""
    frac = (_edge_position(n, p) - u0) / (u1 - u0)
    # Rounding can put an edge a few ulps outside the step it was counted in.
    return t0 + min(max(frac, 0.0), 1.0) * (t1 - t0)


@numba.njit(cache=True)
def encoder_step(state, x, t, p):
    """Advance the encoder to time ``t`` where the true position is ``x`` (call pattern (a)).

    The count is recomputed from ``x`` (path independent), so no count is
    ever lost or added on reversals, however the steps dither around an edge;
    the forward/backward counters receive the positive/negative count change,
    so ``forward - backward == count - count0`` after every step. The motion
    inside a step is taken monotonic: an excursion that crosses an edge and
    returns within one step is invisible, as it would be to the integrator.

    The last two edge times are interpolated linearly inside the step (for the
    period method); the peak signal frequency is tracked for comparison with
    the datasheet maximum (:func:`encoder_overspeed`).

    Parameters
    ----------
    state : numpy.ndarray
        Encoder state (layout in the module docstring), updated in place.
    x : float
        True position at ``t`` [m or rad].
    t : float
        Time at the end of the step [s].
    p : numpy.ndarray
        Encoder parameters.
    """
    t0 = state[ENC_S_T]
    u0 = state[ENC_S_U]
    u1 = scale_position(x, p)
    count = _count_at(u1, p)
    dn = count - state[ENC_S_COUNT]
    if t > t0:
        frequency = abs(u1 - u0) / (p[ENC_PERIOD] * (t - t0))
        state[ENC_S_PEAK_FREQUENCY] = max(state[ENC_S_PEAK_FREQUENCY], frequency)
    if dn > 0.0:
        state[ENC_S_FORWARD] += dn
    elif dn < 0.0:
        state[ENC_S_BACKWARD] -= dn
    if dn != 0.0 and p[ENC_FIDELITY] > 0.0:
        direction = 1.0 if dn > 0.0 else -1.0
        # Forward the last edge crossed is `count`; backward it is `count + 1`.
        last = count if dn > 0.0 else count + 1.0
        if abs(dn) >= 2.0:
            state[ENC_S_PREV_EDGE_T] = _edge_time(last - direction, u0, u1, t0, t, p)
            state[ENC_S_PREV_EDGE_DIR] = direction
        else:
            state[ENC_S_PREV_EDGE_T] = state[ENC_S_EDGE_T]
            state[ENC_S_PREV_EDGE_DIR] = state[ENC_S_EDGE_DIR]
        state[ENC_S_EDGE_T] = _edge_time(last, u0, u1, t0, t, p)
        state[ENC_S_EDGE_DIR] = direction
    state[ENC_S_T] = t
    state[ENC_S_U] = u1
    state[ENC_S_COUNT] = count


@numba.njit(cache=True, inline="always")
def _set_quiet_region(state, x, p):
    """Store the interval of true positions about ``x`` in which the count equals ``state[ENC_S_COUNT]``.

    The count is ``n`` for ``u`` between the edges ``n`` and ``n + 1`` (module docstring), and
    ``|du/dx| <= 1 + |e_p| 2 pi / lambda_p``, so a true position closer to ``x`` than the scale
    distance to the nearer edge, less a margin, over that bound cannot change the count.
    Fidelity 0 (a continuous count) has no such region.
    """
    u = state[ENC_S_U]
    fidelity = p[ENC_FIDELITY]
    radius = -1.0
    if fidelity > 0.0 and abs(u) < _QUIET_RANGE * p[ENC_PERIOD]:
        count = state[ENC_S_COUNT]
        room = min(u - _edge_position(count, p), _edge_position(count + 1.0, p) - u) - _QUIET_MARGIN * p[ENC_RESOLUTION]
        slope = 1.0
        if fidelity == 2.0:
            slope += abs(p[ENC_PRECISION_AMPLITUDE]) * p[ENC_PRECISION_WAVENUMBER]
        radius = room / slope
    state[ENC_S_QUIET_CENTRE] = x
    state[ENC_S_QUIET_RADIUS] = radius


@numba.njit(cache=True, inline="always")
def encoder_advance(state, x, t, p):
    """:func:`encoder_step` for a caller that steps at every integration step: a step that cannot
    cross an edge costs a comparison.

    Such a step changes neither the count nor the edge times; only its end (time, position) is kept,
    and the scale position ``u`` is computed from it when the next step needs it as a start value,
    so every reading equals that of :func:`encoder_step` at every step. The peak signal frequency
    (``ENC_S_PEAK_FREQUENCY``) is taken over the other steps only: a skipped step moves less than one
    count, so its frequency is below ``1 / (4 dt)``, far from any datasheet limit at loop steps.
    """
    if abs(x - state[ENC_S_QUIET_CENTRE]) < state[ENC_S_QUIET_RADIUS]:
        state[ENC_S_T] = t
        state[ENC_S_X] = x
        state[ENC_S_U_STALE] = 1.0
        return
    if state[ENC_S_U_STALE] != 0.0:
        state[ENC_S_U] = scale_position(state[ENC_S_X], p)
        state[ENC_S_U_STALE] = 0.0
    count = state[ENC_S_COUNT]
    encoder_step(state, x, t, p)
    state[ENC_S_X] = x
    if state[ENC_S_COUNT] == count:
        _set_quiet_region(state, x, p)
    else:  # moving: the next step most likely crosses an edge too, the region would go unused
        state[ENC_S_QUIET_RADIUS] = -1.0


@numba.njit(cache=True)
def encoder_reading(state, p):
    """Zeroed position reading [m or rad]: (count - count0) * res."""
    return (state[ENC_S_COUNT] - state[ENC_S_COUNT0]) * p[ENC_RESOLUTION]


@numba.njit(cache=True)
def speed_switch_threshold(resolution, timer_period, window):
    """Speed above which the frequency method beats the period method.

    Period method: an edge interval ``res / v`` timed with a tick ``T_clk``
    has an error below one tick, hence a speed error ``|dv| <= v^2 T_clk /
    (res - v T_clk) ~ v^2 T_clk / res``. Frequency method: counting over a
    window ``T_w`` has an error below one count, ``|dv| < res / T_w``. The
    bounds cross at ``v_sw = res / sqrt(T_clk T_w)`` (Petrella et al. 2007).
    """
    return resolution / math.sqrt(timer_period * window)


@numba.njit(cache=True)
def encoder_frequency_speed(state, t, p):
    """Frequency-method speed: counts since the last speed sample over the elapsed window.

    Error below ``res / T_w``. At fidelity 0 this is the exact mean speed.
    Returns 0 for an empty window. Does not modify ``state``.
    """
    window = t - state[ENC_S_SAMPLE_T]
    if window <= 0.0:
        return 0.0
    return (state[ENC_S_COUNT] - state[ENC_S_SAMPLE_COUNT]) * p[ENC_RESOLUTION] / window


@numba.njit(cache=True)
def encoder_period_speed(state, t, p):
    """Period-method speed at time ``t`` from the last two edges.

    The edge interval and the time since the last edge are counted in timer
    ticks (``floor(t / T_clk)``, a free-running counter); the speed is
    ``res / max(interval, elapsed)``, so it decays towards zero once edges
    stop arriving instead of holding the last value. Two consecutive edges in
    opposite directions are the same edge crossed twice (dither): the net
    displacement is zero and so is the estimate. Intervals below one tick read
    as one tick. Does not modify ``state``.
    """
    direction = state[ENC_S_EDGE_DIR]
    if direction == 0.0 or state[ENC_S_PREV_EDGE_DIR] != direction:
        return 0.0
    tick = p[ENC_TIMER_PERIOD]
    t_last = math.floor(state[ENC_S_EDGE_T] / tick)
    interval = max(t_last - math.floor(state[ENC_S_PREV_EDGE_T] / tick), 1.0)
    elapsed = math.floor(t / tick) - t_last
    return direction * p[ENC_RESOLUTION] / (max(interval, elapsed) * tick)


@numba.njit(cache=True)
def encoder_speed(state, t, p):
    """Measured speed at sample instant ``t`` (call pattern (b)); starts a new window.

    Fidelity 0 returns the exact window-mean speed. Otherwise the frequency
    estimate ``v_f`` over the window since the previous call selects the
    method: period method if ``|v_f| < v_sw`` (:func:`speed_switch_threshold`),
    frequency method otherwise, i.e. whichever has the smaller error bound.
    Deciding on ``v_f`` is safe: its error ``res / T_w`` is a fraction
    ``sqrt(T_clk / T_w)`` of ``v_sw``, and at the crossover both methods are
    equally good.

    Parameters
    ----------
    state : numpy.ndarray
        Encoder state, already stepped to ``t``; its sample slots are updated.
    t : float
        Sample instant [s]; the window is ``t`` minus the previous call's ``t``.
    p : numpy.ndarray
        Encoder parameters.

    Returns
    -------
    float
        Speed [m/s or rad/s].
    """
    window = t - state[ENC_S_SAMPLE_T]
    v_f = encoder_frequency_speed(state, t, p)
    state[ENC_S_SAMPLE_T] = t
    state[ENC_S_SAMPLE_COUNT] = state[ENC_S_COUNT]
    if p[ENC_FIDELITY] == 0.0 or window <= 0.0:
        return v_f
    if abs(v_f) >= speed_switch_threshold(p[ENC_RESOLUTION], p[ENC_TIMER_PERIOD], window):
        return v_f
    return encoder_period_speed(state, t, p)


def encoder_overspeed(state: np.ndarray, max_frequency: float) -> bool:
    """True if the encoder's signal ran faster than its datasheet maximum (Table B.4: 50 kHz).

    The twin's decoder never loses counts; a real one may above this limit,
    so a run that exceeds it should be flagged.
    """
    return bool(state[ENC_S_PEAK_FREQUENCY] > max_frequency)
