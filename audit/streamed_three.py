"""CSV traces whose comparisons read NaN, or with ``unknown`` cells or ``gap`` rows, judged in
three-valued semantics while they are read: the verdict, LTL3 verdict and evidence
:func:`fretc.audit.unknown_ticks.judge_three` gives over the whole trace's columns, in memory
that does not grow with the trace.

The audit reads such a trace again (within :attr:`fretc.logs.CsvSource.extent`), feeding each
requirement the three-valued judge's streams a chunk of rows at a time (Kleene's reading,
the LTL3 verdict, the definite failed triggers, the NaN and unknown ticks, the completions);
:func:`finalize_three` then sets the verdict as :func:`fretc.audit.finalize.finalize` does:
the audit JSON is the same bytes (``tests/audit/test_streamed.py``). What is judged whole
instead, and the memory and CPU it takes: ARCHITECTURE.md ("Three-valued CSV traces, streamed").
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from fretc.common.problems import NAN
from fretc.fretish import ast as A
from fretc.logs import CsvSource
from fretc.monitors.completions import CompletionsStream, TooManyStates
from fretc.monitors.definite import DefiniteStream
from fretc.monitors.expressions import EvidenceUnsupported
from fretc.monitors.interval import Evidence, IntervalStream
from fretc.monitors.judge import compared_exprs
from fretc.monitors.nan import nan_ticks_of
from fretc.monitors.obligations import OpenObligation
from fretc.monitors.three_valued import KleeneStream, Ltl3SetStream
from fretc.monitors.vectorized import VectorizeError
from fretc.audit.damage import verdict_at_damage
from fretc.audit.finalize import StreamTicks, decided
from fretc.audit.streamed import GAP_ROW, NAN_REASON, UNKNOWN_CELLS, CsvStreams
from fretc.audit.unknown_ticks import (COMPLETED_NOTE, gap_words, outgrew_words,
                                       pt_decides_note, unknown_reason)
from fretc.audit.verdict import Ltl3

if TYPE_CHECKING:
    from fretc.audit.model import AuditPlan, RequirementPlan
    from fretc.audit.verdict import LogAudit, Verdict

__all__ = ["ThreeResult", "ThreeStreams", "finalize_three", "judged_three",
           "CONCURRENT_STATES"]

#: The most completions followed in the three-valued streams' own read: past it they are
#: followed, where Kleene's reading leaves the verdict open, in one more read alone
CONCURRENT_STATES = 16


@dataclass
class ThreeResult:
    """What the three-valued streams of one requirement decided over the ``n`` rows of a
    trace (the last at ``last_time``, ns).

    Attributes:
        holds: FRET's finite-trace verdict in every completion of the NaN ticks (True:
            satisfied or vacuous; False: violated).
        evidence: the definite evidence (:class:`fretc.monitors.definite.DefiniteStream`).
        times: tick -> time (ns) of every tick the evidence names.
        ltl3: ``(status, tick, time)`` of the three-valued LTL3 verdict.
        last_hi: the last tick at which the pt formula may be true (None: none).
        possible_trigger: a trigger may have fired in unknown ticks.
        nan: the NaN ticks: ``(count, first tick, its time, last tick, its time)``.
        unknown: the ticks it reads unknown (NaN, ``unknown`` cells): ``(count, first
            tick, its time)``; ``what`` makes them unknown, in words; ``cells``: column ->
            the rows (ascending) of its ``unknown`` cells, for the columns it reads with one
            (a value shown there is None, as the whole-trace audit shows it).
        completed: the verdict was decided by following every completion
            (:mod:`fretc.monitors.completions`); ``outgrew``: why they were not all
            followed (empty: they were).
    """

    holds: bool | None
    evidence: Evidence
    times: dict[int, int]
    ltl3: tuple[str, int | None, int | None]
    last_hi: int | None
    possible_trigger: bool
    nan: tuple[int, int, int, int, int]
    n: int
    last_time: int
    unknown: tuple[int, int, int]
    what: str
    cells: dict[str, np.ndarray]
    completed: bool = False
    outgrew: str = ""
    #: the trace ends at a ``cut`` row, and the obligations open there
    #: (:func:`fretc.audit.damage.open_obligations` over the rows as read)
    cut: bool = False
    opened: list[OpenObligation] = field(default_factory=list)


@dataclass
class _Three:
    """One requirement's three-valued streams while the trace is read."""

    r: RequirementPlan
    names: tuple[str, ...]
    exprs: list[A.Expr]
    kleene: KleeneStream
    definite: DefiniteStream
    ltl3: Ltl3SetStream | None
    nan: list[int] = field(default_factory=lambda: [0, -1, 0, -1, 0])
    #: the ticks it reads unknown (unknown cells, NaN): count, the first and its time
    unknown: list[int] = field(default_factory=lambda: [0, -1, 0])
    cells: bool = False  # (some unknown cell read)
    nan_only: bool = False  # (some NaN tick without an unknown cell)
    gave_up: str | None = None
    #: the completions followed in the same read, from the first to the last tick the first
    #: read found unknown (``range``), kept when Kleene's reading is open there; ``outgrew``
    #: their bound's message (:class:`fretc.monitors.completions.TooManyStates`)
    completions: CompletionsStream | None = None
    range: tuple[int, int] | None = None
    outgrew: str = ""
    #: on a trace with a ``cut`` row: FRET's interval semantics over the rows as read, for
    #: the obligations open at the cut (as the whole-trace judge reads them)
    raw: IntervalStream | None = None


