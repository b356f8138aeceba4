#!/usr/bin/env python3
"""Classify the false negatives of every scored list source of scripts/referee-bevy.sh.

usage: scripts/referee_misses.py SCORES_DIR RUN_DIR

For each setting and source whose score has false negatives, every (pixel, light) pair the
lists miss is found again from the export (the pixel's point from its depth and the camera, in
f64; a light reaches it inside its range and, for a spot, strictly inside its outer cone, as
`manylights score` decides) and put in the first class that fits:

- lookup: the pixel's cell by whole tiles (ceil(W / X) by ceil(H / Y) pixels, as Bevy's CPU
  clusterer bins the screen) differs from the cell the grid's lookup reads (proportional, as
  Bevy's shader), and that tile's cell lists the light;
- row: the cell of the next row up or down, same column and slice, lists it (a y-plane
  decision, as the sphere refinement's);
- column: the next column left or right lists it;
- slice: the next slice nearer or farther lists it;
- other.

Writes SCORES_DIR/misses.csv (one row a setting and source: pairs, each class, and the
distance over range of the pairs: min, median, max; spots among them) and misses.md.
Needs numpy.
"""
import csv
import json
import math
import os
import sys

import numpy as np


def load_export(d):
    m = lambda n: np.load(os.path.join(d, n)).astype(np.float64).reshape(4, 4)
    e = {
        "depth": np.load(os.path.join(d, "depth.npy")),
        "clip_from_world": m("clip_from_world.npy"),
        "view_from_world": m("view_from_world.npy"),
        "pos": np.load(os.path.join(d, "light_position.npy")).astype(np.float64),
        "radius": np.load(os.path.join(d, "light_radius.npy")).astype(np.float64),
        "kind": np.load(os.path.join(d, "light_kind.npy")),
        "axis": np.load(os.path.join(d, "light_direction.npy")).astype(np.float64),
        "cos": np.load(os.path.join(d, "light_cos_outer.npy")).astype(np.float64),
    }
    e["world_from_clip"] = np.linalg.inv(e["clip_from_world"])
    return e


def slice_of(g, d):
    z = g["dims"][2]
    s = g["slicing"]
    k = s["kind"]
    if k == "none":
        v = 0.0
    elif k == "linear":
        v = math.floor((d - s["near"]) / (s["far"] - s["near"]) * z)
    elif k == "exponential":
        v = math.floor(math.log(d / s["near"]) / math.log(s["far"] / s["near"]) * z)
    else:  # near_slice
        v = 0 if d < s["near"] else 1 + math.floor(math.log(d / s["near"]) * (z - 1) / math.log(s["far"] / s["near"]))
    return int(min(max(v, 0), z - 1))


def cell_index(g, x, y, z):
    nx, ny, nz = g["dims"]
    if g["order"] == "x_fastest":
        return (z * ny + y) * nx + x
    return (y * nx + x) * nz + z


def screen_cell(g, px, py):
    nx, ny, _ = g["dims"]
    if g["screen"]["kind"] == "tiles":
        tw, th = g["screen"]["tile_size"]
        return px // tw, py // th
    return ((2 * px + 1) * nx) // (2 * g["width"]), ((2 * py + 1) * ny) // (2 * g["height"])


