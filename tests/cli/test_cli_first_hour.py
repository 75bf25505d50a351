"""What a new user meets first with `twin simulate` (issue 39): the version, values with units in --set, and a line
that says what the printed backlash feature is."""

import subprocess
import sys
from importlib import metadata


def run(*args):
    return subprocess.run([sys.executable, "-m", "app.cli", *args], capture_output=True, text=True, timeout=1800)


def test_version():
    result = run("--version")
    assert result.returncode == 0 and result.stdout.strip() == f"twin {metadata.version('benchtwin')}"


def test_set_takes_values_with_units_and_the_feature_line_says_what_it_is():
    result = run("simulate", "ds2", "--duration", "0.3", "--set", "scene.backlash=20 um",
                 "--set", "reducer.backlash=3 mrad")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    feature = next(k for k, line in enumerate(lines) if line.startswith("backlash feature (Eq. 9.12)"))
    said = lines[feature + 1]
    assert "the mean over the test of |nut - screw equivalent position|, not the gap" in said
    assert "the scene's backlash b is 20 um" in said and "reads b/2 = 10 um" in said  # ds2: the thesis zero


def test_a_value_of_the_wrong_dimension_is_one_line_naming_both_units():
    result = run("simulate", "ds2", "--duration", "0.3", "--set", "scene.backlash=20 N",
                 "--set", "reducer.backlash=3 mm")
    assert result.returncode == 2 and "Traceback" not in result.stderr
    problems = [line for line in result.stderr.splitlines() if line.startswith("  - ")]
    assert len(problems) == 2
    assert any("conditions.backlash" in p and "'N'" in p and "'m'" in p for p in problems), problems
    assert any("reducer.backlash" in p and "'mm'" in p and "'rad'" in p for p in problems), problems
