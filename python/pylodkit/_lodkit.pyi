"""Type stubs of the native module ``pylodkit._lodkit`` (Rust, PyO3).

These are the raw calls behind the public API; use :mod:`pylodkit`, which
checks option ranges and wraps results in ``Mesh`` / ``PointCloud``.
Mesh dicts have ``vertices`` float32 (n, 3), ``faces`` uint32 (m, 3),
``normals`` float32 (n, 3) | None, ``colors`` uint8 (n, 4) | None,
``uvs`` float32 (n, 2) | None; point dicts have ``points``, ``normals``,
``colors``. Every call releases the GIL while it computes.

Example::

    >>> from pylodkit import _lodkit
    >>> d, report = _lodkit.simplify(_lodkit.bunny(), None, 0.1)
"""
import os
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

MeshDict = Dict[str, Optional[np.ndarray]]
#: Every option range of ``lodkit::limits``: ``(lo, hi)`` or ``(lo, hi, lo_open, hi_open)``.
LIMITS: Dict[str, Tuple[Any, ...]]
DEFAULT_LEVELS: int
#: Every option's default by name (``lodkit::limits`` and the engines' option types).
DEFAULTS: Dict[str, Any]
#: A progress function: one dict per event of a job (see ``pylodkit.jobs``).
Progress = Optional[Callable[[Dict[str, Any]], Any]]

def load(path: str) -> Tuple[str, Dict[str, Optional[np.ndarray]]]:
    """``(kind, dict)`` of a file; kind is ``"mesh"`` or ``"points"``.

    Example: ``kind, d = load("bunny.ply")``
    """

def save(obj: Any, path: str, ascii: bool = False) -> None:
    """Writes a mesh-like or points-like object, atomically.

    Example: ``save(bunny(), "bunny.glb")``
    """

def bunny() -> MeshDict:
    """The built-in Stanford bunny. Example: ``bunny()["faces"].shape``"""

def blob(triangles: int, seed: int = ...) -> MeshDict:
    """A noise-displaced sphere of about ``triangles`` faces. Example: ``blob(10_000)``"""

def icosphere(level: int) -> MeshDict:
    """The unit icosphere, 20 × 4**level faces. Example: ``icosphere(3)``"""

def write_atomic(path: str, data: bytes) -> None:
    """lodkit's atomic write (temporary file, fsync, rename). Example: ``write_atomic("a.pop", data)``"""

def write_lod_glb(path: str, stem: str,
                  levels: List[Tuple[Any, int, Optional[Tuple[float, float]], float]]) -> None:
    """An LOD chain GLB as ``lodkit lods`` writes it: ``(mesh, lod, measured, estimated)`` per level, level 0 first."""

def simplify(
    mesh: Any,
    target: Optional[int] = None,
    ratio: Optional[float] = None,
    max_error: Optional[float] = None,
    lock_border: bool = False,
    fill_holes: bool = True,
    heap_size: int = ...,
    normal_weight: float = ...,
    color_weight: float = ...,
    uv_weight: float = ...,
    prune: Optional[float] = None,
    progress: Progress = None,
) -> Tuple[MeshDict, Dict[str, Any]]:
    """One mesh to one budget: ``(mesh dict, report)``. Example: ``simplify(bunny(), None, 0.1)``"""

def lod_chain(
    mesh: Any,
    ratios: Sequence[float],
    max_error: Optional[float] = None,
    lock_border: bool = False,
    fill_holes: bool = True,
    heap_size: int = ...,
    normal_weight: float = ...,
    color_weight: float = ...,
    uv_weight: float = ...,
    prune: Optional[float] = None,
    measure: bool = True,
    samples: Optional[int] = None,
) -> List[Tuple[MeshDict, Dict[str, Any]]]:
    """Each level from the previous. Example: ``lod_chain(bunny(), [0.5, 0.25])``"""

def tiles(
    input: str,
    out: str,
    leaf_triangles: Optional[int] = None,
    leaf_points: Optional[int] = None,
    skirts: bool = True,
    memory: Optional[int] = None,
    compress: bool = True,
) -> Dict[str, Any]: ...

def simplify_file(
    input: str, output: str, target: Optional[int] = None, ratio: Optional[float] = None,
    max_error: Optional[float] = None, lock_border: bool = False, fill_holes: bool = True,
    heap_size: int = ..., normal_weight: float = ..., color_weight: float = ...,
    uv_weight: float = ..., prune: Optional[float] = None, merge: bool = False,
    memory: Optional[int] = None, progress: Progress = None,
) -> Dict[str, Any]:
    """The ``simplify`` job: ``lodkit simplify IN -o OUT --json``'s report."""

def lod_chain_file(
    input: str, out: str, ratios: Optional[List[float]] = None, levels: Optional[int] = None,
    max_error: Optional[float] = None, lock_border: bool = False, fill_holes: bool = True,
    heap_size: int = ..., normal_weight: float = ..., color_weight: float = ...,
    uv_weight: float = ..., prune: Optional[float] = None, samples: Optional[int] = None,
    merge: bool = False, memory: Optional[int] = None, progress: Progress = None,
) -> Dict[str, Any]:
    """The ``lods`` job: ``lods.json`` as a dict."""

