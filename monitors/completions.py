"""FRET's finite-trace verdict over every way of filling a trace's unknown ticks, where Kleene's
three-valued reading (:mod:`fretc.monitors.three_valued`) leaves it open, over a trace fed a
chunk of ticks at a time (:class:`CompletionsStream`); judging a whole trace is feeding it one
chunk (:func:`decide`).

Design notes: ARCHITECTURE.md, `monitors/completions.py`."""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from fretc.compiler.ir import Node, walk
from fretc.monitors.three_valued import SKELETON, KleeneStream, kleene_values, order_of

__all__ = ["CompletionsStream", "TooManyStates", "MAX_STATES", "MAX_STEPS", "decide"]

#: the most states (times the letters of one tick) the run keeps
MAX_STATES = 4096
#: the most work of the run, in node evaluations: each step of a state costs the formula's
#: nodes and the values its bounded operators keep (about 1 us each, so about a second a
#: requirement at most; ``in m ... always satisfy y``, 21 nodes: about 57,000 ticks)
MAX_STEPS = 1_200_000

_INF = math.inf
_TEMPORAL = ("Y", "Z", "O", "H", "S", "T")
#: operators whose value depends on earlier ticks, inside a leaf
_STATEFUL = frozenset(("Y", "Z", "O", "H", "S", "T", "pre", "FTP"))


class TooManyStates(Exception):
    """The completions were not all followed: the states of one tick or the work of the
    run passed :data:`MAX_STATES` or :data:`MAX_STEPS` (the message says which, and at which
    tick)."""


class _Program:
    """The pt formula as a program of nodes (:func:`fretc.monitors.three_valued.order_of`)
    over one tick's leaf values and the state the temporal nodes keep."""

    def __init__(self, root: Node):
        self.nodes = order_of(root)
        self.index = {node: k for k, node in enumerate(self.nodes)}
        self.root = self.index[root]
        self.leaves = [k for k, node in enumerate(self.nodes) if node.op not in SKELETON]
        self.temporal = [k for k, node in enumerate(self.nodes) if node.op in _TEMPORAL]
        self.args = [[self.index[a] for a in node.args] if node.op in SKELETON else []
                     for node in self.nodes]
        #: the work of one step: the nodes, and the values the bounded operators keep
        self.cost = len(self.nodes) + sum(self.nodes[k].hi or 0 for k in self.temporal
                                          if self.nodes[k].op in ("O", "H"))

    def step(self, state: tuple[Any, ...], leaves: dict[int, bool], i: int
             ) -> tuple[bool, tuple[Any, ...]]:
        """The root's value at tick ``i`` and the state after it."""
        val: list[bool] = [False] * len(self.nodes)
        prev = dict(zip(self.temporal, state))
        nxt: dict[int, Any] = {}
        for k, node in enumerate(self.nodes):
            op = node.op
            a = self.args[k]
            if not a:
                v = leaves[k]
            elif op == "!":
                v = not val[a[0]]
            elif op == "&":
                v = val[a[0]] and val[a[1]]
            elif op == "|":
                v = val[a[0]] or val[a[1]]
            elif op == "->":
                v = (not val[a[0]]) or val[a[1]]
            elif op == "<->":
                v = val[a[0]] == val[a[1]]
            elif op == "xor":
                v = val[a[0]] != val[a[1]]
            elif op == "past":
                v = val[a[0]]
            elif op in ("Y", "Z"):
                v = (op == "Z") if i == 0 else bool(prev[k])
                nxt[k] = val[a[0]]
            elif op == "S":
                v = val[a[1]] or (val[a[0]] and i > 0 and bool(prev[k]))
                nxt[k] = v
            elif op == "T":
                v = val[a[1]] and (val[a[0]] or i == 0 or bool(prev[k]))
                nxt[k] = v
            elif node.hi is None:  # O, H unbounded
                if op == "O":
                    v = val[a[0]] or (i > 0 and bool(prev[k]))
                else:
                    v = val[a[0]] and (i == 0 or bool(prev[k]))
                nxt[k] = v
            else:  # O[lo,hi], H[lo,hi]: the operand over ticks i-hi .. i-lo
                hist = (val[a[0]],) + tuple(prev[k] if i else (None,) * node.hi)
                window = [x for x in hist[node.lo or 0:node.hi + 1] if x is not None]
                v = any(window) if op == "O" else all(window)
                nxt[k] = hist[:node.hi]
            val[k] = bool(v)
        return val[self.root], tuple(nxt[k] for k in self.temporal)


