#!/usr/bin/env python3
"""Turns criterion's JSON (CRITERION_HOME of scripts/run-benches.sh) and the CUB JSON into the
Markdown tables of docs/BENCHMARKS.md.

usage: bench_tables.py CRITERION_GPU_DIR CRITERION_CPU_DIR CUB_JSON > tables.md
Times are criterion's median estimates of the GPU timestamp deltas (GPU benches) or wall time
(CPU benches)."""
import json
import os
import sys
from collections import defaultdict


def load(root):
    out = {}
    for dirpath, _, files in os.walk(root):
        if dirpath.endswith("/new") and "benchmark.json" in files and "estimates.json" in files:
            b = json.load(open(os.path.join(dirpath, "benchmark.json")))
            e = json.load(open(os.path.join(dirpath, "estimates.json")))
            out[b["full_id"]] = (b, e["median"]["point_estimate"] / 1e6)  # ns -> ms
    return out


def ms(v):
    return f"{v * 1000:.1f} µs" if v < 1 else f"{v:.2f} ms"


def main():
    gpu, cpu, cub = load(sys.argv[1]), load(sys.argv[2]), json.load(open(sys.argv[3]))
    p = print
    # Culling.
    for res in ["1920x1080", "3840x2160"]:
        counts = sorted({int(b["value_str"]) for b, _ in gpu.values() if b["group_id"].startswith("cull.") and b["function_id"] == res})
        if not counts:
            continue
        p(f"\n**Culling, atrium, {res}** (all culling passes of the strategy: median GPU time)\n")
        p("| strategy | " + " | ".join(f"{c:,}" for c in counts) + " |")
        p("|---|" + "---|" * len(counts))
        for s in ["tiled_gather", "tiled_scatter", "depth_mask", "clustered", "clustered_unordered", "tiled_gather_single"]:
            cells = [ms(gpu[f"cull.{s}/{res}/{c}"][1]) if f"cull.{s}/{res}/{c}" in gpu else "-" for c in counts]
            if any(c != "-" for c in cells):
                p(f"| {s} | " + " | ".join(cells) + " |")
    # The Forward+ paper's configuration.
    paper = sorted((b["function_id"], v) for b, v in gpu.values() if b["group_id"] == "cull.harada2012")
    if paper:
        p("\n**The Forward+ paper's configuration** (`cull.harada2012`: 3,072 lights, 1280x720; every culling pass)\n")
        p("| variant | GPU time |")
        p("|---|---|")
        for f, v in paper:
            p(f"| {f} | {ms(v)} |")
    # Culling and deferred lighting together.
    frames = sorted((b["function_id"], b["value_str"], v) for b, v in gpu.values() if b["group_id"] == "frame.cull_shade")
    if frames:
        p("\n**Culling and deferred lighting together** (`frame.cull_shade`: every culling pass and `shade.deferred` of back-to-back frames)\n")
        p("| setting | resolution / lights | GPU time |")
        p("|---|---|---|")
        for f, size, v in frames:
            p(f"| {f} | {size} | {ms(v)} |")
    # Sort.
    cubp = {r["n"]: r for r in cub["rows"] if r["kind"] == "pairs"}
    cubk = {r["n"]: r for r in cub["rows"] if r["kind"] == "keys"}
    p(f"\n**Radix sort of (u32 key, u32 value) pairs, random 32-bit keys** (CUB through CuPy {cub['cupy']}: argsort = SortPairs of (key, index); keys-only for reference)\n")
    p("| keys | sort.radix | G pairs/s | sort.radix_portable | G pairs/s | lampshade | G pairs/s | CUB pairs | G pairs/s | ours / CUB | CUB keys only |")
    p("|---|---|---|---|---|---|---|---|---|---|---|")

    def cell(v, n):
        return f"{ms(v)} | {n / v / 1e6:.2f}" if v else "- | -"

    for n in sorted(cubp):
        ours = gpu.get(f"sort.radix/{n}")
        if not ours:
            continue
        port = gpu.get(f"sort.radix_portable/{n}")
        lamp = gpu.get(f"sort.lampshade/{n}")
        o, c = ours[1], cubp[n]["ms"]
        p(f"| {n:,} | {cell(o, n)} | {cell(port[1] if port else None, n)} | {cell(lamp[1] if lamp else None, n)} | {cell(c, n)} | {c / o:.0%} | {ms(cubk[n]['ms'])} |")
    # Shading.
    p("\n**Shading at 4,096 lights, atrium, 1920x1080** (tiled gather 16 px lists; raster and compute passes apart)\n")
    p("| backend | frame | geometry pass (raster) | shading pass | shading kind |")
    p("|---|---|---|---|---|")
    rows = {}
    for fid, (b, v) in gpu.items():
        if b["group_id"].startswith("frame.") and b["group_id"] != "frame.cull_shade":
            rows[b["group_id"][6:]] = {"frame": v}
    for fid, (b, v) in gpu.items():
        g = b["group_id"]
        if g in ("prepass.depth", "shade.gbuffer", "shade.visibility"):
            rows[b["function_id"]]["geometry"] = v
        elif g in ("shade.forward", "shade.deferred", "shade.naive"):
            rows[b["function_id"]]["shade"] = v
            rows[b["function_id"]]["kind"] = "compute" if g == "shade.deferred" else "raster"
    for k in ["forward", "deferred", "deferred_stored_position", "naive_forward", "visibility"]:
        r = rows.get(k)
        if r:
            p(f"| {k} | {ms(r['frame'])} | {ms(r.get('geometry', 0))} | {ms(r.get('shade', 0))} | {r.get('kind', '')} |")
    if "forward" in rows and "naive_forward" in rows:
        p(f"\nForward+ against naive forward, whole frames: {rows['naive_forward']['frame'] / rows['forward']['frame']:.1f} times faster.")
    # CPU.
    p("\n**CPU side** (wall time, median)\n")
    p("| benchmark | time |")
    p("|---|---|")
    for fid in sorted(cpu):
        p(f"| {fid} | {ms(cpu[fid][1])} |")


if __name__ == "__main__":
    main()
