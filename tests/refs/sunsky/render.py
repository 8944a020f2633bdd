#!/usr/bin/env python3
"""Mitsuba 3.9.1's reference render of scene.xml (a ground, a box and a sphere under `sunsky`)
for tests/sunsky.rs, and its figures.

Usage (from anywhere):
  DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 render.py [--passes 64]
      [--pass-spp 256] [--workdir /tmp/hppm_sunsky_passes]

Renders passes with seeds 0 .. passes-1 (variant llvm_ad_rgb, the scene's own integrator and
film), each --pass-spp samples per pixel, kept as WORKDIR/pass_SPP_SEED.npy (a run resumes or
extends). Writes images/sunsky.exr (the mean of the passes, float32 RGB) and figures.json:
  pixels_256 / blocks_256: median over passes of relMSE(pass, mean of the other passes) on
                           pixels and on 8x8 block means (Mitsuba's own error at 256 spp)
  noise_pixels / noise_blocks: the reference's own noise (pass variance / passes, relMSE form)
relMSE = mean over pixels and RGB of (x - ref)^2 / (ref^2 + 0.01).
"""
import argparse, glob, json, os, time
import numpy as np
import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))


def block(a, b=8):
    h, w, c = a.shape
    return a.reshape(h // b, b, w // b, b, c).mean(axis=(1, 3))


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 0.01)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--passes', type=int, default=64)
    ap.add_argument('--pass-spp', type=int, default=256)
    ap.add_argument('--workdir', default='/tmp/hppm_sunsky_passes')
    args = ap.parse_args()
    mi.set_variant('llvm_ad_rgb')
    scene = mi.load_file(os.path.join(HERE, 'scene.xml'))
    os.makedirs(args.workdir, exist_ok=True)
    times = []
    for seed in range(args.passes):
        path = os.path.join(args.workdir, f'pass_{args.pass_spp}_{seed}.npy')
        if os.path.exists(path):
            continue
        t = time.time()
        image = np.array(mi.render(scene, spp=args.pass_spp, seed=seed), dtype=np.float32)
        times.append(time.time() - t)
        np.save(path, image)
        print(f'pass {seed}: {times[-1]:.2f} s', flush=True)
    files = sorted(glob.glob(os.path.join(args.workdir, f'pass_{args.pass_spp}_*.npy')))
    passes = np.stack([np.load(f) for f in files]).astype(np.float64)
    k = len(passes)
    ref = passes.mean(axis=0)
    os.makedirs(os.path.join(HERE, 'images'), exist_ok=True)
    mi.Bitmap(ref.astype(np.float32)).write(os.path.join(HERE, 'images', 'sunsky.exr'))
    pixels, blocks = [], []
    for i in range(k):
        others = (k * ref - passes[i]) / (k - 1)
        pixels.append(relmse(passes[i], others))
        blocks.append(relmse(block(passes[i]), block(others)))
    var = passes.var(axis=0, ddof=1)
    block_var = np.stack([block(p) for p in passes]).var(axis=0, ddof=1)
    figures = dict(
        scene='sunsky', passes=k, pass_spp=args.pass_spp, spp=k * args.pass_spp,
        pixels_256=float(np.median(pixels)), blocks_256=float(np.median(blocks)),
        noise_pixels=float(np.mean(var / k / (ref ** 2 + 0.01))),
        noise_blocks=float(np.mean(block_var / k / (block(ref) ** 2 + 0.01))),
        sec_per_pass=float(np.median(times[1:])) if len(times) > 1 else None,
        mean=[float(v) for v in ref.mean(axis=(0, 1))])
    json.dump(figures, open(os.path.join(HERE, 'figures.json'), 'w'), indent=1)
    print(json.dumps(figures, indent=1))


if __name__ == '__main__':
    main()
