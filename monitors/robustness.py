"""Robustness (the margin behind a verdict): quantitative semantics of a requirement's pt
formula over the columns of a trace.

FRET's pt formula at the last tick is the requirement's finite-trace verdict
(../shared/fretish/README.md); this module evaluates the same formula with Donze and Maler's
space robustness (Donze, Maler, FORMATS 2010; Fainekos, Pappas, TCS 2009) instead of truth
values, operator by operator over the same columns :mod:`fretc.monitors.vectorized` reads:

=====================  ==============================================================
``x <= c``, ``x < c``   ``c - x``  (the signed distance to the threshold, in x's unit)
``x >= c``, ``x > c``   ``x - c``
``x = c`` / ``x != c``  ``-|x - c|`` / ``|x - c|``
boolean atom ``p``      ``+inf`` when ``p`` is true, ``-inf`` when false
``true`` / ``false``    ``+inf`` / ``-inf``; ``FTP`` ``+inf`` at tick 0, else ``-inf``
``!p``                  ``-p``
``p & q`` / ``p | q``   ``min`` / ``max`` (``->``, ``<->``, ``xor`` by their definitions)
``Y p`` / ``Z p``       ``p`` one tick earlier; ``-inf`` / ``+inf`` at tick 0
``O p`` / ``H p``       running ``max`` / ``min`` (bounded: over the window, an empty window
                        ``-inf`` for O and ``+inf`` for H)
``a S b``               ``max over j <= i of min(b[j], min over j < k <= i of a[k])``
``a T b``               ``min over j <= i of max(b[j], max over j < k <= i of a[k])``
=====================  ==============================================================

Sign convention (so that the sign always tells the verdict): a value ``>= 0`` means true,
``< 0`` false, everywhere. A comparison that is false at distance 0 (``x < c`` with
``x == c``, ``x != c`` with ``x == c``) or that involves NaN (false, or true for ``!=``) gets
the smallest magnitude of its sign: :data:`TINY` below zero when false, ``0.0`` when true; the
negation of a 0 is ``-TINY``. By induction every node's value is ``>= 0`` exactly where its
truth value is true, so the requirement's robustness is negative exactly when it is violated.

A boolean FRET variable has no distance: ``+-inf`` says "decided by a boolean, no margin".
A vacuous verdict has a value ``>= 0``: the margin by which the scope or condition stayed
away (``+inf`` when they are boolean).
"""

from __future__ import annotations

import math
from typing import Any
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

import numpy as np

from fretc.compiler.ir import Node, name_of, walk

from fretc.monitors.vectorized import VectorizeError, node_series

_FUTURE = ("X", "F", "G", "U", "V", "LAST", "future")

__all__ = ["Robustness", "TINY", "robustness", "robustness_of_traces", "robustness_columns",
           "robustness_series"]

#: The smallest positive double: ``-TINY`` is the robustness of a comparison false at
#: distance 0 (the module docstring's sign convention).
TINY = math.ulp(0.0)
_INF = math.inf

Columns = Mapping[str, np.ndarray]


@dataclass(frozen=True)
class Robustness:
    """A requirement's robustness on one trace.

    Attributes:
        value: the robustness of the pt formula at the last tick (the whole trace), in the
            unit of the comparison that decides it; ``+-inf`` when a boolean decides it.
            Negative exactly when FRET's finite-trace verdict is false.
        tick: the first 0-based tick whose margin equals ``value`` (where the trace came
            closest to violating, or violated).
        margin: float array ``(n,)``, the margin at every tick: the robustness of the body of
            a top-level ``H`` (what must hold at every tick), else of the pt formula at that
            tick.
    """

    value: float
    tick: int
    margin: np.ndarray


#: ticks evaluated at a time by :func:`robustness` (a long trace's formula is evaluated a
#: chunk at a time, carrying each temporal operator's state: the memory is the margin and a
#: few arrays of a chunk, not a few arrays of the whole trace)
ROBUSTNESS_CHUNK = 1 << 16


