"""3D Tiles 1.1 tilesets (``lodkit tiles``): the ``lodkit`` library's tiles
job, called in place."""
from __future__ import annotations

import os
from typing import Any, Dict, Optional, Union

from . import _lodkit as _native
from ._check import within

__all__ = ["tiles"]


def tiles(input: Union[str, os.PathLike], out: Union[str, os.PathLike], *,
          leaf_triangles: Optional[int] = None, leaf_points: Optional[int] = None,
          skirts: bool = True, memory: Optional[int] = None,
          compress: bool = True) -> Dict[str, Any]:
    """Writes a 3D Tiles 1.1 tileset of the mesh or point cloud file
    ``input`` (any format lodkit reads, LAS/LAZ included) into the folder
    ``out`` (absent, empty, or one lodkit wrote; a folder holding other
    files is refused). A mesh gives ``REPLACE`` tiles (full-resolution
    leaves of at most ``leaf_triangles``, each level above simplified, every
    ``geometricError`` measured, ``skirts`` under tile borders); a cloud
    ``ADD`` point tiles (at most ``leaf_points`` a leaf). Returns what was
    written: ``kind``, ``tiles``, ``depth``, ``root_error``, ``bytes``,
    ``tileset`` (the path of ``tileset.json``), and ``level_triangles`` (a
    mesh) or ``points`` and ``origin`` (a cloud). ``memory`` (bytes, as
    ``lodkit tiles --memory``; default a third of the machine's): a binary
    PLY mesh whose in-core tiling would exceed it is tiled out of core, in
    bounded memory, staged beside ``out``. ``compress``: tiles with
    ``EXT_meshopt_compression`` (the default, as ``lodkit tiles``); False
    writes plain tiles.

    Example::

        >>> info = pylodkit.tiles("scan.ply", "scan_tiles")
        >>> info["tiles"] >= 1
        True
    """
    return _native.tiles(
        os.fspath(input), os.fspath(out),
        within("leaf_triangles", leaf_triangles, "tile_leaf_triangles"),
        within("leaf_points", leaf_points, "tile_leaf_points"),
        bool(skirts),
        within("memory", memory, "memory"),
        bool(compress),
    )
