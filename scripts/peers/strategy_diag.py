"""Which bpt strategy carries the noise: vkvcm's and SmallVCM's bpt with one strategy left out.

A diagnostic beside the harness (it needs `peers.py setup` done, and runs in the harness's
venv, which has numpy and OpenEXR):

    ~/.cache/vkvcm-peers/venv/bin/python scripts/peers/strategy_diag.py --scene gbs_s \
        --iterations 64 --seeds 12

For each variant, `full` and with light tracing (`lt`: light vertices connected to the
camera), next-event estimation (`nee`) or vertex connections (`conn`) left out, both
programs render the scene's bpt at the same iteration count for each seed: vkvcm as
`--connect path --sampler independent` (SmallVCM's own connections and random numbers,
like for like) from a copy of glsl/ with the strategy's line switched off
(VKVCM_GLSL_DIR), SmallVCM from a copy of the harness's build with the same strategy
switched off. A variant leaves out part of the image in both programs alike (the image
means below say whether they agree), so its error is measured against the other renders
of the variant (both programs, the render itself left out), with the relMSE weights of
the scene's reference (`<references>/<scene>_bpt.exr`, else `<scene>.exr`). Prints, per
variant and program, relMSE x iterations per seed (sorted), its median and mean.

Not a timing: the renders may share the machine with anything.
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
sys.path.insert(0, str(HERE))
import imgtool  # noqa: E402
import peers  # noqa: E402

# Each strategy: the line of vkvcm's GLSL (file, text) and of SmallVCM's vertexcm.hxx
# (the guard of the strategy's block) that the variant switches off.
STRATEGIES = {
    "lt": (("light_subpath.comp", "connect_to_camera(st, s.p, s.ng, h.is_sphere, b, LIGHT_TRACE_ONLY != 0);"),
           "if(!bsdf.IsDelta() && (mUseVC || mLightTraceOnly))"),
    "nee": (("camera_subpath.comp", "if (st.len + 1u >= min_path_length()) L += st.thr * connect_to_lights(st, s, b, ps);"),
            "if(!bsdf.IsDelta() && mUseVC)\n                {\n                    if(cameraState.mPathLength + 1>= mMinPathLength)"),
    "conn": (("camera_subpath.comp", "L += st.thr * v.thr * connect_vertices(st, s, b, v);\n    }\n#endif"),
             "if(!bsdf.IsDelta() && mUseVC)\n                {\n                    // For VC, each light sub-path"),
}


def switched_off(text, line, what):
    if text.count(line) != 1:
        sys.exit(f"strategy_diag: {what}: expected the line {line!r} once (the source has changed)")
    return text.replace(line, "if (false) " + line if not line.startswith("if(") else
                        line.replace("if(", "if(false && ", 1), 1)


def vkvcm_glsl(tmp, strategy):
    out = tmp / f"glsl_{strategy}"
    shutil.copytree(REPO / "glsl", out)
    if strategy != "full":
        (name, line), _ = STRATEGIES[strategy]
        p = out / name
        p.write_text(switched_off(p.read_text(), line, f"glsl/{name}"))
    return out


def smallvcm_build(tmp, cache, strategy):
    src = cache.smallvcm_dir
    out = tmp / f"smallvcm_{strategy}"
    shutil.copytree(src, out, ignore=shutil.ignore_patterns("smallvcm", "*.o"))
    if strategy != "full":
        p = out / "src" / "vertexcm.hxx"
        p.write_text(switched_off(p.read_text(), STRATEGIES[strategy][1], "SmallVCM's vertexcm.hxx"))
    r = subprocess.run(["make"], cwd=out, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"strategy_diag: building SmallVCM ({strategy}) failed:\n{r.stderr[-2000:]}")
    return out / "smallvcm"


def main():
    try:
        diagnose()
    except peers.HarnessError as e:
        sys.exit(f"strategy_diag: {e}")


def diagnose():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="gbs_s", choices=sorted(peers.SMALLVCM_SCENES))
    ap.add_argument("--iterations", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=12)
    ap.add_argument("--strategies", default="full,lt,nee,conn")
    ap.add_argument("--vkvcm", default=str(REPO / "target" / "release" / "vkvcm"))
    ap.add_argument("--cache", default=str(peers.default_cache()))
    ap.add_argument("--references", default=str(REPO / "target" / "peers" / "references"))
    a = ap.parse_args()
    if a.seeds < 3:
        sys.exit("strategy_diag: --seeds must be at least 3")
    cache = peers.Cache(a.cache)
    cache.require_smallvcm()
    refs = Path(a.references)
    weights_from = next((p for p in (refs / f"{a.scene}_bpt.exr", refs / f"{a.scene}.exr") if p.exists()), None)
    if weights_from is None:
        sys.exit(f"strategy_diag: no reference of {a.scene} in {refs}: run `peers.py reference` first")
    weights = imgtool.rel_mse_weights(imgtool.read_rgb(weights_from))
    size = peers.SMALLVCM_SIZE
    print(f"# bpt on {a.scene}, {a.iterations} iterations at {size}x{size}, seeds 1-{a.seeds}; "
          f"relMSE weights from {weights_from.name}")
    with tempfile.TemporaryDirectory(prefix="vkvcm-strategy-diag-") as t:
        tmp = Path(t)
        vkvcm = peers.Vkvcm(a.vkvcm, tmp)
        vkvcm.check()
        for strategy in a.strategies.split(","):
            if strategy != "full" and strategy not in STRATEGIES:
                sys.exit(f"strategy_diag: unknown strategy {strategy!r} (full, {', '.join(STRATEGIES)})")
            env = {**os.environ, "VKVCM_GLSL_DIR": str(vkvcm_glsl(tmp, strategy))}
            smallvcm = peers.SmallVcm(cache, smallvcm_build(tmp, cache, strategy))
            images = {"vkvcm": [], "SmallVCM": []}
            for seed in range(1, a.seeds + 1):
                # vkvcm like SmallVCM: its connections (`path`) and independent samples.
                _, exr = vkvcm.render_iterations(a.scene, "bpt:path:independent", seed, a.iterations,
                                                 tmp / f"vk_{strategy}_{seed}", env=env)
                images["vkvcm"].append(imgtool.read_rgb(exr).astype(np.float64))
                _, pfm = smallvcm.render_iterations(a.scene, "bpt", seed, a.iterations, tmp / f"sv_{strategy}_{seed}")
                images["SmallVCM"].append(imgtool.read_rgb(pfm).astype(np.float64))
            every = images["vkvcm"] + images["SmallVCM"]
            total = np.sum(every, axis=0)
            means = {prog: np.mean([x.mean() for x in xs]) for prog, xs in images.items()}
            print(f"{strategy} left out" if strategy != "full" else "full",
                  f"- image means: vkvcm {means['vkvcm']:.5f}, SmallVCM {means['SmallVCM']:.5f}")
            for prog, xs in images.items():
                errs = sorted(float(np.mean((x - (total - x) / (len(every) - 1)) ** 2 * weights)) * a.iterations
                              for x in xs)
                print(f"  {prog:8s} relMSE x iterations: median {np.median(errs):.2f}, mean {np.mean(errs):.2f}; "
                      + " ".join(f"{e:.1f}" for e in errs))


if __name__ == "__main__":
    main()