def build(
    input: Optional[str], out: str, levels: int = ..., samples: Optional[int] = None,
    measure: bool = True, merge: bool = False, progress: Progress = None,
) -> Dict[str, Any]:
    """The ``build`` job: ``{"model", "outputs": [[file, bytes], ...]}``."""

def compare_files(
    a: str, b: str, samples: Optional[int] = None, seed: int = ...,
    vertex_samples: bool = True, edge_samples: bool = True, face_samples: bool = True,
    heatmap: Optional[str] = None, progress: Progress = None,
) -> Dict[str, Any]:
    """The ``compare`` job: ``lodkit compare A B --json``."""

def render(
    input: str, output: str, azimuth: float = ..., elevation: float = ..., width: int = ...,
    height: int = ..., fov: float = ..., background: Sequence[int] = ..., smooth: bool = False,
    triangles: Optional[int] = None, lod: Optional[int] = None, level: Optional[int] = None,
    progress: Progress = None,
) -> Dict[str, Any]:
    """The ``render`` job, one view: ``lodkit render IN -o PNG --json``."""

def info(path: str, progress: Progress = None) -> Tuple[str, Dict[str, Any]]:
    """``(kind, dict)``: ``lodkit info FILE --json``; kind is ``model``, ``mco``, ``pop`` or ``image_set``."""

def compare(
    a: Any,
    b: Any,
    samples: Optional[int] = None,
    seed: int = ...,
    vertex_samples: bool = True,
    edge_samples: bool = True,
    face_samples: bool = True,
    progress: Progress = None,
) -> Dict[str, Any]:
    """``lodkit compare --json``'s report. Example: ``compare(bunny(), bunny())["symmetric"]["max"]``"""

class McoModel:
    """A built marching cube octree (immutable). Example: ``m = mco_build([bunny()])``"""

    @property
    def max_lod(self) -> int: ...
    @property
    def full_triangles(self) -> int: ...
    def triangles_at_lod(self, k: int) -> int:
        """Example: ``m.triangles_at_lod(m.max_lod)``"""
    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]:
        """Example: ``lo, hi = m.bounds()``"""
    def extract_triangles(self, triangles: int) -> Tuple[MeshDict, int]:
        """``(mesh dict, lod)``. Example: ``m.extract_triangles(10_000)``"""
    def extract_lod(self, lod: int) -> MeshDict:
        """Example: ``m.extract_lod(0)``"""
    def extract_view(
        self,
        position: Tuple[float, float, float],
        look_at: Optional[Tuple[float, float, float]] = None,
        fov: Optional[float] = None,
        viewport: Optional[float] = None,
        tolerance: Optional[float] = None,
    ) -> Tuple[MeshDict, int]:
        """``(mesh dict, expanded nodes)``. Example: ``m.extract_view((0, 0.1, 0.4))``"""
    def save(self, path: str) -> None:
        """Example: ``m.save("bunny.mco")``"""
    def to_bytes(self) -> bytes:
        """Example: ``m.to_bytes()[:4]``"""
    def info(self) -> Dict[str, Any]:
        """Example: ``m.info()["nodes"]``"""

def mco_build(inputs: Sequence[Any], resolution: Optional[int] = None, progress: Progress = None) -> McoModel:
    """Example: ``mco_build([bunny()], 128)``"""

def mco_load(path: str) -> McoModel:
    """Example: ``mco_load("bunny.mco")``"""

def mco_from_bytes(data: bytes) -> McoModel:
    """Example: ``mco_from_bytes(m.to_bytes())``"""

def pop_encode(
    obj: Any,
    depth: Optional[int] = None,
    precision: Optional[int] = None,
    mode: str = "entropy",
    placement: Optional[str] = None,
    outer_thinning: bool = False,
    relax_below: Optional[int] = None,
    normals: bool = False,
    colours: bool = True,
    raw: bool = False,
) -> Tuple[bytes, Dict[str, Any]]:
    """``(stream, report)``. Example: ``data, report = pop_encode(bunny())``"""

def pop_decode(
    data: bytes,
    level: Optional[int] = None,
    precision: Optional[int] = None,
    points: bool = False,
    decimate: Optional[float] = None,
    strict: bool = False,
) -> Tuple[str, Dict[str, Optional[np.ndarray]], Dict[str, Any]]:
    """``(kind, dict, info)``. Example: ``kind, d, info = pop_decode(data, 5)``"""

def block_task_count(path: Union[str, os.PathLike]) -> int:
    """Tasks in a block task file. Example: ``n = block_task_count("r0/tasks.json")``"""

def run_block_task(path: Union[str, os.PathLike], index: int) -> Tuple[int, int]:
    """``(faces_in, faces_out)``. Example: ``run_block_task("r0/tasks.json", 0)``"""
