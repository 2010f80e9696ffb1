"""FRET's finite-trace verdict over every way of filling a trace's unknown ticks, where the
three-valued (Kleene) evaluation of :mod:`fretc.monitors.three_valued` leaves it open.

Kleene's evaluation is sound but not complete: an unknown value read twice in one formula
(FRET's ``in m`` reads ``m`` at the mode's entry and at its exit) is two independent unknowns
to it, so it can call a verdict unknown that every completion of the trace agrees on. With
``in m the sw shall always satisfy y``, ``m`` true and ``y`` false at tick 0 and ``m`` unknown
at tick 2, every completion violates the requirement at tick 0, yet Kleene's pt is unknown:
a violation the data show would be hidden.

:func:`completed_verdict` decides it: the pt formula is run tick by tick over the set of its
states (the values its temporal operators keep: ``Y Z`` their operand's last value, ``S T
O H`` their own, a bounded ``O H`` its operand's last ``hi`` values), every unknown atom at
an unknown tick standing for both of its values (the atoms: the formula's leaves, each
comparison, variable or function; their values from the Kleene pair, independent of each
other). States are merged as they meet, so the set stays small; from the last unknown tick
on, each state's future is fixed, and one completion leading to it is evaluated over the
rest of the trace with the vectorized evaluator. Reading the atoms as independent admits
more completions than the trace's variables can give (``x > 1`` and ``x > 2`` both free),
so a verdict is what every completion gives, never a guess: True or False only when all of
them agree, None when they differ; past a bound on the states or the work,
:class:`TooManyStates`. This is the
subset construction (Rabin and Scott 1959) over the past-time formula's own state, the
exact three-valued reading of LTL3 (Bauer, Leucker, Schallhart, TOSEM 2011) for FRET's
finite-trace semantics.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import Any

import numpy as np

from fretc.compiler.ir import Node
from fretc.monitors.three_valued import Pair, ThreeValued

__all__ = ["decide", "pt_verdict", "completed_verdict", "TooManyStates", "MAX_STATES",
           "MAX_STEPS"]

#: the most states (times the letters of one tick) the run keeps
MAX_STATES = 4096
#: the most work of the run, in node evaluations: each step of a state costs the formula's
#: nodes and the values its bounded operators keep (about 1 us each, so about a second a
#: requirement at most; ``in m ... always satisfy y``, 21 nodes: about 57,000 ticks)
MAX_STEPS = 1_200_000


class TooManyStates(Exception):
    """The completions were not all followed: the states of one tick or the work of the
    run passed :data:`MAX_STATES` or :data:`MAX_STEPS` (the message says which, and at which
    tick)."""

_SKELETON = ("!", "&", "|", "->", "<->", "xor", "past", "Y", "Z", "O", "H", "S", "T")
_TEMPORAL = ("Y", "Z", "O", "H", "S", "T")


def _order(root: Node) -> list[Node]:
    """The formula's boolean and temporal nodes, children first, each once (leaves too)."""
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
        if node.op in _SKELETON:
            stack.extend((a, False) for a in reversed(node.args))
    return out


class _Program:
    """The pt formula as a program of nodes (:func:`_order`) over one tick's leaf values and
    the state the temporal nodes keep."""

    def __init__(self, root: Node):
        self.nodes = _order(root)
        self.index = {node: k for k, node in enumerate(self.nodes)}
        self.root = self.index[root]
        self.leaves = [k for k, node in enumerate(self.nodes) if node.op not in _SKELETON]
        self.temporal = [k for k, node in enumerate(self.nodes) if node.op in _TEMPORAL]
        self.args = [[self.index[a] for a in node.args] if node.op in _SKELETON else []
                     for node in self.nodes]
        #: the work of one step: the nodes, and the values the bounded operators keep
        self.cost = len(self.nodes) + sum(self.nodes[k].hi or 0 for k in self.temporal
                                          if self.nodes[k].op in ("O", "H"))

    def state_at(self, ev: ThreeValued, i: int) -> tuple[Any, ...]:
        """The state before tick ``i`` read from ``ev``'s (definite) values at ticks < i."""
        out: list[Any] = []
        for k in self.temporal:
            node = self.nodes[k]
            if node.op in ("Y", "Z"):
                out.append(bool(ev.pair(node.args[0])[0][i - 1]) if i else None)
            elif node.op in ("O", "H") and node.hi is not None:
                lo = ev.pair(node.args[0])[0]
                out.append(tuple(bool(lo[j]) if j >= 0 else None
                                 for j in range(i - 1, i - 1 - node.hi, -1)))
            else:
                out.append(bool(ev.pair(node)[0][i - 1]) if i else None)
        return tuple(out)

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


