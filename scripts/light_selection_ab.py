#!/usr/bin/env python3
"""Light selection by power against uniform selection, at equal CPU time
(docs/performance.md, "Defaults that matter for speed, and why"). Standard library only.

    python3 scripts/light_selection_ab.py [--vkvcm target/release/vkvcm] [--out DIR]
        [--algos pt,bpt,vcm] [--seeds 5] [--seconds 6] [--size 128] [--reference-seconds 600]

1. Writes a multi-light scene (`many_lamps.gltf`): a closed grey room, 3 x 2.5 x 3, with a
   glossy floor, lit by a large dim ceiling panel, eight small wall lamps whose radiance
   spans a factor of 100, and a point light in a corner: 18 emitting triangles and a point
   light, whose powers span a factor of about 900 (the point light about 17, the panel's
   triangles 1.3 each, the lamps' from 1.9 down to 0.02).
2. Renders a reference with `vkvcm reference --algo bpt` (its own error estimate is printed
   by `vkvcm diff`).
3. For each seed and estimator, renders with --light-selection power and uniform, in
   alternating order, each for --seconds of wall time in its own process, charged the
   whole process's CPU time (user + sys, RUSAGE_CHILDREN), and measures relMSE against the
   reference (`vkvcm diff`).
4. Prints per estimator and selection: the median and range over seeds of relMSE x CPU-s
   (lower is better) and of relMSE, and the ratio power / uniform of the medians.

Run it on an idle machine: the CPU time of a process under contention is not its own.
"""
import argparse
import base64
import json
import os
import platform
import resource
import statistics
import struct
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def quad(p0, p1, p2, p3):
    """Two triangles p0 p1 p2, p0 p2 p3 (counter-clockwise seen from their front)."""
    return [p0, p1, p2, p0, p2, p3]


def write_scene(path):
    """The room, its lights and a camera, as a self-contained glTF (data URI buffer)."""
    w, h, d = 3.0, 2.5, 3.0
    x0, x1, y0, y1, z0, z1 = -w / 2, w / 2, 0.0, h, -d / 2, d / 2
    # (material, triangles); the room's faces point inwards.
    parts = {
        "floor": quad((x0, y0, z1), (x1, y0, z1), (x1, y0, z0), (x0, y0, z0)),
        "walls": quad((x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0))
        + quad((x0, y0, z1), (x0, y0, z0), (x0, y1, z0), (x0, y1, z1))
        + quad((x1, y0, z0), (x1, y0, z1), (x1, y1, z1), (x1, y1, z0))
        + quad((x1, y0, z1), (x0, y0, z1), (x0, y1, z1), (x1, y1, z1))
        + quad((x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)),
        # The ceiling panel, just below the ceiling, facing down.
        "panel": quad((-0.6, y1 - 0.01, -0.6), (0.6, y1 - 0.01, -0.6), (0.6, y1 - 0.01, 0.6), (-0.6, y1 - 0.01, 0.6)),
    }
    lamps = []
    for k in range(8):
        # Small squares on the back and side walls, facing into the room.
        s = 0.06
        cy = 0.6 + 0.2 * k
        if k % 2 == 0:
            cx = -1.0 + 0.25 * k
            zf = z0 + 0.01
            lamps.append(quad((cx - s, cy - s, zf), (cx + s, cy - s, zf), (cx + s, cy + s, zf), (cx - s, cy + s, zf)))
        else:
            cz = -1.0 + 0.25 * k
            xf = x0 + 0.01
            lamps.append(quad((xf, cy - s, cz + s), (xf, cy - s, cz - s), (xf, cy + s, cz - s), (xf, cy + s, cz + s)))
    materials = [
        {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.45, 0.4, 1], "metallicFactor": 0.0,
                                                   "roughnessFactor": 0.3}, "doubleSided": True},
        {"name": "walls", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0.0,
                                                   "roughnessFactor": 1.0}, "doubleSided": True},
        {"name": "panel", "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0},
         "emissiveFactor": [1.0, 0.95, 0.9], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 0.6}},
         "doubleSided": True},
    ]
    for k in range(8):
        strength = 100.0 * 10 ** (-2.0 * k / 7)  # 100 down to 1
        materials.append({"name": f"lamp{k}", "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0},
                          "emissiveFactor": [1.0, 0.8, 0.6],
                          "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": strength}},
                          "doubleSided": True})
    groups = [parts["floor"], parts["walls"], parts["panel"]] + lamps
    data = bytearray()
    accessors, views, prims = [], [], []
    for m, tris in enumerate(groups):
        offset = len(data)
        for p in tris:
            data += struct.pack("<3f", *p)
        lo = [min(p[i] for p in tris) for i in range(3)]
        hi = [max(p[i] for p in tris) for i in range(3)]
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(data) - offset})
        accessors.append({"bufferView": len(views) - 1, "componentType": 5126, "count": len(tris), "type": "VEC3",
                          "min": lo, "max": hi})
        prims.append({"attributes": {"POSITION": len(accessors) - 1}, "material": m})
    gltf = {
        "asset": {"version": "2.0", "generator": "vkvcm scripts/light_selection_ab.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength", "KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1.0, 0.9, 0.8], "intensity": 1.5}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"mesh": 0},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [1.2, 2.2, -1.2]},
            # Camera near the front wall, looking at the back corner a little downwards.
            {"camera": 0, "translation": [0.0, 1.3, 1.4], "rotation": [-0.0998, 0.0, 0.0, 0.995]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.01}}],
        "meshes": [{"primitives": prims}],
        "materials": materials,
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(data)).decode()}],
        "bufferViews": views,
        "accessors": accessors,
    }
    path.write_text(json.dumps(gltf))


