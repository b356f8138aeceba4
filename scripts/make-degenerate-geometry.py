#!/usr/bin/env python3
"""Writes experiments/stability/assets/degenerate-geometry.gltf, stability case 19's glTF file:
what real files hold that procedural scenes do not, before a floor and a back wall in view of
the file's camera. Rows of problem triangles: zero-area ones (three collinear vertices, and
all three the same vertex), slivers (a thousandth of a millimetre wide, some seen edge on),
fans of triangles sharing duplicated vertices, vertices whose normals point opposite ways
(flipped: the interpolated normal passes through zero inside the triangle), and zero-length
normals. The buffer is embedded as base64. Run from the repository root:

    python3 scripts/make-degenerate-geometry.py
"""
import base64
import json
import math
import struct
from pathlib import Path

OUT = Path("experiments/stability/assets/degenerate-geometry.gltf")


def tri(pos, nrm, out):
    base = len(out[0])
    out[0].extend(pos)
    out[1].extend(nrm)
    out[2].extend([base, base + 1, base + 2])


def main():
    pos, nrm, idx = [], [], []
    geo = (pos, nrm, idx)
    up, front = (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
    # The floor and the back wall (y = 0, z = -3).
    for a, b, c in (((-6, 0, -3), (6, 0, -3), (6, 0, 4)), ((-6, 0, -3), (6, 0, 4), (-6, 0, 4))):
        tri([a, b, c], [up] * 3, geo)
    for a, b, c in (((-6, 0, -3), (6, 4, -3), (6, 0, -3)), ((-6, 0, -3), (-6, 4, -3), (6, 4, -3))):
        tri([a, b, c], [front] * 3, geo)
    for k in range(8):
        x = -4.5 + 1.2 * k
        # Zero area: collinear vertices, and one vertex three times.
        tri([(x, 0.5, 0), (x + 0.5, 1.0, 0), (x + 1.0, 1.5, 0)], [front] * 3, geo)
        tri([(x, 2.0, 0)] * 3, [front] * 3, geo)
        # Slivers: 1e-6 m wide, facing the camera and seen edge on (in the plane of the ray).
        tri([(x, 0.2, 0.5), (x + 1.0, 0.2, 0.5), (x + 0.5, 0.2 + 1e-6, 0.5)], [front] * 3, geo)
        tri([(x, 1.0, 2.0), (x, 1.0 + 0.8, 2.0 - 3.0), (x + 1e-6, 1.0, 2.0)], [(1.0, 0.0, 0.0)] * 3, geo)
        # Duplicated vertices: a fan whose triangles repeat the same positions.
        c = (x + 0.5, 2.8, -1.0)
        for j in range(4):
            a0, a1 = j * math.pi / 2, (j + 1) * math.pi / 2
            tri([c, (c[0] + 0.4 * math.cos(a0), c[1] + 0.4 * math.sin(a0), c[2]),
                 (c[0] + 0.4 * math.cos(a1), c[1] + 0.4 * math.sin(a1), c[2])], [front] * 3, geo)
            tri([c, (c[0] + 0.4 * math.cos(a0), c[1] + 0.4 * math.sin(a0), c[2]),
                 (c[0] + 0.4 * math.cos(a1), c[1] + 0.4 * math.sin(a1), c[2])], [front] * 3, geo)
        # Flipped normals: opposite at two vertices, so the interpolated normal passes zero.
        tri([(x, 0.3, 1.2), (x + 1.0, 0.3, 1.2), (x + 0.5, 1.3, 1.2)],
            [front, (0.0, 0.0, -1.0), (0.0, 0.0, 0.0)], geo)
        # Zero-length normals at every vertex (the importer stands +Y in).
        tri([(x, 1.5, 1.0), (x + 1.0, 1.5, 1.0), (x + 0.5, 2.3, 1.0)], [(0.0, 0.0, 0.0)] * 3, geo)
    blob = bytearray()
    views, accessors = [], []
    for name, data, fmt, kind in (("POSITION", pos, "f", "VEC3"), ("NORMAL", nrm, "f", "VEC3"),
                                  ("indices", idx, "I", "SCALAR")):
        while len(blob) % 4:
            blob.append(0)
        start = len(blob)
        flat = [float(c) if fmt == "f" else c for p in data for c in (p if isinstance(p, tuple) else (p,))]
        blob += struct.pack("<%d%s" % (len(flat), fmt), *flat)
        views.append({"buffer": 0, "byteOffset": start, "byteLength": len(blob) - start})
        a = {"bufferView": len(views) - 1, "componentType": 5126 if fmt == "f" else 5125,
             "count": len(data), "type": kind}
        if name == "POSITION":
            a["min"] = [min(p[k] for p in data) for k in range(3)]
            a["max"] = [max(p[k] for p in data) for k in range(3)]
        accessors.append(a)
    gltf = {
        "asset": {"version": "2.0", "generator": "manylights scripts/make-degenerate-geometry.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "geometry", "mesh": 0},
            # The camera at (0, 1.6, 6) looking down -Z.
            {"name": "camera", "camera": 0, "translation": [0.0, 1.6, 6.0]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1, "zfar": 100.0}}],
        "meshes": [{"name": "degenerate", "primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"name": "grey", "pbrMetallicRoughness": {
            "baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0.0, "roughnessFactor": 0.5}}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()}],
    }
    OUT.write_text(json.dumps(gltf, indent=1) + "\n")
    print("wrote", OUT)


if __name__ == "__main__":
    main()
