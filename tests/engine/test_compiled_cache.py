"""numba's on-disk cache is keyed on the project source: editing a called function in another module is
seen by the next process (numerics.compiled_cache; numba alone checks only the caller's own file)."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import twin
from numerics import compiled_cache

ROOT = Path(twin.__file__).resolve().parent.parent

# measurands (twin/engine/plant.py) puts the torque of elasto_backlash (twin/physics/coupling.py, inlined into the
# lane kernel) into the work rows: a deflection of 1e-3 rad past a 0 backlash at stiffness 2 and no damping transmits
# 2e-3 N m (one lane, no load system).
PROBE = """
import numpy as np
import twin
from twin.layout import K, N_CONSTANTS, N_STATES, S
from twin.levels import SUBSYSTEMS, level_codes
from twin.engine.plant import W, measurands, work_rows
x = np.zeros((N_STATES, 1)); c = np.zeros((N_CONSTANTS, 1)); w = work_rows(1)
levels = level_codes({name: ("absent" if name == "pneumatics" else s.full) for name, s in SUBSYSTEMS.items()})
x[S.REDUCER_ANGLE] = 1e-3
c[K.TORSION_STIFFNESS] = 2.0
measurands(0.0, x, c, w, 1, levels, np.zeros((1, 8)))
print(repr(float(w[W.TORQUE, 0])))
print(os.environ["NUMBA_CACHE_DIR"])
"""


def run_probe(copy: Path, cache_base: Path) -> tuple[float, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env.update(PYTHONPATH=str(copy), NUMBA_CACHE_DIR=str(cache_base))
    done = subprocess.run([sys.executable, "-c", "import os\n" + PROBE], cwd=copy, env=env,
                          capture_output=True, text=True, check=True)
    value, directory = done.stdout.split()
    return float(value), directory


def test_an_edited_callee_in_another_module_is_recompiled(tmp_path):
    copy = tmp_path / "src"
    for package in compiled_cache.COMPILED_PACKAGES:
        shutil.copytree(ROOT / package, copy / package, ignore=shutil.ignore_patterns("__pycache__"))
    cache_base = tmp_path / "numba-cache"

    before, first_dir = run_probe(copy, cache_base)
    assert before == 2e-3
    assert any(Path(first_dir).rglob("*.nbi")), "the first process wrote no cache: the test would prove nothing"
    again, same_dir = run_probe(copy, cache_base)
    assert (again, same_dir) == (before, first_dir)  # unchanged source: same cache directory, reused

    coupling = copy / "twin" / "physics" / "coupling.py"
    text = coupling.read_text()
    edited = text.replace("torque = elastic + saturated_damping_force",
                          "torque = 3.0 * elastic + saturated_damping_force")
    assert edited != text
    coupling.write_text(edited)

    after, second_dir = run_probe(copy, cache_base)
    assert after == 6e-3  # the edit is seen, not the caller's stale machine code
    assert Path(second_dir).parent == cache_base and second_dir != first_dir


def test_the_cache_directory_is_keyed_on_every_source_file(tmp_path):
    for package in compiled_cache.COMPILED_PACKAGES:
        (tmp_path / package / "sub").mkdir(parents=True)
        (tmp_path / package / "sub" / "m.py").write_text("x = 1\n")
    key = compiled_cache.source_hash(tmp_path)
    (tmp_path / "sensors" / "sub" / "m.py").write_text("x = 2\n")
    assert compiled_cache.source_hash(tmp_path) != key
    (tmp_path / "sensors" / "notes.txt").write_text("not compiled")
    assert compiled_cache.source_hash(tmp_path) == compiled_cache.source_hash(tmp_path)


def test_a_child_process_reuses_the_keyed_directory_and_a_user_base_is_honoured(tmp_path):
    keyed = compiled_cache.cache_directory("abc", {"NUMBA_CACHE_DIR": str(tmp_path)})
    assert keyed == tmp_path / "benchtwin-abc"
    # a child inherits the keyed directory: same base, no nesting
    assert compiled_cache.cache_directory("abc", {"NUMBA_CACHE_DIR": str(keyed)}) == keyed
    assert compiled_cache.cache_directory("def", {"NUMBA_CACHE_DIR": str(keyed)}) == tmp_path / "benchtwin-def"
    default = compiled_cache.cache_directory("abc", {"XDG_CACHE_HOME": str(tmp_path)})
    assert default == tmp_path / "benchtwin" / "numba" / "benchtwin-abc"


def test_this_process_uses_the_keyed_directory():
    assert os.environ["NUMBA_CACHE_DIR"] == str(compiled_cache.cache_directory(compiled_cache.source_hash()))
