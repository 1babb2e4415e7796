"""Image arithmetic for the side-by-side harness; runs in the harness's venv (numpy, OpenEXR).

The driver (peers.py, system python3) calls this as a separate process after the timed
renders, so that none of it runs while a renderer is being timed. Every subcommand prints
one JSON object on stdout.

    imgtool.py reference OUT.exr IN...   reference image with per-pixel variance
    imgtool.py agree A.exr B.exr         do two references agree within their noise?
    imgtool.py relmse JOBS.json          relMSE of many images against references
    imgtool.py means IN...               image means of independent renders, their mean and
                                         its standard error from their spread

Images: vkvcm EXRs (R, G, B, plus moment2.R/G/B = sum of squares / iterations and the
vkvcm:iterations attribute), Mitsuba EXRs (R, G, B), SmallVCM's float32 .pfm (its driver
patch writes rows top to bottom), and this tool's reference EXRs (R, G, B and var.R/G/B,
the variance of each pixel's mean).
"""

import json
import sys

import numpy as np
import OpenEXR

# THE error metric of the harness (the same as `vkvcm diff`'s relative MSE,
# src/image/metrics.rs): mean over all pixels and the three channels of
# (x - ref)^2 / (ref^2 + REL_MSE_EPSILON). The epsilon keeps black reference pixels from
# dominating. No trimming: fireflies are handled by reporting the median over seeds.
REL_MSE_EPSILON = 1e-2


# Relative size of float32 rounding differences that cmd_agree does not count as noise.
Z_ROUNDING = 1e-6


def rel_mse_weights(ref):
    """Each value's weight in the relMSE: 1 / (ref^2 + REL_MSE_EPSILON)."""
    return 1.0 / (ref.astype(np.float64) ** 2 + REL_MSE_EPSILON)


def rel_mse(image, ref):
    d = image.astype(np.float64) - ref.astype(np.float64)
    return float(np.mean(d * d * rel_mse_weights(ref)))


