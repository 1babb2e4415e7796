#!/usr/bin/env python3
"""The anisotropic GGX comparison (tests/render_anisotropy.rs,
`anisotropic_metal_matches_mitsuba_microfacets`): one scene description, written as a
glTF for vkvcm, and its reference image computed with Mitsuba 3's microfacet
distribution.

The scene: a floor (y = 0, |x| <= 4, -8 <= z <= 3) of two white metals (glTF metallic 1,
base colour 1, so Schlick's Fresnel is exactly 1) with KHR_materials_anisotropy, under a
one-sided emissive quad (y = LAMP_Y, facing down) that the camera does not see:
  left (x < 0): roughness 0.3, anisotropyStrength 0.7, anisotropyRotation 25 degrees, the
    primitive's own TANGENT (+x, w = +1);
  right (x > 0): roughness 0.2, anisotropyStrength 1, anisotropyRotation 45 degrees, and a
    2 x 2 anisotropyTexture (nearest) of one texel value, direction 30 degrees, B 0.8; no
    TANGENT: vkvcm generates it from TEXCOORD_0 (u along +x, v along +z, as
    scripts/texture_reference.py's normal map: tangent +x, bitangent cross(N, T) = -z).
The glTF extension's rules, applied here on their own: the direction is
(cos r, sin r) rotated texture direction (RG * 2 - 1, normalised) in the frame (T, B),
strength = factor x B, alpha = roughness^2, alpha_t = mix(alpha, 1, strength^2) along the
direction and alpha_b = alpha across it.

The reference: paths of two segments (camera, floor, lamp), as vkvcm renders with
--max-path-length 2. Per pixel, N samples (uniform in the pixel, the camera model of
tests/common/scenes.rs `camera`, square image), each drawing a microfacet normal from
Mitsuba 3's `MicrofacetDistribution(GGX, alpha_t, alpha_b)` visible normals (its own
implementation of Heitz 2018, in the frame (direction, cross(n, direction), n)), wi the
reflection of wo, weight f cos / pdf = G2 / G1(wo) with Mitsuba's smith_g1 for G1 and the
height-correlated G2 = 1 / (1 + Lambda(wo) + Lambda(wi)), Lambda = 1 / G1 - 1 (vkvcm's
lobe; Mitsuba's `roughconductor` uses the separable G1 G1, so its full render is not
this BSDF), times the lamp's radiance where wi reaches it. Mitsuba's distribution
evaluates D (the pdf it returns is G1(wo) D(m) wo.m / wo.z, checked against that formula
for every sample).

    python3 scripts/anisotropy_reference.py gltf        # tests/env/anisotropy_scene.gltf (stdlib only)
    VENV/bin/python scripts/anisotropy_reference.py mitsuba [--spp 8192]
        # tests/env/mitsuba_anisotropy_{mean,var}.exr and mitsuba_anisotropy.json
        # (pip install mitsuba numpy; the mean and unbiased variance of the spp samples)
"""
import argparse
import base64
import json
import math
import os
import struct
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
OUT = os.path.join(ROOT, "tests", "env")

SIZE = 20
CAMERA = {"from": [0.0, 2.0, 2.5], "to": [0.0, 0.0, 0.5], "up": [0.0, 1.0, 0.0], "yfov_deg": 40.0}
LAMP_Y = 1.5
LAMP = {"x": [-2.5, 2.5], "z": [-4.5, 0.5], "radiance": 3.0}
FLOOR = {"x": [-4.0, 4.0], "z": [-8.0, 3.0]}
LEFT = {"roughness": 0.3, "strength": 0.7, "rotation_deg": 25.0}
RIGHT = {"roughness": 0.2, "strength": 1.0, "rotation_deg": 45.0, "texel_deg": 30.0, "texel_b": 204}


def texel():
    """The anisotropy texture's RGBA bytes."""
    a = math.radians(RIGHT["texel_deg"])
    return [round((math.cos(a) + 1) / 2 * 255), round((math.sin(a) + 1) / 2 * 255), RIGHT["texel_b"], 255]


def png(w, h, rgba):
    """A w x h RGBA8 PNG (stdlib)."""
    import zlib

    raw = b"".join(b"\x00" + bytes(rgba * w) for _ in range(h))

    def chunk(t, d):
        c = struct.pack(">I", len(d)) + t + d
        return c + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)

    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)) + chunk(
        b"IDAT", zlib.compress(raw)
    ) + chunk(b"IEND", b"")


