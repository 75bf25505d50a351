"""The sample measured test of the README: a run of the twin, logged as a bench's acquisition logs it.

What the diagnosis is not told (written to ``bench_run_truth.toml``): a ball-screw backlash of ``HIDDEN_BACKLASH``
under data set 2 conditions (scene ds2, no preload), and every tolerance of the observability campaign's table
(``campaigns/specs/observability.toml``: Table 9.5 and its extension, 48 rows) drawn with ``HIDDEN_SEED``, the sensor
noise from the same seed's noise stream (no campaign of the project uses that seed).

How the bench logs it (``bench_run.csv``, mapped by ``bench_run.toml``): its own column names, the time in ms, the
linear encoder in mm on the scale's absolute position (``SCALE_ORIGIN_MM`` at the start), the torque-meter encoder in
degrees from its index (``ANGLE_INDEX_DEG``), the torque meter in volts behind an amplifier (``VOLTS_PER_NM``,
``AMPLIFIER_OFFSET_V``), each column written to the digits of ``LOGGED_DECIMALS`` (finer than the instruments'
resolutions: 1 µm, 0.045°, 0.3 mV).

Usage: python examples/measured/make_bench_run.py [--out DIR]   (default: this folder; rewrites its three files)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

import campaigns
import twin
from campaigns.runner.sampling import noise_generator, sample_run
from twin.scenes import split_targets

HERE = Path(__file__).resolve().parent
SPEC = HERE.parents[1] / "campaigns" / "specs" / "observability.toml"
#: The hidden fault and the seed of the hidden tolerances and noise.
HIDDEN_BACKLASH = 2.5e-6
HIDDEN_SEED = 4242
OUTPUTS = ["backlash_feature", "backlash_hysteresis", "drag_torque_feature", "linear_encoder_position",
           "screw_angle_measured", "torque_measured"]
#: The bench's logging: position on an absolute scale [mm], angle from the encoder's index [deg], torque-meter
#: amplifier output [V] (0.5 V per N m, 0.1 V offset).
SCALE_ORIGIN_MM = 123.456
ANGLE_INDEX_DEG = 37.5
VOLTS_PER_NM = 0.5
AMPLIFIER_OFFSET_V = 0.1
#: Decimals each column is logged with (None: every digit of the double, as the known-answer tests write it).
LOGGED_DECIMALS = {"Time [ms]": 3, "LinEnc_X": 4, "TM_Angle": 4, "TM_Torque_V": 5}
MAPPING = f"""\
# The mapping of examples/measured/bench_run.csv onto the twin's signals (docs/campaigns.md, Measured tests).
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


def hidden_run(spec_path: Path = SPEC, backlash: float = HIDDEN_BACKLASH, seed: int = HIDDEN_SEED):
    """The twin's ds2 run with ``backlash`` and the tolerances of the spec's table drawn with ``seed``; returns the
    run and the drawn values by target."""
    spec = campaigns.load_spec(spec_path)
    values = sample_run(spec.distributions(), seed, 0, 0)
    drawn = {d.target: float(v) for d, v in zip(spec.distributions(), values, strict=True)}
    conditions, parameters = split_targets(drawn)
    scene = twin.load_scene("ds2").with_conditions({**conditions, "backlash": backlash, "preload": 0.0})
    params = twin.load_parameters("bench").with_values(parameters)
    return twin.simulate(scene, params, rng=noise_generator(seed, 0, 0), outputs=OUTPUTS), drawn


def write_bench_csv(run, path: Path, decimals: dict[str, int] | None = LOGGED_DECIMALS, header: str = "") -> Path:
    """The run's channels as the bench's acquisition logs them (module docstring); ``header``: ``#`` lines first."""
    frame = pd.DataFrame({
        "Time [ms]": run["time"].values * 1e3,
        "LinEnc_X": run["linear_encoder_position"].values * 1e3 + SCALE_ORIGIN_MM,
        "TM_Angle": np.degrees(run["screw_angle_measured"].values) + ANGLE_INDEX_DEG,
        "TM_Torque_V": run["torque_measured"].values * VOLTS_PER_NM + AMPLIFIER_OFFSET_V,
    })
    with path.open("w", encoding="utf-8", newline="") as handle:
        handle.write(header)
        if decimals is None:
            frame.to_csv(handle, index=False, float_format="%.15g")
        else:
            frame.round(decimals).to_csv(handle, index=False)
    return path


def truth(run, drawn: dict[str, float]) -> str:
    """``bench_run_truth.toml``: what the sample hides, and the twin's own features of the run."""
    lines = ["# What examples/measured/bench_run.csv hides (examples/measured/make_bench_run.py).",
             f'spec = "{SPEC.relative_to(HERE.parents[1])}"', f"seed = {HIDDEN_SEED}", "",
             "[conditions]", 'scene = "ds2"', f"backlash = {HIDDEN_BACKLASH!r}  # m", "preload = 0.0  # N", "",
             "[features]  # the twin's, from its unrounded signals (SI units)"]
    lines += [f"{name} = {float(run[name])!r}" for name in ("backlash_feature", "backlash_hysteresis",
                                                            "drag_torque_feature")]
    lines += ["", "[tolerances]  # every row of the spec's table, drawn with the seed (SI units)"]
    lines += [f'"{target}" = {value!r}' for target, value in drawn.items()]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=HERE, help="folder to write into (default: this one)")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    run, drawn = hidden_run()
    header = ("# bench run 2026-11-20 #3 (a sample: a run of the twin, examples/measured/make_bench_run.py; "
              "what it hides: bench_run_truth.toml)\n")
    written = [write_bench_csv(run, args.out / "bench_run.csv", header=header), args.out / "bench_run.toml",
               args.out / "bench_run_truth.toml"]
    written[1].write_text(MAPPING, encoding="utf-8")
    written[2].write_text(truth(run, drawn), encoding="utf-8")
    for path in written:
        print(f"wrote {path} ({path.stat().st_size / 1e3:.0f} kB)")

if __name__ == "__main__":
    main()
