#!/usr/bin/env bash
# Re-resolve the lock files of scripts/setup.sh from pyproject.toml's ranges: the newest allowed versions, with
# hashes, for every Python >= 3.11 (markers where versions differ). Run it on purpose (a dependency added or
# raised), then run the whole suite from a fresh `bash scripts/setup.sh test` and commit the locks with the
# results of that run; benchmarks/dependency_drift.py shows beforehand what would change.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/uv ] || .venv/bin/python -m pip install --quiet uv
compile=(.venv/bin/uv pip compile pyproject.toml --universal --python-version 3.11 --generate-hashes --quiet)
"${compile[@]}" -o requirements/runtime.lock
# the test lock is constrained by the runtime lock: the demo and the tests run the same versions
"${compile[@]}" --extra test -c requirements/runtime.lock -o requirements/test.lock
echo "lock: wrote requirements/runtime.lock and requirements/test.lock"
