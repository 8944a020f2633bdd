"""Run in this folder: writes smooth_sphere.ply (a 16-ring UV sphere with its radial vertex normals) and renders
smooth_sphere.xml with Mitsuba 3 into smooth_sphere.exr
(`python smooth_sphere.py scalar_rgb 1024` with Mitsuba 3.9.1 from PyPI). computed_normals.ply
is smooth_sphere.ply without its normal properties; computed_normals.exr is Mitsuba's render of
smooth_sphere.xml with `-D mesh=computed_normals.ply`."""
import math, struct, sys
rings = 16
segments = 2 * rings
verts, faces = [], []
def index(i, j):
    return i * (segments + 1) + j
for i in range(rings + 1):
    for j in range(segments + 1):
        t = math.pi * i / rings
        p = 2 * math.pi * j / segments
        verts.append((math.sin(t) * math.cos(p), math.cos(t), math.sin(t) * math.sin(p)))
for i in range(rings):
    for j in range(segments):
        a, b, c, d = index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)
        if i != rings - 1:
            faces.append((a, c, b))
        if i != 0:
            faces.append((a, d, c))
with open("smooth_sphere.ply", "w") as f:
    f.write("ply\nformat ascii 1.0\ncomment UV sphere, tests/data/mitsuba/smooth_sphere.py\n")
    f.write(f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n")
    f.write("property float nx\nproperty float ny\nproperty float nz\n")
    f.write(f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    for v in verts:
        f.write("%.7f %.7f %.7f %.7f %.7f %.7f\n" % (v + v))
    for t in faces:
        f.write("3 %d %d %d\n" % t)
if len(sys.argv) > 1:
    import mitsuba as mi
    mi.set_variant(sys.argv[1])
    scene = mi.load_file("smooth_sphere.xml")
    image = mi.render(scene, spp=int(sys.argv[2]) if len(sys.argv) > 2 else 256, seed=1)
    mi.util.write_bitmap("smooth_sphere.exr", image)
