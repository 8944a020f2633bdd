"""Writes the textures of the normalmap and bumpmap scenes beside this file and in
../bumpmap (8-bit PNGs, read raw):

    python3 make_textures.py

tiles.png   normal map: 4 x 4 tiles of 8 x 8 texels, each a constant normal tilted 10 to 35
            degrees in its own direction (so that an 8 x 8 pixel block's mean changes with it)
waves.png   normal map of the height field sin(2 pi 2 u) sin(2 pi v) / 6
saw.png     height map: a sawtooth in u (two slow rises, each ending in a one-texel drop),
            constant along v: most of it slopes the same way
bumps.png   height map: a few Gaussian blobs
"""
import math
import os
import random

import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
BUMP = os.path.join(HERE, "..", "bumpmap")
N = 32


def save_normals(normals, path):
    normals = normals / np.linalg.norm(normals, axis=2, keepdims=True)
    Image.fromarray(np.round((normals + 1) / 2 * 255).astype(np.uint8), "RGB").save(path)


def save_heights(heights, path):
    Image.fromarray(np.round(np.clip(heights, 0, 1) * 255).astype(np.uint8), "L").save(path)


def main():
    rng = random.Random(5)
    tiles = np.zeros((N, N, 3))
    for ty in range(4):
        for tx in range(4):
            tilt = math.radians(rng.uniform(10, 35))
            phi = rng.uniform(0, 2 * math.pi)
            n = (math.sin(tilt) * math.cos(phi), math.sin(tilt) * math.sin(phi), math.cos(tilt))
            tiles[ty * 8:(ty + 1) * 8, tx * 8:(tx + 1) * 8] = n
    save_normals(tiles, os.path.join(HERE, "tiles.png"))

    u = (np.arange(N) + 0.5) / N
    uu, vv = np.meshgrid(u, u)
    # h = sin(2 pi 2 u) sin(2 pi v) / 6; n = (-dh/du, -dh/dv, 1) with u, v in texture units.
    dh_du = 2 * math.pi * 2 * np.cos(2 * math.pi * 2 * uu) * np.sin(2 * math.pi * vv) / 6
    dh_dv = 2 * math.pi * np.sin(2 * math.pi * 2 * uu) * np.cos(2 * math.pi * vv) / 6
    save_normals(np.stack([-dh_du, -dh_dv, np.ones_like(uu)], axis=2) * [0.5, 0.5, 1], os.path.join(HERE, "waves.png"))

    save_heights(np.tile((np.arange(N) % 16) / 17, (N, 1)), os.path.join(BUMP, "saw.png"))
    heights = np.zeros((N, N))
    for _ in range(6):
        cx, cy, s = rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0.06, 0.15)
        for ox in (-1, 0, 1):
            for oy in (-1, 0, 1):
                heights += np.exp(-((uu - cx - ox) ** 2 + (vv - cy - oy) ** 2) / (2 * s * s))
    save_heights(heights / heights.max(), os.path.join(BUMP, "bumps.png"))


if __name__ == "__main__":
    main()
