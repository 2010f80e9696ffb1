"""Vectorized (numpy) evaluation of past-time formulas over a whole sampled trace.

The generated monitors (:mod:`fretc.compiler.codegen`) compute the pt formula tick by tick in
Python; for an offline audit of a long log the same values can be computed for all ticks
at once from the columns of the sampled trace (one 1-D array per FRET variable). This module
does that, operator by operator, with exactly the semantics of the generated ``step()``
(which is the Havelund-Rosu dynamic programme; Havelund & Rosu, TACAS 2002):

Design notes: ARCHITECTURE.md, `monitors/vectorized.py`."""

from __future__ import annotations

import builtins
import functools
from collections.abc import Mapping, Sequence

import numpy as np

from fretc.compiler.ir import Node, name_of, walk
from fretc.compiler.printers import to_smv

from fretc.monitors.arrays import COMPARISONS, CONNECTIVES, arith, connective, py_max, py_min, shifted

__all__ = ["VectorizeError", "pt_series", "node_series", "atom_letters", "supports"]

Columns = Mapping[str, np.ndarray]


class VectorizeError(ValueError):
    """The formula cannot be evaluated over columns: a future-time operator or a future-time
    function in a pt formula (FRET leaves those unexpanded), or a variable missing from the
    columns (the message names it)."""


_FUTURE = ("X", "F", "G", "U", "V", "LAST", "future")


@functools.lru_cache(maxsize=1024)
def supports(node: Node) -> bool:
    """True when :func:`pt_series` can evaluate ``node`` (no future-time operator); kept
    per formula (asked again for each trace a requirement judges)."""
    return not any(n.op in _FUTURE for n in walk(node))


class _Series:
    """Memoized per-node arrays over ``n`` ticks."""

    def __init__(self, columns: Columns, n: int, starts: np.ndarray | None = None):
        self.columns = columns
        self.n = n
        self.memo: dict[tuple[Node, bool], np.ndarray] = {}
        #: the first tick of each tick's trace (0 for every tick of one trace)
        self.seg: np.ndarray | np.int64 = starts if starts is not None else np.int64(0)

    # (the index arrays are made when an operator reads them, and then kept)
    @functools.cached_property
    def idx(self) -> np.ndarray:
        """Each tick's index (``int64``)."""
        return np.arange(self.n, dtype=np.int64)

    @functools.cached_property
    def first(self) -> np.ndarray:
        """Whether each tick is its trace's first (bool)."""
        if isinstance(self.seg, np.ndarray):
            return self.idx == self.seg
        out = np.zeros(self.n, np.bool_)
        out[:1] = True
        return out

    # ------------------------------------------------------------------ reading variables
    def read(self, name: str, numeric: bool) -> np.ndarray:
        col = self.columns.get(name)
        if col is None:
            raise VectorizeError(f"no column for variable {name!r}")
        col = np.asarray(col)
        if col.shape != (self.n,):
            raise VectorizeError(f"column {name!r} has shape {col.shape}, expected ({self.n},)")
        if numeric:
            return col.astype(np.float64, copy=False)
        if col.dtype == np.bool_:
            return col
        return col.astype(np.bool_)  # bool(x): NaN and non-zero are true

    # ------------------------------------------------------------------ evaluation
    def bool(self, node: Node) -> np.ndarray:
        return self.get(node, False)

    def num(self, node: Node) -> np.ndarray:
        return self.get(node, True)

    def get(self, node: Node, numeric: builtins.bool) -> np.ndarray:
        key = (node, numeric)
        got = self.memo.get(key)
        if got is None:
            got = self._compute(node, numeric)
            self.memo[key] = got
        return got

    def _compute(self, node: Node, numeric: builtins.bool) -> np.ndarray:
        op = node.op
        if op in _FUTURE:
            raise VectorizeError(f"future-time operator {op!r} (or function "
                                 f"{node.name or ''}) in a past-time formula")
        if op == "!" or op in CONNECTIVES:
            return self._connective(node)
        if op in ("Y", "Z", "O", "H", "S", "T"):
            return self._temporal(node)
        if op in ("cmp", "arith", "neg", "fn", "ite", "pre", "past") and (
                op != "fn" or node.name in _FUNCS):
            return self._term(node, numeric)
        return self._leaf(node, numeric)

    def _leaf(self, node: Node, numeric: builtins.bool) -> np.ndarray:
        """Constants, variables, FTP, and uninterpreted calls (read as columns named by
        their text)."""
        op, n = node.op, self.n
        if op == "true":
            return np.ones(n, np.bool_)
        if op == "false":
            return np.zeros(n, np.bool_)
        if op == "FTP":
            return self.first.copy()
        if op in ("ap", "var"):
            return self.read(name_of(node), numeric=(op == "var"))
        if op in ("call", "fn"):
            return self.read(to_smv(node), numeric=(op == "fn"))
        if op == "num":  # one number read at every tick (a read-only view, no array)
            return np.broadcast_to(np.float64(float(name_of(node))), (n,))
        raise VectorizeError(f"cannot evaluate IR node {op!r}")

    def _term(self, node: Node, numeric: builtins.bool) -> np.ndarray:
        """Comparisons, arithmetic, the numeric functions, ``ite``, ``pre``."""
        op, a = node.op, node.args
        if op == "cmp":
            x, y = self.num(a[0]), self.num(a[1])
            return COMPARISONS[name_of(node)](x, y)
        if op == "arith":
            return arith(name_of(node), self.num(a[0]), self.num(a[1]))
        if op == "neg":
            return -self.num(a[0])
        if op == "fn":
            args = [self.num(x) for x in a]
            return _FUNCS[name_of(node)](args)
        if op == "ite":
            c = self.bool(a[0])
            if numeric:
                return np.where(c, self.num(a[1]), self.num(a[2]))
            return np.where(c, self.bool(a[1]), self.bool(a[2]))
        if op == "pre":
            init, x = self.num(a[0]), self.num(a[1])
            out = shifted(x, init[0] if self.n else None, np.float64)
            out[self.first] = init[self.first]
            return out
        return self.get(a[0], numeric)  # "past"

    def _connective(self, node: Node) -> np.ndarray:
        op, a = node.op, node.args
        if op == "!":
            return ~self.bool(a[0])
        return connective(op, self.bool(a[0]), self.bool(a[1]))

    def _temporal(self, node: Node) -> np.ndarray:
        """The past-time operators (module docstring's table)."""
        op, a, n = node.op, node.args, self.n
        if op in ("Y", "Z"):
            out = shifted(self.bool(a[0]), op == "Z", np.bool_)
            out[self.first] = op == "Z"
            return out
        if op in ("O", "H") and node.hi is None:
            x = self.bool(a[0])
            if not n:
                return x
            if op == "O":  # the last tick holding x, in this trace
                return np.maximum.accumulate(np.where(x, self.idx, -1)) >= self.seg
            return np.maximum.accumulate(np.where(x, -1, self.idx)) < self.seg
        if op in ("O", "H"):
            return self._bounded_once(node)
        x, y = self.bool(a[0]), self.bool(a[1])
        if op == "T":
            x, y = ~x, ~y
        last_y = np.maximum.accumulate(np.where(y, self.idx, -1)) if n else self.idx
        last_not_x = np.maximum.accumulate(np.where(x, -1, self.idx)) if n else self.idx
        s = (last_y >= self.seg) & (last_not_x <= last_y)
        return ~s if op == "T" else s

    def _bounded_once(self, node: Node) -> np.ndarray:
        """``O[lo,hi]`` / ``H[lo,hi]``: window sums of hits (``x`` for O, ``!x`` for H) in
        ``[max(0, i-hi), i-lo]``."""
        op, n = node.op, self.n
        x = self.bool(node.args[0])
        lo, hi = node.lo or 0, node.hi
        assert hi is not None  # (bounded)
        hits = x if op == "O" else ~x
        cs = np.zeros(n + 1, np.int64)
        np.cumsum(hits, out=cs[1:])
        upper = self.idx - lo  # inclusive
        lower = np.maximum(self.idx - hi, self.seg)
        nonempty = upper >= self.seg
        count = np.where(nonempty, cs[np.clip(upper + 1, 0, n)] - cs[np.minimum(lower, n)], 0)
        if op == "O":
            return nonempty & (count > 0)
        return ~nonempty | (count == 0)


