#!/usr/bin/env python3
"""A/B of a sampling change at equal iterations: variance per sample of vkvcm renders
with the shaders of two folders (VKVCM_GLSL_DIR), from each render's per-pixel second
moment, interleaved over seeds. Runs in the Cycles harness's venv (numpy, OpenEXR).

    python scripts/peers/ab_variance.py --a /tmp/glsl-before --b glsl \\
        --iterations 64 --seeds 3 SCENE.gltf [-- extra vkvcm render arguments]

or of two settings with the same shaders (--a-args and --b-args: each side's own render
arguments, e.g. --a-args="--light-selection power" --b-args="--light-selection tree").

Each render draws independent samples (--sampler independent: the per-pixel variance of
Sobol samples is no error estimate). Per pixel and channel, the variance of one sample is
(moment2 - mean^2) n / (n - 1); the figure is its mean weighted as the harness's relMSE,
1 / (m^2 + 0.01) with m the mean of all renders of both sides (one weight for both, so
the ratio compares the variances alone). An unbiased change keeps the image means equal:
the mean ratio and its z (difference over the standard error from the pixels' variances)
are printed too, and a second z from the spread of the seeds' image means (give it
--seeds 6 or more): the pixels' sample variances miss the rare large samples of a
heavy-tailed estimator, whose image means then scatter beyond the first z's standard
error; a few seeds of a skewed one can miss them too, so neither z proves a bias alone.
"""

import argparse
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import OpenEXR

REPO = Path(__file__).resolve().parent.parent.parent


def read(path):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {k: np.array(c.pixels, dtype=np.float64) for k, c in f.channels().items()}
        n = int(str(f.header().get("vkvcm:iterations", 0)) or 0)
    rgb = np.stack([ch["R"], ch["G"], ch["B"]], -1)
    m2 = np.stack([ch["moment2.R"], ch["moment2.G"], ch["moment2.B"]], -1)
    return rgb, m2, n


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--a", default=str(REPO / "glsl"), help="GLSL folder of side A (e.g. a `git archive` of glsl/)")
    ap.add_argument("--b", default=str(REPO / "glsl"), help="GLSL folder of side B")
    ap.add_argument("--a-args", default="", help="render arguments of side A only")
    ap.add_argument("--b-args", default="", help="render arguments of side B only")
    ap.add_argument("--algo", default="pt", help="the estimator (bpt, vcm: their camera subpaths' samples)")
    ap.add_argument("--iterations", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--vkvcm", default=str(REPO / "target" / "release" / "vkvcm"))
    ap.add_argument("--out", default="/tmp/vkvcm-ab")
    ap.add_argument("extra", nargs="*", help="more vkvcm render arguments (after --)")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    imgs = {"a": [], "b": []}
    for seed in range(1, args.seeds + 1):
        for side in ("ab" if seed % 2 else "ba"):
            exr = out / f"{side}_{seed}.exr"
            env = dict(os.environ, VKVCM_GLSL_DIR=str(Path(getattr(args, side)).resolve()))
            cmd = [args.vkvcm, "render", args.scene, "--algo", args.algo, "--sampler", "independent",
                   "--width", str(args.size), "--height", str(args.size), "--seed", str(seed),
                   "--iterations", str(args.iterations), "-o", str(exr), "--quiet", *args.extra,
                   *getattr(args, f"{side}_args").split()]
            r = subprocess.run(cmd, env=env, capture_output=True, text=True)
            if r.returncode != 0:
                sys.exit(f"{' '.join(cmd)} failed:\n{r.stderr[-2000:]}")
            imgs[side].append(read(exr))
    mean = np.mean([x[0] for s in imgs.values() for x in s], axis=0)
    w = 1.0 / (mean * mean + 1e-2)
    res = {}
    for side, runs in imgs.items():
        v = []
        for rgb, m2, n in runs:
            var = np.maximum(m2 - rgb * rgb, 0.0) * n / max(n - 1, 1)
            v.append(float(np.mean(var * w)))
        img = np.mean([x[0] for x in runs], axis=0)
        var_mean = np.mean([np.maximum(x[1] - x[0] ** 2, 0) / max(x[2] - 1, 1) for x in runs], axis=0) / len(runs)
        res[side] = (v, img, var_mean)
        print(f"{side}: variance per sample {' '.join(f'{x:.4g}' for x in v)} (mean {np.mean(v):.4g})")
    (va, ia, sa), (vb, ib, sb) = res["a"], res["b"]
    diff = ib.mean() - ia.mean()
    se = np.sqrt((sa.sum() + sb.sum())) / ia.size
    # The seeds' image means, each side's spread over its seeds (Welch).
    ma = np.array([x[0].mean() for x in imgs["a"]])
    mb = np.array([x[0].mean() for x in imgs["b"]])
    se_seeds = np.sqrt(ma.var(ddof=1) / ma.size + mb.var(ddof=1) / mb.size) if ma.size > 1 else float("nan")
    print(f"B/A variance per sample: {np.mean(vb) / np.mean(va):.3f} (per seed "
          f"{' '.join(f'{b / a:.3f}' for a, b in zip(va, vb))}); image mean B/A {ib.mean() / ia.mean():.4f}, "
          f"z {diff / se:.2f} (pixels), {diff / se_seeds:.2f} (seeds)")


if __name__ == "__main__":
    main()
