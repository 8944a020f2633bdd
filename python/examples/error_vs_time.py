"""Error against render time for three graphs on one scene, measured and estimated.

A notebook-style script (each `# %%` is a cell in VS Code or Jupyter): renders the Cornell box
with a glass sphere through `pt`, `hybrid` and `hybrid_pppm` progressively and after each
stretch of rendering records the relMSE against Mitsuba 3's converged image
(tests/refs/images) and hppm's own estimate, which needs no reference. Run from a clone:

    python python/examples/error_vs_time.py --out error.png          # about a minute
    python python/examples/error_vs_time.py --quick --out error.png  # a few seconds
"""

# %%
import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import hppm

REPO = Path(__file__).resolve().parents[2]
parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--quick", action="store_true", help="2 s per graph instead of 20")
parser.add_argument("--out", default="error_vs_time.png")
args = parser.parse_args()

scene = hppm.load_scene(REPO / "tests/refs/scenes/cornell_glass_sphere/scene.xml")
reference = hppm.read_exr(REPO / "tests/refs/images/cornell_glass_sphere.exr")
graphs = ["pt", "hybrid"] if args.quick else ["pt", "hybrid", "hybrid_pppm"]
seconds = 2.0 if args.quick else 20.0
print(f"{scene!r} on {hppm.device()}")


# %%
def error_curve(graph):
    """(seconds rendered, measured relMSE, estimated relMSE) after stretches that double."""
    renderer = hppm.Renderer(scene, graph, seed=1)
    renderer.iterate()  # the first iteration compiles the pipelines: not counted
    curve, rendered, stretch = [], 0.0, 0.125
    while rendered < seconds:
        rendered += renderer.run(time=stretch)["seconds"]
        estimate = renderer.error_estimate()
        measured = hppm.relmse(renderer.image(), reference)
        curve.append((rendered, measured, estimate["relmse"] if estimate else float("nan")))
        stretch = min(2 * stretch, seconds - rendered)
    print(f"{graph}: {renderer!r}, relMSE {measured:.2e} (estimated {curve[-1][2]:.2e})")
    return curve


curves = {graph: error_curve(graph) for graph in graphs}

# %%
figure, axes = plt.subplots(figsize=(6, 4.5))
for (graph, curve), colour in zip(curves.items(), ["C0", "C1", "C2"]):
    t, measured, estimated = zip(*curve)
    axes.plot(t, measured, "-o", color=colour, label=f"{graph}: against Mitsuba's reference")
    axes.plot(t, estimated, "--", color=colour, label=f"{graph}: hppm's estimate")
axes.set(xscale="log", yscale="log", xlabel="seconds rendered", ylabel="relMSE")
axes.set_title("Cornell box, glass sphere, 128x128")
axes.legend(fontsize=8)
figure.tight_layout()
figure.savefig(args.out, dpi=120)
print(f"wrote {args.out}")
