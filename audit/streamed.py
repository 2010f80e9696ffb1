"""CSV traces judged while they are read: each requirement's verdict and evidence from
streams fed a chunk of rows at a time, in memory that does not grow with the trace.

A CSV trace audited without bindings is read once with a sink (:class:`fretc.logs.CsvSource`'s
``sink``): each chunk of rows goes to three streams per requirement (FRET's interval
semantics, the pt formula's robustness, the LTL3 verdict), each the exact counterpart of one
part of the whole-trace judge, and the verdict is set by the same code as the whole-trace
audit's (:func:`fretc.audit.finalize.judged`): the audit JSON is the same byte for byte
(``tests/audit/test_streamed.py``). What is judged whole or three-valued instead
(:func:`unstreamed_reason`, :data:`NAN_REASON`,
:data:`UNKNOWN_CELLS`, :data:`GAP_ROW`), the reads again and the memory: ARCHITECTURE.md
("CSV traces, streamed").
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from fretc.fretish import ast as A
from fretc.logs import CsvSource
from fretc.monitors.expressions import EvidenceUnsupported
from fretc.monitors.interval import Evidence
from fretc.monitors.interval import IntervalStream, stream_unsupported
from fretc.monitors.judge import Ltl3Stream, compared_exprs
from fretc.monitors.nan import nan_ticks_of
from fretc.monitors.obligations import OpenObligation
from fretc.monitors.robustness import RobustnessStream, RobustnessSummary
from fretc.monitors.vectorized import VectorizeError, supports
from fretc.audit.verdict import MARGIN_POINTS

if TYPE_CHECKING:
    from fretc.audit.model import AuditPlan, RequirementPlan

#: why a requirement's streams give up at a NaN (the three-valued streams then take it,
#: :mod:`fretc.audit.streamed_three`)
NAN_REASON = "a comparison reads NaN"
#: the start of why a requirement reading ``unknown`` cells is given up (the columns follow)
UNKNOWN_CELLS = "unknown cells in "
#: why every requirement is given up on a trace with a ``gap`` row
GAP_ROW = "a gap row"

__all__ = ["ENABLED", "NAN_REASON", "UNKNOWN_CELLS", "GAP_ROW", "StreamedResult", "CsvStreams",
           "unstreamed_reason", "values_around", "RequirementStreams", "streams_of",
           "feed_streams"]

#: Whether CSV traces are judged while read (tests set it False to compare the two judges).
ENABLED = True


@dataclass
class StreamedResult:
    """What the streams of one requirement decided over the ``n`` rows of a trace.

    Attributes:
        evidence: the interval semantics' :class:`~fretc.monitors.interval.Evidence`.
        times: tick -> time (ns) of every tick < ``n`` the evidence names.
        ltl3: ``(status, tick, time)`` of the LTL3 verdict (``"unknown"``, None, None
            without an online monitor).
        robustness: the pt formula's :class:`~fretc.monitors.robustness.RobustnessSummary`.
        n: the rows (ticks) judged; ``last_time`` the last one's time (ns).
    """

    evidence: Evidence
    times: dict[int, int]
    ltl3: tuple[str, int | None, int | None]
    robustness: RobustnessSummary
    n: int
    last_time: int
    #: the trace ends at a ``cut`` row: the verdict is the one its intact rows decide
    #: (:func:`fretc.audit.damage.verdict_at_damage`)
    cut: bool = False
    #: at a cut: the obligations open there (:func:`fretc.audit.damage.open_obligations`)
    opened: list[OpenObligation] = field(default_factory=list)


@dataclass
class RequirementStreams:
    """One requirement's streams while its trace (a CSV trace's rows, a clock's ticks) is
    read."""

    r: RequirementPlan
    names: tuple[str, ...]
    exprs: list[A.Expr]
    interval: IntervalStream
    rob: RobustnessStream
    ltl3: Ltl3Stream | None
    #: why the requirement is judged whole after all (None: the streams decide it)
    gave_up: str | None = None
    #: after it gave up for a NaN: the first and last ticks a comparison of it reads NaN at
    #: (where the three-valued streams' completions start and end, audit/streamed_three.py)
    nan_range: tuple[int, int] | None = None


def unstreamed_reason(plan: AuditPlan, r: RequirementPlan) -> str | None:
    """None when requirement ``r`` of ``plan`` can be judged while a CSV trace is read
    (module docstring), else why not, in words."""
    req, f = r.requirement, r.formalization
    if not ENABLED:
        return "streaming is off"
    if r.error is not None or req is None or f is None or req.freeform:
        return "not judged"
    if plan.coverage:
        return "--coverage records obligations over the whole trace"
    if r.streams is not None:  # (its columns computed from the whole pass: audit.streams)
        return "it reads a stream variable FRET defines (through pre), computed whole"
    if getattr(r.compiled, "probability", None) is not None:
        return "its triggers are trials (a probability bound)"
    why = stream_unsupported(req)
    if why is not None:
        return why
    if not f.pt_causal or not supports(f.pt):
        return "its pt formula has a future-time operator"
    return None


def streams_of(r: RequirementPlan) -> RequirementStreams | str:
    """The streams of ``r`` (taken by :func:`unstreamed_reason`), or why one cannot be made
    (an automaton without tables, a bounded window longer than a robustness chunk)."""
    req, f = r.requirement, r.formalization
    assert req is not None and f is not None  # (unstreamed_reason took it)
    try:
        interval = IntervalStream(req, f.ticks)
        rob = RobustnessStream(f.pt, MARGIN_POINTS)
        ltl3 = None if r.offline else Ltl3Stream(r.monitor_source)
    except (EvidenceUnsupported, VectorizeError) as exc:
        return str(exc)
    return RequirementStreams(r, tuple(r.variables), compared_exprs(req), interval, rob, ltl3)


@dataclass
class CsvStreams:
    """The requirements of a CSV audit judged while the trace is read: the sink
    (:data:`fretc.logs.csv.read.RowSink`) handed to :class:`fretc.logs.CsvSource`.

    Build it with :meth:`of`; after the read, :meth:`close` says which requirements the
    streams decided (:attr:`results`) and which must be judged whole (:attr:`whole`)."""

    streams: list[RequirementStreams]
    n: int = 0
    first_time: int | None = None
    last_time: int | None = None
    #: requirement index -> what its streams decided (after :meth:`close`)
    #: (after :meth:`close`; a requirement whose comparisons read NaN, or that reads
    #: ``unknown`` cells, may then get a :class:`fretc.audit.streamed_three.ThreeResult`:
    #: :func:`~fretc.audit.streamed_three.judged_three`)
    results: dict[int, StreamedResult] = field(default_factory=dict)
    #: requirement index -> why it is judged whole after all (after :meth:`close`)
    whole: dict[int, str] = field(default_factory=dict)
    #: requirement index -> the first and last ticks a comparison of it reads NaN at, for
    #: those given up for a NaN (after :meth:`close`)
    nan_ranges: dict[int, tuple[int, int]] = field(default_factory=dict)

    @classmethod
    def of(cls, plan: AuditPlan, candidates: Iterable[RequirementPlan]) -> CsvStreams:
        """The streams of every requirement of ``candidates`` that
        :func:`unstreamed_reason` takes and whose streams can be made."""
        streams = []
        for r in candidates:
            if unstreamed_reason(plan, r) is None:
                got = streams_of(r)
                if isinstance(got, RequirementStreams):
                    streams.append(got)
        return cls(streams)

    @property
    def names(self) -> set[str]:
        """The columns the streams read."""
        return {n for s in self.streams for n in s.names}

    @property
    def indexes(self) -> set[int]:
        """The requirements streamed (their indexes)."""
        return {s.r.index for s in self.streams}

    def __call__(self, first: int, times: np.ndarray, columns: dict[str, np.ndarray]
                 ) -> None:
        """Feed a chunk of rows (:data:`fretc.logs.csv.read.RowSink`) to every stream."""
        k = len(times)
        if k == 0:
            return
        if self.first_time is None:
            self.first_time = int(times[0])
        self.last_time = int(times[-1])
        self.n = first + k
        for s in self.streams:
            if s.gave_up is None:
                feed_streams(s, columns, k, times, first)
            elif s.gave_up == NAN_REASON:
                _nan_range(s, columns, k, first)

    def close(self, source: CsvSource) -> None:
        """After the read: the results of the streams, or why a requirement is judged
        whole after all (module docstring)."""
        for s in self.streams:
            i = s.r.index
            unknown = [c for c in s.names if source.unknown_rows.get(c)]
            why = s.gave_up or (GAP_ROW if source.gap_rows else None) or (
                f"{UNKNOWN_CELLS}{', '.join(unknown)}" if unknown else None)
            if why is None and self.n == 0:
                why = "no row"
            if why is None and source.cut_time is not None:
                self.results[i] = self._at_cut(s)
                continue
            if why is not None:
                self.whole[i] = why
                if s.nan_range is not None:
                    self.nan_ranges[i] = s.nan_range
                continue
            assert self.last_time is not None  # (n rows)
            ev, times = s.interval.finish()
            status, tick, time = (s.ltl3.finish() if s.ltl3 is not None
                                  else ("unknown", None, None))
            self.results[i] = StreamedResult(ev, times, (status, tick, time),
                                             s.rob.finish(), self.n, self.last_time)
        self.streams = []

    def _at_cut(self, s: RequirementStreams) -> StreamedResult:
        """What the streams of ``s`` decided over the rows before a ``cut`` row, with the
        obligations open at the cut."""
        assert self.last_time is not None  # (n rows)
        ev, times = s.interval.finish()
        ltl3 = s.ltl3.finish() if s.ltl3 is not None else ("unknown", None, None)
        return StreamedResult(ev, times, ltl3, s.rob.finish(), self.n, self.last_time,
                              cut=True, opened=s.interval.open_at_end())


def feed_streams(s: RequirementStreams, columns: Mapping[str, np.ndarray], k: int,
                 times: np.ndarray, first: int) -> None:
    """Feed one chunk of ``k`` ticks (the trace's ticks ``first ..``; ``columns`` variable
    -> at least ``k`` values, ``times`` int64 ns) to the streams of ``s``; a chunk where a
    comparison reads NaN (unknown ticks: the three-valued judge's) or a column is missing
    gives up (``s.gave_up`` says why)."""
    try:
        cols = {n: columns[n] for n in s.names}
    except KeyError as exc:
        s.gave_up = f"no column {exc.args[0]!r}"
        return
    if nan_ticks_of(s.exprs, cols, k).any():
        s.gave_up = NAN_REASON
        s.interval = s.rob = s.ltl3 = None  # type: ignore[assignment]  # (their memory freed)
        _nan_range(s, columns, k, first)
        return
    s.interval.feed(cols, k, times)
    s.rob.feed(cols, k, times)
    if s.ltl3 is not None:
        s.ltl3.feed(cols, k, times)


def _nan_range(s: RequirementStreams, columns: Mapping[str, np.ndarray], k: int, first: int) -> None:
    """Widen ``s.nan_range`` by the chunk's ticks at which a comparison of ``s`` reads NaN."""
    at = np.flatnonzero(nan_ticks_of(s.exprs, {n: columns[n] for n in s.names}, k))
    if len(at):
        lo = s.nan_range[0] if s.nan_range is not None else first + int(at[0])
        s.nan_range = (lo, first + int(at[-1]))


def values_around(path: str, period_ns: int, types: Mapping[str, str],
                  wanted: Mapping[str, set[int]], extent: int | None = None
                  ) -> tuple[dict[int, int], dict[str, dict]]:
    """The times of some rows and the values of some columns there, read again from the CSV
    trace ``path`` up to the last row wanted (the values a violation's evidence shows
    around its trigger and its violation, :func:`fretc.audit.finalize.values_around`).

    Args:
        path: the trace; ``period_ns`` its rows' period without a ``time`` column.
        types: column -> ``"bool"`` or ``"float"``, as the whole file gave them (a chunk
            read early cannot tell a column of 0/1 cells from a number column).
        wanted: column -> the rows (0-based) whose values are wanted.
        extent: the bytes of the file read (:attr:`fretc.logs.CsvSource.extent`, the
            audit's first read's: rows appended since are not read; None: its size now).

    Returns:
        ``(times, values)``: row -> time (ns) of every wanted row; column -> row -> value
        (``bool`` or ``float``, as :func:`fretc.monitors.stepwise.to_python` gives a column's
        item).
    """
    rows = sorted({i for got in wanted.values() for i in got})
    times: dict[int, int] = {}
    values: dict[str, dict[int, bool | float]] = {c: {} for c in wanted}
    if not rows:
        return times, values
    last = rows[-1]

    def sink(first: int, ts: np.ndarray, cols: dict[str, np.ndarray]) -> None:
        lo = int(np.searchsorted(rows, first))
        hi = int(np.searchsorted(rows, first + len(ts)))
        for i in rows[lo:hi]:
            times[i] = int(ts[i - first])
            for c, got in wanted.items():
                if i in got:
                    x = cols[c][i - first]
                    values[c][i] = bool(x) if types.get(c) == "bool" else float(x)

    CsvSource(path, period_ns=period_ns, keep=(), sink=sink, streamed=set(wanted),
              keep_times=False, max_rows=last + 1, extent=extent)
    return times, values
