"""The operations of binding expressions on values, shared by the per-tick and the vectorized
evaluators (:mod:`fretc.signals.bindings.compile`).

Python ``bool``/``float`` go through Python operators (fast path for one tick); anything else
through numpy, item by item, keeping the validity mask of :class:`Valid` arrays.  ``x / 0``
is ±inf (nan for 0/0) as IEEE 754; NaN propagates through ``min``/``max`` of several values,
as ``np.minimum``/``np.maximum``.  Reductions of an empty array: ``min`` → +inf, ``max`` →
-inf, ``mean`` → nan, ``any`` → false, ``all`` → true, ``count``/``len``/``norm`` → 0;
but ``min``/``max`` of LaserScan ranges with no valid return and an invalid measurement
(REP 117: NaN, a value outside the limits) → NaN, unknown (a blind LiDAR is no clear path),
and ``invalid(ranges)`` counts the invalid measurements.

Design notes: ARCHITECTURE.md, `signals/bindings/operations.py`."""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from typing import Any

import numpy as np

from fretc.signals.bindings.extract import Valid

__all__ = ["PY_TYPES", "Ops", "num", "min2", "max2", "NP_BINARY", "PY_BINARY", "COMPARISONS",
           "LOGICAL", "py_three_valued", "np_three_valued", "undeclared_inf"]

#: The Python types of one tick's values (the fast path).
PY_TYPES = (float, bool, int)


def num(x: Any) -> Any:
    """Booleans as numbers for arithmetic (numpy would treat bool + bool as logical or)."""
    if isinstance(x, np.ndarray) and x.dtype == np.bool_:
        return x.astype(np.float64)
    return x


