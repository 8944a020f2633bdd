#!/usr/bin/env python3
"""Writes the small Mitsuba `serialized` files next to this script and what Mitsuba 3 reads
from them (mitsuba_3.9.1.txt), which src/loaders/serialized.rs's tests compare its reader with.

    python3 make_fixture.py     # needs `pip install mitsuba` (made with 3.9.1, scalar_rgb)

The files are written by this script's own writer (the format as Mitsuba 3's
src/shapes/serialized.cpp documents and reads it):

- two_shapes_v4.serialized (version 4, u64 offset table):
  shape 0 "cube": 24 vertices with normals, texture coordinates and vertex colours, single
  precision; shape 1 "tetra": 4 vertices without normals or texture coordinates, with colours,
  double precision, its FaceNormals flag set (Mitsuba 3 ignores that flag and computes vertex
  normals all the same: the fixture shows it).
- two_shapes_v3.serialized (version 3: no names, u32 offset table):
  shape 0: a quad of two triangles with texture coordinates, no normals, single precision;
  shape 1: a triangle with normals, double precision.

The fixture lists, per file and shape, Mitsuba's `mi.traverse(shape)` arrays: faces,
vertex_positions, vertex_normals and vertex_texcoords (an empty line when it has none), and the
shape's name, as `key value value ...` lines (floats with 9 significant digits, exact for f32).
"""

import os
import struct
import zlib

import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))

HAS_NORMALS, HAS_TEXCOORDS, HAS_COLORS = 0x1, 0x2, 0x8
FACE_NORMALS, SINGLE, DOUBLE = 0x10, 0x1000, 0x2000


def shape_bytes(version, name, positions, faces, normals=None, uvs=None, colors=None,
                double=False, face_normals=False):
    flags = DOUBLE if double else SINGLE
    flags |= HAS_NORMALS if normals else 0
    flags |= HAS_TEXCOORDS if uvs else 0
    flags |= HAS_COLORS if colors else 0
    flags |= FACE_NORMALS if face_normals else 0
    real = 'd' if double else 'f'
    body = struct.pack('<I', flags)
    if version == 4:
        body += name.encode() + b'\0'
    body += struct.pack('<QQ', len(positions), len(faces))
    for values in (positions, normals, uvs, colors):
        for v in values or []:
            body += struct.pack('<%d%s' % (len(v), real), *v)
    for f in faces:
        body += struct.pack('<3I', *f)
    return struct.pack('<HH', 0x041C, version) + zlib.compress(body)


def write_file(path, version, shapes):
    data, offsets = b'', []
    for s in shapes:
        offsets.append(len(data))
        data += shape_bytes(version, **s)
    entry = '<Q' if version == 4 else '<I'
    data += b''.join(struct.pack(entry, o) for o in offsets)
    data += struct.pack('<I', len(shapes))
    with open(path, 'wb') as f:
        f.write(data)


def cube():
    positions, normals, uvs, colors, faces = [], [], [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = sign
            u_axis, v_axis = (axis + 1) % 3, (axis + 2) % 3
            if sign < 0:
                u_axis, v_axis = v_axis, u_axis
            base = len(positions)
            for (a, b) in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis], p[u_axis], p[v_axis] = sign, a, b
                positions.append(p)
                normals.append(n)
                uvs.append([(a + 1) / 2, (b + 1) / 2])
                colors.append([0.25, 0.5, 0.75])
            faces += [(base, base + 1, base + 2), (base, base + 2, base + 3)]
    return dict(name='cube', positions=positions, faces=faces, normals=normals, uvs=uvs,
                colors=colors)


def tetra():
    positions = [[0.1, 0.2, 0.3], [1.3, 0.1, -0.2], [0.4, 1.7, 0.1], [0.5, 0.6, 1.1]]
    faces = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]
    colors = [[1.0, 0.0, 0.0]] * 4
    return dict(name='tetra', positions=positions, faces=faces, colors=colors, double=True,
                face_normals=True)


def quad():
    positions = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.5], [2.0, 1.0, 0.0], [0.0, 1.0, 0.25]]
    uvs = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
    return dict(name='', positions=positions, faces=[(0, 1, 2), (0, 2, 3)], uvs=uvs)


def triangle():
    positions = [[0.3, -0.1, 2.0], [1.0 / 3.0, 1.0, 2.0], [-0.7, 0.2, 2.1]]
    normals = [[0.0, 0.0, 1.0], [0.0, 0.6, 0.8], [0.6, 0.0, 0.8]]
    return dict(name='', positions=positions, faces=[(0, 1, 2)], normals=normals, double=True)


def main():
    mi.set_variant('scalar_rgb')
    files = [('two_shapes_v4.serialized', 4, [cube(), tetra()]),
             ('two_shapes_v3.serialized', 3, [quad(), triangle()])]
    lines = ['# Mitsuba %s (scalar_rgb) reading the files make_fixture.py wrote' % mi.__version__]
    for file, version, shapes in files:
        path = os.path.join(HERE, file)
        write_file(path, version, shapes)
        for index in range(len(shapes)):
            shape = mi.load_dict({'type': 'serialized', 'filename': path,
                                  'shape_index': index})
            params = mi.traverse(shape)
            lines.append('file %s' % file)
            lines.append('shape %d' % index)
            # The name is the file's (version 4), else Mitsuba's "file@index".
            name = str(shape).split('name = "', 1)[1].split('"', 1)[0]
            lines.append('name %s' % name)
            lines.append('faces ' + ' '.join(str(int(i)) for i in params['faces']))
            for key in ('vertex_positions', 'vertex_normals', 'vertex_texcoords'):
                values = params[key]
                lines.append(' '.join([key] + ['%.9g' % float(x) for x in values]))
    with open(os.path.join(HERE, 'mitsuba_3.9.1.txt'), 'w') as f:
        f.write('\n'.join(lines) + '\n')


if __name__ == '__main__':
    main()
