"""Kleene's three-valued reading of a requirement's pt formula over a trace with unknown ticks
(a gap in the log, a comparison with NaN), and the LTL3 verdict over every letter an unknown
tick may be, over a trace fed a chunk of ticks at a time (:class:`KleeneStream`,
:class:`Ltl3SetStream`); judging a whole trace is feeding it one chunk
(:func:`kleene_values`, :func:`ltl3_verdict`).

Design notes: ARCHITECTURE.md, `monitors/three_valued.py`."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from fretc.compiler.ir import Node, name_of, walk
from fretc.compiler.printers import to_smv
from fretc.monitors.arrays import COMPARISONS, arith, py_max, py_min, shifted
from fretc.monitors.judge import earliest_verdict
from fretc.monitors.robustness import _Rho, chunkable
from fretc.monitors.vectorized import VectorizeError, supports

if TYPE_CHECKING:
    from fretc.compiler.codegen import MonitorSource

__all__ = ["Pair", "Kleene", "KleeneStream", "Ltl3SetStream", "SKELETON", "kleene_unsupported",
           "kleene_values", "leaves_of", "letters_of", "ltl3_verdict", "order_of", "pair_of",
           "stretched_window"]

Pair = tuple[np.ndarray, np.ndarray]
_INF = math.inf
_FUTURE = ("X", "F", "G", "U", "V", "LAST", "future")
#: nodes :class:`_Rho` evaluates (temporal operators, FTP)
_TEMPORAL = frozenset(("Y", "Z", "O", "H", "S", "T", "FTP", "past"))
#: the functions the evaluator interprets (any other is uninterpreted)
_FUNCS = {"absReal": lambda a: np.abs(a[0]), "absInt": lambda a: np.abs(a[0]),
          "minReal": py_min, "minInt": py_min, "maxReal": py_max, "maxInt": py_max}


def kleene_unsupported(node: Node, whole: bool = False) -> str | None:
    """None when Kleene's reading of ``node`` can be fed a chunk at a time (``whole``: fed the
    whole trace as one chunk), else why not, in words: a future-time operator or a node the
    vectorized engine does not evaluate; and, a chunk at a time, a comparison over a
    past-time value or ``pre``, or an uninterpreted function (unknown wherever any variable
    is)."""
    if any(x.op in _FUTURE for x in walk(node)) or not supports(node):
        return "a future-time operator or a node not evaluated over columns"
    if whole:
        return None
    if not chunkable(node):
        return "a comparison reads a past-time value or pre"
    if any(x.op == "call" or (x.op == "fn" and x.name not in _FUNCS) for x in walk(node)):
        return "an uninterpreted function (unknown wherever any variable is)"
    return None


#: the boolean and temporal operators of a pt formula: its *skeleton*; any other node is a
#: *leaf* (a comparison, a variable, a call, a boolean if-then-else: read as one value a tick)
SKELETON = ("!", "&", "|", "->", "<->", "xor", "past", "Y", "Z", "O", "H", "S", "T")


def order_of(root: Node) -> list[Node]:
    """The formula's skeleton nodes and leaves (:data:`SKELETON`), children first, each
    once."""
    out: list[Node] = []
    seen: set[Node] = set()
    stack: list[tuple[Node, bool]] = [(root, False)]
    while stack:
        node, done = stack.pop()
        if done:
            if node not in seen:
                seen.add(node)
                out.append(node)
            continue
        if node in seen:
            continue
        stack.append((node, True))
        if node.op in SKELETON:
            stack.extend((a, False) for a in reversed(node.args))
    return out


def leaves_of(pt: Node) -> list[Node]:
    """The leaves of ``pt`` (:data:`SKELETON`), each once, in :func:`order_of`'s order."""
    return [node for node in order_of(pt) if node.op not in SKELETON]


def pair_of(values: np.ndarray) -> Pair:
    """Kleene's ``(lo, hi)`` of values of :class:`Kleene`: true in every completion, may be
    true."""
    return values > 0, values >= 0


