#!/usr/bin/env bash
# The whole test suite three times in a row with both cores saturated by two busy loops (issue 20:
# no test may fail from timing). Run after `bash scripts/test.sh` has installed .venv; ~10-11 min per run on
# the 2-core machine. Prints each run's result, wall time and load average; stops at the first failure.
set -uo pipefail
cd "$(dirname "$0")/.."
mkdir -p out
python3 -c 'while True: pass' & b1=$!
python3 -c 'while True: pass' & b2=$!
trap 'kill $b1 $b2 2>/dev/null' EXIT
for i in 1 2 3; do
  echo "run $i start $(date -u +%T) load $(cut -d' ' -f1-3 /proc/loadavg)"
  start=$(date +%s)
  .venv/bin/python -m pytest -q -p no:randomly > "out/suite_under_load_$i.log" 2>&1; rc=$?
  echo "run $i rc=$rc wall $(( $(date +%s) - start )) s load $(cut -d' ' -f1-3 /proc/loadavg): $(tail -1 "out/suite_under_load_$i.log")"
  [ "$rc" -ne 0 ] && exit "$rc"
done
