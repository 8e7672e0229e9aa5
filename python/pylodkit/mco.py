"""Continuous level of detail: the marching cube octree (``lodkit mco``).

Build a model once from meshes, point clouds or scans, keep it as a
``.mco`` file, and cut it at any triangle budget, LOD number or camera::

    >>> import pylodkit as lk
    >>> model = lk.mco.build(lk.bunny())
    >>> lod = model.extract(triangles=10_000)
    >>> near = model.extract(view=(0.0, 0.1, 0.4), tolerance=1.0)
    >>> model.save("bunny.mco")
"""
from __future__ import annotations

import os
from typing import Any, Callable, Dict, Optional, Sequence, Tuple, Union

from . import _check
from . import _lodkit as _native
from ._core import Mesh, _as_input
from .errors import OptionError

#: Largest ``resolution`` of a build (the CLI's bound).
MAX_RESOLUTION: int = _check.LIMITS["resolution"][1]


class Model:
    """A built marching cube octree: one vertex buffer, every cut crack-free.

    Immutable; cuts release the GIL, so several threads may cut at once.

    Example::

        >>> model = lk.mco.build(lk.bunny())
        >>> model.max_lod, model.full_triangles
        (3129, 20362)
        >>> model.extract(lod=model.max_lod // 2)
        Mesh(6118 vertices, 11518 faces, normals)
    """

    def __init__(self, native: Any) -> None:
        self._m = native

    @property
    def max_lod(self) -> int:
        """The highest LOD number (every leaf cube drawn)."""
        return self._m.max_lod

    @property
    def full_triangles(self) -> int:
        """Triangles of the cut at ``max_lod``."""
        return self._m.full_triangles

    def triangles_at_lod(self, lod: int) -> int:
        """Exact triangle count of the cut at LOD number ``lod``.

        Example::

            >>> model.triangles_at_lod(model.max_lod) == model.full_triangles
            True
        """
        _check.integer("lod", lod, 0, self.max_lod)
        return self._m.triangles_at_lod(lod)

    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]:
        """The model's bounding box ``(min, max)``.

        Example::

            >>> lo, hi = model.bounds()
        """
        lo, hi = self._m.bounds()
        return tuple(lo), tuple(hi)

    def extract(
        self,
        *,
        triangles: Optional[int] = None,
        lod: Optional[int] = None,
        view: Optional[Sequence[float]] = None,
        look_at: Optional[Sequence[float]] = None,
        fov: Optional[float] = None,
        viewport: Optional[float] = None,
        tolerance: Optional[float] = None,
    ) -> Mesh:
        """One cut as a standalone :class:`Mesh` (``lodkit mco extract``).

        Give exactly one of:

        - ``triangles``: the cut nearest that budget;
        - ``lod``: the cut at that LOD number (``0..=max_lod``);
        - ``view=(x, y, z)``: the view-dependent cut for a camera there,
          looking at ``look_at`` (default: the model's centre), vertical
          field of view ``fov`` degrees in (0, 180) (default 60), a viewport
          ``viewport`` pixels high in [1, 65536] (default 1080), refined until
          each node's projected error is within ``tolerance`` pixels (> 0,
          default 1).

        Example::

            >>> model.extract(triangles=5_000).n_faces <= model.full_triangles
            True
        """
        given = [k for k, v in (("triangles", triangles), ("lod", lod), ("view", view)) if v is not None]
        if len(given) != 1:
            raise OptionError("give exactly one of triangles=, lod= or view= (got %s)"
                              % (", ".join(given) or "none"))
        if view is None:
            for name, v in (("look_at", look_at), ("fov", fov), ("viewport", viewport),
                            ("tolerance", tolerance)):
                if v is not None:
                    raise OptionError("%s applies to a view-dependent cut: give view=(x, y, z) too"
                                      % name)
        if triangles is not None:
            n = _check.integer("triangles", triangles, 0, 2**64 - 1)
            d, _ = self._m.extract_triangles(n)
            return Mesh(**d)
        if lod is not None:
            k = _check.integer("lod", lod, 0, 2**64 - 1)
            if k > self.max_lod:
                raise OptionError("lod=%d is outside 0..=%d for this model" % (k, self.max_lod))
            return Mesh(**self._m.extract_lod(k))
        pos = _vec3("view", view)
        target = None if look_at is None else _vec3("look_at", look_at)
        d, _ = self._m.extract_view(
            pos,
            target,
            _check.within("fov", fov, "view_fov"),
            _check.within("viewport", viewport, "viewport"),
            _check.within("tolerance", tolerance, "tolerance"),
        )
        return Mesh(**d)

    def save(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes the model as a ``.mco`` file (version 2), atomically.

        Example::

            >>> model.save("bunny.mco")
        """
        self._m.save(os.fspath(path))

    def to_bytes(self) -> bytes:
        """The ``.mco`` bytes :meth:`save` writes.

        Example::

            >>> lk.mco.from_bytes(model.to_bytes()).max_lod == model.max_lod
            True
        """
        return self._m.to_bytes()

    def info(self) -> Dict[str, Any]:
        """``lodkit mco info --json``'s model figures: resolution, cube,
        depth, vertices, nodes, lod_array, lod_numbers, full_triangles,
        crack_patches, input_samples, has_colors and per-level nodes and
        triangles (level 0 = the leaf cubes).

        Example::

            >>> model.info()["levels"][0]["triangles"] == model.full_triangles
            True
        """
        return self._m.info()

    def __repr__(self) -> str:
        return "mco.Model(max_lod=%d, full_triangles=%d)" % (self.max_lod, self.full_triangles)


def _vec3(name: str, v: Sequence[float]) -> Tuple[float, float, float]:
    try:
        xs = [float(x) for x in v]
    except (TypeError, ValueError):
        xs = []
    if len(xs) != 3:
        raise OptionError("%s=%r: expected X,Y,Z: three numbers, each a finite number" % (name, v))
    for x in xs:
        _check.real(name, x)
    return xs[0], xs[1], xs[2]


def build(inputs: Any, *more: Any, resolution: Optional[int] = None,
          progress: Optional[Callable[[Dict[str, Any]], Any]] = None) -> Model:
    """Builds a model from meshes, point clouds and files (``lodkit mco build``).

    ``inputs`` is one input or a list; each is a :class:`~pylodkit.Mesh`, a
    :class:`~pylodkit.PointCloud`, an (n, 3) array of points, a
    ``trimesh.Trimesh`` or open3d geometry (as :func:`~pylodkit.from_trimesh`
    / :func:`~pylodkit.from_open3d` convert them), anything with
    ``vertices``/``faces`` arrays, or a path (a ``.conf`` adds each posed
    scan it lists). All go on one lattice of ``resolution`` leaf cubes
    along the longest axis (``LIMITS["resolution"]``; default: for one
    mesh, a lattice whose full cut has about its triangle count, else a
    cube of twice the sample spacing); closed meshes give a closed model.
    This is the ``lodkit`` library's build, the one ``lodkit mco build``
    runs (the same ``.mco`` bytes for the same inputs); ``progress`` gets
    its events (see :mod:`pylodkit.jobs`). Deterministic; the GIL is
    released while it builds.

    Example::

        >>> model = lk.mco.build(lk.bunny(), resolution=128)
    """
    items = list(inputs) if isinstance(inputs, (list, tuple)) else [inputs]
    items.extend(more)
    if not items:
        raise OptionError("give at least one input")
    items = [os.fspath(i) if isinstance(i, os.PathLike) else _as_input(i) for i in items]
    r = _check.within("resolution", resolution, "resolution")
    if progress is not None and not callable(progress):
        raise OptionError("progress=%r: expected a function taking one dict, or None" % (progress,))
    return Model(_native.mco_build(items, r, progress))


def load(path: Union[str, "os.PathLike[str]"]) -> Model:
    """Reads a ``.mco`` file (version 1 or 2).

    Example::

        >>> model = lk.mco.load("bunny.mco")
    """
    return Model(_native.mco_load(os.fspath(path)))


def from_bytes(data: bytes) -> Model:
    """A model from ``.mco`` bytes (any untrusted bytes are safe: malformed ones raise ``InputError``).

    Example::

        >>> model = lk.mco.from_bytes(open("bunny.mco", "rb").read())
    """
    return Model(_native.mco_from_bytes(bytes(data)))


__all__ = ["Model", "build", "load", "from_bytes", "MAX_RESOLUTION"]
