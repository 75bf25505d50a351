"""Memory of reading a measured test's CSV (issue 39): the earlier reader against campaigns.workflows.measured's.

The earlier reader parsed the whole file with pandas' Python engine and a sniffed delimiter (every column, every value
a Python object first: a 187 MB log took 2.87 GB, 15x the file). campaigns.workflows.measured now tells the delimiter
from the first lines and reads only the mapped columns with the C engine, in chunks of CSV_CHUNK_ROWS rows, straight
into float arrays. Each reader runs in a fresh process on the same file, a bench log of the README sample's layout
(time in ms, three channels; 1 kHz); the figure is its peak resident memory above what the process held after its
imports, per byte of the file. The new reader is also timed through the whole `import_measured` (resampling and the
features).

Usage: python benchmarks/measured_import_memory.py [--rows 3000000] [--quick]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from machine import header

ROOT = Path(__file__).resolve().parents[1]
COLUMNS = ["Time [ms]", "LinEnc_X", "TM_Angle", "TM_Torque_V"]
MAPPING = """\
[test]
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
gain = 2.0
"""
#: What each child process runs after its imports (``path``, ``mapping`` and ``wanted`` are defined before).
READERS = {
    "earlier (python engine, every column)": """
frame = pd.read_csv(path, sep=None, engine="python", comment="#")
columns = {n: pd.to_numeric(frame[n], errors="coerce").to_numpy(dtype=float) for n in wanted}
""",
    "campaigns.workflows.measured (C engine, mapped columns, chunks)": """
names, columns = _read_csv(path, wanted)
""",
    "campaigns.workflows.measured: the whole import (resampling, features)": """
test = import_measured(path, mapping)
""",
}
CHILD = """
import json, resource, sys, time
import pandas as pd
from pathlib import Path
from campaigns.workflows.measured import _read_csv, import_measured, load_mapping
path, mapping = Path(sys.argv[1]), load_mapping(sys.argv[2])
wanted = [mapping.time, *(c.column for c in mapping.channels.values())]
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
start = time.perf_counter()
{code}
wall = time.perf_counter() - start
print(json.dumps({{"before": before * 1024, "peak": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
                  "wall": wall}}))
"""


def write_log(path: Path, rows: int) -> None:
    """A 1 kHz bench log of the README sample's layout: a ±5 mm, 1 Hz sinusoid of the sled on an absolute scale, the
    screw angle that follows it (5 mm lead) and a torque in volts, at the sample's logged decimals."""
    t = np.arange(rows) * 1e-3
    sled = 5.0 * np.sin(2 * np.pi * t)
    block = np.column_stack([t * 1e3, 123.456 + sled, 37.5 + sled / 5.0 * 360.0, 0.1 + 0.3 * np.cos(2 * np.pi * t)])
    with path.open("w") as handle:
        handle.write(",".join(COLUMNS) + "\n")
        for chunk in np.array_split(block, max(1, rows // 200_000)):
            np.savetxt(handle, chunk, fmt=["%.3f", "%.4f", "%.4f", "%.5f"], delimiter=",")


def measure(code: str, path: Path, mapping: Path) -> dict:
    result = subprocess.run([sys.executable, "-c", CHILD.format(code=code), str(path), str(mapping)],
                            capture_output=True, text=True, check=True, cwd=ROOT)
    return json.loads(result.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rows", type=int, default=3_000_000, help="rows of the log (1 kHz: 3e6 rows is 50 min)")
    parser.add_argument("--quick", action="store_true", help="a 300 000-row log (about 10 MB; seconds)")
    args = parser.parse_args()
    rows = 300_000 if args.quick else args.rows
    header("measured-test import: peak memory of reading a bench CSV, earlier reader against "
           "campaigns.workflows.measured",
           args.quick)
    with tempfile.TemporaryDirectory() as folder:
        log, mapping = Path(folder) / "log.csv", Path(folder) / "mapping.toml"
        start = time.perf_counter()
        write_log(log, rows)
        mapping.write_text(MAPPING)
        size = log.stat().st_size
        print(f"# a {rows}-row log, {size / 1e6:.1f} MB, written in {time.perf_counter() - start:.1f} s; "
              "each reader in a fresh process: peak resident memory above its imports, per byte of the file")
        for name, code in READERS.items():
            figures = measure(code, log, mapping)
            extra = figures["peak"] - figures["before"]
            print(f"{name:60s} {extra / 1e6:8.0f} MB  {extra / size:5.1f} x the file  {figures['wall']:6.1f} s")


if __name__ == "__main__":
    main()
