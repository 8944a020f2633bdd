#!/usr/bin/env python3
"""`auto` against the graphs it chooses among, at equal time, on scenes with Mitsuba references.

For each scene, one `hppm compare` command renders `auto`, `pt`, `hybrid` and `hybrid_pppm` for
the same time (default 60 s; `auto`'s pilots count in its time) against the scene's reference,
and the final relMSE of each is read from errors.csv. Prints a Markdown table: each graph's
relMSE, the best single graph, auto's choice, auto over the best and auto over pt. Run from the
repository root after `cargo build --release`:

    python3 benches/auto_choice.py [--time 60] [--out target/auto_choice] [SCENE_NAME ...]
"""

import argparse
import csv
import subprocess
import sys
from pathlib import Path

# (name, scene file, reference, size)
SCENES = [
    ("cornell_glass_sphere", "tests/refs/scenes/cornell_glass_sphere/scene.xml", "tests/refs/images/cornell_glass_sphere.exr", "128x128"),
    ("water_glass", "tests/refs/scenes/water_glass/scene.xml", "tests/refs/images/water_glass.exr", "128x128"),
    ("glass_ring_tilted", "tests/refs/scenes/glass_ring_tilted/scene.xml", "tests/refs/images/glass_ring_tilted.exr", "128x128"),
    ("point_light_caustic", "tests/refs/scenes/point_light_caustic/scene.xml", "tests/refs/images/point_light_caustic_composite.exr", "128x128"),
    ("cornell_diffuse", "tests/refs/scenes/cornell_diffuse/scene.xml", "tests/refs/images/cornell_diffuse.exr", "128x128"),
    ("materials_cornell", "tests/refs/scenes/materials_cornell/scene.xml", "tests/refs/images/materials_cornell.exr", "128x128"),
    ("lajolla_veach", "tests/data/mitsuba06/lajolla/veach_mi/mi.xml", "tests/refs/mitsuba06/images/lajolla_veach.exr", "96x64"),
    ("sdmm_volumetric_caustic", "tests/data/mitsuba06/sdmm/volumetric-caustic/volumetric-caustic.xml", "tests/refs/mitsuba06/images/sdmm_volumetric_caustic.exr", "64x64"),
]
GRAPHS = ["auto", "pt", "hybrid", "hybrid_pppm"]


def final_errors(errors_csv):
    last = {}
    with open(errors_csv) as f:
        for row in csv.DictReader(f):
            last[row["graph"]] = float(row["relmse"])
    return last


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--time", type=float, default=60.0)
    parser.add_argument("--out", default="target/auto_choice")
    parser.add_argument("--hppm", default="target/release/hppm")
    parser.add_argument("names", nargs="*")
    args = parser.parse_args()
    rows = []
    for name, scene, reference, size in SCENES:
        if args.names and name not in args.names:
            continue
        out = Path(args.out) / name
        command = [args.hppm, "compare", scene, "--reference", reference, "--size", size,
                   "--time", str(args.time), "--snapshots", "4", "--out", str(out)]
        for g in GRAPHS:
            command += ["--graph", g]
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            print(f"{name}: hppm compare failed:\n{done.stderr}", file=sys.stderr)
            continue
        chosen = next((l.split("auto: chose ")[1].split(" ")[0] for l in (done.stdout + done.stderr).splitlines()
                       if "auto: chose " in l), "?")
        errors = final_errors(out / "errors.csv")
        singles = {g: errors[g] for g in GRAPHS[1:]}
        best = min(singles, key=singles.get)
        rows.append((name, errors["auto"], singles, best, chosen))
        print(f"{name}: {errors} chose {chosen}", file=sys.stderr, flush=True)
    print(f"| scene | auto | pt | hybrid | hybrid_pppm | best alone | auto chose | auto / best | auto / pt |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, a, singles, best, chosen in rows:
        cells = " | ".join(f"{singles[g]:.3e}" for g in GRAPHS[1:])
        print(f"| {name} | {a:.3e} | {cells} | {best} | {chosen} | {a / singles[best]:.2f} | "
              f"{a / singles['pt']:.2f} |")


if __name__ == "__main__":
    main()
