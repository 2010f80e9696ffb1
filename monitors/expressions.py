"""FRETish expressions and FRET's temporal functions evaluated over the columns of a sampled
trace (one numpy array per FRET variable, one item per tick), for FRET's interval semantics
(:mod:`fretc.monitors.interval`).

Values follow the generated monitors' conventions (a number read as a condition is
``bool(x)``; ``/`` by zero is NaN). Each temporal function is computed from the "meaning"
column of ``../shared/fretish/README.md`` section 6b, relative to the scope's ``Left`` /
``Right`` (:func:`fretc.monitors.interval.endpoints`) or in FRET's endpoint-free forms inside scope
conditions; index ``n`` is FRET's absorbing state after the trace (section 6's trace model).
"""

from __future__ import annotations

import builtins
import functools
from collections.abc import Mapping

import numpy as np

from fretc.compiler.expressions import Expander, SemanticsError
from fretc.compiler.ir import TRUE
from fretc.compiler.printers import to_smv
from fretc.fretish import ast as A
from fretc.fretish.fret_since import SINCE, stream_name

from fretc.monitors.arrays import COMPARISONS, CONNECTIVES, arith, connective, py_max, py_min, shifted

__all__ = ["ColumnExpressions", "EvidenceUnsupported"]

class EvidenceUnsupported(ValueError):
    """The requirement uses something the direct interval semantics does not evaluate: an
    uninterpreted function (one FRET does not define) or a free-form sentence."""


#: Stands for "no endpoint": before the first tick / past the absorbing state.
_FAR = 1 << 40

_PAST_FUNCS = ("persisted", "occurred", "prevOcc", "preBool")


