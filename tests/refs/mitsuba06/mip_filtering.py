#!/usr/bin/env python3
# Usage: DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 mip_filtering.py TEXTURE N [N ...]
# What 0.6's trilinear MIP-mapping changes against bilinear lookups averaged over each pixel
# (what a path tracer's samples converge to), for a texture mapped fronto-parallel onto an
# image N pixels wide (minification = texture width / N).
import numpy as np, mitsuba as mi, sys
mi.set_variant('scalar_rgb')
tex = np.array(mi.Bitmap(sys.argv[1]).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False))
H, W, _ = tex.shape
def bilinear(t, u, v):
    h, w, _ = t.shape
    x = u * w - 0.5; y = v * h - 0.5
    x0 = np.floor(x).astype(int); y0 = np.floor(y).astype(int)
    fx = (x - x0)[..., None]; fy = (y - y0)[..., None]
    g = lambda yy, xx: t[np.clip(yy, 0, h - 1), np.clip(xx, 0, w - 1)]
    return (g(y0, x0) * (1 - fx) * (1 - fy) + g(y0, x0 + 1) * fx * (1 - fy)
            + g(y0 + 1, x0) * (1 - fx) * fy + g(y0 + 1, x0 + 1) * fx * fy)
def pyramid(t):
    levels = [t]
    while min(levels[-1].shape[:2]) > 1:
        a = levels[-1]; h, w = a.shape[0] // 2 * 2, a.shape[1] // 2 * 2
        a = a[:h, :w]; levels.append(0.25 * (a[0::2, 0::2] + a[1::2, 0::2] + a[0::2, 1::2] + a[1::2, 1::2]))
    return levels
levels = pyramid(tex)
def relmse(a, b): return float(np.mean((a - b) ** 2 / (b ** 2 + 0.01)))
def block(a, b=8):
    h, w, c = a.shape; return a[:h//b*b, :w//b*b].reshape(h // b, b, w // b, b, c).mean(axis=(1, 3))
for N in [int(x) for x in sys.argv[2:]]:
    # bilinear averaged over the pixel: 16x16 stratified samples
    s = (np.arange(16) + 0.5) / 16
    px = np.arange(N)
    u = (px[None, :, None, None] + s[None, None, None, :]) / N
    v = (px[:, None, None, None] + s[None, None, :, None]) / N
    u, v = np.broadcast_arrays(u, v)
    box = bilinear(tex, u.reshape(N, N, -1), v.reshape(N, N, -1)).mean(axis=2)
    # trilinear: level from the footprint (texels per pixel), lerp between two levels, at the centre
    lod = np.log2(max(W / N, 1.0)); l0 = int(np.floor(lod)); f = lod - l0
    uc = (px[None, :] + 0.5) / N * np.ones((N, 1)); vc = (px[:, None] + 0.5) / N * np.ones((1, N))
    a = bilinear(levels[min(l0, len(levels) - 1)], uc, vc)
    b = bilinear(levels[min(l0 + 1, len(levels) - 1)], uc, vc)
    tri = a * (1 - f) + b * f
    print(f'{sys.argv[1]} {W}x{H} on {N}x{N} px (lod {lod:.2f}): relMSE trilinear vs pixel-averaged bilinear: pixels {relmse(tri, box):.2e}, 8x8 blocks {relmse(block(tri), block(box)):.2e}; means {tri.mean():.5f} {box.mean():.5f}')
