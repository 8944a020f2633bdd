#!/usr/bin/env python3
"""A latitude-longitude sphere mesh of about N triangles, as a binary PLY with vertex normals,
and the glass-sphere Cornell box with that mesh in place of its analytic glass sphere: the
scene that measures load, BVH build and render time against triangle count, and checks a
multi-million-triangle mesh renders as the analytic sphere does (docs/scale.md).

    python3 tests/scale/sphere_mesh.py --triangles 16000000 --out /tmp/sphere16m

writes /tmp/sphere16m/sphere.ply and /tmp/sphere16m/scene.xml (and scene_analytic.xml, the
same box with the analytic sphere, to compare against)."""
import argparse, os, re
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
BOX = os.path.join(HERE, "..", "refs", "scenes", "cornell_glass_sphere", "scene.xml")
CENTER, RADIUS = (0.42, -0.62, 0.42), 0.38


def sphere(triangles):
    # rings x segments quads, the polar ones as single triangles: 2 * rings * segments - 2 * segments.
    segments = max(3, int(round((triangles / 4) ** 0.5 * 2 ** 0.5)))
    rings = max(2, int(round((triangles + 2 * segments) / (2 * segments))))
    theta = np.linspace(0.0, np.pi, rings + 1)
    phi = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta[1:-1], phi, indexing="ij")
    normals = np.stack([np.sin(t) * np.cos(p), np.cos(t), np.sin(t) * np.sin(p)], -1).reshape(-1, 3)
    normals = np.concatenate([[[0, 1, 0]], normals, [[0, -1, 0]]]).astype(np.float32)
    positions = (normals * RADIUS + np.array(CENTER)).astype(np.float32)
    ring = lambda i: 1 + (i - 1) * segments  # first vertex of inner ring i (1-based)
    s = np.arange(segments)
    s1 = (s + 1) % segments
    faces = [np.stack([np.zeros(segments, int), ring(1) + s1, ring(1) + s], -1)]
    for i in range(1, rings - 1):
        a, b = ring(i) + s, ring(i) + s1
        c, d = ring(i + 1) + s, ring(i + 1) + s1
        faces += [np.stack([a, b, d], -1), np.stack([a, d, c], -1)]
    last = len(positions) - 1
    faces.append(np.stack([np.full(segments, last), ring(rings - 1) + s, ring(rings - 1) + s1], -1))
    return positions, normals, np.concatenate(faces).astype(np.int32)


def write_ply(path, positions, normals, faces):
    vertex = np.concatenate([positions, normals], 1).astype("<f4")
    face = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    face["n"], face["i"] = 3, faces
    with open(path, "wb") as f:
        f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertex)}\n"
                 "property float x\nproperty float y\nproperty float z\n"
                 "property float nx\nproperty float ny\nproperty float nz\n"
                 f"element face {len(faces)}\nproperty list uchar int vertex_indices\n"
                 "end_header\n").encode())
        f.write(vertex.tobytes())
        f.write(face.tobytes())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--triangles", type=int, required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    positions, normals, faces = sphere(args.triangles)
    write_ply(os.path.join(args.out, "sphere.ply"), positions, normals, faces)
    box = open(BOX).read()
    with open(os.path.join(args.out, "scene_analytic.xml"), "w") as f:
        f.write(box)
    mesh = ('<shape type="ply">\n        <string name="filename" value="sphere.ply"/>\n'
            '        <bsdf type="dielectric"><float name="int_ior" value="1.5"/>'
            '<float name="ext_ior" value="1"/></bsdf>\n    </shape>')
    glass = re.compile(r'<shape type="sphere">\s*<point name="center" x="0.42".*?</shape>', re.S)
    assert glass.search(box), "the glass sphere of the box"
    with open(os.path.join(args.out, "scene.xml"), "w") as f:
        f.write(glass.sub(mesh, box))
    print(f"{len(faces)} triangles, {len(positions)} vertices in {args.out}")


if __name__ == "__main__":
    main()
