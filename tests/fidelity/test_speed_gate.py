"""The gate of the automatic fidelity: the rules' levels only where the stored speedup pays for them.

Every test reads its own speed file (and, where the threshold matters, its own rules file), so none depends on a
timing: the measured speedups of the shipped ``twin/fidelity/speed.toml`` are data, checked here only for their form.
"""

import pytest

import twin
from twin.fidelity import SUBSYSTEMS, resolve_fidelity
from twin.fidelity.rules import RULES_FILE, SPEED_FILE, load_speedups
from twin.scenes import list_scenes

MEASUREMENT = '[measurement]\nmachine = "test"\ndate = "2026-01-01"\nload = "0.00"\nlanes = 16\nrepeats = 5\n'


def speed_file(tmp_path, **speedups):
    path = tmp_path / "speed.toml"
    path.write_text(MEASUREMENT + "".join(f"[scenes.{name}]\nspeedup = {value}\n" for name, value in speedups.items()))
    return path


def reduced(fidelity) -> dict[str, str]:
    return {name: level for name, level in fidelity.levels.items() if level != SUBSYSTEMS[name].full}


def test_below_the_threshold_every_simplified_subsystem_keeps_its_full_level(tmp_path, bench):
    """ds2 at 1.06x: what the rules would simplify (current loop, thermal model, nut roll, torque-meter refresh) runs
    full, and each reason gives the number, the file and the threshold; nothing else changes."""
    scene = twin.load_scene("ds2")
    rules_alone = resolve_fidelity(scene, bench, speed_file=None)
    gated = resolve_fidelity(scene, bench, speed_file=speed_file(tmp_path, ds2=1.06))
    assert reduced(rules_alone) and not reduced(gated)
    assert gated.levels == resolve_fidelity(scene, bench, "full").levels
    for name, level in reduced(rules_alone).items():
        reason = gated.reasons[name]
        assert reason.startswith("automatic levels buy 1.06x on ds2 (") and "below 1.10x: full model" in reason
        assert f"the rules would take {level}: " in reason
    kept = set(SUBSYSTEMS) - set(reduced(rules_alone))
    assert all(gated.reasons[name] == rules_alone.reasons[name] for name in kept)


def test_at_or_above_the_threshold_the_rules_apply_and_say_what_they_buy(tmp_path, bench):
    scene = twin.load_scene("ds1")
    rules_alone = resolve_fidelity(scene, bench, speed_file=None)
    paying = resolve_fidelity(scene, bench, speed_file=speed_file(tmp_path, ds1=1.37))
    assert paying.levels == rules_alone.levels and reduced(paying)
    assert all("automatic levels buy 1.37x on ds1" in paying.reasons[name] and "at least 1.10x" in paying.reasons[name]
               for name in reduced(paying))
    exactly = resolve_fidelity(scene, bench, speed_file=speed_file(tmp_path, ds1=1.10))
    assert exactly.levels == rules_alone.levels


def test_the_threshold_is_the_rules_file_setting(tmp_path, bench):
    rules = tmp_path / "rules.toml"
    rules.write_text(RULES_FILE.read_text().replace("min_lane_speedup = 1.10", "min_lane_speedup = 1.5"))
    gated = resolve_fidelity(twin.load_scene("ds1"), bench, rules_file=rules,
                             speed_file=speed_file(tmp_path, ds1=1.37))
    assert not reduced(gated) and "below 1.50x: full model" in gated.reasons["current_loop"]


def test_explicit_requests_and_scene_conditions_are_untouched(tmp_path, bench):
    """A level asked for by name stays, and so does the level a scene's condition fixes (a detached cylinder); only
    what is left to "auto" is gated. A request with nothing left to "auto" never reads the speed file."""
    slow = speed_file(tmp_path, ds2=1.01, chapter7_backlash=1.01)
    mixed = resolve_fidelity(twin.load_scene("ds2"), bench, {"current_loop": "ideal", "default": "auto"},
                             speed_file=slow)
    assert mixed.level("current_loop") == "ideal" and mixed.reasons["current_loop"] == "requested"
    assert reduced(mixed) == {"current_loop": "ideal"}
    detached = resolve_fidelity(twin.load_scene("chapter7_backlash"), bench, speed_file=slow)
    assert detached.level("pneumatics") == "absent" and "detached" in detached.reasons["pneumatics"]
    missing = tmp_path / "nowhere.toml"
    assert resolve_fidelity(twin.load_scene("ds2"), bench, "full", speed_file=missing).levels == \
        resolve_fidelity(twin.load_scene("ds2"), bench, "full").levels


