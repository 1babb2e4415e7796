#!/usr/bin/env python3
"""vkvcm side by side with SmallVCM and Mitsuba 3, on one machine, in one sitting.

    peers.py setup --smallvcm-src PATH     build SmallVCM, make the venv, fetch LLVM 19
    peers.py scenes                        write the peer scene (glTF + Mitsuba XML)
    peers.py reference [--quick]           reference images (once per machine/commit)
    peers.py run [--quick]                 the alternating comparison; prints the table
    peers.py per-sample                    error per sample: every program the same iterations

See scripts/peers/README.md for what is measured and how to read the table. This driver
uses only the standard library (the system python3); numpy, OpenEXR and Mitsuba run in
the venv that `setup` makes, as separate processes.
"""

import argparse
import datetime
import hashlib
import json
import os
import random
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
sys.path.insert(0, str(HERE))
import scene_desc  # noqa: E402

PATCH = HERE / "smallvcm-driver.patch"
REQUIREMENTS = HERE / "requirements.txt"

# SmallVCM's four scenes: vkvcm's built-in names and SmallVCM's `-s` index.
SMALLVCM_SCENES = {"gbs_s": 0, "glm_c": 1, "gbs_p": 2, "gbs_b": 3}
SMALLVCM_SIZE = 256
# SmallVCM's max path length is fixed (config.hxx: mMaxPathLength = 10); vkvcm is given
# the same with --max-path-length.
SMALLVCM_MAX_PATH_LENGTH = 10
# Estimators compared with SmallVCM. vkvcm's --algo names equal SmallVCM's -a acronyms
# (its config.hxx: pt = PathTracer, bpt = VertexCM kBpt, vcm = VertexCM kVcm).
# `bpt:path` / `vcm:path` are vkvcm's bpt / vcm with SmallVCM's connections (--connect
# path); plain `bpt` and `vcm` are vkvcm's defaults (the light-vertex cache).
SMALLVCM_ESTIMATORS = ("vcm", "bpt", "pt")
# The scene vkvcm and Mitsuba both describe (scene_desc.py), and the vkvcm estimators
# run against Mitsuba's `path` integrator on it.
MITSUBA_SCENE = "cornell_mg"
MITSUBA_ESTIMATORS = ("pt", "bpt", "vcm")
MITSUBA_VARIANT = "llvm_ad_rgb"
# Estimators that cannot sample every path of a scene, and so converge to less than the
# full solution there: pt and bpt under SmallVCM's delta lights (the sun of gbs_s, the
# point light of gbs_p), whose light reaches the camera through specular surfaces on paths
# that neither estimator samples (pt: light - specular - ...; bpt: light - specular -
# diffuse - specular - camera, a caustic seen in the mirror). The two programs' estimators
# share that definition, so their rows measure against a reference of the estimator itself
# (`<scene>_<estimator>.exr`): the run's error is then its noise, not a missing part of the
# image that no budget removes. Every other row measures against the scene's reference.
OWN_REFERENCES = {"gbs_s": ("pt", "bpt"), "gbs_p": ("pt", "bpt")}

# Seeds: runs use 1..N, references REF_SEED + k. SmallVCM is given 1000 x that (its thread
# k adds k, so no two processes share a stream); Mitsuba derives its passes' seeds as
# (seed << 16) + pass, so seeds stay below 2^16.
REF_SEED = 50000

QUICK = {"cpu": 3.0, "seeds": 3, "ref_cpu": 16.0, "ref_chunks": 8}
FULL = {"cpu": 20.0, "seeds": 5, "ref_cpu": 600.0, "ref_chunks": 16}
# `per-sample`'s iterations per render and seeds per row.
PER_SAMPLE_QUICK = {"iterations": 8, "seeds": 3}
PER_SAMPLE_FULL = {"iterations": 64, "seeds": 8}


class HarnessError(Exception):
    """An error for the user: printed as one message, no traceback."""


