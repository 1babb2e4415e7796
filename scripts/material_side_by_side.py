#!/usr/bin/env python3
"""vkvcm beside Blender's Cycles on a row of spheres of one glTF material extension, where
the two models differ and no per-pixel test applies (docs/scene-format.md, "Materials"):
writes docs/img/EXT_side_by_side.png, vkvcm (pt) | Cycles | their luminance ratio (grey:
equal; red: vkvcm brighter; blue: darker; full colour at a factor of 2).

    python3 scripts/material_side_by_side.py clearcoat|sheen|iridescence|anisotropy|dispersion
        [--vkvcm target/release/vkvcm] [--iterations 256] [--samples 256] [--out docs/img]
    python3 scripts/material_side_by_side.py sheen --scene-only sheen.gltf

The scene (written here, plain glTF 2.0 with the extension, so that vkvcm and Blender's own
importer read the same file): four UV spheres with normals, texture coordinates and
tangents along their parallels, on a grey floor, lit by an emissive quad above, black
world, paths of at most 10 segments (Cycles: 8 bounces), a box pixel filter. Runs in the
Cycles harness's venv (`python3 scripts/peers/blender_cycles.py setup`), re-executing
itself there.
"""

import argparse
import base64
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "peers"))
import blender_cycles  # noqa: E402

RED = [0.8, 0.1, 0.05]
GOLD = [1.0, 0.76, 0.33]

# Per extension: (label, base colour, metallic, roughness, the extension's object or None).
VARIANTS = {
    "clearcoat": [
        ("red", RED, 0.0, 0.5, None),
        ("red, smooth coat", RED, 0.0, 0.5, {"clearcoatFactor": 1.0, "clearcoatRoughnessFactor": 0.0}),
        ("red, coat r 0.3", RED, 0.0, 0.5, {"clearcoatFactor": 1.0, "clearcoatRoughnessFactor": 0.3}),
        ("gold, coat r 0.1", GOLD, 1.0, 0.5, {"clearcoatFactor": 1.0, "clearcoatRoughnessFactor": 0.1}),
    ],
    "sheen": [
        ("red", RED, 0.0, 0.6, None),
        ("red, white sheen r 0.3", RED, 0.0, 0.6, {"sheenColorFactor": [1.0, 1.0, 1.0], "sheenRoughnessFactor": 0.3}),
        ("red, blue sheen r 0.6", RED, 0.0, 0.6, {"sheenColorFactor": [0.2, 0.5, 1.0], "sheenRoughnessFactor": 0.6}),
        ("black, white sheen r 0.5", [0.0, 0.0, 0.0], 0.0, 0.6,
         {"sheenColorFactor": [1.0, 1.0, 1.0], "sheenRoughnessFactor": 0.5}),
    ],
    "iridescence": [
        ("gold", GOLD, 1.0, 0.2, None),
        ("gold, film 400 nm", GOLD, 1.0, 0.2,
         {"iridescenceFactor": 1.0, "iridescenceIor": 1.3, "iridescenceThicknessMaximum": 400.0}),
        ("black dielectric, film 300 nm", [0.02, 0.02, 0.02], 0.0, 0.15,
         {"iridescenceFactor": 1.0, "iridescenceIor": 1.5, "iridescenceThicknessMaximum": 300.0}),
        ("white dielectric, film 600 nm", [0.8, 0.8, 0.8], 0.0, 0.3,
         {"iridescenceFactor": 1.0, "iridescenceIor": 1.8, "iridescenceThicknessMaximum": 600.0}),
    ],
    "anisotropy": [
        ("metal r 0.4", [0.9, 0.9, 0.9], 1.0, 0.4, None),
        ("strength 0.5", [0.9, 0.9, 0.9], 1.0, 0.4, {"anisotropyStrength": 0.5}),
        ("strength 1", [0.9, 0.9, 0.9], 1.0, 0.4, {"anisotropyStrength": 1.0}),
        ("strength 1, turned 90 deg", [0.9, 0.9, 0.9], 1.0, 0.4,
         {"anisotropyStrength": 1.0, "anisotropyRotation": math.pi / 2}),
    ],
    # Glass (transmission 1, IOR 1.5, a volume so that Blender's importer makes it solid
    # glass as vkvcm does): the colour fringes of the caustics and of the floor seen
    # through the spheres.
    "dispersion": [
        ("glass", [1.0, 1.0, 1.0], 0.0, 0.0, None),
        ("dispersion 1", [1.0, 1.0, 1.0], 0.0, 0.0, {"dispersion": 1.0}),
        ("dispersion 4", [1.0, 1.0, 1.0], 0.0, 0.0, {"dispersion": 4.0}),
        ("rough 0.2, dispersion 4", [1.0, 1.0, 1.0], 0.0, 0.2, {"dispersion": 4.0}),
    ],
}
EXTENSION = {k: f"KHR_materials_{k}" for k in VARIANTS}
# Extensions every sphere of a variant set carries besides its own.
SPHERE_EXTENSIONS = {
    "dispersion": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                   "KHR_materials_volume": {"thicknessFactor": 1.0}, "KHR_materials_ior": {"ior": 1.5}},
}


