#!/usr/bin/env python3
"""Renders reference.exr with Mitsuba 3.9.1 (llvm_ad_rgb, the scene's own `path` integrator):
calls of 256 spp with consecutive seeds from FIRST_SEED (default 900000), averaged, for
SECONDS of wall time, the running mean written every 20 calls. It renders the scene.xml of the
directory it runs in, so other scenes use it too (scenes/glass_ring: SECONDS 720, FIRST_SEED
700000).

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 render_reference.py 1500 [FIRST_SEED]
"""
import sys
import time

import mitsuba as mi
import numpy as np

SECONDS = float(sys.argv[1]) if len(sys.argv) > 1 else 1500.0
FIRST_SEED = int(sys.argv[2]) if len(sys.argv) > 2 else 900000

mi.set_variant("llvm_ad_rgb")
scene = mi.load_file("scene.xml")
total, calls, start = None, 0, time.time()
while time.time() - start < SECONDS:
    image = np.array(mi.render(scene, spp=256, seed=FIRST_SEED + calls))
    total = image if total is None else total + image
    calls += 1
    if calls % 20 == 0:
        mi.Bitmap((total / calls).astype(np.float32)).write("reference.exr")
        print(f"{calls * 256} spp, {time.time() - start:.0f} s", flush=True)
mi.Bitmap((total / calls).astype(np.float32)).write("reference.exr")
print(f"done: {calls * 256} spp in {time.time() - start:.0f} s")