def completed_verdict(pt: Node, ev: ThreeValued) -> bool | None:
    """The pt formula at the last of ``ev``'s ticks in every completion of its unknown ticks
    (module docstring): True when all satisfy, False when all violate, None when they
    differ.

    Raises:
        TooManyStates: past :data:`MAX_STATES` or :data:`MAX_STEPS`.
        VectorizeError: a node the three-valued evaluator cannot take.
    """
    n = ev.n
    if n == 0:
        return None
    prog = _Program(pt)
    lo = {k: ev.pair(prog.nodes[k])[0] for k in prog.leaves}
    hi = {k: ev.pair(prog.nodes[k])[1] for k in prog.leaves}
    free_at = np.zeros(n, np.bool_)
    for k in prog.leaves:
        free_at |= lo[k] != hi[k]
    gaps = ev.stretch
    if gaps is not None:  # (a gap tick is followed whatever its leaves: its count is free)
        free_at |= gaps
    free_ticks = np.flatnonzero(free_at)
    if not len(free_ticks):
        root_lo = ev.pair(pt)[0]
        return bool(root_lo[-1])
    first, last = int(free_ticks[0]), int(free_ticks[-1])
    # state -> one completion reaching it: a chain (previous chain, tick, {leaf: value})
    states: dict[tuple[Any, ...], Any] = {prog.state_at(ev, first): None}
    finals: set[bool] = set()
    steps = 0
    for i in range(first, last + 1):
        known = {k: bool(lo[k][i]) for k in prog.leaves}
        free = [k for k in prog.leaves if lo[k][i] != hi[k][i]]
        letters = 1 << len(free)
        steps += len(states) * letters * prog.cost
        if len(states) * letters > MAX_STATES:
            raise TooManyStates(f"{len(states)} states times {letters} letters at tick {i} "
                                f"(bound {MAX_STATES})")
        if steps > MAX_STEPS:
            raise TooManyStates(f"more than {MAX_STEPS} node evaluations by tick {i}")
        nxt: dict[tuple[Any, ...], Any] = {}
        gap = gaps is not None and bool(gaps[i])
        for state, chain in states.items():
            for bits in itertools.product((False, True), repeat=len(free)):
                leaves = dict(known)
                leaves.update(zip(free, bits))
                root, after = prog.step(state, leaves, i)
                if i == n - 1:
                    finals.add(root)
                if after not in nxt:
                    letter = dict(zip(free, bits))
                    nxt[after] = ((chain, i, (letter,)) if gap else
                                  (chain, i, letter) if free else chain)
        if gap:
            steps = _stretch(prog, nxt, known, free, i, i == n - 1, finals, steps)
        states = nxt
    if last < n - 1:
        for chain in states.values():
            finals.add(_evaluate_completion(pt, ev, prog, chain))
            if len(finals) > 1:
                return None
    return finals.pop() if len(finals) == 1 else None


