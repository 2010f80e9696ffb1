"""The passes over one log: each requirement sampled on its own clock and the columns kept
(:func:`run_passes`); then everything cut at the damage (:func:`cut_at_damage`).

A requirement's clock is its own variables (their bindings, and so the topics they read):
../shared/DESIGN.md, "Each verdict stands alone". Its tick grid, first and last tick,
warm-up (a binding that reads a topic's previous message waits for its second), gaps and
closing tick are those of its own variables only, so no other requirement of the run can
change them; requirements whose variables are the same share one sampled stream
(:func:`fretc.signals.sample_groups`), which for them is the same thing. The columns are judged afterwards, once, by
:func:`fretc.monitors.judge.judge` (:mod:`fretc.audit.finalize`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from fretc.signals.bindings import Bindings
from fretc.common.problems import SignalError
from fretc.signals import blocks_of_ticks, sample, sample_blocks
from fretc.signals.blocks import MAX_TICKS
from fretc.logs import CSV_TOPIC
from fretc.audit.columns import TickColumns
from fretc.audit.model import AuditPlan, RequirementPlan

__all__ = ["ClockPass", "ClockKey", "LogPasses", "run_passes", "cut_at_damage", "clock_key",
           "restrict",
           "expected_ticks", "lost_in_words", "MAX_TICKS"]



@dataclass
class ClockPass:
    """The ticks of one clock: its sampling (:class:`fretc.signals.Sampling`), tick
    times (ns) and the columns (variable -> values, topic -> held log times)."""

    sampling: Any
    times: np.ndarray
    columns: dict[str, np.ndarray]
    log_times: dict[str, np.ndarray]
    cut: int = 0  # ticks dropped after the damage (cut_at_damage)
    intact_end: int | None = None  # exclusive bound of the judged ticks' times
    #: when the judged span ends where something could not be read - messages of the
    #: clock's topics present but not decoded (topic, count, channel, first and last log
    #: time), or a comparison with NaN (audit.finalize) - that, in words
    lost: str | None = None


@dataclass
class LogPasses:
    """One read of a log: a :class:`ClockPass` per clock, and what went wrong per clock."""

    sampling: Any
    passes: dict[ClockKey, ClockPass]
    failed: dict[ClockKey, dict[str, SignalError]]
    errors: dict[ClockKey, SignalError]


def restrict(b: Bindings, names: list[str]) -> Bindings:
    """``b`` with only the variables in ``names``."""
    return Bindings({n: b.variables[n] for n in b.variables if n in names}, b.tick, b.time_base,
                    b.header_lag_ns, b.source)


def expected_ticks(source, bindings: Bindings | None) -> int | None:
    """Ticks the log should give: a CSV trace's rows, or its span over a fixed tick period
    (None when unknown: a topic tick, no span)."""
    if source.kind == "csv":
        return getattr(source, "row_count", None)
    if bindings is None or bindings.tick.period_ns is None:
        return None
    st, en = source.start_time, source.end_time
    if st is None or en is None:
        return None
    return (en - st) // bindings.tick.period_ns + 1


class ClockKey(NamedTuple):
    """The clock a requirement is sampled on (:func:`clock_key`): ``variables`` its bound
    FRET variables, ``topics`` the topics they read."""

    variables: frozenset
    topics: frozenset


def clock_key(r: RequirementPlan, bindings: Bindings | None) -> ClockKey:
    """The clock a requirement is sampled on: its own bound variables and their topics
    (../shared/DESIGN.md, "Each verdict stands alone": its tick grid, start, end, warm-up
    and gaps come from them and the bindings' tick, never from other requirements of the
    run; two requirements share a clock only when their variables are the same)."""
    if bindings is None:
        return ClockKey(frozenset(), frozenset())
    names = frozenset(v for v in r.variables if v in bindings.variables)
    return ClockKey(names, frozenset(t for v in names for t in bindings.variables[v].topics))


class _Clock:
    """The columns of one clock's requirements while the log is read."""

    def __init__(self, key: ClockKey, rs: list[RequirementPlan],
                 bindings: Bindings | None) -> None:
        self.names: list[str] = []
        for r in rs:
            for v in r.variables:
                if v not in self.names:
                    self.names.append(v)
        topics = sorted(key.topics) if bindings is not None else [CSV_TOPIC]
        self.columns = TickColumns(self.names, topics)


