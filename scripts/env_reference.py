#!/usr/bin/env python3
"""The environment-map comparison with Mitsuba 3 (tests/render_environment.rs,
`environment_map_matches_mitsuba`): one scene description, written as a glTF for vkvcm
and rendered by Mitsuba 3 as the independent reference.

The scene: a grey diffuse ground square (y = 0, |x|, |z| <= 2), a diffuse sphere and a
mirror sphere of radius 0.5 on it, lit only by tests/env/sky.hdr turned 30 degrees about +Y
(scripts/make_env_map.py). Conventions matched (docs/environment.md, docs/toolchain.md):
vkvcm's opaque surfaces reflect on both sides (Mitsuba: `twosided`), its mirror without an
IOR is a plain reflectance (Mitsuba: `conductor` with material `none` scaled by
`specular_reflectance`), camera `fov_axis` y with a box pixel filter, `max_depth` = vkvcm's
--max-path-length (both count segments), the envmap's lat-long mapping and `to_world`
rotation are the same functions in both.

    python3 scripts/env_reference.py gltf        # writes tests/env/env_scene.gltf (stdlib only)
    VENV/bin/python scripts/env_reference.py mitsuba [--seeds 16 --spp 256]
        # renders tests/env/mitsuba_mean.exr and tests/env/mitsuba_var.exr: the mean and the
        # unbiased per-pixel variance over SEEDS independent renders of SPP samples each,
        # and tests/env/mitsuba.json (what made them). Needs `pip install mitsuba numpy`.

With `--glass` (both commands) the mirror sphere is a smooth glass sphere of IOR 1.5
instead (tests/env/glass_scene.gltf, tests/env/mitsuba_glass_{mean,var}.exr,
mitsuba_glass.json): vkvcm's dielectric (VKVCM_materials_phong mirror 1, ior 1.5) against
Mitsuba's `dielectric` (int_ior 1.5, ext_ior 1). Both use the exact Fresnel equations;
Mitsuba scales radiance by the squared IOR ratio at each refraction, which cancels over
the entry and the exit of a closed sphere lit from outside.

With `--rough-glass` (both commands) that glass sphere is rough instead: a glTF material
with KHR_materials_transmission (transmissionFactor 1), KHR_materials_ior (1.5) and
roughnessFactor ROUGH_GLASS_ROUGHNESS (tests/env/rough_glass_scene.gltf,
tests/env/mitsuba_rough_glass_{mean,var}.exr, mitsuba_rough_glass.json), which vkvcm
imports as its rough dielectric of GGX alpha = roughness^2 (glsl/bsdf.glsl), against
Mitsuba's `roughdielectric` (distribution ggx, the same alpha, int_ior 1.5): both are the
BSDF of Walter et al. 2007 with the separable Smith shadowing G1(wo) G1(wi).

With `--volume` / `--rough-volume` (both commands) that glass sphere, smooth / of roughness
ROUGH_GLASS_ROUGHNESS, is a glTF material with KHR_materials_transmission, KHR_materials_ior
(1.5), a tinting baseColorFactor VOLUME_TINT and KHR_materials_volume (attenuationColor
VOLUME_COLOR at attenuationDistance VOLUME_DISTANCE): vkvcm tints the transmitted part by
the base colour and attenuates segments inside the sphere by exp(-sigma l), sigma =
-ln(attenuationColor) / attenuationDistance (Beer-Lambert, glsl/medium.glsl). Mitsuba:
`dielectric` / `roughdielectric` with specular_transmittance = the tint, the sphere's
`interior` a `homogeneous` medium of albedo 0 and sigma_t = sigma, integrator `volpath`
(tests/env/{volume,rough_volume}_scene.gltf, mitsuba_{volume,rough_volume}_{mean,var}.exr
and .json). These scenes are VOLUME_SIZE pixels square, looking down at the glass sphere (no pixel sees only the sky, whose
clipped texels have no variance to test with).

With `--smooth` (both commands) the diffuse sphere is a coarse smooth-shaded mesh instead
(a UV sphere of 6 x 10 quads with the sphere's normals at its vertices, tests/env/
smooth_scene.gltf, tests/env/mitsuba_smooth_{mean,var}.exr, mitsuba_smooth.json): the
comparison for vkvcm's shading normals (docs/numerics.md). Mitsuba gets the same triangles
as an OBJ file with vertex normals, and a one-sided `diffuse` (wo below the shading
hemisphere is black in both; a direction that the shading normal allows but the facet does
not is rejected by vkvcm and, in Mitsuba, enters the closed mesh, where it finds no light).
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

SCENE = {
    "width": 48,
    "height": 48,
    "max_path_length": 8,
    "camera": {"from": [0.0, 1.2, 3.5], "to": [0.0, 0.4, 0.0], "up": [0.0, 1.0, 0.0], "yfov_deg": 40.0},
    "environment": {"file": "sky.hdr", "strength": 1.0, "rotation_deg": 30.0},
    "ground": {"half_size": 2.0, "diffuse": [0.5, 0.5, 0.5]},
    "spheres": [
        {"center": [-0.6, 0.5, 0.0], "radius": 0.5, "diffuse": [0.8, 0.5, 0.3]},
        {"center": [0.6, 0.5, 0.0], "radius": 0.5, "mirror": [0.9, 0.9, 0.9]},
    ],
}


def write_json(path, value):
    """`value` as indented JSON with a final newline."""
    with open(path, "w") as f:
        json.dump(value, f, indent=1)
        f.write("\n")


def look_at_quaternion(eye, target, up):
    """The glTF node rotation (x, y, z, w) whose -Z looks from eye to target, +Y near up."""
    f = [t - e for t, e in zip(target, eye)]
    n = math.sqrt(sum(c * c for c in f))
    f = [c / n for c in f]
    z = [-c for c in f]  # the camera looks along -Z
    x = [up[1] * z[2] - up[2] * z[1], up[2] * z[0] - up[0] * z[2], up[0] * z[1] - up[1] * z[0]]
    n = math.sqrt(sum(c * c for c in x))
    x = [c / n for c in x]
    y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]]
    m = [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]  # columns x, y, z
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        return [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, 0.25 * s]
    if m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
        return [0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s]
    if m[1][1] > m[2][2]:
        s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
        return [(m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s]
    s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
    return [(m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s, (m[1][0] - m[0][1]) / s]


# The smooth variant's mesh: rings x segments quads.
SMOOTH_RINGS, SMOOTH_SEGMENTS = 6, 10


def smooth_sphere_triangles(center, radius):
    """[(positions, normals)] of a UV sphere's triangles, counter-clockwise seen from outside."""
    def d(i, j):
        th = math.pi * i / SMOOTH_RINGS
        ph = 2 * math.pi * j / SMOOTH_SEGMENTS
        return (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
    sub = lambda a, b: [x - y for x, y in zip(a, b)]
    cross = lambda a, b: [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    out = []
    for i in range(SMOOTH_RINGS):
        for j in range(SMOOTH_SEGMENTS):
            a, b, c, e = d(i, j), d(i + 1, j), d(i + 1, j + 1), d(i, j + 1)
            for tri in ((a, b, c), (a, c, e)):
                n = cross(sub(tri[1], tri[0]), sub(tri[2], tri[0]))
                if sum(x * x for x in n) < 1e-18:
                    continue  # a pole's degenerate triangle
                if sum(x * y for x, y in zip(n, [tri[0][k] + tri[1][k] + tri[2][k] for k in range(3)])) < 0:
                    tri = (tri[0], tri[2], tri[1])
                out.append(([[center[k] + radius * v[k] for k in range(3)] for v in tri], [list(v) for v in tri]))
    return out


GLASS_IOR = 1.5
ROUGH_GLASS_ROUGHNESS = 0.3
VOLUME_TINT = [1.0, 0.85, 0.6]
VOLUME_COLOR = [0.7, 0.35, 0.15]
VOLUME_DISTANCE = 0.8
VOLUME_SIZE = 32
VOLUME_CAMERA = {"from": [1.0, 2.6, 1.6], "to": [0.55, 0.4, 0.0], "up": [0.0, 1.0, 0.0], "yfov_deg": 30.0}


def volume_sigma():
    """The attenuation coefficient of --volume / --rough-volume: -ln(c) / d per channel."""
    return [-math.log(c) / VOLUME_DISTANCE for c in VOLUME_COLOR]


def glass_spheres(spheres, rough=False):
    """`spheres` with the mirror sphere made of glass (`--glass`), rough with `--rough-glass`."""
    glass = {"glass": GLASS_IOR} | ({"roughness": ROUGH_GLASS_ROUGHNESS} if rough else {})
    return [{k: v for k, v in sp.items() if k != "mirror"} | glass if "mirror" in sp else sp for sp in spheres]


def scene_of(glass, rough, volume=False):
    """The scene description: SCENE, with the glass sphere for --glass / --rough-glass, and
    with the absorbing tinted glass sphere for --volume (glass) / --rough-volume (rough)."""
    if volume:
        vol = {"volume": {"color": VOLUME_COLOR, "distance": VOLUME_DISTANCE, "sigma": volume_sigma()}, "tint": VOLUME_TINT}
        spheres = [sp | vol if "glass" in sp else sp for sp in glass_spheres(SCENE["spheres"], rough)]
        return dict(SCENE, spheres=spheres, width=VOLUME_SIZE, height=VOLUME_SIZE, camera=VOLUME_CAMERA)
    return dict(SCENE, spheres=glass_spheres(SCENE["spheres"], rough)) if glass or rough else SCENE


def write_gltf(path, smooth, glass=False, rough=False, volume=False):
    s = scene_of(glass, rough, volume)
    h = s["ground"]["half_size"]
    quad = [(-h, 0, -h), (-h, 0, h), (h, 0, h), (-h, 0, -h), (h, 0, h), (h, 0, -h)]
    blob = b"".join(struct.pack("<3f", *p) for p in quad)
    phong = lambda d=(0, 0, 0), m=(0, 0, 0): {"VKVCM_materials_phong": {"diffuse": list(d), "mirror": list(m), "ior": -1}}
    materials = [{"name": "ground", "extensions": phong(d=s["ground"]["diffuse"])}]
    meshes = [{"name": "ground", "primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}]
    accessors = [{"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3", "min": [-h, 0, -h], "max": [h, 0, h]}]
    views = [{"buffer": 0, "byteLength": len(blob)}]
    spheres = []
    for i, sp in enumerate(s["spheres"]):
        ext = phong(d=sp.get("diffuse", (0, 0, 0)), m=sp.get("mirror", (0, 0, 0)))
        if "roughness" in sp or "volume" in sp:
            # glTF's own glass: base colour (white: clear), metallic 0, full transmission.
            tint = sp.get("tint", [1, 1, 1])
            pbr = {"baseColorFactor": tint + [1], "metallicFactor": 0.0, "roughnessFactor": sp.get("roughness", 0.0)}
            ext = {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": sp["glass"]}}
            if "volume" in sp:
                v = sp["volume"]
                ext["KHR_materials_volume"] = {"attenuationColor": v["color"], "attenuationDistance": v["distance"]}
            materials.append({"name": f"sphere{i}", "pbrMetallicRoughness": pbr, "extensions": ext})
        else:
            if "glass" in sp:
                ext = {"VKVCM_materials_phong": {"diffuse": [0, 0, 0], "mirror": [1, 1, 1], "ior": sp["glass"]}}
            materials.append({"name": f"sphere{i}", "extensions": ext})
        if smooth and "diffuse" in sp:
            tris = smooth_sphere_triangles(sp["center"], sp["radius"])
            pos = [p for t in tris for p in t[0]]
            nrm = [n for t in tris for n in t[1]]
            for values, name in ((pos, "POSITION"), (nrm, "NORMAL")):
                chunk = b"".join(struct.pack("<3f", *v) for v in values)
                views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(chunk)})
                acc = {"bufferView": len(views) - 1, "componentType": 5126, "count": len(values), "type": "VEC3"}
                if name == "POSITION":
                    acc["min"] = [min(v[k] for v in values) for k in range(3)]
                    acc["max"] = [max(v[k] for v in values) for k in range(3)]
                accessors.append(acc)
                blob += chunk
            n = len(accessors)
            meshes.append({"name": f"sphere{i}", "primitives": [{"attributes": {"POSITION": n - 2, "NORMAL": n - 1}, "material": i + 1}]})
        else:
            spheres.append({"center": sp["center"], "radius": sp["radius"], "material": i + 1})
    cam = s["camera"]
    env = s["environment"]
    doc = {
        "asset": {"version": "2.0", "generator": "vkvcm scripts/env_reference.py"},
        "extensionsUsed": ["VKVCM_spheres", "VKVCM_materials_phong", "VKVCM_environment"]
        + (["KHR_materials_transmission", "KHR_materials_ior"] if rough or volume else [])
        + (["KHR_materials_volume"] if volume else []),
        "extensions": {"VKVCM_environment": {"uri": env["file"], "strength": env["strength"], "rotation": env["rotation_deg"]}},
        "scene": 0,
        "scenes": [{"name": scene_stem(smooth, glass, rough, volume), "nodes": list(range(3 + len(meshes) - 1))}],
        "nodes": [
            {"name": "ground", "mesh": 0},
            {"name": "spheres", "extensions": {"VKVCM_spheres": {"spheres": spheres}}},
            {"name": "camera", "camera": 0, "translation": cam["from"], "rotation": look_at_quaternion(cam["from"], cam["to"], cam["up"])},
        ] + [{"name": m["name"], "mesh": k + 1} for k, m in enumerate(meshes[1:])],
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(cam["yfov_deg"]), "znear": 0.01, "aspectRatio": 1.0}}],
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    }
    # vkvcm's two-sided surfaces (the Mitsuba side's BSDFs are `twosided`).
    for m in doc["materials"]:
        m["doubleSided"] = True
    write_json(path, doc)
    print(f"wrote {path}")


