"""The value conventions the offline engines share with the generated monitors, over numpy
arrays of one value per tick (:mod:`fretc.monitors.vectorized` over the IR,
:mod:`fretc.monitors.interval` over the requirement's expressions): ``/`` by zero, ``mod``
by zero and an overflowing ``^`` give NaN; ``min``/``max`` keep Python's ``min(a, b)`` /
``max(a, b)`` choice when NaN is involved. (:mod:`fretc.compiler.evaluate` holds the same rules
for single Python values.)"""

from __future__ import annotations

import operator

import numpy as np
from typing import Any, TYPE_CHECKING

if TYPE_CHECKING:
    from numpy.typing import DTypeLike

__all__ = ["COMPARISONS", "CONNECTIVES", "arith", "connective", "py_min", "py_max",
           "shifted"]

#: Comparison operator -> numpy function.
COMPARISONS = {
    "=": np.equal, "!=": np.not_equal, "<": np.less, "<=": np.less_equal,
    ">": np.greater, ">=": np.greater_equal,
}
#: The binary boolean connectives.
CONNECTIVES = ("&", "|", "xor", "->", "<->")
ADD_SUB_MUL = {"+": operator.add, "-": operator.sub, "*": operator.mul}


def arith(op: str, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``x op y`` for ``op`` in ``+ - * / mod ^`` (NaN where the generated code's helpers
    give NaN).

    Raises:
        ValueError: another operator.
    """
    # (the same cases as compiler.evaluate's scalar _arith, on whole columns at once)
    with np.errstate(all="ignore"):
        if op in ADD_SUB_MUL:
            return ADD_SUB_MUL[op](x, y)
        if op == "/":
            return np.where(y == 0, np.nan, x / np.where(y == 0, 1.0, y))
        if op == "mod":
            return np.fmod(x, y)
        if op == "^":
            out = np.power(x, y)
            overflow = np.isinf(out) & np.isfinite(x) & np.isfinite(y)
            return np.where(overflow, np.nan, out)
    raise ValueError(f"unknown arithmetic operator {op!r}")


def connective(op: str, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``x op y`` for a binary connective of :data:`CONNECTIVES` (``<->`` for any other)."""
    if op == "&":
        return x & y
    if op == "|":
        return x | y
    if op == "xor":
        return x != y
    if op == "->":
        return ~x | y
    return x == y


def py_min(args: list[np.ndarray]) -> np.ndarray:
    """Element-wise ``min(a, b, ...)`` as Python's (the first unless a later one is less)."""
    out = args[0]
    for b in args[1:]:
        out = np.where(b < out, b, out)
    return out


def py_max(args: list[np.ndarray]) -> np.ndarray:
    """Element-wise ``max(a, b, ...)`` as Python's."""
    out = args[0]
    for b in args[1:]:
        out = np.where(b > out, b, out)
    return out


def shifted(x: np.ndarray, first: Any, dtype: DTypeLike) -> np.ndarray:
    """``x`` one tick later: ``first`` at tick 0, ``x[i-1]`` at tick ``i``."""
    n = len(x)
    out = np.empty(n, dtype)
    if n:
        out[0] = first
        out[1:] = x[:-1]
    return out
