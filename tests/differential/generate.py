#!/usr/bin/env python3
"""Random Mitsuba 3 scenes from the plugin set hppm loads, with Mitsuba's own reference images.

Each scene is a seeded draw: analytic shapes and meshes (spheres, cubes, rectangles, disks, OBJ
and PLY meshes, hollow rings standing on the floor) under random transforms including mirrored
ones; every BSDF hppm supports with random parameters; every emitter kind; a camera from a
random direction; thin walls, nested and touching dielectrics; a scene scale from 1e-2 to 1e2.
The same index always gives the same scene (Python's `random.Random(index)`), so a failing
scene can be regenerated and studied on its own.

    python3 tests/differential/generate.py --first 0 --count 40 --out tests/differential/corpus
    python3 tests/differential/generate.py --first 1000 --count 1000 --out /tmp/corpus --spp 1024

Writes `<out>/NNNN/scene.xml` (with its meshes), `<out>/NNNN/reference.exr` (the mean of
`--batches` independent Mitsuba renders) and `<out>/NNNN/reference_se.exr` (each pixel's standard
error of that mean, from the batches' spread), and `<out>/manifest.txt`: `# reference_spp N`, then
one line per scene, `NNNN pt hybrid`, or `NNNN pt` where the hybrid cannot agree with Mitsuba's
path tracer (a delta light seen through a delta BSDF, `L S+ D E`, which only photons reach). References need `pip install mitsuba==3.9.1 numpy`
and Debian's `libllvm19` (`DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so`).
With `--check BINARY` every scene is first loaded by hppm (`BINARY render --spp 1`) and the run
stops on one it refuses: the generator draws only from what hppm claims to support.

With `--media` every scene also holds participating media (`add_media`): Mitsuba's
`homogeneous` media inside glass (some of the scene's dielectric spheres and cubes, or new ones:
albedo 0..0.3, coloured sigma_t), inside `null` spheres and cubes (scattering blobs: albedo
0.5..0.95, optical thickness 0.3..5 across, phase isotropic, hg or rayleigh) and, in half the
scenes, fog (a `null` box around the objects, or the sensor's medium with no boundary), given
nested or by reference, sigma_t per unit length of the scene scaled by 1 / scale. The media are
drawn from a random stream of their own (`random.Random(f"media {index}")`), so the scene under
them is the one the index gives without `--media`, and an index and the flag always give the
same scene. Scenes 0040 on of the committed corpus are drawn with it:

    python3 tests/differential/generate.py --first 40 --count 12 --media --spp 32768 --out tests/differential/corpus

A media scene's integrator is `volpath` (the same max_depth and rr_depth), and its reference
steps around two faults of Mitsuba 3.9.1's volpath: it is rendered from the same scene written
at scale 1 (`MEDIA_UNIT`), the light of area lights and environments from a copy with
`sample_emitters` false in every medium and that of delta lights from a copy holding only them
(`reference_copies`); the scene.xml hppm reads keeps Mitsuba's defaults. Its manifest line
follows the rule above. volpath differs from `path` in one more way the generator does not step
around: it treats `thindielectric` transmission as a null event (shadow rays pass the pane, the
crossing does not count towards max_depth), so with a delta light it reaches `L T+ D E` through
thin glass, which hppm's `pt` renders as `path` does (scene 0040).
"""

import argparse
import math
import os
import random
import subprocess
import sys

SIZE = 32
MAX_DEPTH = 8


def fmt(v):
    return ", ".join(f"{x:.6g}" for x in v)


