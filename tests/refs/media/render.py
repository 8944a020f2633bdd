#!/usr/bin/env python3
"""Render / extend a Mitsuba 3 reference for one media scene, and measure its noise.

Usage (from anywhere):
  DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \
    python3 render.py SCENE [--passes N] [--pass-spp 256] [--seed0 0] [--workdir DIR] \
                            [--max-depth D] [--single256] [--no-combine]

* Renders passes with seeds seed0 .. seed0+N-1, each with --pass-spp samples per pixel
  (integrator: the scene's default, volpath; max_depth: the scene's default unless --max-depth),
  and stores each as WORKDIR/SCENE/pass_SPP_SEED.npy (existing passes are skipped, so a run
  can be resumed or extended by raising --passes).
* Combines every stored pass of that spp: the mean is written to images/SCENE.exr (float32 RGB).
  Statistics (printed and written to WORKDIR/SCENE/stats.json):
    own_relmse   : the reference's own noise, mean over pixels and RGB of
                   (sample variance of the passes / k) / (ref^2 + 0.01)
    pass_relmse  : median over passes of relMSE(pass_i, mean of the other passes)
                   (= Mitsuba's error at pass-spp; includes the leave-one-out mean's own noise,
                   about 1/(k-1) of it)
    pass_block   : the same on 8x8-pixel block means
                   (pass_relmse_mean / pass_block_mean: the means over passes instead of medians;
                   they differ where rare fireflies make the error heavy-tailed)
    sec_per_pass : median wall time of one mi.render call (after the first, which JIT-compiles)
* --single256 also renders one independent 256-spp image with seed 1000000 (not used in the
  reference) to images/SCENE_256spp.exr and reports its relMSE (pixel and 8x8-block) against
  the reference.
relMSE = mean over pixels and RGB channels of (x - ref)^2 / (ref^2 + 0.01).
"""
import argparse, json, os, re, time, glob
import numpy as np
import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 0.01)))


def block(a, b=8):
    h, w, c = a.shape
    return a.reshape(h // b, b, w // b, b, c).mean(axis=(1, 3))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('scene')
    ap.add_argument('--passes', type=int, default=32)
    ap.add_argument('--pass-spp', type=int, default=256)
    ap.add_argument('--seed0', type=int, default=0)
    ap.add_argument('--workdir', default='/tmp/hppm_media_passes')
    ap.add_argument('--max-depth', type=int, default=None)
    ap.add_argument('--single256', action='store_true')
    ap.add_argument('--no-combine', action='store_true')
    ap.add_argument('--no-medium-nee', action='store_true',
                    help='render with sample_emitters false in every medium: Mitsuba 3.9.1 '
                         'volpath\'s light sampling from media through null boundaries is '
                         'biased dark (see README.md); passes go to WORKDIR/SCENE_nonee')
    args = ap.parse_args()

    mi.set_variant('llvm_ad_rgb')
    xml = os.path.join(HERE, 'scenes', args.scene, 'scene.xml')
    params = {}
    if args.max_depth is not None:
        params['max_depth'] = args.max_depth
    if args.no_medium_nee:
        # The same scene with phase sampling only in its media, written beside it (relative
        # paths) for the load and removed after.
        text = open(xml).read()
        text = re.sub(r'(<medium\b[^>]*[^/]>)', r'\1<boolean name="sample_emitters" value="false"/>', text)
        xml = os.path.join(HERE, 'scenes', args.scene, 'scene_no_medium_nee.xml')
        open(xml, 'w').write(text)
        try:
            scene = mi.load_file(xml, **params)
        finally:
            os.remove(xml)
    else:
        scene = mi.load_file(xml, **params)
    wdir = os.path.join(args.workdir, args.scene + ('_nonee' if args.no_medium_nee else ''))
    os.makedirs(wdir, exist_ok=True)
    times_path = os.path.join(wdir, 'times.json')
    times = json.load(open(times_path)) if os.path.exists(times_path) else []

    first = True
    for i in range(args.seed0, args.seed0 + args.passes):
        p = os.path.join(wdir, f'pass_{args.pass_spp}_{i}.npy')
        if os.path.exists(p):
            continue
        t = time.time()
        img = np.array(mi.render(scene, spp=args.pass_spp, seed=i), dtype=np.float32)
        dt = time.time() - t
        np.save(p, img)
        if not first:
            times.append(dt)
            json.dump(times, open(times_path, 'w'))
        first = False
        print(f'{args.scene} pass seed {i}: {dt:.2f} s', flush=True)

    if args.no_combine:
        return
    files = sorted(glob.glob(os.path.join(wdir, f'pass_{args.pass_spp}_*.npy')))
    X = np.stack([np.load(f) for f in files]).astype(np.float64)
    k = X.shape[0]
    ref = X.mean(axis=0)
    os.makedirs(os.path.join(HERE, 'images'), exist_ok=True)
    mi.Bitmap(ref.astype(np.float32)).write(os.path.join(HERE, 'images', f'{args.scene}.exr'))
    var = X.var(axis=0, ddof=1)
    own = float(np.mean(var / k / (ref ** 2 + 0.01)))
    pr, pb = [], []
    for i in range(k):
        loo = (k * ref - X[i]) / (k - 1)
        pr.append(relmse(X[i], loo))
        pb.append(relmse(block(X[i]), block(loo)))
    stats = dict(scene=args.scene, passes=k, pass_spp=args.pass_spp, spp=k * args.pass_spp,
                 own_relmse=own, pass_relmse=float(np.median(pr)),
                 pass_relmse_q25_q75=[float(np.percentile(pr, 25)), float(np.percentile(pr, 75))],
                 pass_relmse_mean=float(np.mean(pr)),
                 pass_block=float(np.median(pb)), pass_block_mean=float(np.mean(pb)),
                 sec_per_pass=float(np.median(times)) if times else None,
                 mean_rgb=[float(v) for v in ref.mean(axis=(0, 1))])
    # own noise of the 8x8 block means
    B = np.stack([block(x) for x in X])
    stats['own_block'] = float(np.mean(B.var(axis=0, ddof=1) / k / (block(ref) ** 2 + 0.01)))
    stats['ratio_own_to_pass'] = own / stats['pass_relmse']

    if args.single256:
        t = time.time()
        img = np.array(mi.render(scene, spp=256, seed=1000000), dtype=np.float32)
        dt = time.time() - t
        mi.Bitmap(img).write(os.path.join(HERE, 'images', f'{args.scene}_256spp.exr'))
        img = img.astype(np.float64)
        stats['single256'] = dict(seed=1000000, relmse=relmse(img, ref),
                                  block=relmse(block(img), block(ref)), sec=dt)
    json.dump(stats, open(os.path.join(wdir, 'stats.json'), 'w'), indent=1)
    print(json.dumps(stats, indent=1))


if __name__ == '__main__':
    main()
