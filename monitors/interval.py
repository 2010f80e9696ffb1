"""FRET's interval semantics of one requirement, the verdict and the evidence behind it, over
a trace fed a chunk of ticks at a time (:class:`IntervalStream`); judging a whole trace is
feeding it one chunk (:func:`evaluate_requirement`).

The monitors decide a requirement with its past-time formula; this module decides it again
from the meaning the formulas encode (``../shared/fretish/README.md`` sections 2-4; FRET's
``fretishSemantics`` manual; Giannakopoulou et al., IST 2021), without any formula code, and
says *why*: scope intervals, trigger points (:func:`trigger_ticks`), each trigger's obligation
(:data:`fretc.monitors.obligations.OBLIGATIONS`); the first violation (:class:`Violation`) is
the earliest trigger whose obligation fails. Only uninterpreted functions and free-form
sentences raise :class:`EvidenceUnsupported`. Memory O(chunk + k + :data:`MAX_LISTED`), CPU
O(chunk) numpy work per chunk. The rule step by step, expressions and chunking:
ARCHITECTURE.md ("FRET's interval semantics").
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from fretc.fretish import ast as A
from fretc.fretish.fret_since import SINCE
from fretc.monitors.evidence import MAX_LISTED, Evidence, Violation
from fretc.monitors.expressions import ColumnExpressions, EvidenceUnsupported
from fretc.monitors.interval_fates import BOUNDED, NONE, Bounded, Chunk, Group, Ledger
from fretc.monitors.obligations import (OBLIGATIONS, Interval, OneTrigger, OpenObligation,
                                        open_reason)

__all__ = ["EvidenceUnsupported", "Violation", "Evidence", "MAX_LISTED", "IntervalStream",
           "evaluate_requirement", "verdict_of", "every_trigger", "Triggered", "duration_of",
           "favoured", "endpoints", "scope_mode", "scope_intervals", "stream_unsupported",
           "trigger_ticks", "NOT_POINTWISE", "OBLIGATIONS"]

#: FRET's temporal functions: their value at a tick reads other ticks (and the scope's
#: ``Left``/``Right``), so a chunk alone cannot evaluate them.
NOT_POINTWISE = ("persisted", "occurred", "persists", "occurs", "prevOcc", "nextOcc",
                 "preBool", "preInt", "preReal", SINCE)
#: No limit on the violations listed (:func:`every_trigger`).
_ALL = 1 << 62


# --------------------------------------------------------------------------- expressions
def endpoints(kind: str, mode: np.ndarray | None, n: int) -> tuple[np.ndarray, np.ndarray]:
    """FRET's ``Left`` and ``Right`` of a scope (``../shared/fretish/README.md`` section 6b's
    table) at each of the ``n`` ticks of a finite trace: ``Left`` (a pt formula) marks the
    first position of a scope interval, ``Right`` (an ft formula, false after the last tick)
    its last position, as the temporal functions of conditions, responses and stop
    conditions see them.

    Args:
        kind: a scope kind of :data:`fretc.fretish.ast.SCOPE_KINDS`.
        mode: the mode's truth at each tick (None for ``null``).
        n: ticks (>= 1).

    Returns:
        (left, right): two bool arrays of ``n`` items.

    FRET's ``Right`` of ``notin``/``onlyIn``/``before`` has no ``LAST`` disjunct, so an
    interval of those scopes reaching the last tick has no ``Right`` (its functions look
    into the absorbing state after the trace); ``onlyAfter``'s is the end of every ``m`` run.
    """
    i = np.arange(n)
    first = i == 0
    last = i == n - 1
    if kind == "null" or mode is None:
        return first, last.copy()
    m = np.asarray(mode, dtype=np.bool_)
    prev = np.concatenate(([False], m[:-1]))           # Y m (false at 0)
    prev_z = np.concatenate(([True], m[:-1]))          # Z m (true at 0)
    nxt = np.concatenate((m[1:], [False]))             # X m (unused at the last tick)
    run_start = m & ~prev                              # m & Z !m
    run_end = m & (last | ~nxt)                        # m & (LAST | X !m)
    gap_start = ~m & prev_z                            # !m & Z m
    gap_end = ~m & ~last & nxt                         # !m & !LAST & X m
    if kind == "in":
        return run_start, run_end
    if kind in ("notin", "onlyIn"):
        return gap_start, gap_end
    if kind == "after":
        fall = ~m & prev                               # first !m & Y m
        left = np.zeros(n, np.bool_)
        if fall.any():
            left[int(np.argmax(fall))] = True
        return left, last.copy()
    if kind == "onlyAfter":
        return first, run_end
    if kind == "before":
        return first, gap_end
    if kind == "onlyBefore":
        left = np.zeros(n, np.bool_)
        if m.any():
            left[int(np.argmax(m))] = True             # m & Z !m & Z H !m
        return left, last.copy()
    raise ValueError(f"unknown scope kind {kind!r}")


def scope_mode(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int
               ) -> np.ndarray | None:
    """The truth of ``req``'s scope mode (or scope condition) at each of ``n`` ticks, its
    temporal functions in FRET's endpoint-free forms (``../shared/fretish/README.md``
    section 6b); None for the ``null`` scope."""
    if req.scope.kind == "null":
        return None
    assert req.scope.mode is not None  # (a scope other than null has its mode)
    return ColumnExpressions(columns, n, free=True).bool(req.scope.mode)[:n]


def _expressions(req: A.Requirement) -> list[tuple[str, A.Expr]]:
    """(role, expression) of each expression the interval semantics evaluates for ``req``."""
    out: list[tuple[str, A.Expr]] = []
    if req.scope.kind != "null" and req.scope.mode is not None:
        out.append(("scope condition", req.scope.mode))
    if req.condition.kind != "null" and req.condition.expr is not None:
        out.append(("condition", req.condition.expr))
    if req.timing.kind in A.STOP_TIMINGS and req.timing.stop is not None:
        out.append(("stop condition", req.timing.stop))
    if req.response is not None:
        out.append(("response", req.response))
    return out


class _ChunkExpressions(ColumnExpressions):
    """:class:`ColumnExpressions` (FRET's endpoint-free forms, which equal the scoped ones for
    pointwise expressions) over one chunk whose first tick is the trace's tick ``offset``:
    ``FTP`` is true at the trace's tick 0 only."""

    def __init__(self, columns: Mapping[str, np.ndarray], n: int, offset: int) -> None:
        super().__init__(columns, n, free=True)
        self.offset = offset

    def bool(self, e: A.Expr) -> np.ndarray:
        """As :meth:`ColumnExpressions.bool`, ``FTP`` read at the chunk's offset."""
        if isinstance(e, A.Var) and e.name == "FTP":
            return self.idx == -self.offset
        return super().bool(e)


