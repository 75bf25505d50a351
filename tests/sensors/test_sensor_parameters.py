"""The sensors parameter file: Table 9.5 coverage, bounds, units, docs mapping, validation."""

import math
import re
import tomllib
from pathlib import Path

import pytest

from sensors.parameters import sensor_values
from twin.parameters import BUILTIN_DIR, load_parameters

SENSORS_TOML = BUILTIN_DIR / "bench" / "sensors.toml"

ROOT = Path(__file__).resolve().parents[2]

# Table 9.5 rows of the sensor groups (Bertolino 2020, Sec. 9.4), transcribed.
TABLE_9_5_SENSOR_ROWS = {
    "Torque meter / Sensitivity range 1: ±0.2 %Nom, G",
    "Torque meter / Sensitivity range 2: ±0.2 %Nom, G",
    "Torque meter / Temperature on offset range 1: ±0.01 %FS/K, G",
    "Torque meter / Temperature on offset range 2: ±0.02 %FS/K, G",
    "Torque meter / Temperature on sensitivity range 1: ±0.015 %Nom/K, G",
    "Torque meter / Temperature on sensitivity range 2: ±0.03 %Nom/K, G",
    "Load cell / Repeatability: ±0.085 %Read, G",
    "Load cell / Offset: ±0.02 %FS, G",
    "Load cell / Temperature on offset: ±0.03 %FS/K, G",
    "Load cell / Sensitivity: ±0.1 %Nom, G",
    "Load cell / Temperature on sensitivity: ±0.011 %Nom/K, G",
    "Preload load cell / Accuracy: ±0.2 %Nom, G",
    "Preload load cell / Sensitivity range 1: ±0.5 %Nom, G",
    "Preload load cell / Sensitivity range 2: ±0.5 %Nom, G",
    "Preload load cell / Temperature on offset range 1: ±0.02 %FS/K, G",
    "Preload load cell / Temperature on offset range 2: ±0.02 %FS/K, G",
    "Preload load cell / Temperature on sensitivity range 1: ±0.02 %Nom/K, G",
    "Preload load cell / Temperature on sensitivity range 2: ±0.02 %Nom/K, G",
    "Preload load cell conditioning module / Temperature on offset: ±0.0015 %FS/K, G",
    "Preload load cell conditioning module / Temperature on sensitivity range 1: ±0.0015 %Nom/K, G",
    "Preload load cell conditioning module / Temperature on sensitivity range 2: ±0.0015 %Nom/K, G",
    "Linear encoder / Precision: -5÷5 µm, G",
    "Linear encoder / Tolerance between phases: -45÷45 deg, G",
    "Linear encoder / Asymmetry in each phase: -15÷15 deg, G",
    "Motor resolver / Offset: ±0.02 %FS, G",
    "Motor resolver / Resolution: 0.8 ′, C",
    "Motor resolver / Accuracy: ±10 ′, G",
    "Torque meter encoder / Tolerance between phases: -45÷45 deg, G",
    "Torque meter encoder / Asymmetry in each phase: -15÷15 deg, G",
    "Electrical noise / Electrical noise: ±2.5 %FS, U",
}
OTHER_GROUP_TARGETS = [
    "room_temperature",
    "supply_pressure",
    "reducer.torsional_stiffness",
    "reducer.backlash",
    "motor.winding_resistance_20C",
    "motor.torque_constant",
    "motor.speed_constant",
    "motor.inertia",
]
UNIT_SCALE = {"%Nom": 1e-2, "%FS": 1e-2, "%Read": 1e-2, "%Nom/K": 1e-2, "%FS/K": 1e-2,
              "µm": 1e-6, "deg": math.pi / 180, "′": math.pi / 10800}


@pytest.fixture(scope="module")
def entries():
    return tomllib.loads(SENSORS_TOML.read_text())


def test_every_sensor_row_of_table_9_5_maps_to_exactly_one_parameter(entries):
    rows = [e["table_9_5"] for e in entries.values() if "table_9_5" in e]
    assert sorted(rows) == sorted(TABLE_9_5_SENSOR_ROWS)
    assert len(rows) == len(set(rows)) == 30