class ImageError(Exception):
    pass


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        if kind != b"PF":
            raise ImageError(f"{path}: not a colour PFM (header {kind!r})")
        w, h = (int(x) for x in f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    if data.size != w * h * 3:
        raise ImageError(f"{path}: {data.size} floats for a {w}x{h} RGB image")
    # SmallVCM's driver patch writes rows top to bottom (unlike the PFM convention).
    return data.reshape(h, w, 3).astype(np.float32)


def read_exr(path):
    """(rgb HxWx3, extra channels {name: HxW}, header) of an EXR."""
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {name: np.array(c.pixels, dtype=np.float32) for name, c in f.channels().items()}
        header = dict(f.header())
    if not all(c in ch for c in "RGB"):
        raise ImageError(f"{path}: no R, G, B channels (has {', '.join(sorted(ch))})")
    rgb = np.stack([ch.pop("R"), ch.pop("G"), ch.pop("B")], axis=-1)
    return rgb, ch, header


def read_rgb(path):
    path = str(path)
    if path.endswith(".pfm"):
        return read_pfm(path)
    return read_exr(path)[0]


def read_with_variance(path):
    """(mean, variance of the mean per pixel and channel, what the variance is from)."""
    rgb, ch, header = read_exr(path)
    if all(f"var.{c}" in ch for c in "RGB"):
        var = np.stack([ch[f"var.{c}"] for c in "RGB"], axis=-1)
        return rgb, var, header.get("peers:variance", "var channels")
    if all(f"moment2.{c}" in ch for c in "RGB"):
        n = int(str(header.get("vkvcm:iterations", "0")))
        if n < 2:
            raise ImageError(f"{path}: vkvcm EXR with {n} iterations has no variance estimate")
        m2 = np.stack([ch[f"moment2.{c}"] for c in "RGB"], axis=-1).astype(np.float64)
        var = np.maximum(m2 - rgb.astype(np.float64) ** 2, 0.0) / (n - 1)
        return rgb, var.astype(np.float32), f"vkvcm second moment over {n} iterations"
    raise ImageError(f"{path}: neither var.R/G/B nor moment2.R/G/B channels: no per-pixel variance")


def write_reference(path, mean, var, attributes):
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    header.update({k: str(v) for k, v in attributes.items()})
    channels = {c: np.ascontiguousarray(mean[..., i], dtype=np.float32) for i, c in enumerate("RGB")}
    channels.update({f"var.{c}": np.ascontiguousarray(var[..., i], dtype=np.float32) for i, c in enumerate("RGB")})
    with OpenEXR.File(header, channels) as f:
        f.write(str(path))


def noise_floor(mean, var):
    """Expected relMSE of the reference itself against the truth, from its noise."""
    return float(np.mean(var.astype(np.float64) * rel_mse_weights(mean)))


def cmd_reference(out, inputs):
    """One input with a second moment (vkvcm): its variance. Several (independent chunks of
    equal budget, any format): their mean, and the variance of the mean from their spread."""
    if len(inputs) == 1:
        mean, var, source = read_with_variance(inputs[0])
    else:
        imgs = np.stack([read_rgb(p).astype(np.float64) for p in inputs])
        mean = imgs.mean(axis=0)
        var = imgs.var(axis=0, ddof=1) / len(inputs)
        source = f"spread of {len(inputs)} independent chunks"
    if not np.all(np.isfinite(mean)):
        raise ImageError(f"non-finite pixels in the reference from {inputs[0]}")
    write_reference(out, mean, var, {"peers:variance": source})
    return {"out": str(out), "mean": float(np.mean(mean)), "variance_from": source,
            "noise_floor_relmse": noise_floor(mean, var), "width": int(mean.shape[1]), "height": int(mean.shape[0])}


def cmd_agree(a_path, b_path):
    """Mean relative difference of the image means (with its standard error), and the
    standard deviation of the per-pixel z = (a - b) / sqrt(var_a + var_b) (about 1 when
    they differ by noise alone; a little above 1 when a variance comes from few chunks)."""
    a, va, sa = read_with_variance(a_path)
    b, vb, sb = read_with_variance(b_path)
    if a.shape != b.shape:
        raise ImageError(f"{a_path} is {a.shape[1]}x{a.shape[0]}, {b_path} {b.shape[1]}x{b.shape[0]}")
    a, b, va, vb = (x.astype(np.float64) for x in (a, b, va, vb))
    # Plus a float32 rounding floor: pixels without noise (the background seen through the
    # glass sphere in gbs_b: every sample the same) differ by rounding alone, 1e-8 on
    # values of 1, with a chunk-spread variance of 1e-16, which would read as z = 5.
    s = va + vb + (Z_ROUNDING * np.maximum(np.abs(a), np.abs(b))) ** 2
    used = s > 0
    z = (a - b)[used] / np.sqrt(s[used])
    # The image means' difference in units of its standard error (the pixels' noise is
    # independent): the sharpest test of a global bias.
    mean_se = float(np.sqrt(s.sum()) / s.size)
    return {
        "mean_a": float(a.mean()), "mean_b": float(b.mean()),
        "mean_rel_diff": float((a.mean() - b.mean()) / b.mean()),
        "mean_rel_diff_se": mean_se / float(b.mean()),
        "mean_diff_sigmas": float((a.mean() - b.mean()) / mean_se),
        "z_std": float(z.std()), "z_mean": float(z.mean()),
        "z_abs_gt_4": int(np.sum(np.abs(z) > 4)), "values": int(z.size), "values_without_variance": int((~used).sum()),
        "relmse_a_vs_b": rel_mse(a, b), "relmse_expected_from_noise": float(np.mean(s * rel_mse_weights(b))),
        "variance_a": sa, "variance_b": sb,
    }


def cmd_relmse(jobs_path):
    """JOBS.json: [{"image": PATH, "reference": PATH}, ...] -> {"relmse": [...]}."""
    with open(jobs_path) as f:
        jobs = json.load(f)
    refs, out = {}, []
    for job in jobs:
        r = job["reference"]
        if r not in refs:
            refs[r] = read_rgb(r)
        img = read_rgb(job["image"])
        if img.shape != refs[r].shape:
            raise ImageError(f"{job['image']} is {img.shape[1]}x{img.shape[0]}, its reference {r} "
                             f"{refs[r].shape[1]}x{refs[r].shape[0]}")
        out.append(rel_mse(img, refs[r]))
    return {"relmse": out}


def cmd_means(inputs):
    """The image mean (over pixels and R, G, B) of each input, and their mean with its
    standard error from their spread. The inputs must be independent renders (different
    seeds, separate processes): the pixels of one bpt or vcm render are correlated through
    the light subpaths they share, so a standard error from one render's per-pixel variances
    (cmd_agree's) is too small for them; the spread of whole renders has no such bias."""
    means = [float(read_rgb(p).astype(np.float64).mean()) for p in inputs]
    n = len(means)
    se = float(np.std(means, ddof=1) / np.sqrt(n)) if n > 1 else None
    return {"n": n, "mean": float(np.mean(means)), "se": se, "means": means}


def main(argv):
    try:
        if len(argv) >= 3 and argv[0] == "reference":
            result = cmd_reference(argv[1], argv[2:])
        elif len(argv) == 3 and argv[0] == "agree":
            result = cmd_agree(argv[1], argv[2])
        elif len(argv) == 2 and argv[0] == "relmse":
            result = cmd_relmse(argv[1])
        elif len(argv) >= 2 and argv[0] == "means":
            result = cmd_means(argv[1:])
        else:
            print(__doc__, file=sys.stderr)
            return 2
    except (ImageError, OSError, ValueError, KeyError) as e:
        print(f"imgtool: error: {e}", file=sys.stderr)
        return 1
    json.dump(result, sys.stdout)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