class Ops:
    """Array semantics; ``axis`` None evaluates one tick, 1 evaluates ticks × items.
    ``nan_unread``: comparisons with NaN are NaN and logic is three-valued (the default
    policy); False: IEEE 754 (``[tick] nan = "false"``). ``inf_unread``: ±inf read from a
    log field is NaN (:func:`undeclared_inf`; ``[tick] inf = "value"`` turns it off)."""

    def __init__(self, vectorized: bool, nan_unread: bool = True, inf_unread: bool = True
                 ) -> None:
        self.vec = vectorized
        self.axis = 1 if vectorized else None
        self.nan_unread = nan_unread
        self.inf_unread = inf_unread

    def _split(self, x: Any) -> tuple[Any, Any]:
        if isinstance(x, Valid):
            return x.data, x.mask
        if self.vec and isinstance(x, np.ndarray) and x.ndim == 1:
            return x[:, None], None
        return x, None

    def lift2(self, fn: Callable[[Any, Any], Any], a: Any, b: Any, numeric: bool) -> Any:
        """``fn(a, b)`` on numbers or arrays; a :class:`Valid` operand's mask is kept (both
        masks: both must hold). ``numeric``: booleans become numbers first."""
        if isinstance(a, Valid) or isinstance(b, Valid):
            da, ma = self._split(a)
            db, mb = self._split(b)
            if numeric:
                da, db = num(da), num(db)
            mask = ma if mb is None else mb if ma is None else ma & mb
            return Valid(fn(da, db), mask)
        if numeric:
            a, b = num(a), num(b)
        return fn(a, b)

    def lift1(self, fn: Callable[[Any], Any], a: Any, numeric: bool) -> Any:
        """``fn(a)`` on a number or an array, keeping a :class:`Valid` mask."""
        if isinstance(a, Valid):
            return Valid(fn(num(a.data) if numeric else a.data), a.mask)
        return fn(num(a) if numeric else a)

    # reductions of an array value ----------------------------------------------------------
    def _filled(self, a: Valid, fill: float) -> np.ndarray:
        data = num(a.data)
        return data if a.mask is None else np.where(a.mask, data, fill)

    def _truthy(self, a: Valid) -> np.ndarray:
        t = a.data != 0
        return t if a.mask is None else t & a.mask

    def _unknown_items(self, a: Valid) -> np.ndarray | None:
        """Items that are NaN truth values (a comparison with NaN, three-valued), among the
        valid ones; None when there is none or NaN compares false."""
        if not self.nan_unread or a.data.dtype.kind != "f":
            return None
        u = np.isnan(a.data)
        if a.mask is not None:
            u &= a.mask
        return u if u.any() else None

    @staticmethod
    def _invalid(a: Valid) -> np.ndarray:
        """The items REP 117 calls invalid measurements: outside the validity mask and not
        +inf ("no return within range_max", a clear beam): NaN, and finite values outside
        ``[range_min, range_max]`` (-inf, a detection too close, reads as ``range_min``:
        valid). None of an array without a mask."""
        if a.mask is None or a.data.dtype.kind != "f":
            return np.zeros(a.data.shape, dtype=np.bool_)
        return ~a.mask & ~np.isposinf(a.data)

    def _blind(self, a: Valid, got: Any) -> Any:
        """``min``/``max`` of a masked array (REP 117's LaserScan ranges) with no valid item
        but an invalid measurement: NaN, unknown, not the empty array's +inf / -inf. A LiDAR
        that keeps publishing while every return is NaN (a covered window, a failed
        receiver) measured nothing: its "nearest return" is no clear path (the shield reads
        the NaN as an input it cannot read, the audit as an unknown tick). Every beam
        +inf (no return within range) is still +inf: REP 117's clear view."""
        if a.mask is None or a.data.dtype.kind != "f":
            return got
        empty = ~a.mask.any(axis=self.axis)
        if not np.any(empty):  # (the common case: a valid return in every scan)
            return got
        blind = empty & self._invalid(a).any(axis=self.axis)
        return np.where(blind, np.nan, got) if np.any(blind) else got

    def _count(self, a: Valid) -> Any:
        if a.mask is None:
            n = a.data.shape[-1]
            return np.full(a.data.shape[0], float(n)) if self.vec else float(n)
        return self._out(a.mask.sum(axis=self.axis))

    def _out(self, x: Any) -> Any:
        if self.vec:
            return np.asarray(x, dtype=np.float64) if np.asarray(x).dtype != np.bool_ else np.asarray(x)
        if isinstance(x, np.ndarray) and x.ndim == 0:
            x = x[()]
        return x.item() if isinstance(x, np.generic) else x

    def reduce(self, func: str, a: Valid) -> Any:
        """``func`` (min, max, mean, norm, any, all, count, len, invalid) of an array over
        its valid items (``invalid``: its invalid measurements, :meth:`_invalid`; ``min`` and
        ``max`` of no valid item and an invalid one NaN, :meth:`_blind`): a number per tick
        (one tick) or an array of them (vectorized)."""
        ax = self.axis
        # ndarray methods (not np.min etc.): same ufunc reductions, less Python overhead.
        if func == "min":  # where=: no filled copy; the same values
            return self._out(self._blind(a, num(a.data).min(
                axis=ax, initial=np.inf, where=True if a.mask is None else a.mask)))
        if func == "max":
            return self._out(self._blind(a, num(a.data).max(
                axis=ax, initial=-np.inf, where=True if a.mask is None else a.mask)))
        if func == "invalid":
            return self._out(self._invalid(a).sum(axis=ax).astype(np.float64))
        if func == "mean":
            total = self._filled(a, 0.0).sum(axis=ax)
            n = a.mask.sum(axis=ax) if a.mask is not None else a.data.shape[-1]
            return self._out(np.divide(total, n))
        if func == "norm":
            d = num(a.data)
            sq = d * d
            if a.mask is not None:
                sq = np.where(a.mask, sq, 0.0)
            return self._out(np.sqrt(sq.sum(axis=ax)))
        unknown = self._unknown_items(a)
        if func == "any":
            got = (self._truthy(a) & ~unknown).any(axis=ax) if unknown is not None else \
                self._truthy(a).any(axis=ax)
            return self._out(_or_unknown(got, unknown, ax, when=False))
        if func == "all":
            t = a.data != 0
            if a.mask is not None:
                t = t | ~a.mask
            if unknown is not None:
                t = t | unknown
            return self._out(_or_unknown(t.all(axis=ax), unknown, ax, when=True))
        if func == "count":
            got = self._truthy(a).sum(axis=ax).astype(np.float64)
            if unknown is not None:
                got = np.where(unknown.any(axis=ax), np.nan, got)
            return self._out(got)
        if func == "len":
            return self._count(a)
        raise AssertionError(func)  # pragma: no cover


def undeclared_inf(v: Any, path: tuple) -> Any:
    """A field's value with ±inf read as NaN (unread: no number was measured; bindings
    docs, "NaN, ±inf"), item by item in arrays. Kept: a path through a field named
    ``range`` or ``ranges`` (``sensor_msgs/Range``, LaserScan ranges and their beams, whose
    ±inf REP 117 defines)."""
    if any(p in ("range", "ranges") for p in path if isinstance(p, str)):
        return v  # REP 117 fields (Range.range, LaserScan ranges and their beams)
    if type(v) is float:
        return math.nan if v in (math.inf, -math.inf) else v
    if isinstance(v, Valid):
        if v.mask is not None or v.data.dtype.kind != "f" or not np.isinf(v.data).any():
            return v
        return Valid(np.where(np.isinf(v.data), np.nan, v.data), None)
    if isinstance(v, np.ndarray) and v.dtype.kind == "f" and np.isinf(v).any():
        return np.where(np.isinf(v), np.nan, v)
    if isinstance(v, np.floating) and np.isinf(v):
        return math.nan
    return v


