#!/usr/bin/env python3
"""Variance per sample, A/B: relMSE at equal iterations of shader variants, seed by seed.

Every variant renders each scene with the same seeds and iteration count, with one
binary and its shaders read from a folder (VKVCM_GLSL_DIR; `embedded` for the binary's
own), and its relMSE against a reference image is taken with `vkvcm diff`. Variants that
draw the same random numbers as the base are correlated with it seed by seed, so the ratio
of their relMSEs is measured far more precisely than either relMSE. Equal iterations, not
equal time: a variant that changes the cost per sample needs a throughput A/B as well
(scripts/ab_bench.sh); one that changes only weights costs the same per sample.

    python3 scripts/variance_ab.py --scenes glm_c,gbs_p --algo bpt --iterations 16 \
        --seeds 8 --reference 'target/peers/references/{scene}.exr' \
        --variant base=embedded --variant rescaled='/tmp/exp/{scene}/glsl'

`{scene}` in a variant's folder or in the reference is replaced by the scene's name. A
variant may add `vkvcm render` arguments of its own after a `|`, e.g.
`--variant cache='embedded|--connect cache'` (such variants draw different random numbers,
so their ratios to the base vary more from seed to seed: compare the medians). The first
variant is the base of the ratios. Prints a markdown table: per scene and variant,
the median relMSE over the seeds, its ratio to the base's median, and the median (range)
of relMSE / the base's relMSE seed by seed.
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile


def rel_mse(vkvcm, image, reference):
    out = subprocess.run([vkvcm, "diff", image, reference], capture_output=True, text=True, check=True).stdout
    m = re.search(r"^rel_mse\s+(\S+)", out, re.MULTILINE)
    if not m:
        sys.exit(f"no rel_mse in `vkvcm diff` output:\n{out}")
    return float(m.group(1))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--vkvcm", default="target/release/vkvcm")
    ap.add_argument("--scenes", required=True, help="comma-separated scene names or files")
    ap.add_argument("--algo", default="bpt")
    ap.add_argument("--iterations", type=int, default=16)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--seeds", type=int, default=8, help="seeds 1..N")
    ap.add_argument("--reference", required=True, help="reference EXR; {scene} is replaced")
    ap.add_argument("--variant", action="append", required=True, metavar="NAME=GLSL_DIR[|ARGS]",
                    help="shader folder of a variant ({scene} is replaced; `embedded`: the binary's own), "
                         "and after a | render arguments of its own")
    ap.add_argument("--render-args", default="", help="extra arguments of every `vkvcm render`")
    a = ap.parse_args()
    variants = [v.split("=", 1) for v in a.variant]
    if any(len(v) != 2 for v in variants) or len(variants) < 2:
        sys.exit("give at least two --variant NAME=GLSL_DIR[|ARGS]")
    variants = [(name, *spec.partition("|")[::2]) for name, spec in variants]
    work = tempfile.mkdtemp(prefix="variance_ab.")
    print(f"# {a.algo}, {a.iterations} iterations at {a.size}x{a.size}, seeds 1-{a.seeds}, "
          f"binary {a.vkvcm}, render args '{a.render_args}'", flush=True)
    print("| scene | variant | relMSE, median | / base's median | relMSE / base's seed by seed, median (range) |")
    print("|---|---|---|---|---|")
    for scene in a.scenes.split(","):
        name = os.path.splitext(os.path.basename(scene))[0]
        reference = a.reference.format(scene=name)
        errors = {v: [] for v, _, _ in variants}
        for seed in range(1, a.seeds + 1):
            for v, glsl, args in variants:  # same seed for every variant, one after the other
                env = dict(os.environ)
                env.pop("VKVCM_GLSL_DIR", None)
                if glsl != "embedded":
                    env["VKVCM_GLSL_DIR"] = glsl.format(scene=name)
                image = os.path.join(work, f"{name}_{v}_{seed}.exr")
                cmd = [a.vkvcm, "render", scene, "-a", a.algo, "-i", str(a.iterations), "--width", str(a.size),
                       "--height", str(a.size), "--seed", str(seed), "-o", image] + a.render_args.split() + args.split()
                subprocess.run(cmd, env=env, capture_output=True, check=True)
                errors[v].append(rel_mse(a.vkvcm, image, reference))
                os.remove(image)
        base = errors[variants[0][0]]
        for v, _, _ in variants:
            ratios = [e / b for e, b in zip(errors[v], base)]
            ratio = "" if v == variants[0][0] else \
                f"{statistics.median(ratios):.3f} ({min(ratios):.3f}-{max(ratios):.3f})"
            median_ratio = "" if v == variants[0][0] else \
                f"{statistics.median(errors[v]) / statistics.median(base):.3f}"
            print(f"| {name} | {v} | {statistics.median(errors[v]):.4e} | {median_ratio} | {ratio} |", flush=True)
    os.rmdir(work)


if __name__ == "__main__":
    main()
