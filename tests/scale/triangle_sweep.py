#!/usr/bin/env python3
"""Load, build and per-iteration time against triangle count: the glass-sphere Cornell box with
its glass sphere made of N triangles (sphere_mesh.py), rendered by hppm (128x128, hybrid.ron,
--profile, iterations 2-4: render --profile leaves out the first, which compiles the
pipelines) and loaded by Mitsuba 3 in the same run, one after the other. Prints a
Markdown table for BENCHMARKS.md.

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        python3 tests/scale/triangle_sweep.py --hppm target/release/hppm --work /tmp/meshes \\
        --triangles 1000,16000,262000,1000000,4000000,16000000
"""
import argparse, os, re, subprocess, sys, time

HERE = os.path.dirname(os.path.abspath(__file__))


def peak_kib(cmd):
    out = subprocess.run(["/usr/bin/time", "-f", "PEAK %M"] + cmd, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{out.stderr}")
    peak = int(re.search(r"PEAK (\d+)", out.stderr).group(1))
    return out.stdout + out.stderr, peak


def mitsuba_load_seconds(scene):
    code = ("import time, mitsuba as mi; mi.set_variant('llvm_ad_rgb'); t = time.time(); "
            f"s = mi.load_file({scene!r}); print(time.time() - t)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    return float(out.stdout.strip().splitlines()[-1]) if out.returncode == 0 else float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--hppm", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--triangles", default="1000,16000,262000,1000000,4000000,16000000")
    args = ap.parse_args()
    print("| triangles | hppm load (s) | hppm prepare: BVH + upload + pipelines (s) | Mitsuba 3 load_file (s) "
          "| peak RSS (GB) | chunked tables | node ms per iteration |")
    print("|---|---|---|---|---|---|---|")
    for n in [int(t) for t in args.triangles.split(",")]:
        folder = os.path.join(args.work, f"sphere{n}")
        if not os.path.exists(os.path.join(folder, "scene.xml")):
            subprocess.run([sys.executable, os.path.join(HERE, "sphere_mesh.py"),
                            "--triangles", str(n), "--out", folder], check=True, capture_output=True)
        scene = os.path.join(folder, "scene.xml")
        log, peak = peak_kib([args.hppm, "render", scene, "--graph", "graphs/hybrid.ron",
                              "--spp", "4", "--size", "128x128", "--profile",
                              "--out", os.path.join(folder, "render.exr")])
        tris = re.search(r"\((\d+) triangles, loaded in ([\d.]+) s\)", log)
        prep = re.search(r"prepared in ([\d.]+) s", log).group(1)
        chunks = re.search(r"in chunks: (.*)", log)
        nodes = re.findall(r"^  (\w+) +\w+ +[\d.]+ +([\d.]+)$", log, re.M)
        node_text = ", ".join(f"{name} {float(ms):.0f}" for name, ms in nodes)
        print(f"| {int(tris.group(1)):,} | {tris.group(2)} | {prep} | {mitsuba_load_seconds(scene):.2f} "
              f"| {peak / 1048576:.1f} | {chunks.group(1) if chunks else 'none'} | {node_text} |", flush=True)


if __name__ == "__main__":
    main()