def write_gltf(path):
    buf = bytearray()
    views, accessors = [], []

    def add(data, fmt, count, typ, minmax=None):
        while len(buf) % 4:
            buf.append(0)
        off = len(buf)
        buf.extend(struct.pack("<" + fmt * count, *data))
        views.append({"buffer": 0, "byteOffset": off, "byteLength": len(buf) - off})
        acc = {"bufferView": len(views) - 1, "componentType": 5126, "count": count // {"VEC2": 2, "VEC3": 3, "VEC4": 4}[typ], "type": typ}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        return len(accessors) - 1

    def quad(x0, x1, z0, z1, y, down=False):
        # Counter-clockwise seen from +y (normal +y), or from below with `down`.
        p = [(x0, y, z1), (x1, y, z1), (x1, y, z0), (x0, y, z0)]
        idx = [0, 1, 2, 0, 2, 3] if not down else [0, 2, 1, 0, 3, 2]
        tris = [c for i in idx for c in p[i]]
        return tris

    def minmax(pos):
        xs, ys, zs = pos[0::3], pos[1::3], pos[2::3]
        return [min(xs), min(ys), min(zs)], [max(xs), max(ys), max(zs)]

    prims = []
    fz = FLOOR["z"]
    # Left floor: TANGENT +x (w = +1).
    pos = quad(FLOOR["x"][0], 0.0, fz[0], fz[1], 0.0)
    a_p = add(pos, "f", 18, "VEC3", minmax(pos))
    a_n = add([0.0, 1.0, 0.0] * 6, "f", 18, "VEC3")
    a_t = add([1.0, 0.0, 0.0, 1.0] * 6, "f", 24, "VEC4")
    prims.append({"attributes": {"POSITION": a_p, "NORMAL": a_n, "TANGENT": a_t}, "material": 0})
    # Right floor: texture coordinates u = x / 2, v = z / 2 (tangents generated).
    pos = quad(0.0, FLOOR["x"][1], fz[0], fz[1], 0.0)
    a_p = add(pos, "f", 18, "VEC3", minmax(pos))
    a_n = add([0.0, 1.0, 0.0] * 6, "f", 18, "VEC3")
    uv = [c for i in range(6) for c in (pos[3 * i] / 2.0, pos[3 * i + 2] / 2.0)]
    a_uv = add(uv, "f", 12, "VEC2")
    prims.append({"attributes": {"POSITION": a_p, "NORMAL": a_n, "TEXCOORD_0": a_uv}, "material": 1})
    # The lamp, facing down.
    pos = quad(LAMP["x"][0], LAMP["x"][1], LAMP["z"][0], LAMP["z"][1], LAMP_Y, down=True)
    a_p = add(pos, "f", 18, "VEC3", minmax(pos))
    prims.append({"attributes": {"POSITION": a_p}, "material": 2})

    def metal(roughness, ext):
        return {
            "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 1.0, "roughnessFactor": roughness},
            "doubleSided": True,
            "extensions": {"KHR_materials_anisotropy": ext},
        }

    materials = [
        metal(LEFT["roughness"], {"anisotropyStrength": LEFT["strength"], "anisotropyRotation": math.radians(LEFT["rotation_deg"])}),
        metal(
            RIGHT["roughness"],
            {
                "anisotropyStrength": RIGHT["strength"],
                "anisotropyRotation": math.radians(RIGHT["rotation_deg"]),
                "anisotropyTexture": {"index": 0},
            },
        ),
        {
            "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0, "roughnessFactor": 1.0},
            "emissiveFactor": [1, 1, 1],
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": LAMP["radiance"]}},
        },
    ]
    image = "data:image/png;base64," + base64.b64encode(png(2, 2, texel())).decode()
    doc = {
        "asset": {"version": "2.0", "generator": "scripts/anisotropy_reference.py"},
        "extensionsUsed": ["KHR_materials_anisotropy", "KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": prims}],
        "materials": materials,
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728}],
        "images": [{"uri": image}],
        "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(buf)).decode()}],
        "bufferViews": views,
        "accessors": accessors,
    }
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def material_at(x):
    """(alpha_t, alpha_b, direction (world)) of the floor at x, by the extension's rules."""
    if x < 0.0:
        m, d = LEFT, (1.0, 0.0)
        strength = m["strength"]
    else:
        m = RIGHT
        t = texel()
        d = (t[0] / 255 * 2 - 1, t[1] / 255 * 2 - 1)
        n = math.hypot(*d)
        d = (d[0] / n, d[1] / n)
        strength = m["strength"] * t[2] / 255
    r = math.radians(m["rotation_deg"])
    dx, dy = math.cos(r) * d[0] - math.sin(r) * d[1], math.sin(r) * d[0] + math.cos(r) * d[1]
    # Tangent +x, bitangent cross(N, T) = cross(+y, +x) = -z.
    direction = (dx, 0.0, -dy)
    a = m["roughness"] ** 2
    return a + (1 - a) * strength**2, a, direction


