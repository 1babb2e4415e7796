#!/usr/bin/env python3
"""vkvcm's pt against Blender's Cycles (CPU, through `pip install bpy`) on glTF assets.

    python3 scripts/peers/blender_cycles.py setup [--python python3.13]   # the venv (bpy, numpy, OpenEXR)
    python3 scripts/peers/blender_cycles.py run --quick                   # a few minutes: two generated scenes, 64x64
    python3 scripts/peers/blender_cycles.py run                           # the full comparison (README-cycles.md)
    python3 scripts/peers/blender_cycles.py run --assets glass,emitters --cpu 20 --seeds 3

Both renderers read the same glTF file: a copy of the asset with a camera node added
(cycles_assets.py), imported by Blender's own glTF importer. Uniform white environment of
radiance 1, max path length 10 (vkvcm's segments) = Cycles' max_bounces 8, box pixel filter
of one pixel, no denoising, adaptive sampling, clamping or glossy filter. Each renderer is
measured against a long reference of its own (model differences do not count); every
render is a fresh process charged its whole CPU time (user + sys).

The driver runs with the venv's python (it re-executes itself there); Cycles renders run
as `python blender_cycles.py _cycles ...` in the same venv.
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
sys.path.insert(0, str(HERE))
import cycles_assets  # noqa: E402

REQUIREMENTS = ["bpy==5.3.0", "numpy>=1.26,<3", "OpenEXR>=3.3,<4"]
CACHE = Path(os.environ.get("VKVCM_CYCLES_CACHE", Path.home() / ".cache" / "vkvcm-cycles"))
# Same as peers' imgtool.REL_MSE_EPSILON and `vkvcm diff`.
REL_MSE_EPSILON = 1e-2
# CPU-s the calibration's probe samples must cost beyond the start-up.
PROBE_CPU = 1.5


class HarnessError(Exception):
    pass


def log(msg):
    print(f"[{datetime.now().strftime('%H:%M:%S')}] {msg}", flush=True)


def venv_python(cache):
    return cache / "venv" / "bin" / "python"


# ---------------------------------------------------------------------------------------
# setup


def cmd_setup(args):
    cache = Path(args.cache)
    cache.mkdir(parents=True, exist_ok=True)
    venv = cache / "venv"
    log(f"making {venv} with {args.python} (bpy 5.3 needs Python 3.13)")
    r = subprocess.run([args.python, "-m", "venv", str(venv)])
    if r.returncode != 0:
        raise HarnessError(f"{args.python} -m venv failed: is Python 3.13 with venv installed?")
    r = subprocess.run([str(venv / "bin" / "pip"), "install", "-q", *REQUIREMENTS])
    if r.returncode != 0:
        raise HarnessError("pip install failed (network? bpy's wheel is about 300 MB)")
    out = subprocess.run([str(venv_python(cache)), "-c", "import bpy; print(bpy.app.version_string)"],
                         capture_output=True, text=True)
    log(f"bpy {out.stdout.strip()} ready in {venv}")


# ---------------------------------------------------------------------------------------
# Rendering, each one a child process charged its CPU time.


def run_charged(cmd, log_path, env=None):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    with open(log_path, "w") as out:
        p = subprocess.run([str(c) for c in cmd], stdout=out, stderr=subprocess.STDOUT, env=env)
    wall = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if p.returncode != 0:
        tail = "\n".join(Path(log_path).read_text(errors="replace").splitlines()[-10:])
        raise HarnessError(f"{Path(str(cmd[0])).name} exited with {p.returncode} (log {log_path}):\n{tail}")
    return cpu, wall


class Vkvcm:
    def __init__(self, binary, size, max_len, name="vkvcm", glsl=None):
        # `glsl`: render with the shaders of that folder (VKVCM_GLSL_DIR), e.g. a commit's
        # glsl/ for a before/after row; such a row is scored against vkvcm's reference.
        self.binary, self.size, self.max_len, self.name, self.glsl = binary, size, max_len, name, glsl
        self.ref_of = "vkvcm" if glsl else None

    def render(self, scene, seed, spp, out):
        cmd = [self.binary, "render", scene, "--algo", "pt", "--camera", cycles_assets.CAMERA, "--env", "white",
               "--max-path-length", self.max_len, "--width", self.size, "--height", self.size, "--seed", seed,
               "--iterations", spp, "-o", out, "--quiet"]
        return run_charged(cmd, str(out) + ".log", env=dict(os.environ, VKVCM_GLSL_DIR=self.glsl) if self.glsl else None)


class Cycles:
    name = "cycles"
    ref_of = None

    def __init__(self, cache, size, threads, max_len, ggx):
        self.python, self.size, self.threads, self.max_len, self.ggx = venv_python(cache), size, threads, max_len, ggx

    def render(self, scene, seed, spp, out):
        return run_charged([self.python, __file__, "_cycles", scene, seed, spp, out, self.size, self.threads,
                            self.max_len, self.ggx], str(out) + ".log")


def cycles_child(scene, seed, spp, out, size, threads, max_len, ggx):
    """Runs inside the venv: the harness's Cycles render of an asset (its added camera,
    the white sky, size x size); ggx `single`: the Principled BSDFs the importer made use
    single-scattering GGX, glTF's model and vkvcm's, instead of Blender's default
    multiple-scattering GGX (which keeps the energy that rough lobes lose)."""
    def single_scatter(bpy):
        for m in bpy.data.materials:
            for n in (m.node_tree.nodes if m.use_nodes else []):
                if n.type == "BSDF_PRINCIPLED":
                    n.distribution = "GGX"
    render_cycles(scene, cycles_assets.CAMERA, seed, spp, out, size, size, threads, (1.0, 1.0, 1.0),
                  after_import=single_scatter if ggx == "single" else None, max_path_length=int(max_len))


def render_cycles(scene, camera, seed, spp, out, width, height, threads, world_rgb, after_import=None,
                  max_path_length=10):
    """Runs inside the venv: imports the glTF with Blender's importer and renders it with
    Cycles through the camera whose name starts with `camera` (None: the file's first) to a
    float EXR, settings matched to vkvcm's (below), a uniform world of colour world_rgb.
    `after_import(bpy)`, if given, adjusts what the importer made (what it does not read)."""
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.preferences.addon_enable(module="cycles")  # the empty factory settings leave it off
    bpy.ops.import_scene.gltf(filepath=str(scene))
    if after_import is not None:
        after_import(bpy)
    sc = bpy.context.scene
    cams = [o for o in sc.objects if o.type == "CAMERA" and (camera is None or o.name.startswith(camera))]
    if not cams:
        raise SystemExit(f"no camera {camera or ''} after import")
    sc.camera = cams[0]
    sc.render.engine = "CYCLES"
    c = sc.cycles
    c.device = "CPU"
    c.samples = int(spp)
    c.seed = int(seed)
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    # vkvcm's max path length (segments) = camera segment + Cycles' bounces + the segment
    # to the light (Cycles' 0 bounces is direct light only): 10 = 8 bounces.
    bounces = int(max_path_length) - 2
    c.max_bounces = bounces
    c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = c.volume_bounces = bounces
    c.transparent_max_bounces = bounces
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    sc.render.threads_mode = "FIXED"
    sc.render.threads = int(threads)
    sc.render.resolution_x, sc.render.resolution_y = int(width), int(height)
    sc.render.resolution_percentage = 100
    sc.render.film_transparent = False
    sc.view_settings.view_transform = "Standard"
    sc.view_settings.look = "None"
    world = bpy.data.worlds.new("uniform")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (*world_rgb, 1.0)
    bg.inputs["Strength"].default_value = 1.0
    sc.world = world
    s = sc.render.image_settings
    s.file_format = "OPEN_EXR"
    s.color_depth = "32"
    s.color_mode = "RGB"
    sc.render.filepath = str(out)
    bpy.ops.render.render(write_still=True)


# ---------------------------------------------------------------------------------------
# Images and metrics (numpy, OpenEXR: in the venv).


def read_rgb(path):
    import numpy as np
    import OpenEXR
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {name: np.array(c.pixels, dtype=np.float64) for name, c in f.channels().items()}
    return np.stack([ch["R"], ch["G"], ch["B"]], axis=-1)


def reference(paths):
    """Mean of independent renders of equal spp and the variance of that mean."""
    import numpy as np
    imgs = np.stack([read_rgb(p) for p in paths])
    return imgs.mean(0), imgs.var(0, ddof=1) / len(paths)


def score(img, ref, ref_var):
    """relMSE of img against ref, less the reference's own noise floor."""
    import numpy as np
    w = 1.0 / (ref * ref + REL_MSE_EPSILON)
    return float(np.mean((img - ref) ** 2 * w) - np.mean(ref_var * w))


def to_srgb8(img):
    import numpy as np
    x = np.clip(img, 0.0, 1.0)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (x * 255 + 0.5).astype(np.uint8)


def montage(path, panels):
    """Panels side by side (sRGB of the linear images; the last a ratio map)."""
    import numpy as np
    row = np.concatenate([to_srgb8(p) for p in panels], axis=1)
    h, w, _ = row.shape
    Path(path).write_bytes(cycles_assets.png(w, h, [r.tobytes() for r in row]))


def ratio_map(a, b):
    """vkvcm / Cycles luminance as colour: grey = equal, red = vkvcm brighter, blue darker
    (full colour at a factor of 2)."""
    import numpy as np
    la, lb = a.mean(-1), b.mean(-1)
    r = np.log2((la + 1e-3) / (lb + 1e-3))
    t = np.clip(r, -1, 1)
    out = np.full(a.shape, 0.5)
    out[..., 0] += 0.5 * np.clip(t, 0, 1) - 0.5 * np.clip(-t, 0, 1) * 0.5
    out[..., 2] += 0.5 * np.clip(-t, 0, 1) - 0.5 * np.clip(t, 0, 1) * 0.5
    out[..., 1] -= 0.25 * np.abs(t)
    return out ** 2.2  # to_srgb8 applies the sRGB curve


def object_mask(*refs):
    """Pixels that are not the bare white sky in either reference."""
    import numpy as np
    m = np.zeros(refs[0].shape[:2], bool)
    for r in refs:
        m |= np.abs(r - 1.0).max(-1) > 1e-3
    return m


# ---------------------------------------------------------------------------------------
# run


def calibrate(prog, scene, work, spp_probe):
    """(start-up CPU-s, CPU-s per sample): a 1-sample run twice (the second counted, so
    kernel caches are warm as for any second render) and probe runs from spp_probe
    samples up, 4x more each time until the samples cost at least PROBE_CPU CPU-s more
    than the start-up (else a noisy start-up swamps the difference)."""
    prog.render(scene, 999, 1, work / f"{prog.name}_warm.exr")
    startup, _ = prog.render(scene, 998, 1, work / f"{prog.name}_warm.exr")
    spp = max(spp_probe, 2)
    while True:
        cpu, _ = prog.render(scene, 997, spp, work / f"{prog.name}_probe.exr")
        if cpu - startup >= PROBE_CPU or spp >= 65536:
            return startup, max((cpu - startup) / (spp - 1), 1e-6)
        spp *= 4


def spp_for(budget, startup, per):
    return max(1, int(round((budget - startup) / per)))


def run_asset(args, name, progs, out):
    adir = out / name
    adir.mkdir(parents=True, exist_ok=True)
    scene, view = cycles_assets.prepare(name, Path(args.cache) / "assets")
    log(f"{name}: {scene} (camera at {[round(x, 2) for x in view['eye']]})")
    res = {"asset": name, "scene": str(scene), "view": view, "programs": {}}
    for prog in progs:
        startup, per = calibrate(prog, scene, adir, args.probe_spp)
        if prog.ref_of:
            res["programs"][prog.name] = {"startup": startup, "cpu_per_spp": per, "ref_of": prog.ref_of, "runs": []}
            continue
        ref_spp = spp_for(args.ref_cpu / args.ref_chunks, startup, per)
        log(f"{name} {prog.name}: start-up {startup:.1f} CPU-s, {per * 1e3:.1f} CPU-ms per sample; "
            f"reference {args.ref_chunks} x {ref_spp} spp")
        chunks = []
        for k in range(args.ref_chunks):
            p = adir / f"{prog.name}_ref{k}.exr"
            prog.render(scene, 5000 + k, ref_spp, p)
            chunks.append(p)
        res["programs"][prog.name] = {"startup": startup, "cpu_per_spp": per, "ref_spp": ref_spp,
                                      "ref_chunks": [str(p) for p in chunks], "runs": []}
    # Timed runs, alternating the programs' order by seed.
    budget = {p: spp_for(args.cpu, r["startup"], r["cpu_per_spp"]) for p, r in res["programs"].items()}
    for seed in range(1, args.seeds + 1):
        order = progs if seed % 2 else progs[::-1]
        for prog in order:
            r = res["programs"][prog.name]
            spp = min(budget.values()) if args.equal_spp else budget[prog.name]
            p = adir / f"{prog.name}_s{seed}.exr"
            cpu, wall = prog.render(scene, seed, spp, p)
            r["runs"].append({"seed": seed, "spp": spp, "cpu": cpu, "wall": wall, "image": str(p)})
            log(f"{name} {prog.name} seed {seed}: {spp} spp, {cpu:.1f} CPU-s, {wall:.1f} s")
    measure(res, adir)
    return res


def measure(res, adir):
    import numpy as np
    refs = {}
    for pname, r in sorted(res["programs"].items(), key=lambda kv: "ref_of" in kv[1]):
        if "ref_of" in r:
            ref, var = refs[r["ref_of"]]
        else:
            ref, var = reference(r["ref_chunks"])
            refs[pname] = ref, var
        w = 1.0 / (ref * ref + REL_MSE_EPSILON)
        r["ref_floor"] = float(np.mean(var * w))
        for run in r["runs"]:
            rel = score(read_rgb(run["image"]), ref, var)
            run["relmse"] = rel
            run["var_per_spp"] = rel * run["spp"]
            run["relmse_cpu"] = rel * run["cpu"]
            run["spp_per_cpu"] = run["spp"] / run["cpu"]
    if "vkvcm" in refs and "cycles" in refs:
        a, b = refs["vkvcm"][0], refs["cycles"][0]
        m = object_mask(a, b)
        res["mean_ratio_image"] = float(a.mean() / b.mean())
        res["mean_ratio_object"] = float(a[m].mean() / b[m].mean()) if m.any() else None
        res["object_pixels"] = int(m.sum())
        first = [read_rgb(res["programs"][p]["runs"][0]["image"]) for p in ("vkvcm", "cycles")]
        montage(adir / "montage.png", [a, b, first[0], first[1], ratio_map(a, b)])
        res["montage"] = str(adir / "montage.png")


def median(xs):
    xs = sorted(xs)
    n = len(xs)
    return (xs[n // 2] + xs[(n - 1) // 2]) / 2 if n else float("nan")


def table(results, header):
    lines = [header, "",
             "| asset | image mean vkvcm/Cycles (object) | variance per sample vkvcm/Cycles | "
             "samples per CPU-s vkvcm/Cycles | relMSE x CPU-s vkvcm/Cycles | variance per sample vkvcm, Cycles |",
             "|---|---|---|---|---|---|"]
    for res in results:
        p = res["programs"]
        if "vkvcm" not in p or "cycles" not in p:
            continue
        med = {k: {q: median([run[q] for run in p[k]["runs"]]) for q in
                   ("var_per_spp", "spp_per_cpu", "relmse_cpu")} for k in p}
        obj = res.get("mean_ratio_object")
        for k in sorted(med, key=lambda k: (k != "vkvcm-before", k)):
            if k == "cycles":
                continue
            ratio = {q: med[k][q] / med["cycles"][q] for q in med[k]}
            label = res["asset"] + (" (before)" if k != "vkvcm" else "")
            lines.append(f"| {label} | {res['mean_ratio_image']:.3f} ({obj:.3f}) | {ratio['var_per_spp']:.2f} | "
                         f"{ratio['spp_per_cpu']:.2f} | {ratio['relmse_cpu']:.2f} | "
                         f"{med[k]['var_per_spp']:.3g}, {med['cycles']['var_per_spp']:.3g} |")
    lines += ["", "Medians over the seeds; variance per sample = relMSE x spp against the renderer's own",
              "reference, less that reference's noise floor; CPU = whole process (user + sys)."]
    return "\n".join(lines)


def git(*a):
    try:
        return subprocess.run(["git", "-C", str(REPO), *a], capture_output=True, text=True).stdout.strip()
    except OSError:
        return "?"


def cmd_run(args):
    cache = Path(args.cache)
    if args.quick:
        args.size, args.cpu, args.seeds, args.ref_cpu, args.ref_chunks, args.probe_spp = 64, 4.0, 3, 24.0, 4, 4
        args.assets = args.assets or "glass,emitters"
    assets = (args.assets or ",".join(cycles_assets.ALL)).split(",")
    binary = args.vkvcm or os.environ.get("VKVCM_BIN") or str(REPO / "target" / "release" / "vkvcm")
    if not Path(binary).exists():
        raise HarnessError(f"no vkvcm binary at {binary} (cargo build --release, or --vkvcm PATH)")
    progs = []
    if "vkvcm" in args.programs:
        progs.append(Vkvcm(binary, args.size, args.max_path_length))
        if args.before_glsl:
            progs.append(Vkvcm(binary, args.size, args.max_path_length, "vkvcm-before",
                               str(Path(args.before_glsl).resolve())))
    if "cycles" in args.programs:
        progs.append(Cycles(cache, args.size, args.threads, args.max_path_length, args.cycles_ggx))
    stamp = datetime.now(timezone.utc).strftime("%Y%m%d-%H%M%S")
    out = Path(args.out) / stamp
    out.mkdir(parents=True, exist_ok=True)
    load = os.getloadavg()
    header = (f"{'QUICK ' if args.quick else ''}vkvcm pt vs Cycles, {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC, "
              f"commit {git('rev-parse', '--short', 'HEAD')}{' (dirty)' if git('status', '--porcelain') else ''}, "
              f"{os.uname().nodename}, {os.cpu_count()} CPUs, load {load[0]:.1f} at start; "
              f"{args.size}x{args.size}, {args.cpu:g} CPU-s x {args.seeds} seeds per renderer, "
              f"references {args.ref_chunks} x {args.ref_cpu / args.ref_chunks:g} CPU-s"
              + (f"; max path length {args.max_path_length}" if args.max_path_length != 10 else "")
              + (f"; Cycles' GGX {args.cycles_ggx}-scattering" if args.cycles_ggx != "multi" else "")
              + ("; equal spp (what the slowest renderer does in the budget)" if args.equal_spp else "")
              + (f"; VKVCM_GLSL_DIR={os.environ['VKVCM_GLSL_DIR']}" if os.environ.get("VKVCM_GLSL_DIR") else "")
              + (f"; before: {args.before_glsl}" if args.before_glsl else ""))
    log(header)
    results = []
    for name in assets:
        results.append(run_asset(args, name, progs, out))
        (out / "results.json").write_text(json.dumps({"header": header, "results": results}, indent=1))
    text = table(results, header)
    (out / "table.md").write_text(text + "\n")
    print(text)
    log(f"written {out}/table.md, results.json and a montage.png per asset "
        f"(vkvcm ref | Cycles ref | vkvcm run | Cycles run | ratio)")


def cmd_table(args):
    d = json.loads((Path(args.run) / "results.json").read_text())
    print(table(d["results"], d["header"]))


def ensure_venv(args):
    """Re-executes this script with the venv's python if numpy or OpenEXR is missing."""
    try:
        import numpy  # noqa: F401
        import OpenEXR  # noqa: F401
        return
    except ImportError:
        py = venv_python(Path(args.cache))
        if not py.exists():
            raise HarnessError(f"no venv at {py.parent.parent}: run `python3 {__file__} setup` first")
        os.execv(str(py), [str(py), __file__, *sys.argv[1:]])


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "_cycles":
        cycles_child(*sys.argv[2:10])
        return
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", default=str(CACHE), help="venv and assets (default %(default)s)")
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("setup")
    s.add_argument("--python", default="python3.13")
    r = sub.add_parser("run")
    r.add_argument("--quick", action="store_true", help="64x64, 4 CPU-s x 3 seeds, glass and emitters")
    r.add_argument("--assets", help=f"comma-separated, of {','.join(cycles_assets.ALL)} (default: all) "
                   f"and by name {','.join(cycles_assets.BY_NAME)}")
    r.add_argument("--programs", default="vkvcm,cycles")
    r.add_argument("--size", type=int, default=256)
    r.add_argument("--cpu", type=float, default=20.0, help="CPU-s per timed run (default %(default)s)")
    r.add_argument("--seeds", type=int, default=3)
    r.add_argument("--ref-cpu", type=float, default=240.0, help="CPU-s of each reference, all chunks")
    r.add_argument("--ref-chunks", type=int, default=4)
    r.add_argument("--probe-spp", type=int, default=8)
    r.add_argument("--max-path-length", type=int, default=10,
                   help="vkvcm's segments; Cycles' bounces are 2 fewer (default %(default)s; 2: direct light only)")
    r.add_argument("--cycles-ggx", choices=["multi", "single"], default="multi",
                   help="Cycles' GGX: Blender's default multiple-scattering one, or single-scattering as "
                   "glTF's model and vkvcm (like for like where rough lobes lose energy)")
    r.add_argument("--equal-spp", action="store_true",
                   help="every renderer renders the samples the slowest one does in --cpu, so that the "
                   "variance per sample compares equal sample counts (a stratified or QMC sampler's "
                   "relMSE x spp falls as spp grows); relMSE x CPU-s is then that of fewer samples "
                   "for the faster renderers")
    r.add_argument("--threads", type=int, default=os.cpu_count() or 2, help="Cycles' threads")
    r.add_argument("--before-glsl", help="also render vkvcm with the shaders of this folder (e.g. `git archive "
                   "COMMIT glsl | tar -x -C DIR`, then DIR/glsl), a 'before' row scored against the same reference")
    r.add_argument("--vkvcm", help="the vkvcm binary (default target/release/vkvcm or $VKVCM_BIN)")
    r.add_argument("--out", default=str(REPO / "target" / "cycles"))
    t = sub.add_parser("table")
    t.add_argument("run", help="a run's folder (target/cycles/STAMP)")
    args = ap.parse_args()
    try:
        if args.cmd == "setup":
            cmd_setup(args)
            return
        ensure_venv(args)
        {"run": cmd_run, "table": cmd_table}[args.cmd](args)
    except (HarnessError, cycles_assets.AssetError) as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
