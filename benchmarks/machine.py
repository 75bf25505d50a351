"""What every benchmark prints first: the machine and the package versions its figures depend on.

A figure without the machine it was measured on cannot be compared with another; the load
average says whether the machine was busy with something else while it ran.
"""

from __future__ import annotations

import os
import platform
from datetime import UTC, datetime
from importlib import metadata

PACKAGES = ("benchtwin", "numpy", "numba", "scipy", "xarray", "dask", "distributed")


def cpu_model() -> str:
    """The processor's model name (``/proc/cpuinfo`` on Linux), else what :mod:`platform` knows."""
    try:
        with open("/proc/cpuinfo") as handle:
            for line in handle:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def header(title: str, quick: bool = False) -> None:
    """Print the benchmark's title, the machine, its load and the package versions (``#`` lines)."""
    versions = []
    for name in PACKAGES:
        try:
            versions.append(f"{name} {metadata.version(name)}")
        except metadata.PackageNotFoundError:
            versions.append(f"{name} not installed")
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg()) if hasattr(os, "getloadavg") else "unknown"
    print(f"# {title}{' (quick mode: small sizes, figures indicative only)' if quick else ''}")
    print(f"# {datetime.now(UTC).isoformat(timespec='seconds')}; {cpu_model()}, {os.cpu_count()} cores, "
          f"load average {load}; python {platform.python_version()}")
    print(f"# {'; '.join(versions)}", flush=True)
