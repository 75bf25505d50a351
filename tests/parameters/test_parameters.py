"""Parameter sets: provenance of every value, validation of files and overrides."""

import pytest

import twin
from twin.errors import ParameterError


def test_every_parameter_has_unit_and_provenance(bench):
    for p in bench._parameters.values():
        assert p.unit, p.name
        assert (p.source is None) != (p.assumption is None), p.name
        assert (p.source or p.assumption).strip(), p.name


def test_override_validates_and_lists_every_problem(bench):
    with pytest.raises(ParameterError) as info:
        bench.with_values({"motor.inertia": -1.0, "ball_screw.elastic_modulus": 0.0, "motor.nonsense": 1.0,
                           "reducer.backlash": float("nan")})
    problems = info.value.problems
    assert len(problems) == 4
    text = str(info.value)
    for name in ("motor.inertia", "ball_screw.elastic_modulus", "motor.nonsense", "reducer.backlash"):
        assert name in text
    assert "allowed: > 0" in text


def test_override_returns_new_set(bench):
    changed = bench.with_values({"motor.inertia": 1.6e-4})
    assert changed.value("motor.inertia") == 1.6e-4
    assert bench.value("motor.inertia") == 1.5e-4


def test_malformed_file_reports_field(tmp_path):
    (tmp_path / "motor.toml").write_text('[inertia]\nvalue = -2.0\nunit = "kg*m^2"\nsource = "x"\ngt = 0.0\n'
                                        '[mass]\nvalue = 1.0\nunit = "kg"\n'
                                        '[bad]\nvalue = 1.0\nunit = "kg"\nsource = "a"\nassumption = "b"\ncolour = 3\n')
    with pytest.raises(ParameterError) as info:
        twin.load_parameters(tmp_path)
    text = str(info.value)
    assert "motor.inertia" in text and "motor.mass" in text and "motor.bad" in text and "colour" in text


def test_unknown_set_name():
    with pytest.raises(ParameterError, match="built-in set"):
        twin.load_parameters("no_such_set")


def test_table_9_5_rows_are_tagged(bench):
    tagged = [p for p in bench._parameters.values() if p.table_9_5]
    groups = {p.table_9_5.split("/")[0].strip() for p in tagged}
    assert {"Motor", "Reducer"} <= groups


def test_repr_is_short_and_names_the_set(bench):
    """A parameter set at the prompt: its name, its count and a few values, never all 200 (to_frame has them)."""
    text = repr(bench)
    assert text.startswith("ParameterSet('bench', ") and f"{len(bench)} parameters" in text
    first = bench[bench.names[0]]
    assert f"{first.name}={first.value:g} {first.unit}" in text
    assert text.count("=") == 3 and "to_frame()" in text and "\n" not in text


def test_table_as_a_data_frame(bench):
    frame = bench.to_frame()
    assert list(frame.columns) == ["value", "unit", "source"] and frame.index.name == "name"
    assert len(frame) == len(bench) and frame.index.is_unique
    assert frame.loc["motor.inertia", "value"] == bench.value("motor.inertia")
    assert frame.loc["motor.inertia", "unit"] == bench["motor.inertia"].unit
    assumed = next(bench[name] for name in bench if bench[name].is_assumption)
    assert frame.loc[assumed.name, "source"] == f"ASSUMPTION: {assumed.assumption}"


def test_packages_list_their_lazy_names_and_the_version():
    """``dir(twin)`` and ``dir(campaigns)`` show the names imported on first use (tab completion finds them), and
    ``twin.__version__`` is the installed package's."""
    from importlib import metadata

    import campaigns

    assert set(twin.__all__) <= set(dir(twin)) and "__version__" in dir(twin)
    assert set(campaigns.__all__) <= set(dir(campaigns))
    assert twin.__version__ == metadata.version("benchtwin")


def test_a_count_takes_whole_numbers_only(tmp_path):
    """``integer = true`` marks a count: a fraction is refused with the field and what is allowed, the flag itself
    must be a boolean."""
    (tmp_path / "nut.toml").write_text('[balls]\nvalue = 22.0\nunit = "1"\nsource = "x"\nmin = 1.0\ninteger = true\n')
    nut = twin.load_parameters(tmp_path)
    assert nut.with_values({"nut.balls": 3}).value("nut.balls") == 3.0
    with pytest.raises(ParameterError, match=r"nut.balls: value 2.5 1 is not a whole number; allowed: a whole "
                                             r"number >= 1"):
        nut.with_values({"nut.balls": 2.5})
    (tmp_path / "nut.toml").write_text('[balls]\nvalue = 22.0\nunit = "1"\nsource = "x"\ninteger = "yes"\n')
    with pytest.raises(ParameterError, match="nut.balls.integer: must be true or false"):
        twin.load_parameters(tmp_path)
