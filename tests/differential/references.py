#!/usr/bin/env python3
"""Mitsuba 3 references for hand-written scenes kept beside the generated corpus.

    python3 tests/differential/references.py tests/differential/plugins [--spp 16384]

Each sub-folder of the given folder that holds a scene.xml gets reference.exr and
reference_se.exr, rendered exactly as generate.py renders the corpus's (the mean of 16
independent Mitsuba renders, and each pixel's standard error from their spread). The folder's
manifest.txt is written by hand: which graphs render each scene. Needs
`pip install mitsuba==3.9.1 numpy` and DRJIT_LIBLLVM_PATH (see generate.py).
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from generate import render_reference  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("folder")
    p.add_argument("--spp", type=int, default=16384)
    p.add_argument("--batches", type=int, default=16)
    p.add_argument("--only", nargs="*", help="render only these sub-folders")
    a = p.parse_args()
    import mitsuba as mi
    for name in sorted(os.listdir(a.folder)):
        scene = os.path.join(a.folder, name, "scene.xml")
        if not os.path.exists(scene) or (a.only and name not in a.only):
            continue
        mean, se = render_reference(scene, a.spp, a.batches)
        mi.Bitmap(mean.astype("float32")).write(os.path.join(a.folder, name, "reference.exr"))
        mi.Bitmap(se.astype("float32")).write(os.path.join(a.folder, name, "reference_se.exr"))
        print(name, flush=True)


if __name__ == "__main__":
    main()
