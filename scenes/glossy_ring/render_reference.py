#!/usr/bin/env python3
"""Renders reference.exr with Mitsuba 3.9.1 (llvm_ad_rgb): two independent halves of SPP_HALF
samples per pixel (seeds 1 and 2), averaged. Prints the halves' relMSE against each other (the
metric of `hppm compare`, mean of (a-b)^2/(r^2+0.01)) and the reference's own noise estimated
from them: the averaged image's relMSE against the truth is about a quarter of the halves'.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 render_reference.py
"""
import sys
import time

import mitsuba as mi
import numpy as np

SPP_HALF = int(sys.argv[1]) if len(sys.argv) > 1 else 262144
# Dr.Jit's wavefront holds every sample of a render at once: render in chunks.
CHUNK = 8192

mi.set_variant("llvm_ad_rgb")
scene = mi.load_file("scene.xml")


def render(seed):
    total = 0.0
    chunks = SPP_HALF // CHUNK if SPP_HALF >= CHUNK else 1
    spp = SPP_HALF // chunks
    for c in range(chunks):
        # Distinct seeds per chunk and half: independent streams.
        total = total + np.array(mi.render(scene, spp=spp, seed=seed * 100003 + c))
    return total / chunks


start = time.time()
a = render(1)
b = render(2)
seconds = time.time() - start
ref = 0.5 * (a + b)
rel = lambda x, y: float(np.mean((x - y) ** 2 / (ref ** 2 + 0.01)))
halves = rel(a, b)
print(f"{2 * SPP_HALF} spp in {seconds:.0f} s; relMSE between halves {halves:.3e}; "
      f"reference's own relMSE about {halves / 4:.3e}; mean {ref.mean(axis=(0, 1))}")
mi.Bitmap(ref.astype(np.float32)).write("reference.exr")
