"""Three-valued evaluation of a requirement over a trace with unknown ticks (a gap in the log,
a comparison with NaN): what every way of filling the unknown ticks agrees on.

A tick can be unknown for some variables only (a gap holds some topics; a NaN is one
operand). The pt formula is evaluated over pairs of bool arrays ``(lo, hi)``: ``lo`` true
where the value is true whatever the unknown ticks held, ``hi`` true where it may be true
(Kleene's strong three-valued logic). Negation swaps the pair; every other operator of a pt
formula (``& | -> <-> xor``, ``Y Z O H S T`` and their bounded forms) is applied to ``lo``
and ``hi`` alone, which is exact for each operator and sound for the whole formula: where
``lo`` is true every completion of the unknown ticks satisfies, where ``hi`` is false every
one violates (Kleene 1952; the same three-valued reading as LTL3's, Bauer, Leucker,
Schallhart, TOSEM 2011). Numbers carry an unknown mask through arithmetic; a comparison is
unknown where an operand is, and, under fretc's NaN rule (docs/guide/ticks.md, "NaN"), where
an operand is NaN.

A *gap tick* (``stretch``: a ``gap`` row of a CSV trace, a tick a gap of a tick topic
lost, docs/guide/ticks.md) stands for one tick or more, how many not known: its pair is what
every one of those ticks, for every count, may be, and a tick after it reads the ticks before
it at every distance from the one a single tick gives on (:meth:`ThreeValued.pair`).

FRET's finite-trace verdict is the pt formula at the last tick
(:func:`fretc.monitors.completions.pt_verdict`); the
LTL3 verdict runs the monitor automata over every letter an unknown tick may be
(:func:`ltl3_verdict`): definite once every run is decided.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from fretc.compiler.ir import Node, name_of
from fretc.compiler.printers import to_smv
from fretc.monitors.arrays import COMPARISONS, arith, py_max, py_min, shifted
from fretc.monitors.vectorized import VectorizeError

if TYPE_CHECKING:
    from fretc.compiler.codegen import MonitorSource

__all__ = ["Pair", "ThreeValued", "ltl3_verdict", "stretched_window"]

Pair = tuple[np.ndarray, np.ndarray]
_FUTURE = ("X", "F", "G", "U", "V", "LAST", "future")
_FUNCS = {"absReal": lambda a: np.abs(a[0]), "absInt": lambda a: np.abs(a[0]),
          "minReal": py_min, "minInt": py_min, "maxReal": py_max, "maxInt": py_max}


def _since(x: np.ndarray, y: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """``x S y`` at every tick (the latest ``y`` no older than the latest ``!x``)."""
    if not len(idx):
        return idx.astype(np.bool_)
    last_y = np.maximum.accumulate(np.where(y, idx, -1))
    last_not_x = np.maximum.accumulate(np.where(x, -1, idx))
    return (last_y >= 0) & (last_not_x <= last_y)


def _hits(x: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Whether ``x`` is true at some tick of ``[lower[i], upper[i]]``, at every ``i`` (an
    empty range where ``upper < lower``; bounds clipped to the ticks)."""
    n = len(x)
    cs = np.zeros(n + 1, np.int64)
    np.cumsum(x, out=cs[1:])
    lower = np.clip(lower, 0, n)
    upper = np.clip(upper + 1, 0, n)
    return (upper > lower) & (cs[upper] - cs[np.minimum(lower, upper)] > 0)


