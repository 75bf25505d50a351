#!/usr/bin/env bash
# Install BenchTwin into .venv and run the main job: simulate the nominal scene (Figs. 9.6/9.7) and plot it.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
.venv/bin/twin simulate nominal --out out/nominal.nc --plot out/nominal.png