def _progress(source, expected: int | None, progress: Callable[[float], None]
              ) -> Callable[[Any], None]:
    """Report the fraction of the log read at tick time ``time`` (ns): by log time over the log's span, or
    by ticks over the ticks expected."""
    start_t, end_t = source.start_time, source.end_time
    span = (end_t - start_t) if (start_t is not None and end_t is not None
                                 and end_t > start_t) else None

    def report(time: int, count: int) -> None:
        if span is not None:
            progress(min(1.0, max(0.0, (time - start_t) / span)))
        elif expected:
            progress(min(1.0, count / expected))
    return report


def run_passes(plan: AuditPlan, source, bindings: Bindings | None,
               active: list[RequirementPlan],
               progress: Callable[[float], None] | None) -> LogPasses:
    """Read the log once: sample every clock of ``active``, keep the columns, then cut each
    clock at the damage.

    Raises:
        SignalError: a signal cannot be computed (the variable is named), or more than
            :data:`MAX_TICKS` ticks.
    """
    expected = expected_ticks(source, bindings)
    groups: dict[ClockKey, list[RequirementPlan]] = {}
    for r in active:
        groups.setdefault(clock_key(r, bindings), []).append(r)
    clocks = {key: _Clock(key, rs, bindings) for key, rs in groups.items()}
    if bindings is not None:
        sampling = sample_blocks(source, bindings,
                                 {key: (c.names, key.topics) for key, c in clocks.items()})
        stream = iter(sampling)
        failed, errors = sampling.failed, sampling.errors
    else:
        sampling = sample(source, None)
        key0 = next(iter(groups))
        c0 = clocks[key0]
        stream = ((key0, b) for b in blocks_of_ticks(iter(sampling), c0.names,
                                                     c0.columns.topics))
        failed, errors = {key0: {}}, {}
    report = _progress(source, expected, progress) if progress is not None else None
    count = 0
    for key, block in stream:
        clocks[key].columns.append_block(block)
        count += len(block.times)
        if count > MAX_TICKS:
            raise SignalError(f"{source.path}: more than {MAX_TICKS:,} ticks (the limit); "
                              "choose a longer tick period")
        if report is not None:
            report(int(block.times[-1]), count)
    passes: dict[frozenset, ClockPass] = {}
    for key, clock in clocks.items():
        times, columns, log_times = clock.columns.finish()
        s = sampling.groups[key] if bindings is not None else sampling
        passes[key] = ClockPass(s, times, columns, log_times)
        cut_at_damage(passes[key], source, bindings, key.topics)
    return LogPasses(sampling, passes, failed, errors)


def cut_at_damage(res: ClockPass, source, bindings: Bindings | None,
                  topics: frozenset = frozenset()) -> None:
    """Keep only the ticks of the span read completely (../shared/DESIGN.md "Damage is never
    evidence"): those strictly before the source's ``intact_end_of(topics)`` (a cut, the
    first gap, or the first message of one of the clock's ``topics`` that was present but
    not decoded, which ends the held value of its topic as a cut does; under the header
    time base, ``header_lag_ns`` earlier, since a lost message's stamp may precede its log
    time by that much). Sets ``res.cut`` to the number of ticks dropped, and ``res.lost``
    when messages not decoded end the span."""
    end = source.intact_end_of(topics)
    if end is None:
        return
    if end != source.intact_end:
        res.lost = lost_in_words(source, topics)
    if bindings is not None and bindings.time_base != "log":
        end -= bindings.header_lag_ns
    keep = int(np.searchsorted(res.times, end, side="left"))
    n = len(res.times)
    res.intact_end = end
    if keep >= n:
        return
    res.cut = n - keep
    res.times = res.times[:keep]
    res.columns = {k: v[:keep] for k, v in res.columns.items()}
    res.log_times = {k: v[:keep] for k, v in res.log_times.items()}


def lost_in_words(source, topics) -> str:
    """The messages of ``topics`` present but not decoded in the source's latest pass
    (:attr:`fretc.logs.LogSource.lost`), one clause per (kind, topic, channel), earliest first:
    how many, the channel, the first and last log time (ns) and why."""
    parts = []
    for (kind, topic, channel), (first, last, count, why) in sorted(
            source.lost.items(), key=lambda kv: (kv[1][0], kv[0][0], kv[0][1])):
        if topic not in topics:
            continue
        on = f" on channel {channel}" if channel is not None else ""
        parts.append(f"{count} message{'s' if count != 1 else ''} of {topic}{on} not "
                     f"decoded ({kind}: {why}), log time {first}..{last} ns")
    return "; ".join(parts)