def _three_of(r: RequirementPlan, cut: bool) -> _Three | str:
    """The streams of ``r`` (a requirement :mod:`fretc.audit.streamed` took; ``cut``: the
    trace ends at a ``cut`` row), or why they cannot be made."""
    req, f = r.requirement, r.formalization
    assert req is not None and f is not None  # (streamed before: formalized)
    try:
        kleene = KleeneStream(f.pt)
        definite = DefiniteStream(req, f.ticks)
        ltl3 = (None if r.offline or r.monitor_source is None
                else Ltl3SetStream(r.monitor_source))
        raw = IntervalStream(req, f.ticks, limit=1) if cut else None
    except (EvidenceUnsupported, VectorizeError) as exc:
        return str(exc)
    return _Three(r, tuple(r.variables), compared_exprs(req), kleene,
                  definite, ltl3, raw=raw)


@dataclass
class ThreeStreams:
    """The requirements of a CSV audit judged in three-valued semantics while the trace is
    read again: the sink (:data:`fretc.logs.csv.read.RowSink`) handed to
    :class:`fretc.logs.CsvSource`. Build it with :meth:`of`; after the read, :meth:`close`
    says which it decided (:attr:`results`) and which must be judged whole (:attr:`whole`)."""

    streams: list[_Three]
    n: int = 0
    last_time: int | None = None
    results: dict[int, ThreeResult] = field(default_factory=dict)
    whole: dict[int, str] = field(default_factory=dict)
    #: requirement index -> (its plan, the first and last ticks a leaf of its pt formula is
    #: unknown at): Kleene's reading open at the last tick, every completion to follow
    open: dict[int, tuple[RequirementPlan, tuple[int, int] | None]] = field(
        default_factory=dict)
    #: column -> the rows (ascending) of its ``unknown`` cells, as the first read found them
    #: (the ``gap`` rows among them: every column unknown there)
    unknown_rows: dict[str, np.ndarray] = field(default_factory=dict)
    #: the ``gap`` rows (ascending): gap ticks, each one tick or more
    gap_rows: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    @classmethod
    def of(cls, requirements: Iterable[RequirementPlan], cut: bool = False) -> ThreeStreams:
        """The streams of each requirement of ``requirements`` whose streams can be made
        (``cut``: on a trace ending at a ``cut`` row); the others in :attr:`whole` with the
        reason."""
        out = cls([])
        for r in requirements:
            got = _three_of(r, cut)
            if isinstance(got, str):
                out.whole[r.index] = got
            else:
                out.streams.append(got)
        return out

    @property
    def names(self) -> set[str]:
        """The columns the streams read."""
        return {n for s in self.streams for n in s.names}

    def __call__(self, first: int, times: np.ndarray, columns: dict[str, np.ndarray]
                 ) -> None:
        """Feed a chunk of rows (:data:`fretc.logs.csv.read.RowSink`) to every stream."""
        k = len(times)
        if k == 0:
            return
        self.last_time = int(times[-1])
        self.n = first + k
        marked = _cells(self.unknown_rows, first, k)
        stretch = _cells({"": self.gap_rows}, first, k).get("")
        for s in self.streams:
            if s.gave_up is None:
                try:
                    _feed(s, columns, k, times, first, marked, stretch)
                except (KeyError, VectorizeError, EvidenceUnsupported, ValueError) as exc:
                    s.gave_up = f"cannot be read a chunk at a time ({exc})"

    def close(self) -> None:
        """After the read: each requirement's result, or why it is judged whole after all."""
        for s in self.streams:
            i = s.r.index
            lo, hi, last_hi = s.kleene.finish() if self.n else (False, True, None)
            why = s.gave_up or ("more runs of unknown ticks than the streams keep"
                                if s.definite.too_many else None)
            settled = None
            if why is None and lo != hi and s.completions is not None \
                    and s.kleene.free == s.range:  # (the same search as one more read)
                settled = (None, s.outgrew) if s.outgrew else (s.completions.finish(), "")
            if why is None and s.unknown[0] and self.last_time is not None:
                ev, times = s.definite.finish()
                ltl3 = s.ltl3.finish() if s.ltl3 is not None else ("unknown", None, None)
                if ltl3[1] is not None and ltl3[2] is not None:  # (a violation may be shown there)
                    times = {**times, ltl3[1]: ltl3[2]}
                marked = [c for c in s.names if len(self.unknown_rows.get(c, ()))]
                what = ", ".join(([f"unknown values of {', '.join(marked)}"] if marked
                                  else []) + (["comparisons with NaN"]
                                              if s.nan_only or not marked else []))
                what += gap_words(int(np.sum(self.gap_rows < self.n)))
                self.results[i] = ThreeResult(lo if lo == hi else None, ev, times, ltl3,
                                              last_hi, s.definite.possible_trigger,
                                              (s.nan[0], s.nan[1], s.nan[2], s.nan[3],
                                               s.nan[4]), self.n, self.last_time,
                                              (s.unknown[0], s.unknown[1], s.unknown[2]),
                                              what, {c: self.unknown_rows[c] for c in marked})
                if s.raw is not None:
                    s.raw.finish()
                    self.results[i].cut = True
                    self.results[i].opened = s.raw.open_at_end()
                if settled is not None:
                    _settle(self.results[i], *settled)
                elif lo != hi:  # (open: every completion followed, another read)
                    self.open[i] = (s.r, s.kleene.free)
            else:
                self.whole[i] = why or "no unknown tick read"
        self.streams = []


