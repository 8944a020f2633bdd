#!/usr/bin/env python3
"""Writes ring.obj: a thin-walled ring (open tube) of radius 1 around the y axis, standing on
y = 0, height 0.35, wall thickness 0.03, with 256 segments. Inner wall, outer wall and top rim
share no vertices, so a renderer that smooths normals smooths only along each wall; the walls
carry exact radial vertex normals (`vn`), the rim its face normal."""
import math

SEGMENTS = 256
R_IN, R_OUT, HEIGHT = 1.0, 1.03, 0.35

v, vn, faces = [], [], []


def vert(x, y, z):
    v.append((x, y, z))
    return len(v)


def normal(x, y, z):
    vn.append((x, y, z))
    return len(vn)


def ring_points(r, y):
    return [(r * math.cos(2 * math.pi * i / SEGMENTS), y, r * math.sin(2 * math.pi * i / SEGMENTS))
            for i in range(SEGMENTS)]


def wall(r, inward):
    bottom = [vert(*p) for p in ring_points(r, 0.0)]
    top = [vert(*p) for p in ring_points(r, HEIGHT)]
    sign = -1.0 if inward else 1.0
    normals = [normal(sign * math.cos(2 * math.pi * i / SEGMENTS), 0.0,
                      sign * math.sin(2 * math.pi * i / SEGMENTS)) for i in range(SEGMENTS)]
    for i in range(SEGMENTS):
        j = (i + 1) % SEGMENTS
        quad = [(bottom[i], normals[i]), (bottom[j], normals[j]), (top[j], normals[j]), (top[i], normals[i])]
        # Counter-clockwise seen from the side the normal points to.
        if not inward:
            quad.reverse()
        faces.append(quad)


wall(R_IN, inward=True)
wall(R_OUT, inward=False)
up = normal(0.0, 1.0, 0.0)
inner = [vert(*p) for p in ring_points(R_IN, HEIGHT)]
outer = [vert(*p) for p in ring_points(R_OUT, HEIGHT)]
for i in range(SEGMENTS):
    j = (i + 1) % SEGMENTS
    faces.append([(inner[i], up), (inner[j], up), (outer[j], up), (outer[i], up)])

with open("ring.obj", "w") as f:
    f.write("# Thin-walled ring, written by make_ring.py\n")
    for p in v:
        f.write("v %.7f %.7f %.7f\n" % p)
    for n in vn:
        f.write("vn %.7f %.7f %.7f\n" % n)
    for quad in faces:
        a, b, c, d = quad
        for tri in ((a, b, c), (a, c, d)):
            f.write("f " + " ".join("%d//%d" % t for t in tri) + "\n")
