"""Meshes, point clouds, files, simplification and distances."""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _check, jobs
from . import _lodkit as _native
from .errors import InputError, OptionError

PathLike = Union[str, "os.PathLike[str]"]

#: Most samples per kind a measurement may take (the CLI's ``--samples`` bound).
MAX_SAMPLES: int = _check.LIMITS["samples"][1]
#: Largest ``heap_size``.
MAX_HEAP_SIZE: int = _check.LIMITS["heap_size"][1]
#: Most levels of a halving chain.
MAX_LEVELS: int = _check.LIMITS["levels"][1]


def _opt_array(a):
    return None if a is None else np.asarray(a)


_FLOATS = (np.float32, np.float64)
_INDICES = (np.int32, np.int64, np.uint32, np.uint64)


def _describe(a: np.ndarray) -> str:
    return "an array of dtype %s and shape %s" % (a.dtype, a.shape)


def _check_array(name: str, a: np.ndarray, cols: Tuple[int, ...], dtypes: Tuple[Any, ...],
                 what: str, rows: Optional[Tuple[int, str]] = None, n: str = "n") -> None:
    """``InputError`` unless ``a`` is one of ``dtypes``, 2-D with ``cols``
    columns and (when given) ``rows[0]`` rows (``rows[1]`` names what they
    count), worded as the native readers word it; O(1), nothing is read."""
    shape = "(%s, %s)" % (n, " or ".join(str(c) for c in cols))
    if not any(a.dtype == d for d in dtypes):
        raise InputError("%s: expected %s of shape %s, got %s" % (name, what, shape, _describe(a)))
    if a.ndim != 2 or a.shape[1] not in cols:
        got = "(%d, %d)" % a.shape if a.ndim == 2 else "shape %s" % (a.shape,)
        raise InputError("%s: expected shape %s, got %s" % (name, shape, got))
    if rows is not None and a.shape[0] != rows[0]:
        raise InputError("%s: has %d rows but %s (one per vertex is needed)"
                         % (name, a.shape[0], rows[1]))


def _check_attributes(n: int, of: str, normals, colors, uvs=None) -> None:
    rows = (n, of)
    if normals is not None:
        _check_array("normals", normals, (3,), _FLOATS, "a float32 or float64 array", rows)
    if colors is not None:
        _check_array("colors", colors, (3, 4), (np.uint8,) + _FLOATS,
                     "a uint8 array (0..255) or a float array (0..1)", rows)
    if uvs is not None:
        _check_array("uvs", uvs, (2,), _FLOATS, "a float32 or float64 array", rows)


