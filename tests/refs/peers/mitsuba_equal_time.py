"""Mitsuba 3's error against time on a scene, as a `hppm compare --peer` CSV.

Renders the scene with Mitsuba 3 (llvm_ad_rgb, its own `path` integrator as the file sets it) in
calls of SPP samples per pixel with fresh seeds, as a user renders, and after each call writes
the wall time since the start (Python's imports excluded; scene load, JIT and every render
included) and the relMSE of the running mean against the reference, until SECONDS have passed.

    pip install mitsuba==3.9.1 numpy && apt-get install -y libllvm19
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        python3 tests/refs/peers/mitsuba_equal_time.py SCENE.xml REFERENCE.exr SECONDS OUT.csv [SPP [SEED]]

SEED (default 700000) is the first call's seed; each later call takes the next one, so runs with
seeds further apart than their call count are independent.

relMSE is the metric of tests/refs/README.md: the mean over pixels and channels of
(x - ref)^2 / (ref^2 + 0.01).
"""

import sys
import time

import numpy as np
import mitsuba as mi


def relmse(image, reference):
    return float(np.mean((image - reference) ** 2 / (reference ** 2 + 0.01)))


def main():
    scene_path, reference_path, seconds, out = sys.argv[1:5]
    spp = int(sys.argv[5]) if len(sys.argv) > 5 else 256
    first_seed = int(sys.argv[6]) if len(sys.argv) > 6 else 700000
    mi.set_variant("llvm_ad_rgb")
    reference = np.array(mi.Bitmap(reference_path), dtype=np.float64)[..., :3]
    start = time.time()
    scene = mi.load_file(scene_path)
    total = np.zeros_like(reference)
    rows = []
    calls = 0
    while time.time() - start < float(seconds):
        image = np.array(mi.render(scene, spp=spp, seed=first_seed + calls), dtype=np.float64)
        calls += 1
        total += image[..., :3]
        rows.append((time.time() - start, relmse(total / calls, reference)))
    with open(out, "w") as f:
        f.write(f"# Mitsuba 3.9.1 path (llvm_ad_rgb), {scene_path}, {spp} spp per call\n")
        f.write("seconds,relmse,label\n")
        for t, e in rows:
            f.write(f"{t:.3f},{e:.6g},Mitsuba 3 path\n")
    print(f"{calls * spp} spp in {rows[-1][0]:.1f} s: relMSE {rows[-1][1]:.4g}")


if __name__ == "__main__":
    main()
