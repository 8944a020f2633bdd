# Types of the extension module (python/src), for editors and type checkers.
from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike]
_Image = npt.NDArray[np.float32]  # (height, width, 3), linear RGB
_Progress = Callable[[Dict[str, Any]], Optional[bool]]

class Error(Exception):
    file: Optional[str]
    line: Optional[int]
    column: Optional[int]

class SceneError(Error): ...
class GraphError(Error): ...
class GpuError(Error): ...

class Scene:
    path: str
    size: Tuple[int, int]
    spp: Optional[int]
    triangles: int
    features: str

class Graph:
    file: str
    text: str
    nodes: List[Tuple[str, str]]

class Renderer:
    iterations: int
    spp: int
    photons: int
    spp_per_iteration: int
    photons_per_iteration: int
    size: Tuple[int, int]
    seed: int
    pruned: List[str]
    def __init__(
        self,
        scene: Union[Scene, _Path],
        graph: Union[Graph, _Path, None] = None,
        *,
        size: Optional[Tuple[int, int]] = None,
        seed: int = 0,
    ) -> None: ...
    def iterate(self, n: int = 1) -> None: ...
    def run(
        self,
        *,
        spp: Optional[int] = None,
        time: Optional[float] = None,
        photons: Optional[int] = None,
        target_error: Optional[float] = None,
        adaptive: bool = False,
        progress: Optional[_Progress] = None,
    ) -> Dict[str, Any]: ...
    def image(self) -> _Image: ...
    def aovs(self) -> Dict[str, _Image]: ...
    def error_estimate(self) -> Optional[Dict[str, Any]]: ...
    def counters(self) -> Dict[str, int]: ...

def device(adapter: Optional[str] = None) -> str: ...
def load_scene(path: _Path, **params: Any) -> Scene: ...
def load_graph(name_or_path: _Path) -> Graph: ...
def bundled_graphs() -> List[str]: ...
def render(
    scene: Union[Scene, _Path],
    graph: Union[Graph, _Path, None] = None,
    *,
    spp: Optional[int] = None,
    time: Optional[float] = None,
    photons: Optional[int] = None,
    target_error: Optional[float] = None,
    adaptive: bool = False,
    seed: int = 0,
    size: Optional[Tuple[int, int]] = None,
    aovs: bool = False,
    progress: Optional[_Progress] = None,
) -> Union[_Image, Tuple[_Image, Dict[str, _Image]]]: ...
def read_exr(path: _Path) -> _Image: ...
def write_image(path: _Path, image: _Image) -> None: ...
def relmse(image: _Image, reference: _Image) -> float: ...
def cli(args: List[str]) -> int: ...