@dataclass(eq=False)
class Mesh:
    """An indexed triangle mesh of numpy arrays.

    - ``vertices``: (n, 3) float32 or float64, object units.
    - ``faces``: (m, 3) integer indices into ``vertices``, counter-clockwise
      seen from outside (any of int32, int64, uint32, uint64).
    - ``normals``: optional (n, 3) float per-vertex normals.
    - ``colors``: optional (n, 4) or (n, 3) per-vertex colours, uint8
      (0..255) or float (0..1); lodkit returns uint8 RGBA.
    - ``uvs``: optional (n, 2) float texture coordinates, origin bottom-left.

    Arrays are kept as given (``np.asarray``: no copy for an ndarray) and
    read in place by every call. Meshes lodkit returns have float32
    vertices and uint32 faces that numpy owns (no copy was made). Shapes
    and dtypes are checked here (:class:`~pylodkit.InputError`, a
    ``ValueError``, naming the array); face indices are checked by the
    call that reads them.

    Example::

        >>> import numpy as np, pylodkit as lk
        >>> tetra = lk.Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32),
        ...                 np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
        >>> tetra
        Mesh(4 vertices, 4 faces)
    """

    vertices: np.ndarray
    faces: np.ndarray
    normals: Optional[np.ndarray] = None
    colors: Optional[np.ndarray] = None
    uvs: Optional[np.ndarray] = None

    def __post_init__(self) -> None:
        self.vertices = np.asarray(self.vertices)
        self.faces = np.asarray(self.faces)
        self.normals = _opt_array(self.normals)
        self.colors = _opt_array(self.colors)
        self.uvs = _opt_array(self.uvs)
        _check_array("vertices", self.vertices, (3,), _FLOATS, "a float32 or float64 array")
        if self.faces.size == 0 and self.faces.ndim < 2:
            self.faces = np.zeros((0, 3), np.uint32)  # [] or np.array([]): no faces
        _check_array("faces", self.faces, (3,), _INDICES,
                     "an int32, int64, uint32 or uint64 array", n="m")
        _check_attributes(self.n_vertices, "the mesh has %d vertices" % self.n_vertices,
                          self.normals, self.colors, self.uvs)

    @property
    def n_vertices(self) -> int:
        """Number of vertices."""
        return int(self.vertices.shape[0])

    @property
    def n_faces(self) -> int:
        """Number of triangles."""
        return int(self.faces.shape[0])

    def attributes(self) -> List[str]:
        """Names of the attributes present, e.g. ``["normals", "colors"]``."""
        return [k for k in ("normals", "colors", "uvs") if getattr(self, k) is not None]

    def __repr__(self) -> str:
        extra = "".join(", " + a for a in self.attributes())
        return "Mesh(%d vertices, %d faces%s)" % (self.n_vertices, self.n_faces, extra)


@dataclass(eq=False)
class PointCloud:
    """Points with optional per-point normals and colours.

    - ``points``: (n, 3) float32 or float64.
    - ``normals``: optional (n, 3) float.
    - ``colors``: optional (n, 4) or (n, 3) uint8 or float in [0, 1].

    Shapes and dtypes are checked here (:class:`~pylodkit.InputError`).

    Example::

        >>> import numpy as np, pylodkit as lk
        >>> lk.PointCloud(np.random.default_rng(0).normal(size=(1000, 3)))
        PointCloud(1000 points)
    """

    points: np.ndarray
    normals: Optional[np.ndarray] = None
    colors: Optional[np.ndarray] = None

    def __post_init__(self) -> None:
        self.points = np.asarray(self.points)
        self.normals = _opt_array(self.normals)
        self.colors = _opt_array(self.colors)
        _check_array("points", self.points, (3,), _FLOATS, "a float32 or float64 array")
        _check_attributes(len(self), "the cloud has %d points" % len(self), self.normals,
                          self.colors)

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def __repr__(self) -> str:
        extra = "".join(", " + a for a in ("normals", "colors") if getattr(self, a) is not None)
        return "PointCloud(%d points%s)" % (len(self), extra)


Geometry = Union[Mesh, PointCloud]


def _as_input(obj: Any) -> Any:
    """What every call reads: a ``trimesh.Trimesh`` or an open3d geometry
    through :func:`from_trimesh` / :func:`from_open3d` (so their vertex
    colours and UVs come along), anything else as it is."""
    module = type(obj).__module__ or ""
    if module.startswith("trimesh") and hasattr(obj, "faces") and hasattr(obj, "visual"):
        return from_trimesh(obj)
    if module.startswith("open3d") and (hasattr(obj, "triangles") or hasattr(obj, "points")):
        return from_open3d(obj)
    return obj


def _is_path(obj: Any) -> bool:
    """Whether ``obj`` names a file (a job on files reads it)."""
    return isinstance(obj, (str, os.PathLike))


def _in_memory(**file_options: Any) -> None:
    """``OptionError`` for an option of the jobs on files given with an
    in-memory mesh."""
    for name, v in file_options.items():
        if v is not None and v is not False:
            raise OptionError("%s: applies when the input is a path, not an in-memory mesh" % name)


