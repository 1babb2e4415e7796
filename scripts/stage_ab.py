#!/usr/bin/env python3
"""GPU time per iteration of each pass, variants interleaved: where a change moves time.

`vkvcm render --profile-json` times every pass (light subpaths, grid build, camera
subpaths) with timestamps. This script renders each scene and estimator with every
variant in turn, for ROUNDS rounds, the variants' order rotated per round, and reports
per pass and in total the variant's median over the base's, the median of the per-round
(paired) ratios and the ratio of the fastest rounds. On a shared VM single renders
spread by 15-25% or more, so read all three, and a pass's own ratio before the total:
a change that removes work in one pass can slow another (the light-vertex store
without its copy: a faster light pass, slower readers; docs/performance.md, "Tried and
not kept"). Counts of work that do not spread:
scripts/instructions_ab.py.

Each variant is NAME=GLSL_DIR[@BINARY][|ARGS] (scripts/ab_variants.py):

    python3 scripts/stage_ab.py --rounds 10 --algos bpt,vcm \\
        --variant base=/tmp/base/glsl@/tmp/base/target/release/vkvcm --variant exp=$PWD/glsl
"""

import argparse
import collections
import json
import os
import statistics
import subprocess
import sys
import tempfile

from ab_variants import HELP, parse_variant, variant_env

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def stage_times(variant, scene, algo, size, iterations, out_dir):
    """{pass name: GPU ms per iteration, "total": their sum} of one render."""
    profile = os.path.join(out_dir, "profile.json")
    cmd = [variant.binary, "render", scene, "-a", algo, "-i", str(iterations), "--width", str(size),
           "--height", str(size), "--profile-json", profile, "-o", os.path.join(out_dir, "image.exr")]
    r = subprocess.run(cmd + variant.extra, env=variant_env(variant), capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"render failed ({' '.join(cmd)}):\n{r.stderr[-2000:]}")
    with open(profile) as f:
        p = json.load(f)
    times = {s["stage"]: s["ms_per_iteration"] for s in p["stages"]}
    times["total"] = p["gpu_ms_per_iteration"]
    return times


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", default="gbs_s")
    ap.add_argument("--algos", default="bpt,vcm")
    ap.add_argument("--variant", action="append", required=True, help=HELP)
    ap.add_argument("--rounds", type=int, default=10)
    ap.add_argument("--size", type=int, default=256, help="frame width and height")
    ap.add_argument("--iterations", type=int, default=16)
    ap.add_argument("--binary", default=os.path.join(ROOT, "target/release/vkvcm"))
    args = ap.parse_args()
    variants = [parse_variant(v, args.binary) for v in args.variant]
    if len(variants) < 2:
        sys.exit("give a base and at least one variant")

    print(f"# GPU ms per iteration by pass, {args.size}x{args.size}, {args.iterations} iterations, "
          f"{args.rounds} rounds; ratios against {variants[0].name}: of the medians, "
          f"median of the paired rounds, of the fastest rounds")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes.split(","):
            for algo in args.algos.split(","):
                runs = collections.defaultdict(list)  # (variant, pass) -> ms per round
                for r in range(args.rounds):
                    for k in range(len(variants)):
                        v = variants[(r + k) % len(variants)]
                        for stage, ms in stage_times(v, scene, algo, args.size, args.iterations, tmp).items():
                            runs[(v.name, stage)].append(ms)
                base = variants[0].name
                for stage in [s for (n, s) in runs if n == base]:
                    b = runs[(base, stage)]
                    line = f"{scene} {algo} {stage}: {base} {statistics.median(b):.2f} ms"
                    for v in variants[1:]:
                        x = runs[(v.name, stage)]
                        paired = statistics.median(a / c for a, c in zip(x, b))
                        line += (f" | {v.name} {statistics.median(x):.2f} ms, x{statistics.median(x) / statistics.median(b):.3f}"
                                 f" paired x{paired:.3f} fastest x{min(x) / min(b):.3f}")
                    print(line, flush=True)


if __name__ == "__main__":
    main()
