"""The operations of binding expressions on values, shared by the per-tick and the vectorized
evaluators (:mod:`signals.bindings.compile`).

Python ``bool``/``float`` go through Python operators (fast path for one tick); anything else
through numpy, item by item, keeping the validity mask of :class:`Valid` arrays.  ``x / 0``
is ±inf (nan for 0/0) as IEEE 754; NaN propagates through ``min``/``max`` of several values,
as ``np.minimum``/``np.maximum``.  Reductions of an empty array: ``min`` → +inf, ``max`` →
-inf, ``mean`` → nan, ``any`` → false, ``all`` → true, ``count``/``len``/``norm`` → 0.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from typing import Any

import numpy as np

from .extract import Valid

__all__ = ["PY_TYPES", "Ops", "num", "min2", "max2", "NP_BINARY", "PY_BINARY"]

#: The Python types of one tick's values (the fast path).
PY_TYPES = (float, bool, int)


def num(x: Any) -> Any:
    """Booleans as numbers for arithmetic (numpy would treat bool + bool as logical or)."""
    if isinstance(x, np.ndarray) and x.dtype == np.bool_:
        return x.astype(np.float64)
    return x


class Ops:
    """Array semantics; ``axis`` None evaluates one tick, 1 evaluates ticks × items."""

    def __init__(self, vectorized: bool) -> None:
        self.vec = vectorized
        self.axis = 1 if vectorized else None

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

    def _count(self, a: Valid) -> Any:
        if a.mask is None:
            n = a.data.shape[-1]
            return np.full(a.data.shape[0], float(n)) if self.vec else float(n)
        return self._out(a.mask.sum(axis=self.axis))

    def _out(self, x: Any) -> Any:
        if self.vec:
            return np.asarray(x, dtype=np.float64) if np.asarray(x).dtype != np.bool_ else np.asarray(x)
        return x.item() if isinstance(x, np.generic) else x

    def reduce(self, func: str, a: Valid) -> Any:
        """``func`` (min, max, mean, norm, any, all, count, len) of an array over its valid
        items: a number per tick (one tick) or an array of them (vectorized)."""
        ax = self.axis
        # ndarray methods (not np.min etc.): same ufunc reductions, less Python overhead.
        if func == "min":  # where=: no filled copy; the same values
            return self._out(num(a.data).min(axis=ax, initial=np.inf,
                                              where=True if a.mask is None else a.mask))
        if func == "max":
            return self._out(num(a.data).max(axis=ax, initial=-np.inf,
                                              where=True if a.mask is None else a.mask))
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
        if func == "any":
            return self._out(self._truthy(a).any(axis=ax))
        if func == "all":
            t = a.data != 0
            if a.mask is not None:
                t = t | ~a.mask
            return self._out(t.all(axis=ax))
        if func == "count":
            return self._out(self._truthy(a).sum(axis=ax).astype(np.float64))
        if func == "len":
            return self._count(a)
        raise AssertionError(func)  # pragma: no cover


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
NP_BINARY = {
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
