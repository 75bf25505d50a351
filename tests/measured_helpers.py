"""A synthetic "measured" test and the small campaign it is diagnosed against (issue 30, measured tests).

The test is made by the twin with parameters the diagnosis does not know: a backlash of ``HIDDEN_BACKLASH`` and
every Table 9.5 tolerance drawn from the campaign's own table with another seed, its sensor noise from another
stream. Its channels are written to a CSV file as a bench's acquisition would log them, by the generator of the
README's sample (examples/measured/make_bench_run.py): its own column names, a time in ms, the linear encoder in mm on
an absolute scale, the torque-meter encoder in degrees from an arbitrary index, the torque meter in volts behind an
amplifier (gain and offset undone by the mapping).
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The README's sample (examples/measured/): its generator logs a run as a bench does; the tests log theirs with it.
SAMPLE = ROOT / "examples" / "measured"
_spec = importlib.util.spec_from_file_location("make_bench_run", SAMPLE / "make_bench_run.py")
bench_run = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench_run)
MAPPING = bench_run.MAPPING
#: The hidden fault and the seed of the hidden tolerances and noise (no campaign uses it).
HIDDEN_BACKLASH = 11e-6
HIDDEN_SEED = bench_run.HIDDEN_SEED
#: The sweep of the small campaign (data set 2 conditions): levels around the hidden backlash.
LEVELS = {"b0": 0.0, "b4": 4e-6, "b8": 8e-6, "b16": 16e-6}
RUNS = 8


def sweep_spec(directory: Path) -> Path:
    """A reduced observability sweep: ``LEVELS`` under data set 2 conditions, ``RUNS`` runs each, every Table 9.5
    tolerance (the observability spec's table), no fidelity audit, no traces."""
    datasets = "\n".join(
        f'[[datasets]]\nname = "{name}"\nscene = "ds2"\nconditions = {{ backlash = {level!r}, preload = 0.0 }}\n'
        for name, level in LEVELS.items())
    path = directory / "sweep.toml"
    path.write_text(
        f'extends = "{ROOT / "campaigns" / "specs" / "observability.toml"}"\n'
        f'name = "measured_sweep"\nruns_per_dataset = {RUNS}\n'
        f'features = ["backlash_feature", "backlash_hysteresis"]\n'
        f'[fidelity_audit]\nruns = 0\n[observability]\nsweep = {list(LEVELS)!r}\n{datasets}'.replace("'", '"'))
    return path


def hidden_run(spec_path: Path):
    """The twin's run with the hidden backlash and tolerances drawn from the spec's table with ``HIDDEN_SEED``."""
    return bench_run.hidden_run(spec_path, HIDDEN_BACKLASH, HIDDEN_SEED)[0]


def write_bench_csv(run, path: Path) -> Path:
    """The run's channels as the bench's acquisition logs them, every digit of the doubles kept (round-off only)."""
    return bench_run.write_bench_csv(run, path, decimals=None)


def write_mapping(path: Path) -> Path:
    path.write_text(MAPPING)
    return path


def close(a: float, b: float, rel: float = 1e-9, abs_: float = 1e-15) -> bool:
    return math.isclose(a, b, rel_tol=rel, abs_tol=abs_)