class CompletionsStream:
    """Every completion of the unknown ticks of ``pt`` over ``n`` ticks fed a chunk at a
    time, the first and last ticks where a leaf is unknown or a gap tick lies being ``first``
    and ``last`` (module docstring).

    Args:
        nan_unknown: as :class:`fretc.monitors.three_valued.Kleene`'s.

    Raises:
        ValueError: (constructor) ``0 <= first <= last < n`` does not hold.
    """

    def __init__(self, pt: Node, first: int, last: int, n: int,
                 nan_unknown: bool = True) -> None:
        if not 0 <= first <= last < n:
            raise ValueError(f"free ticks {first}..{last} outside 0..{n - 1}")
        self.pt, self.first, self.last, self.n = pt, first, last, n
        self.nan_unknown = nan_unknown
        self.prog = prog = _Program(pt)
        self.leaf_carry: dict[int, dict] = {k: {} for k in prog.leaves}
        #: leaves whose value reads earlier ticks: given their values after ``last``
        self.stateful = [k for k in prog.leaves
                         if any(x.op in _STATEFUL for x in walk(prog.nodes[k]))]
        #: before ``first``: node -> (its carry, its last definite values, how many kept)
        self.kept: dict[Node, tuple[dict, list[bool], int]] = {}
        for k in prog.temporal:
            node = prog.nodes[k]
            if node.op in ("Y", "Z"):
                self.kept.setdefault(node.args[0], ({}, [], 1))
            elif node.op in ("O", "H") and node.hi is not None:
                got = self.kept.get(node.args[0])
                keep = max(node.hi, got[2] if got else 0, 1)
                self.kept[node.args[0]] = ({}, [], keep)
            else:
                self.kept.setdefault(node, ({}, [], 1))
        self.states: dict[tuple[Any, ...], Any] | None = None
        self.carries: list[dict] | None = None  # (after ``last``: one per state)
        self.values: list[float] = []
        self.finals: set[bool] = set()
        self.steps = 0
        self.start = 0

    def feed(self, columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray],
             k: int, stretch: np.ndarray | None = None) -> None:
        """The next ``k >= 0`` ticks (``columns``, ``unknown`` and ``stretch`` as
        :func:`fretc.monitors.three_valued.kleene_values` takes them).

        Raises:
            TooManyStates: past :data:`MAX_STATES` or :data:`MAX_STEPS`."""
        if k <= 0:
            return
        a, b = self.start, self.start + k
        how = dict(nan_unknown=self.nan_unknown, stretch=stretch)
        if a < self.first:
            self._before(columns, unknown, k, min(b, self.first) - a, how)
        values = None
        if a <= self.last or self.stateful:  # (the leaves' state, for the ticks to come)
            values = self._leaves(columns, unknown, k, how)
        if a <= self.last and b > self.first:
            assert values is not None
            gaps = None if stretch is None else np.asarray(stretch[:k], np.bool_)
            self._free(values, gaps, max(a, self.first), min(b - 1, self.last))
        if b - 1 > self.last:
            self._after(columns, k, max(a, self.last + 1) - a, values)
        self.start = b

    def _before(self, columns, unknown, k: int, upto: int, how: dict) -> None:
        """Keep the values the state at ``first`` reads (ticks ``start .. start+upto-1``)."""
        for node, (carry, last, keep) in self.kept.items():
            v = kleene_values(node, columns, unknown, k, self.start, carry, **how)[:upto]
            last.extend(bool(x) for x in (v[-keep:] > 0).tolist())
            del last[:-keep]

    def _state_at_first(self) -> tuple[Any, ...]:
        """The program's state before ``first``, read from the values kept."""
        out: list[Any] = []
        i = self.first
        for k in self.prog.temporal:
            node = self.prog.nodes[k]
            if node.op in ("O", "H") and node.hi is not None:
                last = self.kept[node.args[0]][1]
                out.append(tuple(last[-1 - d] if d < len(last) and i - 1 - d >= 0 else None
                                 for d in range(node.hi)))
            else:
                last = self.kept[node.args[0] if node.op in ("Y", "Z") else node][1]
                out.append(last[-1] if i else None)
        return tuple(out)

    def _leaves(self, columns, unknown, k: int, how: dict) -> dict[int, np.ndarray]:
        """Each leaf's Kleene value over the chunk (its state carried)."""
        return {j: kleene_values(self.prog.nodes[j], columns, unknown, k, self.start, carry,
                                 **how)
                for j, carry in self.leaf_carry.items()}

    def _free(self, values: dict[int, np.ndarray], gaps: np.ndarray | None, lo_tick: int,
              hi_tick: int) -> None:
        """Step the states over the ticks ``lo_tick .. hi_tick`` (in this chunk, whose
        leaves' values are ``values`` and gap ticks ``gaps``)."""
        prog, a = self.prog, self.start
        if self.states is None:
            self.states = {self._state_at_first(): None}
        for i in range(lo_tick, hi_tick + 1):
            known = {j: bool(values[j][i - a] > 0) for j in prog.leaves}
            free = [j for j in prog.leaves if values[j][i - a] == 0]
            letters = 1 << len(free)
            self.steps += len(self.states) * letters * prog.cost
            self._bound(len(self.states) * letters, letters, f"at tick {i}", i)
            nxt: dict[tuple[Any, ...], Any] = {}
            for state in self.states:
                for bits in itertools.product((False, True), repeat=len(free)):
                    leaves = dict(known)
                    leaves.update(zip(free, bits))
                    root, after = prog.step(state, leaves, i)
                    if i == self.n - 1:
                        self.finals.add(root)
                    nxt.setdefault(after, None)
            if gaps is not None and gaps[i - a]:
                self._stretch(nxt, known, free, i)
            self.states = nxt

    def _bound(self, states: int, letters: int, where: str, i: int) -> None:
        """Raise :class:`TooManyStates` past the bounds (read as set: tests lower them)."""
        if states > MAX_STATES:
            raise TooManyStates(f"{states // letters} states times {letters} letters {where} "
                                f"(bound {MAX_STATES})")
        if self.steps > MAX_STEPS:
            raise TooManyStates(f"more than {MAX_STEPS} node evaluations by tick {i}")

    def _stretch(self, states: dict[tuple[Any, ...], Any], known: dict[int, bool],
                 free: list[int], i: int) -> None:
        """Add to ``states`` (those one tick of the gap tick ``i`` leads to) every state
        further ticks of the gap lead to, each tick any letter of the ``free`` leaves (a gap
        stands for one tick or more); at the last tick each of them may end the trace."""
        prog = self.prog
        frontier = list(states)
        later = max(i, 1)  # (the gap's later ticks are not the trace's first)
        letters = 1 << len(free)
        while frontier:
            self.steps += len(frontier) * letters * prog.cost
            self._bound(len(states) * letters, letters, f"in the gap at tick {i}", i)
            nxt = []
            for state in frontier:
                for bits in itertools.product((False, True), repeat=len(free)):
                    leaves = dict(known)
                    leaves.update(zip(free, bits))
                    root, after = prog.step(state, leaves, later)
                    if i == self.n - 1:
                        self.finals.add(root)
                    if after not in states:
                        states[after] = None
                        nxt.append(after)
            frontier = nxt

    def _after(self, columns, k: int, at: int, values: dict[int, np.ndarray] | None) -> None:
        """Evaluate each state's completion over the chunk's ticks from ``at``."""
        if self.carries is None:
            assert self.states is not None  # (the free ticks came first)
            self.carries = [self._carry(state) for state in self.states]
            self.values = [math.nan] * len(self.carries)
        part = {name: np.asarray(col)[at:k] for name, col in columns.items()}
        fixed = ({self.prog.nodes[j]: values[j][at:k] for j in self.stateful}
                 if values is not None else None)
        for j, carry in enumerate(self.carries):
            v = kleene_values(self.pt, part, {}, k - at, self.start + at, carry,
                              nan_unknown=self.nan_unknown, fixed=fixed)
            self.values[j] = float(v[-1])

    def _carry(self, state: tuple[Any, ...]) -> dict:
        """The state as :func:`kleene_values`' carried state of the temporal operators."""
        carry: dict = {}
        for k, value in zip(self.prog.temporal, state):
            node = self.prog.nodes[k]
            if node.op in ("O", "H") and node.hi is not None:
                carry[node] = np.array([_INF if x else -_INF for x in reversed(value)
                                        if x is not None], np.float64)
            else:
                carry[node] = _INF if value else -_INF
        return carry

    def finish(self) -> bool | None:
        """True when every completion satisfies the formula at the last tick, False when
        every one violates it, None when they differ.

        Raises:
            ValueError: not every tick was fed."""
        if self.start != self.n:
            raise ValueError(f"{self.start} of {self.n} ticks fed")
        finals = set(self.finals)
        finals.update(v > 0 for v in self.values)
        return finals.pop() if len(finals) == 1 else None


