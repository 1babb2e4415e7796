#!/usr/bin/env python3
"""Embree's BVH build time on the meshes `vkvcm-bench bvh-build --export-triangles DIR`
wrote, for a side-by-side comparison with vkvcm's build (docs/bvh.md, "Build benchmark").

Builds each DIR/*.f32 mesh (9 little-endian float32 per triangle) `--rounds` times with
Embree through the embreex bindings (`pip install embreex`): one triangle geometry,
Embree's default scene build quality (medium), committed by the first ray query, which
is timed with it (one ray: negligible); the copy of the vertices into Embree's buffers
before it is reported apart. Prints the median wall-clock build and seconds per 1,000,000
triangles. Embree uses all cores of the process's CPU affinity (TBB): restrict
it with taskset to compare thread counts, e.g.

    vkvcm-bench bvh-build --threads 1,2 --export-triangles /tmp/meshes
    taskset -c 0 python3 scripts/embree_build.py /tmp/meshes       # 1 thread
    taskset -c 0,1 python3 scripts/embree_build.py /tmp/meshes     # 2 threads
"""
import argparse
import os
import pathlib
import statistics
import sys
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir", type=pathlib.Path, help="directory of .f32 meshes")
    ap.add_argument("--rounds", type=int, default=5)
    a = ap.parse_args()
    try:
        import numpy as np
        from embreex import rtcore_scene as rtcs
        from embreex.mesh_construction import TriangleMesh
    except ImportError as e:
        sys.exit(f"error: {e} (pip install embreex)")
    meshes = sorted(a.dir.glob("*.f32"))
    if not meshes:
        sys.exit(f"error: no .f32 mesh in {a.dir}")
    print(f"Embree build (embreex) on {len(os.sched_getaffinity(0))} CPUs of the affinity mask")
    origin = np.zeros((1, 3), dtype=np.float32)
    direction = np.array([[0.0, 0.0, 1.0]], dtype=np.float32)
    for path in meshes:
        tris = np.fromfile(path, dtype="<f4").reshape(-1, 3, 3)
        seconds, setup = [], []
        for _ in range(a.rounds):
            start = time.perf_counter()
            scene = rtcs.EmbreeScene()
            TriangleMesh(scene, tris)  # copies the vertices into Embree's buffers
            committed = time.perf_counter()
            scene.run(origin, direction)  # commits (builds) the scene
            seconds.append(time.perf_counter() - committed)
            setup.append(committed - start)
            del scene
        median = statistics.median(seconds)
        print(
            f"{path.stem}: {len(tris)} triangles: build median {median:.3f} s (min {min(seconds):.3f} s) "
            f"over {a.rounds} rounds = {median * 1e6 / len(tris):.3f} s per 1M triangles; "
            f"mesh setup before it (not counted) {statistics.median(setup):.3f} s"
        )


if __name__ == "__main__":
    main()
