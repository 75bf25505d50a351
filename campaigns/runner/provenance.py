"""What produced a campaign's numbers: package versions and a hash of the model code.

Every chunk file records the provenance of the driver that wrote it, and ``results.nc`` the
provenance of every chunk it was assembled from. A resumed campaign compares the provenance
of the chunks already on disk with its own and refuses to mix them (different versions or
model code may give different numbers for the same spec and seed) unless told to
(``allow_version_mix``), in which case ``results.nc`` lists every provenance it mixes.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import platform
from functools import lru_cache
from importlib import metadata
from pathlib import Path

#: Packages whose versions determine the results (all recorded in ``package_versions``).
VERSIONED = ("benchtwin", "numpy", "scipy", "xarray", "netCDF4", "dask", "distributed", "pydantic", "numba")
#: The subset whose change may change a run's numbers: compared on resume.
RESULT_DETERMINING = ("benchtwin", "numpy", "numba", "scipy")
#: Packages whose source is the model (the run function's own package is added).
MODEL_PACKAGES = ("twin", "sensors")
#: Files of a package that define the model: its code and its data (parameter sets, scenes, rules).
MODEL_SUFFIXES = (".py", ".toml")
#: Folders of a package that hold inputs, not the model: campaign specs (each campaign keys its files by its own
#: spec hash), so adding a spec beside the shipped ones leaves every campaign resumable.
INPUT_FOLDERS = ("specs",)


def package_versions() -> dict[str, str]:
    """Versions of the packages that determine the results."""
    versions = {"python": platform.python_version()}
    for name in VERSIONED:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


def run_function_package(run_function) -> str | None:
    """Top-level package of a run function (of its class for a callable instance)."""
    module = getattr(run_function, "__module__", None) or type(run_function).__module__
    return module.split(".")[0] if module else None


@lru_cache(maxsize=8)
def code_hash(packages: tuple[str, ...]) -> str:
    """SHA-256 over the model files (:data:`MODEL_SUFFIXES`) of ``packages``, by relative path, without the
    :data:`INPUT_FOLDERS`."""
    digest = hashlib.sha256()
    for package in sorted(set(packages)):
        spec = importlib.util.find_spec(package)
        if spec is None:
            digest.update(f"{package}: not importable\0".encode())
            continue
        roots = [Path(r) for r in spec.submodule_search_locations or []]
        files = [(root, p) for root in roots for p in root.rglob("*")
                 if p.suffix in MODEL_SUFFIXES and "__pycache__" not in p.parts
                 and not set(p.relative_to(root).parts[:-1]) & set(INPUT_FOLDERS)]
        if not roots and spec.origin:  # a plain module
            files = [(Path(spec.origin).parent, Path(spec.origin))]
        for root, path in sorted(files):
            digest.update(f"{package}/{path.relative_to(root).as_posix()}\0".encode())
            digest.update(path.read_bytes())
            digest.update(b"\0")
    return digest.hexdigest()


def provenance(run_function) -> dict[str, str]:
    """The provenance of runs executed now with ``run_function``: result-determining versions and code hash."""
    versions = package_versions()
    packages = tuple(sorted(set(MODEL_PACKAGES) | {p for p in [run_function_package(run_function)] if p}))
    return {**{name: versions[name] for name in RESULT_DETERMINING}, "model_code": code_hash(packages),
            "model_packages": ",".join(packages)}


def as_text(record: dict[str, str]) -> str:
    """Canonical JSON of a provenance (what chunks store and compare)."""
    return json.dumps(record, sort_keys=True, separators=(",", ":"))


def differences(old: dict[str, str], new: dict[str, str]) -> list[str]:
    """Human-readable differences between two provenances, e.g. ``numpy 1.26.4 -> 2.1.0``."""
    out = []
    for key in sorted(set(old) | set(new)):
        a, b = old.get(key, "unknown"), new.get(key, "unknown")
        if a != b:
            if key == "model_code":
                a, b = a[:12], b[:12]
            out.append(f"{'model code hash' if key == 'model_code' else key} {a} -> {b}")
    return out