def _hits(x: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Whether ``x`` is true at some tick of ``[lower[i], upper[i]]``, at every ``i`` (an
    empty range where ``upper < lower``; bounds clipped to the ticks)."""
    n = len(x)
    cs = np.zeros(n + 1, np.int64)
    np.cumsum(x, out=cs[1:])
    lower = np.clip(lower, 0, n)
    upper = np.clip(upper + 1, 0, n)
    return (upper > lower) & (cs[upper] - cs[np.minimum(lower, upper)] > 0)


def stretched_window(pair: Pair, lo: int, hi: int, once: bool, stretch: np.ndarray) -> Pair:
    """``O[lo,hi]`` (``once``) or ``H[lo,hi]`` of the Kleene ``pair`` over ticks some of
    which are gap ticks (``stretch``, bool array: each one tick or more). Tick ``s`` lies at
    the distance ``i - s`` from tick ``i`` when no gap tick lies in ``[s, i]``, else at any
    distance from ``i - s`` on: ``O`` may be true where its operand may be at a tick some
    count puts in the window, and is true where it is at a tick every count does (the tick
    itself, at distance 0, for a gap tick and ``lo == 0``); ``H`` is the dual. Sound for every
    count of every gap (Kleene 1952). Only the ticks ``[i - hi, i]`` are read at tick ``i``."""
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


def _values(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Kleene's values (module docstring) of a pair."""
    return np.where(lo, _INF, np.where(hi, 0.0, -_INF))


class Kleene(_Rho):
    """Kleene's values (module docstring) of the nodes of the pt formula ``root`` over one
    chunk of ``n`` ticks of ``columns``, the trace's tick ``start`` its first, the temporal
    operators' state carried in ``carry`` (one dict per formula, empty at tick 0).

    Args:
        unknown: variable -> bool array of ``n``: its unknown ticks.
        nan_unknown: a NaN operand of a comparison (or a NaN number read as a condition) is
            unknown (fretc's NaN rule); False under ``[tick] nan = "false"``, where NaN
            compares as IEEE 754 says.
        stretch: the chunk's gap ticks (bool array of ``n``, their variables unknown in
            ``unknown`` too), or None.
        fixed: node -> its values over the chunk, read as given (a completion's leaves:
            :mod:`fretc.monitors.completions`).

    Raises:
        VectorizeError: (from :meth:`rho`) a future-time operator, or a missing column.
    """

    def __init__(self, columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray],
                 n: int, root: Node, start: int = 0, carry: dict | None = None, *,
                 nan_unknown: bool = True, stretch: np.ndarray | None = None,
                 fixed: Mapping[Node, np.ndarray] | None = None) -> None:
        super().__init__(columns, n, root, start, carry)
        self.unknown, self.nan_unknown, self.fixed = unknown, nan_unknown, fixed or {}
        self.stretch = (np.asarray(stretch[:n], np.bool_)
                        if stretch is not None and np.any(stretch[:n]) else None)
        self.none = np.zeros(n, np.bool_)
        any_unknown = self.none.copy()
        for m in unknown.values():
            any_unknown |= np.asarray(m[:n], np.bool_)
        self.any_unknown = any_unknown
        self._numbers: dict[Node, tuple[np.ndarray, np.ndarray]] = {}

    # ------------------------------------------------------------------ booleans
    def _compute(self, node: Node) -> np.ndarray:
        op, a = node.op, node.args
        got = self.fixed.get(node)
        if got is not None:
            return np.asarray(got, np.float64)
        if op in _FUTURE:
            raise VectorizeError(f"future-time operator {op!r} in a past-time formula")
        if op == "!":
            return -self.rho(a[0])
        if op in ("&", "|"):
            return self._connective(op, a[0], a[1])
        if op in ("->", "<->", "xor"):
            x, y = self.rho(a[0]), self.rho(a[1])
            if op == "->":
                return np.maximum(-x, y)
            iff = np.minimum(np.maximum(-x, y), np.maximum(x, -y))
            return iff if op == "<->" else -iff
        if op == "ite":
            c, t, e = self.rho(a[0]), self.rho(a[1]), self.rho(a[2])
            return np.maximum(np.maximum(np.minimum(c, t), np.minimum(-c, e)),
                              np.minimum(t, e))
        if op in ("Y", "Z"):
            return self._previous(node)
        if op == "FTP":
            out = super()._compute(node)
            if self.start == 0 and self.stretch is not None and self.stretch[0]:
                out[0] = 0.0  # (a gap at the first tick: its later ticks are not the first)
            return out
        if op in _TEMPORAL:
            return super()._compute(node)
        return _values(*self._atom(node))

    def _previous(self, node: Node) -> np.ndarray:
        """``Y``/``Z``: the operand one tick earlier (``-inf``/``+inf`` before tick 0); at a
        gap tick unknown where that differs from the gap's own (its later ticks read it)."""
        x = self.rho(node.args[0])
        out = np.empty(self.n)
        out[0] = self._carried(node, -_INF if node.op == "Y" else _INF)
        out[1:] = x[:-1]
        self._keep(node, float(x[-1]))
        g = self.stretch
        if g is not None:
            out = np.where(g & (np.sign(out) != np.sign(x)), 0.0, out)
        return out

    def _bounded(self, node: Node, x: np.ndarray) -> np.ndarray:
        """A bounded ``O``/``H`` (:meth:`_Rho._bounded`), counting the ticks of a gap as
        :func:`stretched_window` does where a gap tick lies in the window; the last ``hi``
        ticks' gaps carried with their values."""
        hi = node.hi
        assert hi is not None  # (a bounded operator)
        g = self.stretch if self.stretch is not None else self.none
        gaps = self._carried((node, "gaps"), g[:0])
        seen = np.concatenate((gaps, g))
        self._keep((node, "gaps"), seen[max(0, len(seen) - hi):].copy() if hi else g[:0])
        if not seen.any():
            return super()._bounded(node, x)
        tail = self._carried(node, x[:0])
        xs = np.concatenate((tail, x))
        self._keep(node, xs[max(0, len(xs) - hi):].copy() if hi else x[:0])
        got = stretched_window(pair_of(xs), node.lo or 0, hi, node.op == "O",
                               seen[len(seen) - len(xs):])
        return _values(*got)[len(tail):]

    def _atom(self, node: Node) -> Pair:
        """``(lo, hi)`` of a node that reads one tick (a comparison, a variable, a call, a
        number read as a condition)."""
        op, a = node.op, node.args
        if op == "true":
            return ~self.none, ~self.none
        if op == "false":
            return self.none, self.none
        if op == "ap":
            col, unk = self._column(name_of(node))
            if col.dtype != np.bool_:
                if self.nan_unknown:
                    unk = unk | np.isnan(col.astype(np.float64))
                col = col.astype(np.bool_)
            return col & ~unk, col | unk
        if op == "call":  # an uninterpreted predicate: unknown where anything is
            col = np.asarray(self._column_of_call(node), np.bool_)
            return col & ~self.any_unknown, col | self.any_unknown
        if op == "cmp":
            (x, ux), (y, uy) = self.number(a[0]), self.number(a[1])
            with np.errstate(invalid="ignore"):
                val = COMPARISONS[name_of(node)](x, y)
            unk = ux | uy
            if self.nan_unknown:
                unk = unk | np.isnan(x) | np.isnan(y)
            return val & ~unk, val | unk
        if op in ("var", "fn", "arith", "neg", "pre", "num"):  # a number read as a condition
            x, unk = self.number(node)
            if self.nan_unknown:
                unk = unk | np.isnan(x)
            val = x.astype(np.bool_)
            return val & ~unk, val | unk
        raise VectorizeError(f"cannot evaluate IR node {op!r}")

    # ------------------------------------------------------------------ numbers
    def number(self, node: Node) -> tuple[np.ndarray, np.ndarray]:
        """``(values, unknown)`` of a numeric node over the chunk: float values (those of the
        columns as read) and where they are unknown."""
        got = self._numbers.get(node)
        if got is None:
            got = self._numbers[node] = self._number(node)
        return got

    def _column(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        col = self.columns.get(name)
        if col is None:
            raise VectorizeError(f"no column for variable {name!r}")
        col = np.asarray(col)[:self.n]
        if col.shape != (self.n,):
            raise VectorizeError(f"column {name!r} has {len(col)} ticks, expected {self.n}")
        unk = self.unknown.get(name)
        return col, (self.none if unk is None else np.asarray(unk[:self.n], np.bool_))

    def _column_of_call(self, node: Node) -> np.ndarray:
        col = self.columns.get(to_smv(node))
        if col is None:
            raise VectorizeError(f"no column for {to_smv(node)!r}")
        return np.asarray(col)[:self.n]

    def _number(self, node: Node) -> tuple[np.ndarray, np.ndarray]:
        op, a, n = node.op, node.args, self.n
        if op == "num":
            return np.full(n, float(name_of(node)), np.float64), self.none
        if op == "var" or op == "ap":
            col, unk = self._column(name_of(node))
            return col.astype(np.float64), unk
        if op == "fn" and node.name not in _FUNCS:  # an uninterpreted function
            return self._column_of_call(node).astype(np.float64), self.any_unknown
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
            return self._pre(node)
        if op == "ite":
            c = pair_of(self.rho(a[0]))
            (t, ut), (e, ue) = self.number(a[1]), self.number(a[2])
            known = c[0] == c[1]
            return np.where(c[0], t, e), np.where(known, np.where(c[0], ut, ue), True)
        if op == "past":
            return self.number(a[0])
        lo, hi = pair_of(self.rho(node))  # a condition read as a number: 0/1
        return lo.astype(np.float64), lo != hi

    def _pre(self, node: Node) -> tuple[np.ndarray, np.ndarray]:
        """``pre(init, x)``: ``x`` one tick earlier (``init``'s first value at the first
        tick); at a gap tick unknown where that differs from the gap's own."""
        n = self.n
        (i0, u0), (x, ux) = self.number(node.args[0]), self.number(node.args[1])
        px = shifted(x, i0[0] if n else None, np.float64)
        pu = shifted(ux, bool(u0[0]) if n else False, np.bool_)
        g = self.stretch
        if g is not None:  # a gap's later ticks read its own values
            with np.errstate(invalid="ignore"):
                pu = pu | (g & (ux | ~((px == x) | (np.isnan(px) & np.isnan(x)))))
        return px, pu


def kleene_values(node: Node, columns: Mapping[str, np.ndarray],
                  unknown: Mapping[str, np.ndarray], k: int, start: int, carry: dict, *,
                  nan_unknown: bool = True, stretch: np.ndarray | None = None,
                  fixed: Mapping[Node, np.ndarray] | None = None) -> np.ndarray:
    """Kleene's value of the past-time formula ``node`` (module docstring: ``> 0`` true,
    ``>= 0`` may be true) at the trace's ticks ``start .. start+k-1`` (float array
    ``(k,)``), its temporal operators' state carried in ``carry`` (one dict per formula,
    empty at tick 0); the other arguments as :class:`Kleene`'s. Over a whole trace:
    ``start`` 0, an empty ``carry``.

    Raises:
        VectorizeError: as :class:`Kleene`."""
    return Kleene(columns, unknown, k, node, start, carry, nan_unknown=nan_unknown,
                  stretch=stretch, fixed=fixed).rho(node)


class KleeneStream:
    """Kleene's reading of a pt formula at the last tick of a trace fed a chunk at a time,
    the last tick where it may be true, and the first and last ticks where one of its
    leaves (as :mod:`fretc.monitors.completions` reads them) is unknown or a gap tick lies:
    where its completions are to be followed.

    Args:
        pt: the pt formula.
        nan_unknown: as :class:`Kleene`'s.
        whole: a formula :func:`kleene_unsupported` refuses a chunk at a time is taken, fed
            the whole trace as one chunk.

    Raises:
        VectorizeError: (constructor) :func:`kleene_unsupported`'s reason."""

    def __init__(self, pt: Node, nan_unknown: bool = True, whole: bool = False) -> None:
        why = kleene_unsupported(pt, whole)
        self.at_once = kleene_unsupported(pt) is not None
        if why is not None:
            raise VectorizeError(why)
        self.pt, self.nan_unknown = pt, nan_unknown
        self.carry: dict = {}
        self.start = 0
        self.last = math.nan
        #: the last tick at which ``hi`` is true (None: none so far)
        self.last_hi: int | None = None
        #: the formula's leaves as :mod:`fretc.monitors.completions` reads them (each with
        #: its own state), and the first and last tick where one of them is unknown or a
        #: gap tick lies
        self.leaves: dict[Node, dict] = {node: {} for node in leaves_of(pt)}
        self.free: tuple[int, int] | None = None

    def feed(self, columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray],
             k: int, stretch: np.ndarray | None = None) -> None:
        """The next ``k >= 0`` ticks (``columns``, ``unknown`` and ``stretch`` as
        :func:`kleene_values` takes them).

        Raises:
            ValueError: a second chunk of a formula fed the whole trace as one chunk."""
        if k <= 0:
            return
        if self.at_once and self.start:
            raise ValueError("the pt formula is read over the whole trace as one chunk")
        nan_unknown = self.nan_unknown
        values = kleene_values(self.pt, columns, unknown, k, self.start, self.carry,
                               nan_unknown=nan_unknown, stretch=stretch)
        free = np.zeros(k, np.bool_) if stretch is None else np.array(stretch[:k], np.bool_)
        for leaf, carry in self.leaves.items():
            v = kleene_values(leaf, columns, unknown, k, self.start, carry,
                              nan_unknown=nan_unknown, stretch=stretch)
            free |= (v >= 0) & ~(v > 0)
        at = np.flatnonzero(free)
        if len(at):
            first = self.free[0] if self.free is not None else self.start + int(at[0])
            self.free = (first, self.start + int(at[-1]))
        self.last = float(values[-1])
        may = np.flatnonzero(values >= 0)
        if len(may):
            self.last_hi = self.start + int(may[-1])
        self.start += k

    def finish(self) -> tuple[bool, bool, int | None]:
        """``(lo, hi, last_hi)`` at the last tick fed: true in every completion, may be true,
        and the last tick where the formula may be true (None: nowhere).

        Raises:
            ValueError: no tick was fed."""
        if self.start == 0:
            raise ValueError("no tick was fed")
        return self.last > 0, self.last >= 0, self.last_hi


