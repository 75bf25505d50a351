"""Loop margins per parameter set (twin.control.margins): two methods agree, the nominal figures are the
documented ones, and the linearised position loop reproduces the nonlinear twin's small-signal response."""

import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from twin.control.design import design_loops
from twin.control.force_loop_design import design_force_loop
from twin.control.margins import LOOPS, LOWEST_HZ, loop_margins, loop_responses, loop_systems, margins_from_response

DOC = Path(__file__).resolve().parents[2] / "docs" / "control_design.md"
NOMINAL_SCENE = {"pneumatics.supply_pressure": 7.0e5, "pneumatics.air_temperature": 298.15}


def _load_system(p):
    return {**p, **NOMINAL_SCENE}


def _perturbed(bench):
    """A sampled-looking bench: motor and reducer tolerances at the edges of Table 9.5's ranges."""
    p = dict(bench.values())
    p["motor.winding_resistance_20C"] *= 1.10
    p["motor.torque_constant"] *= 0.90
    p["motor.inertia"] *= 1.10
    p["reducer.torsional_stiffness"] *= 0.95
    return p


def _python_control_margins(system):
    """python-control's margins as the grid defines them, the smallest of each kind over every crossing it lists.

    ``stability_margins`` alone returns one crossing of its own choosing, and on the speed loop it can choose a
    spurious one: the digital realisations carry exactly cancelling pole-zero pairs at z = 1 (see
    CANCELLATION_TOLERANCE below), so below ~1 rad/s the phase of L sits within rounding of -180 deg with |L| >> 1,
    and the rounding, which depends on the OpenBLAS kernel, makes dozens of "phase crossings" there (the speed
    loop's gain margin read -1.42 dB under SkylakeX, 24.44 dB under Haswell; -89 dB and -102 dB among the listed
    ones). With ``returnall=True`` every crossing is listed, and the loop's own are kept as the grid keeps them: at or
    above the grid's lowest frequency (0.31 rad/s; the spurious gain crossings lie below 0.2 rad/s, the lowest real
    one at 40 rad/s), and for the gain margin only phase crossings with |L| < 1. The loops are not conditionally
    stable (test_closed_loops_are_stable_at_nominal), so every physical phase crossing has |L| < 1. The check can
    still fail: a wrong grid margin matches none of the kept crossings.
    """
    import control

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the frd fallback warning of stability_margins is expected here
        gm, pm, sm, wpc, wgc, wms = control.stability_margins(system, returnall=True)
    lowest = 2 * math.pi * LOWEST_HZ
    gm_db = [20 * math.log10(g) for g, w in zip(gm, wpc, strict=True) if w >= lowest and np.isfinite(g) and g > 1]
    in_band_pm = [(m, w) for m, w in zip(pm, wgc, strict=True) if w >= lowest]
    in_band_sm = [m for m, w in zip(sm, wms, strict=True) if w >= lowest]
    assert in_band_pm and in_band_sm, "python-control finds no gain crossover in the grid's band"
    phase_margin, crossover = min(in_band_pm)
    return min(gm_db, default=math.inf), phase_margin, crossover / (2 * math.pi), 1.0 / min(in_band_sm)


@pytest.mark.parametrize("which", ["nominal", "perturbed"])
def test_grid_margins_match_python_control(bench, which):
    """The numpy grid (100 points/decade, crossings interpolated) against python-control's stability_margins on the
    same loops. Tolerances: the grid's interpolation error -- phase margin 0.02 deg, gain margin 0.02 dB, crossover
    0.05 %, and |S|max read on grid points only, which can under-read a peak by at most ~0.1 % at this spacing."""
    p = dict(bench.values()) if which == "nominal" else _perturbed(bench)
    load = _load_system(p)
    systems = loop_systems(p, load, 4000.0)
    mine = {loop: m for loop, (ts, w, r) in loop_responses(p, load, 4000.0, load_cell_refresh=False).items()
            for m in [margins_from_response(loop, ts, w, r)]}
    assert set(mine) == set(LOOPS)
    for loop in LOOPS:
        gm, pm, fc, peak = _python_control_margins(systems[loop])
        m = mine[loop]
        assert m.phase_margin == pytest.approx(pm, abs=0.02), loop
        assert m.crossover_frequency == pytest.approx(fc, rel=5e-4), loop
        if math.isinf(gm):
            assert math.isinf(m.gain_margin), loop
        else:
            assert m.gain_margin == pytest.approx(gm, abs=0.02), loop
        assert peak * (1 - 1e-3) <= m.peak_sensitivity <= peak * (1 + 1e-6), loop


#: Pole-zero pairs closer than this are cancelled before the closed-loop poles are judged. The digital loops'
#: realisations carry exactly cancelling pairs at z = 1: the resolver's differencing (1 - 1/z) against the motor
#: angle's integrator (speed loop), the load cell's position against the piston's (force loop). Rounding puts
#: the uncancelled copy at 1 +- 1e-7 (0.99999992 with one BLAS kernel, 1.00000006 with another), so the raw poles
#: cannot decide stability; the pairs sit 1e-7 apart, 10x below this tolerance, and the nearest true pole (0.987)
#: is 1e4 times further from the unit circle than it.
CANCELLATION_TOLERANCE = 1e-6
#: The true closed-loop poles at nominal lie within |z| <= 0.99 (speed 0.987, position 0.990, force 0.984): a
#: stable loop must keep this much distance from the unit circle, far beyond any rounding.
STABILITY_DISTANCE = 1e-3