def robustness(pt: Node, columns: Columns, n: int, chunk: int | None = None) -> Robustness:
    """The robustness of the pt formula ``pt`` over ticks ``0..n-1`` (``n >= 1``), evaluated
    ``chunk`` ticks (default :data:`ROBUSTNESS_CHUNK`) at a time when ``n`` is longer (the same values: each temporal
    operator's state carried from chunk to chunk) unless a comparison's operands hold a
    past-time operator or ``pre`` (then over the whole trace at once).

    Raises:
        VectorizeError: a future-time operator or function in ``pt``, or a missing or
            mis-shaped column (as :func:`fretc.monitors.vectorized.pt_series`).
    """
    if n < 1:
        raise ValueError("robustness needs at least one tick")
    chunk = ROBUSTNESS_CHUNK if chunk is None else chunk
    top = pt.op == "H" and pt.hi is None  # the margin is that of the body of a top H
    body = pt.args[0] if top else pt
    if n > chunk and _chunkable(body, chunk):
        margin = np.empty(n, dtype=np.float64)
        carry: dict[Node, object] = {}
        for a in range(0, n, chunk):
            b = min(n, a + chunk)
            margin[a:b] = _Rho(_Window(columns, a, b), b - a, body, a, carry).rho(body)
    else:
        margin = _Rho(columns, n, body).rho(body)
    value = float(margin.min()) if top else float(margin[-1])
    tick = int(np.argmax(margin == value))  # the first tick at the value
    return Robustness(value, tick, margin)


#: operators :class:`_Rho` evaluates itself (carrying their state from chunk to chunk);
#: any other node is evaluated by :func:`fretc.monitors.vectorized.node_series`
_OWN = frozenset(("!", "&", "|", "->", "<->", "xor", "Y", "Z", "O", "H", "S", "T", "ite",
                  "past", "FTP"))
#: operators whose value at a tick depends on earlier ticks
_STATEFUL = frozenset(("Y", "Z", "O", "H", "S", "T", "FTP", "pre"))


def _chunkable(body: Node, chunk: int) -> bool:
    """Whether ``body`` can be evaluated a chunk at a time: every node
    :func:`~fretc.monitors.vectorized.node_series` evaluates (comparisons, atoms) depends on
    its own tick only, and no bounded window reaches back further than a chunk."""
    for node in walk(body):
        if node.op in ("O", "H") and node.hi is not None and node.hi > chunk:
            return False
        if node.op not in _OWN and any(x.op in _STATEFUL for x in walk(node)):
            return False
    return True


class _Window(Mapping):
    """The ticks ``a..b-1`` of every column (views)."""

    def __init__(self, columns: Columns, a: int, b: int) -> None:
        self.columns, self.a, self.b = columns, a, b

    def __getitem__(self, name: str) -> np.ndarray:
        return np.asarray(self.columns[name])[self.a:self.b]

    def __iter__(self) -> Iterator[str]:
        return iter(self.columns)

    def __len__(self) -> int:
        return len(self.columns)


def robustness_of_traces(pt: Node, columns: Columns, firsts: np.ndarray,
                         lengths: np.ndarray) -> list[Robustness] | None:
    """The robustness (:func:`robustness`) of each of ``len(firsts)`` traces laid end to end
    in ``columns`` (trace ``e`` its ``lengths[e] >= 1`` ticks from ``firsts[e]``), in one
    evaluation of the formula that restarts every temporal operator at each trace's first
    tick: the values :func:`robustness` gives each trace alone (equal by test). None when
    that evaluation cannot restart (a comparison's operand holds a past-time operator or
    ``pre``) or the traces hold more than :data:`ROBUSTNESS_CHUNK` ticks in all: judge them
    one at a time.

    Raises:
        VectorizeError: as :func:`robustness`."""
    got = robustness_columns(pt, columns, firsts, lengths)
    if got is None:
        return None
    margin, values, ticks = got
    return [Robustness(value, tick, margin[a:a + m].copy())
            for a, m, value, tick in zip(firsts.tolist(), lengths.tolist(), values.tolist(),
                                         ticks.tolist())]


