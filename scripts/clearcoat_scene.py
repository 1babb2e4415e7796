#!/usr/bin/env python3
"""Writes the clear-coat comparison scene of docs/img/clearcoat_side_by_side.png
(docs/scene-format.md, "Clear coat"): four UV spheres in a row, a red dielectric of
roughness 0.5 without a coat, with a smooth coat, with a coat of roughness 0.3, and a
gold metal of roughness 0.5 under a coat of roughness 0.1; an emissive quad above and a
grey floor; a perspective camera. Plain glTF 2.0 + KHR_materials_clearcoat, so that
vkvcm and Blender's importer read the same file.

usage: clearcoat_scene.py OUT.gltf
"""
import base64
import json
import math
import struct
import sys


def sphere(cx, rings=24, segs=48, r=0.45):
    pos, nrm, idx = [], [], []
    for i in range(rings + 1):
        th = math.pi * i / rings
        for j in range(segs + 1):
            ph = 2 * math.pi * j / segs
            n = (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
            pos.append((cx + r * n[0], r + r * n[1], r * n[2]))
            nrm.append(n)
    for i in range(rings):
        for j in range(segs):
            a, b = i * (segs + 1) + j, (i + 1) * (segs + 1) + j
            idx += [a, a + 1, b, b, a + 1, b + 1]
    return pos, nrm, idx


def quad(y, s, down):
    pos = [(-s, y, -s), (s, y, -s), (s, y, s), (-s, y, s)]
    n = (0, -1, 0) if down else (0, 1, 0)
    idx = [0, 1, 2, 0, 2, 3] if down else [0, 2, 1, 0, 3, 2]
    return pos, [n] * 4, idx


def main(out):
    buf = bytearray()
    gltf = {"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_materials_clearcoat", "KHR_materials_emissive_strength"],
            "buffers": [], "bufferViews": [], "accessors": [], "meshes": [], "nodes": [], "materials": []}

    def add_mesh(geo, material):
        pos, nrm, idx = geo
        views = []
        for data, fmt, target in ((pos, "3f", 34962), (nrm, "3f", 34962), (idx, "I", 34963)):
            off = len(buf)
            flat = [x for v in data for x in (v if isinstance(v, tuple) else (v,))]
            buf.extend(struct.pack("<%d%s" % (len(flat), fmt[-1]), *flat))
            gltf["bufferViews"].append({"buffer": 0, "byteOffset": off, "byteLength": len(buf) - off, "target": target})
            views.append(len(gltf["bufferViews"]) - 1)
        lo = [min(p[k] for p in pos) for k in range(3)]
        hi = [max(p[k] for p in pos) for k in range(3)]
        acc = gltf["accessors"]
        acc.append({"bufferView": views[0], "componentType": 5126, "count": len(pos), "type": "VEC3", "min": lo, "max": hi})
        acc.append({"bufferView": views[1], "componentType": 5126, "count": len(nrm), "type": "VEC3"})
        acc.append({"bufferView": views[2], "componentType": 5125, "count": len(idx), "type": "SCALAR"})
        n = len(acc)
        gltf["meshes"].append({"primitives": [{"attributes": {"POSITION": n - 3, "NORMAL": n - 2}, "indices": n - 1,
                                               "material": material}]})
        gltf["nodes"].append({"mesh": len(gltf["meshes"]) - 1})

    def material(name, base, metallic, roughness, coat=None, emission=None):
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": base + [1.0], "metallicFactor": metallic,
                                                     "roughnessFactor": roughness}, "doubleSided": True}
        if coat is not None:
            m["extensions"] = {"KHR_materials_clearcoat": {"clearcoatFactor": coat[0], "clearcoatRoughnessFactor": coat[1]}}
        if emission is not None:
            m["emissiveFactor"] = [1.0, 1.0, 1.0]
            m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": emission}}
        gltf["materials"].append(m)
        return len(gltf["materials"]) - 1

    red = [0.8, 0.1, 0.05]
    mats = [material("red", red, 0.0, 0.5), material("red smooth coat", red, 0.0, 0.5, (1.0, 0.0)),
            material("red coat r 0.3", red, 0.0, 0.5, (1.0, 0.3)),
            material("gold coat r 0.1", [1.0, 0.76, 0.33], 1.0, 0.5, (1.0, 0.1))]
    for k, m in enumerate(mats):
        add_mesh(sphere(-1.5 + k), m)
    add_mesh(quad(0.0, 4.0, False), material("floor", [0.5, 0.5, 0.5], 0.0, 0.8))
    add_mesh(quad(3.0, 1.0, True), material("lamp", [0.0, 0.0, 0.0], 0.0, 1.0, emission=8.0))
    cam = {"type": "perspective", "perspective": {"yfov": 0.6, "aspectRatio": 2.0, "znear": 0.05}}
    gltf["cameras"] = [cam]
    # Looking down 15 degrees towards the row from +z.
    a = math.radians(-15.0)
    gltf["nodes"].append({"camera": 0, "translation": [0.0, 1.6, 4.6],
                          "rotation": [math.sin(a / 2), 0.0, 0.0, math.cos(a / 2)]})
    gltf["scenes"] = [{"nodes": list(range(len(gltf["nodes"])))}]
    gltf["scene"] = 0
    gltf["buffers"] = [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}]
    with open(out, "w") as f:
        json.dump(gltf, f)


if __name__ == "__main__":
    main(sys.argv[1])