def log(msg):
    print(msg, file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------------------
# Places


def default_cache():
    return Path(os.environ.get("VKVCM_PEERS_CACHE", Path.home() / ".cache" / "vkvcm-peers"))


class Cache:
    """What `setup` makes: SmallVCM's build, the venv, LLVM 19, and setup.json about them."""

    def __init__(self, root):
        self.root = Path(root)
        self.smallvcm_dir = self.root / "smallvcm"
        self.smallvcm = self.smallvcm_dir / "smallvcm"
        self.venv = self.root / "venv"
        self.python = self.venv / "bin" / "python"
        self.llvm_dir = self.root / "llvm19"
        self.info_path = self.root / "setup.json"

    def info(self):
        if not self.info_path.exists():
            return {}
        return json.loads(self.info_path.read_text())

    def save_info(self, info):
        self.root.mkdir(parents=True, exist_ok=True)
        self.info_path.write_text(json.dumps(info, indent=1) + "\n")

    def require_smallvcm(self):
        if not self.smallvcm.exists():
            raise HarnessError(f"SmallVCM is not built in {self.smallvcm_dir}: run "
                               f"`{sys.argv[0]} setup --smallvcm-src PATH` (PATH: SmallVCM's source)")
        return self.smallvcm

    def require_venv(self):
        if not self.python.exists():
            raise HarnessError(f"the venv {self.venv} is missing: run `{sys.argv[0]} setup` first")
        return self.python

    def mitsuba_env(self):
        env = dict(os.environ)
        llvm = self.info().get("llvm")
        if llvm:
            env["DRJIT_LIBLLVM_PATH"] = llvm
        elif MITSUBA_VARIANT.startswith("llvm"):
            raise HarnessError(f"LLVM 19 for Mitsuba's {MITSUBA_VARIANT} is not set up in {self.llvm_dir}: "
                               f"run `{sys.argv[0]} setup`")
        return env


# ---------------------------------------------------------------------------------------
# Running programs, charged their whole process's CPU time


class Charged:
    def __init__(self, cpu, wall, output):
        self.cpu, self.wall, self.output = cpu, wall, output


def run_charged(cmd, log_path, env=None, cwd=None):
    """Runs cmd to completion (stdout and stderr to log_path) and returns its CPU time
    (user + sys of the process and everything it waited for, from the RUSAGE_CHILDREN
    delta: the driver runs one child at a time) and wall time."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    with open(log_path, "w") as out:
        try:
            p = subprocess.run([str(c) for c in cmd], stdout=out, stderr=subprocess.STDOUT, env=env, cwd=cwd)
        except OSError as e:
            raise HarnessError(f"cannot run {cmd[0]}: {e}")
    wall = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    text = Path(log_path).read_text(errors="replace")
    if p.returncode != 0:
        tail = "\n".join(text.splitlines()[-8:])
        raise HarnessError(f"{Path(str(cmd[0])).name} exited with status {p.returncode} "
                           f"(command: {' '.join(str(c) for c in cmd)}; log {log_path}):\n{tail}")
    return Charged(cpu, wall, text)


def capture(cmd, env=None, cwd=None):
    """stdout of a short command; HarnessError if it fails."""
    try:
        p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, env=env, cwd=cwd)
    except OSError as e:
        raise HarnessError(f"cannot run {cmd[0]}: {e}")
    if p.returncode != 0:
        raise HarnessError(f"{' '.join(str(c) for c in cmd)} failed (status {p.returncode}):\n{p.stderr.strip()}")
    return p.stdout


def imgtool(cache, *args):
    out = capture([cache.require_venv(), HERE / "imgtool.py", *args])
    return json.loads(out)


def parse(pattern, text, what):
    m = re.search(pattern, text)
    if not m:
        raise HarnessError(f"could not find {what} in the output:\n{text[-800:]}")
    return m


# ---------------------------------------------------------------------------------------
# The three programs. Each renders (scene, estimator, seed) for about `cpu` CPU-seconds of
# its whole process and returns (iterations, Charged). Start-up costs (vkvcm's shader
# compilation, Mitsuba's Python import and JIT) are measured by a warm-up run and taken
# off the budget given to the render loop, so that each process's total is about `cpu`.


class Vkvcm:
    name = "vkvcm"

    def __init__(self, binary, out):
        self.binary = Path(binary)
        self.out = Path(out)
        self.startup = {}  # (scene, estimator) -> CPU-s of a 1-iteration run
        self.cpu_per_iteration = {}  # (scene, estimator) -> CPU-s per iteration beyond the first

    def check(self):
        if not self.binary.exists():
            raise HarnessError(f"vkvcm binary {self.binary} not found: build it (cargo build --release) or pass --vkvcm PATH")

    def scene_args(self, scene):
        if scene in SMALLVCM_SCENES:
            path = REPO / "scenes" / f"{scene}.gltf"
            return path, SMALLVCM_SIZE, SMALLVCM_SIZE, SMALLVCM_MAX_PATH_LENGTH
        desc = scene_desc.SCENES[scene]
        w, h = desc["resolution"]
        return self.out / "scenes" / f"{scene}.gltf", w, h, desc["max_path_length"]

    def command(self, scene, estimator, seed, out_exr, budget):
        path, w, h, length = self.scene_args(scene)
        algo, settings = split_estimator(estimator)
        cmd = [self.binary, "render", path, "--algo", algo, "--width", w, "--height", h, "--seed", seed,
               "--max-path-length", length, "-o", out_exr]
        return cmd + settings + budget

    def warm_up(self, scene, estimator, workdir):
        # Twice: the first run may compile the kernels into Mesa's shader cache; the
        # second is the start-up every later run pays (plus its one iteration).
        for _ in range(2):
            c = run_charged(self.command(scene, estimator, 0, workdir / "warmup.exr", ["--iterations", "1"]),
                            workdir / "warmup.log")
        self.startup[(scene, estimator)] = c.cpu
        return c.cpu

    def render(self, scene, estimator, seed, cpu, out_base, render_wall=None):
        """About `cpu` CPU-seconds in all (or, with render_wall, a --time probe). vkvcm's
        --time is wall time, which a loaded machine stretches; so once a run of this cell
        has measured the CPU one iteration costs, the budget is given as an iteration
        count, which costs about the same CPU under any load. The first run of a cell aims
        with --time at the machine's core count in CPU per wall second."""
        key = (scene, estimator)
        startup = self.startup.get(key, 0.0)  # includes one iteration
        if render_wall is not None:
            budget = ["--time", f"{render_wall:.3f}"]
        elif key in self.cpu_per_iteration:
            budget = ["--iterations", str(max(1, 1 + round((cpu - startup) / self.cpu_per_iteration[key])))]
        else:
            budget = ["--time", f"{max(0.2, (cpu - startup) / float(os.cpu_count() or 1)):.3f}"]
        exr = out_base.with_suffix(".exr")
        c = run_charged(self.command(scene, estimator, seed, exr, budget), out_base.with_suffix(".log"))
        iterations = int(parse(r"(\d+) iterations in ([0-9.]+) s", c.output, "vkvcm's iteration count").group(1))
        if iterations > 1 and c.cpu > startup:
            self.cpu_per_iteration[key] = (c.cpu - startup) / (iterations - 1)
        return iterations, c, exr

    def render_iterations(self, scene, estimator, seed, iterations, out_base, env=None):
        """Exactly `iterations` iterations: (Charged, image)."""
        exr = out_base.with_suffix(".exr")
        c = run_charged(self.command(scene, estimator, seed, exr, ["--iterations", str(iterations)]),
                        out_base.with_suffix(".log"), env=env)
        return c, exr

    def describe(self):
        version = capture([self.binary, "--version"]).strip()
        devices = capture([self.binary, "devices"])
        first = devices.splitlines()[0] if devices else ""
        m = re.search(r"driver (.*?), Vulkan", first)
        digest = hashlib.sha256(self.binary.read_bytes()).hexdigest()[:12]
        return {"binary": str(self.binary), "version": version, "sha256": digest, "device": first,
                "driver": m.group(1) if m else first}


class SmallVcm:
    name = "SmallVCM"

    def __init__(self, cache, binary=None):
        self.cache = cache
        # Another build of SmallVCM than the harness's (strategy_diag.py's variants).
        self.binary = binary
        self.startup = {}  # (scene, estimator) -> CPU-s of a 1-iteration run
        self.overhead = {}  # (scene, estimator) -> CPU-s of a run outside its timed loop

    def check(self):
        self.cache.require_smallvcm()

    def command(self, scene, estimator, seed, out_hdr, budget):
        return [self.binary or self.cache.smallvcm, "-s", SMALLVCM_SCENES[scene], "-a", estimator, "-r",
                SMALLVCM_SIZE, "-seed", seed, "-o", out_hdr] + budget

    def warm_up(self, scene, estimator, workdir):
        c = run_charged(self.command(scene, estimator, 0, workdir / "warmup.hdr", ["-i", "1"]), workdir / "warmup.log")
        loop = float(parse(r"CPU seconds: *([0-9.]+)", c.output, "SmallVCM's CPU seconds").group(1))
        self.startup[(scene, estimator)] = c.cpu
        self.overhead[(scene, estimator)] = max(0.0, c.cpu - loop)
        return c.cpu

    def render(self, scene, estimator, seed, cpu, out_base):
        # SmallVCM's -t is CPU time (clock(), all threads) of its render loop; it stops
        # after the iteration that crosses it (each thread finishes its own).
        seconds = max(0.1, cpu - self.overhead.get((scene, estimator), 0.0))
        c = self._run(scene, estimator, seed, ["-t", f"{seconds:.3f}"], out_base)
        iterations = int(parse(r"Iterations total: (\d+)", c.output, "SmallVCM's iteration count").group(1))
        return iterations, c, out_base.with_suffix(".pfm")

    def render_iterations(self, scene, estimator, seed, iterations, out_base):
        """Exactly `iterations` iterations (summed over its threads): (Charged, image)."""
        c = self._run(scene, estimator, seed, ["-i", str(iterations)], out_base)
        done = int(parse(r"Iterations total: (\d+)", c.output, "SmallVCM's iteration count").group(1))
        if done != iterations:
            raise HarnessError(f"SmallVCM ran {done} iterations, not {iterations} (log {out_base.with_suffix('.log')})")
        return c, out_base.with_suffix(".pfm")

    def _run(self, scene, estimator, seed, budget, out_base):
        # Seed 1000 x seed: its thread k adds k.
        return run_charged(self.command(scene, estimator, 1000 * seed, out_base.with_suffix(".hdr"), budget),
                           out_base.with_suffix(".log"))

    def describe(self):
        info = self.cache.info().get("smallvcm", {})
        return {"binary": str(self.cache.smallvcm), "source": info.get("source", "?"),
                "patch_sha256": info.get("patch_sha256", "?"), "compiler": info.get("compiler", "?")}


class Mitsuba:
    name = "Mitsuba"

    def __init__(self, cache, out):
        self.cache = cache
        self.out = Path(out)
        self.startup = {}  # scene -> CPU-s of a 1-spp run
        self.cpu_per_spp = {}  # scene -> CPU-s per spp beyond start-up

    def check(self):
        self.cache.require_venv()
        self.cache.mitsuba_env()

    def command(self, scene, seed, spp, out_exr):
        return [self.cache.python, HERE / "mitsuba_render.py", self.out / "scenes" / f"{scene}.xml",
                "--spp", spp, "--seed", seed, "--out", out_exr, "--variant", MITSUBA_VARIANT]

    def _run(self, scene, seed, spp, out_base):
        exr = out_base.with_suffix(".exr")
        c = run_charged(self.command(scene, seed, spp, exr), out_base.with_suffix(".log"), env=self.cache.mitsuba_env())
        return c, exr

    def warm_up(self, scene, estimator, workdir):
        # 1 spp twice (the first may fill Dr.Jit's kernel cache, as vkvcm's first run
        # fills Mesa's shader cache; the second is the start-up), then 32 spp: CPU per spp.
        if scene not in self.startup:
            for _ in range(2):
                one, _ = self._run(scene, 0, 1, workdir / "warmup1")
            many, _ = self._run(scene, 0, 32, workdir / "warmup32")
            self.startup[scene] = one.cpu
            self.cpu_per_spp[scene] = max(1e-4, (many.cpu - one.cpu) / 31)
        return self.startup[scene]

    def spp_for(self, scene, cpu):
        return max(1, round((cpu - self.startup.get(scene, 0.0)) / self.cpu_per_spp.get(scene, 0.05)))

    def render(self, scene, estimator, seed, cpu, out_base, spp=None):
        spp = spp or self.spp_for(scene, cpu)
        c, exr = self._run(scene, seed, spp, out_base)
        startup = self.startup.get(scene, 0.0)
        if c.cpu > startup:
            self.cpu_per_spp[scene] = max(1e-4, (c.cpu - startup) / spp)
        return spp, c, exr

    def render_iterations(self, scene, estimator, seed, iterations, out_base):
        """Exactly `iterations` samples per pixel: (Charged, image)."""
        _, c, exr = self.render(scene, estimator, seed, None, out_base, spp=iterations)
        return c, exr

    def describe(self):
        info = self.cache.info().get("venv", {})
        return {"mitsuba": info.get("mitsuba", "?"), "drjit": info.get("drjit", "?"), "variant": MITSUBA_VARIANT,
                "llvm": self.cache.info().get("llvm", "?")}


# ---------------------------------------------------------------------------------------
# setup


def cmd_setup(args):
    cache = Cache(args.cache)
    cache.root.mkdir(parents=True, exist_ok=True)
    info = cache.info()
    if not args.skip_smallvcm:
        info["smallvcm"] = setup_smallvcm(cache, args.smallvcm_src)
        cache.save_info(info)
    if not args.skip_mitsuba:
        info["venv"] = setup_venv(cache)
        cache.save_info(info)
        info["llvm"] = setup_llvm(cache)
        cache.save_info(info)
        log("checking Mitsuba's %s variant on the peer scene (8 spp) ..." % MITSUBA_VARIANT)
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            xml = tmp / "scene.xml"
            scene_desc.write_mitsuba_xml(scene_desc.CORNELL, xml)
            m = Mitsuba(cache, tmp)
            c = run_charged([cache.python, HERE / "mitsuba_render.py", xml, "--spp", 8, "--seed", 1,
                             "--out", tmp / "t.exr", "--variant", MITSUBA_VARIANT], tmp / "t.log", env=m.cache.mitsuba_env())
            log(f"  ok: {c.wall:.1f} s wall, {c.cpu:.1f} CPU-s")
    log(f"setup done; cache {cache.root} (setup.json records what was built)")


def setup_smallvcm(cache, src):
    if not src:
        raise HarnessError("give SmallVCM's source: --smallvcm-src PATH (a checkout of "
                           "https://github.com/SmallVCM/SmallVCM, the folder holding Makefile and src/), "
                           "or --skip-smallvcm")
    src = Path(src).expanduser()
    if not (src / "src" / "smallvcm.cxx").is_file() or not (src / "Makefile").is_file():
        raise HarnessError(f"{src} is not SmallVCM's source: expected {src}/Makefile and {src}/src/smallvcm.cxx")
    for tool in ("g++", "make", "patch"):
        if not shutil.which(tool):
            raise HarnessError(f"{tool} not found on PATH (needed to build SmallVCM)")
    log(f"building SmallVCM from {src} into {cache.smallvcm_dir} (patched driver, about a minute) ...")
    if cache.smallvcm_dir.exists():
        shutil.rmtree(cache.smallvcm_dir)
    shutil.copytree(src, cache.smallvcm_dir, ignore=shutil.ignore_patterns(".git", "*.o", "smallvcm"))
    p = subprocess.run(["patch", "-p1", "--forward", "-i", str(PATCH)], cwd=cache.smallvcm_dir,
                       capture_output=True, text=True)
    if p.returncode != 0:
        raise HarnessError(f"{PATCH.name} does not apply to {src} (is it SmallVCM commit a13690f, unpatched?):\n"
                           f"{p.stdout}{p.stderr}")
    p = subprocess.run(["make"], cwd=cache.smallvcm_dir, capture_output=True, text=True)
    if p.returncode != 0 or not cache.smallvcm.exists():
        raise HarnessError(f"building SmallVCM failed:\n{p.stdout[-2000:]}{p.stderr[-2000:]}")
    compiler = capture(["g++", "--version"]).splitlines()[0]
    log(f"  built {cache.smallvcm} ({compiler})")
    return {"source": str(src.resolve()), "patch_sha256": hashlib.sha256(PATCH.read_bytes()).hexdigest()[:12],
            "compiler": compiler, "built": now()}


def setup_venv(cache):
    if not cache.python.exists():
        log(f"making the venv {cache.venv} ...")
        p = subprocess.run([sys.executable, "-m", "venv", str(cache.venv)], capture_output=True, text=True)
        if p.returncode != 0:
            raise HarnessError(f"python3 -m venv failed (Debian: apt-get install python3-venv):\n{p.stderr}")
    wanted = [l.strip() for l in REQUIREMENTS.read_text().splitlines() if l.strip() and not l.startswith("#")]
    log(f"installing {' '.join(wanted)} into it (pip; a few minutes the first time) ...")
    p = subprocess.run([str(cache.python), "-m", "pip", "install", "--quiet", "-r", str(REQUIREMENTS)])
    if p.returncode != 0:
        raise HarnessError("pip install into the venv failed (see its messages above)")
    out = capture([cache.python, "-c", "import mitsuba, drjit, numpy, OpenEXR, json; print(json.dumps({"
                   "'mitsuba': mitsuba.__version__, 'drjit': drjit.__version__, 'numpy': numpy.__version__, "
                   "'openexr': OpenEXR.__version__}))"])
    versions = json.loads(out)
    log(f"  {versions}")
    return versions


def setup_llvm(cache):
    """Mitsuba's llvm_* variants crash with Debian 12's LLVM 15; Debian's libllvm19,
    unpacked (not installed), works (docs/toolchain.md section 6)."""
    found = sorted(cache.llvm_dir.glob("root/usr/lib/*/libLLVM.so.19*"))
    if found:
        return str(found[0])
    for tool in ("apt-get", "dpkg"):
        if not shutil.which(tool):
            raise HarnessError(f"{tool} not found: fetch libLLVM.so.19 yourself, unpack it under "
                               f"{cache.llvm_dir}/root/usr/lib/<arch>/ and rerun setup")
    log(f"fetching libllvm19 (apt-get download, unpacked into {cache.llvm_dir}; nothing installed) ...")
    cache.llvm_dir.mkdir(parents=True, exist_ok=True)
    p = subprocess.run(["apt-get", "download", "libllvm19"], cwd=cache.llvm_dir, capture_output=True, text=True)
    if p.returncode != 0:
        raise HarnessError("apt-get download libllvm19 failed (run apt-get update; on Debian 12 the package is "
                           f"in bookworm or bookworm-backports):\n{p.stderr.strip()}")
    debs = sorted(cache.llvm_dir.glob("libllvm19_*.deb"))
    if not debs:
        raise HarnessError(f"apt-get download left no libllvm19_*.deb in {cache.llvm_dir}")
    capture(["dpkg", "-x", debs[-1], cache.llvm_dir / "root"])
    found = sorted(cache.llvm_dir.glob("root/usr/lib/*/libLLVM.so.19*"))
    if not found:
        raise HarnessError(f"{debs[-1].name} holds no libLLVM.so.19*")
    log(f"  {found[0]}")
    return str(found[0])


# ---------------------------------------------------------------------------------------
# scenes


def cmd_scenes(args):
    write_scenes(Path(args.out))


def write_scenes(out):
    folder = out / "scenes"
    folder.mkdir(parents=True, exist_ok=True)
    for name, desc in scene_desc.SCENES.items():
        try:
            scene_desc.write_gltf(desc, folder / f"{name}.gltf")
            scene_desc.write_mitsuba_xml(desc, folder / f"{name}.xml")
        except scene_desc.SceneError as e:
            raise HarnessError(f"scene {name}: {e}")
    log(f"wrote {', '.join(f'{n}.gltf/.xml' for n in scene_desc.SCENES)} in {folder}")


# ---------------------------------------------------------------------------------------
# reference


def cmd_reference(args):
    budget = QUICK if args.quick else FULL
    ref_cpu = args.cpu or budget["ref_cpu"]
    chunks = args.chunks or budget["ref_chunks"]
    out = Path(args.out)
    make_references(Cache(args.cache), Path(args.vkvcm), out, ref_dir(out, args.quick), scenes_of(args), ref_cpu, chunks,
                    own_only=args.own_only)


def ref_dir(out, quick):
    return out / ("references-quick" if quick else "references")


def scenes_of(args):
    names = list(SMALLVCM_SCENES) + [MITSUBA_SCENE]
    chosen = args.scenes.split(",") if args.scenes else names
    for s in chosen:
        if s not in names:
            raise HarnessError(f"unknown scene {s!r}: the harness's scenes are {', '.join(names)}")
    return chosen


def split_estimator(estimator):
    """A vkvcm estimator as `--estimators` names it, `algo[:path|:cache[:N]][:sobol|
    :independent][@N_L]` (the names of `vkvcm-bench render --algos`), as (algo, its `vkvcm
    render` settings)."""
    spec, at, light_paths = estimator.partition("@")
    settings = []
    rest, _, last = spec.rpartition(":")
    if rest and last in ("sobol", "independent"):
        settings += ["--sampler", last]
        spec = rest
    algo, _, connect = spec.partition(":")
    if connect:
        kind, _, n = connect.partition(":")
        if kind not in ("path", "cache") or (n and (kind != "cache" or not n.isdigit())):
            raise HarnessError(f"estimator {estimator!r}: the connection strategy is `path`, `cache` or `cache:N`")
        settings += ["--connect", kind] + (["--cache-connections", n] if n else [])
    if at:
        if not light_paths.isdigit():
            raise HarnessError(f"estimator {estimator!r}: `@N` needs a number of light subpaths")
        settings += ["--light-paths", light_paths]
    return algo, settings


def reference_name(scene, estimator):
    """The reference (file stem in the references folder) that a row of `estimator`
    (vkvcm's, e.g. `bpt:path`, or the peer's) on `scene` measures against."""
    algo = split_estimator(estimator)[0]
    return f"{scene}_{algo}" if algo in OWN_REFERENCES.get(scene, ()) else scene


def make_references(cache, vkvcm_bin, out, refs, scenes, ref_cpu, chunks, own_only=False):
    """For each scene, the reference the run measures against (about ref_cpu CPU-seconds),
    and an agreement check of the two programs on it (ref_cpu / 2 each; printed and stored
    in <scene>.json):

    * SmallVCM's scenes: the reference is one long vkvcm vcm render (one process, so the
      merging radius shrinks over all its iterations; vcm is the only estimator of the
      three that reaches every path, e.g. caustics seen in the mirror; per-pixel noise from
      its second moment). The check: vkvcm's bpt against SmallVCM's bpt (unbiased, so
      SmallVCM's can be run as independent chunks, whose spread gives its per-pixel noise).
    * The Mitsuba scene: the reference is Mitsuba's path tracer, in independent chunks;
      the check: vkvcm's pt, one process, against it.
    * OWN_REFERENCES: a reference of the estimator itself (vkvcm, one process, ref_cpu / 2),
      checked against SmallVCM's same estimator (chunks, ref_cpu / 4). `own_only` makes
      only these.
    """
    vk = Vkvcm(vkvcm_bin, out)
    vk.check()
    cache.require_venv()
    write_scenes(out)
    refs.mkdir(parents=True, exist_ok=True)
    work = refs / "work"
    work.mkdir(exist_ok=True)
    summary = []
    for scene in scenes:
        if not own_only:
            summary.append(make_scene_reference(vk, cache, out, refs, work, scene, ref_cpu, chunks))
        # After the scene's reference, against which each own reference's missing light is measured.
        for estimator in OWN_REFERENCES.get(scene, ()):
            t0 = time.monotonic()
            record = make_own_reference(vk, cache, refs, work, scene, estimator, ref_cpu / 2, ref_cpu / 4, chunks)
            summary.append(record)
            log(f"  {agreement_line(record)} ({time.monotonic() - t0:.0f} s)")
    print("\n".join(agreement_line(r) for r in summary))


def make_scene_reference(vk, cache, out, refs, work, scene, ref_cpu, chunks):
    """The scene's reference and its agreement check (make_references); returns the record."""
    check_cpu = ref_cpu / 2  # each side of the agreement check
    t0 = time.monotonic()
    log(f"reference {scene}: about {ref_cpu:.0f} CPU-s, then {check_cpu:.0f} CPU-s per program for the check ...")
    if scene in SMALLVCM_SCENES:
        sv = SmallVcm(cache)
        sv.check()
        # The reference: vkvcm vcm, one process.
        ref_run = timed_vkvcm_long(vk, scene, "vcm", REF_SEED, ref_cpu, work / f"{scene}_ref_vkvcm_vcm", work)
        ref = imgtool(cache, "reference", refs / f"{scene}.exr", ref_run["image"])
        # The check: SmallVCM bpt in chunks against vkvcm bpt.
        images, cpu, its = [], 0.0, 0
        sv.warm_up(scene, "bpt", work)
        for k in range(chunks):
            n, c, img = sv.render(scene, "bpt", REF_SEED + k, check_cpu / chunks,
                                  work / f"{scene}_check_smallvcm_bpt_{k}")
            images.append(img)
            cpu += c.cpu
            its += n
        imgtool(cache, "reference", work / f"{scene}_check_smallvcm_bpt.exr", *images)
        mine = timed_vkvcm_long(vk, scene, "bpt", REF_SEED + 1, check_cpu, work / f"{scene}_check_vkvcm_bpt", work)
        agree = imgtool(cache, "agree", mine["image"], work / f"{scene}_check_smallvcm_bpt.exr")
        record = {"scene": scene, "reference": {"program": "vkvcm", "estimator": "vcm", "process": "one",
                                                 "cpu_s": ref_run["cpu"], "iterations": ref_run["iterations"],
                                                 "noise_floor_relmse": ref["noise_floor_relmse"]},
                  "check": {"a": f"vkvcm bpt, one process, {mine['iterations']} iterations, {mine['cpu']:.0f} CPU-s",
                            "b": f"SmallVCM bpt, {chunks} chunks, {its} iterations, {cpu:.0f} CPU-s", **agree}}
    else:
        mi = Mitsuba(cache, out)
        mi.check()
        mi.warm_up(scene, "path", work)
        images, cpu, spp = [], 0.0, 0
        for k in range(chunks):
            n, c, img = mi.render(scene, "path", REF_SEED + k, ref_cpu / chunks, work / f"{scene}_ref_mitsuba_{k}")
            images.append(img)
            cpu += c.cpu
            spp += n
        ref = imgtool(cache, "reference", refs / f"{scene}.exr", *images)
        mine = timed_vkvcm_long(vk, scene, "pt", REF_SEED + 1, check_cpu, work / f"{scene}_check_vkvcm_pt", work)
        agree = imgtool(cache, "agree", mine["image"], refs / f"{scene}.exr")
        record = {"scene": scene, "reference": {"program": "Mitsuba", "estimator": "path", "process": f"{chunks} chunks",
                                                 "cpu_s": cpu, "iterations": spp,
                                                 "noise_floor_relmse": ref["noise_floor_relmse"]},
                  "check": {"a": f"vkvcm pt, one process, {mine['iterations']} iterations, {mine['cpu']:.0f} CPU-s",
                            "b": f"Mitsuba path ({MITSUBA_VARIANT}), {chunks} chunks, {spp} spp, {cpu:.0f} CPU-s",
                            **agree}}
    record.update({"date": now(), "commit": git_commit(), "ref_cpu_budget": ref_cpu, "chunks": chunks})
    (refs / f"{scene}.json").write_text(json.dumps(record, indent=1) + "\n")
    log(f"  {agreement_line(record)} ({time.monotonic() - t0:.0f} s)")
    return record


def make_own_reference(vk, cache, refs, work, scene, estimator, ref_cpu, check_cpu, chunks):
    """`<scene>_<estimator>.exr`: vkvcm's estimator, one process of ref_cpu CPU-s (its
    second moment gives the per-pixel noise), and the check: SmallVCM's same estimator in
    chunks of check_cpu in all, against it."""
    name = reference_name(scene, estimator)
    log(f"reference {name}: about {ref_cpu:.0f} CPU-s, then {check_cpu:.0f} CPU-s of SmallVCM for the check ...")
    ref_run = timed_vkvcm_long(vk, scene, estimator, REF_SEED + 2, ref_cpu, work / f"{name}_ref_vkvcm", work)
    ref = imgtool(cache, "reference", refs / f"{name}.exr", ref_run["image"])
    sv = SmallVcm(cache)
    sv.check()
    sv.warm_up(scene, estimator, work)
    images, cpu, its = [], 0.0, 0
    for k in range(chunks):
        n, c, img = sv.render(scene, estimator, REF_SEED + 100 + k, check_cpu / chunks,
                              work / f"{name}_check_smallvcm_{k}")
        images.append(img)
        cpu += c.cpu
        its += n
    imgtool(cache, "reference", work / f"{name}_check_smallvcm.exr", *images)
    agree = imgtool(cache, "agree", refs / f"{name}.exr", work / f"{name}_check_smallvcm.exr")
    # How far the estimator's expectation lies from the full image: its relMSE against the
    # scene's reference (when there is one; both references' noise included).
    missing = None
    if (refs / f"{scene}.exr").exists():
        jobs = work / f"{name}_vs_scene.json"
        jobs.write_text(json.dumps([{"image": str(refs / f"{name}.exr"), "reference": str(refs / f"{scene}.exr")}]))
        missing = imgtool(cache, "relmse", jobs)["relmse"][0]
    record = {"scene": name, "reference": {"program": "vkvcm", "estimator": estimator, "process": "one",
                                           "cpu_s": ref_run["cpu"], "iterations": ref_run["iterations"],
                                           "noise_floor_relmse": ref["noise_floor_relmse"],
                                           "relmse_vs_scene_reference": missing},
              "check": {"a": f"the reference (vkvcm {estimator})",
                        "b": f"SmallVCM {estimator}, {chunks} chunks, {its} iterations, {cpu:.0f} CPU-s", **agree},
              "date": now(), "commit": git_commit(), "ref_cpu_budget": ref_cpu, "chunks": chunks}
    (refs / f"{name}.json").write_text(json.dumps(record, indent=1) + "\n")
    return record


def timed_vkvcm_long(vk, scene, estimator, seed, cpu, out_base, work):
    """One vkvcm process of about `cpu` CPU-seconds (a reference, or a side of an agreement
    check), drawing independent samples: its per-pixel second moment is its noise estimate
    (the noise floor, the checks' z-tests), and the per-pixel variance of a render of Sobol
    samples, vkvcm's default for camera subpaths, is no error estimate (docs/estimators.md,
    "Samplers")."""
    settings = split_estimator(estimator)[1]
    if "--sampler" not in settings:
        spec, at, light_paths = estimator.partition("@")
        estimator = f"{spec}:independent{at}{light_paths}"
    elif settings[settings.index("--sampler") + 1] != "independent":
        raise HarnessError(f"{estimator}: a reference or check renders independent samples (its noise estimate)")
    vk.warm_up(scene, estimator, work)
    # A short run first (a tenth of the budget, 1-3 s wall), to learn the CPU an iteration costs.
    vk.render(scene, estimator, seed, 0.0, out_base.with_name(out_base.name + "_probe"),
              render_wall=min(3.0, max(1.0, cpu / 10)))
    n, c, img = vk.render(scene, estimator, seed, cpu, out_base)
    return {"iterations": n, "cpu": c.cpu, "image": img}


def agreement_line(r):
    c, ref = r["check"], r["reference"]
    sigmas = c.get("mean_diff_sigmas")
    sigmas = "" if sigmas is None else f" ({sigmas:+.1f} standard errors)"
    against_scene = ref.get("relmse_vs_scene_reference")
    against_scene = "" if against_scene is None else f", relMSE {against_scene:.2e} against the scene's reference"
    return (f"{r['scene']}: reference {ref['program']} {ref['estimator']} ({ref['iterations']} iterations, "
            f"{ref['cpu_s']:.0f} CPU-s, noise floor relMSE {ref['noise_floor_relmse']:.2e}{against_scene}); "
            f"check {c['a']} vs {c['b']}: mean relative difference {c['mean_rel_diff']:+.2e}{sigmas}, "
            f"relMSE between them {c['relmse_a_vs_b'] / c['relmse_expected_from_noise']:.3f} x what their noise "
            f"explains, per-pixel z std {c['z_std']:.3f} (mean {c['z_mean']:+.3f}, |z|>4: {c['z_abs_gt_4']} of "
            f"{c['values']})")


# ---------------------------------------------------------------------------------------
# run


def cmd_run(args):
    budget = QUICK if args.quick else FULL
    cpu = args.cpu or budget["cpu"]
    seeds = seeds_of(args, budget)
    out, cache, programs, scenes, refs, cells, work = open_sitting(args, "runs")
    vk = programs["vkvcm"]

    header = describe_sitting(cache, vk, programs, cpu, seeds, args.quick, refs)
    header["load_before"] = os.getloadavg()
    t_start = time.monotonic()

    log(f"warm-up runs (not counted): {len(cells)} cells ...")
    for scene, e, peer, pe in cells:
        vk.warm_up(scene, e, work)
        programs[peer].warm_up(scene, pe, work)

    rows = []
    total = len(cells) * seeds * 2
    for scene, prog, est, seed in alternating_runs(cells, seeds):
        base = work / f"{scene}_{est.replace(':', '-')}_{prog}_{seed}"
        iterations, c, img = programs[prog].render(scene, est, seed, cpu, base)
        rows.append({"scene": scene, "estimator": est, "program": prog, "seed": seed, "iterations": iterations,
                     "cpu_s": c.cpu, "wall_s": c.wall, "image": str(img),
                     "startup_cpu_s": startup_of(programs[prog], scene, est)})
        log(f"[{len(rows)}/{total}] {scene} {est} {prog} seed {seed}: {iterations} iterations, "
            f"{c.cpu:.2f} CPU-s, {c.wall:.2f} s")
    finish_sitting(cache, header, t_start, rows, cells, refs, scenes, work, render_table)


def seeds_of(args, budget):
    """--seeds, else the budget's; at least 3."""
    seeds = args.seeds or budget["seeds"]
    if seeds < 3:
        raise HarnessError("--seeds must be at least 3 (one run's relMSE is dominated by fireflies)")
    return seeds


def open_sitting(args, kind):
    """What a sitting (`run`, `per-sample`) needs: (out folder, cache, {program name:
    program}, scenes, references folder, cells, its new folder OUT/kind/STAMP)."""
    out, cache, programs, scenes = sitting_programs(args)
    refs = sitting_references(args, out, cache, scenes)
    work = out / kind / datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    work.mkdir(parents=True)
    return out, cache, programs, scenes, refs, cells_of(scenes, args.estimators), work


def sitting_programs(args):
    """The programs of a sitting, checked, and the peer scenes written: (out folder,
    cache, {program name: program}, scenes)."""
    out = Path(args.out)
    cache = Cache(args.cache)
    programs = {"vkvcm": Vkvcm(args.vkvcm, out), "SmallVCM": SmallVcm(cache), "Mitsuba": Mitsuba(cache, out)}
    programs["vkvcm"].check()
    cache.require_venv()
    scenes = scenes_of(args)
    if any(s in SMALLVCM_SCENES for s in scenes):
        programs["SmallVCM"].check()
    if MITSUBA_SCENE in scenes:
        programs["Mitsuba"].check()
    write_scenes(out)
    return out, cache, programs, scenes


def sitting_references(args, out, cache, scenes):
    """The references folder of a sitting: --references, else the full or (--quick) the
    quick one, whose missing references a quick sitting makes itself."""
    refs = Path(args.references) if args.references else ref_dir(out, args.quick)
    missing = [s for s in scenes if any(not (refs / f"{n}.exr").exists() for n in references_of(s))]
    if missing and args.quick and not args.references:
        log(f"no quick references for {', '.join(missing)} in {refs}: making them "
            f"({QUICK['ref_cpu']:.0f} CPU-s per program and scene)")
        make_references(cache, Path(args.vkvcm), out, refs, missing, QUICK["ref_cpu"], QUICK["ref_chunks"])
    elif missing:
        raise HarnessError(f"no reference for {', '.join(missing)} in {refs}: run `{sys.argv[0]} reference` first "
                           "(or --references DIR)")
    return refs


def cells_of(scenes, estimators):
    """The cells of a sitting, (scene, vkvcm estimator, peer, the peer's estimator), in the
    order they run within a round; `estimators`: the vkvcm estimators, comma-separated, or
    None for each peer's defaults."""
    cells = []
    for scene in scenes:
        if scene in SMALLVCM_SCENES:
            for e in (estimators.split(",") if estimators else SMALLVCM_ESTIMATORS):
                cells.append((scene, e, "SmallVCM", split_estimator(e)[0]))
        else:
            for e in (estimators.split(",") if estimators else MITSUBA_ESTIMATORS):
                cells.append((scene, e, "Mitsuba", "path"))
    return cells


def finish_sitting(cache, header, t_start, rows, cells, refs, scenes, work, render):
    """Scores a sitting's renders, writes results.json and table.md (`render`'s table) into
    `work` and prints the table."""
    header["load_after"] = os.getloadavg()
    header["elapsed_s"] = time.monotonic() - t_start
    score(cache, header, rows, refs, scenes, work)
    (work / "results.json").write_text(json.dumps({"sitting": header, "cells": cells, "rows": rows}, indent=1) + "\n")
    table = render(header, rows, cells)
    (work / "table.md").write_text(table)
    print(table)
    log(f"results: {work}/results.json, table: {work}/table.md")


# A peer's row can serve several vkvcm cells (SmallVCM's bpt against both `bpt` and
# `bpt:path`, Mitsuba's path against pt, bpt and vcm): its k-th cell renders seed
# i + PEER_SEED_STRIDE k, so that each of its runs is an independent render of its own.
PEER_SEED_STRIDE = 100


def peer_repeats(cells):
    """For each cell, how many earlier cells share its peer row: k above."""
    seen = {}
    repeats = []
    for scene, _, peer, pe in cells:
        key = (scene, pe, peer)
        repeats.append(seen.get(key, 0))
        seen[key] = repeats[-1] + 1
    return repeats


def alternating_runs(cells, seeds):
    """The renders of a sitting in order, as (scene, program, estimator, seed): round i
    runs every cell, vkvcm then its peer in odd rounds, the peer first in even ones; vkvcm
    renders seed i, the peer i + PEER_SEED_STRIDE k in its k-th cell."""
    repeats = peer_repeats(cells)
    for i in range(1, seeds + 1):
        for (scene, e, peer, pe), k in zip(cells, repeats):
            order = [("vkvcm", e, i), (peer, pe, i + PEER_SEED_STRIDE * k)]
            if i % 2 == 0:
                order.reverse()
            for prog, est, seed in order:
                yield scene, prog, est, seed


def references_of(scene):
    """The references (file stems) that a run on `scene` measures against."""
    return [scene] + [reference_name(scene, e) for e in OWN_REFERENCES.get(scene, ())]


def score(cache, header, rows, refs, scenes, work):
    """Each row's relMSE against its reference (reference_name), less the reference's noise
    floor, and the references' records into the header.

    A render x and a reference independent of it: E[(x - ref)^2] = E[(x - truth)^2] +
    var(ref), so the relMSE against the reference exceeds the one against the truth by the
    reference's noise floor (mean of var / (ref^2 + eps), imgtool.noise_floor). Left in,
    it adds the same amount to both programs' rows and pulls their ratio towards 1 (by up to
    10% for pt on gbs_s, whose runs' error is about 10x that floor)."""
    for r in rows:
        r["reference"] = str(refs / f"{reference_name(r['scene'], r['estimator'])}.exr")
    records = {n: json.loads((refs / f"{n}.json").read_text())
               for s in scenes for n in references_of(s) if (refs / f"{n}.json").exists()}
    jobs = work / "relmse_jobs.json"
    jobs.write_text(json.dumps([{"image": r["image"], "reference": r["reference"]} for r in rows]))
    for r, e in zip(rows, imgtool(cache, "relmse", jobs)["relmse"]):
        record = records.get(Path(r["reference"]).stem)
        if record is None:
            raise HarnessError(f"no {Path(r['reference']).with_suffix('.json')}: the reference's noise floor is unknown")
        r["relmse_against_reference"] = e
        r["relmse"] = e - record["reference"]["noise_floor_relmse"]
    header["relmse_less_noise_floor"] = True
    header["references"] = list(records.values())


def cmd_table(args):
    """Prints the table of a finished run again (from its results.json); with --rescore,
    first measures its images again against the references now in its references folder
    (or --references), and writes results-rescored.json and table-rescored.md beside it."""
    path = Path(args.results)
    if path.is_dir():
        path = path / "results.json"
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as e:
        raise HarnessError(f"cannot read {path}: {e}")
    header, rows, cells = data["sitting"], data["rows"], [tuple(c) for c in data["cells"]]
    render = render_table if per_sample_iterations(header) is None else render_per_sample_table
    if args.rescore:
        cache = Cache(args.cache)
        cache.require_venv()
        refs = Path(args.references or header["references_dir"])
        scenes = list(dict.fromkeys(r["scene"] for r in rows))
        missing = [n for s in scenes for n in references_of(s) if not (refs / f"{n}.exr").exists()]
        if missing:
            raise HarnessError(f"no reference {', '.join(missing)} in {refs}: run `{sys.argv[0]} reference` "
                               "(`--own-only` makes only the estimators' own references)")
        score(cache, header, rows, refs, scenes, path.parent)
        header["rescored"] = {"date": now(), "references_dir": str(refs),
                              "command": " ".join([Path(sys.argv[0]).name] + sys.argv[1:])}
        (path.parent / "results-rescored.json").write_text(
            json.dumps({"sitting": header, "cells": cells, "rows": rows}, indent=1) + "\n")
        table = render(header, rows, cells)
        (path.parent / "table-rescored.md").write_text(table)
        print(table, end="")
        return
    print(render(header, rows, cells), end="")


# ---------------------------------------------------------------------------------------
# per-sample


def cmd_per_sample(args):
    """Error per sample, apart from speed: each program renders the same number of
    iterations (SmallVCM's iterations, Mitsuba's spp: one sample per pixel each) for each
    seed, and the table gives relMSE x iterations, which a program with a 1/N error keeps
    constant. The run's relMSE x CPU-s ratio is this ratio times the ratio of iterations
    per CPU-second; a difference in the run that this does not show is speed."""
    budget = PER_SAMPLE_QUICK if args.quick else PER_SAMPLE_FULL
    iterations = args.iterations or budget["iterations"]
    seeds = seeds_of(args, budget)
    if iterations < 1:
        raise HarnessError("--iterations must be at least 1")
    out, cache, programs, scenes, refs, cells, work = open_sitting(args, "per-sample")
    vk = programs["vkvcm"]
    header = describe_sitting(cache, vk, programs, None, seeds, args.quick, refs)
    header["per_sample_iterations"] = iterations
    header["load_before"] = os.getloadavg()
    t_start = time.monotonic()
    rows = []
    total = len(cells) * seeds * 2
    for scene, prog, est, seed in alternating_runs(cells, seeds):
        base = work / f"{scene}_{est.replace(':', '-')}_{prog}_{seed}"
        c, img = programs[prog].render_iterations(scene, est, seed, iterations, base)
        rows.append({"scene": scene, "estimator": est, "program": prog, "seed": seed,
                     "iterations": iterations, "cpu_s": c.cpu, "wall_s": c.wall, "image": str(img)})
        log(f"[{len(rows)}/{total}] {scene} {est} {prog} seed {seed}: {c.cpu:.2f} CPU-s")
    finish_sitting(cache, header, t_start, rows, cells, refs, scenes, work, render_per_sample_table)


def per_sample_iterations(h):
    """The iteration count of a `per-sample` sitting's header (None for a `run`'s)."""
    return h.get("per_sample_iterations")


def render_per_sample_table(h, rows, cells):
    groups = rows_by_program(rows)
    lines = [
        f"# vkvcm side by side: error per sample{' (QUICK: smoke test, not for figures)' if h['quick'] else ''}",
        "",
        f"- date: {h['date']}; command: `{h['command']}` ({h['elapsed_s'] / 60:.1f} min)",
        f"- machine: {h['machine']}; CPU: {h['cpu_model']}, {h['cores']} cores",
        f"- vkvcm: repository commit {h['commit']}; binary {h['vkvcm']['binary']} ({h['vkvcm']['version']}, "
        f"sha256 {h['vkvcm']['sha256']}); device {h['vkvcm']['driver']}",
        f"- every render {per_sample_iterations(h)} iterations (one sample per pixel each; Mitsuba: spp), {h['seeds']} seeds "
        "per row, programs alternating",
        "- relMSE as in the run's table (less the reference's noise floor); relMSE x iterations: lower is better, "
        "constant in the iteration count for an error falling as 1/N; \"vs peer\" = the peer's median / this row's "
        "(above 1: vkvcm has less error per sample), in brackets its 90% bootstrap interval over the seeds",
        "- " + references_line(rows),
        "",
        "| scene | estimator | program | runs | relMSE x iterations: median (min-max) | mean | vs peer |",
        "|---|---|---|---|---|---|---|",
    ]
    for (scene, est, prog), g, peer_g in table_rows(cells, groups):
        err = [error_per_sample(r) for r in g]
        ratio = "" if peer_g is None else ratio_with_interval(peer_g, g, error_per_sample)
        lines.append(f"| {scene} | {est} | {prog} | {len(g)} | {median_range(err, sig)} | "
                     f"{sig(statistics.mean(err))} | {ratio} |")
    return "\n".join(lines) + "\n"


def startup_of(program, scene, est):
    if isinstance(program, Mitsuba):
        return program.startup.get(scene)
    return program.startup.get((scene, est))


def describe_sitting(cache, vk, programs, cpu, seeds, quick, refs):
    u = os.uname()
    model = "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "date": now(), "machine": f"{u.sysname} {u.nodename} {u.release} {u.version} {u.machine}",
        "cpu_model": model, "cores": os.cpu_count(), "commit": git_commit(), "vkvcm": vk.describe(),
        "smallvcm": programs["SmallVCM"].describe(), "mitsuba": programs["Mitsuba"].describe(),
        "cpu_budget_s": cpu, "seeds": seeds, "quick": quick, "references_dir": str(refs),
        "command": " ".join([Path(sys.argv[0]).name] + sys.argv[1:]),
    }


