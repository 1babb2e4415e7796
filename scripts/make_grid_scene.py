#!/usr/bin/env python3
"""A plain glTF (.glb) height-field grid of about N triangles, a camera and a sun, for
scene-size benchmarks (docs/performance.md, "Scene size"). Standard library only.

    python3 scripts/make_grid_scene.py 10000000 /tmp/grid_10m.glb
    python3 scripts/make_grid_scene.py 1000000 /tmp/grid_100x1m.glb 100

With a third argument K, the mesh is placed by K nodes (an instanced scene of K x N
triangles that stores N): K tiles side by side, each the grid scaled down by the number of
tiles per row, covering the same square. With --double-sided anywhere among the arguments
the material says doubleSided true (else glTF's default, one-sided: docs/scene-format.md,
"One-sided surfaces"; the camera sees the grid's front either way).

The grid spans [-1, 1]^2 in x/z with a gentle height y = 0.05 sin(7x) cos(5z), so the BVH
is not trivially flat; positions are float32, indices uint32, one mesh, one node. The
camera looks down at the grid from (0, 1.2, 2.2); a directional light shines from above.
"""
import json
import math
import struct
import sys


def main():
    args = [a for a in sys.argv[1:] if a != "--double-sided"]
    double_sided = len(args) < len(sys.argv) - 1
    if len(args) not in (2, 3):
        sys.exit(__doc__)
    target = int(args[0])
    out = args[1]
    instances = int(args[2]) if len(args) == 3 else 1
    per_row = math.ceil(math.sqrt(instances))
    tiles = [
        {"mesh": 0, "scale": [1 / per_row] * 3,
         "translation": [-1 + (2 * (k % per_row) + 1) / per_row, 0, -1 + (2 * (k // per_row) + 1) / per_row]}
        for k in range(instances)
    ] if instances > 1 else [{"mesh": 0}]
    n = max(1, int(math.sqrt(target / 2)))  # n x n quads, 2 triangles each
    verts = bytearray()
    for j in range(n + 1):
        z = -1 + 2 * j / n
        for i in range(n + 1):
            x = -1 + 2 * i / n
            verts += struct.pack("<3f", x, 0.05 * math.sin(7 * x) * math.cos(5 * z), z)
    idx = bytearray()
    row = n + 1
    for j in range(n):
        for i in range(n):
            a = j * row + i
            idx += struct.pack("<6I", a, a + row, a + 1, a + 1, a + row, a + row + 1)
    binary = bytes(verts) + bytes(idx)
    gltf = {
        "asset": {"version": "2.0", "generator": "vkvcm scripts/make_grid_scene.py"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(tiles) + 2))}],
        "nodes": [
            {"camera": 0, "translation": [0, 1.2, 2.2], "rotation": rotation_x(-0.5)},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "rotation": rotation_x(-1.2)},
        ] + tiles,
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 3.0}]}},
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0, "roughnessFactor": 1},
                       "doubleSided": double_sided}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(verts)},
            {"buffer": 0, "byteOffset": len(verts), "byteLength": len(idx)},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": (n + 1) ** 2, "type": "VEC3",
             "min": [-1, -0.05, -1], "max": [1, 0.05, 1]},
            {"bufferView": 1, "componentType": 5125, "count": 6 * n * n, "type": "SCALAR"},
        ],
    }
    js = json.dumps(gltf).encode()
    js += b" " * (-len(js) % 4)
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(js) + 8 + len(binary)
    with open(out, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(js), b"JSON") + js)
        f.write(struct.pack("<I4s", len(binary), b"BIN\0") + binary)
    print(f"{out}: {2 * n * n} triangles x {instances} placements, {len(binary) / 2**20:.0f} MiB of buffers")


def rotation_x(angle):
    return [math.sin(angle / 2), 0, 0, math.cos(angle / 2)]


if __name__ == "__main__":
    main()
