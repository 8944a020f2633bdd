#!/usr/bin/env python3
"""Write sunsky_rgb.bin: the fields of Mitsuba 3.9.1's sunsky datasets that its RGB variants use,
in Mitsuba's own TensorFile format (include/mitsuba/core/tensor.h, src/core/tensor.cpp), for
src/scene/sunsky (read with include_bytes!, so an installed hppm needs no data files).

Usage:
  python3 extract_rgb.py [MITSUBA_DATA_DIR]
MITSUBA_DATA_DIR defaults to the `data/sunsky` folder of the installed `mitsuba` package
(pip install mitsuba==3.9.1); it holds sunsky_datasets.bin, sampling_data.bin and LICENSE
(BSD-3, Hosek and Wilkie; copied beside this script).

Fields kept (everything else, the spectral datasets and the sampling tables, is left out):
  sky_params_rgb  (10 turbidities, 2 albedos, 6 elevation control points, 3 channels, 9 params)
  sky_rad_rgb     (10, 2, 6, 3)
  sun_rad_rgb     (10 turbidities, 45 elevation segments, 3 channels, 4 polynomial
                   coefficients, 6 limb-darkening powers): `complex_sun` only
  sun_irradiance  (10 turbidities, 30 elevations 2..89 degrees, 11 wavelengths 320..720 nm),
                  from sampling_data.bin
Mitsuba stores the first three as float64 and converts them to its Float, float32 in the RGB
variants, when it loads them (`load_field` in include/mitsuba/render/sunsky.h); they are written
here as float32, the values Mitsuba computes with. sun_irradiance is float32 already.

TensorFile layout: "tensor_file\\0", version (2 bytes: 1, 0), field count (u32); per field its
name length (u16), name, dimension count (u16), dtype (u8: 10 float32, 11 float64, drjit's
VarType), data offset from the file's start (u64), each dimension (u64); then the data,
little-endian, row-major.
"""
import os
import struct
import sys

import numpy as np

FIELDS = [('sunsky_datasets.bin', 'sky_params_rgb'), ('sunsky_datasets.bin', 'sky_rad_rgb'),
          ('sunsky_datasets.bin', 'sun_rad_rgb'), ('sampling_data.bin', 'sun_irradiance')]
DTYPES = {10: '<f4', 11: '<f8'}


def read_tensor_file(path):
    data = open(path, 'rb').read()
    assert data[:12] == b'tensor_file\0', f'{path}: not a tensor file'
    (count,) = struct.unpack_from('<I', data, 14)
    at, fields = 18, {}
    for _ in range(count):
        (length,) = struct.unpack_from('<H', data, at)
        name = data[at + 2:at + 2 + length].decode()
        at += 2 + length
        ndim, dtype, offset = struct.unpack_from('<HBQ', data, at)
        at += 11
        shape = struct.unpack_from(f'<{ndim}Q', data, at)
        at += 8 * ndim
        fields[name] = np.frombuffer(data, DTYPES[dtype], int(np.prod(shape)), offset).reshape(shape)
    return fields


def write_tensor_file(path, fields):
    header = b'tensor_file\0' + bytes([1, 0]) + struct.pack('<I', len(fields))
    size = len(header) + sum(2 + len(n) + 2 + 1 + 8 + 8 * a.ndim for n, a in fields)
    offset = (size + 7) // 8 * 8
    entries, blobs = b'', b''
    for name, array in fields:
        entries += struct.pack('<H', len(name)) + name.encode()
        entries += struct.pack('<HBQ', array.ndim, 10, offset + len(blobs))
        entries += struct.pack(f'<{array.ndim}Q', *array.shape)
        blobs += array.astype('<f4').tobytes()
    out = header + entries
    out += b'\0' * (offset - len(out))
    open(path, 'wb').write(out + blobs)


def main():
    if len(sys.argv) > 1:
        source = sys.argv[1]
    else:
        import mitsuba
        source = os.path.join(os.path.dirname(mitsuba.__file__), 'data', 'sunsky')
    files = {}
    kept = []
    for file, name in FIELDS:
        if file not in files:
            files[file] = read_tensor_file(os.path.join(source, file))
        kept.append((name, files[file][name].astype(np.float32)))
    here = os.path.dirname(os.path.abspath(__file__))
    out = os.path.join(here, 'sunsky_rgb.bin')
    write_tensor_file(out, kept)
    again = read_tensor_file(out)
    for name, array in kept:
        assert np.array_equal(again[name], array), name
        print(name, array.shape)
    print(out, os.path.getsize(out), 'bytes')


if __name__ == '__main__':
    main()
