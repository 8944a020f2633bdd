#!/usr/bin/env python3
"""Mitsuba 3's side of an equal-time comparison: `volpath` (the scene's integrator) renders
64-spp passes with seeds 0, 1, ... until SECONDS have passed, and the mean image's relMSE against
REFERENCE is printed with the samples it took (BENCHMARKS.md runs it right after `hppm compare`
on the same scene, so that both see the same machine).

Usage: DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
         python3 equal_time.py SCENE.xml REFERENCE.exr SECONDS [--no-medium-nee]

--no-medium-nee renders with `sample_emitters` false in every medium (phase sampling only;
see README.md for why). relMSE = mean over pixels and RGB of (x - ref)^2 / (ref^2 + 0.01).
"""
import argparse, os, re, tempfile, time
import numpy as np
import mitsuba as mi


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('scene')
    ap.add_argument('reference')
    ap.add_argument('seconds', type=float)
    ap.add_argument('--no-medium-nee', action='store_true')
    args = ap.parse_args()
    mi.set_variant('llvm_ad_rgb')
    path = args.scene
    if args.no_medium_nee:
        text = re.sub(r'(<medium\b[^>]*[^/]>)',
                      r'\1<boolean name="sample_emitters" value="false"/>', open(path).read())
        fd, path = tempfile.mkstemp(suffix='.xml', dir=os.path.dirname(os.path.abspath(args.scene)))
        with os.fdopen(fd, 'w') as f:
            f.write(text)
    try:
        scene = mi.load_file(path)
    finally:
        if path != args.scene:
            os.remove(path)
    ref = np.array(mi.Bitmap(args.reference), dtype=np.float64)[..., :3]
    total, passes, start = None, 0, time.time()
    while time.time() - start < args.seconds:
        image = np.array(mi.render(scene, spp=64, seed=passes), dtype=np.float64)[..., :3]
        total = image if total is None else total + image
        passes += 1
    elapsed = time.time() - start
    mean = total / passes
    error = float(np.mean((mean - ref) ** 2 / (ref ** 2 + 0.01)))
    label = 'volpath, phase sampling only in media' if args.no_medium_nee else 'volpath'
    print(f'{label}: {passes * 64} spp in {elapsed:.1f} s, relMSE {error:.3e}')


if __name__ == '__main__':
    main()
