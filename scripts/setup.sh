#!/usr/bin/env bash
# Create .venv (if missing) and install BenchTwin with the given extras, e.g. `scripts/setup.sh test,report`.
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1:-}"
# setuptools' notice about editable installs of a flat layout is about our packaging, not the user's business
export PYTHONWARNINGS="ignore:Editable installation"
python3 -m venv .venv
.venv/bin/python -m pip install --quiet --upgrade pip
if [ -n "$extras" ]; then
  .venv/bin/python -m pip install --quiet -e ".[${extras}]"
else
  .venv/bin/python -m pip install --quiet -e .
fi