class _AnyColumns(Mapping[str, np.ndarray]):
    """Every name has an empty column: evaluating an expression over 0 ticks then raises only
    what does not depend on the data (an arithmetic operator as a condition, a call the
    compiler cannot print)."""

    _EMPTY = np.zeros(0)

    def __getitem__(self, key: str) -> np.ndarray:
        return self._EMPTY

    def __contains__(self, key: object) -> bool:
        return True

    def __iter__(self) -> Iterator[str]:
        return iter(())

    def __len__(self) -> int:
        return 0


def _temporal_function(req: A.Requirement) -> str | None:
    """Why ``req``'s expressions are not pointwise (module docstring), or None."""
    for role, e in _expressions(req):
        for x in A.walk(e):
            if isinstance(x, A.Call) and x.name in NOT_POINTWISE:
                return (f"the {role} uses FRET's temporal function {x.name}, whose value at "
                        "a tick reads other ticks: the interval stream evaluates pointwise "
                        "expressions only")
    return None


def stream_unsupported(req: A.Requirement) -> str | None:
    """None when :class:`IntervalStream` takes ``req`` in chunks of any size, else why not, in
    words: a free-form sentence; an expression (scope condition, condition, stop condition,
    response) that uses one of FRET's temporal functions (:data:`NOT_POINTWISE`, the
    occurrence phrases included: such a requirement is fed the whole trace as one chunk);
    or one the interval semantics cannot evaluate whatever the data (the reason
    :class:`EvidenceUnsupported` gives). An uninterpreted function is taken: its column is
    looked for in each chunk (:meth:`IntervalStream.feed`)."""
    if req.freeform or req.response is None:
        return "a free-form requirement has no semantics"
    why = _temporal_function(req)
    if why is not None:
        return why
    ex = _ChunkExpressions(_AnyColumns(), 0, 0)
    for _role, e in _expressions(req):
        try:
            ex.bool(e)
        except EvidenceUnsupported as exc:
            return str(exc)
    return None


