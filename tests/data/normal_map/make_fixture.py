"""Writes the fixture tests/normal_map.rs checks hppm's normalmap and bumpmap against: Mitsuba
3's own perturbed shading frames, read at ray hits on the shapes of scene.xml.

    pip install mitsuba==3.9.1 numpy pillow && python3 make_fixture.py

Uses the scalar_rgb variant (no LLVM needed). Writes normal.png and height.png (small random
textures), mesh_uv.obj and mesh_nouv.obj, scene.xml (the scene hppm loads) and
mitsuba_frames.csv.

How the frame is read: Mitsuba loads scene.xml with every nested `diffuse` replaced by a
Python BSDF (`Recorder`) that returns 1 and records the incident and outgoing directions it is
handed. Those are the directions in the perturbed frame, as any nested BSDF sees them, after
`twosided` has flipped them for the back; and the value `normalmap`/`bumpmap` return is then
exactly what they multiply the nested BSDF by (the shadow terminator, and 0 where a direction
lies on different sides of the two frames).

Each row: shape index (its order in scene.xml, hppm's material index), the ray (origin,
direction), Mitsuba's surface interaction (p, uv, geometric n, shading frame s t n, dp_du,
dp_dv), then for three light directions (world space) the value and the outgoing direction the
nested BSDF saw, and the incident direction it saw (the same for all three).
"""
import math
import os
import random

import mitsuba as mi
import numpy as np
from PIL import Image

mi.set_variant("scalar_rgb")
HERE = os.path.dirname(os.path.abspath(__file__))

NORMAL = '<texture name="normalmap" type="bitmap"><boolean name="raw" value="true"/><string name="filename" value="normal.png"/></texture>'
HEIGHT = '<texture name="height" type="bitmap"><boolean name="raw" value="true"/><string name="filename" value="height.png"/>{extra}</texture>'
DIFFUSE = '<bsdf type="diffuse"/>'

# (shape, BSDF, which sides rays come from: 1 front, -1 back, 0 both)
SHAPES = [
    # A sheared, scaled rectangle: dp_du and dp_dv of different lengths, not orthogonal.
    ('<shape type="rectangle"><transform name="to_world"><matrix value="1.2 0.5 0 0  0.1 0.8 0.2 0  0 -0.3 1 0  0 0 0 1"/></transform>{bsdf}</shape>',
     f'<bsdf type="normalmap">{NORMAL}{DIFFUSE}</bsdf>', 1),
    # A bump map through a rotated, scaled to_uv (the gradient's transpose multiply).
    ('<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-70"/><translate x="4"/></transform>{bsdf}</shape>',
     '<bsdf type="bumpmap">' + HEIGHT.format(extra='<transform name="to_uv"><scale x="2" y="1.5"/><rotate z="1" angle="30"/></transform>')
     + '<float name="scale" value="0.15"/>' + DIFFUSE + '</bsdf>', 1),
    ('<shape type="sphere"><point name="center" value="8, 0, 0"/><float name="radius" value="0.7"/>{bsdf}</shape>',
     f'<bsdf type="normalmap">{NORMAL}{DIFFUSE}</bsdf>', 1),
    # Inward normals, seen from outside: the back of a twosided bump map.
    ('<shape type="sphere"><point name="center" value="12, 0, 0"/><float name="radius" value="0.8"/><boolean name="flip_normals" value="true"/>{bsdf}</shape>',
     '<bsdf type="twosided"><bsdf type="bumpmap">' + HEIGHT.format(extra='') + '<float name="scale" value="0.02"/>' + DIFFUSE + '</bsdf></bsdf>', -1),
    # Texture coordinates and vertex normals; one triangle's uvs are degenerate.
    ('<shape type="obj"><string name="filename" value="mesh_uv.obj"/><transform name="to_world"><translate x="16"/></transform>{bsdf}</shape>',
     f'<bsdf type="twosided"><bsdf type="normalmap">{NORMAL}{DIFFUSE}</bsdf></bsdf>', 0),
    # No texture coordinates (barycentric dp_du), flipped, twosided inside the bump map.
    ('<shape type="obj"><string name="filename" value="mesh_nouv.obj"/><boolean name="flip_normals" value="true"/><transform name="to_world"><translate x="20"/></transform>{bsdf}</shape>',
     '<bsdf type="bumpmap">' + HEIGHT.format(extra='') + '<float name="scale" value="0.3"/><bsdf type="twosided">' + DIFFUSE + '</bsdf></bsdf>', 0),
    # twosided inside the normal map; no flipping of invalid normals, no shadow terminator.
    ('<shape type="rectangle"><transform name="to_world"><rotate y="1" angle="40"/><translate x="24"/></transform>{bsdf}</shape>',
     f'<bsdf type="normalmap">{NORMAL}<boolean name="flip_invalid_normals" value="false"/><boolean name="use_shadowing_function" value="false"/><bsdf type="twosided">{DIFFUSE}</bsdf></bsdf>', 0),
    # sRGB-decoded height map, mirrored at its edges, around a twosided.
    ('<shape type="rectangle"><transform name="to_world"><scale x="1.5"/><rotate x="1" angle="20"/><translate x="28"/></transform>{bsdf}</shape>',
     '<bsdf type="twosided"><bsdf type="bumpmap"><texture type="bitmap" name="bumps"><string name="filename" value="height.png"/><string name="wrap_mode" value="mirror"/><transform name="to_uv"><scale value="1.7"/></transform></texture><float name="scale" value="0.1"/>' + DIFFUSE + '</bsdf></bsdf>', 0),
]


