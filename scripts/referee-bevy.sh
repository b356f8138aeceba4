#!/usr/bin/env bash
# The Bevy referee over experiments/referee-bevy.ron (issue 47): run the experiment (its frames
# exported with this workbench's lists; a rerun skips finished cells), hand each setting's frame
# to Bevy's CPU clusterer (referees/bevy) under each configuration below, score every list
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
# built if missing), MANYLIGHTS_ADAPTER (the GPU).
#
# List sources: Bevy's default grid (FixedZ, 4,096 clusters, 24 slices, first slice 5 m, far
# bound at the previous frame's farthest light); Bevy's fixed XYZ grid of 32 px and 32 slices
# (the size of this workbench's best cluster grid at 1080p); Bevy's knobs one at a time: the
# first slice 0.5, 1 and 2 m deep, 12 and 48 z slices, the far bound at the camera's far plane;
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
    mkdir -p "$dir"
    "$M" score --export "$3" --lists "$4" --out "$dir" "${@:5}" > "$dir/score.txt"
    echo "$1 $2: $(grep -m1 'false negatives' "$dir/score.txt")"
}
declare -A seen
while IFS=$'\t' read -r setting variant id w h; do
    export_dir="$RUN/cells/$id"
    score "$setting" "manylights-$variant" "$export_dir" "$export_dir/lists"
    [ -n "${seen[$setting]:-}" ] && continue
    seen[$setting]=1
    xyz="$(( (w + 31) / 32 )),$(( (h + 31) / 32 )),32"
    while read -r source args; do
        lists="$OUT/$setting/$source/lists"
        # shellcheck disable=SC2086
        "$REF" "$export_dir" "$lists" $args > "$OUT/$setting/$source.adapter.txt" 2>&1 \
            || { cat "$OUT/$setting/$source.adapter.txt" >&2; exit 1; }
        score "$setting" "$source" "$export_dir" "$lists"
    done <<SOURCES
bevy-default
bevy-xyz-32px-32 --xyz $xyz
bevy-first-slice-0.5 --first-slice-depth 0.5
bevy-first-slice-1 --first-slice-depth 1
bevy-first-slice-2 --first-slice-depth 2
bevy-z-12 --z-slices 12
bevy-z-48 --z-slices 48
bevy-far-camera --far-z camera
SOURCES
    # This workbench's cluster test on exactly Bevy's cells: the grid's cost apart from the test's.
    for grid in bevy-default bevy-xyz-32px-32; do
        score "$setting" "manylights-on-$grid" "$export_dir" "$OUT/$setting/$grid/lists" --cluster-on-grid
    done
done < "$OUT/cells.tsv"
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
"$M" score-chart "$OUT"
python3 scripts/referee_misses.py "$OUT" "$RUN"
