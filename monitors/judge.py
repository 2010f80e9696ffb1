"""The offline judge: one requirement's verdict, its LTL3 verdict and its evidence, decided once
over the columns of a trace (one value per tick per FRET variable).

The audit (and a watch at the end of its run) asks :func:`judge` and nothing else:

Design notes: ARCHITECTURE.md, `monitors/judge.py`."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from fretc.monitors import stepwise
from fretc.monitors.interval import Evidence, EvidenceUnsupported, evaluate_requirement
from fretc.monitors.robustness import (POINTS, RobustnessSummary, chunkable, past_truth,
                                       robustness, stateful)
from fretc.monitors.vectorized import (VectorizeError, atom_letters, node_series, pt_series,
                                       supports)
from fretc.monitors.nan import nan_ticks_of

if TYPE_CHECKING:
    from fretc.compiler.ir import Node
    from fretc.fretish import ast as A
    from fretc.compiler.semantics import Formalization
    from fretc.compiler.codegen import MonitorSource

__all__ = ["Judgement", "Ltl3Stream", "judge", "ltl3_verdict", "ltl3_verdicts", "nan_ticks",
           "earliest_verdict", "compared_exprs"]


@dataclass
class Judgement:
    """What :func:`judge` decided about one requirement over ``n`` ticks.

    Attributes:
        holds: FRET's finite-trace verdict over the ticks (True: satisfied or vacuous).
        evidence: the interval semantics' evidence (None where it cannot evaluate the
            requirement; ``note`` says why).
        ltl3: the LTL3 verdict, ``"satisfied"``, ``"violated"`` or ``"unknown"``.
        ltl3_tick: the 0-based tick at which ``ltl3`` became definite (None when unknown, or
            definite before any tick).
        engine: what decided ``holds``: ``"interval"`` (the interval semantics),
            ``"vectorized"`` (the pt formula over the columns) or ``"stepwise"`` (the
            generated monitor replayed).
        note: why the interval semantics gave no evidence, or None.
        robustness: the pt formula's robustness over the ticks
            (:class:`fretc.monitors.robustness.RobustnessSummary`), or None where the pt
            formula cannot be evaluated over columns (a future-time function).
    """

    holds: bool
    evidence: Evidence | None
    ltl3: str
    ltl3_tick: int | None
    engine: str
    note: str | None = None
    robustness: RobustnessSummary | None = None


def judge(requirement: A.Requirement, formalization: Formalization,
          columns: Mapping[str, np.ndarray], n: int, *,
          monitor_source: MonitorSource | None = None,
          monitor_cls: type | None = None, rob: RobustnessSummary | None = None,
          ltl3: tuple[str, int | None] | None = None, times: np.ndarray | None = None,
          points: int = POINTS) -> Judgement:
    """Decide one requirement over the first ``n`` ticks of ``columns``.

    Args:
        requirement: the parsed requirement (:class:`fretc.fretish.ast.Requirement`).
        formalization: its :class:`fretc.compiler.semantics.Formalization` (pt, ticks).
        columns: FRET variable -> numpy array of at least ``n`` values (bool or float).
        n: the number of ticks judged (``n >= 1``).
        monitor_source: the requirement's :class:`fretc.compiler.codegen.MonitorSource` (its LTL3
            automata tables), or None for a requirement without an online monitor.
        monitor_cls: its generated monitor class, for the replay fallbacks, or None.
        rob: the pt formula's robustness over these ticks when computed already (with other
            traces: :func:`fretc.monitors.robustness.robustness_columns`), else None.
        ltl3: the LTL3 verdict and tick of ``monitor_source``'s automata over these ticks
            when computed already (with other traces: :func:`ltl3_verdicts`), else None.
        times: the ticks' times (int64 ns; None: their indexes), and ``points`` the margin
            points its robustness keeps (:func:`fretc.monitors.robustness.robustness`).

    Raises:
        EvidenceUnsupported: neither the interval semantics, nor the pt formula over the
            columns, nor a generated monitor can decide the requirement (a free-form
            requirement without a monitor).
    """
    ev, note = None, None
    try:
        ev = evaluate_requirement(requirement, columns, n, formalization.ticks)
    except EvidenceUnsupported as exc:
        if monitor_cls is None and not _pt_evaluable(formalization):
            raise
        note = f"interval evidence unavailable: {exc}"
    replayed = None
    if ev is not None:
        holds, engine = ev.holds, "interval"
    elif _pt_evaluable(formalization):
        holds, engine = bool(pt_series(formalization.pt, columns, n)[-1]), "vectorized"
    else:
        assert monitor_cls is not None  # (else the interval evidence's error was raised)
        replayed = stepwise.replay(monitor_cls, columns, n)
        holds, engine = bool(replayed.finish()), "stepwise"
    status, tick = (ltl3 if ltl3 is not None and monitor_source is not None else
                    _ltl3(monitor_source, monitor_cls, columns, n, replayed))
    if rob is None and _pt_evaluable(formalization):
        rob = robustness(formalization.pt, columns, n, times=times, points=points)
    return Judgement(holds, ev, status, tick, engine, note, rob)


def _pt_evaluable(formalization) -> bool:
    """The pt formula can be evaluated over columns (causal, no future-time operator)."""
    return bool(formalization.pt_causal) and supports(formalization.pt)


def _ltl3(monitor_source, monitor_cls, columns, n: int, replayed) -> tuple[str, int | None]:
    """The LTL3 verdict and its tick: the automata over the columns, else the replayed
    generated monitor, else unknown (no online monitor)."""
    if monitor_source is None:
        return "unknown", None
    try:
        return ltl3_verdict(monitor_source, columns, n)
    except (VectorizeError, KeyError):
        if monitor_cls is None:
            return "unknown", None
    mon = replayed if replayed is not None else stepwise.replay(monitor_cls, columns, n)
    return mon.status, mon.status_tick


def ltl3_verdict(monitor_source: MonitorSource, columns: Mapping[str, np.ndarray], n: int
                 ) -> tuple[str, int | None]:
    """The earliest definitive LTL3 verdict of a monitor over a whole trace of ``n`` ticks:
    an :class:`Ltl3Stream` fed it as one chunk (the deterministic Spot monitors embedded by
    :func:`fretc.compiler.codegen.monitor_source`, ``bad`` for ft_inf: rejection means
    *violated*; ``good`` for its negation: rejection means *satisfied*).

    Returns:
        ``(verdict, tick)``: verdict ``"satisfied"``, ``"violated"`` or ``"unknown"``; tick
        the 0-based tick where it became definitive (None when unknown or definitive before
        any tick), as the generated ``status`` / ``status_tick``.

    Raises:
        VectorizeError: an automaton given as condition chains (more than
            ``codegen.TABLE_MAX_APS`` atoms): use the step-wise monitor; an atom that cannot
            be evaluated over columns.
    """
    stream = Ltl3Stream(monitor_source, whole=True)
    stream.feed(columns, n, np.arange(n, dtype=np.int64))
    status, tick, _time = stream.finish()
    return status, tick


#: letters read into Python at a time by :func:`_advance`
_LETTERS_CHUNK = 1 << 16


def _first_rejection(table, state: int, letters: np.ndarray) -> int | None:
    """The first tick at which the automaton ``table`` from ``state`` rejects over
    ``letters``, or None (read a chunk at a time: no list of every letter)."""
    return _advance(table, state, letters)[1]


def _advance(table, state: int, letters: np.ndarray) -> tuple[int, int | None]:
    """The automaton ``table`` (``table[state][letter]``, negative: rejected) run from
    ``state`` over ``letters``: ``(state, None)`` after the last letter, or ``(rejecting
    state, index)`` at the first rejection (the letters read a chunk at a time)."""
    for lo in range(0, len(letters), _LETTERS_CHUNK):
        for i, letter in enumerate(letters[lo:lo + _LETTERS_CHUNK].tolist(), lo):
            state = table[state][letter]
            if state < 0:
                return state, i
    return state, None


def ltl3_verdicts(monitor_source: MonitorSource, columns: Mapping[str, np.ndarray], n: int,
                  starts: np.ndarray, firsts: np.ndarray, lengths: np.ndarray
                  ) -> list[tuple[str, int | None]]:
    """:func:`ltl3_verdict` of each of several traces laid end to end in ``columns`` (trace
    ``e`` at ``firsts[e]``, ``lengths[e]`` ticks; ``starts`` each tick's trace's first
    index, as :func:`fretc.monitors.vectorized.pt_series` takes it): the automata restart
    at each trace. Ticks are 0-based in each trace.

    Raises:
        VectorizeError: as :func:`ltl3_verdict`."""
    ms = monitor_source
    bad, good = ms.bad, ms.good
    count = len(firsts)
    if bad is not None and bad.empty:
        return [("violated", None)] * count
    if good is not None and good.empty:
        return [("satisfied", None)] * count
    live = [(aut, outcome) for aut, outcome in ((bad, "violated"), (good, "satisfied"))
            if aut is not None and not aut.complete]
    best: list[tuple[str, int | None]] = [("unknown", None)] * count
    for aut, outcome in live:
        if aut.table is None:
            raise VectorizeError("automaton with condition chains (too many atoms to "
                                 "tabulate): use the step-wise monitor")
        letters = atom_letters(aut.atoms, columns, n, starts)
        hits = first_rejections(aut.table, aut.initial, letters, firsts, lengths)
        for e in np.flatnonzero(hits >= 0).tolist():
            hit, seen = int(hits[e]), best[e][1]
            if seen is None or hit < seen:  # (the earlier automaton's on a tie)
                best[e] = (outcome, hit)
    return best


class Ltl3Stream:
    """:func:`ltl3_verdict` over a trace fed a chunk of ticks at a time (the LTL3 verdict of
    Bauer, Leucker, Schallhart, TOSEM 2011: the earliest tick after which every
    continuation satisfies, or every one violates, ft_inf), and the time of its tick.

    Each live automaton (``bad``: rejection means *violated*; ``good``: *satisfied*) keeps
    its state from chunk to chunk and stops at its first rejection; the verdict is the
    earlier rejection (``bad``'s on a tie), as :func:`ltl3_verdict` decides it. An atom
    whose value depends on earlier ticks (a past-time function, ``FTP``) is evaluated with
    its temporal operators' state carried (:func:`fretc.monitors.robustness.past_truth`).
    Memory: the letters and atoms of one chunk, and per atom its operators' state (a
    bounded window's last ticks): independent of the trace's length. :func:`ltl3_verdict`
    is a whole trace fed as one chunk.
    """

    def __init__(self, monitor_source: MonitorSource, whole: bool = False) -> None:
        """``whole``: an atom that cannot be evaluated a chunk at a time (a comparison over a
        past-time operator or ``pre``) is taken, the stream fed the whole trace as one chunk.

        Raises:
            VectorizeError: an automaton with condition chains (too many atoms to tabulate:
                use the step-wise monitor), or a live automaton's atom that cannot be
                evaluated over columns (a future-time operator) or, without ``whole``, a
                chunk at a time."""
        ms = monitor_source
        bad, good = ms.bad, ms.good
        self.decided: str | None = None  # definite before any tick
        if bad is not None and bad.empty:
            self.decided = "violated"
        elif good is not None and good.empty:
            self.decided = "satisfied"
        live = [] if self.decided else [
            (aut, outcome) for aut, outcome in ((bad, "violated"), (good, "satisfied"))
            if aut is not None and not aut.complete]
        self.live: list[_Running] = []
        for aut, outcome in live:
            if aut.table is None:
                raise VectorizeError("automaton with condition chains (too many atoms to "
                                     "tabulate): use the step-wise monitor")
            self.live.append(_Running(aut.table, aut.initial, tuple(aut.atoms), outcome))
        #: each atom depending on earlier ticks -> its temporal operators' state
        self.carry: dict[Node, dict] = {}
        #: an atom evaluated over the whole trace, fed as one chunk
        self.at_once = False
        for run in self.live:
            for atom in run.atoms:
                if not supports(atom):
                    raise VectorizeError(f"atom {atom} cannot be evaluated over columns (a "
                                         "future-time operator)")
                if stateful(atom) and not chunkable(atom):
                    if not whole:
                        raise VectorizeError(f"atom {atom} cannot be evaluated a chunk at a "
                                             "time (a comparison over a past-time value)")
                    self.at_once = True
                elif stateful(atom):
                    self.carry[atom] = {}
        self.start = 0  # ticks fed

    def feed(self, columns: Mapping[str, np.ndarray], k: int, times: np.ndarray) -> None:
        """The next ``k >= 0`` ticks: ``columns`` FRET variable -> a 1-D array whose first
        ``k`` values are these ticks' (as :func:`ltl3_verdict` reads them), ``times``
        their times (int64 ns, at least ``k``).

        Raises:
            VectorizeError: a column missing or shorter than ``k``.
            ValueError: a second chunk of a stream with an atom evaluated at once."""
        if self.at_once and self.start and k > 0:
            raise ValueError("an atom compares a past-time value: the LTL3 automata are fed "
                             "the whole trace as one chunk")
        running = [run for run in self.live if run.hit is None]
        if k > 0 and running:
            window = {name: np.asarray(col)[:k] for name, col in columns.items()}
            past = {atom: past_truth(atom, window, k, self.start, self.carry[atom])
                    for atom in {a for run in running for a in run.atoms if a in self.carry}}
            for run in running:
                letters = (_letters(run.atoms, window, k, past) if past
                           else atom_letters(run.atoms, window, k))
                run.state, hit = _advance(run.table, run.state, letters)
                if hit is not None:
                    run.hit, run.hit_time = self.start + hit, int(times[hit])
        self.start += max(k, 0)

    def finish(self) -> tuple[str, int | None, int | None]:
        """``(verdict, tick, time)``: :func:`ltl3_verdict`'s verdict and tick over the ticks
        fed, and the time of the tick (ns, as fed; None with the tick)."""
        return earliest_verdict(self.decided, self.live)


def earliest_verdict(decided: str | None, runs: Iterable[Any]
                     ) -> tuple[str, int | None, int | None]:
    """The LTL3 verdict of automata run over a trace: ``decided`` when one was empty (a
    verdict before any tick), else the outcome of the earliest rejection among ``runs``
    (each with ``outcome``, ``hit`` and ``hit_time``, ``hit`` None while not rejected; the
    first of them on a tie: ``bad`` before ``good``), else ``("unknown", None, None)``."""
    if decided is not None:
        return decided, None, None
    best: tuple[str, int | None, int | None] = ("unknown", None, None)
    for run in runs:
        if run.hit is not None and (best[1] is None or run.hit < best[1]):
            best = (run.outcome, run.hit, run.hit_time)
    return best


@dataclass
class _Running:
    """One live automaton of an :class:`Ltl3Stream`: its table, state, atoms, what its
    rejection means, and the tick and time of its first rejection (None: none yet)."""

    table: list[list[int]]
    state: int
    atoms: tuple[Node, ...]
    outcome: str
    hit: int | None = None
    hit_time: int | None = None


def _letters(atoms: tuple[Node, ...], columns: Mapping[str, np.ndarray], k: int,
             past: dict[Node, np.ndarray]) -> np.ndarray:
    """:func:`atom_letters` of one chunk, the atoms that depend on earlier ticks read from
    ``past`` (their truths over the chunk), the others evaluated over the chunk."""
    dtype = np.dtype(np.uint16 if len(atoms) <= 16 else np.int64)
    out = np.zeros(k, dtype)
    for j, atom in enumerate(atoms):
        truth = past[atom] if atom in past else node_series(atom, columns, k)
        np.bitwise_or(out, np.left_shift(truth.astype(dtype), j, dtype=dtype), out=out)
    return out


#: Traces stepped together by :func:`first_rejections` while at least this many are still
#: running (one numpy step for all of them); the rest are stepped one tick at a time
STEP_TOGETHER = 32


def first_rejections(table: list[list[int]], initial: int, letters: np.ndarray,
                     firsts: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """The first tick (0-based in its trace) at which the automaton ``table`` (``table[state]
    [letter]``, negative: rejected) from ``initial`` rejects each trace (``letters``, trace
    ``e`` at ``firsts[e]``, ``lengths[e]`` ticks), -1 where it never does: tick ``k`` of
    every trace still running in one numpy step while :data:`STEP_TOGETHER` or more run
    (the short traces of many entities), the rest as :func:`_first_rejection` steps them."""
    hits = np.full(len(firsts), -1, np.int64)
    firsts = np.asarray(firsts, np.int64)
    lengths = np.asarray(lengths, np.int64)
    active = np.flatnonzero(lengths > 0)
    state = np.full(len(active), initial, np.int64)
    try:
        steps = np.asarray(table, np.int64)
    except ValueError:  # (rows of unequal length: every trace stepped one tick at a time)
        steps = np.zeros((0, 0), np.int64)
    together = STEP_TOGETHER if steps.ndim == 2 and steps.size else len(firsts) + 1
    k = 0
    while len(active) and len(active) >= together:
        state = steps[state, letters[firsts[active] + k]]
        out = state < 0
        hits[active[out]] = k
        keep = ~out & (lengths[active] > k + 1)
        active, state = active[keep], state[keep]
        k += 1
    for e, st in zip(active.tolist(), state.tolist()):
        a = int(firsts[e])
        hit = _first_rejection(table, st, letters[a + k:a + int(lengths[e])])
        if hit is not None:
            hits[e] = hit + k
    return hits


def nan_ticks(requirement: A.Requirement, columns: Mapping[str, np.ndarray], n: int) -> np.ndarray:
    """The ticks (bool array of ``n``) at which a comparison of ``requirement`` (scope mode,
    condition, stop condition, response) reads NaN: unread ticks (:mod:`fretc.monitors.nan`).
    A free-form requirement has none."""
    if requirement.freeform:
        return np.zeros(n, dtype=np.bool_)
    return nan_ticks_of(compared_exprs(requirement), columns, n)


def compared_exprs(req: A.Requirement) -> list[A.Expr]:
    """The expressions of ``req`` whose comparisons a NaN leaves unread, each read as a
    condition: the scope mode, the condition (and each part of a compound one), the stop
    condition and the response, those it has (FRET's requirement fields)."""
    exprs = [req.scope.mode, req.condition.expr, req.timing.stop, req.response]
    exprs += [p.expr for p in req.condition.parts]
    return [e for e in exprs if e is not None]
