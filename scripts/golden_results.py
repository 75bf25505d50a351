"""Re-generate the golden results file of ``tests/campaigns/test_golden_results.py``.

Run it only when the model changes on purpose (the campaign results are meant to stay bit-identical
otherwise), and say in the commit why the numbers moved::

    .venv/bin/python scripts/golden_results.py

It runs the small thesis campaign ``tests/campaigns/data/golden_thesis_small.toml`` (fixed seed) and
stores its ``results.nc`` without the machine-dependent parts (``wall_time``, the provenance and
execution attributes) as ``tests/campaigns/data/golden_thesis_small.nc``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
import xarray as xr

import campaigns

DATA = Path(__file__).resolve().parent.parent / "tests" / "campaigns" / "data"
SPEC = DATA / "golden_thesis_small.toml"
GOLDEN = DATA / "golden_thesis_small.nc"


def comparable(ds: xr.Dataset) -> xr.Dataset:
    """The part of a results file that must not depend on the machine, the workers or the date."""
    return ds.drop_vars("wall_time").drop_attrs()


def differences(new: xr.Dataset, golden: xr.Dataset) -> list[str]:
    """One line per variable or coordinate that differs (bit for bit), with the largest difference for numbers."""
    lines = []
    if set(new.variables) != set(golden.variables):
        lines.append(f"variables: new has {sorted(set(new.variables) - set(golden.variables))}, "
                     f"golden has {sorted(set(golden.variables) - set(new.variables))}")
    for name in sorted(set(new.variables) & set(golden.variables)):
        a, b = new[name], golden[name]
        if a.dims != b.dims or a.shape != b.shape:
            lines.append(f"{name}: shape {dict(a.sizes)} != golden {dict(b.sizes)}")
        elif a.dtype.kind == "f":
            if not np.array_equal(a.values, b.values, equal_nan=True):
                lines.append(f"{name}: max |new - golden| = {np.nanmax(np.abs(a.values - b.values)):.3g}")
        elif a.dtype.kind != "f" and not np.array_equal(a.values, b.values):
            lines.append(f"{name}: {a.values.ravel()[:6]} != golden {b.values.ravel()[:6]}")
        if a.attrs != b.attrs:
            lines.append(f"{name}: attributes {a.attrs} != golden {b.attrs}")
    return lines


def run_golden_campaign(out_dir: Path) -> xr.Dataset:
    """Run the golden spec into ``out_dir`` and return its comparable results (loaded in memory)."""
    results = campaigns.run_campaign(campaigns.load_spec(SPEC), out_dir, workers=1, progress=False)
    with xr.open_dataset(results) as ds:
        return comparable(ds).load()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=GOLDEN, help=f"where to write (default {GOLDEN})")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        ds = run_golden_campaign(Path(tmp) / "out")
    encoding = {name: {"zlib": True, "complevel": 9} for name in ds.data_vars if ds[name].dtype.kind in "fiu"}
    ds.to_netcdf(args.out, encoding=encoding)
    print(f"wrote {args.out} ({args.out.stat().st_size} bytes, {len(ds.data_vars)} variables)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
