#!/usr/bin/env python3
"""The table of scripts/bench-ab.sh: each bench's criterion median for builds A and B in every
round, and B's median over rounds against A's.

usage: bench_ab.py OUT_DIR A_COMMIT B_COMMIT > ab.md"""
import os
import re
import statistics
import sys
from collections import defaultdict

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_tables import load  # noqa: E402  (criterion's medians, in ms)


def main():
    root, a, b = sys.argv[1], sys.argv[2], sys.argv[3]
    runs = defaultdict(dict)  # bench -> (side, round) -> µs
    rounds = set()
    for d in sorted(os.listdir(root)):
        m = re.fullmatch(r"([AB])-(\d+)", d)
        if m:
            rounds.add(int(m.group(2)))
            for bench, (_, ms) in load(os.path.join(root, d)).items():
                runs[bench][(m.group(1), int(m.group(2)))] = ms * 1e3
    rounds = sorted(rounds)
    head = " | ".join(f"{s} {r}" for r in rounds for s in "AB")
    print(f"A = {a}, B = {b}; criterion medians in µs, interleaved A B per round\n")
    print(f"| bench | {head} | B / A (medians over rounds) |")
    print("|---|" + "---|" * (2 * len(rounds) + 1))
    for bench in sorted(runs):
        t = runs[bench]
        cells = " | ".join(f"{t[(s, r)]:.1f}" if (s, r) in t else "-" for r in rounds for s in "AB")
        av = [t[("A", r)] for r in rounds if ("A", r) in t]
        bv = [t[("B", r)] for r in rounds if ("B", r) in t]
        ratio = f"{statistics.median(bv) / statistics.median(av):.3f}" if av and bv else "-"
        print(f"| {bench} | {cells} | {ratio} |")


if __name__ == "__main__":
    main()