def sphere(cx, rings=32, segs=64, r=0.45):
    """Positions, normals, texture coordinates (u along the parallels) and tangents (+u)."""
    pos, nrm, uv, tan, idx = [], [], [], [], []
    for i in range(rings + 1):
        th = math.pi * i / rings
        for j in range(segs + 1):
            ph = 2 * math.pi * j / segs
            n = (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
            pos.append((cx + r * n[0], r + r * n[1], r * n[2]))
            nrm.append(n)
            uv.append((j / segs, i / rings))
            tan.append((-math.sin(ph), 0.0, math.cos(ph), 1.0))
    for i in range(rings):
        for j in range(segs):
            a, b = i * (segs + 1) + j, (i + 1) * (segs + 1) + j
            if i > 0:  # not at the top pole, where a and a + 1 coincide
                idx += [a, a + 1, b]
            if i < rings - 1:  # nor at the bottom one
                idx += [b, a + 1, b + 1]
    return pos, nrm, uv, tan, idx


def quad(y, s, down):
    pos = [(-s, y, -s), (s, y, -s), (s, y, s), (-s, y, s)]
    n = (0.0, -1.0, 0.0) if down else (0.0, 1.0, 0.0)
    uv = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    idx = [0, 1, 2, 0, 2, 3] if down else [0, 2, 1, 0, 3, 2]
    return pos, [n] * 4, uv, [(1.0, 0.0, 0.0, 1.0)] * 4, idx


def write_scene(ext, out):
    buf = bytearray()
    used = [EXTENSION[ext], "KHR_materials_emissive_strength", *SPHERE_EXTENSIONS.get(ext, {})]
    gltf = {"asset": {"version": "2.0"}, "extensionsUsed": used,
            "buffers": [], "bufferViews": [], "accessors": [], "meshes": [], "nodes": [], "materials": []}

    def accessor(data, fmt, kind, target, bounds=False):
        off = len(buf)
        flat = [x for v in data for x in (v if isinstance(v, tuple) else (v,))]
        buf.extend(struct.pack("<%d%s" % (len(flat), fmt), *flat))
        gltf["bufferViews"].append({"buffer": 0, "byteOffset": off, "byteLength": len(buf) - off, "target": target})
        a = {"bufferView": len(gltf["bufferViews"]) - 1, "componentType": 5126 if fmt == "f" else 5125,
             "count": len(data), "type": kind}
        if bounds:
            a["min"] = [min(p[k] for p in data) for k in range(3)]
            a["max"] = [max(p[k] for p in data) for k in range(3)]
        gltf["accessors"].append(a)
        return len(gltf["accessors"]) - 1

    def add_mesh(geo, material):
        pos, nrm, uv, tan, idx = geo
        attributes = {"POSITION": accessor(pos, "f", "VEC3", 34962, bounds=True),
                      "NORMAL": accessor(nrm, "f", "VEC3", 34962),
                      "TEXCOORD_0": accessor(uv, "f", "VEC2", 34962),
                      "TANGENT": accessor(tan, "f", "VEC4", 34962)}
        indices = accessor(idx, "I", "SCALAR", 34963)
        gltf["meshes"].append({"primitives": [{"attributes": attributes, "indices": indices, "material": material}]})
        gltf["nodes"].append({"mesh": len(gltf["meshes"]) - 1})

    def material(name, base, metallic, roughness, extensions=None, emission=None):
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": base + [1.0], "metallicFactor": metallic,
                                                     "roughnessFactor": roughness}, "doubleSided": True}
        if extensions:
            m["extensions"] = extensions
        if emission is not None:
            m["emissiveFactor"] = [1.0, 1.0, 1.0]
            m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": emission}}
        gltf["materials"].append(m)
        return len(gltf["materials"]) - 1

    for k, (label, base, metallic, roughness, e) in enumerate(VARIANTS[ext]):
        if e and "iridescenceThicknessMaximum" in e:
            # Blender 5.3's importer reads the maximum thickness under this key, not the
            # extension's iridescenceThicknessMaximum (else every film is 400 nm there);
            # vkvcm ignores it.
            e = dict(e, iridescenceThickness=e["iridescenceThicknessMaximum"])
        extensions = dict(SPHERE_EXTENSIONS.get(ext, {}), **({EXTENSION[ext]: e} if e else {}))
        add_mesh(sphere(-1.5 + k), material(label, base, metallic, roughness, extensions or None))
    add_mesh(quad(0.0, 4.0, False), material("floor", [0.5, 0.5, 0.5], 0.0, 0.8))
    add_mesh(quad(3.0, 1.0, True), material("lamp", [0.0, 0.0, 0.0], 0.0, 1.0, emission=8.0))
    gltf["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.6, "aspectRatio": 2.0, "znear": 0.05}}]
    a = math.radians(-15.0)  # looking down 15 degrees towards the row from +z
    gltf["nodes"].append({"camera": 0, "translation": [0.0, 1.6, 4.6],
                          "rotation": [math.sin(a / 2), 0.0, 0.0, math.cos(a / 2)]})
    gltf["scenes"] = [{"nodes": list(range(len(gltf["nodes"])))}]
    gltf["scene"] = 0
    gltf["buffers"] = [{"byteLength": len(buf),
                        "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}]
    Path(out).write_text(json.dumps(gltf))


def set_cycles_dispersion(bpy):
    """Blender 5.3's importer leaves the Principled BSDF's Transmission Dispersion Scale at
    0 (no dispersion) whatever KHR_materials_dispersion says: set it from the variants.
    With the node's default Abbe number 20, scale d gives Abbe number 20 / d, glTF's
    dispersion d (OpenPBR's convention, which glTF adopted)."""
    for label, _, _, _, e in VARIANTS["dispersion"]:
        node = bpy.data.materials[label].node_tree.nodes.get("Principled BSDF")
        if node is not None and e:
            node.inputs["Transmission Dispersion Abbe Number"].default_value = 20.0
            node.inputs["Transmission Dispersion Scale"].default_value = e["dispersion"]


AFTER_IMPORT = {"dispersion": set_cycles_dispersion}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("extension", choices=sorted(VARIANTS))
    ap.add_argument("--scene-only", metavar="OUT.gltf", help="write the scene and stop")
    ap.add_argument("--vkvcm", default=os.environ.get("VKVCM_BIN", str(HERE.parent / "target/release/vkvcm")))
    ap.add_argument("--iterations", type=int, default=256, help="vkvcm's (default %(default)s)")
    ap.add_argument("--samples", type=int, default=256, help="Cycles' (default %(default)s)")
    ap.add_argument("--size", default="320x160", help="WxH (default %(default)s)")
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 2, help="Cycles' threads")
    ap.add_argument("--out", default=str(HERE.parent / "docs" / "img"))
    ap.add_argument("--cache", default=str(blender_cycles.CACHE), help="the harness's venv (default %(default)s)")
    a = ap.parse_args()
    if a.scene_only:
        write_scene(a.extension, a.scene_only)
        return
    try:
        import numpy  # noqa: F401
        import bpy  # noqa: F401
    except ImportError:
        py = blender_cycles.venv_python(Path(a.cache))
        if not py.exists():
            raise SystemExit(f"no {py}: run `python3 scripts/peers/blender_cycles.py setup` first")
        os.execv(str(py), [str(py), __file__, *sys.argv[1:]])
    width, height = (int(x) for x in a.size.split("x"))
    with tempfile.TemporaryDirectory() as tmp:
        scene, vk, cy = Path(tmp, "scene.gltf"), Path(tmp, "vkvcm.exr"), Path(tmp, "cycles.exr")
        write_scene(a.extension, scene)
        subprocess.run([a.vkvcm, "render", str(scene), "--algo", "pt", "--env", "none", "--width", str(width),
                        "--height", str(height), "--max-path-length", "10", "--iterations", str(a.iterations),
                        "-o", str(vk), "--quiet"], check=True)
        blender_cycles.render_cycles(scene, None, 1, a.samples, cy, width, height, a.threads, (0.0, 0.0, 0.0),
                                     AFTER_IMPORT.get(a.extension))
        vk_img, cy_img = blender_cycles.read_rgb(vk), blender_cycles.read_rgb(cy)
    out = Path(a.out) / f"{a.extension}_side_by_side.png"
    blender_cycles.montage(out, [vk_img, cy_img, blender_cycles.ratio_map(vk_img, cy_img)])
    print(f"{out}: image means vkvcm {vk_img.mean():.4f}, Cycles {cy_img.mean():.4f}")


if __name__ == "__main__":
    main()
