"""Demand profiles: sequences of segments compiled to arrays for the compiled loop.

A profile is a list of segments, each starting where the previous one ended
(value and time). Kinds:

``hold``
    keep the current value until ``end``.
``ramp``
    linear to ``to`` at ``end``.
``smooth_step``
    to ``to`` at ``end`` with the C1 cubic smooth step of Eq. 7.56.
``sinusoid``
    ``amplitude * sin(2 pi frequency (t - start) + phase) - amplitude * sin(phase)``
    added to the current value, so the profile is continuous at the start.

After the last segment the last value is held.
"""

from __future__ import annotations

import math

import numba
import numpy as np

KINDS = {"hold": 0, "ramp": 1, "smooth_step": 2, "sinusoid": 3}
_FIELDS = {
    "hold": {"kind", "end"},
    "ramp": {"kind", "end", "to"},
    "smooth_step": {"kind", "end", "to"},
    "sinusoid": {"kind", "end", "amplitude", "frequency", "phase"},
}
_REQUIRED = {"hold": {"end"}, "ramp": {"end", "to"}, "smooth_step": {"end", "to"},
             "sinusoid": {"end", "amplitude", "frequency"}}

# Columns of the compiled segment table.
COL_KIND, COL_T0, COL_T1, COL_V0, COL_V1, COL_AMP, COL_FREQ, COL_PHASE = range(8)


def compile_profile(segments: list[dict], field: str, initial: float = 0.0) -> tuple[np.ndarray, list[str]]:
    """Validate segments and compile them to an ``(n, 8)`` float table.

    Parameters
    ----------
    segments : list of dict
        Segments as read from the scene TOML.
    field : str
        Field path used in error messages (e.g. ``"position_demand"``).
    initial : float
        Value before the first segment.

    Returns
    -------
    table, problems
        The compiled table (empty table if there are problems) and a list of problems.
    """
    problems: list[str] = []
    rows = []
    t0, v0 = 0.0, float(initial)
    for k, seg in enumerate(segments):
        where = f"{field}[{k}]"
        if not isinstance(seg, dict):
            problems.append(f"{where}: expected a table, got {type(seg).__name__}")
            continue
        kind = seg.get("kind")
        if kind not in KINDS:
            problems.append(f"{where}.kind: {kind!r} is not one of {', '.join(KINDS)}")
            continue
        extra = set(seg) - _FIELDS[kind]
        missing = _REQUIRED[kind] - set(seg)
        problems += [
            f"{where}.{f}: not a field of a '{kind}' segment; allowed: {', '.join(sorted(_FIELDS[kind] - {'kind'}))}"
            for f in sorted(extra)]
        problems += [f"{where}.{f}: missing (required for '{kind}')" for f in sorted(missing)]
        bad = [f for f in _FIELDS[kind] - {"kind"} if f in seg and not _is_finite_number(seg[f])]
        problems += [f"{where}.{f}: must be a finite number, got {seg[f]!r}" for f in bad]
        if extra or missing or bad:
            continue
        t1 = float(seg["end"])
        if t1 <= t0:
            problems.append(f"{where}.end: {t1:g} s must be after the segment start {t0:g} s")
            continue
        if kind == "sinusoid" and seg["frequency"] <= 0:
            problems.append(f"{where}.frequency: must be > 0 Hz, got {seg['frequency']!r}")
            continue
        amp, freq, phase = (float(seg.get("amplitude", 0.0)), float(seg.get("frequency", 0.0)),
                            float(seg.get("phase", 0.0)))
        if kind in ("ramp", "smooth_step"):
            v1 = float(seg["to"])
        elif kind == "sinusoid":
            v1 = v0 + amp * (math.sin(2 * math.pi * freq * (t1 - t0) + phase) - math.sin(phase))
        else:
            v1 = v0
        rows.append((KINDS[kind], t0, t1, v0, v1, amp, freq, phase))
        t0, v0 = t1, v1
    if not rows:
        rows.append((KINDS["hold"], 0.0, 0.0, v0, v0, 0.0, 0.0, 0.0))
    table = np.array(rows, dtype=np.float64)
    return (table if not problems else np.zeros((0, 8))), problems


def _is_finite_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


@numba.njit(cache=True)
def smooth_step(x, x0, f0, x1, f1):
    """Cubic smooth step of Eq. 7.56 (C1-continuous between (x0, f0) and (x1, f1))."""
    if x <= x0:
        return f0
    if x >= x1:
        return f1
    u = (x - x0) / (x1 - x0)
    return f0 + (f1 - f0) * u * u * (3.0 - 2.0 * u)


@numba.njit(cache=True)
def profile_value(table, t):
    """Value of a compiled profile at time ``t`` (last value held after the end)."""
    n = table.shape[0]
    for k in range(n):
        if t < table[k, COL_T1]:
            kind = int(table[k, COL_KIND])
            t0 = table[k, COL_T0]
            t1 = table[k, COL_T1]
            v0 = table[k, COL_V0]
            v1 = table[k, COL_V1]
            if kind == 0:
                return v0
            if kind == 1:
                return v0 + (v1 - v0) * (t - t0) / (t1 - t0)
            if kind == 2:
                return smooth_step(t, t0, v0, t1, v1)
            amp = table[k, COL_AMP]
            phase = table[k, COL_PHASE]
            return v0 + amp * (math.sin(2.0 * math.pi * table[k, COL_FREQ] * (t - t0) + phase) - math.sin(phase))
    return table[n - 1, COL_V1]


@numba.njit(cache=True)
def profile_values(table, times):
    """:func:`profile_value` at every instant of ``times`` (one compiled loop, not one call per instant)."""
    out = np.empty(times.shape[0])
    for k in range(times.shape[0]):
        out[k] = profile_value(table, times[k])
    return out
