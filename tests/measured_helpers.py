"""A synthetic "measured" test and the small campaign it is diagnosed against (issue 30, measured tests).

The test is made by the twin with parameters the diagnosis does not know: a backlash of ``HIDDEN_BACKLASH`` and
every Table 9.5 tolerance drawn from the campaign's own table with another seed, its sensor noise from another
stream. Its channels are written to a CSV file as a bench's acquisition would log them: its own column names, a time
in ms, the linear encoder in mm on an absolute scale, the torque-meter encoder in degrees from an arbitrary index,
the torque meter in volts behind an amplifier (gain and offset undone by the mapping).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

import campaigns
import twin
from campaigns.sampling import noise_generator, sample_run
from twin.scenes import split_targets

ROOT = Path(__file__).resolve().parents[1]
#: The hidden fault and the seed of the hidden tolerances and noise (no campaign uses it).
HIDDEN_BACKLASH = 11e-6
HIDDEN_SEED = 4242
#: The sweep of the small campaign (data set 2 conditions): levels around the hidden backlash.
LEVELS = {"b0": 0.0, "b4": 4e-6, "b8": 8e-6, "b16": 16e-6}
RUNS = 8
OUTPUTS = ["backlash_feature", "backlash_hysteresis", "drag_torque_feature", "linear_encoder_position",
           "screw_angle_measured", "torque_measured"]
#: The bench's logging: position on an absolute scale [mm], angle from the encoder's index [deg], torque-meter
#: amplifier output [V] (0.5 V per N m, 0.1 V offset).
SCALE_ORIGIN_MM = 123.456
ANGLE_INDEX_DEG = 37.5
VOLTS_PER_NM = 0.5
AMPLIFIER_OFFSET_V = 0.1
MAPPING = f"""\
[test]
name = "bench run 2026-11-20 #3"
scene = "ds2"
time = "Time [ms]"
time_unit = "ms"

[channels.linear_encoder_position]
column = "LinEnc_X"
unit = "mm"

[channels.screw_angle_measured]
column = "TM_Angle"
unit = "deg"

[channels.torque_measured]
column = "TM_Torque_V"
unit = "N m"
gain = {1.0 / VOLTS_PER_NM}
offset = {-AMPLIFIER_OFFSET_V / VOLTS_PER_NM}
"""


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
    spec = campaigns.load_spec(spec_path)
    values = sample_run(spec.distributions(), HIDDEN_SEED, 0, 0)
    conditions, parameters = split_targets({d.target: float(v) for d, v in zip(spec.distributions(), values,
                                                                                 strict=True)})
    scene = twin.load_scene("ds2").with_conditions({**conditions, "backlash": HIDDEN_BACKLASH, "preload": 0.0})
    params = twin.load_parameters("bench").with_values(parameters)
    return twin.simulate(scene, params, rng=noise_generator(HIDDEN_SEED, 0, 0), outputs=OUTPUTS)


def write_bench_csv(run, path: Path) -> Path:
    """The run's channels as the bench's acquisition logs them (module docstring)."""
    pd.DataFrame({
        "Time [ms]": run["time"].values * 1e3,
        "LinEnc_X": run["linear_encoder_position"].values * 1e3 + SCALE_ORIGIN_MM,
        "TM_Angle": np.degrees(run["screw_angle_measured"].values) + ANGLE_INDEX_DEG,
        "TM_Torque_V": run["torque_measured"].values * VOLTS_PER_NM + AMPLIFIER_OFFSET_V,
    }).to_csv(path, index=False, float_format="%.15g")
    return path


def write_mapping(path: Path) -> Path:
    path.write_text(MAPPING)
    return path


def close(a: float, b: float, rel: float = 1e-9, abs_: float = 1e-15) -> bool:
    return math.isclose(a, b, rel_tol=rel, abs_tol=abs_)