def stretched_window(pair: tuple[np.ndarray, np.ndarray], lo: int, hi: int, once: bool,
                     stretch: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``O[lo,hi]`` (``once``) or ``H[lo,hi]`` of the Kleene ``pair`` over ticks some of
    which are gap ticks (``stretch``, bool array: each one tick or more). Tick ``s`` lies at
    the distance ``i - s`` from tick ``i`` when no gap tick lies in ``[s, i]``, else at any
    distance from ``i - s`` on: ``O`` may be true where its operand may be at a tick some
    count puts in the window, and is true where it is at a tick every count does (the tick
    itself, at distance 0, for a gap tick and ``lo == 0``); ``H`` is the dual. Sound for every
    count of every gap (Kleene 1952)."""
    x_lo, x_hi = pair
    n = len(x_lo)
    idx = np.arange(n, dtype=np.int64)
    last_gap = np.maximum.accumulate(np.where(stretch, idx, -1)) if n else idx
    may_lower = idx - hi
    may_upper = np.maximum(idx - lo, last_gap)
    sure_lower = np.maximum(idx - hi, last_gap + 1 - (stretch & (lo == 0)))
    sure_upper = idx - lo
    if once:
        return _hits(x_lo, sure_lower, sure_upper), _hits(x_hi, may_lower, may_upper)
    return ~_hits(~x_lo, may_lower, may_upper), ~_hits(~x_hi, sure_lower, sure_upper)


def _window(x: np.ndarray, lo: int, hi: int, once: bool, idx: np.ndarray) -> np.ndarray:
    """``O[lo,hi] x`` (``once``) or ``H[lo,hi] x``: window sums over ``[i-hi, i-lo]``."""
    n = len(x)
    hits = x if once else ~x
    cs = np.zeros(n + 1, np.int64)
    np.cumsum(hits, out=cs[1:])
    upper = idx - lo
    lower = np.maximum(idx - hi, 0)
    nonempty = upper >= 0
    count = np.where(nonempty, cs[np.clip(upper + 1, 0, n)] - cs[np.minimum(lower, n)], 0)
    return nonempty & (count > 0) if once else ~nonempty | (count == 0)


class ThreeValued:
    """A pt formula's nodes over ``n`` ticks of ``columns`` with the variables' unknown
    ticks ``unknown`` (variable -> bool array of ``n``); ``nan_unknown``: a NaN operand of a
    comparison (or a NaN number read as a condition) is unknown (fretc's default NaN rule;
    False under ``[tick] nan = "false"``, where NaN compares as IEEE 754 says); ``stretch``:
    the gap ticks (bool array of ``n``; module docstring), their variables unknown in
    ``unknown`` too.

    Raises:
        VectorizeError: (from :meth:`pair`) a future-time operator, or a missing column.
    """

    def __init__(self, columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray],
                 n: int, nan_unknown: bool = True, stretch: np.ndarray | None = None):
        self.columns, self.unknown, self.n = columns, unknown, n
        self.nan_unknown = nan_unknown
        #: the gap ticks (None: none)
        self.stretch = (np.asarray(stretch[:n], np.bool_)
                        if stretch is not None and np.any(stretch[:n]) else None)
        self.idx = np.arange(n, dtype=np.int64)
        self.none = np.zeros(n, np.bool_)
        any_unknown = self.none.copy()
        for m in unknown.values():
            any_unknown |= np.asarray(m[:n], np.bool_)
        self.any_unknown = any_unknown
        self._memo: dict[tuple[Node, bool], object] = {}

    # ------------------------------------------------------------------ leaves
    def _column(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        col = self.columns.get(name)
        if col is None:
            raise VectorizeError(f"no column for variable {name!r}")
        col = np.asarray(col)[:self.n]
        if col.shape != (self.n,):
            raise VectorizeError(f"column {name!r} has {len(col)} ticks, expected {self.n}")
        unk = self.unknown.get(name)
        return col, (self.none if unk is None else np.asarray(unk[:self.n], np.bool_))

    def _bool_leaf(self, name: str) -> Pair:
        col, unk = self._column(name)
        if col.dtype != np.bool_:
            if self.nan_unknown:
                unk = unk | np.isnan(col.astype(np.float64))
            col = col.astype(np.bool_)
        return col & ~unk, col | unk

    # ------------------------------------------------------------------ evaluation
    def pair(self, node: Node) -> Pair:
        """``(lo, hi)`` of a boolean node (module docstring)."""
        key = (node, False)
        got = self._memo.get(key)
        if got is None:
            got = self._memo[key] = self._pair(node)
        return got  # type: ignore[return-value]

    def fix(self, node: Node, values: np.ndarray) -> None:
        """Read the boolean ``node`` as known, ``values`` (bool array over the ticks) at
        every tick, from here on: a completion of its unknown ticks
        (:func:`fretc.monitors.completions.completed_verdict`). Nodes above it evaluated
        before keep their pairs: fix the leaves first."""
        self._memo[(node, False)] = (values, values)

    def number(self, node: Node) -> tuple[np.ndarray, np.ndarray]:
        """``(values, unknown)`` of a numeric node: float values (those of the columns as
        read) and where they are unknown."""
        key = (node, True)
        got = self._memo.get(key)
        if got is None:
            got = self._memo[key] = self._number(node)
        return got  # type: ignore[return-value]

    def _pair(self, node: Node) -> Pair:
        op, a, n = node.op, node.args, self.n
        if op in _FUTURE:
            raise VectorizeError(f"future-time operator {op!r} in a past-time formula")
        if op == "true":
            return np.ones(n, np.bool_), np.ones(n, np.bool_)
        if op == "false":
            return self.none, self.none
        if op == "FTP":
            first = self.idx == 0
            if self.stretch is not None and n and self.stretch[0]:
                return first & False, first  # (a gap at the first tick: its later ticks)
            return first, first
        if op == "ap":
            return self._bool_leaf(name_of(node))
        if op == "call":  # an uninterpreted predicate: unknown where anything is
            col = np.asarray(self._column_of_call(node), np.bool_)
            return col & ~self.any_unknown, col | self.any_unknown
        if op == "!":
            lo, hi = self.pair(a[0])
            return ~hi, ~lo
        if op in ("&", "|", "->", "<->", "xor"):
            return self._connective(op, self.pair(a[0]), self.pair(a[1]))
        if op == "cmp":
            (x, ux), (y, uy) = self.number(a[0]), self.number(a[1])
            with np.errstate(invalid="ignore"):
                val = COMPARISONS[name_of(node)](x, y)
            unk = ux | uy
            if self.nan_unknown:
                unk = unk | np.isnan(x) | np.isnan(y)
            return val & ~unk, val | unk
        if op == "ite":
            c, t, e = self.pair(a[0]), self.pair(a[1]), self.pair(a[2])
            return ((c[0] & t[0]) | (~c[1] & e[0]) | (t[0] & e[0]),
                    (c[1] & t[1]) | (~c[0] & e[1]))
        if op == "past":
            return self.pair(a[0])
        if op in ("Y", "Z"):
            lo, hi = self.pair(a[0])
            z = op == "Z"
            y_lo, y_hi = shifted(lo, z, np.bool_), shifted(hi, z, np.bool_)
            g = self.stretch
            if g is not None:  # a gap's later ticks read its own
                y_lo, y_hi = y_lo & ~(g & ~lo), y_hi | (g & hi)
            return y_lo, y_hi
        if op in ("O", "H"):
            return self._once(node)
        if op in ("S", "T"):
            (xl, xh), (yl, yh) = self.pair(a[0]), self.pair(a[1])
            if op == "S":
                return _since(xl, yl, self.idx), _since(xh, yh, self.idx)
            return ~_since(~xl, ~yl, self.idx), ~_since(~xh, ~yh, self.idx)
        if op in ("var", "fn", "arith", "neg", "pre", "num"):  # a number read as a condition
            x, unk = self.number(node)
            if self.nan_unknown:
                unk = unk | np.isnan(x)
            val = x.astype(np.bool_)
            return val & ~unk, val | unk
        raise VectorizeError(f"cannot evaluate IR node {op!r}")

    def _column_of_call(self, node: Node) -> np.ndarray:
        col = self.columns.get(to_smv(node))
        if col is None:
            raise VectorizeError(f"no column for {to_smv(node)!r}")
        return np.asarray(col)[:self.n]

    @staticmethod
    def _connective(op: str, x: Pair, y: Pair) -> Pair:
        (xl, xh), (yl, yh) = x, y
        if op == "&":
            return xl & yl, xh & yh
        if op == "|":
            return xl | yl, xh | yh
        if op == "->":
            return ~xh | yl, ~xl | yh
        both = (xl & yl) | (~xh & ~yh)          # surely equal
        differ = (xl & ~yh) | (~xh & yl)         # surely different
        maybe_equal = ~differ
        maybe_differ = ~both
        if op == "<->":
            return both, maybe_equal
        return differ, maybe_differ             # xor

    def _once(self, node: Node) -> Pair:
        lo, hi = self.pair(node.args[0])
        once = node.op == "O"
        if node.hi is None:
            acc = np.logical_or.accumulate if once else np.logical_and.accumulate
            return (acc(lo), acc(hi)) if self.n else (lo, hi)
        b_lo, b_hi = node.lo or 0, node.hi
        if self.stretch is not None:
            return stretched_window((lo, hi), b_lo, b_hi, once, self.stretch)
        return (_window(lo, b_lo, b_hi, once, self.idx),
                _window(hi, b_lo, b_hi, once, self.idx))

    def _number(self, node: Node) -> tuple[np.ndarray, np.ndarray]:
        op, a, n = node.op, node.args, self.n
        if op == "num":
            return np.full(n, float(name_of(node)), np.float64), self.none
        if op == "var" or op == "ap":
            col, unk = self._column(name_of(node))
            return col.astype(np.float64), unk
        if op == "fn" and node.name not in _FUNCS:  # an uninterpreted function
            col = self._column_of_call(node).astype(np.float64)
            return col, self.any_unknown
        if op == "fn":
            args = [self.number(x) for x in a]
            unk = self.none
            for _v, u in args:
                unk = unk | u
            return _FUNCS[name_of(node)]([v for v, _u in args]), unk
        if op == "arith":
            (x, ux), (y, uy) = self.number(a[0]), self.number(a[1])
            return arith(name_of(node), x, y), ux | uy
        if op == "neg":
            x, ux = self.number(a[0])
            return -x, ux
        if op == "pre":
            (i0, u0), (x, ux) = self.number(a[0]), self.number(a[1])
            px = shifted(x, i0[0] if n else None, np.float64)
            pu = shifted(ux, bool(u0[0]) if n else False, np.bool_)
            g = self.stretch
            if g is not None:  # a gap's later ticks read its own values
                with np.errstate(invalid="ignore"):
                    pu = pu | (g & (ux | ~((px == x) | (np.isnan(px) & np.isnan(x)))))
            return px, pu
        if op == "ite":
            c = self.pair(a[0])
            (t, ut), (e, ue) = self.number(a[1]), self.number(a[2])
            known = c[0] == c[1]
            return np.where(c[0], t, e), np.where(known, np.where(c[0], ut, ue), True)
        if op == "past":
            return self.number(a[0])
        lo, hi = self.pair(node)  # a condition read as a number: 0/1
        return lo.astype(np.float64), lo != hi


def ltl3_verdict(monitor_source: MonitorSource, ev: ThreeValued) -> tuple[str, int | None]:
    """The earliest definite LTL3 verdict of the monitor automata of
    :func:`fretc.compiler.codegen.monitor_source` over ``ev``'s ticks, an unknown atom
    standing for both of its values (the set of states every letter an unknown tick may be
    leads to). ``("violated", i)`` once every run of the ``bad`` automaton (for ft_inf) is
    rejected at tick ``i``; ``("satisfied", i)`` likewise for ``good`` (its negation);
    ``("unknown", None)`` otherwise.

    Raises:
        VectorizeError: an automaton given as condition chains (too many atoms to tabulate),
            or an atom that cannot be evaluated over columns.
    """
    ms = monitor_source
    bad, good = ms.bad, ms.good
    if bad is not None and bad.empty:
        return "violated", None
    if good is not None and good.empty:
        return "satisfied", None
    best: tuple[str, int | None] = ("unknown", None)
    for aut, outcome in ((bad, "violated"), (good, "satisfied")):
        if aut is None or aut.complete:
            continue
        if aut.table is None:
            raise VectorizeError("automaton with condition chains: no table")
        hit = _first_rejection(aut, ev)
        if hit is not None and (best[1] is None or hit < best[1]):
            best = (outcome, hit)
    return best


def _first_rejection(aut, ev: ThreeValued) -> int | None:
    """The first tick at which every run of ``aut`` over the possible letters is rejected
    (a negative state), or None."""
    known = np.zeros(ev.n, np.int64)
    free: list[np.ndarray] = []
    for j, atom in enumerate(aut.atoms):
        lo, hi = ev.pair(atom)
        known |= lo.astype(np.int64) << j
        free.append(lo != hi)
    free_bits = np.zeros(ev.n, np.int64)
    for j, f in enumerate(free):
        free_bits |= f.astype(np.int64) << j
    states = {aut.initial}
    table = aut.table
    gaps = ev.stretch
    for i in range(ev.n):
        letters = _letters(int(known[i]), int(free_bits[i]))
        live = _moved(table, states, letters)
        if not live:
            return i
        if gaps is not None and gaps[i]:  # one tick or more: every count's states
            live = _reach(table, live, letters)
        states = live
    return None


def _moved(table: list[list[int]], states: set[int], letters: list[int]) -> set[int]:
    """The live states (>= 0) ``table`` moves ``states`` to on any of ``letters``."""
    return {t for s in states for x in letters if (t := table[s][x]) >= 0}


def _reach(table: list[list[int]], states: set[int], letters: list[int]) -> set[int]:
    """``states`` with every live state further ticks of ``letters`` lead to (a gap tick
    standing for one tick or more: the states after it for every count)."""
    seen, frontier = set(states), set(states)
    while frontier:
        frontier = _moved(table, frontier, letters) - seen
        seen |= frontier
    return seen


def _letters(fixed: int, free: int) -> list[int]:
    """Every letter that agrees with ``fixed`` outside the bits of ``free``."""
    out = [fixed & ~free]
    bit = 1
    while free >= bit:
        if free & bit:
            out += [x | bit for x in out]
        bit <<= 1
    return out
