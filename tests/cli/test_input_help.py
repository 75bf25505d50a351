"""Issue 30, point 5: the five input mistakes of a new user, each answered by a message that helps, before any work.

1. ``--set motor.inertai=...`` names ``motor.inertia`` (did you mean, difflib), as do misspelt spec fields,
   conditions, scenes and features;
2. ``kg m^2``, ``kg*m**2``, ``kg·m²`` (and ``kg m2``) are one unit (pint);
3. ``motor.inertia=1.65`` (10^4 x nominal) is warned about before the run, on the command line and in a spec;
4. ``backlash = 80`` in a spec is refused at validation, saying ``80 m is outside ...`` and what was likely meant;
5. a sampled range outside what its parameter allows is refused before compilation.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import pytest

import campaigns
import twin
from app.cli import main
from campaigns.runner.spec import SpecError, condition_range_problem
from campaigns.units import conversion, normalise
from twin.errors import InputError, did_you_mean

DEMO = Path(__file__).resolve().parents[2] / "campaigns" / "specs" / "demo.toml"


def _spec(tmp_path, body: str):
    path = tmp_path / "spec.toml"
    path.write_text(f'extends = "{DEMO.resolve()}"\nname = "probe"\n'
                    + textwrap.dedent(body))
    return path


def _problems(tmp_path, body: str) -> list[str]:
    with pytest.raises(SpecError) as info:
        campaigns.load_spec(_spec(tmp_path, body))
    return info.value.problems


def test_a_misspelt_parameter_names_the_one_meant(capsys):
    with pytest.raises(InputError) as info:
        twin.load_parameters("bench").with_values({"motor.inertai": 1.6e-4})
    (problem,) = info.value.problems
    assert problem.startswith("motor.inertai: unknown parameter; did you mean 'motor.inertia'?")
    assert main(["simulate", "nominal", "--set", "motor.inertai=1.6e-4", "--set", "scene.backlsh=1e-6"]) == 2
    err = capsys.readouterr().err
    assert "did you mean 'motor.inertia'?" in err and "did you mean 'backlash'?" in err


def test_did_you_mean_stays_quiet_without_a_likely_name():
    assert did_you_mean("motor.inertai", ["motor.inertia", "motor.inductance"]) == "did you mean 'motor.inertia'?"
    assert did_you_mean("gearbox.ratio", ["motor.inertia", "motor.inductance"]) == ""


def test_misspelt_spec_fields_conditions_and_targets_name_the_one_meant(tmp_path):
    problems = _problems(tmp_path, """
        [solver]
        integrater = "rk4"

        [[datasets]]
        name = "a"
        scene = "ds2"
        conditions = { backlsh = 1e-6 }

        [[uncertainties]]
        target = "motor.inertai"
        distribution = "uniform"
        half_range = 1e-6

        [observability]
        sweep = []
        """)
    assert ("solver.integrater: unknown field; did you mean 'integrator'? "
            "allowed: integrator, engine, dt, output_dt, fidelity") in problems
    assert any(p.startswith("datasets[0].conditions.backlsh: unknown condition backlsh; did you mean 'backlash'?")
               for p in problems), problems
    assert any(p.startswith("uncertainties[0]: unknown parameter 'motor.inertai'; did you mean 'motor.inertia'?")
               for p in problems), problems


@pytest.mark.parametrize("unit", ["kg m^2", "kg*m**2", "kg·m²", "kg m2", "kg*m^2", "kg⋅m^2"])
def test_every_spelling_of_a_unit_converts(unit):
    assert conversion(unit, "kg*m^2") == (1.0, 0.0)


def test_units_convert_with_their_scale_and_offset():
    assert conversion("um", "m")[0] == pytest.approx(1e-6)
    assert conversion("µm", "m")[0] == pytest.approx(1e-6)
    assert conversion("degC", "K") == pytest.approx((1.0, 273.15))
    assert conversion("deg", "rad")[0] == pytest.approx(math.pi / 180)
    assert conversion("%/K", "1/K")[0] == pytest.approx(0.01)
    assert conversion("bar", "Pa")[0] == pytest.approx(1e5)
    assert conversion("N m", "N*m")[0] == 1.0
    assert normalise("kg/m3") == "kg/m**3"
    with pytest.raises(ValueError, match="does not convert"):
        conversion("um", "N/m")
    with pytest.raises(ValueError, match="unknown unit 'furlongs per fortnite'"):
        conversion("furlongs per fortnite", "m")


def test_a_spec_row_in_any_spelling_of_the_unit_resolves_the_same(tmp_path):
    resolved = []
    for unit in ("kg m^2", "kg*m**2", "kg·m²"):
        spec = campaigns.load_spec(_spec(tmp_path, f"""
            [[uncertainties]]
            target = "motor.inertia"
            distribution = "uniform"
            low = 1.4e-4
            high = 1.6e-4
            unit = "{unit}"
            """))
        (row,) = [d for d in spec.distributions() if d.target == "motor.inertia"]
        resolved.append((row.low, row.high))
    assert resolved == [(1.4e-4, 1.6e-4)] * 3


def test_an_implausible_override_is_warned_about_before_the_run(capsys, monkeypatch):
    ran = []

    def simulate(*args, **kwargs):  # what stderr holds when the run would start
        ran.append(capsys.readouterr().err)
        raise KeyboardInterrupt

    monkeypatch.setattr(twin, "simulate", simulate)
    with pytest.raises(KeyboardInterrupt):
        main(["simulate", "nominal", "--set", "motor.inertia=1.65"])
    (err,) = ran  # the warning was printed before simulate was called
    assert "twin: warning: motor.inertia = 1.65 kg*m^2 is 1.1e+04 times its nominal" in err
    assert "unit or exponent slip" in err
    assert twin.load_parameters("bench").implausible({"motor.inertia": 1.6e-4}) == []  # 7 % off: fine


def test_an_implausible_sampled_range_is_a_spec_warning(tmp_path):
    spec = campaigns.load_spec(_spec(tmp_path, """
        [[uncertainties]]
        target = "motor.inertia"
        distribution = "uniform"
        low = 1.6
        high = 1.7
        """))
    (warning,) = spec.warnings
    assert warning.startswith("uncertainties[0]: motor.inertia = 1.65 kg*m^2 is 1.1e+04 times its nominal")


def test_a_condition_out_of_range_is_caught_at_validation_with_what_was_meant(tmp_path):
    problems = _problems(tmp_path, """
        [[datasets]]
        name = "a"
        scene = "ds2"
        conditions = { backlash = 80, preload = 0.0 }

        [observability]
        sweep = []
        """)
    assert problems == ["datasets[0].conditions: backlash: 80 m is outside the allowed range 0 ... 1e-3 m (total axial "
                        "play of each nut); spec values are in SI units: for 80 µm write 8e-05"]
    assert condition_range_problem("backlash", 5e-6) is None
    assert "for 300 degC write 573.15" not in (condition_range_problem("room_temperature", 300.0) or "")
    assert condition_range_problem("room_temperature", 25.0).endswith("for 25 degC write 298.15")


def test_a_sampled_range_outside_the_parameters_bounds_is_refused(tmp_path):
    problems = _problems(tmp_path, """
        [[uncertainties]]
        target = "motor.inertia"
        distribution = "uniform"
        low = -1e-4
        high = 2e-4
        """)
    assert problems == ["uncertainties[0]: motor.inertia: the range's low -0.0001 kg*m^2 is outside the allowed range "
                        "> 0 kg*m^2; every run drawing it would fail"]


def test_the_cli_refuses_a_bad_spec_before_any_work(tmp_path, capsys):
    path = _spec(tmp_path, """
        [[datasets]]
        name = "a"
        scene = "ds2"
        conditions = { backlash = 80, preload = 0.0 }

        [observability]
        sweep = []
        """)
    assert main(["campaign", "run", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "80 m is outside the allowed range" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
