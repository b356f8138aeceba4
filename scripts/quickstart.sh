#!/usr/bin/env bash
# The quickstart: checks the machine, builds the release binary and renders the atrium with the
# brute-force reference renderer (256 lights, 640x360), printing per-pass GPU times and writing
# out/quickstart/reference.png and .exr. About a minute on lavapipe, most of it the build.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/ensure-vulkan.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cargo run --release --quiet -- render --scene atrium --lights 256 --width 640 --height 360 --out out/quickstart "$@"
