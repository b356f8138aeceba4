#!/usr/bin/env python3
"""NVIDIA CUB's radix sort through CuPy, on the GPU machine, as the yardstick of sort.radix.

cupy.sort of uint32 keys is CUB's DeviceRadixSort::SortKeys; cupy.argsort is its SortPairs with
(key, index) pairs, the same work as sort.radix's (key, value). Times are CUDA events, median of
10 after 3 warm-ups. Writes JSON to the path given (default: cub.json)."""
import json
import sys

import cupy as cp

out = sys.argv[1] if len(sys.argv) > 1 else "cub.json"
rows = []
for n in [1 << 20, 1 << 22, 1 << 24, 1 << 26]:
    keys = cp.random.randint(0, 2**32, size=n, dtype=cp.uint64).astype(cp.uint32)
    for kind, fn in [("keys", cp.sort), ("pairs", cp.argsort)]:
        for _ in range(3):
            fn(keys)
        times = []
        for _ in range(10):
            a, b = cp.cuda.Event(), cp.cuda.Event()
            a.record()
            fn(keys)
            b.record()
            b.synchronize()
            times.append(cp.cuda.get_elapsed_time(a, b))
        times.sort()
        ms = times[len(times) // 2]
        rows.append({"n": n, "kind": kind, "ms": ms, "gkeys_per_s": n / ms / 1e6})
        print(f"CUB {kind} n={n}: {ms:.3f} ms, {n / ms / 1e6:.2f} G/s", flush=True)
json.dump({"device": cp.cuda.runtime.getDeviceProperties(0)["name"].decode(), "cupy": cp.__version__, "rows": rows}, open(out, "w"), indent=1)
