#!/usr/bin/env bash
# The Bevy referee over experiments/referee-bevy.ron (issue 47): run the experiment (its frames
# exported with this workbench's lists; a rerun skips finished cells), hand each setting's frame
# to Bevy's CPU clusterer (referees/bevy) and its GPU clusterer (referees/bevy-gpu) under each
# configuration below, score every list
# source with `manylights score`, and write OUT/scores.csv and OUT/scores.md (one row a setting
# and list source). Heatmaps of each source's false negatives and extra lights are under
# OUT/<setting>/<source>/.
#
# usage: scripts/referee-bevy.sh [RUN_DIR] [OUT_DIR]
#   RUN_DIR  the experiment's run (default out/referee-bevy/run)
#   OUT_DIR  the scores (default out/referee-bevy/scores)
# Environment: EXPERIMENT (default experiments/referee-bevy.ron; a smaller copy for a quick
# check), MANYLIGHTS (the binary; default target/release/manylights, built if missing),
# BEVY_REFEREE (the adapter; default referees/bevy/target/release/manylights-bevy-referee,
# built if missing), BEVY_GPU_REFEREE (the GPU clusterer's adapter; default
# referees/bevy-gpu/target/release/manylights-bevy-gpu-referee, built if missing),
# MANYLIGHTS_ADAPTER (the GPU that renders the frames; Bevy picks its own), JOBS (lists
# and scores made at a time; default 1), RESUME=1 (keep the lists and scores a stopped run finished; by
# default every source is made and scored again).
#
# List sources: Bevy's default grid (FixedZ, 4,096 clusters, 24 slices, first slice 5 m, far
# bound at the previous frame's farthest light); Bevy's fixed XYZ grid of 32 px and 32 slices
# (the size of this workbench's best cluster grid at 1080p); Bevy's knobs one at a time: the
# first slice 0.5, 1 and 2 m deep, 12 and 48 z slices, the far bound at the camera's far plane;
# the same for Bevy's GPU clusterer (bevy-gpu-*), whose lists are read once three frames give
# the same, and a run of it with Bevy's own initial list capacities (its frames' entries in
# OUT/settle.md, not scored: settle.md says whether its settled lists are bevy-gpu-default's);
# this workbench's cluster test on the default and the XYZ grid's cells (`score
# --cluster-on-grid`); and this workbench's lists for each variant of the experiment. Then
# scripts/referee_misses.py classifies every false negative (OUT/misses.csv, misses.md).
# `manylights score-chart` draws the scores (OUT/figures/scores.svg).
set -euo pipefail
cd "$(dirname "$0")/.."
RUN=${1:-out/referee-bevy/run}
OUT=${2:-out/referee-bevy/scores}
M=${MANYLIGHTS:-target/release/manylights}
REF=${BEVY_REFEREE:-referees/bevy/target/release/manylights-bevy-referee}
EXPERIMENT=${EXPERIMENT:-experiments/referee-bevy.ron}
command -v python3 >/dev/null || { echo "error: python3 is needed to list the run's cells" >&2; exit 1; }
python3 -c "import numpy" 2>/dev/null || { echo "error: numpy is needed to classify the misses (pip install numpy)" >&2; exit 1; }
[ -x "$M" ] || cargo build --release
[ -x "$REF" ] || cargo build --release --manifest-path referees/bevy/Cargo.toml
GPU_REF=${BEVY_GPU_REFEREE:-referees/bevy-gpu/target/release/manylights-bevy-gpu-referee}
# rustup takes the toolchain from referees/bevy-gpu/rust-toolchain.toml there.
[ -x "$GPU_REF" ] || (cd referees/bevy-gpu && cargo build --release)
"$M" run "$EXPERIMENT" --out "$RUN"
mkdir -p "$OUT"
# setting, variant, id, width, height: one line a cell.
python3 - "$RUN/results.json" > "$OUT/cells.tsv" <<'PY'
import json, sys
for r in json.load(open(sys.argv[1])):
    parts = dict(p.split("=", 1) for p in r["cell"].split(","))
    print(parts["setting"], parts["variant"], r["id"], r["width"], r["height"], sep="\t")
PY
score() { # setting source export lists [score's options]
    local dir="$OUT/$1/$2"
    [ "${RESUME:-0}" = 1 ] && [ -f "$dir/score.json" ] && return
    mkdir -p "$dir"
    "$M" score --export "$3" --lists "$4" --out "$dir" "${@:5}" > "$dir/score.txt"
    echo "$1 $2: $(grep -m1 'false negatives' "$dir/score.txt")"
}
# One source's lists of a setting's frame, scored; on Bevy's default and XYZ grids also this
# workbench's cluster test on exactly those cells (the grid's cost apart from the test's).
source_lists() { # setting export_dir source clusterer [adapter options]
    local setting=$1 export_dir=$2 source=$3 clusterer=$4 adapter=$REF
    local lists="$OUT/$setting/$source/lists"
    [ "$clusterer" = cpu ] || adapter=$GPU_REF
    # The adapters write grid.json last.
    if [ "${RESUME:-0}" != 1 ] || [ ! -f "$lists/grid.json" ]; then
        "$adapter" "$export_dir" "$lists" "${@:5}" > "$OUT/$setting/$source.adapter.txt" 2>&1 \
            || { cat "$OUT/$setting/$source.adapter.txt" >&2; exit 1; }
    fi
    [ "$clusterer" = gpu-log ] && return
    score "$setting" "$source" "$export_dir" "$lists"
    case $source in
        bevy-default | bevy-xyz-32px-32)
            score "$setting" "manylights-on-$source" "$export_dir" "$lists" --cluster-on-grid ;;
    esac
}
# JOBS lists and scores at a time (each in the background; a failure stops the script).
JOBS=${JOBS:-1}
throttle() { while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do wait -n; done; }
declare -A seen
while IFS=$'\t' read -r setting variant id w h; do
    export_dir="$RUN/cells/$id"
    throttle
    score "$setting" "manylights-$variant" "$export_dir" "$export_dir/lists" < /dev/null &
    [ -n "${seen[$setting]:-}" ] && continue
    seen[$setting]=1
    mkdir -p "$OUT/$setting"
    xyz="$(( (w + 31) / 32 )),$(( (h + 31) / 32 )),32"
    while read -r source clusterer args; do
        throttle
        # shellcheck disable=SC2086
        source_lists "$setting" "$export_dir" "$source" "$clusterer" $args < /dev/null &
    done <<SOURCES
