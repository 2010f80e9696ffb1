"""Kleene's three-valued reading of a pt formula, and the LTL3 verdict over every letter an
unknown tick may be, over a trace fed a chunk of ticks at a time: the counterparts of
:meth:`fretc.monitors.three_valued.ThreeValued.pair` (at the last tick) and
:func:`fretc.monitors.three_valued.ltl3_verdict` (over the whole trace), in memory that does
not grow with the trace.

**Kleene's values as robustness.** A three-valued truth is written as a float: ``+inf``
true in every completion, ``-inf`` false in every one, ``0.0`` (or ``-0.0``) unknown.
Negation is ``-x``; ``&`` and ``|`` are ``min`` and ``max``; ``Y Z O H S T`` are the
recurrences :class:`fretc.monitors.robustness._Rho` runs for Donze and Maler's robustness
(``max``/``min`` over ticks, ``-inf``/``+inf`` where a window is empty or before tick 0).
Thresholding at ``> 0`` (Kleene's ``lo``: true whatever the unknown ticks held) and at
``>= 0`` (``hi``: may be true) is monotone, so it commutes with ``min`` and ``max``: the
threshold of every node's value is the ``lo``/``hi`` pair
:class:`~fretc.monitors.three_valued.ThreeValued` computes for it (Kleene 1952; negation
swaps ``lo`` and ``hi`` as ``-x`` swaps the thresholds). A boolean if-then-else is
``max(min(c, t), min(-c, e), min(t, e))``, Kleene's with its ``t & e`` term. The atoms
(comparisons, variables, numbers read as conditions: nodes that read one tick) take
:class:`~fretc.monitors.three_valued.ThreeValued`'s pairs over the chunk, so the rules for a
NaN operand and an unknown value are its own. Each temporal operator's state is carried from
chunk to chunk as :func:`fretc.monitors.robustness.past_truth` carries it.

**The LTL3 verdict** (Bauer, Leucker, Schallhart, TOSEM 2011) runs each live automaton over
the set of its states every letter an unknown tick may be leads to (a subset construction,
Rabin and Scott 1959); a tick whose letter is known moves a single state through the table
as :func:`fretc.monitors.judge.ltl3_verdict` does.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from fretc.compiler.ir import Node, walk
from fretc.monitors.judge import earliest_verdict
from fretc.monitors.robustness import _Rho, chunkable
from fretc.monitors.three_valued import ThreeValued, _letters
from fretc.monitors.vectorized import VectorizeError, supports

if TYPE_CHECKING:
    from fretc.compiler.codegen import MonitorSource

__all__ = ["KleeneStream", "Ltl3SetStream", "kleene_unsupported", "kleene_values", "leaves_of"]

_INF = math.inf
_FUTURE = ("X", "F", "G", "U", "V", "LAST", "future")
#: nodes :class:`_Kleene` evaluates as :class:`_Rho` does (temporal operators, FTP)
_TEMPORAL = frozenset(("Y", "Z", "O", "H", "S", "T", "FTP", "past"))


def kleene_unsupported(node: Node) -> str | None:
    """None when :class:`KleeneStream` (and :class:`Ltl3SetStream`'s atoms) can evaluate
    ``node`` a chunk at a time, else why not, in words: a future-time operator, a node the
    vectorized engine does not evaluate, a comparison over a past-time value or ``pre``,
    or an uninterpreted function (unknown wherever any variable is, over the whole trace)."""
    if any(x.op in _FUTURE for x in walk(node)) or not supports(node):
        return "a future-time operator or a node not evaluated over columns"
    if not chunkable(node):
        return "a comparison reads a past-time value or pre"
    if any(x.op == "call" or (x.op == "fn" and x.name not in _FUNCTIONS) for x in walk(node)):
        return "an uninterpreted function (unknown wherever any variable is)"
    return None


#: the functions :class:`~fretc.monitors.three_valued.ThreeValued` interprets
_FUNCTIONS = frozenset(("absReal", "absInt", "minReal", "minInt", "maxReal", "maxInt"))


class _Kleene(_Rho):
    """:class:`_Rho` with Kleene's values (module docstring) over one chunk of ``n`` ticks,
    the trace's tick ``start`` its first, the temporal operators' state in ``carry``."""

    def __init__(self, columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray],
                 n: int, root: Node, start: int, carry: dict) -> None:
        super().__init__(columns, n, root, start, carry)
        self.three = ThreeValued(columns, unknown, n, nan_unknown=True)

    def _compute(self, node: Node) -> np.ndarray:
        op, a = node.op, node.args
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
        if op in _TEMPORAL:
            return super()._compute(node)
        lo, hi = self.three.pair(node)  # an atom: ThreeValued's pair over the chunk
        return np.where(lo, _INF, np.where(hi, 0.0, -_INF))


def kleene_values(node: Node, columns: Mapping[str, np.ndarray],
                  unknown: Mapping[str, np.ndarray], k: int, start: int, carry: dict
                  ) -> np.ndarray:
    """Kleene's value of the past-time formula ``node`` (module docstring: ``> 0`` true,
    ``>= 0`` may be true) at the trace's ticks ``start .. start+k-1`` (float array
    ``(k,)``), its temporal operators' state carried in ``carry`` (one dict per formula,
    empty at tick 0); ``unknown``: variable -> bool array of ``k`` (its unknown ticks).

    Raises:
        VectorizeError: as :meth:`fretc.monitors.three_valued.ThreeValued.pair`."""
    return _Kleene(columns, unknown, k, node, start, carry).rho(node)


class KleeneStream:
    """Kleene's reading of a pt formula at the last tick of a trace fed a chunk at a time
    (:meth:`fretc.monitors.three_valued.ThreeValued.pair` over the whole trace, read at its
    last tick), and the last tick where it may be true (``hi``).

    Raises:
        VectorizeError: (constructor) :func:`kleene_unsupported`'s reason."""

    def __init__(self, pt: Node) -> None:
        why = kleene_unsupported(pt)
        if why is not None:
            raise VectorizeError(why)
        self.pt = pt
        self.carry: dict = {}
        self.start = 0
        self.last = math.nan
        #: the last tick at which ``hi`` is true (None: none so far)
        self.last_hi: int | None = None
        #: the formula's leaves as :mod:`fretc.monitors.completions` reads them (each with
        #: its own state), and the first and last tick where one of them is unknown
        self.leaves: dict[Node, dict] = {node: {} for node in leaves_of(pt)}
        self.free: tuple[int, int] | None = None

    def feed(self, columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray],
             k: int) -> None:
        """The next ``k >= 0`` ticks (``columns`` and ``unknown`` as :func:`kleene_values`)."""
        if k <= 0:
            return
        values = kleene_values(self.pt, columns, unknown, k, self.start, self.carry)
        free = np.zeros(k, np.bool_)
        for leaf, carry in self.leaves.items():
            v = kleene_values(leaf, columns, unknown, k, self.start, carry)
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