def _wrap(kind: str, d: Dict[str, Any]) -> Geometry:
    return Mesh(**d) if kind == "mesh" else PointCloud(**d)


def load(path: PathLike) -> Geometry:
    """Reads a mesh or point-cloud file (.ply, .obj, .stl, .gltf, .glb, .xyz, .pts).

    The format follows the extension (``.txt`` reads as XYZ); a PLY range
    grid becomes its valid samples as a :class:`PointCloud`. Errors:
    :class:`~pylodkit.FileError` when the file cannot be read,
    :class:`~pylodkit.InputError` when it is malformed — with the CLI's
    message, naming the file. The GIL is released while reading.

    Example::

        >>> mesh = lk.load("bunny.ply")
        >>> mesh.n_faces
        69451
    """
    kind, d = _native.load(os.fspath(path))
    return _wrap(kind, d)


def save(obj: Union[Geometry, Any], path: PathLike, *, ascii: bool = False) -> None:
    """Writes a mesh or point cloud; the format follows the extension.

    Meshes: .ply, .obj, .stl, .glb (and .xyz/.pts for their vertices);
    point clouds: .ply, .xyz, .pts. PLY and STL are binary unless
    ``ascii``. The write is atomic (temporary file, fsync, rename) and
    deterministic, as every lodkit writer. Anything with ``vertices`` and
    ``faces`` arrays is a mesh (a ``trimesh.Trimesh`` too).

    Example::

        >>> lk.save(lk.bunny(), "bunny.glb")
    """
    _native.save(_as_input(obj), os.fspath(path), ascii)


def bunny() -> Mesh:
    """The Stanford bunny (35,947 vertices, 69,451 faces), built in as in ``lodkit build``.

    Example::

        >>> lk.bunny()
        Mesh(35947 vertices, 69451 faces)
    """
    return Mesh(**_native.bunny())


def blob(triangles: int, seed: int = _check.DEFAULTS["noise_seed"]) -> Mesh:
    """A noise-displaced sphere of about ``triangles`` faces (closed, genus 0).

    The benchmarks' stand-in for a dense scan; deterministic for a seed.

    Example::

        >>> lk.blob(1_000_000).n_faces
        1002252
    """
    _check.integer("triangles", triangles, 1, 1 << 30)
    _check.integer("seed", seed, 0, 2**32 - 1)
    return Mesh(**_native.blob(triangles, seed))


def icosphere(level: int) -> Mesh:
    """The unit icosphere with 20 × 4**level faces (``level`` in 0..=8).

    Example::

        >>> lk.icosphere(3).n_faces
        1280
    """
    _check.integer("level", level, 0, 8)
    return Mesh(**_native.icosphere(level))


def _simplify_options(max_error, lock_border, fill_holes, heap_size, normal_weight,
                      color_weight, uv_weight, prune) -> Dict[str, Any]:
    return dict(
        max_error=_check.within("max_error", max_error, "max_error"),
        lock_border=bool(lock_border),
        fill_holes=bool(fill_holes),
        heap_size=_check.within("heap_size", heap_size, "heap_size"),
        normal_weight=_check.within("normal_weight", normal_weight, "weight"),
        color_weight=_check.within("color_weight", color_weight, "weight"),
        uv_weight=_check.within("uv_weight", uv_weight, "weight"),
        prune=_check.within("prune", prune, "prune"),
    )