def write_textures(rng):
    # Normals within about 50 degrees of +z, encoded (n + 1) / 2 as Mitsuba's documentation asks.
    normals = np.zeros((8, 8, 3))
    for y in range(8):
        for x in range(8):
            z = rng.uniform(0.65, 1.0)
            phi = rng.uniform(0, 2 * math.pi)
            r = math.sqrt(1 - z * z)
            normals[y, x] = (r * math.cos(phi), r * math.sin(phi), z)
    Image.fromarray(np.round((normals + 1) / 2 * 255).astype(np.uint8), "RGB").save(os.path.join(HERE, "normal.png"))
    heights = np.array([[rng.uniform(0.0, 1.0) for _ in range(8)] for _ in range(8)])
    Image.fromarray(np.round(heights * 255).astype(np.uint8), "L").save(os.path.join(HERE, "height.png"))


def write_meshes():
    # A 4x4 grid of bumpy quads; the uvs are stretched and one triangle's are all equal.
    lines_uv, lines_nouv, faces_uv, faces_nouv = [], [], [], []
    n = 4
    for j in range(n + 1):
        for i in range(n + 1):
            x, y = i / n * 2 - 1, j / n * 2 - 1
            z = 0.15 * math.sin(2.1 * x + 0.5) * math.cos(1.7 * y)
            lines_uv.append(f"v {x} {y} {z}")
            lines_nouv.append(f"v {x} {y} {z}")
            lines_uv.append(f"vt {0.9 * i / n + 0.05 * j / n} {1.2 * j / n}")
            nx, ny = -0.15 * 2.1 * math.cos(2.1 * x + 0.5) * math.cos(1.7 * y), 0.15 * 1.7 * math.sin(2.1 * x + 0.5) * math.sin(1.7 * y)
            length = math.sqrt(nx * nx + ny * ny + 1)
            lines_uv.append(f"vn {nx / length} {ny / length} {1 / length}")
    lines_uv.append("vt 0.5 0.5")
    degenerate = (n + 1) ** 2 + 1
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            b, c, d = a + 1, a + n + 2, a + n + 1
            for tri in ((a, b, c), (a, c, d)):
                if (i, j) == (1, 2) and tri == (a, b, c):
                    faces_uv.append("f " + " ".join(f"{v}/{degenerate}/{v}" for v in tri))
                else:
                    faces_uv.append("f " + " ".join(f"{v}/{v}/{v}" for v in tri))
                faces_nouv.append("f " + " ".join(str(v) for v in tri))
    with open(os.path.join(HERE, "mesh_uv.obj"), "w") as f:
        f.write("\n".join(lines_uv + faces_uv) + "\n")
    with open(os.path.join(HERE, "mesh_nouv.obj"), "w") as f:
        f.write("\n".join(lines_nouv + faces_nouv) + "\n")


def scene_xml():
    shapes = "\n    ".join(shape.format(bsdf=bsdf) for shape, bsdf, _ in SHAPES)
    return f'<scene version="3.0.0">\n    <!-- Written by make_fixture.py. -->\n    <sensor type="perspective"/>\n    {shapes}\n</scene>\n'


class Recorder(mi.BSDF):
    calls = []

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        self.m_flags = flags
        self.m_components = [flags]

    def eval(self, ctx, si, wo, active=True):
        Recorder.calls.append((mi.Vector3f(si.wi), mi.Vector3f(wo)))
        return mi.Color3f(1.0)

    def pdf(self, ctx, si, wo, active=True):
        return 1.0

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), 1.0

    def sample(self, ctx, si, sample1, sample2, active=True):
        return mi.BSDFSample3f(), mi.Color3f(0.0)

    def to_string(self):
        return "Recorder[]"


