#!/usr/bin/env python3
"""A scene of the size and kind people download: about 262k triangles in ten textured meshes
(binary PLY with uvs and normals), each with its own 2048x2048 JPEG texture, on a floor under
an area light. Measures what a user waits for before the first image: hppm's load, prepare
(BVH build, upload, pipelines) and first iteration, with Mitsuba 3's load_file of the same
file in the same run (BENCHMARKS.md, "Loading a real-sized textured scene").

    python3 tests/scale/textured_scene.py --out /tmp/textured [--hppm target/release/hppm]

Needs numpy and Pillow; Mitsuba (`pip install mitsuba==3.9.1`, DRJIT_LIBLLVM_PATH) for its
figure.
"""
import argparse, os, subprocess, time
import numpy as np
from PIL import Image

MESHES, TRIANGLES, TEXTURE = 10, 262_144, 2048


def wavy_grid(n, seed):
    """An n x n grid of quads (2 n^2 triangles) bent into a hill, with uvs and normals."""
    u, v = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij")
    rng = np.random.default_rng(seed)
    a, b = rng.uniform(1, 3, 2)
    x, z = u - 0.5, v - 0.5
    y = 0.15 * np.sin(a * np.pi * u) * np.sin(b * np.pi * v) + 0.2
    p = np.stack([x, y, z], -1).reshape(-1, 3).astype(np.float32)
    # Normals from the height field's gradient.
    dy_du = 0.15 * a * np.pi * np.cos(a * np.pi * u) * np.sin(b * np.pi * v)
    dy_dv = 0.15 * b * np.pi * np.sin(a * np.pi * u) * np.cos(b * np.pi * v)
    nrm = np.stack([-dy_du, np.ones_like(u), -dy_dv], -1).reshape(-1, 3)
    nrm = (nrm / np.linalg.norm(nrm, axis=1, keepdims=True)).astype(np.float32)
    uv = np.stack([u, v], -1).reshape(-1, 2).astype(np.float32)
    i = np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]
    i = i.reshape(-1)
    faces = np.concatenate([np.stack([i, i + 1, i + n + 2], 1), np.stack([i, i + n + 2, i + n + 1], 1)])
    return p, nrm, uv, faces.astype(np.int32)


def write_ply(path, p, nrm, uv, faces):
    vertex = np.zeros(len(p), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("nx", "<f4"),
                                      ("ny", "<f4"), ("nz", "<f4"), ("u", "<f4"), ("v", "<f4")])
    for k, name in enumerate("xyz"):
        vertex[name] = p[:, k]
    for k, name in enumerate(["nx", "ny", "nz"]):
        vertex[name] = nrm[:, k]
    vertex["u"], vertex["v"] = uv[:, 0], uv[:, 1]
    face = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"], face["i"] = 3, faces
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(p)}\n"
              + "".join(f"property float {n}\n" for n in ["x", "y", "z", "nx", "ny", "nz", "u", "v"])
              + f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(vertex.tobytes())
        f.write(face.tobytes())


def write_texture(path, seed):
    rng = np.random.default_rng(seed)
    small = rng.uniform(0, 255, (64, 64, 3)).astype(np.uint8)
    big = Image.fromarray(small).resize((TEXTURE, TEXTURE), Image.BICUBIC)
    big.save(path, quality=90)


def build(out):
    os.makedirs(out, exist_ok=True)
    n = int(round((TRIANGLES / MESHES / 2) ** 0.5))
    shapes = []
    for k in range(MESHES):
        p, nrm, uv, faces = wavy_grid(n, k)
        write_ply(os.path.join(out, f"mesh{k}.ply"), p, nrm, uv, faces)
        write_texture(os.path.join(out, f"texture{k}.jpg"), k)
        x, z = (k % 5) * 1.1 - 2.2, (k // 5) * 1.1 - 0.55
        bsdf = ("diffuse", "reflectance") if k % 2 == 0 else ("roughplastic", "diffuse_reflectance")
        shapes.append(
            f'<shape type="ply"><string name="filename" value="mesh{k}.ply"/>'
            f'<transform name="to_world"><translate x="{x:.3f}" z="{z:.3f}"/></transform>'
            f'<bsdf type="{bsdf[0]}"><texture type="bitmap" name="{bsdf[1]}">'
            f'<string name="filename" value="texture{k}.jpg"/></texture></bsdf></shape>')
    xml = f"""<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="6"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="0, 3, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
        <film type="hdrfilm"><integer name="width" value="512"/><integer name="height" value="512"/></film>
    </sensor>
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="6"/></transform>
        <bsdf type="diffuse"/></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="1.5"/><lookat origin="1, 4, 2" target="0, 0, 0" up="0, 1, 0"/></transform>
        <emitter type="area"><rgb name="radiance" value="8, 8, 8"/></emitter></shape>
    {chr(10).join('    ' + s for s in shapes)}
</scene>
"""
    path = os.path.join(out, "scene.xml")
    with open(path, "w") as f:
        f.write(xml)
    return path, MESHES * 2 * n * n


def main():
    a = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("--out", default="/tmp/textured")
    a.add_argument("--hppm", default="target/release/hppm")
    a = a.parse_args()
    path, triangles = build(a.out)
    print(f"{path}: {triangles} triangles, {MESHES} JPEG textures of {TEXTURE}x{TEXTURE}")
    for graph in ["graphs/pt.ron", "graphs/hybrid.ron"]:
        start = time.time()
        run = subprocess.run([a.hppm, "render", path, "--graph", graph, "--spp", "1", "--profile",
                              "--out", os.path.join(a.out, "first.exr")], capture_output=True, text=True)
        wall = time.time() - start
        lines = [l for l in run.stderr.splitlines() if any(w in l for w in ("loaded", "prepare", "ms", "iteration"))]
        print(f"hppm {graph}: {wall:.2f} s to the first image (1 spp, 512x512)")
        for l in lines:
            print("   ", l)
    try:
        import mitsuba as mi
        mi.set_variant("llvm_ad_rgb")
        start = time.time()
        scene = mi.load_file(path)
        loaded = time.time() - start
        start = time.time()
        mi.render(scene, spp=1)
        first = time.time() - start
        print(f"Mitsuba 3 llvm_ad_rgb: load_file {loaded:.2f} s, first 1-spp render {first:.2f} s")
    except ImportError:
        print("Mitsuba not installed: no side-by-side figure")


if __name__ == "__main__":
    main()
