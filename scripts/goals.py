#!/usr/bin/env python3
"""The goals' table of docs/BENCHMARKS.md ("Goals") from one run of scripts/run-benches.sh.

usage: goals.py OUT_DIR > goals.md

Reads OUT_DIR/criterion-gpu (the GPU and frame benchmarks, criterion's medians),
OUT_DIR/criterion-spans (the frame benchmark as spans), OUT_DIR/goals/*.log (`manylights cull
--repeat 50`, ordered and `--unordered`, each run twice: the faster of the two runs' medians
counts), OUT_DIR/cub.json where the CUB yardstick ran, and gpu.txt, date.txt and commit.txt for
the header. A goal whose figures are missing says so instead of a verdict."""
import json
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_tables import load  # noqa: E402  (criterion's medians, in ms)


def bench(results, group, function, value=None):
    """The median (ms) of the bench `group/function/value` (any value where None: the frame
    benchmark's sizes shrink in its quick mode)."""
    for b, v in results.values():
        if b["group_id"] == group and b["function_id"] == function and value in (None, b.get("value_str")):
            return v
    return None


def cull_log(path):
    """A `manylights cull --repeat` log's median run and span (ms) and false negatives."""
    if not os.path.exists(path):
        return None
    text = open(path).read()
    total = re.search(r"total \(median run\)\s+([0-9.]+) ms", text)
    span = re.search(r"span \(one timestamp pair\)\s+([0-9.]+) ms", text)
    fneg = re.search(r"false negatives\s+(\d+)", text)
    if not (total and span):
        return None
    return float(total.group(1)), float(span.group(1)), int(fneg.group(1)) if fneg else None


def check(root, name):
    """The faster of a check's two runs (a, b): (median run, span, false negatives)."""
    runs = [r for r in (cull_log(os.path.join(root, "goals", f"{name}-{x}.log")) for x in "ab") if r]
    return min(runs) if runs else None


def us(v):
    return f"{v * 1000:.1f} µs" if v < 1 else f"{v:.3f} ms"


def verdict(value, goal):
    if value is None:
        return "not measured in this run"
    if value <= goal:
        return "yes"
    return f"no, {value / goal:.2f}x over"


def read(root, name):
    p = os.path.join(root, name)
    return open(p).read().strip() if os.path.exists(p) else "?"


def main():
    root = sys.argv[1]
    gpu = load(os.path.join(root, "criterion-gpu"))
    spans = load(os.path.join(root, "criterion-spans"))
    rows = []

    def frame_row(goal_text, function, goal_ms):
        v = bench(gpu, "frame.cull_shade", function)
        s = bench(spans, "frame.cull_shade", function)
        got = "-" if v is None else f"**{us(v)}**" + (f" (span {us(s)})" if s else "")
        rows.append((goal_text, f"`frame.cull_shade/{function}`: {got}", verdict(v, goal_ms)))

    paper = bench(gpu, "cull.harada2012", "tiled_gather8")
    rows.append(("the Forward+ paper's configuration culled in under 50 µs (issue 6)",
                 "-" if paper is None else f"`cull.harada2012/tiled_gather8`: **{us(paper)}** (box test on)",
                 verdict(paper, 0.050)))
    million = bench(gpu, "cull.clustered_unordered", "1920x1080", "1048576")
    rows.append(("1M point lights at 1920x1080 culled in under 1 ms, unordered (issue 6)",
                 "-" if million is None else f"`cull.clustered_unordered/1920x1080/1048576`: **{us(million)}**",
                 verdict(million, 1.0)))
    cub_path = os.path.join(root, "cub.json")
    sort = gpu.get("sort.radix/16777216", (None, None))[1]
    if os.path.exists(cub_path) and sort:
        cub = {r["n"]: r["ms"] for r in json.load(open(cub_path))["rows"] if r["kind"] == "pairs"}
        rate = cub.get(16777216, 0) / sort
        rows.append(("radix sort at least a quarter of CUB's rate at 16M pairs (issue 6)",
                     f"`sort.radix` {us(sort)} against CUB {us(cub.get(16777216, 0))}: **{rate:.0%}**",
                     "yes" if rate >= 0.25 else f"no, {rate:.0%}"))
    frame_row("Forward+ configuration: culling + deferred lighting at most 150 µs (issues 21, 33)",
              "harada2012_gather8", 0.150)
    frame_row("the same into a 16-bit float lit image (`hdr: F16`, issue 33)",
              "harada2012_gather8_f16", 0.150)
    frame_row("CIS 5650 hall, 5,000 lights: twice as fast as gather was (414.7 µs), at most 207 µs (issue 33)",
              "cis5650_5k_gather", 0.207)
    frame_row("the same hall in 24-pixel tiles, gather's fastest there (issue 33)",
              "cis5650_5k_gather24", 0.207)
    frame_row("the same hall, 16-bit float lit image, 16 and 24 px (issue 33): 16 px",
              "cis5650_5k_gather_f16", 0.207)
    frame_row("the same, 24 px", "cis5650_5k_gather24_f16", 0.207)
    frame_row("1M lights at 1080p: culling + deferred lighting under 2 ms, ordered (issues 21, 33)",
              "atrium_1m_clustered32x32", 2.0)
    frame_row("the same at 24 px x 48 slices (issue 33)",
              "atrium_1m_clustered24x48", 2.0)
    frame_row("the same at 24 px x 32 slices (issue 33)",
              "atrium_1m_clustered24x32", 2.0)
    h500 = check(root, "hall500_clusters64x24")
    rows.append(("clusters at 500 lights: culling at most 60 µs as a span (issue 33)",
                 "-" if h500 is None else f"hall, 64 px x 24: span **{us(h500[1])}** (summed {us(h500[0])})",
                 verdict(h500[1] if h500 else None, 0.060)))
    for name, what in [("hall500_clusters64x24", "500 lights in the hall, 64 x 24"),
                       ("hall50k_clusters64x24", "50,000 lights in the hall, 64 x 24"),
                       ("atrium1m_clusters32x32", "1M lights in the atrium, 32 x 32")]:
        o, u = check(root, name), check(root, name + "_unordered")
        if o and u:
            ratio = o[0] / u[0]
            got = f"{what}: **{ratio:.2f}x** ({us(o[0])} against {us(u[0])}; spans {o[1] / u[1]:.2f}x)"
        else:
            ratio, got = None, f"{what}: -"
        met = "not measured in this run" if ratio is None else "yes" if ratio <= 1.3 else f"no, {ratio:.2f}x"
        rows.append(("ordered lists within 1.3x of unordered (issue 33)", got, met))
    logs = os.path.join(root, "goals")
    fneg = []
    for name in sorted(os.listdir(logs)) if os.path.isdir(logs) else []:
        r = cull_log(os.path.join(logs, name))
        if r and r[2]:
            fneg.append(name)
    print(f"{read(root, 'gpu.txt')}; {read(root, 'date.txt')}; commit {read(root, 'commit.txt')}; "
          "criterion medians of per-pass sums unless a span is named; culling checks: the faster "
          "of two runs of `manylights cull --repeat 50`"
          + (f". False negatives in: {', '.join(fneg)}" if fneg else ". No false negative in any check") + ".\n")
    print("| goal | measured | met |")
    print("| --- | --- | --- |")
    for goal, got, met in rows:
        print(f"| {goal} | {got} | {met} |")


if __name__ == "__main__":
    main()
