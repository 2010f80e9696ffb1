"""FRET's finite-trace verdict over every completion of a trace's unknown ticks, where Kleene's
reading leaves it open, over a trace fed a chunk of ticks at a time: the counterpart of
:func:`fretc.monitors.completions.completed_verdict`, in memory that does not grow with the
trace.

The whole-trace search runs the pt formula's program (:class:`fretc.monitors.completions.
_Program`) over the set of its states from the first tick where one of its leaves is unknown
to the last such tick, and then evaluates one completion per state over the rest of the trace.
:class:`CompletionsStream` is given those two ticks (found by an earlier read:
:attr:`fretc.monitors.kleene_stream.KleeneStream.free`) and does the same in three stretches
of the trace:

1. **before the first**: the values the program's state reads at the tick before it (each
   temporal operator's operand or own value, a bounded window's last values) are kept from
   chunk to chunk, as :meth:`~fretc.monitors.completions._Program.state_at` reads them;
2. **from the first to the last**: the states are stepped tick by tick with every value of
   the unknown leaves, with the same counts of states and work and the same
   :class:`~fretc.monitors.completions.TooManyStates` at the same tick;
3. **after the last**: each state is written as the temporal operators' carried state of
   :func:`fretc.monitors.kleene_stream.kleene_values` (a completion's values are definite:
   ``+inf`` or ``-inf``) and the formula evaluated from it over the rest of the trace, a
   chunk at a time; its value at the last tick is that completion's verdict.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from fretc.compiler.ir import Node, walk
from fretc.monitors import completions
from fretc.monitors.completions import TooManyStates, _Program
from fretc.monitors.kleene_stream import kleene_values

__all__ = ["CompletionsStream", "completions_unsupported"]

_INF = math.inf
#: operators whose value depends on earlier ticks, inside a leaf
_STATEFUL = frozenset(("Y", "Z", "O", "H", "S", "T", "pre"))


def completions_unsupported(pt: Node) -> str | None:
    """None when :class:`CompletionsStream` takes ``pt``, else why not: a leaf of its
    program (a node outside the boolean and temporal skeleton) whose value reads earlier
    ticks (a past-time operator inside a boolean if-then-else)."""
    prog = _Program(pt)
    for k in prog.leaves:
        if any(x.op in _STATEFUL for x in walk(prog.nodes[k])):
            return "a leaf of the pt formula reads earlier ticks"
    return None


class CompletionsStream:
    """:func:`fretc.monitors.completions.completed_verdict` of ``pt`` over ``n`` ticks fed a
    chunk at a time, the first and last ticks where a leaf is unknown being ``first`` and
    ``last`` (module docstring).

    Raises:
        ValueError: (constructor) :func:`completions_unsupported`'s reason, or
            ``0 <= first <= last < n`` does not hold.
    """

    def __init__(self, pt: Node, first: int, last: int, n: int) -> None:
        why = completions_unsupported(pt)
        if why is not None:
            raise ValueError(why)
        if not 0 <= first <= last < n:
            raise ValueError(f"free ticks {first}..{last} outside 0..{n - 1}")
        self.pt, self.first, self.last, self.n = pt, first, last, n
        self.prog = prog = _Program(pt)
        self.leaf_carry: dict[int, dict] = {k: {} for k in prog.leaves}
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
             k: int) -> None:
        """The next ``k >= 0`` ticks (``columns`` and ``unknown`` as
        :func:`fretc.monitors.kleene_stream.kleene_values` takes them).

        Raises:
            TooManyStates: as :func:`~fretc.monitors.completions.completed_verdict`, at the
                same tick."""
        if k <= 0:
            return
        a, b = self.start, self.start + k
        if a < self.first:
            self._before(columns, unknown, k, min(b, self.first) - a)
        if a <= self.last and b > self.first:
            self._free(columns, unknown, k, max(a, self.first), min(b - 1, self.last))
        elif a <= self.last:
            self._leaves(columns, unknown, k)  # (their state, for the ticks to come)
        if b - 1 > self.last:
            self._after(columns, k, max(a, self.last + 1) - a)
        self.start = b

    def _before(self, columns, unknown, k: int, upto: int) -> None:
        """Keep the values the state at ``first`` reads (ticks ``start .. start+upto-1``)."""
        for node, (carry, last, keep) in self.kept.items():
            v = kleene_values(node, columns, unknown, k, self.start, carry)[:upto]
            last.extend(bool(x) for x in (v[-keep:] > 0).tolist())
            del last[:-keep]

    def _state_at_first(self) -> tuple[Any, ...]:
        """:meth:`~fretc.monitors.completions._Program.state_at` at ``first``."""
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

    def _leaves(self, columns, unknown, k: int) -> dict[int, np.ndarray]:
        """Each leaf's Kleene value over the chunk (its state carried)."""
        return {j: kleene_values(self.prog.nodes[j], columns, unknown, k, self.start, carry)
                for j, carry in self.leaf_carry.items()}

    def _free(self, columns, unknown, k: int, lo_tick: int, hi_tick: int) -> None:
        """Step the states over the ticks ``lo_tick .. hi_tick`` (in this chunk), as
        :func:`~fretc.monitors.completions.completed_verdict` steps them."""
        prog, a = self.prog, self.start
        values = self._leaves(columns, unknown, k)
        if self.states is None:
            self.states = {self._state_at_first(): None}
        for i in range(lo_tick, hi_tick + 1):
            known = {j: bool(values[j][i - a] > 0) for j in prog.leaves}
            free = [j for j in prog.leaves if values[j][i - a] == 0]
            letters = 1 << len(free)
            self.steps += len(self.states) * letters * prog.cost
            bound, work = completions.MAX_STATES, completions.MAX_STEPS  # (its bounds, as set)
            if len(self.states) * letters > bound:
                raise TooManyStates(f"{len(self.states)} states times {letters} letters at "
                                    f"tick {i} (bound {bound})")
            if self.steps > work:
                raise TooManyStates(f"more than {work} node evaluations by tick {i}")
            nxt: dict[tuple[Any, ...], Any] = {}
            for state in self.states:
                for bits in itertools.product((False, True), repeat=len(free)):
                    leaves = dict(known)
                    leaves.update(zip(free, bits))
                    root, after = prog.step(state, leaves, i)
                    if i == self.n - 1:
                        self.finals.add(root)
                    nxt.setdefault(after, None)
            self.states = nxt

    def _after(self, columns, k: int, at: int) -> None:
        """Evaluate each state's completion over the chunk's ticks from ``at``."""
        if self.carries is None:
            assert self.states is not None  # (the free ticks came first)
            self.carries = [self._carry(state) for state in self.states]
            self.values = [math.nan] * len(self.carries)
        part = {name: np.asarray(col)[at:k] for name, col in columns.items()}
        for j, carry in enumerate(self.carries):
            v = kleene_values(self.pt, part, {}, k - at, self.start + at, carry)
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