#: Kleene's reading at the last tick: true in every completion, may be true, and the last
#: tick where the formula may be true (None: nowhere)
Reading = tuple[bool, bool, int | None]


def decide(pt: Node, columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray],
           n: int, nan_unknown: bool = True, stretch: np.ndarray | None = None
           ) -> tuple[bool | None, Reading, str]:
    """FRET's finite-trace verdict over a whole trace of ``n >= 1`` ticks with unknown ticks:
    Kleene's reading of the pt formula at the last tick
    (:class:`fretc.monitors.three_valued.KleeneStream`), then, where it is open, every
    completion (:class:`CompletionsStream`), each fed the trace as one chunk (``columns``,
    ``unknown``, ``nan_unknown`` and ``stretch``, the gap ticks, as
    :class:`~fretc.monitors.three_valued.Kleene` takes them).

    Returns:
        ``(holds, reading, why)``: ``holds`` True (every completion satisfies), False (every
        one violates) or None (they differ, or the search outgrew its bounds); Kleene's
        reading at the last tick (:data:`Reading`); ``why`` empty, or why the search
        stopped before it decided (:class:`TooManyStates`' message; ``holds`` is then None).

    Raises:
        VectorizeError: the pt formula cannot be evaluated over the columns.
    """
    kleene = KleeneStream(pt, nan_unknown, whole=True)
    kleene.feed(columns, unknown, n, stretch)
    reading = kleene.finish()
    lo, hi, _last_hi = reading
    if lo or not hi:
        return lo, reading, ""
    if kleene.free is None:  # (no leaf unknown: Kleene's reading is the verdict)
        return False, reading, ""
    run = CompletionsStream(pt, *kleene.free, n, nan_unknown)
    try:
        run.feed(columns, unknown, n, stretch)
    except TooManyStates as exc:
        return None, reading, str(exc)
    return run.finish(), reading, ""
