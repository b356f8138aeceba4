#!/usr/bin/env python3
"""Writes experiments/stability/assets/glossy-boxes.gltf, stability case 18's glTF file: a
floor and a back wall under two rows of five boxes, each box its own metallic-roughness
material: roughness 0 (the floor the shaders clamp to), 0.05, 0.2, 0.5 and 1, a dielectric row
and a metal row. One box geometry (24 vertices with face normals, 36 indices) is shared by
every box mesh; the buffer is embedded as base64. Run from the repository root:

    python3 scripts/make-glossy-boxes.py
"""
import base64
import json
import struct
from pathlib import Path

OUT = Path("experiments/stability/assets/glossy-boxes.gltf")


def box():
    faces = [  # normal, then two axes spanning the face
        ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
        ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
        ((0, 1, 0), (0, 0, 1), (1, 0, 0)),
        ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
        ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
        ((0, 0, -1), (0, 1, 0), (1, 0, 0)),
    ]
    pos, nrm, idx = [], [], []
    for n, u, v in faces:
        base = len(pos)
        for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            pos.append(tuple(0.5 * (n[k] + su * u[k] + sv * v[k]) for k in range(3)))
            nrm.append(n)
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nrm, idx


def quad(center, half_u, half_v, normal):
    pos = []
    for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        pos.append(tuple(center[k] + su * half_u[k] + sv * half_v[k] for k in range(3)))
    return pos, [normal] * 4, [0, 1, 2, 0, 2, 3]


def main():
    geoms = [box(), quad((0, 0, 0), (8, 0, 0), (0, 0, 6), (0, 1, 0)),
             quad((0, 4, -4), (8, 0, 0), (0, 4, 0), (0, 0, 1))]
    blob = bytearray()
    views, accessors, prims = [], [], []
    for pos, nrm, idx in geoms:
        acc = {}
        for name, data, fmt, kind in (("POSITION", pos, "3f", "VEC3"), ("NORMAL", nrm, "3f", "VEC3"),
                                      ("indices", idx, "H", "SCALAR")):
            while len(blob) % 4:
                blob.append(0)
            start = len(blob)
            flat = [c for p in data for c in (p if isinstance(p, tuple) else (p,))]
            blob += struct.pack("<%d%s" % (len(flat), fmt[-1]), *flat)
            views.append({"buffer": 0, "byteOffset": start, "byteLength": len(blob) - start})
            a = {"bufferView": len(views) - 1, "componentType": 5126 if fmt[-1] == "f" else 5123,
                 "count": len(data), "type": kind}
            if name == "POSITION":
                a["min"] = [min(p[k] for p in data) for k in range(3)]
                a["max"] = [max(p[k] for p in data) for k in range(3)]
            accessors.append(a)
            acc[name] = len(accessors) - 1
        prims.append(acc)
    materials = [
        {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1],
                                                    "metallicFactor": 0.0, "roughnessFactor": 0.5}},
        {"name": "wall", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.55, 0.6, 1],
                                                   "metallicFactor": 0.0, "roughnessFactor": 0.3}},
    ]
    meshes, nodes = [], []

    def mesh(geom, material, translation, name):
        p = prims[geom]
        meshes.append({"name": name, "primitives": [{
            "attributes": {"POSITION": p["POSITION"], "NORMAL": p["NORMAL"]},
            "indices": p["indices"], "material": material}]})
        nodes.append({"name": name, "mesh": len(meshes) - 1, "translation": translation})

    mesh(1, 0, [0, 0, 0], "floor")
    mesh(2, 1, [0, 0, 0], "wall")
    for row, (metallic, colour) in enumerate(((0.0, [0.8, 0.2, 0.2, 1]), (1.0, [1.0, 0.78, 0.34, 1]))):
        for col, rough in enumerate((0.0, 0.05, 0.2, 0.5, 1.0)):
            name = "%s-roughness-%g" % ("metal" if metallic else "dielectric", rough)
            materials.append({"name": name, "pbrMetallicRoughness": {
                "baseColorFactor": colour, "metallicFactor": metallic, "roughnessFactor": rough}})
            mesh(0, len(materials) - 1, [-5 + 2.5 * col, 0.5, -1.5 + 2.5 * row], name)
    gltf = {
        "asset": {"version": "2.0", "generator": "manylights scripts/make-glossy-boxes.py"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()}],
    }
    OUT.write_text(json.dumps(gltf, indent=1) + "\n")
    print("wrote", OUT)


if __name__ == "__main__":
    main()