def duration_of(req: A.Requirement, duration_ticks: int | None) -> int | None:
    """The timing's duration in ticks (``within``/``for``/``after``; None for the timings
    without one): ``duration_ticks`` as the compiler converted it
    (``Formalization.ticks``), or without it the duration's amount read as ticks.

    Raises:
        EvidenceUnsupported: a fractional amount without ``duration_ticks`` (a duration in
            time units with no tick period)."""
    if req.timing.kind not in A.DURATION_TIMINGS:
        return None
    if duration_ticks is not None:
        return int(duration_ticks)
    assert req.timing.duration is not None  # (a duration timing has it)
    amount = Fraction(req.timing.duration.amount)
    if amount.denominator != 1:
        raise EvidenceUnsupported("a fractional duration without a tick period")
    return int(amount)


def favoured(req: A.Requirement, R: np.ndarray, C: np.ndarray | None,
             S: np.ndarray | None, favour: Any
             ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """``R, C, S`` with their unknown ticks (``favour``) set to meet the obligation: no
    trigger; the response the timing wants (true, false for ``never``, negated in ``only*``
    scopes); the stop condition that ends an ``until`` and does not end a ``before``."""
    want = (not req.scope.kind.startswith("only")) != (req.timing.kind == "never")
    R = np.where(favour.R[:len(R)], want, R)
    if C is not None:
        C = np.where(favour.C[:len(C)], False, C)
    if S is not None:
        S = np.where(favour.S[:len(S)], req.timing.kind == "until", S)
    return R, C, S


# --------------------------------------------------------------------------- scopes
class _Membership:
    """Which ticks lie in a scope interval (for ``only*`` scopes: in an interval of the
    complement), chunk by chunk; the intervals are the maximal runs of it (module
    docstring, point 1)."""

    def __init__(self, kind: str) -> None:
        if kind not in A.SCOPE_KINDS:
            raise ValueError(f"unknown scope kind {kind!r}")
        self.kind = kind
        self.prev_m = False   # the mode at the last tick fed
        self.seen = False     # before/onlyBefore: M so far; after/onlyAfter: a fall so far
        self.ones = np.ones(0, np.bool_)   # (null: every tick; read only)

    def chunk(self, M: np.ndarray | None, L: int) -> np.ndarray:
        """The membership of the next ``L`` ticks (bool array), given their mode ``M``."""
        kind = self.kind
        if kind == "null" or M is None:
            if len(self.ones) < L:
                self.ones = np.ones(L, np.bool_)
            return self.ones[:L]
        if kind == "in":
            return np.asarray(M, np.bool_)
        if kind in ("notin", "onlyIn"):
            return ~M
        if kind in ("before", "onlyBefore"):
            event = M
        else:  # after, onlyAfter: the ticks where M falls (!M just after M)
            event = ~M
            event[0] &= self.prev_m
            event[1:] &= M[:-1]
        seen = np.logical_or.accumulate(event)
        if self.seen:
            seen[:] = True
        self.seen = bool(seen[-1])
        self.prev_m = bool(M[-1])
        return seen if kind in ("onlyBefore", "after") else ~seen


def scope_intervals(kind: str, mode: np.ndarray | None, n: int) -> list[Interval]:
    """The scope intervals ``(s, e)`` of ``n`` ticks whose scope mode is ``mode`` (None for
    ``null``), in order: the runs of their membership (module docstring, point 1; for
    ``only*`` scopes the intervals of the complement)."""
    if n == 0:
        return []
    M = None if mode is None else np.array(mode[:n], np.bool_)
    d = np.diff(_Membership(kind).chunk(M, n).astype(np.int8), prepend=np.int8(0),
                append=np.int8(0))
    return list(zip(np.flatnonzero(d == 1).tolist(), (np.flatnonzero(d == -1) - 1).tolist()))


def trigger_ticks(cond: str, C: np.ndarray | None, I: np.ndarray, starts: np.ndarray,
                  last_ci: bool) -> np.ndarray:
    """The trigger points (local ticks, ascending) of a chunk whose membership is ``I``
    (module docstring, point 2): the interval ``starts`` (``null`` condition), the ticks in
    an interval where ``C`` holds (``holding``), or where ``C & I`` rises, ``last_ci``
    being its value at the tick before the chunk (``regular``)."""
    if cond == "null":
        return starts
    assert C is not None  # (a condition other than null has its truth)
    CI = C & I
    if cond == "holding":
        return np.flatnonzero(CI)
    rise = np.diff(CI.view(np.int8), prepend=np.int8(last_ci))
    return np.flatnonzero(rise == 1)


# --------------------------------------------------------------------------- the stream
class IntervalStream:
    """FRET's interval semantics of one requirement over a trace fed a chunk at a time
    (module docstring): :meth:`finish` gives the :class:`Evidence` of the ticks fed.

    Args:
        req: a parsed, not free-form requirement.
        duration_ticks: the timing's duration in ticks (``within``/``for``/``after``), as
            converted by the compiler (``Formalization.ticks``); None reads the duration's
            amount as ticks.
        limit: the most violations listed (all are counted).
        record: keep every scope interval and trigger point (:attr:`intervals`,
            :attr:`triggers`): memory that grows with them, for a whole trace.

    Raises:
        EvidenceUnsupported: ``req`` is free-form; a fractional duration without
            ``duration_ticks``; a negative duration.

    Attributes:
        n: ticks fed so far.
        pointwise: its expressions read one tick each (module docstring): fed any chunks;
            else fed the whole trace as one chunk.
    """

    def __init__(self, req: A.Requirement, duration_ticks: int | None, *,
                 limit: int = MAX_LISTED, record: bool = False) -> None:
        if req.freeform or req.response is None:
            raise EvidenceUnsupported("a free-form requirement has no semantics")
        self._req = req
        self._response: A.Expr = req.response
        # the expressions evaluated (None where the requirement has none)
        self._mode = req.scope.mode if req.scope.kind != "null" else None
        self._cond = req.condition.expr if req.condition.kind != "null" else None
        self._stop = req.timing.stop if req.timing.kind in A.STOP_TIMINGS else None
        self.pointwise = _temporal_function(req) is None
        timing, negate = req.timing.kind, req.scope.kind.startswith("only")
        k = duration_of(req, duration_ticks) or 0
        if k < 0:
            raise EvidenceUnsupported(f"a negative duration ({k} ticks)")
        self._scope = _Membership(req.scope.kind)
        self._obligation = (Bounded(timing, negate, k) if timing in BOUNDED
                            else Group(timing, negate, limit))
        self._ledger = Ledger(timing, negate, k, limit)
        self.n = 0
        self._in = False          # the last tick fed is in an interval
        self._last_ci = False     # ... and its condition held
        self._last_time = 0
        self._last_R = False
        self._result: tuple[Evidence, dict[int, int]] | None = None
        #: at :meth:`finish`: the open interval's start and its waiting triggers
        self._waiting: tuple[int, list[tuple[int, int | None]]] | None = None
        self._record: tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]] | None = (
            ([], [], []) if record else None)
        #: called with each chunk's trigger points (the trace's tick of the chunk's first,
        #: the local trigger ticks, the local interval starts, the start of the interval
        #: open before the chunk or None, the chunk's times): the definite triggers of
        #: :class:`fretc.monitors.definite.DefiniteStream`
        self.on_triggers: Callable[..., None] | None = None

    def feed(self, columns: Mapping[str, np.ndarray], k: int, times: np.ndarray,
             favour: Any = None) -> None:
        """Take the next ``k`` ticks (the trace's ticks ``n .. n+k-1``).

        Args:
            columns: FRET variable (or printed uninterpreted call) -> array of at least ``k``
                values; a boolean variable as ``bool``, ``uint8`` 0/1 or ``float64`` 0/1,
                which may change from chunk to chunk.
            k: ticks in the chunk (0 is allowed).
            times: ``int64`` array of at least ``k`` tick times (ns).
            favour: where the chunk's condition, response and stop condition are unknown
                (bool arrays ``C``, ``R``, ``S`` of at least ``k``:
                :class:`fretc.monitors.unknowns.Unknowns` over the chunk): there they take
                the value that meets the obligation (no trigger, the response the timing
                wants, the stop condition that ends it), so the failures left are those the
                known ticks make (:func:`favoured`); None: the columns as they are.

        Raises:
            KeyError: a variable without a column.
            EvidenceUnsupported: an uninterpreted function without a column.
            ValueError: a column or ``times`` shorter than ``k``; a feed after
                :meth:`finish`; a second chunk of a requirement that is not pointwise.
        """
        if self._result is not None:
            raise ValueError("the interval stream is finished")
        if k <= 0:
            self.feed_signals(None, NONE, None, None, k, NONE)  # (raises for k < 0)
            return
        M, R, C, S = self._signals(columns, k)
        if favour is not None:
            R, C, S = favoured(self._req, R, C, S, favour)
        self.feed_signals(M, R, C, S, k, times)

    def _signals(self, columns: Mapping[str, np.ndarray], k: int
                 ) -> tuple[np.ndarray | None, np.ndarray, np.ndarray | None, np.ndarray | None]:
        """The chunk's mode, response, condition and stop condition (module docstring).

        Raises:
            ValueError: a second chunk of a requirement that is not pointwise."""
        ex: ColumnExpressions
        if self.pointwise:
            ex = _ChunkExpressions(columns, k, self.n)
            M = ex.bool(self._mode)[:k] if self._mode is not None else None
        elif self.n:
            raise ValueError(f"{_temporal_function(self._req)} (fed the whole trace as one "
                             "chunk)")
        else:
            M = scope_mode(self._req, columns, k)
            left, right = endpoints(self._req.scope.kind, M, k)
            ex = ColumnExpressions(columns, k, left, right)
        R = ex.bool(self._response)[:k]
        C = ex.bool(self._cond)[:k] if self._cond is not None else None
        S = ex.bool(self._stop)[:k] if self._stop is not None else None
        return M, R, C, S

    def feed_signals(self, M: np.ndarray | None, R: np.ndarray, C: np.ndarray | None,
                     S: np.ndarray | None, k: int, times: np.ndarray) -> None:
        """Take the next ``k`` ticks as their signals: the scope mode ``M`` (None for the
        ``null`` scope), the response ``R``, the condition ``C`` and the stop condition
        ``S`` (bool arrays of at least ``k``; None where the requirement has none), and
        their ``times``. Raises ValueError as :meth:`feed`."""
        if self._result is not None:
            raise ValueError("the interval stream is finished")
        if k < 0:
            raise ValueError(f"a chunk of {k} ticks")
        if k == 0:
            return
        times = np.asarray(times, np.int64)[:k]
        if len(times) < k:
            raise ValueError(f"{len(times)} tick times for {k} ticks")
        M = M[:k] if M is not None else None
        self._step(self._scope.chunk(M, k), R[:k], C[:k] if C is not None else None,
                   S[:k] if S is not None else None, times, final=False)
        self.n += k

    def _step(self, I: np.ndarray, R: np.ndarray, C: np.ndarray | None,
              S: np.ndarray | None, times: np.ndarray, final: bool) -> None:
        """Move the semantics through one chunk of membership ``I`` and signals."""
        L = len(I)
        if self._req.scope.kind == "null" and not final:   # one interval: the whole trace
            starts = closes = NONE
            if self.n == 0:
                starts = np.zeros(1, np.int64)
        else:   # the ticks where the membership changes
            edges = np.flatnonzero(I[1:] != I[:-1]) + 1
            if bool(I[0]) != self._in:
                edges = np.concatenate((np.zeros(1, np.int64), edges))
            opened = I[edges]
            starts, closes = edges[opened], edges[~opened] - 1
        T = NONE
        if not final:
            T = trigger_ticks(self._req.condition.kind, C, I, starts, self._last_ci)
            if C is not None:
                self._last_ci = bool(C[-1] & I[-1])
        if self.on_triggers is not None and not final:
            open_interval = self._ledger.open if self._in else None
            self.on_triggers(self.n, T, starts,
                             open_interval[0] if open_interval is not None else None, times)
        if self._record is not None:
            for kept, ticks in zip(self._record, (starts, closes, T)):
                kept.append(self.n + ticks)
        ch = Chunk(self.n, L, R, S, T, closes, self._in, times, self._last_time,
                   self._last_R, final)
        ledger = self._ledger
        awaiting = self._obligation.resolves and ledger.awaiting()
        count, rows, late = self._obligation.chunk(ch, ledger.room(), awaiting)
        ledger.chunk(ch, starts, count, rows, late)
        self._in = bool(I[-1])
        self._last_time = int(times[-1])
        self._last_R = bool(R[-1])

    def finish(self) -> tuple[Evidence, dict[int, int]]:
        """The evidence of the ticks fed, and the time (as fed) of every tick ``< n`` it
        names: its first interval's ends, its first trigger, and each listed violation's
        trigger, interval ends, window ends and violation tick. Later calls return the same;
        :meth:`feed` then raises.

        Raises:
            ValueError: no tick was fed (the interval semantics needs one).
        """
        if self._result is not None:
            return self._result
        if self.n < 1:
            raise ValueError("the interval semantics needs at least one tick")
        if self._in:  # close the open interval at the last tick
            if self._ledger.open is not None:
                self._waiting = (self._ledger.open[0], self._obligation.pending())
            none = np.zeros(1, np.bool_)
            self._step(none, none, None, none, np.zeros(1, np.int64), final=True)
        self._result = self._ledger.evidence(self.n)
        return self._result

    def open_at_end(self, limit: int = 1) -> list[OpenObligation]:
        """After :meth:`finish`: the first ``limit`` triggers whose obligation the ticks fed
        neither meet nor miss (their scope interval open at the last tick), earliest first:
        the obligations a damage after the last tick leaves open."""
        assert self._result is not None  # (finished)
        if self._waiting is None:
            return []
        s, e = self._waiting[0], self.n - 1
        timing, negate = self._req.timing.kind, self._req.scope.kind.startswith("only")
        k = self._ledger.k
        out = []
        for t, first in self._waiting[1]:
            why = open_reason(timing, negate, t, e, k,
                              OneTrigger(t, e + 1 if first is None else first))
            if why is not None:
                out.append(OpenObligation(t, (s, e), why))
                if len(out) >= limit:
                    break
        return out

    @property
    def intervals(self) -> list[Interval]:
        """Every scope interval ``(s, e)`` of the ticks fed, in order (after :meth:`finish`,
        of a stream made with ``record``)."""
        assert self._record is not None and self._result is not None  # (recorded, finished)
        starts, closes = (np.concatenate(x).tolist() for x in self._record[:2])
        return list(zip(starts, closes))

    @property
    def triggers(self) -> np.ndarray:
        """Every trigger point of the ticks fed, ascending (``int64``; of a stream made with
        ``record``)."""
        assert self._record is not None  # (recorded)
        return np.concatenate(self._record[2]) if self._record[2] else NONE