def simplify(
    mesh: Any,
    target: Optional[int] = None,
    *,
    ratio: Optional[float] = None,
    max_error: Optional[float] = None,
    lock_border: bool = False,
    fill_holes: bool = True,
    heap_size: int = _check.DEFAULTS["heap_size"],
    normal_weight: float = _check.DEFAULTS["normal_weight"],
    color_weight: float = _check.DEFAULTS["color_weight"],
    uv_weight: float = _check.DEFAULTS["uv_weight"],
    prune: Optional[float] = None,
    output: Optional[PathLike] = None,
    merge: bool = False,
    memory: Optional[int] = None,
    progress: Optional[Callable[[Dict[str, Any]], Any]] = None,
) -> Any:
    """Simplifies a mesh to a budget with lodkit's HQMS simplifier (``lodkit simplify``).

    ``mesh`` may also be a path: the library's ``simplify`` job then reads
    it (a mesh or a scene, any format lodkit reads) and writes ``output``
    (required; the format follows its extension, written atomically), in
    core, or out of core in blocks when a binary PLY or STL needs more than
    ``memory`` bytes (``LIMITS["memory"]``; default a third of the
    machine's memory), exactly as ``lodkit simplify IN -o OUT`` does; a
    scene keeps its materials in a .glb or .obj output unless ``merge``.
    It returns ``lodkit simplify --json``'s report (a dict). Either way
    the simplification is the library's (a mesh in memory: its in-core
    step), and its events go to ``progress`` (see :mod:`pylodkit.jobs`).

    ``mesh`` is a :class:`Mesh`, a ``trimesh.Trimesh`` or an open3d
    ``TriangleMesh`` (converted as :func:`from_trimesh` / :func:`from_open3d`
    convert them, colours and UVs kept), or any object with ``vertices``
    and ``faces`` arrays. Give ``target`` (triangles), ``ratio`` (fraction of the input's
    triangles, in [0, 1]) or ``max_error`` (stop before a collapse whose
    estimated error, in input units, would exceed it), or an error with a
    budget. The other options and their defaults are the CLI's:
    ``lock_border`` keeps border vertices in place, ``fill_holes=False``
    keeps every hole, ``heap_size`` (1..=2**24) is the replacement-selection
    heap, the weights (0..=1e6) price normals, colours and UVs in the cost,
    ``prune`` (in [0, 1)) removes components smaller than that fraction of
    the diagonal first. Attributes are interpolated; seams are kept.

    Returns ``(mesh, report)``; the report has ``lodkit simplify --json``'s
    figures: ``input_triangles``, ``target_triangles``, ``triangles``,
    ``vertices``, ``estimated_error``, ``passes``, ``collapses``, ``stop``
    (why it stopped, in words) and ``seconds`` (the simplifier's own time).
    Deterministic; the GIL is released while it runs.

    Example::

        >>> lod, report = lk.simplify(lk.bunny(), ratio=0.1)
        >>> report["triangles"] <= 6945, report["stop"]
        (True, 'reached the target')
    """
    if target is not None and ratio is not None:
        raise OptionError("target and ratio conflict: give one of them")
    if target is None and ratio is None and max_error is None:
        raise OptionError("give target=FACES, ratio=R or max_error=E")
    t = _check.within("target", target, "target")
    r = _check.within("ratio", ratio, "ratio")
    opts = _simplify_options(max_error, lock_border, fill_holes, heap_size, normal_weight,
                             color_weight, uv_weight, prune)
    if _is_path(mesh):
        if output is None:
            raise OptionError("output: give the path to write when the input is a file")
        return jobs.simplify_file(mesh, output, t, r, opts, merge=merge, memory=memory,
                                  progress=progress)
    _in_memory(output=output, merge=merge, memory=memory)
    d, report = _native.simplify(_as_input(mesh), t, r, progress=jobs._progress(progress), **opts)
    return Mesh(**d), report


def check_ratios_fall(name: str, ratios: Sequence[float]) -> None:
    """``OptionError`` unless each ratio is smaller than the one before
    (a level as large as the one before would repeat it)."""
    for a, b in zip(ratios, ratios[1:]):
        if not b < a:
            raise OptionError("%s=%r: each level must be smaller than the one before, "
                              "but %r is followed by %r" % (name, list(ratios), a, b))


