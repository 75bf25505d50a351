"""Scenes: the shipped test procedures and validation of malformed ones."""

import numpy as np
import pytest

import twin
from twin.errors import SceneError
from twin.scenes.profiles import compile_profile, profile_value, smooth_step

TABLE_9_4 = {  # data set: (backlash [m], preload [N], external force [N])
    "ds1": (80e-6, 1000.0, 0.0), "ds2": (80e-6, 0.0, 0.0), "ds3": (0.0, 0.0, 4000.0), "ds4": (0.0, 0.0, 0.0),
    "ds5": (0.0, 1000.0, 0.0), "ds6": (5e-6, 0.0, 0.0), "ds7": (40e-6, 0.0, 0.0),
}
#: The thesis's Sec. 7.9.3 backlash runs, reproduced as scenes (docs/validation.md, chapter 7).
CHAPTER_7 = {"chapter7_backlash", "chapter7_backlash_300um", "chapter7_backlash_force"}


def test_shipped_scenes():
    assert set(twin.list_scenes()) == {"nominal", *TABLE_9_4, *CHAPTER_7}


@pytest.mark.parametrize("name", sorted(TABLE_9_4))
def test_data_set_conditions(name):
    scene = twin.load_scene(name)
    backlash, preload, force = TABLE_9_4[name]
    assert scene.condition("backlash") == backlash
    assert scene.condition("preload") == preload
    assert profile_value(scene.force_table(), scene.duration) == force
    # same command sequence as the nominal scene (Sec. 9.4)
    assert scene.position_demand == twin.load_scene("nominal").position_demand


def test_nominal_force_step_at_one_second():
    table = twin.load_scene("nominal").force_table()
    assert profile_value(table, 0.999) == 0.0
    assert profile_value(table, 1.05) == 4000.0


def test_profiles_are_continuous():
    table = twin.load_scene("nominal").position_table()
    t = np.linspace(0, 10, 200001)
    values = np.array([profile_value(table, x) for x in t])
    assert np.max(np.abs(np.diff(values))) < 1e-5  # < 10 um per 50 us: no jumps


def test_smooth_step_eq_7_56():
    assert smooth_step(0.5, 0.0, 0.0, 1.0, 2.0) == pytest.approx(1.0)
    assert smooth_step(-1.0, 0.0, 0.0, 1.0, 2.0) == 0.0 and smooth_step(2.0, 0.0, 0.0, 1.0, 2.0) == 2.0


def test_malformed_scene_lists_every_problem(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('duration = -1\ncolour = 3\n[conditions]\npreload = -5.0\nbacklash = 1.0\n'
                    'preload_configuration = "Z"\nroom_temperature = 298.0\nsupply_pressure = 7e5\n'
                    '[[position_demand]]\nkind = "jump"\nend = 1.0\n'
                    '[[position_demand]]\nkind = "ramp"\nend = 0.5\nto = 1.0\n')
    with pytest.raises(SceneError) as info:
        twin.load_scene(path)
    assert "colour" in str(info.value)
    path.write_text(path.read_text().replace("colour = 3\n", ""))
    with pytest.raises(SceneError) as info:
        twin.load_scene(path)
    text = str(info.value)
    for field in ("duration", "conditions.preload", "conditions.backlash", "conditions.preload_configuration",
                  "position_demand[0].kind"):
        assert field in text


def test_segment_errors():
    _, problems = compile_profile([{"kind": "ramp", "end": 1.0}, {"kind": "sinusoid", "end": 2.0, "amplitude": 1.0,
                                                                   "frequency": -1.0}], "p")
    assert any("p[0].to: missing" in x for x in problems)
    assert any("p[1].frequency" in x for x in problems)


def test_unknown_scene():
    with pytest.raises(SceneError, match="built-in scene"):
        twin.load_scene("no_such_scene")


def test_with_conditions_validates():
    with pytest.raises(SceneError, match="conditions.backlash"):
        twin.load_scene("nominal").with_conditions({"backlash": -1e-6})
