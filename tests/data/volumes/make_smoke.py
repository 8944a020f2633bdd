#!/usr/bin/env python3
"""Writes the grid volumes next to this script in Mitsuba's binary `.vol` format (the format
Mitsuba 3's `gridvolume` plugin reads: src/volumes/grid.cpp documents it, src/render/volumegrid.cpp
reads it), which tests/vol_grid.rs reads with hppm's src/loaders/vol.rs:

    python3 make_smoke.py        # needs numpy only; deterministic (no random generator)

- smoke.vol: 24 x 24 x 24 cells, 1 channel, a smoke-like density: four Gaussian blobs plus a
  little smooth value noise (an integer hash on a 7^3 lattice, smoothstep-interpolated),
  clipped at 0 and divided by its maximum, so values lie in [0, 1] and the largest is exactly 1.
  The file's bounding box is [-1, 1]^3 (the blobs are laid out in it); Mitsuba 3 ignores it
  unless `use_grid_bbox` is set, which the tests check against Mitsuba's own values.
- ramp.vol: 2 x 2 x 2 cells, 1 channel, 0.5 in the cells at x = 0 and 1.5 in those at x = 1,
  bounding box [0, 1]^3. With Mitsuba's cell-centred trilinear lookup and clamping, the density
  at a point x of the unit cube (whatever y and z) is 0.5 for x <= 1/4, exactly 2x for
  1/4 <= x <= 3/4 and 1.5 for x >= 3/4: its integral along x over [0, 1] is 1 (optical depth
  of a unit crossing), and over [0, t] it is 0.5 t (t <= 1/4), t^2 + 1/16 (1/4 <= t <= 3/4),
  1.5 t - 0.5 (t >= 3/4).
- rgb.vol: 3 x 2 x 2 cells, 3 channels (interleaved per cell): channel c of cell (x, y, z) is
  0.25 * (x + 1) + 0.5 * y + 0.125 * z + 0.1 * c; bounding box [0, 1]^3.

Layout (little endian): b"VOL", version byte 3, int32 encoding 1 (float32), int32 x, y, z
resolution, int32 channel count, six float32 (xmin, ymin, zmin, xmax, ymax, zmax), then the
float32 values with x fastest, then y, then z, channels interleaved per cell:
data[((z * yres + y) * xres + x) * channels + c].
"""

import os
import struct

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def write_vol(path, data, bbox_min, bbox_max):
    """`data` is indexed [z, y, x, channel] (C order: x fastest, channels interleaved)."""
    zres, yres, xres, channels = data.shape
    header = b'VOL' + bytes([3]) + struct.pack('<iiiii', 1, xres, yres, zres, channels)
    header += struct.pack('<6f', *bbox_min, *bbox_max)
    with open(path, 'wb') as f:
        f.write(header)
        f.write(np.ascontiguousarray(data, dtype='<f4').tobytes())


def hash3(i, j, k):
    """A deterministic integer hash of lattice points to [0, 1) (uint32 arithmetic)."""
    h = (i.astype(np.uint32) * np.uint32(73856093)) ^ (j.astype(np.uint32) * np.uint32(19349663)) \
        ^ (k.astype(np.uint32) * np.uint32(83492791))
    h ^= h >> np.uint32(13)
    h *= np.uint32(0x5bd1e995)
    h ^= h >> np.uint32(15)
    return (h & np.uint32(0xffffff)).astype(np.float64) / float(1 << 24)


def value_noise(x, y, z, lattice):
    """Smooth value noise in [0, 1) on a `lattice`^3 grid over [-1, 1]^3."""
    def split(t):
        s = (t + 1.0) * 0.5 * (lattice - 1)
        i = np.clip(np.floor(s), 0, lattice - 2).astype(np.int64)
        f = s - i
        return i, f * f * (3.0 - 2.0 * f)
    (ix, fx), (iy, fy), (iz, fz) = split(x), split(y), split(z)
    out = np.zeros_like(x)
    for dx in (0, 1):
        for dy in (0, 1):
            for dz in (0, 1):
                w = (fx if dx else 1 - fx) * (fy if dy else 1 - fy) * (fz if dz else 1 - fz)
                out += w * hash3(ix + dx, iy + dy, iz + dz)
    return out


def smoke(n=24):
    c = -1.0 + 2.0 * (np.arange(n) + 0.5) / n      # cell centres in the bbox [-1, 1]
    z, y, x = np.meshgrid(c, c, c, indexing='ij')   # arrays indexed [z, y, x]
    blobs = [  # centre, sigma, amplitude
        ((0.0, -0.35, 0.0), 0.38, 0.85),
        ((0.3, 0.15, 0.1), 0.27, 0.55),
        ((-0.35, 0.3, -0.2), 0.3, 0.5),
        ((0.05, 0.55, 0.3), 0.2, 0.35),
    ]
    d = np.zeros_like(x)
    for (cx, cy, cz), s, a in blobs:
        d += a * np.exp(-((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / (2 * s * s))
    envelope = np.exp(-(x * x + y * y + z * z) / (2 * 0.6 * 0.6))
    d += 0.25 * (value_noise(x, y, z, 7) - 0.5) * envelope
    d = np.clip(d, 0.0, None).astype(np.float32)
    d /= d.max()
    return d[..., None]


def ramp():
    d = np.empty((2, 2, 2, 1), dtype=np.float32)
    d[:, :, 0, 0] = 0.5
    d[:, :, 1, 0] = 1.5
    return d


def rgb():
    d = np.empty((2, 2, 3, 3), dtype=np.float32)
    for z in range(2):
        for y in range(2):
            for x in range(3):
                for c in range(3):
                    d[z, y, x, c] = 0.25 * (x + 1) + 0.5 * y + 0.125 * z + 0.1 * c
    return d


if __name__ == '__main__':
    write_vol(os.path.join(HERE, 'smoke.vol'), smoke(), (-1, -1, -1), (1, 1, 1))
    write_vol(os.path.join(HERE, 'ramp.vol'), ramp(), (0, 0, 0), (1, 1, 1))
    write_vol(os.path.join(HERE, 'rgb.vol'), rgb(), (0, 0, 0), (1, 1, 1))
