"""Exceptions raised by pylodkit.

Each carries the one-line message the ``lodkit`` CLI prints for the same
failure (without a file name when the input is an in-memory array):

- :class:`InputError` (a ``ValueError``): bad data, the CLI's exit 1 — a
  malformed file, an array of the wrong shape or dtype, a face index out of
  range, a mesh or stream the engines refuse.
- :class:`FileError` (an ``OSError``): a file that cannot be read or
  written.
- :class:`OptionError` (a ``ValueError``): an option outside its range,
  the CLI's exit 2; the message names the range.

All derive from :class:`LodkitError`, so ``except pylodkit.LodkitError``
catches every one of them.

Example::

    >>> import numpy as np, pylodkit as lk
    >>> try:
    ...     lk.simplify(lk.Mesh(np.zeros((3, 3)), [[0, 1, 5]]), ratio=0.5)
    ... except lk.InputError as e:
    ...     print(e)
    faces: face 0 has vertex index 5 but the mesh has 3 vertices
"""


class LodkitError(Exception):
    """Base class of every pylodkit error."""


class InputError(LodkitError, ValueError):
    """Bad input data (a malformed file, a wrong array, a refused mesh)."""


class FileError(LodkitError, OSError):
    """A file that cannot be read or written."""


class OptionError(LodkitError, ValueError):
    """An option outside its range (the message names the range)."""


__all__ = ["LodkitError", "InputError", "FileError", "OptionError"]
