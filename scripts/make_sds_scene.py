#!/usr/bin/env python3
"""Writes scenes/hard/sds.gltf: a point light inside a glass sphere above a diffuse floor,
the floor seen only through a glass slab in front of the camera. Every light path is
L S+ D S+ E: vertex connection (pt, bpt) cannot sample any of it, merging (ppm, bpm, vcm)
can. Same scene as sds_scene() in tests/common/scenes.rs. Python 3 standard library only.
Run from the repository root: python3 scripts/make_sds_scene.py"""
import base64, json, struct

def box_outward(lo, hi):
    c = [(l + h) / 2 for l, h in zip(lo, hi)]
    corners = lambda f: [tuple(lo[i] if f[i] < 0 else hi[i] for i in range(3))]
    tris = []
    for axis in range(3):
        for side in (-1, 1):
            u, v = [a for a in range(3) if a != axis]
            quad = []
            for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis] = hi[axis] if side > 0 else lo[axis]
                p[u] = hi[u] if su > 0 else lo[u]
                p[v] = hi[v] if sv > 0 else lo[v]
                quad.append(p)
            for t in ((quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])):
                e1 = [t[1][i] - t[0][i] for i in range(3)]
                e2 = [t[2][i] - t[0][i] for i in range(3)]
                n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
                centroid = [sum(p[i] for p in t) / 3 for i in range(3)]
                out = sum(n[i] * (centroid[i] - c[i]) for i in range(3))
                tris.append(t if out > 0 else (t[0], t[2], t[1]))
    return tris

s = 3.0
floor = [((-s, -s, 0.0), (s, -s, 0.0), (s, s, 0.0)), ((-s, -s, 0.0), (s, s, 0.0), (-s, s, 0.0))]
slab = box_outward((-3.0, -3.0, 2.0), (3.0, 3.0, 2.3))
blob, accessors, views, prims = b"", [], [], []
for material, tris in ((0, floor), (1, slab)):
    pts = [p for t in tris for p in t]
    data = b"".join(struct.pack("<3f", *p) for p in pts)
    views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
    accessors.append({"bufferView": len(views) - 1, "componentType": 5126, "count": len(pts), "type": "VEC3",
                      "min": [min(p[i] for p in pts) for i in range(3)], "max": [max(p[i] for p in pts) for i in range(3)]})
    prims.append({"attributes": {"POSITION": len(accessors) - 1}, "material": material})
    blob += data
gltf = {
    "asset": {"version": "2.0", "generator": "vkvcm scripts/make_sds_scene.py"},
    "extensionsUsed": ["KHR_lights_punctual", "VKVCM_materials_phong", "VKVCM_spheres"],
    "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1, 1, 1], "intensity": 2.0}]}},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2, 3]}],
    "nodes": [
        {"name": "geometry", "mesh": 0},
        {"name": "glass sphere", "extensions": {"VKVCM_spheres": {"spheres": [{"center": [0.2, 0.1, 0.8], "radius": 0.3, "material": 1}]}}},
        {"name": "light", "translation": [0.2, 0.1, 0.8], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "camera", "camera": 0, "translation": [0.0, 0.0, 3.0]},
    ],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8726646259971648, "aspectRatio": 1.0, "znear": 0.01}}],
    "meshes": [{"name": "floor and slab", "primitives": prims}],
    "materials": [
        {"name": "floor", "extensions": {"VKVCM_materials_phong": {"diffuse": [0.8, 0.8, 0.8]}}},
        {"name": "glass", "extensions": {"VKVCM_materials_phong": {"mirror": [1, 1, 1], "ior": 1.5}}},
    ],
    "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    "bufferViews": views,
    "accessors": accessors,
}
with open("scenes/hard/sds.gltf", "w") as f:
    json.dump(gltf, f, indent=1, sort_keys=True)
    f.write("\n")