def write_obj(path, tris):
    with open(path, "w") as f:
        for pos, nrm in tris:
            for p in pos:
                f.write("v %.9g %.9g %.9g\n" % tuple(p))
            for n in nrm:
                f.write("vn %.9g %.9g %.9g\n" % tuple(n))
        for k in range(len(tris)):
            a = 3 * k + 1
            f.write(f"f {a}//{a} {a + 1}//{a + 1} {a + 2}//{a + 2}\n")


def scene_stem(smooth, glass, rough=False, volume=False):
    if volume:
        return "rough_volume_scene" if rough else "volume_scene"
    return "smooth_scene" if smooth else "rough_glass_scene" if rough else "glass_scene" if glass else "env_scene"


def mitsuba_scene(mi, seed, spp, smooth, tmp, glass=False, rough=False, volume=False):
    s = scene_of(glass, rough, volume)
    T = mi.ScalarTransform4f
    cam = s["camera"]
    env = s["environment"]
    h = s["ground"]["half_size"]
    d = {
        "type": "scene",
        "integrator": {"type": "volpath" if volume else "path", "max_depth": s["max_path_length"], "hide_emitters": False},
        "sensor": {
            "type": "perspective",
            "fov": cam["yfov_deg"],
            "fov_axis": "y",
            "to_world": T().look_at(origin=cam["from"], target=cam["to"], up=cam["up"]),
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
            "film": {"type": "hdrfilm", "width": s["width"], "height": s["height"], "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        },
        "env": {"type": "envmap", "filename": os.path.join(OUT, env["file"]), "scale": env["strength"], "to_world": T().rotate([0, 1, 0], env["rotation_deg"])},
        # Mitsuba's rectangle is [-1, 1]^2 in z = 0; turned onto y = 0.
        "ground": {
            "type": "rectangle",
            "to_world": T().rotate([1, 0, 0], -90).scale([h, h, 1]),
            "bsdf": {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": s["ground"]["diffuse"]}}},
        },
    }
    for i, sp in enumerate(s["spheres"]):
        if "mirror" in sp:
            bsdf = {"type": "conductor", "material": "none", "specular_reflectance": {"type": "rgb", "value": sp["mirror"]}}
        elif "roughness" in sp:
            bsdf = {"type": "roughdielectric", "distribution": "ggx", "alpha": sp["roughness"] ** 2,
                    "sample_visible": False, "int_ior": sp["glass"], "ext_ior": 1.0}
        elif "glass" in sp:
            bsdf = {"type": "dielectric", "int_ior": sp["glass"], "ext_ior": 1.0}
        elif smooth:
            obj = os.path.join(tmp, f"sphere{i}.obj")
            write_obj(obj, smooth_sphere_triangles(sp["center"], sp["radius"]))
            diffuse = {"type": "diffuse", "reflectance": {"type": "rgb", "value": sp["diffuse"]}}
            d[f"sphere{i}"] = {"type": "obj", "filename": obj, "face_normals": False, "bsdf": diffuse}
            continue
        else:
            bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": sp["diffuse"]}}}
        if "tint" in sp:
            bsdf["specular_transmittance"] = {"type": "rgb", "value": sp["tint"]}
        d[f"sphere{i}"] = {"type": "sphere", "center": sp["center"], "radius": sp["radius"], "bsdf": bsdf}
        if "volume" in sp:
            # An RGB value must lie in [0, 1]: sigma_t = (sigma / max) x scale max.
            top = max(sp["volume"]["sigma"])
            sigma = {"type": "rgb", "value": [x / top for x in sp["volume"]["sigma"]]}
            d[f"sphere{i}"]["interior"] = {"type": "homogeneous", "albedo": 0.0, "sigma_t": sigma, "scale": top}
    return d


def render_mitsuba(seeds, spp, variant, smooth, glass=False, rough=False, volume=False):
    try:
        import mitsuba as mi
        import numpy as np
    except ImportError:
        sys.exit("mitsuba and numpy are needed: python3 -m venv VENV && VENV/bin/pip install mitsuba numpy")
    mi.set_variant(variant)
    import tempfile
    tmp = tempfile.mkdtemp()
    stem = ("mitsuba_rough_volume" if rough else "mitsuba_volume") if volume else "mitsuba_smooth" if smooth else "mitsuba_rough_glass" if rough else "mitsuba_glass" if glass else "mitsuba"
    images = []
    t0 = time.time()
    for seed in range(seeds):
        scene = mi.load_dict(mitsuba_scene(mi, seed, spp, smooth, tmp, glass, rough, volume))
        images.append(np.array(mi.render(scene, seed=seed, spp=spp), dtype=np.float64))
        print(f"seed {seed}: {time.time() - t0:.0f} s", flush=True)
    stack = np.stack(images)
    mean = stack.mean(axis=0).astype(np.float32)
    var = stack.var(axis=0, ddof=1).astype(np.float32)
    mi.Bitmap(mean).write(os.path.join(OUT, f"{stem}_mean.exr"))
    mi.Bitmap(var).write(os.path.join(OUT, f"{stem}_var.exr"))
    integrator = "volpath" if volume else "path"
    meta = {"renderer": f"Mitsuba {mi.__version__} {variant}, integrator {integrator}", "seeds": seeds, "spp_per_seed": spp,
            "scene": scene_of(glass, rough, volume),
            "smooth_sphere": [SMOOTH_RINGS, SMOOTH_SEGMENTS] if smooth else None,
            "command": " ".join(sys.argv)}
    write_json(os.path.join(OUT, f"{stem}.json"), meta)
    print(f"wrote tests/env/{stem}_mean.exr, {stem}_var.exr ({seeds} seeds x {spp} spp, {time.time() - t0:.0f} s)")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=["gltf", "mitsuba"])
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--smooth", action="store_true", help="the diffuse sphere as a smooth-shaded mesh")
    ap.add_argument("--glass", action="store_true", help="the mirror sphere made of glass (IOR 1.5)")
    ap.add_argument("--rough-glass", action="store_true", help="the mirror sphere made of rough glass (IOR 1.5, glTF roughness 0.3)")
    ap.add_argument("--volume", action="store_true", help="the mirror sphere made of tinted glass holding an absorbing medium")
    ap.add_argument("--rough-volume", action="store_true", help="--volume with rough glass (glTF roughness 0.3)")
    a = ap.parse_args()
    if a.smooth + a.glass + a.rough_glass + a.volume + a.rough_volume > 1:
        sys.exit("--smooth, --glass, --rough-glass, --volume and --rough-volume are separate scenes")
    volume = a.volume or a.rough_volume
    rough = a.rough_glass or a.rough_volume
    if a.what == "gltf":
        stem = scene_stem(a.smooth, a.glass, rough, volume)
        write_gltf(os.path.join(OUT, stem + ".gltf"), a.smooth, a.glass, rough, volume)
    else:
        render_mitsuba(a.seeds, a.spp, a.variant, a.smooth, a.glass, rough, volume)


if __name__ == "__main__":
    main()
