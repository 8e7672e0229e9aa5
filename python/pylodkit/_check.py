"""Option checks against the ranges of the ``lodkit`` library (``LIMITS``),
worded as the CLI's range parsers word them."""
from __future__ import annotations

import math
from typing import Optional

from . import _lodkit as _native
from .errors import OptionError

#: Every option range of ``lodkit::limits`` by name: ``(lo, hi)`` for an
#: integer, ``(lo, hi, lo_open, hi_open)`` for a real.
LIMITS = _native.LIMITS
#: The default of every option pylodkit offers, by name (``lodkit::limits``
#: and the engines' option types: the CLI's defaults).
DEFAULTS = _native.DEFAULTS


def _fmt(x: float) -> str:
    return str(int(x)) if float(x).is_integer() else repr(float(x))


def real(name: str, value, lo: float = -math.inf, hi: float = math.inf,
         lo_open: bool = False, hi_open: bool = False) -> Optional[float]:
    """``value`` as a float within the range, or ``OptionError``."""
    if value is None:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    ok = math.isfinite(v) and (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok:
        if math.isfinite(lo) and math.isfinite(hi):
            what = "a number in %s%s, %s%s" % ("(" if lo_open else "[", _fmt(lo), _fmt(hi), ")" if hi_open else "]")
        elif math.isfinite(lo):
            what = "a finite number %s %s" % (">" if lo_open else ">=", _fmt(lo))
        elif math.isfinite(hi):
            what = "a finite number %s %s" % ("<" if hi_open else "<=", _fmt(hi))
        else:
            what = "a finite number"
        raise OptionError("%s=%r: expected %s" % (name, value, what))
    return v


def integer(name: str, value, lo: int, hi: int) -> Optional[int]:
    """``value`` as an int in ``lo..=hi``, or ``OptionError``."""
    if value is None:
        return None
    if isinstance(value, bool) or not hasattr(value, "__index__"):
        raise OptionError("%s=%r: expected an integer in %d..=%d" % (name, value, lo, hi))
    v = value.__index__()
    if not lo <= v <= hi:
        raise OptionError("%s=%r: expected an integer in %d..=%d" % (name, value, lo, hi))
    return v


def within(name: str, value, limit: str):
    """``value`` checked against ``LIMITS[limit]`` (an integer or a real range)."""
    r = LIMITS[limit]
    if len(r) == 2:
        return integer(name, value, r[0], r[1])
    lo, hi, lo_open, hi_open = r
    return real(name, value, lo, hi, lo_open=lo_open, hi_open=hi_open)