def normalize(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def rgb(r, lo=0.05, hi=0.95):
    return [r.uniform(lo, hi) for _ in range(3)]


# --- BSDFs -------------------------------------------------------------------------------------

CONDUCTORS = ["none", "Au", "Ag", "Cu", "Al", "Cr"]


def rough_params(r):
    dist = r.choice(["ggx", "beckmann"])
    alpha = r.choice([r.uniform(0.02, 0.1), r.uniform(0.1, 0.6)])
    return f'<string name="distribution" value="{dist}"/><float name="alpha" value="{alpha:.4g}"/>'


def bsdf_xml(r, kind):
    if kind == "diffuse":
        return f'<bsdf type="diffuse"><rgb name="reflectance" value="{fmt(rgb(r))}"/></bsdf>'
    if kind == "dielectric":
        ior = r.choice([1.33, 1.5, r.uniform(1.05, 2.4)])
        return (f'<bsdf type="dielectric"><float name="int_ior" value="{ior:.4g}"/>'
                f'<float name="ext_ior" value="1"/></bsdf>')
    if kind == "thindielectric":
        ior = r.uniform(1.2, 2.0)
        return (f'<bsdf type="thindielectric"><float name="int_ior" value="{ior:.4g}"/>'
                f'<float name="ext_ior" value="1"/></bsdf>')
    if kind == "roughdielectric":
        ior = r.uniform(1.2, 1.9)
        return (f'<bsdf type="roughdielectric">{rough_params(r)}'
                f'<float name="int_ior" value="{ior:.4g}"/><float name="ext_ior" value="1"/></bsdf>')
    if kind == "conductor":
        return f'<bsdf type="conductor"><string name="material" value="{r.choice(CONDUCTORS)}"/></bsdf>'
    if kind == "roughconductor":
        return (f'<bsdf type="roughconductor"><string name="material" value="{r.choice(CONDUCTORS[1:])}"/>'
                f'{rough_params(r)}</bsdf>')
    if kind == "plastic":
        return (f'<bsdf type="plastic"><rgb name="diffuse_reflectance" value="{fmt(rgb(r))}"/>'
                f'<float name="int_ior" value="{r.uniform(1.3, 1.8):.4g}"/></bsdf>')
    if kind == "roughplastic":
        dist = r.choice(["ggx", "beckmann"])
        return (f'<bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="{fmt(rgb(r))}"/>'
                f'<string name="distribution" value="{dist}"/>'
                f'<float name="alpha" value="{r.uniform(0.05, 0.5):.4g}"/></bsdf>')
    if kind == "twosided":
        inner = r.choice(["diffuse", "plastic", "roughconductor"])
        return f'<bsdf type="twosided">{bsdf_xml(r, inner)}</bsdf>'
    raise ValueError(kind)


BSDFS = ["diffuse", "diffuse", "dielectric", "dielectric", "thindielectric", "roughdielectric",
         "conductor", "roughconductor", "plastic", "roughplastic", "twosided"]
# BSDFs with a delta lobe: with a delta light, the paths through them reach no path tracer.
DELTA_BSDFS = {"dielectric", "thindielectric", "conductor", "plastic"}


# --- transforms --------------------------------------------------------------------------------

def placement(r, scale, center, size, uniform=False, mirror_ok=True):
    """A to_world: random rotation, a (possibly non-uniform, possibly mirrored) scale, then the
    object moved to `center`, everything scaled by the scene scale.

    Meshes (`obj`, `ply`, `cube`) are never mirrored: Mitsuba 3.9.1 moves their vertices by a
    mirroring to_world without reversing the triangles' winding, so their faces turn inside out
    (a diffuse mesh renders black from outside), while hppm, like Mitsuba's later versions,
    reverses the winding. The analytic `rectangle` and `disk` agree and are mirrored."""
    parts = []
    if uniform:
        parts.append(f'<scale value="{size:.5g}"/>')
    else:
        s = [size * r.uniform(0.5, 1.5) for _ in range(3)]
        if mirror_ok and r.random() < 0.3:
            s[r.randrange(3)] *= -1
        parts.append(f'<scale x="{s[0]:.5g}" y="{s[1]:.5g}" z="{s[2]:.5g}"/>')
    axis = normalize([r.gauss(0, 1) for _ in range(3)])
    parts.append(f'<rotate x="{axis[0]:.5g}" y="{axis[1]:.5g}" z="{axis[2]:.5g}" angle="{r.uniform(0, 360):.4g}"/>')
    parts.append(f'<translate x="{center[0]:.5g}" y="{center[1]:.5g}" z="{center[2]:.5g}"/>')
    parts.append(f'<scale value="{scale:.5g}"/>')
    return '<transform name="to_world">' + "".join(parts) + "</transform>"


# --- meshes ------------------------------------------------------------------------------------

def uv_sphere_obj(r, smooth):
    rows, cols = r.randint(4, 10), r.randint(6, 16)
    v, vn, f = [], [], []
    for i in range(rows + 1):
        th = math.pi * i / rows
        for j in range(cols):
            ph = 2 * math.pi * j / cols
            p = [math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph)]
            v.append(p)
            vn.append(p)
    idx = lambda i, j: i * cols + (j % cols) + 1
    for i in range(rows):
        for j in range(cols):
            a, b, c, d = idx(i, j), idx(i, j + 1), idx(i + 1, j + 1), idx(i + 1, j)
            if i != 0:
                f.append((a, b, c))
            if i != rows - 1:
                f.append((a, c, d))
    return obj_text(v, vn if smooth else None, f)


def ring_obj(r):
    """A hollow cylinder (a glass ring or tube), y in [0, h], standing on y = 0."""
    segs, r_out = r.randint(12, 48), 1.0
    r_in, h = r.uniform(0.6, 0.95), r.uniform(0.2, 1.0)
    v, f = [], []
    for ring_r, y in [(r_out, 0), (r_out, h), (r_in, 0), (r_in, h)]:
        for j in range(segs):
            a = 2 * math.pi * j / segs
            v.append([ring_r * math.cos(a), y, ring_r * math.sin(a)])
    o0, o1, i0, i1 = 0, segs, 2 * segs, 3 * segs
    for j in range(segs):
        k = (j + 1) % segs
        q = lambda base, x: base + x + 1
        f += [(q(o0, j), q(o1, j), q(o1, k)), (q(o0, j), q(o1, k), q(o0, k))]  # outside wall
        f += [(q(i0, j), q(i0, k), q(i1, k)), (q(i0, j), q(i1, k), q(i1, j))]  # inside wall
        f += [(q(o1, j), q(i1, j), q(i1, k)), (q(o1, j), q(i1, k), q(o1, k))]  # top
        f += [(q(o0, j), q(o0, k), q(i0, k)), (q(o0, j), q(i0, k), q(i0, j))]  # bottom
    return obj_text(v, None, f), h


