"""The lock files of scripts/setup.sh cover pyproject.toml and are what this environment runs (issue 28).

A dependency added to pyproject.toml, or a range raised beyond the locked version, without `bash scripts/lock.sh`
would leave setup.sh installing something the tests never ran with; an environment whose packages differ from
the lock cannot promise the locked results. Both are caught here.
"""

from __future__ import annotations

import functools
import importlib.util
import os
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("dependency_drift", ROOT / "benchmarks" / "dependency_drift.py")
dependency_drift = importlib.util.module_from_spec(_spec)


@functools.cache
def _load_drift():
    sys.path.insert(0, str(ROOT / "benchmarks"))  # its `machine` helper
    try:
        _spec.loader.exec_module(dependency_drift)
    finally:
        sys.path.pop(0)
    return dependency_drift


def _requirements() -> dict[str, list[Requirement]]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    runtime = [Requirement(r) for r in project["dependencies"]]
    test = [Requirement(r) for r in project["optional-dependencies"]["test"]]
    return {"runtime": runtime, "test": runtime + test}


@pytest.mark.parametrize("lock", ["runtime", "test"])
def test_every_dependency_is_locked_within_its_range(lock):
    pins = _load_drift().locked_versions(ROOT / "requirements" / f"{lock}.lock")
    problems = []
    for requirement in _requirements()[lock]:
        name = dependency_drift._normalised(requirement.name)
        if name not in pins:
            problems.append(f"{requirement.name}: not in requirements/{lock}.lock")
        elif not requirement.specifier.contains(pins[name], prereleases=True):
            problems.append(f"{requirement.name}: locked {pins[name]} outside pyproject's {requirement.specifier}")
    assert not problems, "run `bash scripts/lock.sh` (README, reproducible installs):\n" + "\n".join(problems)


def test_this_environment_runs_the_locked_versions():
    if os.environ.get("BENCHTWIN_UNLOCKED") == "1":
        pytest.skip("BENCHTWIN_UNLOCKED=1: an environment of the newest allowed versions, on purpose")
    pins = _load_drift().locked_versions(ROOT / "requirements" / "test.lock")
    differing = []
    for requirement in _requirements()["test"]:
        name = dependency_drift._normalised(requirement.name)
        installed = metadata.version(requirement.name)
        if pins.get(name) != installed:
            differing.append(f"{requirement.name}: installed {installed}, locked {pins.get(name)}")
    assert not differing, ("this environment is not the locked one; re-run `bash scripts/setup.sh test` (or set "
                           "BENCHTWIN_UNLOCKED=1 if that is intended):\n" + "\n".join(differing))