def test_a_data_set_derived_from_a_built_in_scene_finds_its_measurement(tmp_path, bench):
    """A campaign's data set runs its scene with other conditions (a sweep level: ds2 with 1 um backlash) or another
    procedure; the scene keeps its name, so the base scene's measurement gates it."""
    level = twin.load_scene("ds2").with_conditions({"backlash": "1 um"})
    assert level.name == "ds2"
    assert not reduced(resolve_fidelity(level, bench, speed_file=speed_file(tmp_path, ds2=1.06)))


def test_a_scene_without_a_measurement_takes_the_rules_and_says_so(tmp_path, bench):
    """A user's scene has no stored speedup: the rules apply as without a gate (the recommended default: the rules'
    physics conditions are what they were accepted on), and the reason says that nothing is stored."""
    data = twin.load_scene("ds2").to_dict() | {"name": "my_bench_test"}
    scene = twin.scenes.scene_from_dict(data)
    rules_alone = resolve_fidelity(scene, bench, speed_file=None)
    unmeasured = resolve_fidelity(scene, bench, speed_file=speed_file(tmp_path, ds2=1.06))
    assert unmeasured.levels == rules_alone.levels and reduced(unmeasured)
    assert all("no speed measurement stored for scene 'my_bench_test'" in unmeasured.reasons[name]
               for name in reduced(unmeasured))


@pytest.mark.parametrize("text, message", [
    (MEASUREMENT.replace('machine = "test"\n', "") + "[scenes.ds2]\nspeedup = 1.2\n", "measurement.machine: missing"),
    ("[scenes.ds2]\nspeedup = 1.2\n", "measurement: missing table"),
    (MEASUREMENT, "scenes: missing table"),
    (MEASUREMENT + "[scenes.ds2]\nfull_cpu = 1.0\n", "scenes.ds2.speedup: missing"),
    (MEASUREMENT + "[scenes.ds2]\nspeedup = 0.0\n", "scenes.ds2.speedup: must be a positive number"),
    (MEASUREMENT + "[scenes.ds2]\nspeedup = -1.2\n", "scenes.ds2.speedup: must be a positive number"),
    (MEASUREMENT + "[scenes.ds2]\nspeedup = nan\n", "scenes.ds2.speedup: must be a positive number"),
    (MEASUREMENT + '[scenes.ds2]\nspeedup = "fast"\n', "scenes.ds2.speedup: must be a positive number"),
    (MEASUREMENT + "[scenes.ds2\n", "speed.toml: not valid TOML"),
])
def test_bad_speed_file_is_one_clear_error(tmp_path, bench, text, message):
    path = tmp_path / "speed.toml"
    path.write_text(text)
    with pytest.raises(twin.OptionError, match=message):
        resolve_fidelity(twin.load_scene("ds2"), bench, speed_file=path)


def test_missing_speed_file_and_setting_are_clear_errors(tmp_path, bench):
    with pytest.raises(twin.OptionError, match="speed_file: cannot read"):
        resolve_fidelity(twin.load_scene("ds2"), bench, speed_file=tmp_path / "nowhere.toml")
    rules = tmp_path / "rules.toml"
    rules.write_text(RULES_FILE.read_text().replace("min_lane_speedup = 1.10", ""))
    with pytest.raises(twin.OptionError, match="settings.min_lane_speedup: missing or not a number"):
        resolve_fidelity(twin.load_scene("ds2"), bench, rules_file=rules)


def test_the_shipped_measurement_covers_every_built_in_scene():
    """The stored file is complete (benchmarks/fidelity_speed.py --write measures every built-in scene)."""
    assert set(load_speedups(SPEED_FILE)) == set(list_scenes())
