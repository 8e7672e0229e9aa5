"""pylodkit: lodkit's mesh engines on numpy arrays.

The distribution and the import name are ``pylodkit`` (``lodkit`` on PyPI is
an unrelated project). Install from a checkout with ``pip install ./python``.

- :func:`load` / :func:`save`: .ply .obj .stl .gltf .glb .xyz .pts files.
- :class:`Mesh` (``vertices`` (n, 3), ``faces`` (m, 3), optional
  ``normals``, ``colors``, ``uvs``) and :class:`PointCloud`.
- :func:`simplify`, :func:`lod_chain`: HQMS simplification and LOD chains
  (of a :class:`Mesh`, or of a file through the ``lodkit`` library's job,
  in or out of core).
- :func:`compare`: Metro distances, as ``lodkit compare --json``.
- :func:`build`, :func:`render`, :func:`info`, :func:`tiles`: the library's
  ``build``, ``render``, ``info`` and ``tiles`` jobs on files
  (:mod:`pylodkit.jobs`); every job takes ``progress=``, a function of one
  event dict.
- :data:`LIMITS` and :data:`DEFAULTS`: every option's range and default,
  read from the ``lodkit`` library.
- :mod:`pylodkit.mco`: continuous LOD (marching cube octree).
- :mod:`pylodkit.pop`: progressive particle streams.
- :mod:`pylodkit.batch`: LODs for a folder of assets (on Ray when it is installed).
- :func:`from_trimesh` / :func:`to_trimesh`, :func:`from_open3d` / :func:`to_open3d`.

Every call releases the GIL while it computes; errors are
:class:`LodkitError` subclasses carrying the CLI's one-line message.

Example::

    >>> import pylodkit as lk
    >>> bunny = lk.bunny()
    >>> lod, report = lk.simplify(bunny, ratio=0.1)
    >>> lk.compare(bunny, lod)["symmetric"]["mean_pct"] < 0.05
    True
"""
from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version as _version

from . import errors, jobs, mco, pop
from ._check import DEFAULTS, LIMITS
from .jobs import build, info, render
from .tiles import tiles
from ._core import (
    MAX_HEAP_SIZE,
    MAX_LEVELS,
    MAX_SAMPLES,
    Mesh,
    PointCloud,
    blob,
    bunny,
    compare,
    from_open3d,
    from_trimesh,
    icosphere,
    load,
    lod_chain,
    save,
    simplify,
    to_open3d,
    to_trimesh,
)
from .errors import FileError, InputError, LodkitError, OptionError

try:
    __version__ = _version("pylodkit")
except PackageNotFoundError:  # imported from a source tree
    __version__ = "0.0.0"

__all__ = [
    "Mesh", "PointCloud", "load", "save", "bunny", "blob", "icosphere", "simplify",
    "lod_chain", "compare", "from_trimesh", "to_trimesh", "from_open3d", "to_open3d",
    "mco", "pop", "tiles", "build", "render", "info", "jobs", "LIMITS", "DEFAULTS", "errors", "LodkitError", "InputError", "FileError", "OptionError",
    "MAX_SAMPLES", "MAX_HEAP_SIZE", "MAX_LEVELS", "__version__",
]