bevy-default cpu
bevy-xyz-32px-32 cpu --xyz $xyz
bevy-first-slice-0.5 cpu --first-slice-depth 0.5
bevy-first-slice-1 cpu --first-slice-depth 1
bevy-first-slice-2 cpu --first-slice-depth 2
bevy-z-12 cpu --z-slices 12
bevy-z-48 cpu --z-slices 48
bevy-far-camera cpu --far-z camera
bevy-gpu-default gpu
bevy-gpu-xyz-32px-32 gpu --xyz $xyz
bevy-gpu-first-slice-0.5 gpu --first-slice-depth 0.5
bevy-gpu-first-slice-1 gpu --first-slice-depth 1
bevy-gpu-first-slice-2 gpu --first-slice-depth 2
bevy-gpu-z-12 gpu --z-slices 12
bevy-gpu-z-48 gpu --z-slices 48
bevy-gpu-far-camera gpu --far-z camera
bevy-gpu-initial-capacities gpu-log --z-slice-capacity 1024 --index-capacity 65536
SOURCES
done < "$OUT/cells.tsv"
for job in $(jobs -p); do wait "$job"; done
python3 - "$OUT" <<'PY'
import csv, json, os, sys
out = sys.argv[1]
rows = []
for setting in sorted(os.listdir(out)):
    if not os.path.isdir(os.path.join(out, setting)):
        continue
    for source in sorted(os.listdir(os.path.join(out, setting))):
        f = os.path.join(out, setting, source, "score.json")
        if not os.path.isfile(f):
            continue
        s = json.load(open(f))
        rows.append({
            "setting": setting, "source": source, "grid": s["source"],
            "false_negatives": s["false_negatives"],
            "pixels_with_false_negatives": s["pixels_with_false_negatives"],
            "evaluated_per_needed": round(s["false_positive_ratio"], 3),
            "lights_per_pixel": round(s["lights_per_pixel_mean"], 2),
            "needed_per_pixel": round(s["lights_needed_per_pixel_mean"], 2),
            "longest_list": s["max_lights_per_cell"], "cells": s["cells"],
            "list_kib": round(s["list_bytes"] / 1024, 1),
        })
keys = list(rows[0].keys())
with open(os.path.join(out, "scores.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, keys); w.writeheader(); w.writerows(rows)
with open(os.path.join(out, "scores.md"), "w") as f:
    cols = [k for k in keys if k != "grid"]
    f.write("| " + " | ".join(cols) + " |\n|" + "---|" * len(cols) + "\n")
    for r in rows:
        f.write("| " + " | ".join(str(r[k]) for k in cols) + " |\n")
print(f"{len(rows)} scores: {out}/scores.csv, {out}/scores.md")
PY
# How many frames Bevy's GPU clusterer took to settle, and each frame's entries (the adapter's
# log): with the list capacities at their bounds, and with Bevy's own initial capacities.
python3 - "$OUT" <<'PY'
import os, re, sys
out = sys.argv[1]
lines = ["| setting | source | frames | entries each frame (dropped past the index list) | "
         "settled lists the same as bevy-gpu-default's |", "|---|---|---|---|---|"]
same = lambda a, b: all(
    open(os.path.join(a, "lists", n), "rb").read() == open(os.path.join(b, "lists", n), "rb").read()
    for n in ("grid.json", "offsets.npy", "indices.npy"))
for setting in sorted(os.listdir(out)):
    d = os.path.join(out, setting)
    if not os.path.isdir(d):
        continue
    for f in sorted(os.listdir(d)):
        if not (f.startswith("bevy-gpu-") and f.endswith(".adapter.txt")):
            continue
        frames = re.findall(r"^frame \d+: .*?, (\d+) entries, index list capacity \d+, (\d+) dropped",
                            open(os.path.join(d, f)).read(), re.M)
        each = ", ".join(e + (f" ({x})" if x != "0" else "") for e, x in frames)
        source = f[:-len(".adapter.txt")]
        alike = ("" if source != "bevy-gpu-initial-capacities" else
                 "yes" if same(os.path.join(d, source), os.path.join(d, "bevy-gpu-default")) else "no")
        lines.append(f"| {setting} | {source} | {len(frames)} | {each} | {alike} |")
open(os.path.join(out, "settle.md"), "w").write("\n".join(lines) + "\n")
print(f"{len(lines) - 2} GPU clusterer runs: {out}/settle.md")
PY
"$M" score-chart "$OUT"
python3 scripts/referee_misses.py "$OUT" "$RUN"