def median_range(values, fmt):
    return f"{fmt(statistics.median(values))} ({fmt(min(values))}-{fmt(max(values))})"


def sig(x):
    return f"{x:.3g}"


# Resamples of the bootstrap interval of a ratio of medians; its generator's seed is
# fixed, so a table printed again shows the same interval.
BOOTSTRAP_ROUNDS = 4000


def median_ratio_interval(peer, ours, level=0.9):
    """The percentile bootstrap interval (Efron & Tibshirani, "An Introduction to the
    Bootstrap", 1993, ch. 13) of median(peer) / median(ours), each list of values resampled
    with replacement on its own. With five heavy-tailed runs per row (fireflies) the ratio
    of two medians moves by tens of percent from one set of seeds to the next; the
    interval says how far. Returns (low, high)."""
    rng = random.Random(20261205)
    ratios = sorted(statistics.median(rng.choices(peer, k=len(peer))) /
                    statistics.median(rng.choices(ours, k=len(ours))) for _ in range(BOOTSTRAP_ROUNDS))
    cut = int(round((1 - level) / 2 * BOOTSTRAP_ROUNDS))
    return ratios[cut], ratios[BOOTSTRAP_ROUNDS - 1 - cut]


def ratio_with_interval(peer_group, our_group, value):
    """The peer's median `value` over ours, with its bootstrap interval."""
    peer = [value(r) for r in peer_group]
    ours = [value(r) for r in our_group]
    lo, hi = median_ratio_interval(peer, ours)
    return f"{statistics.median(peer) / statistics.median(ours):.2f} ({lo:.2f}-{hi:.2f})"