def _tick_times(n: int) -> np.ndarray:
    """Times for a trace fed without any: each tick's index."""
    return np.arange(max(n, 0), dtype=np.int64)


def evaluate_requirement(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
                         duration_ticks: int | None = None, favour: Any = None) -> Evidence:
    """Decide ``req`` on a whole trace of ``n`` ticks by FRET's interval semantics: an
    :class:`IntervalStream` fed it as one chunk.

    Args:
        req: a parsed (not free-form) requirement.
        columns: FRET variable -> 1-D array of ``n`` values (bool or numeric).
        n: number of ticks (>= 1).
        duration_ticks: as :class:`IntervalStream`'s.
        favour: as :meth:`IntervalStream.feed`'s (the unknown ticks of the parts).

    Raises:
        EvidenceUnsupported: free-form, or an uninterpreted function.
        KeyError: a variable missing from ``columns``.
        ValueError: ``n`` < 1.
    """
    s = IntervalStream(req, duration_ticks)
    s.feed(columns, n, _tick_times(n), favour)
    return s.finish()[0]


def verdict_of(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
               duration_ticks: int | None = None) -> str:
    """FRET's verdict of ``req`` on a finite trace as a word: ``"satisfied"``,
    ``"vacuous"``, ``"violated"``, or ``"unknown"`` when the interval semantics cannot
    evaluate it (:class:`EvidenceUnsupported`: an uninterpreted function, a free-form
    sentence). Arguments and other errors as :func:`evaluate_requirement`; this is the
    :data:`fretc.check.witness.Judge` ``fretc check`` passes for its witnesses."""
    try:
        ev = evaluate_requirement(req, columns, n, duration_ticks)
    except EvidenceUnsupported:
        return "unknown"
    return "violated" if not ev.holds else ("vacuous" if ev.vacuous else "satisfied")


