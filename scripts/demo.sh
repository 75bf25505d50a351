#!/usr/bin/env bash
# Install BenchTwin into .venv and run the main job: the demo Monte Carlo campaign (the Sec. 9.4 study,
# data sets 1-7, every Table 9.5 uncertainty, 59 runs per data set) on a local 2-worker dask cluster,
# the fidelity audit on the same cluster (the runs of each data set the automatic choice simplifies, again at full
# fidelity; the others run the full model already and are not re-run), the analysis
# (correlations, separation, observability) and the HTML/PDF design-review report.
# Each stage is announced with its expected duration; extra arguments go to `twin campaign run`
# (e.g. `--runs 8` for a quicker look).
set -euo pipefail
cd "$(dirname "$0")/.."
start=$SECONDS
echo "[     0 s] install: creating .venv and installing BenchTwin (about 1-3 min the first time, seconds after)"
bash scripts/setup.sh
echo "[$(printf '%6d' $((SECONDS - start))) s] install: done"
.venv/bin/twin campaign run campaigns/specs/demo.toml --out out/demo --analyze --report "$@"
echo "demo finished in $((SECONDS - start)) s"