def lod_chain(
    mesh: Any,
    levels: Optional[int] = None,
    *,
    ratios: Optional[Sequence[float]] = None,
    measure: bool = True,
    samples: Optional[int] = None,
    max_error: Optional[float] = None,
    lock_border: bool = False,
    fill_holes: bool = True,
    heap_size: int = _check.DEFAULTS["heap_size"],
    normal_weight: float = _check.DEFAULTS["normal_weight"],
    color_weight: float = _check.DEFAULTS["color_weight"],
    uv_weight: float = _check.DEFAULTS["uv_weight"],
    prune: Optional[float] = None,
    out: Optional[PathLike] = None,
    merge: bool = False,
    memory: Optional[int] = None,
    progress: Optional[Callable[[Dict[str, Any]], Any]] = None,
) -> Any:
    """A discrete LOD chain, each level simplified from the previous one (``lodkit lods``).

    ``mesh`` may also be a path: the library's LOD chain job then reads it
    and writes ``STEM_lodN.ply`` per level (``.glb`` for a scene, unless
    ``merge``), ``STEM_lods.glb`` and ``lods.json`` into the folder ``out``
    (required), in core, or out of core when a binary PLY or STL needs
    more than ``memory`` bytes (levels then not measured), exactly as
    ``lodkit lods IN --out DIR`` does. It returns ``lods.json`` as a dict
    and sends the job's events to ``progress`` (a ``level`` event per level
    written; see :mod:`pylodkit.jobs`); ``measure=False`` is for in-memory
    meshes only.

    ``levels`` (1..=32, default 6) halves the triangles per level (1/2,
    1/4, ...); ``ratios`` gives each level's fraction of the input instead,
    each smaller than the one before (else :class:`~pylodkit.OptionError`).
    Every level has fewer triangles than the one before: a chain that
    stalls (no valid collapse left, ``max_error``) ends at its last new
    level, so fewer levels than asked may come back; the last report's
    ``chain_end`` then says why (it is ``None`` otherwise).
    With ``measure`` (the default, as ``lods.json``), each level's
    symmetric Metro distance to the input is measured: ``samples`` per
    kind, by default 4 per face of the level within 50,000..=1,000,000.
    The simplifier options are :func:`simplify`'s.

    Returns one ``(mesh, report)`` per level; each report has
    :func:`simplify`'s keys plus ``level``, ``measured_mean_error``,
    ``measured_max_error`` (object units; ``None`` when not measured) and
    ``samples``. The GIL is released while it runs.

    Example::

        >>> chain = lk.lod_chain(lk.bunny(), levels=3)
        >>> [r["triangles"] for _, r in chain]
        [34725, 17361, 8680]
    """
    if levels is not None and ratios is not None:
        raise OptionError("levels and ratios conflict: give one of them")
    if _is_path(mesh):
        if out is None:
            raise OptionError("out: give the folder to write when the input is a file")
        if not measure:
            raise OptionError("measure=False: a chain made from a file is always measured")
        rs = None if ratios is None else [_check.within("ratios", r, "ratio") for r in ratios]
        if rs is not None:
            if not rs:
                raise OptionError("ratios: give at least one fraction in [0, 1]")
            check_ratios_fall("ratios", rs)
        n = _check.within("levels", levels, "levels")
        s = _check.within("samples", samples, "samples")
        opts = _simplify_options(max_error, lock_border, fill_holes, heap_size, normal_weight,
                                 color_weight, uv_weight, prune)
        return jobs.lod_chain_file(mesh, out, rs, n, s, opts, merge=merge, memory=memory,
                                   progress=progress)
    _in_memory(out=out, merge=merge, memory=memory, progress=progress)
    if ratios is None:
        n = _check.within("levels", _check.DEFAULTS["levels"] if levels is None else levels, "levels")
        rs = [0.5 ** (i + 1) for i in range(n)]
    else:
        rs = [_check.within("ratios", r, "ratio") for r in ratios]
        if not rs:
            raise OptionError("ratios: give at least one fraction in [0, 1]")
        check_ratios_fall("ratios", rs)
    s = _check.within("samples", samples, "samples")
    opts = _simplify_options(max_error, lock_border, fill_holes, heap_size, normal_weight,
                             color_weight, uv_weight, prune)
    out = _native.lod_chain(_as_input(mesh), rs, measure=bool(measure), samples=s, **opts)
    return [(Mesh(**d), r) for d, r in out]


