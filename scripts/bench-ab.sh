#!/usr/bin/env bash
# On the GPU machine, from the repository root: the GPU benches of two builds side by side in one
# run, interleaved (A B A B ...), so that a change is compared with the build before it on one
# machine at one time (the machines vary by several percent). Each build is a folder holding the
# bundle of scripts/bench-bundle.sh (its `gpu` bench executable, unpacked here from gpu.xz) and
# its commit.txt.
#
# usage: bench-ab.sh A_DIR B_DIR ROUNDS FILTER OUT_DIR [MORE_ENV]
#   FILTER: criterion's regex over bench ids, such as 'cull\.harada2012/tiled_gather8/'
#   MORE_ENV: variables for both builds, such as MANYLIGHTS_BENCH_SPANS=1
#   BENCH_EXE (environment): which bench executable of each build runs (gpu by default; frame
#   for frame.cull_shade)
# Leaves criterion's JSON in OUT_DIR/<A|B>-<round>/ and the table of medians in OUT_DIR/ab.md
# (scripts/bench_ab.py).
set -uo pipefail
a="$1"; b="$2"; rounds="$3"; filter="$4"; out="$5"; more="${6:-}"
exe="${BENCH_EXE:-gpu}"
mkdir -p "$out"
source "$(dirname "$0")/bench-unpack.sh" "$a" "$b"
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader > "$out/gpu.txt" 2>/dev/null || true
date -u +%Y-%m-%dT%H:%M:%SZ > "$out/date.txt"
for r in $(seq 1 "$rounds"); do
  for side in A B; do
    dir="$a"; [ "$side" = B ] && dir="$b"
    echo "== $side ($(cat "$dir/commit.txt" 2>/dev/null)) round $r $more" | tee -a "$out/ab.log"
    env $more CRITERION_HOME="$out/$side-$r" "$dir/$exe" --bench "$filter" >> "$out/ab.log" 2>&1
  done
done
python3 "$(dirname "$0")/bench_ab.py" "$out" "$(cat "$a/commit.txt" 2>/dev/null)" "$(cat "$b/commit.txt" 2>/dev/null)" > "$out/ab.md"
cat "$out/ab.md"