def leaves_of(pt: Node) -> list[Node]:
    """The leaves of ``pt`` as :mod:`fretc.monitors.completions` reads them (the nodes
    outside its boolean and temporal skeleton), each once, in its order."""
    from fretc.monitors.completions import _Program

    prog = _Program(pt)
    return [prog.nodes[k] for k in prog.leaves]


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
    """:func:`fretc.monitors.three_valued.ltl3_verdict` over a trace fed a chunk of ticks at
    a time: each live automaton (``bad``: rejection means *violated*; ``good``:
    *satisfied*) runs over the set of states every letter an unknown tick may be leads to,
    and stops when every run is rejected; the verdict is the earlier such tick (``bad``'s
    on a tie). Memory: the states (at most the automaton's), the atoms' values over one
    chunk and their temporal operators' state.

    Raises:
        VectorizeError: (constructor) an automaton with condition chains (no table), or an
            atom :func:`kleene_unsupported` refuses.
    """

    def __init__(self, monitor_source: MonitorSource) -> None:
        ms = monitor_source
        bad, good = ms.bad, ms.good
        self.decided: str | None = None
        if bad is not None and bad.empty:
            self.decided = "violated"
        elif good is not None and good.empty:
            self.decided = "satisfied"
        self.live: list[_Sets] = []
        for aut, outcome in ((bad, "violated"), (good, "satisfied")):
            if self.decided or aut is None or aut.complete:
                continue
            if aut.table is None:
                raise VectorizeError("automaton with condition chains: no table")
            for atom in aut.atoms:
                why = kleene_unsupported(atom)
                if why is not None:
                    raise VectorizeError(f"atom {atom}: {why}")
            self.live.append(_Sets(aut.table, {aut.initial}, tuple(aut.atoms), outcome))
        self.start = 0

    def feed(self, columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray],
             k: int, times: np.ndarray) -> None:
        """The next ``k >= 0`` ticks (``columns`` and ``unknown`` as :func:`kleene_values`;
        ``times`` their times, int64 ns)."""
        if k <= 0:
            return
        for run in self.live:
            if run.hit is not None:
                continue
            known = np.zeros(k, np.int64)
            free = np.zeros(k, np.int64)
            for j, atom in enumerate(run.atoms):
                v = kleene_values(atom, columns, unknown, k, self.start,
                                  run.carry.setdefault(atom, {}))
                known |= (v > 0).astype(np.int64) << j
                free |= ((v >= 0) & ~(v > 0)).astype(np.int64) << j
            hit = _run(run, known, free)
            if hit is not None:
                run.hit, run.hit_time = self.start + hit, int(times[hit])
        self.start += k

    def finish(self) -> tuple[str, int | None, int | None]:
        """``(verdict, tick, time)`` over the ticks fed (``"unknown"``, None, None when no
        automaton rejected every run)."""
        return earliest_verdict(self.decided, self.live)


def _run(run: _Sets, known: np.ndarray, free: np.ndarray) -> int | None:
    """Move ``run``'s states over one chunk's letters (``known`` bits, ``free`` bits
    unknown); the chunk's index at which every run is rejected, or None. A single state
    over known letters moves as one table lookup a tick."""
    table, states = run.table, run.states
    k = len(known)
    unknown_at = np.flatnonzero(free).tolist()
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
        nxt = {table[s][x] for s in states for x in _letters(letters[stop], int(free[stop]))}
        states = {s for s in nxt if s >= 0}
        if not states:
            return stop
        i = stop + 1
    run.states = states
    return None