def compare(
    a: Any,
    b: Any,
    *,
    samples: Optional[int] = None,
    seed: int = _check.DEFAULTS["seed"],
    vertex_samples: bool = True,
    edge_samples: bool = True,
    face_samples: bool = True,
    heatmap: Optional[PathLike] = None,
    progress: Optional[Callable[[Dict[str, Any]], Any]] = None,
) -> Dict[str, Any]:
    """Metro-style distances between two meshes (``lodkit compare --json``).

    ``a`` and ``b`` may both be paths: the library's ``compare`` job then
    reads them and, given ``heatmap`` (.ply, .obj or .glb), also writes
    ``b`` coloured by each vertex's distance to ``a`` there (the report
    then has a ``heatmap`` entry), exactly as ``lodkit compare A B
    --heatmap FILE`` does. Either way the measurement is the library's, and
    its events go to ``progress`` (see :mod:`pylodkit.jobs`).

    Samples each surface on its vertices, edges and faces (``samples`` of
    each kind per mesh, 1..=10,000,000; default max(10 × faces of the
    larger mesh, 1M), at most 10M) and measures them against the other.
    Deterministic for a ``seed``.

    Returns the CLI's JSON as a dict: ``a_to_b`` and ``b_to_a`` (samples,
    min, max, mean, rms, max_at, diagonal, max_pct, mean_pct, rms_pct),
    ``symmetric`` (samples, max, mean, rms, diagonal, *_pct: each the larger
    of the two directions, percentages of the union's diagonal),
    ``samples_per_kind`` and ``seed``. The GIL is released while it runs.

    Example::

        >>> lod, _ = lk.simplify(lk.bunny(), ratio=0.1)
        >>> r = lk.compare(lk.bunny(), lod)
        >>> round(r["symmetric"]["mean_pct"], 4)
        0.0185
    """
    n = _check.within("samples", samples, "samples")
    _check.integer("seed", seed, 0, 2**64 - 1)
    if _is_path(a) and _is_path(b):
        return jobs.compare_files(a, b, n, seed, vertex_samples, edge_samples, face_samples,
                                  heatmap=heatmap, progress=progress)
    if _is_path(a) or _is_path(b):
        raise OptionError("a and b: give two paths or two meshes")
    _in_memory(heatmap=heatmap)
    return _native.compare(_as_input(a), _as_input(b), n, seed, bool(vertex_samples),
                           bool(edge_samples), bool(face_samples), jobs._progress(progress))


# -- trimesh and open3d -------------------------------------------------------

def from_trimesh(tm: Any, *, normals: bool = False) -> Mesh:
    """A :class:`Mesh` from a ``trimesh.Trimesh`` (its arrays, not copied).

    Vertex colours come along when ``tm.visual`` holds them, UVs when it is
    a texture visual with UVs; vertex normals only with ``normals=True``
    (trimesh computes them on demand).

    Example::

        >>> import trimesh
        >>> m = lk.from_trimesh(trimesh.creation.icosphere(3))
        >>> lod, _ = lk.simplify(m, ratio=0.5)
    """
    colors = uvs = None
    visual = getattr(tm, "visual", None)
    kind = getattr(visual, "kind", None)
    if kind == "vertex":
        colors = np.asarray(visual.vertex_colors)
    elif kind == "texture" and getattr(visual, "uv", None) is not None:
        uvs = np.asarray(visual.uv)
    return Mesh(
        np.asarray(tm.vertices),
        np.asarray(tm.faces),
        normals=np.asarray(tm.vertex_normals) if normals else None,
        colors=colors,
        uvs=uvs,
    )


