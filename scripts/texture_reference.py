#!/usr/bin/env python3
"""The textures and cut-outs comparison with Mitsuba 3 (tests/render_textures.rs,
`textured_and_masked_scene_matches_mitsuba`): one scene description, written as a glTF
for vkvcm and rendered by Mitsuba 3 as the independent reference.

The scene: the environment-map scene's camera and sky (scripts/env_reference.py:
tests/env/sky.hdr turned 30 degrees) over a ground square (y = 0, |x|, |z| <= 2) with a
bilinearly filtered, repeating 8 x 8 checker texture (texture coordinates 0..2 across the
square), and a vertical cut-out quad (z = -0.6, |x| <= 1, 0 <= y <= 1.4, facing the
camera) with a 4 x 4 texture, nearest filtering and clamping, whose alpha is 0 on half
of its texels (alphaMode MASK). Both materials are Lambertian with the texture as their
reflectance: glTF's metallic/roughness has a GGX lobe as well, so the test replaces the
loaded materials' lobes by the diffuse one (keeping the texture), which is what Mitsuba's
`diffuse` is. Conventions matched: Mitsuba's `bitmap` decodes sRGB and filters in linear
space, with texel centres at (i + 1/2) / size, as vkvcm (docs/textures.md); its uv (0, 0)
is the image's top-left corner as in glTF, so the OBJ files give Mitsuba glTF's texture
coordinates as they are (`flip_tex_coords` false); the cut-out is Mitsuba's `mask` with
the alpha as opacity (0 or 1: a hole or not; a separate grey image, since `bitmap` drops
alpha). A ray through a hole is a bounce in Mitsuba's path integrator and not in vkvcm:
both use 24 segments, so the paths this changes carry no measurable energy.

    python3 scripts/texture_reference.py gltf       # tests/env/textured_scene.gltf + PNGs (stdlib only)
    VENV/bin/python scripts/texture_reference.py mitsuba [--seeds 16 --spp 256]
        # tests/env/mitsuba_textured_{mean,var}.exr and mitsuba_textured.json
"""
import argparse
import base64
import json
import math
import os
import struct
import sys
import tempfile
import time
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from env_reference import OUT, SCENE as ENV_SCENE, look_at_quaternion, write_json  # noqa: E402

MAX_PATH_LENGTH = 24
GROUND_H = 2.0
QUAD = {"z": -0.6, "half_width": 1.0, "height": 1.4}


def checker_texels():
    """8 x 8 RGBA, all opaque: a two-colour checker with a hue ramp, so that a flip shows."""
    out = []
    for j in range(8):
        for i in range(8):
            if (i + j) % 2 == 0:
                out.append((230, 200 - 15 * j, 60 + 20 * i, 255))
            else:
                out.append((40 + 10 * i, 90, 160 - 10 * j, 255))
    return out


def mask_texels():
    """4 x 4 RGBA: distinct colours, alpha 0 where i + j is odd."""
    return [(60 + 50 * i, 40 + 55 * j, 200 - 30 * i, 0 if (i + j) % 2 else 255) for j in range(4) for i in range(4)]


def png(width, height, texels, channels):
    """A PNG (8 bits per channel, colour type 6 RGBA or 0 grey) from row-major texels."""
    kind = {4: 6, 1: 0}[channels]
    raw = b"".join(b"\x00" + bytes(c for t in texels[y * width:(y + 1) * width] for c in t[:channels])
                   for y in range(height))

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xffffffff)

    head = struct.pack(">IIBBBBB", width, height, 8, kind, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", head) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


def ground_triangles():
    h = GROUND_H
    uv = lambda x, z: ((x + h) / (2 * h) * 2.0, (z + h) / (2 * h) * 2.0)
    corners = [(-h, -h), (-h, h), (h, h), (-h, -h), (h, h), (h, -h)]
    return [((x, 0.0, z), uv(x, z)) for x, z in corners]


def quad_triangles():
    w, ht, z = QUAD["half_width"], QUAD["height"], QUAD["z"]
    # Image top-left at the quad's top-left as the camera (at +z) sees it; counter-clockwise
    # seen from +z.
    p = lambda u, v: ((-w + 2 * w * u, ht * (1 - v), z), (u, v))
    return [p(0, 0), p(0, 1), p(1, 1), p(0, 0), p(1, 1), p(1, 0)]


def write_gltf(path):
    cam = ENV_SCENE["camera"]
    env = ENV_SCENE["environment"]
    blob = b""
    views, accessors = [], []

    def add(values, fmt, kind):
        nonlocal blob
        data = b"".join(struct.pack(fmt, *v) for v in values)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        acc = {"bufferView": len(views) - 1, "componentType": 5126, "count": len(values), "type": kind}
        if kind == "VEC3":
            acc["min"] = [min(v[k] for v in values) for k in range(3)]
            acc["max"] = [max(v[k] for v in values) for k in range(3)]
        accessors.append(acc)
        blob += data
        return len(accessors) - 1

    meshes = []
    for k, tris in enumerate((ground_triangles(), quad_triangles())):
        pos = add([t[0] for t in tris], "<3f", "VEC3")
        uv = add([t[1] for t in tris], "<2f", "VEC2")
        meshes.append({"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv}, "material": k}]})
    data_uri = lambda b: "data:image/png;base64," + base64.b64encode(b).decode()
    doc = {
        "asset": {"version": "2.0", "generator": "vkvcm scripts/texture_reference.py"},
        "extensionsUsed": ["VKVCM_environment"],
        "extensions": {"VKVCM_environment": {"uri": env["file"], "strength": env["strength"], "rotation": env["rotation_deg"]}},
        "scene": 0,
        "scenes": [{"name": "textured_scene", "nodes": [0, 1, 2]}],
        "nodes": [
            {"name": "ground", "mesh": 0},
            {"name": "cutout", "mesh": 1},
            {"name": "camera", "camera": 0, "translation": cam["from"], "rotation": look_at_quaternion(cam["from"], cam["to"], cam["up"])},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(cam["yfov_deg"]), "znear": 0.01, "aspectRatio": 1.0}}],
        "meshes": meshes,
        "materials": [
            {"name": "ground", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0}},
            {"name": "cutout", "alphaMode": "MASK", "alphaCutoff": 0.5,
             "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}, "metallicFactor": 0.0}},
        ],
        # 9729 LINEAR, 9728 NEAREST, 10497 REPEAT, 33071 CLAMP_TO_EDGE.
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 10497},
                     {"magFilter": 9728, "minFilter": 9728, "wrapS": 33071, "wrapT": 33071}],
        "textures": [{"sampler": 0, "source": 0}, {"sampler": 1, "source": 1}],
        "images": [{"uri": data_uri(png(8, 8, checker_texels(), 4))}, {"uri": data_uri(png(4, 4, mask_texels(), 4))}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    }
    write_json(path, doc)
    print(f"wrote {path}")