_FUNCS = {
    "absReal": lambda a: np.abs(a[0]), "absInt": lambda a: np.abs(a[0]),
    "minReal": py_min, "minInt": py_min, "maxReal": py_max, "maxInt": py_max,
}


def node_series(node: Node, columns: Columns, n: int, numeric: bool = False) -> np.ndarray:
    """Values of one IR node (boolean, or numeric with ``numeric=True``) at ticks ``0..n-1``.

    Args:
        node: an IR node without future-time operators.
        columns: FRET variable (or printed uninterpreted call) -> 1-D array of ``n`` values
            (bool, int or float; read as ``bool(x)`` where a condition is expected).
        n: number of ticks.

    Raises:
        VectorizeError: a future-time operator, or a missing or mis-shaped column.
    """
    return _Series(columns, n).get(node, numeric)


def pt_series(node: Node, columns: Columns, n: int, starts: np.ndarray | None = None
              ) -> np.ndarray:
    """The pt verdict at every tick: ``out[i]`` equals the value the generated monitor's
    ``step()`` returns at tick ``i`` (bool array of shape ``(n,)``); ``out[-1]`` is the
    FRET finite-trace verdict of the whole run. ``starts``: several traces laid end to end
    (int64 array: the index of each tick's trace's first tick; module docstring), each
    trace's verdict at its last tick.

    Raises:
        VectorizeError: as :func:`node_series`.
    """
    return _Series(columns, n, starts).bool(node)


def atom_letters(atoms: Sequence[Node], columns: Columns, n: int,
                 starts: np.ndarray | None = None) -> np.ndarray:
    """The automaton letter at each tick: bit ``j`` is the truth of ``atoms[j]`` (a
    ``uint16`` array for at most 16 atoms, else ``int64``). Same bit order as the generated
    ``sub`` expressions. ``starts`` as :func:`pt_series`."""
    ev = _Series(columns, n, starts)
    dtype = np.dtype(np.uint16 if len(atoms) <= 16 else np.int64)
    out = np.zeros(n, dtype)
    for j, a in enumerate(atoms):
        np.bitwise_or(out, np.left_shift(ev.bool(a).astype(dtype), j, dtype=dtype), out=out)
    return out
