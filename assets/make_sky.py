#!/usr/bin/env python3
"""Writes assets/sky.exr: a 512 x 256 latitude-longitude sky for the bundled
scene `scenes/sky-materials.json`, in linear RGB (half floats, ZIP).

A procedural clear sky: blue at the zenith brightening to a hazy horizon, a
dim brownish ground below it, and a sun 2.5 degrees in radius, 35 degrees
above the horizon, with a soft glow around it. The sun carries about two
thirds of the light on a horizontal surface, so shadows are distinct but
not black. Rows run from the +y pole (top) to the -y pole (bottom); column
u looks along (sin 2 pi u, 0, -cos 2 pi u), so the middle column is +z.

    python3 assets/make_sky.py      (needs numpy and OpenEXR)
"""

import os

import numpy as np
import OpenEXR
import Imath

W, H = 512, 256
SUN_ELEVATION = np.radians(35.0)
SUN_AZIMUTH_U = 0.62  # image column of the sun, as a fraction of the width
SUN_RADIUS = np.radians(2.5)
SUN_RADIANCE = np.array([900.0, 820.0, 700.0])


def main():
    v = (np.arange(H) + 0.5) / H
    u = (np.arange(W) + 0.5) / W
    theta = np.pi * v[:, None] * np.ones((1, W))
    phi = 2 * np.pi * u[None, :] * np.ones((H, 1))
    d = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], -1)

    elevation = np.pi / 2 - theta
    up = np.clip(np.sin(elevation), 0, 1)[..., None]
    zenith = np.array([0.18, 0.32, 0.75])
    horizon = np.array([0.75, 0.82, 0.95])
    sky = horizon + (zenith - horizon) * up ** 0.45
    ground = np.array([0.16, 0.14, 0.11])
    # A narrow blend across the horizon, so the image has no hard seam.
    t = np.clip((elevation[..., None] + 0.02) / 0.04, 0, 1)
    rgb = ground + (sky - ground) * t

    sun_phi = 2 * np.pi * SUN_AZIMUTH_U
    sun_theta = np.pi / 2 - SUN_ELEVATION
    sun = np.array([np.sin(sun_theta) * np.sin(sun_phi), np.cos(sun_theta),
                    -np.sin(sun_theta) * np.cos(sun_phi)])
    angle = np.arccos(np.clip(d @ sun, -1, 1))[..., None]
    glow = 3.0 * np.exp(-angle / 0.12) * (t > 0)
    rgb = rgb + glow * np.array([1.0, 0.85, 0.6])
    rgb = np.where(angle < SUN_RADIUS, SUN_RADIANCE, rgb)

    header = OpenEXR.Header(W, H)
    half = Imath.Channel(Imath.PixelType(Imath.PixelType.HALF))
    header["channels"] = {c: half for c in "RGB"}
    header["compression"] = Imath.Compression(Imath.Compression.ZIP_COMPRESSION)
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "sky.exr")
    f = OpenEXR.OutputFile(out, header)
    f.writePixels({c: rgb[..., k].astype(np.float16).tobytes() for k, c in enumerate("RGB")})
    f.close()
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
