#!/usr/bin/env bash
# Builds the criterion benchmarks here and puts what must travel to the GPU machine in
# .device/bench/: the stripped bench executables (gpu, cpu, frame) and the CUB script. Run them
# there with scripts/run-benches.sh (see docs/BENCHMARKS.md and ../shared/docs/DEVICE.md).
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p .device/bench
cargo bench --no-run --message-format=json 2>/dev/null \
  | python3 -c 'import json,sys
for l in sys.stdin:
    m=json.loads(l)
    if m.get("reason")=="compiler-artifact" and m.get("executable") and "bench" in m["target"]["kind"] and m["target"]["name"] in ("gpu","cpu","frame"):
        print(m["target"]["name"], m["executable"])' \
  | while read -r name exe; do cp "$exe" ".device/bench/$name"; strip ".device/bench/$name"; done
cp scripts/bench_cub.py .device/bench/
echo "$(git rev-parse --short=12 HEAD)$(git diff --quiet HEAD -- . && echo "" || echo "-dirty")" > .device/bench/commit.txt
ls -la .device/bench
