#!/usr/bin/env bash
# The quickstart: checks the machine, builds the release binary and runs
# experiments/quickstart.ron (four culling strategies, forward, deferred and the visibility buffer,
# on the atrium and Sponza), which renders, measures, and writes out/quickstart/results.csv,
# results.json and report.html (with report.md and figures). About half a minute on lavapipe
# plus the first build.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/ensure-vulkan.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo run --release --quiet -- run experiments/quickstart.ron --out out/quickstart "$@"
