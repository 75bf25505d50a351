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


def vector_extension() -> str:
    """The widest x86 vector extension the processor reports (``/proc/cpuinfo`` flags): what the compiled loops may
    use (AVX2: 4 doubles per register, AVX-512: 8), and why a figure measured on one machine may differ on another."""
    try:
        with open("/proc/cpuinfo") as handle:
            flags = next((line.split(":", 1)[1].split() for line in handle if line.startswith("flags")), [])
    except OSError:
        flags = []
    return "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "no AVX2"


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
    print(f"# {datetime.now(UTC).isoformat(timespec='seconds')}; {cpu_model()} ({vector_extension()}), "
          f"{os.cpu_count()} cores, load average {load}; python {platform.python_version()}")
    print(f"# {'; '.join(versions)}", flush=True)