def _cells(unknown_rows: Mapping[str, np.ndarray], first: int, k: int
           ) -> dict[str, np.ndarray]:
    """Column -> its ``unknown`` cells among the rows ``first .. first+k-1`` (a bool array
    of ``k``), for the columns with one there."""
    out = {}
    for c, rows in unknown_rows.items():
        at = rows[np.searchsorted(rows, first):np.searchsorted(rows, first + k)] - first
        if len(at):
            mask = out[c] = np.zeros(k, np.bool_)
            mask[at] = True
    return out


def _feed(s: _Three, columns: Mapping[str, np.ndarray], k: int, times: np.ndarray,
          first: int, marked: Mapping[str, np.ndarray], stretch: np.ndarray | None) -> None:
    """Feed one chunk of ``k`` rows (the trace's rows ``first ..``; ``marked``: column ->
    its ``unknown`` cells in the chunk; ``stretch``: its ``gap`` rows, or None) to the
    streams of ``s``. Raises KeyError for a missing column, or what the streams raise."""
    cols = {n: np.asarray(columns[n])[:k] for n in s.names}
    nan = nan_ticks_of(s.exprs, cols, k)
    bad = np.flatnonzero(nan)
    if len(bad):
        if s.nan[0] == 0:
            s.nan[1], s.nan[2] = first + int(bad[0]), int(times[bad[0]])
        s.nan[0] += len(bad)
        s.nan[3], s.nan[4] = first + int(bad[-1]), int(times[bad[-1]])
    unknown = {n: m for n, m in marked.items() if n in s.names}
    if unknown:  # (the ticks it reads unknown: the unknown cells and the NaN ticks)
        cells = np.logical_or.reduce(list(unknown.values()))
        s.cells = s.cells or bool(cells.any())
        s.nan_only = s.nan_only or bool((nan & ~cells).any())
        nan = nan | cells
    else:
        s.nan_only = s.nan_only or bool(len(bad))
    at = np.flatnonzero(nan)
    if len(at):
        if s.unknown[0] == 0:
            s.unknown[1], s.unknown[2] = first + int(at[0]), int(times[at[0]])
        s.unknown[0] += len(at)
    s.kleene.feed(cols, unknown, k, stretch)
    if s.completions is not None and not s.outgrew:
        try:
            s.completions.feed(cols, unknown, k, stretch)
        except TooManyStates as exc:
            s.outgrew = str(exc)
        if len(s.completions.carries or ()) > CONCURRENT_STATES:
            s.completions = None  # (too many completions to follow beside the others)
    s.definite.feed(cols, unknown, k, times, stretch)
    if s.ltl3 is not None:
        s.ltl3.feed(cols, unknown, k, times, stretch)
    if s.raw is not None:
        s.raw.feed(cols, k, times)


