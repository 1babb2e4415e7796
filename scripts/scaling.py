#!/usr/bin/env python3
"""How a render's cost scales: samples per CPU-second of pt and vcm against the frame size
and against the number of triangles, to predict a render's time (docs/performance.md,
"Scaling with frame size and triangles").

    python3 scripts/scaling.py [--rounds 3] [--vkvcm-bench target/release/vkvcm-bench] [--quick]

Every row is one `vkvcm-bench render` (one warm-up iteration, then the timed ones;
samples per CPU-second of the whole process during the timed render, the median round
and the range over --rounds). Start-up and kernel builds are not in these figures
(docs/performance.md, "Start-up time").

- Frame size: gbs_s (a sun; SmallVCM's scene 0) and glm_c (an area light) at
  128 to 1024 pixels square, the same number of samples at every size: 2^22 for pt, 2^20
  for vcm (vcm with the default N_L = W x H light subpaths per iteration).
- Triangles: the room of `scripts/make_grid_scene.py --room` (a closed room lit by an
  area light) whose floor has 2 to 10M triangles, at 256x256: the light transport is
  the same in every row, only the triangles a ray may meet change.

Run it on an idle machine; it prints markdown tables and takes about 10 minutes on two
cores (--quick: smaller budgets and fewer sizes, about 1 minute, to check that it runs).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def bench(vkvcm_bench, scene, algo, size, iterations, rounds, work):
    out = os.path.join(work, "bench.json")
    cmd = [vkvcm_bench, "render", "--scenes", scene, "--algos", algo, "--size", str(size),
           "--iterations", str(iterations), "--rounds", str(rounds), "--json", out]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{r.stderr}")
    (row,) = json.load(open(out))
    return row


def row_text(label, algo, size, iterations, row):
    lo, hi = row["samples_per_cpu_second_range"]
    rate = row["samples_per_cpu_second"]
    gpu_ms = sum(k["total_ms"] for k in row["kernels"]) / iterations
    samples = size * size * iterations
    return (f"| {label} | {algo} | {size}x{size} | {iterations} | {samples / 1e6:.2f} M | "
            f"{rate / 1e3:.0f} k ({lo / 1e3:.0f}-{hi / 1e3:.0f} k) | {1e6 / rate:.2f} | {gpu_ms:.1f} |")


HEADER = ("| {first} | estimator | frame | iterations | samples | samples / CPU-s (range) | CPU us / sample "
          "| GPU ms / iteration |\n|---|---|---|---|---|---|---|---|")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--vkvcm-bench", default="target/release/vkvcm-bench")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    sizes = [128, 256] if a.quick else [128, 256, 512, 1024]
    budget = {"pt": 2**18, "vcm": 2**16} if a.quick else {"pt": 2**22, "vcm": 2**20}
    floors = [2, 10_000] if a.quick else [2, 10_000, 100_000, 1_000_000, 10_000_000]
    rounds = 1 if a.quick else a.rounds
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=HERE).stdout.strip()
    print(f"# {a.vkvcm_bench} at commit {commit}, {rounds} round(s); load average {os.getloadavg()[0]:.2f} at the start")
    with tempfile.TemporaryDirectory() as work:
        print("\nFrame size\n")
        print(HEADER.format(first="scene"))
        for scene in ["gbs_s", "glm_c"]:
            for algo in ["pt", "vcm"]:
                for size in sizes:
                    iterations = max(1, budget[algo] // (size * size))
                    row = bench(a.vkvcm_bench, scene, algo, size, iterations, rounds, work)
                    print(row_text(scene, algo, size, iterations, row), flush=True)
        print("\nTriangles (the room of make_grid_scene.py --room; 12 triangles besides the floor)\n")
        print(HEADER.format(first="floor triangles"))
        for floor in floors:
            path = os.path.join(work, "room.glb")
            made = subprocess.run([sys.executable, os.path.join(HERE, "make_grid_scene.py"), str(floor), path, "--room"],
                                  capture_output=True, text=True, check=True).stdout
            triangles = int(made.split("has ")[1].split()[0])
            for algo in ["pt", "vcm"]:
                iterations = max(1, budget[algo] // (256 * 256))
                row = bench(a.vkvcm_bench, path, algo, 256, iterations, rounds, work)
                print(row_text(f"{triangles:,}", algo, 256, iterations, row), flush=True)
    print(f"\n# load average {os.getloadavg()[0]:.2f} at the end")


if __name__ == "__main__":
    main()
