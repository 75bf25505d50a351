"""The controller gains in the parameter file are the documented python-control design, with its margins."""

import pytest

from twin.control.design import design_loops
from twin.control.discrete import pi_step

FILE_KEYS = {"current": ("controller.current_kp", "controller.current_ki"),
             "speed": ("controller.speed_kp", "controller.speed_ki"),
             "position": ("controller.position_kp", "controller.position_ki")}


@pytest.fixture(scope="module")
def designs(bench):
    return design_loops(bench.values())


@pytest.mark.parametrize("loop", sorted(FILE_KEYS))
def test_file_gains_match_design(bench, designs, loop):
    kp_name, ki_name = FILE_KEYS[loop]
    assert bench.value(kp_name) == pytest.approx(designs[loop].kp, rel=1e-5)
    assert bench.value(ki_name) == pytest.approx(designs[loop].ki, rel=1e-5)


def test_margins_and_cascade_separation(designs):
    for d in designs.values():
        assert d.phase_margin_deg > 45.0, d.name
        assert d.gain_margin_db > 6.0, d.name
    # each loop well inside the next: bandwidth ratio >= 5
    assert designs["current"].bandwidth_hz > 5 * designs["speed"].bandwidth_hz
    assert designs["speed"].bandwidth_hz > 5 * designs["position"].bandwidth_hz


def test_speed_loop_below_torsional_mode(bench, designs):
    """The 58 Hz speed crossover stays well below the ~350 Hz torsional mode of couplings + torque meter."""
    import math

    from twin.control.design import _reflected_inertias, torsional_stiffness

    j1, j2 = _reflected_inertias(bench.values())
    mode_hz = math.sqrt(torsional_stiffness(bench.values()) * (1 / j1 + 1 / j2)) / (2 * math.pi)
    assert designs["speed"].crossover_hz < mode_hz / 4


def test_pi_anti_windup_stops_integrating_in_saturation():
    out, integral = pi_step(10.0, 0.0, 1.0, 1.0, 0.1, 2.0)
    assert out == 2.0 and integral == 0.0  # saturated, error pushes further: integration held
    out, integral = pi_step(-1.0, 0.5, 1.0, 1.0, 0.1, 2.0)
    assert out == pytest.approx(-0.5) and integral == pytest.approx(0.4)
    out, integral = pi_step(-10.0, 0.5, 1.0, 1.0, 0.1, 2.0)  # saturated low, error pushes lower: held
    assert out == -2.0 and integral == 0.5
    out, integral = pi_step(-1.0, 4.0, 1.0, 1.0, 0.1, 2.0)  # saturated high by a wound-up integral: unwinds
    assert out == 2.0 and integral == pytest.approx(3.9)


def test_ideal_current_loop_bandwidth_is_the_design(bench, designs):
    """The ideal current-loop fidelity lags at the designed loop's closed-loop -3 dB bandwidth."""
    assert bench.value("controller.current_loop_bandwidth") == pytest.approx(designs["current"].bandwidth_hz, rel=1e-3)
