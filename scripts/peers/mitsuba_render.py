"""Render a Mitsuba 3 XML scene for the side-by-side harness; runs in the harness's venv.

    mitsuba_render.py SCENE.xml --spp N --seed S --out OUT.exr [--variant llvm_ad_rgb]

Renders N samples per pixel in passes of at most --pass-spp (so that the JIT's wavefront,
width x height x pass spp lanes, stays small), each pass with its own seed derived from S,
and writes their average as a float32 RGB EXR. Prints `spp: N` and the render seconds.
The harness charges this whole process's CPU time (Python start-up, scene loading and the
JIT's compilation included), as it charges vkvcm and SmallVCM theirs.

The llvm_* variants need LLVM 19 (docs/toolchain.md section 6): the harness passes
DRJIT_LIBLLVM_PATH, set by `peers.py setup`.
"""

import argparse
import sys
import time


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene")
    p.add_argument("--spp", type=int, required=True)
    p.add_argument("--seed", type=int, required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--variant", default="llvm_ad_rgb")
    p.add_argument("--pass-spp", type=int, default=64)
    a = p.parse_args()
    if a.spp < 1 or a.pass_spp < 1:
        p.error("--spp and --pass-spp must be at least 1")
    if not 0 <= a.seed < 1 << 16:
        p.error("--seed must be in [0, 65535] (the passes' seeds are (seed << 16) + pass, 32 bits)")

    import mitsuba as mi
    import numpy as np

    try:
        mi.set_variant(a.variant)
    except Exception as e:  # an unknown variant, or LLVM missing for llvm_*
        print(f"mitsuba_render: error: variant {a.variant}: {e}", file=sys.stderr)
        return 1
    scene = mi.load_file(a.scene)
    t0 = time.perf_counter()
    total, done, k = None, 0, 0
    while done < a.spp:
        n = min(a.pass_spp, a.spp - done)
        # Seeds of different passes and different --seed values never coincide
        # (up to 2^16 passes per render).
        img = mi.render(scene, spp=n, seed=(a.seed << 16) + k)
        arr = np.array(img, dtype=np.float64)[..., :3] * n
        total = arr if total is None else total + arr
        done += n
        k += 1
    seconds = time.perf_counter() - t0
    mean = (total / a.spp).astype(np.float32)
    mi.Bitmap(mean, pixel_format=mi.Bitmap.PixelFormat.RGB).write(a.out)
    print(f"spp: {a.spp}")
    print(f"passes: {k}")
    print(f"render seconds: {seconds:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
