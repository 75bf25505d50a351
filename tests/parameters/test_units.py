"""One parser of values with units (numerics.units):
``--set scene.backlash="20 um"``, ``with_values({"reducer.backlash":
"3 mrad"})`` and ``with_conditions({"backlash": "20 um"})`` convert to the SI unit the parameter file or the
condition table declares; a wrong dimension is one problem naming the parameter and both units."""

import pytest

import twin
from numerics.units import known_unit, value_in
from twin.errors import ParameterError, SceneError
from twin.scenes import CONDITIONS


@pytest.mark.parametrize(("text", "si_unit", "expected"), [
    # exact to the bit: the decimal product rounded once, as a file's own literal is (80 * 1e-6 in binary is not)
    ("80 um", "m", 8e-05), ("80um", "m", 8e-05), ("80 µm", "m", 8e-05), ("20 um", "m", 2e-05),
    ("3 mrad", "rad", 3e-3), ("25 degC", "K", 298.15), ("1.65e-4 kg m^2", "kg*m^2", 1.65e-4),
    ("1.65e-4 kg·m²", "kg*m^2", 1.65e-4), ("-2.5 kN", "N", -2500.0), ("7 bar", "Pa", 7e5), ("90 %", "1", 0.9),
    ("2e-5", "m", 2e-5), (" .5 ", "m", 0.5),  # a number alone is in the SI unit already
])
def test_values_with_units_convert_to_the_si_unit(text, si_unit, expected):
    assert value_in(text, si_unit) == expected


@pytest.mark.parametrize(("text", "words"), [
    ("3 mm", ["'mm' does not convert to 'rad'", "[length]", "dimensionless"]),
    ("abc", ["'abc' is not a number with an optional unit", "a number alone is in rad"]),
    ("", ["is not a number"]),
    # text pint's parser throws other errors at (TokenError, AssertionError, ZeroDivisionError, ...): the same line
    *[(f"3 {unit}", [f"unknown unit {unit!r}"]) for unit in ("deg)", "(deg", "m*", "m/", "1/0", "splines")],
])
def test_a_value_that_does_not_convert_is_one_value_error(text, words):
    with pytest.raises(ValueError) as info:
        value_in(text, "rad")
    assert all(w in str(info.value) for w in words), str(info.value)
    assert "\n" not in str(info.value)


def test_every_declared_unit_is_understood(bench):
    """Every parameter file's unit and every numeric condition's unit is one the parser reads: a value with a unit
    can be given for any of them."""
    units = {bench[name].unit for name in bench}
    units |= {c.unit for c in CONDITIONS.values() if c.numeric}
    assert [u for u in sorted(units) if not known_unit(u)] == []


def test_parameter_overrides_take_units(bench):
    changed = bench.with_values({"reducer.backlash": "3 mrad", "motor.inertia": "1.65e-4 kg m^2",
                                 "ball_screw.lead": "5 mm"})
    assert changed.value("reducer.backlash") == 3e-3
    assert changed.value("motor.inertia") == 1.65e-4
    assert changed.value("ball_screw.lead") == bench.value("ball_screw.lead") == 5e-3


def test_a_wrong_dimension_names_the_parameter_and_both_units_with_every_other_problem(bench):
    with pytest.raises(ParameterError) as info:
        bench.with_values({"reducer.backlash": "3 mm", "motor.inertia": -1.0, "motor.nonsense": "2 m"})
    problems = info.value.problems
    assert len(problems) == 3
    wrong = next(p for p in problems if p.startswith("reducer.backlash"))
    assert "'mm'" in wrong and "'rad'" in wrong and "[length]" in wrong


def test_a_converted_value_is_checked_against_the_bounds(bench):
    with pytest.raises(ParameterError, match="reducer.backlash: value -0.003 rad is out of range"):
        bench.with_values({"reducer.backlash": "-3 mrad"})
    assert bench.implausible({"ball_screw.lead": "5 m"})  # 1000 times the nominal, said in the warning
    assert bench.implausible({"ball_screw.lead": "5 N"}) == []  # not converted: with_values's error, not a warning


def test_scene_conditions_take_units():
    scene = twin.load_scene("ds2")
    assert scene.with_conditions({"backlash": "20 um"}).condition("backlash") == 2e-05
    assert scene.with_conditions({"room_temperature": "25 degC"}).condition("room_temperature") == 298.15
    assert scene.with_conditions({"supply_pressure": "7 bar"}).condition("supply_pressure") == 7e5
    assert scene.with_conditions({"zero_procedure": "preloaded"}).condition("zero_procedure") == "preloaded"
    with pytest.raises(SceneError) as info:
        scene.with_conditions({"backlash": "20 N", "preload": -1.0, "zero_procedure": "sideways"})
    problems = info.value.problems
    assert len(problems) == 3
    assert any(p.startswith("conditions.backlash:") and "'N'" in p and "'m'" in p for p in problems), problems