def hemisphere(rng, axis, lo=0.0):
    """A direction whose cosine with unit `axis` is uniform in [lo, 1]."""
    axis = np.array(axis)
    z = rng.uniform(lo, 1.0)
    phi = rng.uniform(0, 2 * math.pi)
    r = math.sqrt(1 - z * z)
    helper = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
    s = np.cross(axis, helper)
    s /= np.linalg.norm(s)
    t = np.cross(axis, s)
    return r * math.cos(phi) * s + r * math.sin(phi) * t + z * axis


def v3(v):
    return [float(v[0]), float(v[1]), float(v[2])]


def main():
    rng = random.Random(29)
    write_textures(rng)
    write_meshes()
    text = scene_xml()
    with open(os.path.join(HERE, "scene.xml"), "w") as f:
        f.write(text)
    mi.register_bsdf("recorder", lambda props: Recorder(props))
    os.chdir(HERE)
    scene = mi.load_string(text.replace(DIFFUSE, '<bsdf type="recorder"/>'))
    shapes = scene.shapes()
    # mi.Scene lists shapes in its own order: match them to scene.xml's by position.
    centers = [np.array([4.0 * i, 0, 0]) for i in range(len(SHAPES))]
    order = [min(range(len(centers)), key=lambda i: np.linalg.norm(np.array(v3(s.bbox().center())) - centers[i])) for s in shapes]
    header = ["shape", "o_x", "o_y", "o_z", "d_x", "d_y", "d_z", "p_x", "p_y", "p_z", "u", "v",
              "n_x", "n_y", "n_z", "s_x", "s_y", "s_z", "t_x", "t_y", "t_z", "sn_x", "sn_y", "sn_z",
              "dpdu_x", "dpdu_y", "dpdu_z", "dpdv_x", "dpdv_y", "dpdv_z", "wi_x", "wi_y", "wi_z"]
    for k in range(3):
        header += [f"l{k}_x", f"l{k}_y", f"l{k}_z", f"value{k}", f"wo{k}_x", f"wo{k}_y", f"wo{k}_z"]
    rows = []
    ctx = mi.BSDFContext()
    for shape, index in zip(shapes, order):
        sides = SHAPES[index][2]
        count = 0
        attempts = 0
        while count < 40 and attempts < 400:
            attempts += 1
            ps = shape.sample_position(0.0, mi.Point2f(rng.random(), rng.random()))
            outward = np.array(v3(ps.n))
            side = sides if sides != 0 else rng.choice([1, -1])
            if count % 5 == 0:
                # Every fifth ray grazes the surface, where Mitsuba flips invalid normals.
                w = hemisphere(rng, side * outward, 0.0)
                w = w - 0.9 * np.dot(w, side * outward) * side * outward
                w /= np.linalg.norm(w)
            else:
                w = hemisphere(rng, side * outward, 0.2)
            origin = np.array(v3(ps.p)) + 0.4 * w
            ray = mi.Ray3f(mi.Point3f(*origin), mi.Vector3f(*(-w)))
            si = scene.ray_intersect(ray)
            if not si.is_valid() or abs(si.wi.z) < 1e-3:
                continue
            geometric = np.array(v3(si.n))
            facing = 1.0 if np.dot(w, geometric) > 0 else -1.0
            bsdf = si.bsdf()
            Recorder.calls.clear()
            row = [index] + v3(origin) + v3(-w) + v3(si.p) + [float(si.uv[0]), float(si.uv[1])] + v3(si.n) \
                + v3(si.sh_frame.s) + v3(si.sh_frame.t) + v3(si.sh_frame.n) + v3(si.dp_du) + v3(si.dp_dv)
            lights = []
            for k in range(3):
                light = hemisphere(rng, facing * geometric, 0.02)
                value = bsdf.eval(ctx, si, si.to_local(mi.Vector3f(*light)))
                lights.append((light, float(value[0])))
            if len(Recorder.calls) != 3:
                continue
            row += v3(Recorder.calls[0][0])
            for (light, value), (_, wo) in zip(lights, Recorder.calls):
                row += v3(light) + [value] + v3(wo)
            rows.append(row)
            count += 1
    rows.sort(key=lambda r: r[0])
    with open(os.path.join(HERE, "mitsuba_frames.csv"), "w") as f:
        f.write(",".join(header) + "\n")
        for row in rows:
            f.write(",".join(repr(x) if isinstance(x, float) else str(x) for x in row) + "\n")
    print(f"{len(rows)} rows")


if __name__ == "__main__":
    main()
