#!/usr/bin/env bash
# Create .venv (if missing) and install BenchTwin with the given extras, e.g. `scripts/setup.sh test`.
#
# The exact versions come from the lock files in requirements/ (runtime.lock, and test.lock for the `test` extras),
# with their hashes: a fresh machine gets the packages the tests passed with, whatever PyPI has released since.
# BENCHTWIN_UNLOCKED=1 installs the newest versions pyproject.toml allows instead (what a library user gets; see
# benchmarks/dependency_drift.py). To update the locks: bash scripts/lock.sh (README, "Reproducible installs").
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1:-}"
# setuptools' notice about editable installs of a flat layout is about our packaging, not the user's business
export PYTHONWARNINGS="ignore:Editable installation"
python3 -m venv .venv
.venv/bin/python -m pip install --quiet --upgrade pip
target="."
[ -n "$extras" ] && target=".[${extras}]"
if [ "${BENCHTWIN_UNLOCKED:-0}" = 1 ]; then
  echo "setup: BENCHTWIN_UNLOCKED=1: installing the newest versions pyproject.toml allows (not the lock files)"
  .venv/bin/python -m pip install --quiet -e "$target"
  exit 0
fi
case ",$extras," in
  *,test,*) lock=requirements/test.lock ;;
  ,,) lock=requirements/runtime.lock ;;
  *) echo "setup: no lock file for extras '$extras' (known: test); use BENCHTWIN_UNLOCKED=1" >&2; exit 2 ;;
esac
.venv/bin/python -m pip install --quiet --require-hashes -r "$lock"
# the project itself, editable, with nothing re-resolved: every dependency is already installed from the lock
.venv/bin/python -m pip install --quiet --no-deps -e "$target"