def judged_three(plan: AuditPlan, streams: CsvStreams, source: CsvSource) -> None:
    """Read the CSV trace of ``source`` again (within its first read's bytes,
    :attr:`fretc.logs.CsvSource.extent`) with the three-valued streams of the requirements
    ``streams`` gave up for a NaN (:data:`NAN_REASON`), ``unknown`` cells in the columns
    they read (:data:`UNKNOWN_CELLS`) or a ``gap`` row (:data:`GAP_ROW`); those decided move
    from ``streams.whole`` to ``streams.results`` (a :class:`ThreeResult`)."""
    by_index = {r.index: r for r in plan.requirements}
    gaps = source.gap_rows
    todo = [by_index[i] for i, why in streams.whole.items()
            if why in (NAN_REASON, GAP_ROW) or why.startswith(UNKNOWN_CELLS)]
    three = ThreeStreams.of(todo, cut=source.cut_time is not None)
    if not three.streams:
        return
    # (a gap row: every column unknown there, as csv_marks marks it, and a gap tick)
    three.unknown_rows = {c: np.asarray(sorted({*source.unknown_rows.get(c, ()), *gaps}),
                                        np.int64) for c in three.names
                          if source.unknown_rows.get(c) or gaps}
    three.gap_rows = np.asarray(sorted(gaps), np.int64)
    for s in three.streams:  # (the completions beside them, from the first read's ticks)
        ends = list(streams.nan_ranges.get(s.r.index, ()))
        for c in s.names:
            rows = three.unknown_rows.get(c)
            if rows is not None and len(rows):
                ends += [int(rows[0]), int(rows[-1])]
        pt = s.r.formalization.pt  # type: ignore[union-attr]  # (streamed: formalized)
        if ends:
            s.range = (min(ends), max(ends))
            s.completions = CompletionsStream(pt, *s.range, streams.n)
    CsvSource(str(source.path), period_ns=source.period_ns, keep=(), sink=three,
              streamed=three.names, keep_times=False, extent=source.extent)
    three.close()
    if three.n != streams.n:  # (the same rows as the first read, or judged whole)
        return
    if three.open:
        _completions(source, three)
    for i, got in three.results.items():
        streams.results[i] = got  # type: ignore[assignment]  # (a ThreeResult beside them)
        del streams.whole[i]
    for i, why in three.whole.items():  # (why the three-valued streams gave it up too)
        streams.whole[i] = f"{streams.whole[i]}; {why}"


