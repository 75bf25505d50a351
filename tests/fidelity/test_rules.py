"""Automatic fidelity selection: rules as data, each decision explained, bad input refused.

The rules alone (``speed_file=None``): the gate by measured speed is tests/fidelity/test_speed_gate.py."""

import os

import pytest

import twin
from twin.fidelity import SUBSYSTEMS, load_rules, resolve_fidelity
from twin.fidelity.rules import RULES_FILE
from twin.layout import N_STATES, S


def test_every_subsystem_decided_and_explained(bench):
    fidelity = resolve_fidelity(twin.load_scene("ds2"), bench)
    assert list(fidelity.levels) == list(SUBSYSTEMS)
    assert all(fidelity.reasons[name] for name in SUBSYSTEMS)
    text = fidelity.explain()
    for name, level in fidelity.levels.items():
        assert name in text and level in text
    assert f"integrated states: {fidelity.active_states.size} of {N_STATES}" in text


def test_thesis_data_set_keeps_what_its_feature_needs(bench):
    """ds2 asks for the Eq. 9.12 feature on measured and true signals: the encoders and the Hertz contact stay,
    the cylinder stays (it is fixed to the sled), the current loop and the thermal model go."""
    levels = resolve_fidelity(twin.load_scene("ds2"), bench, speed_file=None).levels
    assert levels["encoders"] == "full" and levels["contact"] == "variable_angle"
    assert levels["pneumatics"] == "full"
    assert levels["current_loop"] == "ideal" and levels["motor_thermal"] == "frozen"
    assert levels["nut_rotation"] == "off" and levels["torque_meter_refresh"] == "ideal"


def test_all_outputs_means_full_detail_where_it_shows(bench):
    """A scene naming no outputs asks for all of them: every subsystem an output can see keeps its full level. The
    one reduction is the screw's axial mass (the quasi-static level, the automatic choice whatever the outputs): its
    3.8-4.8 kHz mode lies far above every motion a scene commands, so no output resolves it."""
    fidelity = resolve_fidelity(twin.load_scene("nominal"), bench, speed_file=None)
    reduced = {name for name, level in fidelity.levels.items() if level != SUBSYSTEMS[name].full}
    assert reduced == {"screw_axial"} and fidelity.level("screw_axial") == "quasi_static"
    assert "axial mode" in fidelity.reasons["screw_axial"]
    assert "requested: winding_temperature" in fidelity.reasons["motor_thermal"]


def test_position_only_study_drops_the_encoders(bench):
    fidelity = resolve_fidelity(twin.load_scene("ds4"), bench, outputs=["backlash_feature_true", "nut1_position"],
                                speed_file=None)
    assert fidelity.level("encoders") == "ideal"
    assert fidelity.level("contact") == "variable_angle"


def test_motor_only_outputs_linearise_the_contact(bench):
    fidelity = resolve_fidelity(twin.load_scene("ds4"), bench, outputs=["motor_speed"], speed_file=None)
    assert fidelity.level("contact") == "linear"


def test_rules_react_to_parameters(bench):
    """Soft guides make the nut roll visible: the rule keeps it; a weak DC bus keeps the full current loop."""
    scene = twin.load_scene("ds5")
    soft = resolve_fidelity(scene, bench.with_values({"sled.guide_roll_stiffness": 300.0}), speed_file=None)
    assert soft.level("nut_rotation") == "on" and "limit 5 nm" in soft.reasons["nut_rotation"]
    weak_bus = resolve_fidelity(scene, bench.with_values({"drive.dc_bus_voltage": 100.0}), speed_file=None)
    assert weak_bus.level("current_loop") == "full" and "of the inverter's limit" in weak_bus.reasons["current_loop"]


def test_thermal_rule_follows_duration_when_the_current_loop_is_full(bench):
    outputs = ["backlash_feature", "motor_current"]  # the current keeps the full loop
    short = resolve_fidelity(twin.load_scene("ds5").with_duration(5.0), bench, outputs=outputs, speed_file=None)
    long = resolve_fidelity(twin.load_scene("ds5").with_duration(60.0), bench, outputs=outputs, speed_file=None)
    assert short.level("current_loop") == "full"
    assert short.level("motor_thermal") == "frozen" and "duration / tau_w = 0.042" in short.reasons["motor_thermal"]
    assert long.level("motor_thermal") == "dynamic"


def test_requested_levels_override_auto_and_say_so(bench):
    fidelity = resolve_fidelity(twin.load_scene("ds2"), bench, {"current_loop": "full", "default": "auto"})
    assert fidelity.level("current_loop") == "full" and fidelity.reasons["current_loop"] == "requested"
    full = resolve_fidelity(twin.load_scene("ds2"), bench, "full")
    # every state, the seals' deflection of the elasto-plastic seal level (the full level, twin.levels) included
    assert full.active_states.size == N_STATES and S.SEAL_DEFLECTION in full.active_states
    regularised = resolve_fidelity(twin.load_scene("ds2"), bench, {"default": "full", "seal_friction": "regularised"})
    assert regularised.active_states.size == N_STATES - 1 and S.SEAL_DEFLECTION not in regularised.active_states