def camera_ray(px, py):
    """tests/common/scenes.rs `camera` with a square SIZE image: origin, unit direction."""
    e, t, up = CAMERA["from"], CAMERA["to"], CAMERA["up"]
    f = [b - a for a, b in zip(e, t)]
    n = math.sqrt(sum(c * c for c in f))
    f = [c / n for c in f]
    r = [f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]]
    n = math.sqrt(sum(c * c for c in r))
    r = [c / n for c in r]
    u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]]
    plane = 0.5 * SIZE / math.tan(0.5 * math.radians(CAMERA["yfov_deg"]))
    d = [f[i] * plane + r[i] * (px - 0.5 * SIZE) + u[i] * (0.5 * SIZE - py) for i in range(3)]
    n = math.sqrt(sum(c * c for c in d))
    return e, [c / n for c in d]


def render(spp, seed):
    import mitsuba as mi
    import numpy as np

    mi.set_variant("scalar_rgb")
    rng = np.random.default_rng(seed)
    mean = np.zeros((SIZE, SIZE, 3), np.float32)
    var = np.zeros((SIZE, SIZE, 3), np.float32)
    dists = {}
    for py in range(SIZE):
        for px in range(SIZE):
            vals = np.zeros(spp)
            for k in range(spp):
                jx, jy, u1, u2 = rng.random(4)
                o, d = camera_ray(px + jx, py + jy)
                if d[1] >= 0:
                    continue
                t = -o[1] / d[1]
                p = [o[i] + t * d[i] for i in range(3)]
                if not (FLOOR["x"][0] <= p[0] <= FLOOR["x"][1] and FLOOR["z"][0] <= p[2] <= FLOOR["z"][1]):
                    continue
                at, ab, tx = material_at(p[0])
                key = (at, ab)
                if key not in dists:
                    dists[key] = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, at, ab, True)
                dist = dists[key]
                # Local frame: x = the direction, y = cross(n, x), z = n = +y.
                bx = (tx[2] * 1.0 - 0.0, 0.0, -tx[0] * 1.0)  # cross((0, 1, 0), tx)
                wo_w = [-c for c in d]
                wo = mi.Vector3f(
                    sum(a * b for a, b in zip(wo_w, tx)), sum(a * b for a, b in zip(wo_w, bx)), wo_w[1]
                )
                m, pdf = dist.sample(wo, mi.Point2f(u1, u2))
                om = float(wo[0] * m[0] + wo[1] * m[1] + wo[2] * m[2])
                wi = [2 * om * float(m[i]) - float(wo[i]) for i in range(3)]
                if wi[2] <= 0 or om <= 0:
                    continue
                g1o = float(dist.smith_g1(wo, m))
                g1i = float(dist.smith_g1(mi.Vector3f(*wi), m))
                if g1o <= 0 or g1i <= 0:
                    continue
                expect = g1o * float(dist.eval(m)) * om / float(wo[2])
                assert abs(float(pdf) - expect) <= 1e-3 * expect + 1e-6, (pdf, expect)
                lo, li = 1.0 / g1o - 1.0, 1.0 / g1i - 1.0
                weight = (1.0 / (1.0 + lo + li)) / g1o
                # wi in the world: x along tx, y along bx, z = +y.
                w = [wi[0] * tx[i] + wi[1] * bx[i] for i in range(3)]
                w[1] += wi[2]
                s = (LAMP_Y - p[1]) / w[1]
                q = [p[i] + s * w[i] for i in range(3)]
                if LAMP["x"][0] <= q[0] <= LAMP["x"][1] and LAMP["z"][0] <= q[2] <= LAMP["z"][1]:
                    vals[k] = weight * LAMP["radiance"]
            mean[py, px, :] = vals.mean()
            var[py, px, :] = vals.var(ddof=1)
        print(f"row {py + 1}/{SIZE}", file=sys.stderr, flush=True)
    return mean, var


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=["gltf", "mitsuba"])
    ap.add_argument("--spp", type=int, default=8192)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    if args.what == "gltf":
        write_gltf(os.path.join(OUT, "anisotropy_scene.gltf"))
        return
    import mitsuba as mi

    t0 = time.time()
    mean, var = render(args.spp, args.seed)
    mi.Bitmap(mean).write(os.path.join(OUT, "mitsuba_anisotropy_mean.exr"))
    mi.Bitmap(var).write(os.path.join(OUT, "mitsuba_anisotropy_var.exr"))
    meta = {
        "seeds": args.spp,
        "what": "per-pixel samples of the anisotropic GGX floor (scripts/anisotropy_reference.py)",
        "mitsuba": mi.__version__,
        "spp": args.spp,
        "seed": args.seed,
        "seconds": round(time.time() - t0, 1),
    }
    with open(os.path.join(OUT, "mitsuba_anisotropy.json"), "w") as f:
        json.dump(meta, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
