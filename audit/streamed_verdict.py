"""The verdict of a requirement judged while its CSV trace was read
(:mod:`fretc.audit.streamed`), set by the steps :func:`fretc.audit.finalize.finalize` sets
a whole-trace verdict with, from what the streams decided (:func:`finalize_streamed`); the
values shown around its violation read again from the file (:func:`streamed_values`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from fretc.logs import CSV_TOPIC, CsvSource
from fretc.audit.finalize import judged, shown_ticks, StreamTicks
from fretc.audit.verdict import TimePoint
from fretc.monitors.stepwise import to_python
from fretc.audit.streamed import StreamedResult, values_around

if TYPE_CHECKING:
    from fretc.audit.streamed_log import ClockResult, Picked
    from fretc.signals.bindings import Bindings
    from fretc.audit.streamed_three import ThreeResult
    from fretc.audit.model import AuditPlan, RequirementPlan
    from fretc.audit.verdict import Verdict

__all__ = ["finalize_streamed", "finalize_clock_streamed", "PickedTicks", "streamed_values"]


def finalize_streamed(plan: AuditPlan, r: RequirementPlan, got: StreamedResult,
                      v: Verdict) -> bool:
    """Set the verdict ``v`` of requirement ``r`` from what its streams decided over the
    trace (``got``), as :func:`fretc.audit.finalize.finalize` sets it from the trace's
    columns (engine ``"interval"``, LTL3 verdict, counts, robustness and margin, the first
    violation and the violations listed). Returns True for a violation: its values around
    the trigger and the violation are still to be read (:func:`streamed_values`)."""
    ticks = StreamTicks(got.times, got.n, got.last_time)
    rob = got.robustness
    status, tick, time = got.ltl3
    judged(plan, r, v, ticks, got.evidence, (status, tick, time),
           (rob.value, rob.tick, rob.tick_time, rob.points), at_cut=got.cut,
           opened=got.opened)
    return v.verdict == "violated"


class PickedTicks(StreamTicks):
    """The ticks of a clock judged as its log was read whose evidence was read again
    (:class:`fretc.audit.streamed_log.Picked`), as :class:`fretc.audit.finalize._Ticks` gives
    a clock's ticks: each with the log time its topics held (the last tick's, ``last_held``,
    kept by the streams); a tick past the last counted on with the bindings' tick period."""

    def __init__(self, n: int, last_time: int, last_held: int | None, picked: Picked,
                 period_ns: int | None) -> None:
        super().__init__(picked.times, n, last_time)
        self.held, self.last_held, self.period_ns = picked.held, last_held, period_ns

    def point(self, i: int) -> TimePoint:
        """Tick ``i`` as a :class:`TimePoint` (its time and held log time; the last tick's
        kept by the streams)."""
        j = min(max(i, 0), self.n - 1)
        if j == self.n - 1:
            return TimePoint(int(i), self.last_time, self.last_held)
        return TimePoint(int(i), self.times[j], self.held[j])

    def time_at(self, i: int) -> int | None:
        """Tick ``i``'s time (ns): a picked tick's, the last tick's, or past it counted on
        with the tick period; None where none is known."""
        if 0 <= i < self.n - 1:
            return self.times[i]
        if i == self.n - 1:
            return self.last_time
        if i >= self.n and self.period_ns:
            return self.last_time + (i - self.n + 1) * self.period_ns
        return None


def finalize_clock_streamed(plan: AuditPlan, r: RequirementPlan, got: ClockResult,
                            v: Verdict, picked: Picked | None, bindings: Bindings | None
                            ) -> None:
    """Set the verdict ``v`` of requirement ``r`` from what its streams decided as its
    clock was read (:mod:`fretc.audit.streamed_log`: on a clock without damage, gaps or
    unknown ticks), as :func:`fretc.audit.finalize.finalize` sets it from the clock's
    columns: the robustness's tick with the log time its topics held there; a violation's
    evidence and values from the ticks read again (``picked``)."""
    res, rob = got.result, got.result.robustness
    ticks: StreamTicks = StreamTicks(res.times, res.n, res.last_time)
    if got.wanted:
        assert picked is not None  # (read again for its wanted ticks)
        period = bindings.tick.period_ns if bindings is not None else None
        ticks = PickedTicks(res.n, res.last_time, got.last_held, picked, period)
    judged(plan, r, v, ticks, res.evidence, res.ltl3,
           (rob.value, rob.tick, rob.tick_time, rob.points), held=got.held)
    if v.verdict != "violated":
        return
    assert picked is not None
    shown = shown_ticks(plan.config.window, v, res.n)
    for name in r.variables:
        col = picked.values.get(name)
        if col is not None:
            v.values[name] = [(i, picked.times[i], to_python(col[i])) for i in shown]
    for t in sorted(picked.log_times):
        lt = picked.log_times[t]
        v.sources[t] = [(i, picked.times[i], lt[i] if lt[i] >= 0 else None) for i in shown]


def streamed_values(plan: AuditPlan, source: CsvSource, violated: list[RequirementPlan],
                    verdicts: Mapping[int, Verdict],
                    streamed: Mapping[int, StreamedResult | ThreeResult]) -> None:
    """The values and message log times of the violated requirements ``violated`` at the
    ticks :func:`fretc.audit.finalize.shown_ticks` shows around their first violation
    (``v.values``, ``v.sources``), read again from the trace in one pass up to the last
    of them (:func:`fretc.audit.streamed.values_around`), within the bytes the audit first
    read (:attr:`fretc.logs.CsvSource.extent`)."""
    want: dict[str, set[int]] = {}
    shown = {}
    for r in violated:
        v = verdicts[r.index]
        shown[r.index] = ticks = shown_ticks(plan.config.window, v, streamed[r.index].n)
        for name in r.variables:
            want.setdefault(name, set()).update(ticks)
    times, values = values_around(str(source.path), source.period_ns, source.types, want,
                                  source.extent)
    for r in violated:
        v, ticks = verdicts[r.index], shown[r.index]
        cells = getattr(streamed[r.index], "cells", {})  # (a ThreeResult's unknown cells)
        for name in r.variables:
            unknown = set(cells[name].tolist()) if name in cells else set()
            v.values[name] = [(i, times[i], None if i in unknown else values[name][i])
                              for i in ticks]
        # (a row's message is the row: its log time the tick's, None when negative)
        v.sources[CSV_TOPIC] = [(i, times[i], times[i] if times[i] >= 0 else None)
                                for i in ticks]
