#!/usr/bin/env python3
"""Writes the test environment map tests/env/sky.hdr (Radiance RGBE, flat scanlines).

A lat-long map in vkvcm's (and Mitsuba 3's) convention: row 0 is the zenith (+Y), column u
looks along (sin 2pi u, 0, -cos 2pi u) at the horizon (u = 0: -Z, u = 1/4: +X). A sky
gradient (blue at the zenith, pale at the horizon), a dim brown ground below the horizon,
and a small bright sun (angular radius 3 degrees, elevation 35 degrees, towards +X-ish)
that carries most of the map's power, so that importance sampling matters.

    python3 scripts/make_env_map.py [OUT.hdr] [--width 128] [--height 64]
"""
import argparse
import math
import os


def radiance(d):
    x, y, z = d
    sun_elev, sun_azim = math.radians(35.0), 0.3  # azimuth as the map's u
    sun = (math.cos(sun_elev) * math.sin(2 * math.pi * sun_azim), math.sin(sun_elev),
           -math.cos(sun_elev) * math.cos(2 * math.pi * sun_azim))
    cos_sun = x * sun[0] + y * sun[1] + z * sun[2]
    sun_radius = math.radians(3.0)
    if y >= 0.0:
        t = y ** 0.5
        sky = [0.9 - 0.6 * t, 0.95 - 0.45 * t, 1.0]
    else:
        sky = [0.25, 0.2, 0.15]
    # A smooth-edged sun (cosine falloff over its radius) so that bilinear filtering of
    # the texels is close to the function itself.
    ang = math.acos(max(-1.0, min(1.0, cos_sun)))
    if ang < sun_radius:
        s = 800.0 * math.cos(0.5 * math.pi * ang / sun_radius) ** 2
        sky = [sky[0] + s, sky[1] + 0.9 * s, sky[2] + 0.7 * s]
    return sky


def rgbe(c):
    m = max(c)
    if m < 1e-32:
        return bytes([0, 0, 0, 0])
    e = math.frexp(m)[1]
    scale = 256.0 / 2.0 ** e
    return bytes([min(255, int(c[0] * scale)), min(255, int(c[1] * scale)), min(255, int(c[2] * scale)), e + 128])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("out", nargs="?", default=os.path.join(here, "..", "tests", "env", "sky.hdr"))
    ap.add_argument("--width", type=int, default=128)
    ap.add_argument("--height", type=int, default=64)
    a = ap.parse_args()
    w, h = a.width, a.height
    body = bytearray()
    for j in range(h):
        theta = math.pi * j / (h - 1)  # texel rows sit at v = j / (H - 1)
        for i in range(w):
            phi = 2 * math.pi * (i + 0.5) / w  # texel columns at u = (i + 1/2) / W
            d = (math.sin(phi) * math.sin(theta), math.cos(theta), -math.cos(phi) * math.sin(theta))
            body += rgbe(radiance(d))
    with open(a.out, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
        f.write(f"-Y {h} +X {w}\n".encode())
        f.write(bytes(body))
    print(f"wrote {a.out} ({w}x{h})")


if __name__ == "__main__":
    main()