def write_obj(path, tris):
    with open(path, "w") as f:
        for p, _ in tris:
            f.write("v %.9g %.9g %.9g\n" % p)
        for _, uv in tris:
            f.write("vt %.9g %.9g\n" % uv)
        for k in range(len(tris) // 3):
            a = 3 * k + 1
            f.write(f"f {a}/{a} {a + 1}/{a + 1} {a + 2}/{a + 2}\n")


def mitsuba_scene(mi, seed, spp, tmp):
    T = mi.ScalarTransform4f
    cam = ENV_SCENE["camera"]
    env = ENV_SCENE["environment"]
    files = {}
    for name, (w, h, texels, ch) in {"checker.png": (8, 8, checker_texels(), 4), "mask.png": (4, 4, mask_texels(), 4),
                                     "mask_alpha.png": (4, 4, [(t[3],) for t in mask_texels()], 1)}.items():
        files[name] = os.path.join(tmp, name)
        with open(files[name], "wb") as f:
            f.write(png(w, h, texels, ch))
    write_obj(os.path.join(tmp, "ground.obj"), ground_triangles())
    write_obj(os.path.join(tmp, "quad.obj"), quad_triangles())
    bitmap = lambda name, filt, wrap, raw=False: {"type": "bitmap", "filename": files[name], "filter_type": filt,
                                                  "wrap_mode": wrap, "raw": raw}
    diffuse = lambda tex: {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": tex}}
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": MAX_PATH_LENGTH, "hide_emitters": False},
        "sensor": {
            "type": "perspective",
            "fov": cam["yfov_deg"],
            "fov_axis": "y",
            "to_world": T().look_at(origin=cam["from"], target=cam["to"], up=cam["up"]),
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
            "film": {"type": "hdrfilm", "width": ENV_SCENE["width"], "height": ENV_SCENE["height"],
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        },
        "env": {"type": "envmap", "filename": os.path.join(OUT, env["file"]), "scale": env["strength"],
                "to_world": T().rotate([0, 1, 0], env["rotation_deg"])},
        "ground": {"type": "obj", "filename": os.path.join(tmp, "ground.obj"), "flip_tex_coords": False,
                   "bsdf": diffuse(bitmap("checker.png", "bilinear", "repeat"))},
        "cutout": {"type": "obj", "filename": os.path.join(tmp, "quad.obj"), "flip_tex_coords": False,
                   "bsdf": {"type": "mask", "opacity": bitmap("mask_alpha.png", "nearest", "clamp", raw=True),
                            "bsdf": diffuse(bitmap("mask.png", "nearest", "clamp"))}},
    }


def render_mitsuba(seeds, spp, variant):
    try:
        import mitsuba as mi
        import numpy as np
    except ImportError:
        sys.exit("mitsuba and numpy are needed: python3 -m venv VENV && VENV/bin/pip install mitsuba numpy")
    mi.set_variant(variant)
    tmp = tempfile.mkdtemp()
    images = []
    t0 = time.time()
    for seed in range(seeds):
        scene = mi.load_dict(mitsuba_scene(mi, seed, spp, tmp))
        images.append(np.array(mi.render(scene, seed=seed, spp=spp), dtype=np.float64))
        print(f"seed {seed}: {time.time() - t0:.0f} s", flush=True)
    stack = np.stack(images)
    mi.Bitmap(stack.mean(axis=0).astype(np.float32)).write(os.path.join(OUT, "mitsuba_textured_mean.exr"))
    mi.Bitmap(stack.var(axis=0, ddof=1).astype(np.float32)).write(os.path.join(OUT, "mitsuba_textured_var.exr"))
    meta = {"renderer": f"Mitsuba {mi.__version__} {variant}, integrator path", "seeds": seeds, "spp_per_seed": spp,
            "max_path_length": MAX_PATH_LENGTH, "command": " ".join(sys.argv)}
    write_json(os.path.join(OUT, "mitsuba_textured.json"), meta)
    print(f"wrote tests/env/mitsuba_textured_mean.exr, _var.exr ({seeds} seeds x {spp} spp, {time.time() - t0:.0f} s)")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=["gltf", "mitsuba"])
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--variant", default="scalar_rgb")
    a = ap.parse_args()
    if a.what == "gltf":
        write_gltf(os.path.join(OUT, "textured_scene.gltf"))
    else:
        render_mitsuba(a.seeds, a.spp, a.variant)


if __name__ == "__main__":
    main()
