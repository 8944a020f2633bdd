"""hppm: hybrid path tracing + progressive photon mapping on the GPU, as a render graph.

    import hppm
    scene = hppm.load_scene("scenes/cornell_glass_sphere.xml")
    image = hppm.render(scene, "hybrid", spp=64)      # float32 array, (height, width, 3)

`load_scene` takes Mitsuba's `-D` parameters as keywords; `load_graph` a RON file or the name
of a bundled graph; `Renderer` renders progressively (`iterate`, `run`, `image`,
`error_estimate`). Errors are `hppm.Error` subclasses (`SceneError`, `GraphError`, `GpuError`)
with `file`, `line` and `column`. See docs/python.md.
"""

from ._hppm import (
    Error,
    GpuError,
    Graph,
    GraphError,
    Renderer,
    Scene,
    SceneError,
    bundled_graphs,
    device,
    load_graph,
    load_scene,
    read_exr,
    relmse,
    render,
    write_image,
)

__all__ = [
    "Error",
    "GpuError",
    "Graph",
    "GraphError",
    "Renderer",
    "Scene",
    "SceneError",
    "bundled_graphs",
    "device",
    "load_graph",
    "load_scene",
    "read_exr",
    "relmse",
    "render",
    "write_image",
]

