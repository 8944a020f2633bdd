#!/usr/bin/env python3
"""Prints what Mitsuba 3 itself evaluates from the grids make_smoke.py writes, as Rust rows that
tests/vol_grid.rs hard-codes (made with mitsuba 3.9.1, variant scalar_rgb):

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 mitsuba_values.py

Each volume is `mi.load_dict({'type': 'gridvolume', 'filename': ..., ...})` with an identity
`to_world`, so a world point is the point of the unit cube the lookup uses (unless
`use_grid_bbox`, which maps the file's bounding box onto it); values are `vol.eval(it)` with
`it = mi.Interaction3f(); it.p = point`, and `vol.max()`. Floats are printed with 9 significant
digits (exact for f32).
"""

import os

import mitsuba as mi

mi.set_variant('scalar_rgb')
HERE = os.path.dirname(os.path.abspath(__file__))

INSIDE = [
    (0.5, 0.5, 0.5), (0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (0.123, 0.456, 0.789),
    (0.9, 0.1, 0.35), (0.37, 0.61, 0.52), (0.25, 0.75, 0.5),
    (3.5 / 24, 7.5 / 24, 11.5 / 24), (0.02, 0.98, 0.5), (0.5, 0.3, 0.45),
]
OUTSIDE = [(-0.2, 0.5, 1.3), (1.1, -0.05, 0.5), (2.3, 0.4, -0.7), (-1.37, 0.61, 0.52)]
# World points for use_grid_bbox (the file's bbox of smoke.vol is [-1, 1]^3).
BBOX_WORLD = [(0.0, 0.0, 0.0), (-0.5, 0.25, 0.1), (0.8, -0.9, 0.3), (-1.0, 1.0, -1.0)]


def g(v):
    return '%.9g' % v


def fmt(x):
    s = g(x)
    return s if ('.' in s or 'e' in s or 'n' in s) else s + '.0'


def show(name, props, points):
    vol = mi.load_dict(dict({'type': 'gridvolume',
                             'filename': os.path.join(HERE, name)}, **props))
    print('// %s %s max %s' % (name, props, g(vol.max())))
    for p in points:
        it = mi.Interaction3f()
        it.p = mi.Point3f(*p)
        v = vol.eval(it)
        print('([%s], [%s]),' % (', '.join(fmt(c) for c in mi.Point3f(*p)),
                                 ', '.join(fmt(c) for c in v)))


show('smoke.vol', {}, INSIDE + OUTSIDE)
show('smoke.vol', {'filter_type': 'nearest'}, INSIDE + OUTSIDE)
show('smoke.vol', {'wrap_mode': 'repeat'}, OUTSIDE)
show('smoke.vol', {'wrap_mode': 'mirror'}, OUTSIDE)
show('smoke.vol', {'wrap_mode': 'mirror', 'filter_type': 'nearest'}, OUTSIDE)
show('smoke.vol', {'use_grid_bbox': True}, BBOX_WORLD)
show('ramp.vol', {}, [(x, 0.3, 0.8) for x in (-0.5, 0.0, 0.2, 0.25, 0.4, 0.5, 0.7, 0.75, 1.0)])
show('rgb.vol', {}, INSIDE)
