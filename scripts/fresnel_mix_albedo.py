#!/usr/bin/env python3
"""Directional albedo of a white smooth dielectric in glTF's metallic/roughness model, with
the specification's `fresnel_mix` (diffuse weighted by 1 - F(wo.h), Appendix B) and with
vkvcm's coupled weighting (1 - E(cos_o)) (1 - E(cos_i)) / (1 - E_avg) (glsl/bsdf.glsl,
diffuse_fresnel_weight) in its smooth limit, where the coat's albedo E is Schlick's F,
both with F0 = 0.04. In the smooth limit the specular lobe reflects F(cos_o); the diffuse
lobe's albedo is integrated by the midpoint rule over the hemisphere. The figures quoted in docs/scene-format.md.

    python3 scripts/fresnel_mix_albedo.py
"""
import math

F0 = 0.04


def schlick(c):
    return F0 + (1 - F0) * (1 - c) ** 5


def albedos(mu_o, n_theta=400, n_phi=400):
    wo = (math.sqrt(1 - mu_o * mu_o), 0.0, mu_o)
    e_avg = F0 + (1 - F0) / 21
    gltf = coupled = 0.0
    for i in range(n_theta):
        th = (i + 0.5) / n_theta * math.pi / 2
        st, ct = math.sin(th), math.cos(th)
        dw = st * (math.pi / 2 / n_theta) * (2 * math.pi / n_phi)
        for j in range(n_phi):
            ph = (j + 0.5) / n_phi * 2 * math.pi
            wi = (st * math.cos(ph), st * math.sin(ph), ct)
            h = [a + b for a, b in zip(wo, wi)]
            hl = math.sqrt(sum(x * x for x in h))
            voh = sum(a * b for a, b in zip(wo, h)) / hl
            f_cos = ct / math.pi * dw  # white Lambert times cos, times the solid angle
            gltf += (1 - schlick(voh)) * f_cos
            coupled += (1 - schlick(mu_o)) * (1 - schlick(ct)) / (1 - e_avg) * f_cos
    spec = schlick(mu_o)
    return spec + gltf, spec + coupled


if __name__ == "__main__":
    print("cos_o  glTF fresnel_mix  vkvcm coupled")
    for mu in (1.0, 0.5, 0.2, 0.1, 0.05):
        g, c = albedos(mu)
        print(f"{mu:5.2f}  {g:16.4f}  {c:13.4f}")
