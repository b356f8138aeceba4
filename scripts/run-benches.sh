#!/usr/bin/env bash
# On the GPU machine, from the repository root, after scripts/bench-bundle.sh ran on the
# development machine: unpacks the Vulkan loader, runs the GPU and CPU benchmarks and the CUB
# yardstick, and leaves criterion's JSON, the CUB JSON and the adapter in OUT_DIR (default
# bench-out). Turn them into tables with scripts/bench_tables.py.
set -uo pipefail
OUT_DIR="${1:-bench-out}"
mkdir -p "$OUT_DIR"
for f in .device/gl/*.deb; do dpkg -x "$f" /; done; ldconfig
export XDG_RUNTIME_DIR=/tmp CRITERION_HOME="$OUT_DIR/criterion"
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader > "$OUT_DIR/gpu.txt" 2>/dev/null || true
date -u +%Y-%m-%dT%H:%M:%SZ > "$OUT_DIR/date.txt"
cp .device/bench/commit.txt "$OUT_DIR/" 2>/dev/null || true
.device/bench/gpu --bench 2>&1 | tee "$OUT_DIR/gpu.log" | grep -E "adapter|time:" | head -5
.device/bench/frame --bench > "$OUT_DIR/frame.log" 2>&1
.device/bench/cpu --bench > "$OUT_DIR/cpu.log" 2>&1
python3 .device/bench/bench_cub.py "$OUT_DIR/cub.json" > "$OUT_DIR/cub.log" 2>&1 || echo "CUB script failed: see cub.log"