def _stretch(prog: _Program, states: dict[tuple[Any, ...], Any], known: dict[int, bool],
             free: list[int], i: int, last: bool, finals: set[bool], steps: int) -> int:
    """Add to ``states`` (those one tick of the gap tick ``i`` leads to, each with its
    chain) every state further ticks of the gap lead to, each tick any letter of the
    ``free`` leaves (a gap stands for one tick or more); at the ``last`` tick each of them
    may end the trace (its root into ``finals``). Returns the work counted so far.

    Raises:
        TooManyStates: past :data:`MAX_STATES` or :data:`MAX_STEPS`."""
    frontier = dict(states)
    later = max(i, 1)  # (the gap's later ticks are not the trace's first)
    letters = 1 << len(free)
    while frontier:
        steps += len(frontier) * letters * prog.cost
        if len(states) * letters > MAX_STATES:
            raise TooManyStates(f"{len(states)} states times {letters} letters in the gap "
                                f"at tick {i} (bound {MAX_STATES})")
        if steps > MAX_STEPS:
            raise TooManyStates(f"more than {MAX_STEPS} node evaluations by tick {i}")
        nxt: dict[tuple[Any, ...], Any] = {}
        for state, (chain, _i, seq) in frontier.items():
            for bits in itertools.product((False, True), repeat=len(free)):
                leaves = dict(known)
                leaves.update(zip(free, bits))
                root, after = prog.step(state, leaves, later)
                if last:
                    finals.add(root)
                if after not in states and after not in nxt:
                    nxt[after] = (chain, i, seq + (dict(zip(free, bits)),))
        states.update(nxt)
        frontier = nxt
    return steps


def _evaluate_completion(pt: Node, ev: ThreeValued, prog: _Program, chain: Any) -> bool:
    """The pt formula at the last tick of ``ev`` with the unknown atoms filled as ``chain``
    says (at its ticks; at a gap tick, a sequence of one letter or more: the ticks it
    stands for) and every other tick's atoms as read."""
    filled = {k: ev.pair(prog.nodes[k])[0].copy() for k in prog.leaves}
    spans: dict[int, tuple[dict[int, bool], ...]] = {}
    while chain is not None:
        chain, i, values = chain
        if isinstance(values, tuple):
            spans[i] = values
            continue
        for k, v in values.items():
            filled[k][i] = v
    n = ev.n
    if spans:  # every gap tick as the ticks its letters fill
        counts = np.ones(n, np.int64)
        for i, seq in spans.items():
            counts[i] = len(seq)
        at = np.repeat(np.arange(n), counts)
        starts = np.concatenate(([0], np.cumsum(counts)[:-1]))
        filled = {k: arr[at] for k, arr in filled.items()}
        for i, seq in spans.items():
            for j, letter in enumerate(seq):
                for k, v in letter.items():
                    filled[k][starts[i] + j] = v
        n = len(at)
    done = ThreeValued(ev.columns, {}, n, ev.nan_unknown)
    for k, arr in filled.items():
        done.fix(prog.nodes[k], arr)
    return bool(done.pair(pt)[0][-1])


def pt_verdict(pt: Node, columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray],
               n: int, nan_unknown: bool = True, stretch: np.ndarray | None = None
               ) -> tuple[bool | None, Pair]:
    """FRET's finite-trace verdict over ``n`` ticks with unknown ticks: True (every way of
    filling them satisfies), False (every one violates) or None (it depends on them, or
    the search of :func:`completed_verdict`, which decides where Kleene's reading leaves it
    open, outgrew its bound); and the pt formula's Kleene ``(lo, hi)`` at every tick
    (:func:`decide` over the columns). ``stretch``: the gap ticks, each one tick or more
    (:class:`~fretc.monitors.three_valued.ThreeValued`).

    Raises:
        VectorizeError: the pt formula cannot be evaluated over columns.
    """
    holds, pair, _why = decide(pt, ThreeValued(columns, unknown, n, nan_unknown, stretch))
    return holds, pair


def decide(pt: Node, ev: ThreeValued) -> tuple[bool | None, Pair, str]:
    """The verdict of :func:`pt_verdict` over the ticks of ``ev``: Kleene's reading of the pt
    formula at the last tick, then, where it is open, the exact search over completions.

    Returns:
        ``(holds, (lo, hi), why)``: ``holds`` True, False or None; the pt formula's Kleene
        pair at every tick; ``why`` empty, or why the search stopped before it decided
        (:class:`TooManyStates`' message; ``holds`` is then None).

    Raises:
        VectorizeError: the pt formula cannot be evaluated over the columns of ``ev``.
    """
    lo, hi = ev.pair(pt)
    if lo[-1]:
        return True, (lo, hi), ""
    if not hi[-1]:
        return False, (lo, hi), ""
    try:
        return completed_verdict(pt, ev), (lo, hi), ""
    except TooManyStates as exc:
        return None, (lo, hi), str(exc)