def obj_text(v, vn, f):
    lines = [f"v {p[0]:.7g} {p[1]:.7g} {p[2]:.7g}" for p in v]
    if vn:
        lines += [f"vn {n[0]:.7g} {n[1]:.7g} {n[2]:.7g}" for n in vn]
        lines += [f"f {a}//{a} {b}//{b} {c}//{c}" for a, b, c in f]
    else:
        lines += [f"f {a} {b} {c}" for a, b, c in f]
    return "\n".join(lines) + "\n"


def box_ply():
    """An ASCII PLY cube [-1, 1]^3, counter-clockwise from outside."""
    v = [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = []
    for a, b, c, d in faces:
        tris += [(a, b, c), (a, c, d)]
    head = ("ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
            "property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n")
    return head + "".join(f"{p[0]} {p[1]} {p[2]}\n" for p in v) + "".join(
        f"3 {a} {b} {c}\n" for a, b, c in tris)


# --- the scene ---------------------------------------------------------------------------------

def generate(index, media=False, unit=None):
    """Scene `index` (with media when `media`); `unit` writes it at that scale instead of the
    one drawn (the same scene, every length times unit / scale: media references)."""
    r = random.Random(index)
    scale = drawn = r.choice([1.0, 1.0, 1.0, 0.01, 100.0, r.uniform(0.1, 10)])
    if unit is not None:
        scale = unit
    files = {}
    shapes = []
    bsdfs_used = set()
    lights = []
    # What the media layer needs to know of each object (recorded without drawing anything):
    # its index in `shapes`, shape, BSDF kind, centre and a radius that bounds it (before the
    # scene scale).
    objects = []
    emitters = []
    area_lights = []  # (centre, bounding radius), before the scene scale

    floor = r.random() < 0.85
    if floor:
        kind = r.choice(["diffuse", "diffuse", "diffuse", "roughplastic", "twosided"])
        bsdfs_used.add(kind)
        shapes.append(
            f'<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/>'
            f'<scale value="{6 * scale:.5g}"/></transform>{bsdf_xml(r, kind)}</shape>')

    for k in range(r.randint(1, 4)):
        kind = r.choice(BSDFS)
        bsdfs_used.add(kind)
        bsdf = bsdf_xml(r, kind)
        shape = r.choice(["sphere", "sphere", "cube", "rectangle", "disk", "obj", "obj_smooth",
                          "ply", "ring", "thin_wall", "nested"])
        size = r.uniform(0.3, 0.9)
        center = [r.uniform(-1.5, 1.5), size if floor else r.uniform(-1, 1.5), r.uniform(-1.5, 1.5)]
        objects.append(dict(at=len(shapes), shape=shape, kind=kind, center=center, size=size,
                            bound=size * BOUND[shape]))
        if shape == "sphere":
            shapes.append(f'<shape type="sphere">{placement(r, scale, center, size, uniform=True)}{bsdf}</shape>')
        elif shape in ("cube", "rectangle", "disk"):
            mirror_ok = shape != "cube"
            shapes.append(f'<shape type="{shape}">{placement(r, scale, center, size, mirror_ok=mirror_ok)}{bsdf}</shape>')
        elif shape in ("obj", "obj_smooth"):
            name = f"mesh{k}.obj"
            files[name] = uv_sphere_obj(r, shape == "obj_smooth")
            face = '' if shape == "obj_smooth" else '<boolean name="face_normals" value="true"/>'
            shapes.append(f'<shape type="obj"><string name="filename" value="{name}"/>{face}'
                          f'{placement(r, scale, center, size, mirror_ok=False)}{bsdf}</shape>')
        elif shape == "ply":
            name = f"mesh{k}.ply"
            files[name] = box_ply()
            shapes.append(f'<shape type="ply"><string name="filename" value="{name}"/>'
                          f'{placement(r, scale, center, size, mirror_ok=False)}{bsdf}</shape>')
        elif shape == "ring":
            # Standing on the floor: its bottom in the floor's plane (coplanar faces).
            name = f"ring{k}.obj"
            files[name], _ = ring_obj(r)
            y0 = 0.0 if floor else center[1]
            objects[-1]["center"] = [center[0], y0, center[2]]
            ang = r.uniform(0, 360)
            shapes.append(
                f'<shape type="obj"><string name="filename" value="{name}"/>'
                f'<boolean name="face_normals" value="true"/><transform name="to_world">'
                f'<scale value="{size:.5g}"/><rotate y="1" angle="{ang:.4g}"/>'
                f'<translate x="{center[0]:.5g}" y="{y0:.5g}" z="{center[2]:.5g}"/>'
                f'<scale value="{scale:.5g}"/></transform>{bsdf}</shape>')
        elif shape == "thin_wall":
            # A pane of glass a few thousandths thick, standing or tilted.
            t = r.choice([0.002, 0.01, 0.05])
            bsdfs_used.add("dielectric")
            shapes.append(
                f'<shape type="cube"><transform name="to_world"><scale x="{size:.5g}" y="{size:.5g}" z="{t:.5g}"/>'
                f'<rotate y="1" angle="{r.uniform(0, 360):.4g}"/><rotate x="1" angle="{r.uniform(-40, 40):.4g}"/>'
                f'<translate x="{center[0]:.5g}" y="{center[1]:.5g}" z="{center[2]:.5g}"/>'
                f'<scale value="{scale:.5g}"/></transform>{bsdf_xml(r, "dielectric")}</shape>')
        elif shape == "nested":
            # A dielectric sphere inside (or touching) another of a different index, 0.1% apart,
            # but never closer than 3e-4 in the world: Mitsuba's fixed ray offset (about
            # 1e-4 (1 + |p|)) jumps a narrower gap, and such a scene measures Mitsuba's offset,
            # not hppm (scenes 1078 and 1171 of the first long runs, at scale 0.01).
            bsdfs_used.add("dielectric")
            inner = size * r.choice([0.5, 0.8, 1.0])  # 1.0: the two surfaces coincide
            inner = min(inner * 0.999, size - 3e-4 / drawn)
            shapes.append(f'<shape type="sphere">{placement(r, scale, center, size, uniform=True)}'
                          f'{bsdf_xml(r, "dielectric")}</shape>')
            shapes.append(f'<shape type="sphere">{placement(r, scale, center, inner, uniform=True)}'
                          f'{bsdf_xml(r, "dielectric")}</shape>')

    # Emitters: one or two, of every kind.
    environment = False
    for _ in range(r.choice([1, 1, 2])):
        kind = r.choice(["area_rect", "area_rect", "area_sphere", "point", "spot", "directional",
                         "constant"])
        power = r.uniform(0.5, 2.0)
        emitters.append(kind)
        if kind in ("area_rect", "area_sphere"):
            d = normalize([r.uniform(-1, 1), r.uniform(0.4, 1.2), r.uniform(-1, 1)])
            dist = r.uniform(3, 5)
            pos = [x * dist for x in d]
            size = r.uniform(0.2, 1.0)
            radiance = power * 12.0 * dist * dist / (size * size)
            area_lights.append((pos, size * math.sqrt(2) if kind == "area_rect" else size * 0.5))
            if kind == "area_rect":
                target = [0, 0.3, 0]
                up = [0, 1, 0] if abs(d[1]) < 0.95 else [1, 0, 0]
                shapes.append(
                    f'<shape type="rectangle"><transform name="to_world"><scale value="{size:.5g}"/>'
                    f'<lookat origin="{fmt(pos)}" target="{fmt(target)}" up="{fmt(up)}"/>'
                    f'<scale value="{scale:.5g}"/></transform>'
                    f'<bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>'
                    f'<emitter type="area"><rgb name="radiance" value="{fmt([radiance] * 3)}"/></emitter></shape>')
            else:
                radiance /= math.pi
                shapes.append(
                    f'<shape type="sphere"><point name="center" value="{fmt([x * scale for x in pos])}"/>'
                    f'<float name="radius" value="{size * 0.5 * scale:.5g}"/>'
                    f'<emitter type="area"><rgb name="radiance" value="{fmt([radiance] * 3)}"/></emitter></shape>')
        elif kind in ("point", "spot"):
            d = normalize([r.uniform(-1, 1), r.uniform(0.3, 1.2), r.uniform(-1, 1)])
            dist = r.uniform(2, 4)
            pos = [x * dist * scale for x in d]
            intensity = power * 3.0 * dist * dist * scale * scale
            lights.append(kind)
            if kind == "point":
                lights_xml = (f'<emitter type="point"><point name="position" value="{fmt(pos)}"/>'
                              f'<rgb name="intensity" value="{fmt([intensity] * 3)}"/></emitter>')
            else:
                cutoff = r.uniform(15, 50)
                lights_xml = (f'<emitter type="spot"><transform name="to_world">'
                              f'<lookat origin="{fmt(pos)}" target="0, 0, 0" up="0, 1, 0.01"/></transform>'
                              f'<rgb name="intensity" value="{fmt([intensity] * 3)}"/>'
                              f'<float name="cutoff_angle" value="{cutoff:.4g}"/>'
                              f'<float name="beam_width" value="{cutoff * r.uniform(0.4, 0.95):.4g}"/></emitter>')
            shapes.append(lights_xml)
        elif kind == "directional":
            lights.append(kind)
            d = normalize([r.uniform(-1, 1), -r.uniform(0.3, 1.2), r.uniform(-1, 1)])
            shapes.append(f'<emitter type="directional"><vector name="direction" value="{fmt(d)}"/>'
                          f'<rgb name="irradiance" value="{fmt([power * 2.0] * 3)}"/></emitter>')
        else:
            radiance = rgb(r, 0.1, 0.6)
            # A scene has at most one environment (Mitsuba refuses two): a second draw of one
            # adds nothing, and the draws after it stay those of the scenes before this fix.
            if not environment:
                environment = True
                shapes.append(f'<emitter type="constant"><rgb name="radiance" value="{fmt(radiance)}"/></emitter>')

    # Camera: from a random direction, a little above the floor when there is one.
    az = r.uniform(0, 2 * math.pi)
    el = r.uniform(0.1, 1.2) if floor else r.uniform(-1.2, 1.2)
    dist = r.uniform(4.5, 8)
    origin = [dist * math.cos(el) * math.cos(az), dist * math.sin(el), dist * math.cos(el) * math.sin(az)]
    target = [r.uniform(-0.3, 0.3), r.uniform(0, 0.6), r.uniform(-0.3, 0.3)]
    fov = r.uniform(30, 60)

    integrator, header, declarations, sensor_medium = "path", "", [], ""
    if media:
        declarations, sensor_medium, what = add_media(
            index, scale, floor, shapes, objects, emitters, area_lights, bsdfs_used, origin)
        integrator, header = "volpath", f", with media: {'; '.join(what)}"

    hybrid = not (lights and bsdfs_used & DELTA_BSDFS)
    xml = f"""<scene version="3.0.0">
    <!-- tests/differential/generate.py, scene {index} (scale {drawn:.4g}){header} -->
    <default name="spp" value="64"/>
    <default name="max_depth" value="{MAX_DEPTH}"/>
""" + "".join(f"    {d}\n" for d in declarations) + f"""    <integrator type="{integrator}">
        <integer name="max_depth" value="$max_depth"/>
        <integer name="rr_depth" value="1000"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="{fov:.4g}"/>
        <string name="fov_axis" value="x"/>
        <float name="near_clip" value="{0.001 * scale:.4g}"/>
        <float name="far_clip" value="{1000 * scale:.4g}"/>{sensor_medium}
        <transform name="to_world">
            <lookat origin="{fmt([x * scale for x in origin])}" target="{fmt([x * scale for x in target])}" up="0, 1, 0"/>
        </transform>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="{SIZE}"/>
            <integer name="height" value="{SIZE}"/>
            <rfilter type="box"/>
            <string name="pixel_format" value="rgb"/>
        </film>
    </sensor>
""" + "".join(f"    {s}\n" for s in shapes) + "</scene>\n"
    return xml, files, hybrid


# --- media (--media) ---------------------------------------------------------------------------

# A radius bounding each object the scene draws, in units of its size (non-uniform scales reach
# 1.5 times the size; a ring's bound is about the middle of its base).
BOUND = {"sphere": 1.0, "cube": 1.5 * math.sqrt(3), "rectangle": 1.5 * math.sqrt(2),
         "disk": 1.5 * math.sqrt(2), "obj": 1.5, "obj_smooth": 1.5, "ply": 1.5 * math.sqrt(3),
         "ring": math.sqrt(2), "thin_wall": math.sqrt(2) + 0.2, "nested": 1.0}
# The scale a media scene's reference is rendered at. Mitsuba 3.9.1's volpath ends a shadow ray
# at its full length less ShadowEpsilon (8.9e-4 of it), but every `null` surface it crosses moves
# the ray's origin by a fixed offset (about 8.9e-5 (1 + |p|)) that it does not subtract: where
# the offsets add up to more than the margin, the ray reaches the emitter's own surface and is
# blocked. At scale 0.01 that is nearly every shadow ray through a null boundary (a fog box lit
# from outside renders parts of the image 3 to 100s of times too dark, with or without
# `sample_emitters`, and at 0.05 half too dark, while at 0.1, 1 and 100 it matches hppm, whose
# image is the same at every scale); at scale 1 only rays shorter than about (1 + |p|) / 10 can
# be (the generator keeps null boundaries 1 away from area lights). The image does
# not depend on the scale (lengths times k, sigma_t over k, intensities times k^2), so the
# reference of a media scene is Mitsuba's render of the same scene written at MEDIA_UNIT.
MEDIA_UNIT = 1.0
# Emitters no path hits: Mitsuba's volpath reaches them from a medium by light sampling only.
DELTA_EMITTERS = {"point", "spot", "directional", "projector"}


def phase_xml(m):
    kind = m.choice(["default", "isotropic", "hg", "hg", "rayleigh"])
    if kind == "default":
        return "", "isotropic (default)"
    if kind == "hg":
        g = m.uniform(-0.7, 0.9)
        return f'<phase type="hg"><float name="g" value="{g:.4g}"/></phase>', f"hg g {g:.2f}"
    return f'<phase type="{kind}"/>', kind


def medium_xml(m, attr, sigma_t, albedo, scale):
    """A homogeneous medium: `sigma_t` per unit length of the scene before its scale (RGB),
    `albedo` (RGB, written as a float when grey). The scene scale divides sigma_t either in the
    value written or through the medium's own `scale`, as drawn. A coloured sigma_t is written
    as an RGB of at most 1 (Mitsuba's RGB variants refuse an `rgb` above 1 there), its magnitude
    in `scale`. Returns the XML and its words."""
    phase, phase_words = phase_xml(m)
    world = [x / scale for x in sigma_t]
    coin = m.random()  # drawn whatever the scale: a scene at another unit draws the same
    if max(sigma_t) == min(sigma_t):
        if coin < 0.5:
            coeffs = f'<float name="sigma_t" value="{world[0]:.6g}"/>'
        else:
            coeffs = f'<float name="sigma_t" value="{sigma_t[0]:.6g}"/><float name="scale" value="{1 / scale:.6g}"/>'
    elif max(world) <= 1 and coin < 0.5:
        coeffs = f'<rgb name="sigma_t" value="{fmt(world)}"/>'
    else:
        top = max(world)
        coeffs = (f'<rgb name="sigma_t" value="{fmt([x / top for x in world])}"/>'
                  f'<float name="scale" value="{top:.6g}"/>')
    if max(albedo) == min(albedo):
        coeffs += f'<float name="albedo" value="{albedo[0]:.4g}"/>'
    else:
        coeffs += f'<rgb name="albedo" value="{fmt(albedo)}"/>'
    words = f"albedo {fmt([round(a, 2) for a in albedo])}, {phase_words}"
    return f'<medium type="homogeneous" {attr}>{coeffs}{phase}</medium>', words


def colour(m, lo, hi, grey_odds=0.4):
    """A value in [lo, hi], the same in every channel with probability grey_odds."""
    if m.random() < grey_odds:
        return [m.uniform(lo, hi)] * 3
    return [m.uniform(lo, hi) for _ in range(3)]


def thickness(m, lo, hi):
    """Optical thicknesses in [lo, hi] (log-uniform), grey or coloured."""
    base = math.exp(m.uniform(math.log(lo), math.log(hi)))
    if m.random() < 0.4:
        return [base] * 3
    return [min(hi, max(lo, base * m.uniform(0.4, 1.6))) for _ in range(3)]


def add_media(index, scale, floor, shapes, objects, emitters, area_lights, bsdfs_used, camera):
    """Draws the media of scene `index` (`--media`) from a stream of their own, so the scene
    under them is the one the index gives without media. Changes `shapes` (interiors added,
    shapes appended) and `bsdfs_used`; returns the medium declarations to put before the
    sensor, the sensor's medium (XML inside <sensor>) and a description.

    - Absorbing glass: some of the scene's glass spheres and cubes (`dielectric`,
      `roughdielectric`) get an interior of albedo 0..0.3 and a coloured sigma_t, optical
      thickness 0.05..3 across; new glass spheres and cubes may be added with one.
    - Scattering blobs: `null` spheres and cubes holding a medium of albedo 0.5..0.95, optical
      thickness 0.3..5 across, phase isotropic (given or by default), hg (g in -0.7..0.9) or
      rayleigh.
    - Fog, in half the scenes: a `null` box around every object (optical thickness 0.2..1.2
      over its largest half-extent; the sensor gets the fog too when the camera is inside it),
      or, where a light is not at infinity, a sensor medium without boundaries (optical
      thickness 0.1..0.6 over the camera's distance), so the whole scene is in fog (light from
      the environment and from directional emitters does not reach into it).
    Media never overlap one another (their bounding spheres apart), so every boundary a path
    crosses names the media on both its sides; shapes with an interior inside fog name the fog
    as their exterior. No `null` boundary passes within 1 of an area light (blobs are placed
    away from them, a fog box grows to take in any within 1 of it, with 1 to spare): Mitsuba's
    short shadow rays through a null surface can be blocked (MEDIA_UNIT). Media are given
    nested or by reference, their sigma_t scaled by 1/scale (the scene's lengths are), in the
    value or through the medium's `scale`."""
    m = random.Random(f"media {index}")
    declarations, what = [], []
    fog_kind = None
    if m.random() < 0.5:
        local = any(k in ("area_rect", "area_sphere", "point", "spot") for k in emitters)
        fog_kind = "sensor" if local and m.random() < 0.4 else "box"
    exterior = '<ref name="exterior" id="fog"/>' if fog_kind else ""
    media_objects = []  # (centre, bound) of every shape with an interior

    def apart(center, bound, null=False):
        return all(math.dist(center, c) > bound + b for c, b in media_objects) and \
            math.dist(center, camera) > bound + 0.1 and \
            not (null and any(math.dist(center, c) < bound + b + 1 for c, b in area_lights))

    def interior(attr_id, sigma_t, albedo):
        """A shape's interior: nested, or declared at the top with an id and referenced."""
        if m.random() < 0.5:
            xml, words = medium_xml(m, 'name="interior"', sigma_t, albedo, scale)
            return xml + exterior, words
        xml, words = medium_xml(m, f'id="{attr_id}"', sigma_t, albedo, scale)
        declarations.append(xml)
        return f'<ref name="interior" id="{attr_id}"/>' + exterior, words

    def glass_medium(size):
        tau = [m.uniform(0.05, 3.0) for _ in range(3)]
        words = f"optical thickness {fmt([round(t, 2) for t in tau])} across, "
        return [t / (2 * size) for t in tau], [m.uniform(0.0, 0.3) for _ in range(3)], words

    # Absorbing glass from the scene's own glass spheres and cubes.
    for k, o in enumerate(objects):
        if o["shape"] in ("sphere", "cube") and o["kind"] in ("dielectric", "roughdielectric") \
                and m.random() < 0.6 and apart(o["center"], o["bound"]):
            sigma_t, albedo, tau_words = glass_medium(o["size"])
            xml, words = interior(f"glass{k}", sigma_t, albedo)
            words = tau_words + words
            shapes[o["at"]] = shapes[o["at"]][:-len("</shape>")] + xml + "</shape>"
            media_objects.append((o["center"], o["bound"]))
            what.append(f"absorbing {o['kind']} {o['shape']} ({words})")

    # New blobs and glass.
    count = m.choice([1, 1, 2]) if media_objects else m.choice([1, 2, 2])
    new_objects = []
    for k in range(count):
        kind = "blob" if m.random() < 0.65 else m.choice(["dielectric", "dielectric", "roughdielectric"])
        shape = m.choice(["sphere", "sphere", "cube"])
        for _ in range(30):
            size = m.uniform(0.3, 0.9)
            center = [m.uniform(-1.5, 1.5), size if floor else m.uniform(-1, 1.5), m.uniform(-1.5, 1.5)]
            if apart(center, size * BOUND[shape], null=kind == "blob"):
                break
        else:
            continue
        media_objects.append((center, size * BOUND[shape]))
        new_objects.append(dict(shape=shape, center=center, bound=size * BOUND[shape]))
        place = placement(m, scale, center, size, uniform=shape == "sphere", mirror_ok=False)
        if kind == "blob":
            tau = thickness(m, 0.3, 5.0)
            sigma_t, albedo = [t / (2 * size) for t in tau], colour(m, 0.5, 0.95)
            bsdf = '<bsdf type="null"/>'
            label = f"scattering {shape} (optical thickness {fmt([round(t, 2) for t in tau])} across"
        else:
            bsdfs_used.add(kind)
            sigma_t, albedo, tau_words = glass_medium(size)
            bsdf = bsdf_xml(m, kind)
            label = f"absorbing {kind} {shape} ({tau_words}"
        xml, words = interior(f"medium{k}", sigma_t, albedo)
        shapes.append(f'<shape type="{shape}">{place}{bsdf}{xml}</shape>')
        what.append(f"{label}{', ' if kind == 'blob' else ''}{words})")

    sensor_medium = ""
    if fog_kind == "box":
        things = objects + new_objects
        lo = [min(o["center"][i] - o["bound"] for o in things) - 0.1 for i in range(3)]
        hi = [max(o["center"][i] + o["bound"] for o in things) + 0.1 for i in range(3)]
        for c, b in area_lights:
            gap = math.dist(c, [min(max(x, l), h) for x, l, h in zip(c, lo, hi)])
            if gap < b + 1:
                lo = [min(l, x - b - 1) for l, x in zip(lo, c)]
                hi = [max(h, x + b + 1) for h, x in zip(hi, c)]
        half = [(h - l) / 2 for l, h in zip(lo, hi)]
        middle = [(h + l) / 2 for l, h in zip(lo, hi)]
        tau = thickness(m, 0.2, 1.2)
        xml, words = medium_xml(m, 'id="fog"', [t / max(half) for t in tau], colour(m, 0.3, 0.95), scale)
        declarations.append(xml)
        shapes.append(
            f'<shape type="cube"><transform name="to_world">'
            f'<scale x="{half[0]:.5g}" y="{half[1]:.5g}" z="{half[2]:.5g}"/>'
            f'<translate x="{middle[0]:.5g}" y="{middle[1]:.5g}" z="{middle[2]:.5g}"/>'
            f'<scale value="{scale:.5g}"/></transform><bsdf type="null"/>'
            f'<ref name="interior" id="fog"/></shape>')
        inside = all(l < c < h for l, c, h in zip(lo, camera, hi))
        if inside:
            sensor_medium = '\n        <ref name="medium" id="fog"/>'
        what.append(f"fog box (optical thickness {fmt([round(t, 2) for t in tau])} over its half-extent, "
                    f"{words}{', camera inside' if inside else ''})")
    elif fog_kind == "sensor":
        tau = thickness(m, 0.1, 0.6)
        dist = math.sqrt(sum(x * x for x in camera))
        xml, words = medium_xml(m, 'id="fog"', [t / dist for t in tau], colour(m, 0.3, 0.95), scale)
        declarations.append(xml)
        sensor_medium = '\n        <ref name="medium" id="fog"/>'
        what.append(f"sensor fog, no boundary (optical thickness {fmt([round(t, 2) for t in tau])} "
                    f"over the camera's distance, {words})")
    return declarations, sensor_medium, what


def reference_copies(text):
    """The scenes whose Mitsuba renders add up to the reference of the scene `text`: the scene
    itself where it has no medium. With media, Mitsuba 3.9.1's `volpath` is biased dark where it
    samples an area light from a point in a medium and the shadow ray leaves the medium through
    a `null` boundary (docs/light-transport.md: 8-13% on a fog-filled Cornell box, its light
    0.01 above the fog), so the light of emitters a path can hit (area lights, environments) is
    rendered from a copy without the delta emitters and with `sample_emitters` false in every
    medium (phase sampling only); that of delta emitters (point, spot, directional), which phase
    sampling never hits, from a copy holding only them, with the scene's own `sample_emitters`
    (measured against hppm through a null boundary at scale 1, a light 0.01 above a fog box:
    point, spot and directional within 1.4 standard errors, where an area light there renders
    10% dark). The scene hppm reads keeps Mitsuba's default (light sampling in media)."""
    if "<medium" not in text:
        return [text]
    import xml.etree.ElementTree as ET

    def copy(keep_delta):
        root = ET.fromstring(text)
        for parent in list(root.iter()):
            for e in [e for e in parent if e.tag == "emitter"]:
                if (e.get("type") in DELTA_EMITTERS) != keep_delta:
                    parent.remove(e)
        if not keep_delta:
            for medium in root.iter("medium"):
                for b in [b for b in medium if b.get("name") == "sample_emitters"]:
                    medium.remove(b)
                ET.SubElement(medium, "boolean", name="sample_emitters", value="false")
        return ET.tostring(root, encoding="unicode")

    kinds = [e.get("type") for e in ET.fromstring(text).iter("emitter")]
    return ([copy(False)] if any(k not in DELTA_EMITTERS for k in kinds) else []) + \
        ([copy(True)] if any(k in DELTA_EMITTERS for k in kinds) else [])


def render_reference(scene_path, spp, batches, text=None):
    """Mitsuba's image of the scene at `scene_path` (or of `text`, a scene to read in its place,
    beside it), and each pixel's standard error: the mean of `batches` renders."""
    import mitsuba as mi
    import numpy as np
    mi.set_variant("llvm_ad_rgb")
    given = text is not None
    if not given:
        with open(scene_path) as f:
            text = f.read()
    copies = reference_copies(text)
    if not given and copies == [text]:
        scenes = [mi.load_file(scene_path)]
    else:
        # Each copy beside the scene, so that its meshes' relative paths resolve.
        scenes = []
        for k, copy in enumerate(copies):
            path = os.path.join(os.path.dirname(os.path.abspath(scene_path)), f"_reference{k}.xml")
            with open(path, "w") as f:
                f.write(copy)
            try:
                scenes.append(mi.load_file(path))
            finally:
                os.remove(path)
    images = []
    per = max(1, spp // batches)
    for b in range(batches):
        img = sum(np.array(mi.render(scene, spp=per, seed=b * 1_000_003 + 17 + 7919 * k), dtype=np.float64)
                  for k, scene in enumerate(scenes))
        images.append(img)
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    se = stack.std(axis=0, ddof=1) / math.sqrt(batches)
    return mean, se


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--first", type=int, default=0)
    p.add_argument("--count", type=int, default=40)
    p.add_argument("--out", default="tests/differential/corpus")
    p.add_argument("--spp", type=int, default=16384, help="reference samples per pixel")
    p.add_argument("--batches", type=int, default=16)
    p.add_argument("--media", action="store_true", help="add participating media to every scene")
    p.add_argument("--check", help="an hppm binary that must load every scene")
    p.add_argument("--no-references", action="store_true")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    manifest = []
    for index in range(a.first, a.first + a.count):
        xml, files, hybrid = generate(index, a.media)
        d = os.path.join(a.out, f"{index:04d}")
        os.makedirs(d, exist_ok=True)
        for name, text in files.items():
            with open(os.path.join(d, name), "w") as f:
                f.write(text)
        scene_path = os.path.join(d, "scene.xml")
        with open(scene_path, "w") as f:
            f.write(xml)
        if a.check:
            out = subprocess.run([a.check, "render", scene_path, "--graph", "graphs/pt.ron", "--spp", "1",
                                  "--size", "8x8", "--out", os.path.join(d, "_check.exr")],
                                 capture_output=True, text=True)
            if os.path.exists(os.path.join(d, "_check.exr")):
                os.remove(os.path.join(d, "_check.exr"))
            if out.returncode != 0:
                sys.exit(f"hppm refuses scene {index} ({scene_path}):\n{out.stderr}")
        if not a.no_references:
            import mitsuba as mi
            # Media at scale 1: Mitsuba's volpath is not scale-invariant (see MEDIA_UNIT).
            text = generate(index, True, unit=MEDIA_UNIT)[0] if a.media else None
            mean, se = render_reference(scene_path, a.spp, a.batches, text)
            mi.Bitmap(mean.astype("float32")).write(os.path.join(d, "reference.exr"))
            mi.Bitmap(se.astype("float32")).write(os.path.join(d, "reference_se.exr"))
        manifest.append(f"{index:04d} pt" + (" hybrid" if hybrid else ""))
        print(manifest[-1], flush=True)
    path = os.path.join(a.out, "manifest.txt")
    header = [] if os.path.exists(path) else [f"# reference_spp {a.spp}"]
    with open(path, "a") as f:
        f.write("".join(line + "\n" for line in header + manifest))


if __name__ == "__main__":
    main()
