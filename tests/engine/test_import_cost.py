"""What loads when: python-control only for designs and margins, never on ``import twin`` or a simulation."""

import subprocess
import sys


def _modules_after(code: str) -> set[str]:
    """Names in ``sys.modules`` of a fresh interpreter after running ``code``."""
    done = subprocess.run([sys.executable, "-c", f"{code}\nimport sys\nprint(' '.join(sys.modules))"],
                          capture_output=True, text=True, timeout=600, check=True)
    return set(done.stdout.split())


def test_import_twin_and_a_simulation_do_not_load_python_control():
    assert "control" not in _modules_after("import twin")
    after_run = _modules_after(
        "import twin\nds = twin.simulate('ds2', duration=0.02)\nassert ds.attrs['status'] == 'ok'")
    assert "twin.engine.loop" in after_run  # the simulation did run through the compiled loop
    assert "control" not in after_run


def test_a_loop_design_loads_python_control():
    code = ("import twin\nfrom twin.control.design import design_loops\n"
            "design_loops(twin.load_parameters('bench').values())")
    assert "control" in _modules_after(code)