def rows_by_program(rows):
    """The runs of each (scene, estimator, program), each image once: in runs made before
    PEER_SEED_STRIDE, a peer row serving several cells rendered the same seed into the same
    file for each, so the file holds the last of those renders, and results.json lists it
    once per cell; the last entry is the one whose CPU time belongs to the image."""
    last = {}
    for r in rows:
        last[(r["scene"], r["estimator"], r["program"], r["image"])] = r
    groups = {}
    for r in last.values():
        groups.setdefault((r["scene"], r["estimator"], r["program"]), []).append(r)
    return groups


def table_rows(cells, groups):
    """The rows of a table in the cells' order, each once: ((scene, estimator, program),
    its runs, and for a vkvcm row the runs of its peer's row, else None)."""
    seen = set()
    for scene, e, peer, pe in cells:
        for key in ((scene, e, "vkvcm"), (scene, pe, peer)):
            if key in seen or key not in groups:
                continue
            seen.add(key)
            yield key, groups[key], groups.get((scene, pe, peer)) if key[2] == "vkvcm" else None


def speed(r):
    """Iterations per CPU-s of a run (higher is better)."""
    return r["iterations"] / r["cpu_s"]


def efficiency(r):
    """relMSE x CPU-s of a run (lower is better)."""
    return r["relmse"] * r["cpu_s"]


