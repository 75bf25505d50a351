"""Dependency drift: what a fresh install of the newest versions pyproject.toml allows would change (issue 28).

``scripts/setup.sh`` installs the exact versions of ``requirements/*.lock``; a library user who runs ``pip install
benchtwin`` gets the newest versions the ranges allow. This script shows the difference before it bites:

* ``--quick`` (CI): resolves the newest allowed versions in a scratch virtual environment (``pip install
  --dry-run --report``, nothing installed) and prints every package whose version differs from the test lock;
* default: also installs them there with the project and runs the golden campaign
  (``scripts/golden_results.py``), then prints which stored variables differ from the golden file and by how
  much: a drift that would move results is seen here first.

Usage: python benchmarks/dependency_drift.py [--quick] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from machine import header

ROOT = Path(__file__).resolve().parents[1]
LOCK = ROOT / "requirements" / "test.lock"
_PIN = re.compile(r"^([A-Za-z0-9_.\-]+)==([^\s;\\]+)(?:\s*;\s*([^\\]+?))?\s*\\?$")


def locked_versions(lock: Path = LOCK) -> dict[str, str]:
    """``{normalised name: version}`` of the lock's pins for this Python (markers evaluated by ``packaging``)."""
    from packaging.markers import Marker

    pins = {}
    for line in lock.read_text().splitlines():
        match = _PIN.match(line.strip())
        if not match:
            continue
        name, version, marker = match.groups()
        if marker is None or Marker(marker).evaluate():
            pins[_normalised(name)] = version
    return pins


def _normalised(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _run(command: list[str], **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run(command, check=True, text=True, capture_output=True, **kwargs)


def newest_allowed(venv: Path) -> dict[str, str]:
    """The versions a fresh ``pip install -e .[test]`` would install today, resolved in ``venv``."""
    report = venv / "report.json"
    _run([str(venv / "bin" / "python"), "-m", "pip", "install", "--quiet", "--dry-run", "--ignore-installed",
          "--report", str(report), "-e", f"{ROOT}[test]"])
    items = json.loads(report.read_text())["install"]
    return {_normalised(item["metadata"]["name"]): item["metadata"]["version"] for item in items
            if _normalised(item["metadata"]["name"]) != "benchtwin"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="resolve only: print the version differences")
    parser.add_argument("--keep", type=Path, help="scratch environment directory to create and keep")
    args = parser.parse_args()
    header("dependency drift: the lock against the newest allowed versions", args.quick)
    with tempfile.TemporaryDirectory() as tmp:
        venv = args.keep or Path(tmp) / "venv"
        start = time.perf_counter()
        _run([sys.executable, "-m", "venv", str(venv)])
        _run([str(venv / "bin" / "python"), "-m", "pip", "install", "--quiet", "--upgrade", "pip"])
        newest = newest_allowed(venv)
        locked = locked_versions()
        changed = sorted(name for name in newest if locked.get(name) != newest[name])
        print(f"# resolved in {time.perf_counter() - start:.0f} s: {len(newest)} packages, {len(changed)} differ "
              f"from {LOCK.relative_to(ROOT)}")
        print(f"{'package':32s} {'locked':>16s} {'newest allowed':>16s}")
        for name in changed:
            print(f"{name:32s} {locked.get(name, '(not locked)'):>16s} {newest[name]:>16s}")
        if args.quick:
            return
        python = str(venv / "bin" / "python")
        _run([python, "-m", "pip", "install", "--quiet", "-e", f"{ROOT}[test]"])
        out = Path(tmp) / "golden_newest.nc"
        _run([python, str(ROOT / "scripts" / "golden_results.py"), "--out", str(out)], cwd=ROOT)
        check = ("import importlib.util, sys, xarray as xr\n"
                 "spec = importlib.util.spec_from_file_location('g', sys.argv[1]); g = importlib.util.module_from_spec("
                 "spec); spec.loader.exec_module(g)\n"
                 "lines = g.differences(xr.open_dataset(sys.argv[2]).load(), xr.open_dataset(g.GOLDEN).load())\n"
                 "print('\\n'.join(lines) if lines else 'golden campaign: bit-identical with the newest versions')\n")
        print(_run([python, "-c", check, str(ROOT / "scripts" / "golden_results.py"), str(out)]).stdout.strip())


if __name__ == "__main__":
    main()
