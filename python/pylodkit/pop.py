"""Progressive octree particle streams (``.pop``, ``lodkit pop``).

Encode a mesh or point cloud as a progressive stream; decode any level, or
whatever prefix of the stream has arrived::

    >>> import pylodkit as lk
    >>> data = lk.pop.encode(lk.bunny())
    >>> coarse = lk.pop.decode(data, level=5)
    >>> part = lk.pop.decode(data[: len(data) // 2])   # the complete chunks of a prefix
"""
from __future__ import annotations

from typing import Any, Dict, Optional, Tuple, Union

from . import _check
from . import _lodkit as _native
from ._core import Mesh, PointCloud, _as_input, _wrap
from .errors import OptionError

#: Largest octree depth ``encode`` takes (the CLI's bound).
MAX_DEPTH: int = _check.LIMITS["pop_depth"][1]
#: Highest level and precision a stream holds.
MAX_BITS: int = _check.LIMITS["pop_bits"][1]


def encode_with_report(
    obj: Any,
    *,
    depth: Optional[int] = None,
    precision: Optional[int] = None,
    mode: str = "entropy",
    placement: Optional[str] = None,
    outer_thinning: bool = False,
    relax_below: Union[str, int] = "auto",
    normals: bool = False,
    colours: bool = True,
    raw: bool = False,
) -> Tuple[bytes, Dict[str, Any]]:
    """:func:`encode`, also returning ``lodkit pop encode --json``'s figures.

    The report has ``mode``, ``depth``, ``precision``, ``particles``,
    per-level ``levels`` (kept, eliminated, phantoms, new_particles,
    structure_bits, attribute_bytes, bytes_so_far), ``precision_bits``,
    ``total_bytes``, ``relax_below`` and ``source`` (``"mesh"``, ``"surface"``:
    a cloud's reconstruction, or ``"samples"``).

    Example::

        >>> data, report = lk.pop.encode_with_report(lk.bunny())
        >>> report["total_bytes"] == len(data)
        True
    """
    d = _check.within("depth", depth, "pop_depth")
    p = _check.within("precision", precision, "pop_bits")
    if d is not None and p is not None and p < d:
        raise OptionError("precision=%d is below depth=%d: the precision N must be in %d..=16"
                          % (p, d, d))
    if mode not in ("entropy", "baseline"):
        raise OptionError("mode=%r: expected 'entropy' or 'baseline'" % (mode,))
    if placement not in (None, "column", "mean"):
        raise OptionError("placement=%r: expected 'column' or 'mean'" % (placement,))
    if mode == "baseline" and placement == "column":
        raise OptionError("placement='column' applies to mode='entropy'; the baseline codes means")
    if relax_below == "auto":
        relax = None
    else:
        if not outer_thinning:
            raise OptionError("relax_below applies with outer_thinning=True")
        relax = _check.within("relax_below", relax_below, "pop_bits")
    return _native.pop_encode(_as_input(obj), d, p, mode, placement, bool(outer_thinning), relax,
                              bool(normals), bool(colours), bool(raw))


def encode(obj: Any, **options: Any) -> bytes:
    """A mesh, point cloud or (n, 3) point array as ``.pop`` bytes (``lodkit pop encode``).

    Options, with the CLI's defaults: ``depth`` (octree resolution R,
    1..=12, default from the sampling density), ``precision`` (N bits,
    1..=16, default 12, raised to R when below), ``mode`` (``"entropy"`` or
    ``"baseline"``), ``placement`` (``"column"`` or ``"mean"``; entropy mode),
    ``outer_thinning``, ``relax_below`` (``"auto"`` or 1..=16, with outer
    thinning), ``normals`` (code particle normals), ``colours`` (keep the
    input's colours), ``raw`` (a cloud's samples as they are; by default a
    cloud is coded from its reconstructed surface, at about one particle
    per point). Deterministic; the GIL is released while it encodes.

    Example::

        >>> data = lk.pop.encode(lk.bunny(), depth=8)
        >>> data[:5]
        b'LKPOP'
    """
    return encode_with_report(obj, **options)[0]


def decode_with_info(
    data: bytes,
    level: Optional[int] = None,
    *,
    precision: Optional[int] = None,
    points: bool = False,
    decimate: Optional[float] = None,
    strict: bool = False,
) -> Tuple[Union[Mesh, PointCloud], Dict[str, Any]]:
    """:func:`decode`, also returning what was decoded.

    The info has ``level``, ``finest_level``, ``depth``, ``particles``,
    ``precision``, ``triangles`` (``None`` with ``points``), ``bytes_read``,
    ``file_bytes``, ``cut`` (where a prefix stopped: chunk, offset, message;
    ``None`` when every chunk read was whole) and, for meshes,
    ``triangulation`` (Table 1's counts).

    Example::

        >>> mesh, info = lk.pop.decode_with_info(data[:5000])
        >>> info["cut"]["chunk"] > 0
        True
    """
    lv = _check.integer("level", level, 0, MAX_BITS)
    p = _check.within("precision", precision, "pop_bits")
    dec = _check.within("decimate", decimate, "pop_decimate")
    if points and dec is not None:
        raise OptionError("decimate applies to a triangulated level, not to points=True")
    kind, d, info = _native.pop_decode(bytes(data), lv, p, bool(points), dec, bool(strict))
    return _wrap(kind, d), info


def decode(data: bytes, level: Optional[int] = None, **options: Any) -> Union[Mesh, PointCloud]:
    """One level of a ``.pop`` stream, triangulated (``lodkit pop decode``).

    ``level`` (0..=16) defaults to the finest the bytes hold; a prefix of a
    stream decodes its complete chunks (``strict=True`` refuses a cut
    chunk). ``precision`` (1..=16) limits the vertex bits read;
    ``points=True`` returns the particles as a :class:`PointCloud`;
    ``decimate`` (in [0, 1]) merges cubes joined by edges shorter than that
    fraction of the cube (§6.3). The GIL is released while it decodes.

    Example::

        >>> lk.pop.decode(lk.pop.encode(lk.bunny()), level=6)
        Mesh(8591 vertices, 17131 faces)
    """
    return decode_with_info(data, level, **options)[0]


__all__ = ["encode", "encode_with_report", "decode", "decode_with_info", "MAX_DEPTH", "MAX_BITS"]
