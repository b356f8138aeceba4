#!/usr/bin/env bash
# On the GPU machine, from the repository root, after scripts/bench-bundle.sh ran on the
# development machine: unpacks the Vulkan loader and the executables, runs the GPU and CPU
# benchmarks, the frame benchmark per pass and as spans, the goals' culling checks
# (`manylights cull --repeat 50`, each twice) and the CUB yardstick, and leaves criterion's
# JSON, the logs, the CUB JSON and the adapter in OUT_DIR (default bench-out). Turn them into
# tables with scripts/bench_tables.py and the goals' table with scripts/goals.py.
# GOALS_ONLY=1 runs only what the goals need (the frame benchmark and the culling checks).
set -uo pipefail
OUT_DIR="${1:-bench-out}"
mkdir -p "$OUT_DIR/goals"
source "$(dirname "$0")/bench-unpack.sh" .device/bench
B=.device/bench
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader > "$OUT_DIR/gpu.txt" 2>/dev/null || true
date -u +%Y-%m-%dT%H:%M:%SZ > "$OUT_DIR/date.txt"
cp "$B/commit.txt" "$OUT_DIR/" 2>/dev/null || true
if [ "${GOALS_ONLY:-0}" = 0 ]; then
  CRITERION_HOME="$OUT_DIR/criterion-gpu" "$B/gpu" --bench 2>&1 | tee "$OUT_DIR/gpu.log" | grep -E "adapter|time:" | head -5
fi
CRITERION_HOME="$OUT_DIR/criterion-gpu" "$B/frame" --bench > "$OUT_DIR/frame.log" 2>&1
MANYLIGHTS_BENCH_SPANS=1 CRITERION_HOME="$OUT_DIR/criterion-spans" "$B/frame" --bench > "$OUT_DIR/frame-spans.log" 2>&1
# The goals' culling spans, ordered and not (docs/BENCHMARKS.md, "Goals"): each check twice,
# the first after the benches' load, so the GPU's clock is up for the second.
HALL="--scene cis5650 --generator uniform --seed 5650 --radius 2 --intensity 4 --width 1920 --height 1080"
M1="--scene atrium --lights 1048576 --generator uniform --seed 1000000 --radius 0.5 --intensity 0.5 --width 1920 --height 1080"
checks=(
  "hall500_clusters64x24|$HALL --lights 500 --strategy clustered --tile-size 64 --slices 24"
  "hall50k_clusters64x24|$HALL --lights 50000 --strategy clustered --tile-size 64 --slices 24"
  "atrium1m_clusters32x32|$M1 --strategy clustered --tile-size 32 --slices 32"
)
for c in "${checks[@]}"; do
  name=${c%%|*}; args=${c#*|}
  for run in a b; do
    "$B/manylights" cull $args --repeat 50 --out /tmp/goal-cull > "$OUT_DIR/goals/$name-$run.log" 2>&1
    "$B/manylights" cull $args --unordered --repeat 50 --out /tmp/goal-cull > "$OUT_DIR/goals/${name}_unordered-$run.log" 2>&1
  done
done
if [ "${GOALS_ONLY:-0}" = 0 ]; then
  CRITERION_HOME="$OUT_DIR/criterion-cpu" "$B/cpu" --bench > "$OUT_DIR/cpu.log" 2>&1
  # Shadow rays a second (benches/rays.rs; Sponza and the kitchen: scripts/device-tree.sh
  # sponza kitchen before the call).
  CRITERION_HOME="$OUT_DIR/criterion-gpu" "$B/rays" --bench > "$OUT_DIR/rays.log" 2>&1
  python3 "$B/bench_cub.py" "$OUT_DIR/cub.json" > "$OUT_DIR/cub.log" 2>&1 || echo "CUB script failed: see cub.log"
fi
echo "done: python3 scripts/goals.py $OUT_DIR"