def test_gaussian_rows_have_nominal_zero_and_the_table_range_as_bounds(entries):
    pattern = re.compile(r": (?:±\s*(?P<h>[\d.]+)|-(?P<lo>[\d.]+)÷(?P<hi>[\d.]+)) (?P<unit>\S+), G$")
    for key, e in entries.items():
        if not e.get("table_9_5", "").endswith(", G"):
            continue
        m = pattern.search(e["table_9_5"])
        assert m, key
        half = float(m["h"] or m["hi"]) * UNIT_SCALE[m["unit"]]
        assert e["value"] == 0.0, key
        assert e["min"] == pytest.approx(-half, rel=1e-12) and e["max"] == pytest.approx(half, rel=1e-12), key


def test_constant_and_uniform_rows(entries):
    assert entries["resolver_resolution"]["value"] == pytest.approx(0.8 * math.pi / 10800, rel=1e-12)
    assert entries["electrical_noise_half_width"]["value"] == 0.025


def test_every_entry_is_well_formed(entries):
    units = {"1", "1/K", "K", "m", "rad", "V", "N", "N*m", "s", "1/s"}
    for key, e in entries.items():
        assert e["unit"] in units, key
        assert ("source" in e) != ("assumption" in e), key
        assert set(e) <= {"value", "unit", "source", "assumption", "min", "gt", "max", "table_9_5",
                          "table_9_5_extension"}, key
        assert any(b in e for b in ("min", "gt", "max")), key  # every value is bounded somewhere


def test_docs_map_every_row_including_other_groups(entries):
    doc = (ROOT / "docs" / "sensors.md").read_text()
    for key, e in entries.items():
        if "table_9_5" in e:
            assert f"`sensors.{key}`" in doc, key
    for target in OTHER_GROUP_TARGETS:
        assert f"`{target}`" in doc, target


def test_sensor_values_keep_their_group_and_name_a_missing_one():
    values = sensor_values({"motor.inertia": 1.0, "sensors.linear_encoder_precision": 4e-6})
    assert values == {"sensors.linear_encoder_precision": 4e-6}
    with pytest.raises(ValueError, match="sensors.linear_encoder_resolution: missing"):
        values["sensors.linear_encoder_resolution"]


def test_bad_sensor_values_are_refused_by_the_parameter_set_naming_each_field():
    """Bounds are checked once, by the parameter set that holds the values (sensors take them as data)."""
    with pytest.raises(ValueError) as err:
        load_parameters(SENSORS_TOML).with_values(
            {"sensors.linear_encoder_phase_error": 1.0, "sensors.no_such_sensor": 0.0, "sensors.daq_bits": 1.0}
        )
    message = str(err.value)
    for field in ("sensors.linear_encoder_phase_error", "sensors.no_such_sensor", "sensors.daq_bits"):
        assert field in message


def test_the_values_of_a_parameter_set_pass_unchanged():
    ps = load_parameters(SENSORS_TOML).with_values({"sensors.linear_encoder_precision": -3e-6})
    values = sensor_values(ps.values())
    assert values["sensors.linear_encoder_precision"] == -3e-6
    assert len(values) == len(ps)


#: Uncertainties the bench has and Table 9.5 does not list (issue 33): nominal = the model before them.
EXTENSION_ROWS = {
    "linear_encoder_mounting_phase": ("1", 0.0, 1.0, "Linear encoder / Mounting phase: 0÷1 signal period (4 µm), U"),
    "torque_meter_encoder_mounting_phase": (
        "1", 0.0, 1.0, "Torque meter encoder / Mounting phase: 0÷1 signal period (2π/2000 rad), U"),
    "resolver_mounting_angle": ("rad", 0.0, 2 * math.pi, "Motor resolver / Mounting angle: 0÷2π rad, U"),
}


def test_extension_rows_are_marked_nominal_zero_bounded_and_documented(entries):
    """The mounting phases and angle: nominal 0 (nothing moves unless a campaign samples them), bounds one period,
    an assumption that says it extends Table 9.5, the proposed row as its `table_9_5_extension` key, and a place in
    docs/sensors.md."""
    doc = (ROOT / "docs" / "sensors.md").read_text()
    for key, (unit, low, high, row) in EXTENSION_ROWS.items():
        e = entries[key]
        assert e["value"] == 0.0 and e["unit"] == unit, key
        assert e["min"] == low and e["max"] == pytest.approx(high, rel=1e-15), key
        assert e["assumption"].startswith("EXTENSION of Table 9.5"), key
        assert "table_9_5" not in e, key  # not a thesis row
        assert e["table_9_5_extension"] == row, key
        assert f"`sensors.{key}`" in doc and row in doc, key
