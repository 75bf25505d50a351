#!/usr/bin/env bash
# Install BenchTwin into .venv and run the main job: the demo Monte Carlo campaign (the Sec. 9.4 study,
# data sets 1-7, every Table 9.5 uncertainty, 50 runs per data set) on a local 2-worker dask cluster,
# its analysis (correlations, separation, observability), and the HTML/PDF design-review report.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
.venv/bin/twin campaign run campaigns/specs/demo.toml --out out/demo --analyze --report "$@"
