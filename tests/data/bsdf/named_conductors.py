"""Prints the NAMED_CONDUCTORS table of src/bsdfs/conductor/named.rs: Mitsuba 3's measured conductor
spectra (the mitsuba-data repository's ior/*.spd) converted to RGB the way Mitsuba's RGB
variants convert them (include/mitsuba/render/ior.h, complex_ior_from_file ->
spectrum_list_to_srgb in src/core/spectrum.cpp: 1000 steps over 360-830 nm, linear
interpolation of the data, the CIE 1931 table, XYZ to linear sRGB, negatives clamped to 0).

    python3 named_conductors.py MITSUBA3_CHECKOUT MITSUBA_DATA_CHECKOUT
"""
import glob
import os
import re
import sys

mitsuba, data = sys.argv[1], sys.argv[2]
source = open(os.path.join(mitsuba, "src/core/spectrum.cpp")).read()
block = source[source.index("cie1931_tbl[MI_CIE_SAMPLES * 3]"):]
table = [float(v) for v in re.findall(r"Float\(([0-9.eE+-]+)\)", block.split("};")[0])]
N = 95
X, Y, Z = table[:N], table[N:2 * N], table[2 * N:3 * N]
LO, HI = 360.0, 830.0


def cie(w):
    t = (w - LO) * ((N - 1) / (HI - LO))
    i = min(max(int(t), 0), N - 2)
    f = t - i
    return [(1 - f) * a[i] + f * a[i + 1] for a in (X, Y, Z)]


def spd(path):
    ws, vs = [], []
    for line in open(path):
        cells = line.split("#")[0].split()
        if len(cells) == 2:
            ws.append(float(cells[0]))
            vs.append(float(cells[1]))
    return ws, vs


def to_rgb(ws, vs):
    xyz = [0.0, 0.0, 0.0]
    steps = 1000
    for i in range(steps):
        w = LO + (i / (steps - 1)) * (HI - LO)
        if w < ws[0] or w > ws[-1]:
            continue
        k = max(j for j in range(len(ws) - 1) if ws[j] <= w)
        w0, w1, v0, v1 = ws[k], ws[k + 1], vs[k], vs[k + 1]
        v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1)
        xyz = [s + c * v for s, c in zip(xyz, cie(w))]
    xyz = [s * (HI - LO) / 106.7502593994140625 / steps for s in xyz]
    m = [[3.240479, -1.537150, -0.498535], [-0.969256, 1.875991, 0.041556],
         [0.055648, -0.204043, 1.057311]]
    return [max(sum(m[r][c] * xyz[c] for c in range(3)), 0.0) for r in range(3)]


names = sorted({os.path.basename(p).split(".")[0] for p in glob.glob(os.path.join(data, "ior/*.eta.spd"))})
for n in names:
    e = to_rgb(*spd(os.path.join(data, f"ior/{n}.eta.spd")))
    k = to_rgb(*spd(os.path.join(data, f"ior/{n}.k.spd")))
    print(f'    ("{n}", [{e[0]:.6}, {e[1]:.6}, {e[2]:.6}], [{k[0]:.6}, {k[1]:.6}, {k[2]:.6}]),')