def classify(setting, source, export, lists):
    g = json.load(open(os.path.join(lists, "grid.json")))
    offsets = np.load(os.path.join(lists, "offsets.npy")).astype(np.int64)
    indices = np.load(os.path.join(lists, "indices.npy")).astype(np.int64)
    if g.get("light_ids"):
        indices = np.load(os.path.join(lists, g["light_ids"])).astype(np.int64)[indices]
    cell = lambda c: set(indices[offsets[c]:offsets[c + 1]].tolist())
    e = export
    h, w = e["depth"].shape
    missed = np.load(os.path.join(scores_dir, setting, source, "false_negatives.npy"))
    nx, ny, nz = g["dims"]
    tw, th = -(-w // nx), -(-h // ny)
    counts = {"lookup": 0, "row": 0, "column": 0, "slice": 0, "other": 0}
    ratios, spots = [], 0
    for py, px in zip(*np.nonzero(missed)):
        ndc = np.array([(px + 0.5) / w * 2 - 1, 1 - (py + 0.5) / h * 2, float(e["depth"][py, px]), 1.0])
        p = e["world_from_clip"] @ ndc
        p = p[:3] / p[3]
        d_view = -(e["view_from_world"] @ np.append(p, 1.0))[2]
        x, y = screen_cell(g, px, py)
        z = slice_of(g, d_view)
        here = cell(cell_index(g, x, y, z))
        to_p = p - e["pos"]
        dist = np.linalg.norm(to_p, axis=1)
        reach = dist < e["radius"]
        spot = e["kind"] == 1
        with np.errstate(invalid="ignore", divide="ignore"):
            inside = (to_p * e["axis"]).sum(axis=1) / dist > e["cos"]
        reach &= ~spot | ((dist > 0) & inside)
        for l in np.nonzero(reach)[0].tolist():
            if l in here:
                continue
            ratios.append(dist[l] / e["radius"][l])
            spots += int(spot[l])
            near = lambda dx, dy, dz: [
                cell_index(g, x + dx * s if dx else x, y + dy * s if dy else y, z + dz * s if dz else z)
                for s in (-1, 1)
                if 0 <= x + dx * s < nx and 0 <= y + dy * s < ny and 0 <= z + dz * s < nz
            ]
            tx, ty = min(px // tw, nx - 1), min(py // th, ny - 1)
            if (tx, ty) != (x, y) and l in cell(cell_index(g, tx, ty, z)):
                counts["lookup"] += 1
            elif any(l in cell(c) for c in near(0, 1, 0)):
                counts["row"] += 1
            elif any(l in cell(c) for c in near(1, 0, 0)):
                counts["column"] += 1
            elif any(l in cell(c) for c in near(0, 0, 1)):
                counts["slice"] += 1
            else:
                counts["other"] += 1
    r = sorted(ratios)
    return {
        "setting": setting, "source": source, "pairs": len(r), **counts, "spots": spots,
        "d_over_r_min": round(float(r[0]), 4) if r else "", "d_over_r_median": round(float(r[len(r) // 2]), 4) if r else "",
        "d_over_r_max": round(float(r[-1]), 4) if r else "",
    }


scores_dir, run_dir = sys.argv[1], sys.argv[2]
cells = [l.rstrip("\n").split("\t") for l in open(os.path.join(scores_dir, "cells.tsv"))]
export_of = {}
for setting, _variant, cid, _w, _h in cells:
    export_of.setdefault(setting, os.path.join(run_dir, "cells", cid))
rows = []
for setting in sorted(export_of):
    export = None
    for source in sorted(os.listdir(os.path.join(scores_dir, setting))):
        f = os.path.join(scores_dir, setting, source, "score.json")
        if not os.path.isfile(f) or json.load(open(f))["false_negatives"] == 0:
            continue
        lists = os.path.join(scores_dir, setting, source, "lists")
        if not os.path.isdir(lists):
            lists = os.path.join(export_of[setting], "lists")
        export = export or load_export(export_of[setting])
        row = classify(setting, source, export, lists)
        expected = json.load(open(f))["false_negatives"]
        if row["pairs"] != expected:
            sys.exit(f"{setting} {source}: found {row['pairs']} pairs, the score has {expected}")
        rows.append(row)
        print(row)
keys = ["setting", "source", "pairs", "lookup", "row", "column", "slice", "other", "spots",
        "d_over_r_min", "d_over_r_median", "d_over_r_max"]
with open(os.path.join(scores_dir, "misses.csv"), "w", newline="") as f:
    wr = csv.DictWriter(f, keys)
    wr.writeheader()
    wr.writerows(rows)
with open(os.path.join(scores_dir, "misses.md"), "w") as f:
    f.write("| " + " | ".join(keys) + " |\n|" + "---|" * len(keys) + "\n")
    for r in rows:
        f.write("| " + " | ".join(str(r[k]) for k in keys) + " |\n")
print(f"{len(rows)} sources with misses: {scores_dir}/misses.csv, misses.md")