@dataclass
class _Sets:
    """One live automaton of :class:`Ltl3SetStream`: its table, the set of its states,
    atoms, what its rejection means, and the tick and time every run was rejected at."""

    table: list[list[int]]
    states: set[int]
    atoms: tuple[Node, ...]
    outcome: str
    hit: int | None = None
    hit_time: int | None = None
    #: the atoms' temporal operators' state (atom -> carry)
    carry: dict = field(default_factory=dict)


class Ltl3SetStream:
    """The LTL3 verdict over a trace fed a chunk of ticks at a time (module docstring): each
    live automaton (``bad``: rejection means *violated*; ``good``: *satisfied*) runs over
    the set of states every letter an unknown tick may be leads to, and stops when every run
    is rejected; the verdict is the earlier such tick (``bad``'s on a tie). Memory: the
    states (at most the automaton's), the atoms' values over one chunk and their temporal
    operators' state. ``nan_unknown`` and ``whole`` as :class:`KleeneStream`'s.

    Raises:
        VectorizeError: (constructor) an automaton with condition chains (no table), or an
            atom :func:`kleene_unsupported` refuses.
    """

    def __init__(self, monitor_source: MonitorSource, nan_unknown: bool = True,
                 whole: bool = False) -> None:
        ms = monitor_source
        bad, good = ms.bad, ms.good
        self.decided: str | None = None
        if bad is not None and bad.empty:
            self.decided = "violated"
        elif good is not None and good.empty:
            self.decided = "satisfied"
        self.live: list[_Sets] = []
        self.nan_unknown, self.at_once = nan_unknown, False
        for aut, outcome in ((bad, "violated"), (good, "satisfied")):
            if self.decided or aut is None or aut.complete:
                continue
            if aut.table is None:
                raise VectorizeError("automaton with condition chains: no table")
            for atom in aut.atoms:
                why = kleene_unsupported(atom, whole)
                if why is not None:
                    raise VectorizeError(f"atom {atom}: {why}")
                self.at_once = self.at_once or kleene_unsupported(atom) is not None
            self.live.append(_Sets(aut.table, {aut.initial}, tuple(aut.atoms), outcome))
        self.start = 0

    def feed(self, columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray],
             k: int, times: np.ndarray, stretch: np.ndarray | None = None) -> None:
        """The next ``k >= 0`` ticks (``columns``, ``unknown`` and ``stretch`` as
        :func:`kleene_values` takes them; ``times`` their times, int64 ns).

        Raises:
            ValueError: a second chunk of a stream fed the whole trace as one chunk."""
        if k <= 0:
            return
        if self.at_once and self.start:
            raise ValueError("an atom is read over the whole trace as one chunk")
        gaps = None if stretch is None or not np.any(stretch[:k]) else stretch[:k]
        for run in self.live:
            if run.hit is not None:
                continue
            known, free = letters_of(run.atoms, columns, unknown, k, self.start, run.carry,
                                     nan_unknown=self.nan_unknown, stretch=gaps)
            hit = _run(run, known, free, gaps)
            if hit is not None:
                run.hit, run.hit_time = self.start + hit, int(times[hit])
        self.start += k

    def finish(self) -> tuple[str, int | None, int | None]:
        """``(verdict, tick, time)`` over the ticks fed (``"unknown"``, None, None when no
        automaton rejected every run)."""
        return earliest_verdict(self.decided, self.live)


