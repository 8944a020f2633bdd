#!/usr/bin/env python3
"""Writes ring.obj: a thick-walled glass ring (a tube), axis +y, outer radius 0.5, inner 0.43,
height 0.3, SEGMENTS facets around, triangles counter-clockwise seen from outside (the glass's
outside, so the inner wall faces the axis). Flat-shaded: the scene sets face_normals.

    python3 make_ring.py > ring.obj
"""
import math

SEGMENTS = 128
OUTER, INNER = 0.5, 0.43
BOTTOM, TOP = 0.0, 0.3

vertices = []
for ring_radius in (OUTER, INNER):
    for y in (BOTTOM, TOP):
        for i in range(SEGMENTS):
            a = 2.0 * math.pi * i / SEGMENTS
            vertices.append((ring_radius * math.cos(a), y, ring_radius * math.sin(a)))


def vertex(outer, top, i):
    # 1-based OBJ index of corner i of the given circle.
    circle = (0 if outer else 2) + (1 if top else 0)
    return circle * SEGMENTS + i % SEGMENTS + 1


faces = []


def quad(a, b, c, d):
    faces.append((a, b, c))
    faces.append((a, c, d))


for i in range(SEGMENTS):
    j = i + 1
    # Angles grow from +x towards +z; seen from outside (+radial) that runs right to left.
    quad(vertex(True, False, i), vertex(True, True, i), vertex(True, True, j), vertex(True, False, j))
    quad(vertex(False, False, j), vertex(False, True, j), vertex(False, True, i), vertex(False, False, i))
    quad(vertex(True, True, i), vertex(False, True, i), vertex(False, True, j), vertex(True, True, j))
    quad(vertex(True, False, j), vertex(False, False, j), vertex(False, False, i), vertex(True, False, i))

print(f"# glass ring: {SEGMENTS} segments, outer {OUTER}, inner {INNER}, height {TOP - BOTTOM}")
for x, y, z in vertices:
    print(f"v {x:.6f} {y:.6f} {z:.6f}")
for a, b, c in faces:
    print(f"f {a} {b} {c}")
