#!/usr/bin/env bash
# Builds the criterion benchmarks and the release binary here and puts what must travel to the
# GPU machine in .device/bench/: the stripped bench executables (gpu, cpu, frame, rays) and
# `manylights` (for the goals' culling spans), each xz-compressed to stay within what travels
# (64 MiB with the working tree), and the CUB script. Run them there with
# scripts/run-benches.sh, which unpacks them (see docs/BENCHMARKS.md and
# ../shared/docs/DEVICE.md).
set -euo pipefail
cd "$(dirname "$0")/.."
command -v xz > /dev/null || { echo "bench-bundle.sh needs xz (apt-get install xz-utils)" >&2; exit 1; }
mkdir -p .device/bench
rm -f .device/bench/gpu .device/bench/cpu .device/bench/frame .device/bench/rays .device/bench/manylights
cargo build --release --bin manylights
strip -o .device/bench/manylights target/release/manylights
cargo bench --no-run --message-format=json 2>/dev/null \
  | python3 -c 'import json,sys
for l in sys.stdin:
    m=json.loads(l)
    if m.get("reason")=="compiler-artifact" and m.get("executable") and "bench" in m["target"]["kind"] and m["target"]["name"] in ("gpu","cpu","frame","rays"):
        print(m["target"]["name"], m["executable"])' \
  | while read -r name exe; do strip -o ".device/bench/$name" "$exe"; done
for exe in gpu cpu frame rays manylights; do xz -T0 -6 -f ".device/bench/$exe"; done
cp scripts/bench_cub.py .device/bench/
echo "$(git rev-parse --short=12 HEAD)$(git diff --quiet HEAD -- . && echo "" || echo "-dirty")" > .device/bench/commit.txt
ls -la .device/bench