def error_per_sample(r):
    """relMSE x iterations of a run (lower is better)."""
    return r["relmse"] * r["iterations"]


def render_table(h, rows, cells):
    groups = rows_by_program(rows)
    vk = h["vkvcm"]
    lines = [
        f"# vkvcm side by side: {'QUICK (smoke test, not for figures)' if h['quick'] else 'full run'}",
        "",
        f"- date: {h['date']}; command: `{h['command']}` ({h['elapsed_s'] / 60:.1f} min)",
        f"- machine: {h['machine']}",
        f"- CPU: {h['cpu_model']}, {h['cores']} cores; load average before {fmt_load(h['load_before'])}, "
        f"after {fmt_load(h['load_after'])}",
        f"- vkvcm: repository commit {h['commit']}; binary {vk['binary']} ({vk['version']}, sha256 {vk['sha256']}); "
        f"device {vk['driver']}",
        f"- SmallVCM: {h['smallvcm']['binary']} from {h['smallvcm']['source']} (driver patch sha256 "
        f"{h['smallvcm']['patch_sha256']}; {h['smallvcm']['compiler']}), -O3 -fopenmp, all cores",
        f"- Mitsuba {h['mitsuba']['mitsuba']} (Dr.Jit {h['mitsuba']['drjit']}), variant {h['mitsuba']['variant']}, "
        f"integrator path",
        f"- budget: about {h['cpu_budget_s']:g} CPU-s per process (user + sys of the whole process, start-up included), "
        f"{h['seeds']} seeds per row, programs alternating; SmallVCM scenes {SMALLVCM_SIZE}x{SMALLVCM_SIZE}, "
        f"{MITSUBA_SCENE} {'x'.join(map(str, scene_desc.CORNELL['resolution']))}; max path length 10",
        "- relMSE = mean over pixels and R, G, B of (x - ref)^2 / (ref^2 + 0.01)"
        + (", less the reference's noise floor (the part its own noise adds; in the reference lines below)"
           if h.get("relmse_less_noise_floor") else "")
        + "; relMSE x CPU-s: lower is better; "
        "\"vs peer\" = the peer's median relMSE x CPU-s / this row's (above 1: vkvcm is more efficient), in "
        "brackets its 90% bootstrap interval over the seeds (how much the ratio of medians moves with the seeds); "
        "\"speed vs peer\" = this row's median iterations per CPU-s / the peer's, likewise (vs peer = speed vs peer x "
        "the peer's error per sample / this row's, which `peers.py per-sample` measures)",
        "- " + references_line(rows),
    ]
    if "rescored" in h:
        lines.append(f"- rescored {h['rescored']['date']} against {h['rescored']['references_dir']}: "
                     f"`{h['rescored']['command']}`")
    lines += [
        "",
        "References and the agreement checks (`peers.py reference`):",
        "",
    ]
    for r in h["references"]:
        lines.append(f"- {agreement_line(r)}")
    lines += [
        "",
        "| scene | estimator | program | runs | CPU-s per run (median) | start-up CPU-s | iterations per CPU-s: median (min-max) "
        "| speed vs peer | relMSE: median | relMSE x CPU-s: median (min-max) | vs peer |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (scene, est, prog), g, peer_g in table_rows(cells, groups):
        ratio = speed_ratio = ""
        if peer_g is not None:
            ratio = ratio_with_interval(peer_g, g, efficiency)
            speed_ratio = ratio_with_interval(g, peer_g, speed)
        startup = g[0]["startup_cpu_s"]
        lines.append(
            f"| {scene} | {est} | {prog} | {len(g)} | {statistics.median(r['cpu_s'] for r in g):.2f} | "
            f"{'' if startup is None else f'{startup:.2f}'} | "
            f"{median_range([speed(r) for r in g], sig)} | {speed_ratio} | "
            f"{sig(statistics.median(r['relmse'] for r in g))} | "
            f"{median_range([efficiency(r) for r in g], sig)} | {ratio} |")
    return "\n".join(lines) + "\n"


def references_line(rows):
    """Which rows measure against which reference (runs before OWN_REFERENCES: all the scene's)."""
    own = sorted({(r["scene"], Path(r["reference"]).stem) for r in rows
                  if "reference" in r and Path(r["reference"]).stem != r["scene"]})
    if not own:
        return "every row measures against its scene's reference"
    return ("rows measure against their scene's reference, except " +
            ", ".join(f"{stem.removeprefix(scene + '_')} on {scene} against `{stem}` (the estimator's own)"
                      for scene, stem in own))


def fmt_load(l):
    return " ".join(f"{x:.2f}" for x in l)


def now():
    return datetime.datetime.now().astimezone().isoformat(timespec="seconds")


def git_commit():
    try:
        c = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO,
                               capture_output=True, text=True).stdout.strip()
        return c + ("-dirty" if dirty else "") if c else "?"
    except OSError:
        return "?"