def robustness_columns(pt: Node, columns: Columns, firsts: np.ndarray, lengths: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """:func:`robustness_of_traces` as columns: ``(margin, values, ticks)``, the margin of
    every tick of the traces laid end to end (float array of ``lengths.sum()``), and per
    trace its value and the first 0-based tick of the trace at that value (``0`` when none
    equals it: a NaN value), as :class:`Robustness` has them for one trace. None when
    :func:`robustness_of_traces` gives None.

    Raises:
        VectorizeError: as :func:`robustness`."""
    n = int(lengths.sum())
    top = pt.op == "H" and pt.hi is None
    body = pt.args[0] if top else pt
    if n > ROBUSTNESS_CHUNK or not _chunkable(body, 1 << 62):  # (any window: no chunks)
        return None
    margin = _Traces(columns, n, body, np.repeat(firsts, lengths)).rho(body)
    values = (np.minimum.reduceat(margin, firsts) if top else margin[firsts + lengths - 1])
    trace = np.repeat(np.arange(len(firsts), dtype=np.int64), lengths)
    far = np.iinfo(np.int64).max
    at = np.where(margin == values[trace], np.arange(n, dtype=np.int64) - firsts[trace], far)
    ticks = np.minimum.reduceat(at, firsts)
    ticks[ticks == far] = 0  # (np.argmax of no hit, as robustness() has it)
    return margin, values, ticks


def robustness_series(node: Node, columns: Columns, n: int) -> np.ndarray:
    """The robustness of a past-time formula ``node`` at every tick (float array ``(n,)``).

    Raises:
        VectorizeError: as :func:`robustness`.
    """
    return _Rho(columns, n, node).rho(node)


def _neg(x: np.ndarray) -> np.ndarray:
    """``-x``, with 0 (true) mapped to ``-TINY`` (false)."""
    return np.where(x == 0, -TINY, -x)


def _fix_sign(rho: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """``rho`` with its sign forced to the comparison's truth (equality of a strict
    comparison, NaN): ``0.0`` where true but not ``>= 0``, ``-TINY`` where false but not
    ``< 0``."""
    with np.errstate(invalid="ignore"):
        rho = np.where(truth & ~(rho >= 0), 0.0, rho)
        return np.where(~truth & ~(rho < 0), -TINY, rho)


#: ticks of a since (``S``, ``T``) recurrence run at a time (:meth:`_Rho._since`)
SINCE_CHUNK = 1 << 14


class _Rho:
    """Per-node robustness arrays over ``n`` ticks of the formula ``root``; a node read by
    several parents is kept until its last parent read it, any other array only while it
    is used (the memory is a few arrays of ``n`` floats, not one per node)."""

    def __init__(self, columns: Columns, n: int, root: Node, start: int = 0,
                 carry: dict | None = None):
        self.columns = columns
        self.n = n
        #: the trace's tick of index 0 here, and the temporal operators' state at the end of
        #: the ticks before it (node -> value), when the trace is evaluated in chunks
        self.start = start
        self.carry = carry
        self.memo: dict[Node, np.ndarray] = {}
        self.uses: dict[Node, int] = {}  # node -> reads by its parents still to come
        seen, stack = {root}, [root]
        while stack:
            for child in stack.pop().args:
                self.uses[child] = self.uses.get(child, 0) + 1
                if child not in seen:
                    seen.add(child)
                    stack.append(child)

    def rho(self, node: Node) -> np.ndarray:
        got = self.memo.get(node)
        if got is None:
            got = self._compute(node)
            if self.uses.get(node, 0) > 1:
                self.memo[node] = got
        left = self.uses.get(node, 0) - 1
        self.uses[node] = left
        if left <= 0:
            self.memo.pop(node, None)
        return got

    def _compute(self, node: Node) -> np.ndarray:
        op, a, n = node.op, node.args, self.n
        if op in _FUTURE:
            raise VectorizeError(f"future-time operator {op!r} in a past-time formula")
        if op == "cmp":
            return self._comparison(node)
        if op == "!":
            return _neg(self.rho(a[0]))
        if op in ("&", "|", "->", "<->", "xor"):
            return self._connective(op, a[0], a[1])
        if op in ("Y", "Z"):
            x = self.rho(a[0])
            out = np.empty(n)
            out[0] = self._carried(node, -_INF if op == "Y" else _INF)
            out[1:] = x[:-1]
            self._keep(node, float(x[-1]))
            return out
        if op == "FTP":
            out = np.full(n, -_INF)
            if self.start == 0:
                out[0] = _INF
            return out
        if op in ("O", "H"):
            return self._once(node)
        if op in ("S", "T"):
            return self._since(node)
        if op == "ite":  # a boolean if-then-else: (c & t) | (!c & e)
            c = self.rho(a[0])
            return np.maximum(np.minimum(c, self.rho(a[1])),
                              np.minimum(_neg(c), self.rho(a[2])))
        if op == "past":
            return self.rho(a[0])
        # constants, FTP, boolean variables and calls: +-inf by their truth
        truth = node_series(node, self.columns, n)
        return np.where(truth, _INF, -_INF)

    def _carried(self, node: Node, initial):
        """The state ``node`` carried from the chunk before (``initial`` at the start)."""
        if self.carry is None or node not in self.carry:
            return initial
        return self.carry[node]

    def _keep(self, node: Node, state) -> None:
        if self.carry is not None:
            self.carry[node] = state

    def _comparison(self, node: Node) -> np.ndarray:
        x = node_series(node.args[0], self.columns, self.n, numeric=True)
        y = node_series(node.args[1], self.columns, self.n, numeric=True)
        truth = node_series(node, self.columns, self.n)
        with np.errstate(invalid="ignore", over="ignore"):
            d = {"<": y - x, "<=": y - x, ">": x - y, ">=": x - y,
                 "=": -np.abs(x - y), "!=": np.abs(x - y)}[name_of(node)]
        return _fix_sign(d, truth)

    def _connective(self, op: str, p: Node, q: Node) -> np.ndarray:
        x, y = self.rho(p), self.rho(q)
        if op == "&":
            return np.minimum(x, y)
        if op == "|":
            return np.maximum(x, y)
        if op == "->":
            return np.maximum(_neg(x), y)
        iff = np.minimum(np.maximum(_neg(x), y), np.maximum(x, _neg(y)))
        return iff if op == "<->" else _neg(iff)

    def _once(self, node: Node) -> np.ndarray:
        """``O`` / ``H``: running max / min, or over the window ``[i-hi, i-lo]``."""
        x, is_once = self.rho(node.args[0]), node.op == "O"
        pick = np.maximum if is_once else np.minimum
        if node.hi is None:
            out = pick.accumulate(x)
            before = self._carried(node, None)
            if before is not None:
                out = pick(out, before)
            self._keep(node, float(out[-1]))
            return out
        lo, hi = node.lo or 0, node.hi
        tail = self._carried(node, x[:0])  # the last ``hi`` ticks before, where they exist
        if len(tail):
            x = np.concatenate((tail, x))
        m = len(x)
        out = np.full(m, -_INF if is_once else _INF)
        for d in range(lo, min(hi, m - 1) + 1):  # the value d ticks back, where it exists
            out[d:] = pick(out[d:], x[:m - d])
        self._keep(node, x[max(0, m - hi):].copy() if hi else x[:0])
        return out[len(tail):]

    def _since(self, node: Node) -> np.ndarray:
        """``a S b``: ``s[i] = max(b[i], min(a[i], s[i-1]))`` from ``s[-1] = -inf``; its dual
        ``a T b``: ``s[i] = min(b[i], max(a[i], s[i-1]))`` from ``+inf``. The recurrence
        runs over :data:`SINCE_CHUNK` ticks at a time as Python floats, so its memory is the
        output array and one chunk, not Python objects for every tick."""
        op = node.op
        a, b = self.rho(node.args[0]), self.rho(node.args[1])
        out = np.empty(self.n, dtype=np.float64)
        s = self._carried(node, -_INF if op == "S" else _INF)
        for k in range(0, self.n, SINCE_CHUNK):
            chunk = []
            if op == "S":
                for ai, bi in zip(a[k:k + SINCE_CHUNK].tolist(), b[k:k + SINCE_CHUNK].tolist()):
                    s = max(bi, min(ai, s))
                    chunk.append(s)
            else:
                for ai, bi in zip(a[k:k + SINCE_CHUNK].tolist(), b[k:k + SINCE_CHUNK].tolist()):
                    s = min(bi, max(ai, s))
                    chunk.append(s)
            out[k:k + len(chunk)] = chunk
        self._keep(node, s)
        return out


class _Traces(_Rho):
    """:class:`_Rho` over traces laid end to end: ``seg[i]`` the first tick of tick ``i``'s
    trace; the temporal operators start again at each trace's first tick (no carry)."""

    def __init__(self, columns: Columns, n: int, root: Node, seg: np.ndarray) -> None:
        super().__init__(columns, n, root)
        self.seg = seg
        self.first = np.arange(n, dtype=np.int64) == seg

    def _compute(self, node: Node) -> np.ndarray:
        op = node.op
        if op in ("Y", "Z"):
            out = np.empty(self.n)
            out[1:] = self.rho(node.args[0])[:-1]
            out[self.first] = -_INF if op == "Y" else _INF
            return out
        if op == "FTP":
            return np.where(self.first, _INF, -_INF)
        return super()._compute(node)

    def _scan(self, x: np.ndarray, combine: Any) -> np.ndarray:
        """The inclusive scan of ``x`` by ``combine(earlier, later)`` (associative) within
        each trace, by doubling (Hillis and Steele): ``log2`` of the longest trace numpy
        steps over all ticks, rather than a step per trace or per tick."""
        n, idx = self.n, np.arange(self.n, dtype=np.int64)
        longest = int((idx - self.seg).max()) + 1 if n else 0
        out, d = x, 1
        while d < longest:
            ok = idx[d:] - d >= self.seg[d:]  # (tick i - d in tick i's trace)
            new = out.copy() if out is x else out
            new[d:] = np.where(ok, combine(out[:-d], out[d:]), out[d:])
            out, d = new, d * 2
        return out.copy() if out is x else out

    def _once(self, node: Node) -> np.ndarray:
        x, is_once = self.rho(node.args[0]), node.op == "O"
        pick = np.maximum if is_once else np.minimum
        if node.hi is None:  # (max and min: exact whatever the order of the steps)
            return self._scan(x, pick)
        lo, hi, m = node.lo or 0, node.hi, self.n
        out = np.full(m, -_INF if is_once else _INF)
        idx = np.arange(m, dtype=np.int64)
        for d in range(lo, min(hi, m - 1) + 1):  # the value d ticks back, in the same trace
            inside = idx[d:] - d >= self.seg[d:]
            out[d:] = np.where(inside, pick(out[d:], x[:m - d]), out[d:])
        return out

    def _since(self, node: Node) -> np.ndarray:
        """``a S b`` and ``a T b`` (:meth:`_Rho._since`'s recurrences) restarting at each
        trace: each tick's step ``s -> max(b, min(a, s))`` (``S``) is the clamp of ``s`` to
        ``[b, max(a, b)]`` (``T``'s ``min(b, max(a, s))`` to ``[min(a, b), b]``), clamps
        compose into clamps, so the recurrence is a scan of clamps (:meth:`_scan`) read at
        the start value (``-inf``: the low end; ``+inf``: the high end). The values are
        the inputs' (no arithmetic): those of the tick by tick loop, which runs instead
        where an input is NaN or a negative zero (Python's ``max`` and ``min`` order
        them as it meets them)."""
        op = node.op
        a, b = self.rho(node.args[0]), self.rho(node.args[1])
        if not (np.isnan(a).any() or np.isnan(b).any()
                or ((a == 0) & np.signbit(a)).any() or ((b == 0) & np.signbit(b)).any()):
            lo, hi = (b, np.maximum(a, b)) if op == "S" else (np.minimum(a, b), b)
            both = np.stack((lo, hi))

            def compose(earlier: np.ndarray, later: np.ndarray) -> np.ndarray:
                return np.minimum(np.maximum(earlier, later[0]), later[1])

            got = self._scan_pairs(both, compose)
            return got[0] if op == "S" else got[1]
        return self._since_loop(op, a.tolist(), b.tolist())

    def _scan_pairs(self, x: np.ndarray, combine: Any) -> np.ndarray:
        """:meth:`_scan` of pairs (``x`` of shape ``(2, n)``, ``combine`` of such arrays)."""
        n, idx = self.n, np.arange(self.n, dtype=np.int64)
        longest = int((idx - self.seg).max()) + 1 if n else 0
        out, d = x, 1
        while d < longest:
            ok = idx[d:] - d >= self.seg[d:]
            new = out.copy()
            new[:, d:] = np.where(ok, combine(out[:, :-d], out[:, d:]), out[:, d:])
            out, d = new, d * 2
        return out

    def _since_loop(self, op: str, a: list, b: list) -> np.ndarray:
        """:meth:`_since` tick by tick (Python floats)."""
        start = -_INF if op == "S" else _INF
        out, s = [], start
        for ai, bi, first in zip(a, b, self.first.tolist()):
            if first:
                s = start
            s = max(bi, min(ai, s)) if op == "S" else min(bi, max(ai, s))
            out.append(s)
        return np.array(out, dtype=np.float64)
