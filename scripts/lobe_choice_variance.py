#!/usr/bin/env python3
"""Variance of pt's estimate of a glTF dielectric's light under a constant sky of radiance 1,
seen from direction cosine mu_o, for a choice of the GGX lobe's selection probability: the
figures behind glsl/bsdf.glsl's fresnel_lobe_weights.

The BSDF is vkvcm's (glsl/bsdf.glsl): GGX with Schlick's F of F0 0.04, height-correlated
Smith G2, sampled by the normals visible from wo (pdf G1(wo) D(h) / (4 mu_o) over the
whole sphere: reflections below the horizon are lost samples), over a diffuse lobe of
colour `base` weighted (1 - E(mu_o)) (1 - E(mu_i)) / (1 - E_avg), sampled by cos / pi.
pt's vertex draws two samples from that mixture (the next-event sample of the sky and the
BSDF sample, each weighted 1/2), so its relative variance is V1 / 2 / I^2, V1 that of one
sample. Per row: the GGX share and relative variance with the lobe weights of
- `E`:      E(mu_o) against (1 - E(mu_o)) base (the directional albedos),
- `F`:      Schlick's F(mu_o) against (1 - F(mu_o)) base,
- `sqrtEF`: sqrt(E F) against (1 - E) base (pt's choice),
- `best`:   the share that minimises it (scanned in steps of 0.01),
- `cosNEE`: bpt's and vcm's estimate, the sky sample by cos / pi about the normal and the
            BSDF sample with the F weights, combined by the balance heuristic.
Integrals by the midpoint rule on an N x 2N grid of the upper hemisphere; E by the same
rule (its average E_avg over 40 cosines). Roughness at least 0.3: the grid does not
resolve sharper lobes.

    /root/.cache/vkvcm-cycles/venv/bin/python scripts/lobe_choice_variance.py   # numpy
"""
import argparse

import numpy as np

F0 = 0.04


def smith_lambda(c, a2):
    c = np.clip(c, 1e-9, 1.0)
    return 0.5 * (-1.0 + np.sqrt(1.0 + a2 * (1.0 - c * c) / (c * c)))


def ggx_d(nh, a2):
    d = nh * nh * (a2 - 1.0) + 1.0
    return a2 / (np.pi * d * d)


def schlick(c):
    return F0 + (1.0 - F0) * (1.0 - c) ** 5


class Hemisphere:
    def __init__(self, n):
        th = (np.arange(n) + 0.5) / n * np.pi / 2
        ph = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
        t, p = np.meshgrid(th, ph, indexing="ij")
        self.dw = np.sin(t) * (np.pi / 2 / n) * (np.pi / n)
        self.wi = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1)

    def ggx(self, mu_o, a):
        """GGX f cos(wi) and its visible-normal pdf at every cell, for wo at cosine mu_o."""
        a2 = a * a
        wo = np.array([np.sqrt(1.0 - mu_o * mu_o), 0.0, mu_o])
        h = self.wi + wo
        h /= np.linalg.norm(h, axis=-1, keepdims=True)
        mu_i = self.wi[..., 2]
        d = ggx_d(h[..., 2], a2)
        g2 = 1.0 / (1.0 + smith_lambda(mu_o, a2) + smith_lambda(mu_i, a2))
        g1 = 1.0 / (1.0 + smith_lambda(mu_o, a2))
        f_cos = schlick(np.sum(h * wo, -1)) * d * g2 / (4.0 * mu_o)
        return f_cos, g1 * d / (4.0 * mu_o)

    def integral(self, x):
        return float(np.sum(x * self.dw))


def table(hemi, roughness, base, cosines):
    a = roughness * roughness
    grid = np.linspace(0.01, 1.0, 40)
    albedo = [hemi.integral(hemi.ggx(m, a)[0]) for m in grid]
    e_avg = 2.0 * np.trapezoid(np.array(albedo) * grid, grid)
    mu_i = hemi.wi[..., 2]
    cos_pdf = mu_i / np.pi
    rows = []
    for mu_o in cosines:
        ggx_f, ggx_pdf = hemi.ggx(mu_o, a)
        e_o = float(np.interp(mu_o, grid, albedo))
        diffuse_f = base / np.pi * (1.0 - e_o) * (1.0 - np.interp(mu_i, grid, albedo)) / (1.0 - e_avg) * mu_i
        f = ggx_f + diffuse_f
        total = hemi.integral(f)

        def rel_var(share):  # two samples of the mixture with this GGX share
            p = (1.0 - share) * cos_pdf + share * ggx_pdf
            return (hemi.integral(f * f / p) - total * total) / 2.0 / total**2

        def rel_var_cosine_nee(share):
            p = (1.0 - share) * cos_pdf + share * ggx_pdf
            w = f / (p + cos_pdf)
            v = sum(hemi.integral(w * w * q) - hemi.integral(w * q) ** 2 for q in (p, cos_pdf))
            return v / total**2

        f_o = schlick(mu_o)
        shares = {
            "E": e_o / (e_o + (1.0 - e_o) * base),
            "F": f_o / (f_o + (1.0 - f_o) * base),
            "sqrtEF": np.sqrt(e_o * f_o) / (np.sqrt(e_o * f_o) + (1.0 - e_o) * base),
        }
        best = min((rel_var(s), s) for s in np.arange(0.0, 1.0, 0.01))
        rows.append((roughness, mu_o, {k: (s, rel_var(s)) for k, s in shares.items()}, best,
                     rel_var_cosine_nee(shares["F"])))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--roughness", default="0.3,0.4,0.6", help="glTF roughnesses (alpha = r^2), at least 0.3")
    ap.add_argument("--cosines", default="0.05,0.15,0.3,0.6,0.95")
    ap.add_argument("--base", type=float, default=0.6, help="the base colour (the harness's floor: 0.6)")
    ap.add_argument("--n", type=int, default=600, help="grid cells per quarter turn")
    args = ap.parse_args()
    hemi = Hemisphere(args.n)
    cosines = [float(c) for c in args.cosines.split(",")]
    print("| roughness | cos_o | E: share, rel. var | F | sqrtEF | best | cosNEE (bpt, vcm) |")
    print("|---|---|---|---|---|---|---|")
    for r in (float(x) for x in args.roughness.split(",")):
        for rough, mu_o, by, best, cos_nee in table(hemi, r, args.base, cosines):
            cells = " | ".join(f"{s:.2f}, {v:.4f}" for s, v in by.values())
            print(f"| {rough} | {mu_o} | {cells} | {best[1]:.2f}, {best[0]:.4f} | {cos_nee:.4f} |")


if __name__ == "__main__":
    main()