class ColumnExpressions:
    """Evaluates fretish AST expressions over columns, at the ``n`` ticks of the trace and
    at FRET's absorbing state after it (index ``n``: every variable false, every number 0;
    ``../shared/fretish/README.md`` section 6), which future-time functions near the end of
    the trace read. Past-time functions (and comparisons of ``preInt``/``preReal``) are
    false there, as FRET's derived past atoms.

    ``left``/``right`` (bool arrays of ``n`` items, :func:`endpoints`) are the scope's
    ``Left``/``Right`` the temporal functions are relative to; ``free`` selects FRET's
    endpoint-free forms (inside scope conditions). Every array is ``n + 1`` items; each
    function costs O(n) (prefix counts, next/last-true indexes)."""

    def __init__(self, columns: Mapping[str, np.ndarray], n: int,
                 left: np.ndarray | None = None, right: np.ndarray | None = None,
                 free: bool = False):
        self.columns = columns
        self.n = n
        self.N = n + 1
        self.free = free or left is None
        self._cols: dict[str, np.ndarray] = {}
        if not self.free:
            self.left = np.concatenate((np.asarray(left, np.bool_), [False]))
            self.right = np.concatenate((np.asarray(right, np.bool_), [False]))

    # (the index arrays, 8 bytes a tick each, are made when a temporal function reads them)
    @functools.cached_property
    def idx(self) -> np.ndarray:
        """Each position's index, ``0..n`` (``int64``)."""
        return np.arange(self.N, dtype=np.int64)

    @functools.cached_property
    def s_last(self) -> np.ndarray:
        """The last ``Left`` at or before each position (``-_FAR`` where none)."""
        return np.maximum.accumulate(np.where(self.left, self.idx, -_FAR))

    @functools.cached_property
    def e_next(self) -> np.ndarray:
        """The first ``Right`` at or after each position (``_FAR`` where none)."""
        return np.minimum.accumulate(np.where(self.right, self.idx, _FAR)[::-1])[::-1]

    def ticks(self, name: str) -> np.ndarray:
        """The column of FRET variable ``name`` at the ``n`` ticks, without the absorbing
        state (a view, no copy). Raises as :meth:`column`."""
        col = self.columns.get(name)
        if col is None:
            raise KeyError(name)
        col = np.asarray(col)
        if len(col) < self.n:
            raise ValueError(f"column {name!r} has {len(col)} values for {self.n} ticks")
        return col[:self.n]

    def column(self, name: str) -> np.ndarray:
        """The column of FRET variable ``name`` with the absorbing state appended (``n + 1``
        items). Raises KeyError for a variable without a column, ValueError for a column
        shorter than the trace."""
        got = self._cols.get(name)
        if got is not None:
            return got
        col = self.ticks(name)
        absorbing = np.zeros(1, dtype=col.dtype if col.dtype != object else np.float64)
        got = np.concatenate((col, absorbing))
        self._cols[name] = got
        return got

    def _compare_leaves(self, op: str, a: A.Expr, b: A.Expr) -> np.ndarray:
        """``a op b`` for a variable or number on each side, as :meth:`bool` computes it
        but without copying a column to append the absorbing state (a number there is 0)."""
        def ticks(e: A.Expr):
            if isinstance(e, A.Var):
                return self.ticks(e.name).astype(np.float64, copy=False), np.float64(0.0)
            assert isinstance(e, A.NumLit)
            value = np.float64(float(e.value))
            return value, value

        (x, x_end), (y, y_end) = ticks(a), ticks(b)
        out = np.empty(self.N, np.bool_)
        with np.errstate(invalid="ignore"):
            COMPARISONS[op](x, y, out=out[:self.n])
            out[self.n] = COMPARISONS[op](x_end, y_end)
        return out

    def bool(self, e: A.Expr) -> np.ndarray:
        """Boolean expression ``e`` at every tick and the absorbing state (``n + 1`` bools).
        Raises :class:`EvidenceUnsupported` for what the interval semantics does not take."""
        N = self.N
        if isinstance(e, A.Var):
            if e.name == "FTP":
                return self.idx == 0
            c = self.column(e.name)
            return c if c.dtype == np.bool_ else c.astype(np.bool_)
        if isinstance(e, A.BoolLit):
            return np.full(N, bool(e.value))
        if isinstance(e, A.Unary):
            if e.op == "!":
                return ~self.bool(e.operand)
            raise EvidenceUnsupported("arithmetic minus where a condition is expected")
        if isinstance(e, A.Binary):
            op = e.op
            if op in A.COMPARISON_OPS:
                if all(_leaf(x) for x in (e.left, e.right)):
                    return self._compare_leaves(op, e.left, e.right)
                x, y = self.num(e.left), self.num(e.right)
                with np.errstate(invalid="ignore"):
                    out = COMPARISONS[op](x, y)
                if _has_pre(e):  # a derived past atom: false in the absorbing state
                    out = out.copy()
                    out[self.n] = False
                return out
            a, b = self.bool(e.left), self.bool(e.right)
            if op in CONNECTIVES:
                return connective(op, a, b)
            raise EvidenceUnsupported(f"arithmetic '{op}' where a condition is expected")
        if isinstance(e, A.Call):
            return self.bool_call(e)
        raise EvidenceUnsupported(f"cannot evaluate {type(e).__name__}")

    def num(self, e: A.Expr) -> np.ndarray:
        """Numeric expression ``e`` at every tick and the absorbing state (``n + 1`` float64;
        ``/`` by zero NaN, as the generated monitors)."""
        N = self.N
        if isinstance(e, A.Var):  # (read only: every caller makes a new array of it)
            return self.column(e.name).astype(np.float64, copy=False)
        if isinstance(e, A.NumLit):  # one number read at every tick (a read-only view)
            return np.broadcast_to(np.float64(float(e.value)), (N,))
        if isinstance(e, A.Unary) and e.op == "-":
            return -self.num(e.operand)
        if isinstance(e, A.Binary) and e.op in A.ARITH_OPS:
            return arith(e.op, self.num(e.left), self.num(e.right))
        if isinstance(e, A.Call):
            name, args = e.name, e.args
            if name == "ite" and len(args) == 3:
                return np.where(self.bool(args[0]), self.num(args[1]), self.num(args[2]))
            if name in ("absReal", "absInt") and len(args) == 1:
                return np.abs(self.num(args[0]))
            if name in ("minReal", "minInt", "maxReal", "maxInt") and args:
                vals = [self.num(a) for a in args]
                return py_min(vals) if name.startswith("min") else py_max(vals)
            if name in ("preInt", "preReal") and len(args) == 2:
                init, x = self.num(args[0]), self.num(args[1])
                return shifted(x, init[0], np.float64)
            return self.uninterpreted(e, numeric=True)
        raise EvidenceUnsupported(f"cannot evaluate {type(e).__name__} as a number")

    def uninterpreted(self, e: A.Call, numeric: builtins.bool) -> np.ndarray:
        """A function FRET does not define (``sqrt(weight)``, ``det_3x3(...)``), read as the
        generated monitors read it: the trace's column named by the printed call
        (:func:`fretc.compiler.printers.to_smv` of its IR, e.g. ``sqrt(weight)``),
        ``n + 1`` items. Raises :class:`EvidenceUnsupported` when the trace has no such
        column (the semantics cannot compute it)."""
        try:
            x = Expander("ft", TRUE, TRUE, free=True)
            key = to_smv(x.term(e) if numeric else x.bool(e))
        except SemanticsError as exc:
            raise EvidenceUnsupported(str(exc)) from exc
        if key not in self.columns:
            raise EvidenceUnsupported(f"function {e.name}/{len(e.args)} is not evaluated by "
                                      f"the interval semantics and the trace has no column "
                                      f"{key!r}")
        c = self.column(key)
        if numeric:
            return c.astype(np.float64)
        return c if c.dtype == np.bool_ else c.astype(np.bool_)

    def _int(self, a: A.Expr) -> int:
        if isinstance(a, A.NumLit) and isinstance(a.value, int) and a.value >= 0:
            return a.value
        raise EvidenceUnsupported("a temporal-function bound that is not an integer literal")

    # counts of p over windows, positions clamped to [0, n] (positions past the trace all
    # repeat the absorbing state n; positions before 0 do not exist)
    def _counts(self, p: np.ndarray):
        cs = np.zeros(self.N + 1, np.int64)
        np.cumsum(p, out=cs[1:])

        def count(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
            lo_c = np.clip(lo, 0, self.n)
            hi_c = np.clip(hi, -1, self.n)
            return np.where(hi_c >= lo_c, cs[np.maximum(hi_c, lo_c - 1) + 1] - cs[lo_c], 0)

        return count

    def bool_call(self, e: A.Call) -> np.ndarray:
        """A boolean call: ``ite`` or one of FRET's temporal functions (section 6b of
        ``../shared/fretish/README.md``), ``n + 1`` bools."""
        name, args = e.name, e.args
        if name == "ite" and len(args) == 3:
            c = self.bool(args[0])
            return (c & self.bool(args[1])) | (~c & self.bool(args[2]))
        if name == "preBool" and len(args) == 2 and isinstance(args[0], A.BoolLit):
            out = shifted(self.bool(args[1]), bool(args[0].value), np.bool_)
            out[self.n] = False  # a derived past atom in the absorbing state
            return out
        if name in ("persisted", "occurred", "persists", "occurs") and len(args) in (2, 3):
            if len(args) == 2:
                m, k, p = 0, self._int(args[0]), self.bool(args[1])
            else:
                m, k, p = self._int(args[0]), self._int(args[1]), self.bool(args[2])
            if m > k:
                raise EvidenceUnsupported(f"{name}: lower bound {m} above upper bound {k}")
            return self._window(name, m, k, p)
        if name in ("prevOcc", "nextOcc") and len(args) == 2:
            p, q = self.bool(args[0]), self.bool(args[1])
            return self._prev_occ(p, q) if name == "prevOcc" else self._next_occ(p, q)
        if name == SINCE and len(args) == 2:
            return self._since(self.bool(args[0]), self.bool(args[1]))
        if stream_name(e) is not None:
            return self._stream(self.bool(args[0]), self.bool(args[1]))
        return self.uninterpreted(e, numeric=False)

    def _stream(self, p: np.ndarray, q: np.ndarray) -> np.ndarray:
        """A FRET boolean stream by its state bit (:func:`fretc.fretish.fret_since.
        stream_expansion`): ``p`` at a tick where it held at the previous one, else ``q``
        (``q`` at the first), tick by tick as :mod:`fretc.compiler.stream_code` computes
        it; false in the absorbing state (a derived past atom)."""
        out = np.zeros(self.N, dtype=np.bool_)
        prev = False
        for t, (x, y) in enumerate(zip(p[:self.n].tolist(), q[:self.n].tolist())):
            prev = out[t] = x if prev else y
        return out

    def _since(self, a: np.ndarray, c: np.ndarray) -> np.ndarray:
        """``a S c`` over the whole trace (a FRET stream monotone in its previous value,
        :mod:`fretc.fretish.fret_since`): ``c`` at some k <= t and ``a`` at every tick of
        (k, t], i.e. the last ``c`` at or after the last ``!a``; false in the absorbing
        state (a derived past atom)."""
        i = self.idx
        last_c = np.maximum.accumulate(np.where(c, i, -1))
        last_not_a = np.maximum.accumulate(np.where(a, -1, i))
        out = (last_c >= 0) & (last_c >= last_not_a)
        out[self.n] = False
        return out

    def _window(self, name: str, m: int, k: int, p: np.ndarray) -> np.ndarray:
        """``persisted``/``occurred``/``persists``/``occurs`` with bounds ``[m, k]``
        (section 6b's meaning column; endpoint-free: ``H``/``O``/``G``/``F`` over
        ``[m, k]``)."""
        i, n = self.idx, self.n
        count = self._counts(p)
        free = self.free
        if name == "persisted":   # p at every position t-k..t-m, and s <= t-k
            lo, hi = np.maximum(i - k, 0), i - m
            out = count(lo, hi) == np.maximum(hi - lo + 1, 0)
            if not free:
                out &= self.s_last <= i - k
        elif name == "occurred":  # p at some j, max(s, t-k) <= j <= t-m
            lo = np.maximum(i - k, 0)
            if not free:
                lo = np.maximum(lo, self.s_last)
            out = count(lo, i - m) > 0
        elif name == "persists":  # p at every position t+m..t+k, and e >= t+k
            lo, hi = np.minimum(i + m, n), np.minimum(i + k, n)
            out = count(lo, hi) == hi - lo + 1
            if not free:
                out &= self.e_next >= i + k
        else:                     # occurs: p at some j, t+m <= j <= min(t+k, e)
            hi = i + k if free else np.minimum(i + k, self.e_next)
            lo = i + m
            out = (hi >= lo) & (count(np.minimum(lo, n), np.minimum(hi, n)) > 0)
        if name in _PAST_FUNCS:
            out[n] = False  # a derived past atom in the absorbing state
        return out

    def _prev_occ(self, p: np.ndarray, q: np.ndarray) -> np.ndarray:
        """``prevOcc(p, q)``: true at t = s; else q at the last p in [s, t-1], true if
        none (section 6b); endpoint-free ``Y((!p) S (p & q))``: q at the last p before t,
        false if none. False at tick 0 off an interval start (FRET's ``Y``)."""
        i, n = self.idx, self.n
        last_p = np.maximum.accumulate(np.where(p, i, -1))
        j = np.concatenate(([-1], last_p[:-1]))        # the last p at or before t-1
        q_at_j = np.where(j >= 0, q[np.maximum(j, 0)], False)
        if self.free:
            out = (j >= 0) & q_at_j
        else:
            s_prev = np.concatenate(([-_FAR], self.s_last[:-1]))
            out = self.left | ((i >= 1) & ((j < 0) | (j < s_prev) | q_at_j))
        out[n] = False
        return out

    def _next_occ(self, p: np.ndarray, q: np.ndarray) -> np.ndarray:
        """``nextOcc(p, q)``: true at t = e; else q at the first p in [t+1, e], true if
        none (section 6b); endpoint-free ``X((!p) U (p & q))``: q at the first p after t,
        false if none. The absorbing state (index n) stands for every position after the
        trace."""
        i, n = self.idx, self.n
        next_p = np.minimum.accumulate(np.where(p, i, _FAR)[::-1])[::-1]
        u = np.minimum(i + 1, n)                       # X: the next position
        j = next_p[u]                                  # the first p at or after t+1
        found = j < _FAR
        q_at_j = np.where(found, q[np.minimum(j, n)], False)
        if self.free:
            return found & q_at_j
        reached = found & (self.e_next[u] >= j)        # no Right in [t+1, j)
        return self.right | ~reached | q_at_j


def _leaf(e: A.Expr) -> bool:
    """A variable with a column (not ``FTP``) or a number."""
    return (isinstance(e, A.Var) and e.name != "FTP") or isinstance(e, A.NumLit)


def _has_pre(e: A.Expr) -> bool:
    """Does a comparison read ``preInt``/``preReal`` (a derived past atom in ft)?"""
    return any(isinstance(x, A.Call) and x.name in ("preInt", "preReal") for x in A.walk(e))
