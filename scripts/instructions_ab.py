#!/usr/bin/env python3
"""Instructions per sample of kernel variants, counted by valgrind: a noise-free A/B.

Timing A/Bs on a shared 2-core VM spread by 15-25% per run (docs/performance.md), so a
change worth a few percent needs dozens of rounds to see. The number of instructions
the CPU executes for a render does not spread: valgrind (callgrind) counts every
instruction of the process, lavapipe's JIT-compiled kernels included, the same to 0.01%
from run to run. This script counts them for `vkvcm render` at 1 and at 1 + N iterations
and reports the difference per sample (one sample = one pixel's path per iteration), so
start-up, kernel compilation and the first iteration's set-up cancel.

Instructions are not time: a change that trades instructions for memory traffic or
cache misses can count fewer and run slower. Use it to see small changes in work (fewer
texel fetches, less arithmetic), then time what it finds with scripts/ab_bench.sh.

Each variant is NAME=GLSL_DIR[@BINARY][|ARGS] (scripts/ab_variants.py; BINARY defaults to
--binary):

    python3 scripts/instructions_ab.py --scenes gbs_s,glm_c --algos pt,bpt,vcm \\
        --variant base=/tmp/base_glsl --variant exp=$PWD/glsl
    python3 scripts/instructions_ab.py --algos bpt \\
        --variant base=/tmp/base/glsl@/tmp/base/target/release/vkvcm --variant exp=$PWD/glsl

Needs valgrind (apt-get install valgrind); lavapipe as the Vulkan driver (the kernels
must run on the CPU for valgrind to count them).
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile

from ab_variants import HELP, parse_variant, variant_env

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def count_instructions(variant, scene, algo, size, iterations, out_dir):
    """Instructions valgrind counts for one `vkvcm render` of `iterations` iterations."""
    out = os.path.join(out_dir, "callgrind.out")
    cmd = [
        "valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
        variant.binary, "render", scene, "-a", algo, "-i", str(iterations),
        "--width", str(size), "--height", str(size),
        "-o", os.path.join(out_dir, "image.exr"),
    ] + variant.extra
    r = subprocess.run(cmd, env=variant_env(variant), capture_output=True, text=True)
    m = re.search(r"Collected : (\d+)", r.stderr)
    if r.returncode != 0 or not m:
        sys.exit(f"valgrind run failed ({' '.join(cmd)}):\n{r.stderr[-2000:]}")
    return int(m.group(1))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", default="gbs_s")
    ap.add_argument("--algos", default="pt")
    ap.add_argument("--variant", action="append", required=True, help=HELP)
    ap.add_argument("--size", type=int, default=64, help="frame width and height")
    ap.add_argument("--iterations", type=int, default=4,
                    help="iterations counted (beyond the first)")
    ap.add_argument("--binary", default=os.path.join(ROOT, "target/release/vkvcm"))
    args = ap.parse_args()

    variants = [parse_variant(v, args.binary) for v in args.variant]

    print(f"# instructions per sample, {args.size}x{args.size}, {args.iterations} iterations "
          f"counted; ratio against {variants[0].name}")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes.split(","):
            for algo in args.algos.split(","):
                base = None
                for v in variants:
                    # A run under valgrind (which shows lavapipe another CPU than the
                    # machine's, so its JIT cache differs) first fills the caches, so
                    # both counted runs load the same compiled kernels.
                    subprocess.run(
                        ["valgrind", "--tool=none", v.binary, "render", scene, "-a", algo, "-i", "1", "--width",
                         str(args.size), "--height", str(args.size), "-o",
                         os.path.join(tmp, "warm.exr")] + v.extra,
                        env=variant_env(v), check=True, capture_output=True)
                    one = count_instructions(v, scene, algo, args.size, 1, tmp)
                    more = count_instructions(v, scene, algo, args.size, 1 + args.iterations, tmp)
                    per_sample = (more - one) / (args.iterations * args.size * args.size)
                    if base is None:
                        base = per_sample
                    print(f"{scene} {algo} {v.name}: {per_sample:.0f} instructions/sample, "
                          f"ratio {per_sample / base:.4f}", flush=True)


if __name__ == "__main__":
    main()