def _completions(source: CsvSource, three: ThreeStreams) -> None:
    """Follow every completion of the requirements whose Kleene reading is open
    (``three.open``) in one more read of the trace (within the first read's bytes), and
    set their results' verdicts: :func:`fretc.monitors.completions.decide`'s."""
    runs: dict[int, tuple[RequirementPlan, CompletionsStream]] = {}
    for i, (r, free) in three.open.items():
        got = three.results[i]
        if free is None:  # (no leaf unknown: Kleene's reading is the verdict)
            got.holds = False
            continue
        assert r.formalization is not None  # (streamed: formalized)
        runs[i] = (r, CompletionsStream(r.formalization.pt, free[0], free[1], three.n))
    if not runs:
        return
    failed: dict[int, str] = {}

    def sink(first: int, times: np.ndarray, columns: dict[str, np.ndarray]) -> None:
        k = len(times)
        for i, (r, run) in runs.items():
            if i in failed or k == 0:
                continue
            cols = {n: np.asarray(columns[n])[:k] for n in r.variables}
            cells = {c: m for c, m in _cells(three.unknown_rows, first, k).items()
                     if c in cols}
            try:
                run.feed(cols, cells, k, _cells({"": three.gap_rows}, first, k).get(""))
            except TooManyStates as exc:
                failed[i] = str(exc)

    names = {n for r, _ in runs.values() for n in r.variables}
    CsvSource(str(source.path), period_ns=source.period_ns, keep=(), sink=sink,
              streamed=names, keep_times=False, extent=source.extent)
    for i, (_r, run) in runs.items():
        _settle(three.results[i], *((None, failed[i]) if i in failed else (run.finish(), "")))


def _settle(got: ThreeResult, holds: bool | None, outgrew: str) -> None:
    """``got``'s verdict from its completions: ``holds`` their verdict (None: they differ,
    or ``outgrew``, the bound's message, stopped them)."""
    got.holds, got.outgrew = holds, outgrew
    got.completed = holds is not None


def finalize_three(plan: AuditPlan, r: RequirementPlan, got: ThreeResult, v: Verdict,
                   la: LogAudit) -> bool:
    """Set the verdict ``v`` of ``r`` from what its three-valued streams decided (``got``),
    as :func:`fretc.audit.finalize.finalize` sets it after
    :func:`fretc.audit.unknown_ticks.judge_three`: the ``nan`` data problem of its NaN
    ticks in ``la``, the unknown ticks, the definite counts, the LTL3 verdict, the notes
    and the verdict. Returns True for a violation (its values around the trigger and the
    violation are still to be read: :func:`fretc.audit.streamed_verdict.streamed_values`)."""
    count, first, first_time, last, last_time = got.nan
    if count:
        what = (f"{count} tick{'s' if count != 1 else ''} of {r.id} compare NaN (first at "
                f"tick {first}, {first_time} ns; last at tick {last}, {last_time} ns): a "
                "comparison with NaN is neither true nor false, so those ticks are unknown")
        la.problems.append({"kind": NAN, "topic": None, "log_time_ns": first_time,
                            "end_time_ns": last_time, "detail": what})
        la.problem_counts[f"{NAN} {r.id}"] = count
    v.engine = "interval"
    ev, holds = got.evidence, got.holds
    count, first, first_time = got.unknown
    v.unknown_ticks = count
    v.intervals, v.triggers, v.violations = ev.intervals, ev.triggers, ev.violations
    status, tick, time = got.ltl3
    if got.cut:  # (as fretc.audit.unknown_ticks judges a trace cut at its end)
        word, why = verdict_at_damage(holds is True, ev.triggers == 0, status, tick, got.n,
                                      ev, got.opened, has_ltl3=not r.offline)
        if word == "unknown":
            v.verdict, v.unknown_reason = "unknown", why
            ev.vacuous = False
            v.ltl3 = Ltl3(status, tick, time)
            return False
        holds = word != "violated"
    if holds is None:
        v.verdict = "unknown"
        v.unknown_reason = unknown_reason(count, got.n, got.what, first, first_time,
                                          outgrew_words(got.outgrew))
        ev.vacuous = False
        v.ltl3 = Ltl3(status, tick, time)
        return False
    if holds and ev.triggers == 0:
        ev.vacuous = True
        if got.possible_trigger:
            v.notes.append("vacuous on the ticks read: a trigger may have fired in unknown "
                           "ticks, and the requirement holds whichever way")
    else:
        ev.vacuous = False
    if not holds and ev.violation is None:
        v.notes.append(COMPLETED_NOTE if got.completed else pt_decides_note(got.last_hi))
    v.ltl3 = Ltl3(status, tick, time)
    v.notes.append(f"robustness unavailable: {count} of its ticks are unknown")
    decided(plan, r, v, holds, ev, status, tick, got.n,
            lambda: StreamTicks(got.times, got.n, got.last_time))
    return v.verdict == "violated"