def letters_of(atoms: tuple[Node, ...], columns: Mapping[str, np.ndarray],
               unknown: Mapping[str, np.ndarray], k: int, start: int, carry: dict,
               **how: Any) -> tuple[np.ndarray, np.ndarray]:
    """The letters of ``k`` ticks over ``atoms`` (bit ``j`` atom ``j``): ``(known, free)``,
    the bits true in every completion and the bits unknown (int64 arrays); each atom's
    temporal state in ``carry`` (atom -> its carry); ``how`` as :func:`kleene_values`'s."""
    known = np.zeros(k, np.int64)
    free = np.zeros(k, np.int64)
    for j, atom in enumerate(atoms):
        v = kleene_values(atom, columns, unknown, k, start, carry.setdefault(atom, {}), **how)
        known |= (v > 0).astype(np.int64) << j
        free |= ((v >= 0) & ~(v > 0)).astype(np.int64) << j
    return known, free


def ltl3_verdict(monitor_source: MonitorSource, columns: Mapping[str, np.ndarray],
                 unknown: Mapping[str, np.ndarray], n: int, nan_unknown: bool = True,
                 stretch: np.ndarray | None = None) -> tuple[str, int | None]:
    """The earliest definite LTL3 verdict of the monitor automata of
    :func:`fretc.compiler.codegen.monitor_source` over a whole trace of ``n`` ticks, an
    unknown atom standing for both of its values and a gap tick for every count of ticks:
    an :class:`Ltl3SetStream` fed it as one chunk. ``("violated", i)`` once every run of
    the ``bad`` automaton (for ft_inf) is rejected at tick ``i``; ``("satisfied", i)``
    likewise for ``good`` (its negation); ``("unknown", None)`` otherwise.

    Raises:
        VectorizeError: an automaton given as condition chains (too many atoms to tabulate),
            or an atom that cannot be evaluated over columns.
    """
    stream = Ltl3SetStream(monitor_source, nan_unknown, whole=True)
    stream.feed(columns, unknown, n, np.arange(n, dtype=np.int64), stretch)
    status, tick, _time = stream.finish()
    return status, tick


