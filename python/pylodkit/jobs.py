"""The ``lodkit`` library's jobs on files, called in place: what the
``lodkit`` command runs, with its options, outputs (the same bytes) and
one-line errors.

- :func:`build`: every level of detail of a file (``lodkit build``).
- :func:`render`: a picture of a mesh, cloud, ``.mco`` cut or ``.pop``
  level (``lodkit render``).
- :func:`info`: a file's figures (``lodkit info --json``).
- :func:`pylodkit.simplify`, :func:`pylodkit.lod_chain` and
  :func:`pylodkit.compare` given paths run the library's ``simplify``,
  ``lods`` and ``compare`` jobs (``simplify_file``, ``lod_chain_file``,
  ``compare_files`` here).

Every job takes ``progress``: a function called with one dict per event
of the job, in order (``event`` is ``note``, ``warning``,
``stage_started``, ``stage_finished``, ``phase``, ``advance`` (``n``,
``done``: the phase's units so far, ``len``), ``phases_finished``,
``timing`` or ``level`` (a chain's level as ``lods.json`` has it)). The
GIL is released while the job runs and taken for each call. An exception
the function raises is raised when the job returns (a job is not stopped
halfway, so what it writes stays whole). Option values outside their
range (``pylodkit.LIMITS``) are :class:`~pylodkit.OptionError`\\ s, as a
request the job cannot serve; bad input is an
:class:`~pylodkit.InputError`, an unreadable file a
:class:`~pylodkit.FileError`.
"""
from __future__ import annotations

import os
from typing import Any, Callable, Dict, Optional, Sequence, Tuple, Union

from . import _check
from . import _lodkit as _native
from .errors import OptionError

PathLike = Union[str, "os.PathLike[str]"]
#: A function taking one event dict.
Progress = Optional[Callable[[Dict[str, Any]], Any]]

__all__ = ["build", "render", "info", "simplify_file", "lod_chain_file", "compare_files"]

_D = _check.DEFAULTS


def _progress(progress: Progress) -> Progress:
    if progress is not None and not callable(progress):
        raise OptionError("progress=%r: expected a function taking one dict, or None" % (progress,))
    return progress


def _memory(memory: Optional[int]) -> Optional[int]:
    return _check.within("memory", memory, "memory")


def simplify_file(input: PathLike, output: PathLike, target: Optional[int], ratio: Optional[float],
                  opts: Dict[str, Any], merge: bool = False, memory: Optional[int] = None,
                  progress: Progress = None) -> Dict[str, Any]:
    """The ``simplify`` job (``lodkit simplify IN -o OUT --json``): options
    checked by :func:`pylodkit.simplify`, which calls it for a path."""
    return _native.simplify_file(os.fspath(input), os.fspath(output), target, ratio, merge=bool(merge),
                                 memory=_memory(memory), progress=_progress(progress), **opts)


def lod_chain_file(input: PathLike, out: PathLike, ratios: Optional[Sequence[float]],
                   levels: Optional[int], samples: Optional[int], opts: Dict[str, Any],
                   merge: bool = False, memory: Optional[int] = None,
                   progress: Progress = None) -> Dict[str, Any]:
    """The ``lods`` job (``lodkit lods IN --out DIR --json``, ``lods.json``
    as a dict): options checked by :func:`pylodkit.lod_chain`, which calls
    it for a path."""
    return _native.lod_chain_file(os.fspath(input), os.fspath(out),
                                  None if ratios is None else list(ratios), levels,
                                  samples=samples, merge=bool(merge), memory=_memory(memory),
                                  progress=_progress(progress), **opts)


def compare_files(a: PathLike, b: PathLike, samples: Optional[int], seed: int,
                  vertex_samples: bool, edge_samples: bool, face_samples: bool,
                  heatmap: Optional[PathLike] = None, progress: Progress = None) -> Dict[str, Any]:
    """The ``compare`` job (``lodkit compare A B --json``): options checked
    by :func:`pylodkit.compare`, which calls it for two paths."""
    return _native.compare_files(os.fspath(a), os.fspath(b), samples, seed, bool(vertex_samples),
                                 bool(edge_samples), bool(face_samples),
                                 None if heatmap is None else os.fspath(heatmap),
                                 progress=_progress(progress))


def build(input: Optional[PathLike], out: PathLike, *, levels: int = _D["levels"],
          samples: Optional[int] = None, measure: bool = True, merge: bool = False,
          progress: Progress = None) -> Dict[str, Any]:
    """Builds every level of detail of ``input`` into the folder ``out``
    (``lodkit build``): the input as GLB and PLY, the HQMS chain of
    ``levels`` halvings (``lods/``), the marching cube octree (``.mco``),
    the progressive stream (``.pop``), each measured against the input
    (``samples`` per kind, by default 4 per face of each level; none with
    ``measure=False``), with ``report.md``, ``report.html`` and the manifest
    ``.lodkit-build.json``.

    ``input`` is a mesh, point cloud, range image, scan set or calibrated
    image set (as the CLI reads them), or ``None`` for the built-in
    Stanford bunny; ``merge`` joins a textured or multi-part input into one
    mesh. ``out`` is made beside itself and moved into place at the end: a
    failed build leaves it as it was, and only a folder an earlier build
    made is replaced (another folder is an :class:`~pylodkit.OptionError`).
    A degenerate product is an :class:`~pylodkit.InputError` after the
    folder is written (each also sent to ``progress`` as a ``warning``).

    Returns ``{"model": name, "outputs": [[file, bytes], ...]}`` (files
    relative to ``out``). Cost: dominated by the octree build and the
    measurements.

    Example::

        >>> r = pylodkit.build(None, "bunny_lods")
        >>> r["model"]
        'stanford_bunny'
    """
    return _native.build(
        None if input is None else os.fspath(input), os.fspath(out),
        _check.within("levels", levels, "levels"),
        _check.within("samples", samples, "samples"),
        bool(measure), bool(merge), progress=_progress(progress),
    )