@dataclass
class Triggered:
    """Every scope interval and trigger of a requirement on a whole trace
    (:func:`every_trigger`).

    Attributes:
        R, C, S: the response, condition and stop condition at each tick (C, S None
            where the requirement has none).
        intervals: the scope intervals ``(s, e)``, in order.
        triggers: the trigger points of each interval (lists of ticks, ascending).
        failed: trigger point -> its failed obligation (every one), as the evidence lists it.
    """

    R: np.ndarray
    C: np.ndarray | None
    S: np.ndarray | None
    intervals: list[Interval]
    triggers: list[list[int]]
    failed: dict[int, Violation]


def every_trigger(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
                  duration_ticks: int | None = None) -> Triggered:
    """Every scope interval, trigger and failed obligation of ``req`` on a whole trace of
    ``n >= 1`` ticks (:class:`Triggered`), by an :class:`IntervalStream` fed it as one chunk
    (the questions asked per trigger: trials, obligations open at a damage). Errors as
    :func:`evaluate_requirement`."""
    s = IntervalStream(req, duration_ticks, limit=_ALL, record=True)
    M, R, C, S = s._signals(columns, n)
    s.feed_signals(M, R, C, S, n, _tick_times(n))
    ev, _times = s.finish()
    intervals = s.intervals
    ticks = s.triggers
    cut = np.searchsorted(ticks, [e for _s, e in intervals], side="right")
    triggers = [x.tolist() for x in np.split(ticks, cut[:-1])] if intervals else []
    return Triggered(R, C, S, intervals, triggers, {v.trigger_tick: v for v in ev.listed})
