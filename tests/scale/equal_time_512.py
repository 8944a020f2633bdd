"""512x512, 60 s: hppm hybrid.ron against Mitsuba 3 path (256 spp per call), both in one run,
relMSE (x-r)^2/(r^2+0.01) against a Mitsuba reference rendered here first (batches of 128 spp
for REF_MINUTES); the reference's own noise (the variance of its mean, from its batches) is
subtracted from each relMSE, since both images are compared with the same noisy reference.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \
        python3 tests/scale/equal_time_512.py cornell_glass_sphere 6

Needs target/release/hppm; works in /tmp/eq512/SCENE."""
import os, re, shutil, subprocess, sys, time
import numpy as np, mitsuba as mi
mi.set_variant('llvm_ad_rgb')
scene_name, ref_minutes = sys.argv[1], float(sys.argv[2])
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
src = f"{ROOT}/tests/refs/scenes/{scene_name}"
work = f"/tmp/eq512/{scene_name}"
if not os.path.exists(work):
    shutil.copytree(src, work)
    xml = open(f"{work}/scene.xml").read()
    xml = re.sub(r'(<integer name="width" value=")\d+', r'\g<1>512', xml)
    xml = re.sub(r'(<integer name="height" value=")\d+', r'\g<1>512', xml)
    open(f"{work}/scene.xml", "w").write(xml)
scene = mi.load_file(f"{work}/scene.xml")
def render(spp, seed):
    return np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)[..., :3]
# reference: batches of 128 spp until ref_minutes
if not os.path.exists(f"{work}/ref_mean.npy"):
    batches = []
    t = time.time()
    while time.time() - t < ref_minutes * 60:
        batches.append(render(128, 100000 + len(batches)))
    b = np.stack(batches)
    np.save(f"{work}/ref_mean.npy", b.mean(0))
    np.save(f"{work}/ref_var.npy", b.var(0, ddof=1) / len(b))
    print(f"reference: {len(b) * 128} spp in {time.time() - t:.0f} s", flush=True)
ref = np.load(f"{work}/ref_mean.npy"); ref_var = np.load(f"{work}/ref_var.npy")
def relmse(x):
    raw = ((x - ref) ** 2 / (ref ** 2 + 0.01)).mean()
    noise = (ref_var / (ref ** 2 + 0.01)).mean()
    return raw, raw - noise, noise
# Mitsuba path, 60 s, 256 spp per call
acc, calls, t = 0, 0, time.time()
while time.time() - t < 60:
    acc = acc + render(256, calls); calls += 1
mts_time = time.time() - t
mts = acc / calls
# hppm hybrid, 60 s
out = subprocess.run([f"{ROOT}/target/release/hppm", "render", f"{work}/scene.xml", "--time", "60",
                      "--out", f"{work}/hppm.exr"], capture_output=True, text=True, cwd=ROOT)
line = out.stdout.strip().splitlines()[-1] if out.stdout else out.stderr
hp = np.array(mi.Bitmap(f"{work}/hppm.exr"), dtype=np.float64)[..., :3]
m_raw, m_cor, noise = relmse(mts); h_raw, h_cor, _ = relmse(hp)
print(f"| {scene_name} | reference noise {noise:.2e} | Mitsuba path {calls * 256} spp in {mts_time:.1f} s: "
      f"relMSE {m_cor:.3e} (raw {m_raw:.3e}) | hppm hybrid: relMSE {h_cor:.3e} (raw {h_raw:.3e}); {line} |", flush=True)