def to_trimesh(mesh: Mesh, **kwargs: Any) -> Any:
    """A ``trimesh.Trimesh`` of a :class:`Mesh` (``process=False``: vertices kept as they are).

    Normals become ``vertex_normals``, colours ``vertex_colors``, UVs a
    ``TextureVisuals``. Extra keywords go to ``trimesh.Trimesh``.

    Example::

        >>> tm = lk.to_trimesh(lk.bunny())
        >>> tm.is_watertight
        False
    """
    import trimesh

    kwargs.setdefault("process", False)
    visual = None
    if mesh.uvs is not None:
        visual = trimesh.visual.TextureVisuals(uv=mesh.uvs)
    elif mesh.colors is not None:
        visual = trimesh.visual.ColorVisuals(vertex_colors=mesh.colors)
    return trimesh.Trimesh(
        vertices=mesh.vertices,
        faces=mesh.faces.astype(np.int64, copy=False),
        vertex_normals=mesh.normals,
        visual=visual,
        **kwargs,
    )


def from_open3d(geometry: Any) -> Geometry:
    """A :class:`Mesh` from an ``open3d.geometry.TriangleMesh``, or a
    :class:`PointCloud` from an ``open3d.geometry.PointCloud``.

    Vertex normals and colours (open3d's float RGB in [0, 1]) come along
    when present.

    Example::

        >>> import open3d as o3d
        >>> m = lk.from_open3d(o3d.geometry.TriangleMesh.create_sphere())
    """
    if hasattr(geometry, "triangles"):
        return Mesh(
            np.asarray(geometry.vertices),
            np.asarray(geometry.triangles),
            normals=np.asarray(geometry.vertex_normals) if geometry.has_vertex_normals() else None,
            colors=np.asarray(geometry.vertex_colors) if geometry.has_vertex_colors() else None,
        )
    return PointCloud(
        np.asarray(geometry.points),
        normals=np.asarray(geometry.normals) if geometry.has_normals() else None,
        colors=np.asarray(geometry.colors) if geometry.has_colors() else None,
    )


def to_open3d(obj: Geometry) -> Any:
    """An ``open3d.geometry.TriangleMesh`` (or ``PointCloud``) of a lodkit geometry.

    Colours become open3d's float RGB in [0, 1] (alpha is dropped).

    Example::

        >>> o3d_mesh = lk.to_open3d(lk.bunny())
        >>> len(o3d_mesh.triangles)
        69451
    """
    import open3d as o3d

    def rgb(c):
        c = np.asarray(c)
        c = c[:, :3]
        return c.astype(np.float64) / 255.0 if c.dtype == np.uint8 else c.astype(np.float64)

    v3 = o3d.utility.Vector3dVector
    if isinstance(obj, PointCloud):
        pc = o3d.geometry.PointCloud(v3(np.asarray(obj.points, np.float64)))
        if obj.normals is not None:
            pc.normals = v3(np.asarray(obj.normals, np.float64))
        if obj.colors is not None:
            pc.colors = v3(rgb(obj.colors))
        return pc
    m = o3d.geometry.TriangleMesh(
        v3(np.asarray(obj.vertices, np.float64)),
        o3d.utility.Vector3iVector(np.asarray(obj.faces, np.int32)),
    )
    if obj.normals is not None:
        m.vertex_normals = v3(np.asarray(obj.normals, np.float64))
    if obj.colors is not None:
        m.vertex_colors = v3(rgb(obj.colors))
    return m


__all__ = [
    "Mesh", "PointCloud", "load", "save", "bunny", "blob", "icosphere", "simplify",
    "lod_chain", "compare", "from_trimesh", "to_trimesh", "from_open3d", "to_open3d",
    "MAX_SAMPLES", "MAX_HEAP_SIZE", "MAX_LEVELS",
]

