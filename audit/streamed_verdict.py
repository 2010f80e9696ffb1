"""The verdict of a requirement judged while its CSV trace was read
(:mod:`fretc.audit.streamed`), set by the steps :func:`fretc.audit.finalize.finalize` sets
a whole-trace verdict with, from what the streams decided (:func:`finalize_streamed`); the
values shown around its violation read again from the file (:func:`streamed_values`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from fretc.logs import CSV_TOPIC, CsvSource
from fretc.audit.finalize import judged, shown_ticks, StreamTicks
from fretc.audit.streamed import StreamedResult, values_around

if TYPE_CHECKING:
    from fretc.audit.streamed_log import ClockResult
    from fretc.audit.streamed_three import ThreeResult
    from fretc.audit.model import AuditPlan, RequirementPlan
    from fretc.audit.verdict import Verdict

__all__ = ["finalize_streamed", "finalize_clock_streamed", "streamed_values"]


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
           (rob.value, rob.tick, rob.tick_time, rob.points))
    return v.verdict == "violated"


def finalize_clock_streamed(plan: AuditPlan, r: RequirementPlan, got: ClockResult,
                            v: Verdict) -> None:
    """Set the verdict ``v`` of requirement ``r`` from what its streams decided as its
    clock was read (:mod:`fretc.audit.streamed_log`: a verdict that holds, on a clock without
    damage, gaps or unknown ticks), as :func:`fretc.audit.finalize.finalize` sets it from
    the clock's columns; the robustness's tick with the log time its topics held there."""
    res, rob = got.result, got.result.robustness
    judged(plan, r, v, StreamTicks(res.times, res.n, res.last_time), res.evidence, res.ltl3,
           (rob.value, rob.tick, rob.tick_time, rob.points), held=got.held)


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