def test_removed_states_leave_the_integrated_vector(bench):
    fidelity = resolve_fidelity(twin.load_scene("ds2"), bench, speed_file=None)
    removed = set(fidelity.removed_states)
    assert {S.HALL_CURRENT, S.CURRENT_PI, S.WINDING_TEMP, S.NUT1_ANGLE, S.NUT2_ANGULAR_SPEED} <= removed
    assert not removed & set(fidelity.active_states.tolist())
    ds = twin.simulate("ds2", duration=0.2, fidelity=dict(fidelity.levels))
    assert ds.attrs["integrated_states"] == fidelity.active_states.size == ds.sizes["state"]
    assert "winding_temp" not in ds.state.values and "winding_temperature" not in ds


@pytest.mark.parametrize("fidelity, outputs, message", [
    ({"gearbox": "full"}, None, "fidelity.gearbox: unknown subsystem"),
    ({"contact": "rigid"}, None, "fidelity.contact: level 'rigid' is not one of auto, variable_angle"),
    ("cheap", None, "'cheap' is not 'auto', 'full'"),
    ({"default": "some"}, None, "'some' is not 'auto', 'full'"),
    ({"pneumatics": "absent"}, None, "'absent' cannot apply the force demand"),
    ({"motor_thermal": "frozen"}, ["winding_temperature"],
     "does not produce the requested output(s) winding_temperature"),
    ("auto", ["backlash_feature", "speedometer"], "outputs: 'speedometer' is not a signal or feature"),
])
def test_bad_fidelity_input_is_a_clear_error(bench, fidelity, outputs, message):
    with pytest.raises(twin.OptionError) as info:
        twin.simulate("nominal", bench, fidelity=fidelity, outputs=outputs, duration=0.01)
    assert message in str(info.value)


def test_scene_outputs_are_validated():
    with pytest.raises(twin.SceneError, match="outputs: 'torque_ripple' is not a signal or feature"):
        twin.scenes.scene_from_dict({"duration": 1.0, "outputs": ["torque_ripple"], "conditions": {
            "preload": 0.0, "preload_configuration": "O", "backlash": 0.0, "room_temperature": 298.15,
            "supply_pressure": 7e5}})


def test_rules_file_is_checked(tmp_path):
    bad = tmp_path / "rules.toml"
    bad.write_text('[settings]\ncontact_load_allowance = 200.0\nhot_winding_temperature_rise = 130.0\n[[rules]]\n'
                   'subsystem = "contact"\nlevel = "rigid"\n'
                   'because = "x"\nmax_softness = 1.0\n')
    with pytest.raises(twin.OptionError) as info:
        load_rules(bad)
    assert "rules[0].level: 'rigid'" in str(info.value) and "unknown condition(s) max_softness" in str(info.value)
    bad.write_text('[settings]\ncontact_load_allowance = 200.0\n')
    with pytest.raises(twin.OptionError, match="settings.hot_winding_temperature_rise: missing or not a number"):
        load_rules(bad)


def test_force_demand_condition_as_data(tmp_path, bench):
    """A rules file is data: a project may drop the cylinder on force-free tests (the shipped rules do not,
    see rules.toml) and the decision cites the condition."""
    rules = tmp_path / "rules.toml"
    rules.write_text('[settings]\ncontact_load_allowance = 200.0\nhot_winding_temperature_rise = 130.0\n'
                     'min_lane_speedup = 1.10\n[[rules]]\nsubsystem = "pneumatics"\n'
                     'level = "absent"\nbecause = "cylinder disconnected for force-free tests"\nforce_demand = false\n')
    free = resolve_fidelity(twin.load_scene("ds2"), bench, rules_file=rules, speed_file=None)
    loaded = resolve_fidelity(twin.load_scene("ds3"), bench, rules_file=rules, speed_file=None)
    assert free.level("pneumatics") == "absent" and "force demand none" in free.reasons["pneumatics"]
    assert loaded.level("pneumatics") == "full" and "force demand present" in loaded.reasons["pneumatics"]


def test_rules_file_parsed_once_and_again_when_it_changes(tmp_path):
    """The parse is cached per file version: the same objects while the file is unchanged, the new rules as soon
    as it is rewritten (another size and modification time)."""
    path = tmp_path / "rules.toml"
    original = RULES_FILE.read_text()
    path.write_text(original)
    settings, rules = load_rules(path)
    assert load_rules(path)[1] is rules
    path.write_text(original + '\n[[rules]]\nsubsystem = "motor_thermal"\nlevel = "frozen"\nbecause = "test"\n')
    os.utime(path, ns=(path.stat().st_atime_ns, path.stat().st_mtime_ns + 10**9))
    changed = load_rules(path)[1]
    assert len(changed) == len(rules) + 1 and changed[-1]["because"] == "test"