def run_charged(cmd, log):
    """Runs cmd; returns (CPU-s of the whole process: user + sys, wall s)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    with open(log, "w") as out:
        p = subprocess.run([str(c) for c in cmd], stdout=out, stderr=subprocess.STDOUT)
    wall = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.exit(f"{' '.join(map(str, cmd))} failed (log {log}):\n" + Path(log).read_text()[-2000:])
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), wall


def rel_mse(vk, image, reference):
    out = subprocess.run([str(vk), "diff", str(image), str(reference)], capture_output=True, text=True, check=True)
    for line in out.stdout.splitlines():
        if line.startswith("rel_mse"):
            return float(line.split()[1])
    sys.exit(f"vkvcm diff printed no rel_mse:\n{out.stdout}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vkvcm", default=str(REPO / "target" / "release" / "vkvcm"))
    ap.add_argument("--out", default=str(REPO / "target" / "light_selection_ab"))
    ap.add_argument("--algos", default="pt,bpt,vcm")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=6.0, help="wall seconds per render")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--reference-seconds", type=float, default=600.0)
    a = ap.parse_args()
    vk = Path(a.vkvcm).resolve()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    scene = out / "many_lamps.gltf"
    write_scene(scene)
    size = ["--width", str(a.size), "--height", str(a.size)]
    ref = out / f"reference_{a.size}_{int(a.reference_seconds)}.exr"
    if not ref.exists():
        print(f"reference: vkvcm reference --algo bpt, {a.reference_seconds:g} s ...", flush=True)
        run_charged([vk, "reference", scene, "--algo", "bpt", "--time", a.reference_seconds, "-o", ref] + size,
                    out / "reference.log")
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    print(f"# {time.strftime('%Y-%m-%d %H:%M:%S %Z')}, commit {commit}, {platform.node()}, "
          f"{os.cpu_count()} CPUs, load average before {os.getloadavg()[0]:.2f}")
    print(f"# scene {scene.name} at {a.size}x{a.size}, {a.seconds:g} s wall per render, {a.seeds} seeds, "
          f"reference {ref.name}")
    rows = {}
    algos = a.algos.split(",")
    for seed in range(1, a.seeds + 1):
        for algo in algos:
            order = ["power", "uniform"] if (seed + algos.index(algo)) % 2 else ["uniform", "power"]
            for sel in order:
                img = out / f"{algo}_{sel}_{seed}.exr"
                cpu, wall = run_charged([vk, "render", scene, "--algo", algo, "--light-selection", sel, "--seed",
                                         1000 + seed, "--time", a.seconds, "-o", img] + size,
                                        out / f"{algo}_{sel}_{seed}.log")
                e = rel_mse(vk, img, ref)
                rows.setdefault((algo, sel), []).append((e * cpu, e, cpu))
                print(f"seed {seed} {algo:4} {sel:8} relMSE {e:.4e} CPU-s {cpu:6.2f} wall {wall:5.2f} "
                      f"relMSE x CPU-s {e * cpu:.4e}", flush=True)
    print(f"# load average after {os.getloadavg()[0]:.2f}")
    print("| estimator | selection | relMSE x CPU-s, median (range) | relMSE, median | power / uniform |")
    print("|---|---|---|---|---|")
    for algo in algos:
        med = {}
        for sel in ["uniform", "power"]:
            r = rows[(algo, sel)]
            eff = [x[0] for x in r]
            med[sel] = statistics.median(eff)
            ratio = f"{med['power'] / med['uniform']:.2f}" if sel == "power" else ""
            print(f"| {algo} | {sel} | {med[sel]:.4e} ({min(eff):.3e} - {max(eff):.3e}) | "
                  f"{statistics.median(x[1] for x in r):.4e} | {ratio} |")


if __name__ == "__main__":
    main()