def _or_unknown(got: Any, unknown: np.ndarray | None, ax: int | None, when: bool
                ) -> Any:
    """``got`` (bool per tick, an array or a numpy bool), NaN where it equals ``when`` and an item was unknown
    (``any``: no item true but one unknown; ``all``: no item false but one unknown)."""
    if unknown is None:
        return got
    undecided = (got == when) & unknown.any(axis=ax)
    if not np.any(undecided):
        return got
    return np.where(undecided, np.nan, np.asarray(got, dtype=np.float64))


def min2(a: Any, b: Any) -> Any:
    """The smaller of two Python numbers; NaN if either is NaN."""
    if a != a or b != b:  # NaN propagates, as np.minimum
        return math.nan
    return a if a <= b else b


def max2(a: Any, b: Any) -> Any:
    """The larger of two Python numbers; NaN if either is NaN."""
    if a != a or b != b:
        return math.nan
    return a if a >= b else b


def _div(a: Any, b: Any) -> Any:
    if b == 0:
        return float(np.divide(np.float64(a), np.float64(b)))
    return a / b


#: Binary operator -> (numpy function, whether its operands are numbers).
NP_BINARY: dict[str, tuple[Callable[[Any, Any], Any], bool]] = {
    "+": (np.add, True), "-": (np.subtract, True), "*": (np.multiply, True),
    "/": (np.divide, True),
    "<": (np.less, False), "<=": (np.less_equal, False), ">": (np.greater, False),
    ">=": (np.greater_equal, False), "=": (np.equal, False), "!=": (np.not_equal, False),
    "&": (np.logical_and, False), "|": (np.logical_or, False),
    "->": (lambda a, b: np.logical_or(np.logical_not(a), b), False),
    "<->": (lambda a, b: np.logical_not(np.logical_xor(a, b)), False),
}
#: Binary operator -> the same operation on Python bools and floats.
PY_BINARY: dict[str, Callable[[Any, Any], Any]] = {
    "+": operator.add, "-": operator.sub, "*": operator.mul, "/": _div,
    "<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge,
    "=": operator.eq, "!=": operator.ne,
    "&": lambda a, b: bool(a) and bool(b), "|": lambda a, b: bool(a) or bool(b),
    "->": lambda a, b: (not a) or bool(b), "<->": lambda a, b: bool(a) == bool(b),
}


#: The comparison operators (their value is NaN when an operand is NaN, policy "unread").
COMPARISONS = frozenset(("<", "<=", ">", ">=", "=", "!="))
#: The logical operators (three-valued when an operand is NaN, policy "unread").
LOGICAL = frozenset(("&", "|", "->", "<->", "!"))


def _truth(x: Any) -> Any:
    """A Python value as True / False / NaN (unknown)."""
    if x != x:
        return math.nan
    return bool(x)


def py_three_valued(op: str, a: Any, b: Any = None) -> Any:
    """Kleene's strong three-valued ``op`` (``& | -> <-> !``) of Python bools/numbers, NaN
    being unknown; ``b`` unused for ``!``. Returns bool, or NaN when unknown."""
    x = _truth(a)
    if op == "!":
        return x if x != x else not x
    y = _truth(b)
    if op == "->":
        op, x = "|", (x if x != x else not x)
    if op == "&":
        if x is False or y is False:
            return False
        return math.nan if (x != x or y != y) else True
    if op == "|":
        if x is True or y is True:
            return True
        return math.nan if (x != x or y != y) else False
    # <->
    return math.nan if (x != x or y != y) else x == y


def _np_truth(x: Any) -> tuple[Any, Any]:
    """(truth, unknown) of a numpy value: bool arrays, ``unknown`` where x is NaN."""
    x = np.asarray(x)
    if x.dtype.kind == "f":
        unknown = np.isnan(x)
        return (x != 0) & ~unknown, unknown
    return x.astype(np.bool_), np.zeros(x.shape, dtype=np.bool_)


def np_three_valued(op: str, a: Any, b: Any = None) -> Any:
    """:func:`py_three_valued` item by item on numpy values: a bool array when nothing is
    unknown, else float64 with 0/1 and NaN where unknown."""
    x, ux = _np_truth(a)
    if op == "!":
        out, unknown = ~x, ux
    else:
        y, uy = _np_truth(b)
        if op == "->":
            x = ~x & ~ux  # not(unknown) stays unknown
        if op == "&":
            false = (~x & ~ux) | (~y & ~uy)
            out, unknown = x & y, (ux | uy) & ~false
        elif op in ("|", "->"):
            true = x | y
            out, unknown = true, (ux | uy) & ~true
        else:  # <->
            out, unknown = x == y, ux | uy
    if not unknown.any():
        return out
    return np.where(unknown, np.nan, out.astype(np.float64))