def test_closed_loops_are_stable_at_nominal(bench):
    """Stability on minimal realisations (the cancelled integrators removed, see CANCELLATION_TOLERANCE), with a
    distance from the stability boundary that no rounding can produce; cross-checked by the margins' own
    Nyquist view (positive gain and phase margins)."""
    import control

    systems = loop_systems(bench.values(), _load_system(bench.values()), 0.0)
    current = control.minreal(systems["current_closed"], tol=CANCELLATION_TOLERANCE, verbose=False)
    assert np.all(current.poles().real < -STABILITY_DISTANCE)
    for loop in ("speed", "position", "force"):
        minimal = control.minreal(systems[f"{loop}_closed"], tol=CANCELLATION_TOLERANCE, verbose=False)
        assert np.all(np.abs(minimal.poles()) < 1.0 - STABILITY_DISTANCE), loop
    margins = loop_margins(bench.values(), _load_system(bench.values()), 0.0)
    for loop in LOOPS:
        assert margins[loop].phase_margin > 0 and margins[loop].gain_margin > 0, loop


def _documented():
    """The 'as the twin runs the loops' table of docs/control_design.md: {row: (fc, GM, PM, |S|max)}."""
    text = DOC.read_text(encoding="utf-8").split("## Margins as the twin runs the loops", 1)[1]
    rows = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 5 and cells[1].endswith("Hz"):
            numbers = [float(re.sub(r"[^0-9.inf]", "", c)) for c in cells[1:]]
            rows[cells[0].split(" (")[0]] = tuple(numbers)
    return rows


def test_nominal_margins_are_the_documented_ones(bench):
    """docs/control_design.md prints the nominal margins to 2 decimals (crossover to 0.01 Hz, |S|max to 0.001):
    a mismatch beyond half the last printed digit means the docs are stale."""
    documented = _documented()
    assert {"current", "speed", "position", "force at 0 N", "force at 4 kN"} <= set(documented)
    p = bench.values()
    for force, label in ((0.0, "force at 0 N"), (4000.0, "force at 4 kN")):
        margins = loop_margins(p, _load_system(p), force)
        rows = {"current": margins["current"], "speed": margins["speed"], "position": margins["position"],
                label: margins["force"]}
        for row, m in rows.items():
            fc, gm, pm, peak = documented[row]
            assert m.crossover_frequency == pytest.approx(fc, abs=0.0051 if fc < 100 else 0.051), row
            assert m.gain_margin == pytest.approx(gm, abs=0.0051) if math.isfinite(gm) else math.isinf(m.gain_margin)
            assert m.phase_margin == pytest.approx(pm, abs=0.0051), row
            assert m.peak_sensitivity == pytest.approx(peak, abs=0.00051), row


def test_margins_against_the_designs(bench):
    """The current and force loops are the designs' own models: their margins are the design figures (current: same
    continuous loop, 0.01 deg; force: the design lacks only the load cell's 26 us mean refresh delay, 0.1 deg of phase
    at 10 Hz and 0.1 dB of gain margin). The digital motion loops run without the design's one-sample computation
    delay, so they keep more margin than designed, by at most that delay's phase at crossover plus the integral's
    discretisation (speed: 360 fc Ts = 2.6 deg)."""
    p = bench.values()
    designs = design_loops(p)
    force_design = design_force_loop({k: v for k, v in _load_system(p).items() if k.startswith("pneumatics.")})
    margins = loop_margins(p, _load_system(p), 4000.0)
    assert margins["current"].phase_margin == pytest.approx(designs["current"].phase_margin_deg, abs=0.01)
    assert margins["current"].crossover_frequency == pytest.approx(designs["current"].crossover_hz, rel=1e-3)
    assert margins["force"].phase_margin == pytest.approx(force_design["phase_margin_deg"], abs=0.15)
    assert margins["force"].gain_margin == pytest.approx(force_design["gain_margin_db"], abs=0.15)
    speed = margins["speed"]
    assert 0 < speed.phase_margin - designs["speed"].phase_margin_deg < 360 * speed.crossover_frequency * 125e-6
    assert speed.gain_margin > designs["speed"].gain_margin_db
    assert margins["position"].phase_margin > designs["position"].phase_margin_deg
    assert margins["position"].gain_margin > designs["position"].gain_margin_db


def test_margins_move_with_the_plant(bench):
    """A weaker motor (torque constant -10 %) lowers the speed loop's crossover in proportion (the loop gain is
    proportional to k_t/J around crossover) and the fixed-gain loop keeps its stability."""
    p = dict(bench.values())
    nominal = loop_margins(p, loops=("speed",))["speed"]
    p["motor.torque_constant"] *= 0.9
    weaker = loop_margins(p, loops=("speed",))["speed"]
    assert weaker.crossover_frequency == pytest.approx(0.9 * nominal.crossover_frequency, rel=0.03)
    assert weaker.gain_margin == pytest.approx(nominal.gain_margin - 20 * math.log10(0.9), abs=0.05)


def test_position_sample_time_must_be_a_multiple_of_the_drive_sample(bench):
    p = dict(bench.values())
    p["controller.position_loop_sample_time"] = 1.1e-3 + 1e-5
    with pytest.raises(ValueError, match="controller.position_loop_sample_time"):
        loop_margins(p, loops=("position",))


def test_python_control_is_not_loaded_by_margins():
    """Contract: python-control loads lazily (only designs and the cross-check need it)."""
    import subprocess
    import sys

    code = ("import sys; from twin.parameters import load_parameters; from twin.control.margins import loop_margins; "
            "loop_margins(load_parameters('bench').values()); print('control' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "False"
