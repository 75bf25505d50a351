"""The `twin` command: runs end to end and reports bad input without a traceback."""

import subprocess
import sys

import xarray as xr


def run(*args):
    return subprocess.run([sys.executable, "-m", "app.cli", *args], capture_output=True, text=True, timeout=600)


def test_simulate_writes_dataset_and_plot(tmp_path):
    out, plot = tmp_path / "run.nc", tmp_path / "run.png"
    result = run("simulate", "ds4", "--duration", "0.5", "--out", str(out), "--plot", str(plot))
    assert result.returncode == 0, result.stderr
    assert "backlash feature" in result.stdout
    assert "integrator: rk4 at 62.5 us" in result.stdout  # the default, named with its step
    assert plot.stat().st_size > 10_000
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == "ok"
        assert ds.nut1_position.attrs["units"] == "m"


def test_simulate_names_the_default_step_it_took():
    """The default step follows the run's fidelity: the drive period where the preload allows the quasi-static screw
    axial (ds1), and the retired automatic integrator is refused with the methods there are."""
    result = run("simulate", "ds1", "--duration", "0.2")
    assert result.returncode == 0, result.stderr
    assert "integrator: rk4 at 125 us" in result.stdout
    retired = run("simulate", "ds2", "--duration", "0.2", "--integrator", "auto")
    assert retired.returncode == 2 and "Traceback" not in retired.stderr
    assert "invalid choice: 'auto'" in retired.stderr and "rk4" in retired.stderr


def test_bad_input_is_a_clear_error():
    result = run("simulate", "nominal", "--set", "motor.inertia=-1", "--set", "scene.backlash=-2e-6",
                 "--set", "nope.x=1")
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    for field in ("motor.inertia", "conditions.backlash", "nope.x"):
        assert field in result.stderr


def test_unknown_scene():
    result = run("simulate", "no_such_scene")
    assert result.returncode == 2 and "no_such_scene" in result.stderr and "Traceback" not in result.stderr


def test_scenes_lists_data_sets():
    result = run("scenes")
    assert result.returncode == 0 and "ds7" in result.stdout and "nominal" in result.stdout


def test_explain_fidelity_prints_each_choice_and_why():
    # ds1: a scene whose automatic levels pay (twin/fidelity/speed.toml), so the rules' reasons show
    result = run("simulate", "ds1", "--duration", "0.2", "--explain-fidelity")
    assert result.returncode == 0, result.stderr
    assert "current_loop          ideal" in result.stdout and "automatic levels buy" in result.stdout
    assert "peak voltage demand" in result.stdout and "integrated states: 16 of 25" in result.stdout


def test_fidelity_option_and_levels_listing():
    result = run("simulate", "ds2", "--duration", "0.2", "--fidelity", "default=full,encoders=ideal")
    assert result.returncode == 0, result.stderr
    assert "encoders=ideal" in result.stdout and "(25 integrated states)" in result.stdout
    listing = run("fidelity", "levels")
    assert listing.returncode == 0 and "nut_rotation" in listing.stdout and "removes 4 states" in listing.stdout


def test_bad_fidelity_is_a_clear_error():
    result = run("simulate", "nominal", "--fidelity", "pneumatics=absent,gearbox=full")
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert "fidelity.gearbox" in result.stderr
    audit = run("fidelity", "audit", "no_such_scene", "--runs", "1")
    assert (audit.returncode == 2 and "no_such_scene" in audit.stderr
            and "runs: 1 must be an integer >= 5 (the fewest paired runs an audit verdict needs)" in audit.stderr)