# ---------------------------------------------------------------------------------------


def main():
    p = argparse.ArgumentParser(prog="peers.py", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--cache", default=str(default_cache()),
                   help="where setup puts SmallVCM, the venv and LLVM 19 (default $VKVCM_PEERS_CACHE or ~/.cache/vkvcm-peers)")
    p.add_argument("--out", default=str(REPO / "target" / "peers"), help="scenes, references and runs (default target/peers)")
    p.add_argument("--vkvcm", default=os.environ.get("VKVCM_BIN", str(REPO / "target" / "release" / "vkvcm")),
                   help="vkvcm binary (default $VKVCM_BIN or target/release/vkvcm)")
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("setup", help="build SmallVCM, make the venv, fetch LLVM 19")
    s.add_argument("--smallvcm-src", help="SmallVCM's source (the folder with Makefile and src/)")
    s.add_argument("--skip-smallvcm", action="store_true")
    s.add_argument("--skip-mitsuba", action="store_true", help="no venv, no LLVM")
    s.set_defaults(func=cmd_setup)

    s = sub.add_parser("scenes", help="write the peer scene (glTF and Mitsuba XML) into OUT/scenes")
    s.set_defaults(func=cmd_scenes)

    for name, what in (("reference", "reference images and the agreement checks"), ("run", "the alternating comparison")):
        s = sub.add_parser(name, help=what)
        s.add_argument("--quick", action="store_true", help="small budgets: a smoke test of a few minutes, not figures")
        s.add_argument("--scenes", help=f"comma-separated (default all: {', '.join(list(SMALLVCM_SCENES) + [MITSUBA_SCENE])})")
        s.add_argument("--cpu", type=float, help="CPU-seconds per process (run) or per program and scene (reference)")
        if name == "reference":
            s.add_argument("--chunks", type=int, help="independent chunks of a peer's reference")
            s.add_argument("--own-only", action="store_true",
                           help="only the references of estimators that converge to less than the full image "
                                "(pt and bpt on gbs_s and gbs_p)")
            s.set_defaults(func=cmd_reference)
        else:
            s.add_argument("--seeds", type=int, help="runs per row, at least 3")
            s.add_argument("--estimators", help="vkvcm estimators, comma-separated, as `vkvcm-bench render --algos` names them "
                                "(e.g. vcm,bpt,bpt:path,vcm:cache:2,vcm@32768,pt,pt:independent)")
            s.add_argument("--references", help="folder of references (default OUT/references, with --quick OUT/references-quick)")
            s.set_defaults(func=cmd_run)
    s = sub.add_parser("per-sample", help="error per sample: every program renders the same iteration count")
    s.add_argument("--scenes", help=f"comma-separated (default all: {', '.join(list(SMALLVCM_SCENES) + [MITSUBA_SCENE])})")
    s.add_argument("--estimators", help="vkvcm estimators, comma-separated, as for `run`")
    s.add_argument("--quick", action="store_true",
                   help="8 iterations, 3 seeds, the quick references (made if missing): a smoke test, not figures")
    s.add_argument("--iterations", type=int, help="iterations (samples per pixel) of every render (default 64)")
    s.add_argument("--seeds", type=int, help="renders per row, at least 3 (default 8)")
    s.add_argument("--references", help="folder of references (default OUT/references, with --quick OUT/references-quick)")
    s.set_defaults(func=cmd_per_sample)
    s = sub.add_parser("table", help="print the table of a finished run (or per-sample) again")
    s.add_argument("results", help="a run's folder (OUT/runs/STAMP, OUT/per-sample/STAMP) or its results.json")
    s.add_argument("--rescore", action="store_true",
                   help="measure the run's images again against the references there are now")
    s.add_argument("--references", help="with --rescore: folder of references (default: the run's)")
    s.set_defaults(func=cmd_table)
    args = p.parse_args()
    try:
        args.func(args)
    except HarnessError as e:
        print(f"peers.py: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("peers.py: interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