def _run(run: _Sets, known: np.ndarray, free: np.ndarray, gaps: np.ndarray | None
         ) -> int | None:
    """Move ``run``'s states over one chunk's letters (``known`` bits, ``free`` bits
    unknown; ``gaps`` the gap ticks, or None); the chunk's index at which every run is
    rejected, or None. A single state over known letters moves as one table lookup a tick;
    at a gap tick the states take every state further ticks of its letters lead to."""
    table, states = run.table, run.states
    k = len(known)
    stops = free != 0 if gaps is None else (free != 0) | gaps
    unknown_at = np.flatnonzero(stops).tolist()
    letters = known.tolist()
    i = 0
    for stop in unknown_at + [k]:
        if len(states) == 1 and i < stop:  # known letters: one state through the table
            s = next(iter(states))
            for j in range(i, stop):
                s = table[s][letters[j]]
                if s < 0:
                    return j
            states = {s}
        else:
            for j in range(i, stop):
                nxt = {table[s][letters[j]] for s in states}
                states = {s for s in nxt if s >= 0}
                if not states:
                    return j
        if stop == k:
            break
        choices = _letters(letters[stop], int(free[stop]))
        states = _moved(table, states, choices)
        if not states:
            return stop
        if gaps is not None and gaps[stop]:  # one tick or more: every count's states
            states = _reach(table, states, choices)
        i = stop + 1
    run.states = states
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
