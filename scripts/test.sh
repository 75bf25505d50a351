#!/usr/bin/env bash
# Install BenchTwin with its test dependencies into .venv and run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh test
# Two processes (pytest-xdist), one per core of the project's machine; a file's tests stay together (their module
# fixtures are built once). Every test is deterministic under load, so the split changes no result.
exec .venv/bin/python -m pytest -n 2 --dist loadfile "$@"
