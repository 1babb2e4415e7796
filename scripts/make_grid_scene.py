#!/usr/bin/env python3
"""A plain glTF (.glb) height-field grid of about N triangles, a camera and a sun, for
scene-size benchmarks (docs/performance.md, "Memory"). Standard library only.

    python3 scripts/make_grid_scene.py 10000000 /tmp/grid_10m.glb
    python3 scripts/make_grid_scene.py 1000000 /tmp/grid_100x1m.glb 100

With a third argument K, the mesh is placed by K nodes (an instanced scene of K x N
triangles that stores N): K tiles side by side, each the grid scaled down by the number of
tiles per row, covering the same square. With --double-sided anywhere among the arguments
the material says doubleSided true (else glTF's default, one-sided: docs/scene-format.md,
"One-sided surfaces"; the camera sees the grid's front either way).

With --room the grid is the floor of a closed room instead (for estimators whose cost
depends on the light transport, scripts/scaling.sh): walls at x, z = +-1 (red, green and
white, 12 more triangles with the ceiling and the lamp), a ceiling at y = 2 with a square
area light under it, the camera inside looking at the back wall, no sun. The floor is the
same surface at every N (only its tessellation changes), so the image barely changes with
N while the number of triangles a ray may meet does.

The grid spans [-1, 1]^2 in x/z with a gentle height y = 0.05 sin(7x) cos(5z), so the BVH
is not trivially flat; positions are float32, indices uint32, one mesh, one node. The
camera looks down at the grid from (0, 1.2, 2.2); a directional light shines from above.
"""
import json
import math
import struct
import sys


def main():
    args = [a for a in sys.argv[1:] if a not in ("--double-sided", "--room")]
    double_sided = "--double-sided" in sys.argv[1:]
    room = "--room" in sys.argv[1:]
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
    if room:
        gltf = room_gltf(n, binary, len(verts), len(idx))
        write_glb(out, gltf, binary + room_geometry())
        print(f"{out}: a room whose floor has {2 * n * n} triangles")
        return
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
    write_glb(out, gltf, binary)
    print(f"{out}: {2 * n * n} triangles x {instances} placements, {len(binary) / 2**20:.0f} MiB of buffers")


def write_glb(out, gltf, binary):
    js = json.dumps(gltf).encode()
    js += b" " * (-len(js) % 4)
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(js) + 8 + len(binary)
    with open(out, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(js), b"JSON") + js)
        f.write(struct.pack("<I4s", len(binary), b"BIN\0") + binary)


# The room's quads (corners in order around the quad) by material: 1 red, 2 green, 3 white,
# 4 the lamp (emissive, facing down).
ROOM_QUADS = [
    (1, [(-1, -0.1, -1), (-1, -0.1, 1), (-1, 2, 1), (-1, 2, -1)]),
    (2, [(1, -0.1, -1), (1, 2, -1), (1, 2, 1), (1, -0.1, 1)]),
    (3, [(-1, -0.1, -1), (-1, 2, -1), (1, 2, -1), (1, -0.1, -1)]),
    (3, [(-1, -0.1, 1), (1, -0.1, 1), (1, 2, 1), (-1, 2, 1)]),
    (3, [(-1, 2, -1), (-1, 2, 1), (1, 2, 1), (1, 2, -1)]),
    (4, [(-0.25, 1.99, -0.25), (0.25, 1.99, -0.25), (0.25, 1.99, 0.25), (-0.25, 1.99, 0.25)]),
]


def room_geometry():
    """Positions (4 per quad) then indices (6 per quad, uint32) of ROOM_QUADS."""
    verts = b"".join(struct.pack("<3f", *c) for _, quad in ROOM_QUADS for c in quad)
    idx = b"".join(struct.pack("<6I", 0, 1, 2, 0, 2, 3) for _ in ROOM_QUADS)
    return verts + idx


def room_gltf(n, grid_binary, grid_vert_bytes, grid_idx_bytes):
    base = len(grid_binary)
    quad_vert_bytes = 4 * 12 * len(ROOM_QUADS)
    views = [
        {"buffer": 0, "byteOffset": 0, "byteLength": grid_vert_bytes},
        {"buffer": 0, "byteOffset": grid_vert_bytes, "byteLength": grid_idx_bytes},
        {"buffer": 0, "byteOffset": base, "byteLength": quad_vert_bytes},
        {"buffer": 0, "byteOffset": base + quad_vert_bytes, "byteLength": 24 * len(ROOM_QUADS)},
    ]
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": (n + 1) ** 2, "type": "VEC3",
         "min": [-1, -0.05, -1], "max": [1, 0.05, 1]},
        {"bufferView": 1, "componentType": 5125, "count": 6 * n * n, "type": "SCALAR"},
    ]
    primitives = [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]
    for q, (material, quad) in enumerate(ROOM_QUADS):
        accessors.append({"bufferView": 2, "byteOffset": 48 * q, "componentType": 5126, "count": 4, "type": "VEC3",
                          "min": [min(c[k] for c in quad) for k in range(3)],
                          "max": [max(c[k] for c in quad) for k in range(3)]})
        accessors.append({"bufferView": 3, "byteOffset": 24 * q, "componentType": 5125, "count": 6, "type": "SCALAR"})
        primitives.append({"attributes": {"POSITION": len(accessors) - 2}, "indices": len(accessors) - 1,
                           "material": material})

    def diffuse(rgb):
        return {"pbrMetallicRoughness": {"baseColorFactor": rgb + [1], "metallicFactor": 0, "roughnessFactor": 1},
                "doubleSided": True}
    lamp = diffuse([0, 0, 0])
    lamp["emissiveFactor"] = [1, 1, 1]
    lamp["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": 15}}
    return {
        "asset": {"version": "2.0", "generator": "vkvcm scripts/make_grid_scene.py --room"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"camera": 0, "translation": [0, 1.0, 0.95], "rotation": rotation_x(-0.25)},
            {"mesh": 0},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 1.2, "znear": 0.01}}],
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "materials": [diffuse([0.7, 0.7, 0.7]), diffuse([0.63, 0.065, 0.05]), diffuse([0.14, 0.45, 0.09]),
                      diffuse([0.7, 0.7, 0.7]), lamp],
        "meshes": [{"primitives": primitives}],
        "buffers": [{"byteLength": base + len(room_geometry())}],
        "bufferViews": views,
        "accessors": accessors,
    }


def rotation_x(angle):
    return [math.sin(angle / 2), 0, 0, math.cos(angle / 2)]


if __name__ == "__main__":
    main()