def _kind(path: PathLike) -> str:
    ext = os.path.splitext(os.fspath(path))[1].lower()
    return ext[1:] if ext in (".mco", ".pop") else "geometry"


def render(input: PathLike, png: PathLike, *, azimuth: float = _D["azimuth"],
           elevation: float = _D["elevation"],
           size: Tuple[int, int] = (_D["width"], _D["height"]), fov: float = _D["fov"],
           background: Sequence[int] = _D["background"], smooth: bool = False,
           triangles: Optional[int] = None, lod: Optional[int] = None,
           level: Optional[int] = None, progress: Progress = None) -> Dict[str, Any]:
    """Draws ``input`` and writes one picture as the PNG ``png`` (``lodkit
    render``), atomically: a mesh, a point cloud (points as discs), a
    textured scene, the cut of a ``.mco`` model for a ``triangles`` budget
    or at a ``lod`` number (default: the finest), or a ``.pop`` stream's
    octree ``level`` (default: the finest its complete chunks hold).

    The camera frames the object from ``azimuth`` (degrees about +Y from
    +Z towards +X) and ``elevation`` (``LIMITS["elevation"]``, towards
    +Y) with a vertical field of view ``fov`` (``LIMITS["fov"]``);
    ``size`` is ``(width, height)`` in pixels (each in
    ``LIMITS["picture_size"]``), ``background`` an RGB triple in 0..=255;
    ``smooth`` shades from computed normals when the mesh has none. The
    defaults are the CLI's (``pylodkit.DEFAULTS``).

    Returns ``lodkit render --json``'s report: ``input``, ``drawn`` (in
    words), ``width``, ``height``, ``output``, ``views`` (1) and
    ``coverage`` (the fraction of the picture the object covers).

    Example::

        >>> r = pylodkit.render("bunny.ply", "bunny.png", size=(256, 256))
        >>> r["views"]
        1
    """
    kind = _kind(input)
    if os.path.splitext(os.fspath(png))[1].lower() != ".png":
        raise OptionError("png=%r: expected a .png path" % (os.fspath(png),))
    if kind != "mco" and (triangles is not None or lod is not None):
        raise OptionError("triangles and lod apply to .mco models, not to %s" % os.fspath(input))
    if kind != "pop" and level is not None:
        raise OptionError("level applies to .pop streams, not to %s" % os.fspath(input))
    if triangles is not None and lod is not None:
        raise OptionError("triangles and lod conflict: give one of them")
    az = _check.real("azimuth", azimuth)
    el = _check.within("elevation", elevation, "elevation")
    if not isinstance(size, (tuple, list)) or len(size) != 2:
        raise OptionError("size=%r: expected (width, height)" % (size,))
    lo, hi = _check.LIMITS["picture_size"]
    w = _check.integer("size", size[0], lo, hi)
    h = _check.integer("size", size[1], lo, hi)
    f = _check.within("fov", fov, "fov")
    bg = list(background) if isinstance(background, (tuple, list)) else None
    if bg is None or len(bg) != 3:
        raise OptionError("background=%r: expected (R, G, B), each in 0..=255" % (background,))
    bg = [_check.integer("background", c, 0, 255) for c in bg]
    t = _check.integer("triangles", triangles, 0, 2**64 - 1)
    k = _check.integer("lod", lod, 0, 2**64 - 1)
    lv = _check.integer("level", level, 0, _check.LIMITS["pop_bits"][1])
    return _native.render(os.fspath(input), os.fspath(png), az, el, w, h, f, bg, bool(smooth),
                          t, k, lv, progress=_progress(progress))


def info(path: PathLike, *, progress: Progress = None) -> Dict[str, Any]:
    """A file's figures, as ``lodkit info FILE --json`` prints them (the
    library's serde types, as a dict): for a mesh, cloud or range image
    (``vertices``, ``faces``, ``bbox``, ``area``, topology, ...); for a
    ``.mco`` model what ``lodkit mco info --json`` prints (``version``,
    ``chunks``, lattice and level figures); for a ``.pop`` stream every
    level decoded and triangulated (``lodkit pop stats``); for a
    calibration (``transforms.json``, COLMAP text) its image set. Errors
    name the file.

    Example::

        >>> pylodkit.info("bunny.ply")["faces"]
        69451
    """
    _, d = _native.info(os.fspath(path), progress=_progress(progress))
    return d

