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

from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, NamedTuple, TYPE_CHECKING

import numpy as np

from fretc.common.streams import base_topic, log_topics
from fretc.signals.bindings import Bindings
from fretc.common.problems import SignalError
from fretc.signals import blocks_of_ticks, sample, sample_blocks
from fretc.signals.blocks import MAX_TICKS
from fretc.signals.csv_columns import csv_columns
from fretc.logs import CSV_TOPIC, CsvSource
from fretc.logs.base import Gap
from fretc.logs.recorded_gaps import LEFT_FOR_GOOD
from fretc.audit.columns import ClockPass, TickColumns
from fretc.audit.gaps import (Placed, gaps_of_clock, inner_gaps, insert_gap_ticks, placed,
                              split_bridged, unknown_masks)
from fretc.audit.model import AuditPlan, RequirementPlan

if TYPE_CHECKING:
    from fretc.logs.base import LogSource

__all__ = ["ClockPass", "ClockKey", "LogPasses", "run_passes", "cut_at_damage", "mark_gaps",
           "clock_key", "restrict", "expected_ticks", "lost_in_words", "csv_marks", "MAX_TICKS"]



@dataclass
class LogPasses:
    """One read of a log: a :class:`ClockPass` per clock, and what went wrong per clock."""

    sampling: Any
    passes: dict[ClockKey, ClockPass]
    failed: dict[ClockKey, dict[str, SignalError]]
    errors: dict[ClockKey, SignalError]
    #: the log's inner gaps judged as unknown ticks, and those bridged (``--bridge-gaps``)
    gaps: list = field(default_factory=list)
    bridged: list = field(default_factory=list)
    #: what the streams decided as the log was read (:class:`fretc.audit.streamed_log.
    #: Closed`; a clock judged so holds no tick in :attr:`passes`), or None
    streamed: Any = None


def restrict(b: Bindings, names: list[str]) -> Bindings:
    """``b`` with only the variables in ``names``."""
    return Bindings({n: b.variables[n] for n in b.variables if n in names}, b.tick, b.time_base,
                    b.header_lag_ns, b.source)


def expected_ticks(source: LogSource, bindings: Bindings | None) -> int | None:
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
        tick = bindings.tick.topic if bindings is not None else None
        if tick is not None and tick not in topics:  # (where a gap of it goes: KP-176)
            topics = sorted([*topics, tick])
        self.columns = TickColumns(self.names, topics)


def _progress(source, expected: int | None, progress: Callable[[float], None]
              ) -> Callable[[int, int], None]:
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


def run_passes(plan: AuditPlan, source: LogSource, bindings: Bindings | None,
               active: list[RequirementPlan],
               progress: Callable[[float], None] | None,
               streams: Callable[[dict[ClockKey, list[RequirementPlan]]], Any] | None = None
               ) -> LogPasses:
    """Read the log once: sample every clock of ``active``, keep the columns, then cut each
    clock at the damage. ``streams``: given the clocks and their requirements, the clocks
    judged as they are read instead (a :class:`fretc.audit.streamed_log.LogStreams`: its
    ``take``, ``flush`` and ``close``).

    Raises:
        SignalError: a signal cannot be computed (the variable is named), or more than
            :data:`MAX_TICKS` ticks.
    """
    expected = expected_ticks(source, bindings)
    groups: dict[ClockKey, list[RequirementPlan]] = {}
    for r in active:
        groups.setdefault(clock_key(r, bindings), []).append(r)
    clocks = {key: _Clock(key, rs, bindings) for key, rs in groups.items()}
    judged = streams(groups) if streams is not None else None
    stream: Iterator[tuple[Any, Any]]  # (clock key, TickBlock)
    #: clock key -> (times, columns, log times) read whole, not block by block
    finished: dict[ClockKey, tuple[np.ndarray, dict, dict]] = {}
    sampling: Any  # a GroupSampling, or the Sampling of a CSV trace
    if bindings is not None:
        sampling = sample_blocks(source, bindings,
                                 {key: (c.names, key.topics) for key, c in clocks.items()})
        stream = iter(sampling)
        failed, errors = sampling.failed, sampling.errors
    else:
        key0 = next(iter(groups))
        c0 = clocks[key0]
        failed, errors = {key0: {}}, {}
        if isinstance(source, CsvSource):  # the columns the source kept: no row objects
            sampling, times, cols = csv_columns(source, c0.names)
            if len(times) > MAX_TICKS:
                raise SignalError(f"{source.path}: more than {MAX_TICKS:,} ticks (the "
                                  "limit); choose a longer tick period")
            if progress is not None and len(times):
                _progress(source, expected, progress)(int(times[-1]), len(times))
            finished[key0] = (times, cols, {t: times for t in c0.columns.topics})
            stream = iter(())
        else:
            sampling = sample(source, None)
            stream = ((key0, b) for b in blocks_of_ticks(iter(sampling), c0.names,
                                                         c0.columns.topics))
    report = _progress(source, expected, progress) if progress is not None else None
    count = 0
    for key, block in stream:
        if judged is None or not judged.take(key, block, clocks[key].columns):
            clocks[key].columns.append_block(block)
        count += len(block.times)
        if count > MAX_TICKS:
            raise SignalError(f"{source.path}: more than {MAX_TICKS:,} ticks (the limit); "
                              "choose a longer tick period")
        if report is not None:
            report(int(block.times[-1]), count)
    if judged is not None:  # (the ticks a streamed clock gathered since its last chunk)
        for key, clock in clocks.items():
            judged.flush(key, clock.columns)
    passes: dict[ClockKey, ClockPass] = {}
    gaps, bridged = split_bridged(inner_gaps(source), plan.config.bridge_gaps_ns)
    for key, clock in clocks.items():
        times, columns, log_times = (finished[key] if key in finished
                                     else clock.columns.finish())
        s = sampling.groups[key] if bindings is not None else sampling
        passes[key] = res = ClockPass(s, times, columns, log_times)
        cut_at_damage(res, source, bindings, key.topics)
        mark_gaps(res, clock.names, bindings, gaps, key.topics,
                  lost_in_words(source, log_topics(key.topics) if bindings is not None
                                else [CSV_TOPIC]),
                  bindings is not None and bindings.time_base != "log" and source.kind != "csv")
        if source.kind == "csv":
            csv_marks(res, source, clock.names, bindings)
    out = LogPasses(sampling, passes, failed, errors, gaps, bridged)
    if judged is not None:
        out.streamed = judged.close(source, gaps)
    return out


def csv_marks(res: ClockPass, source: LogSource, names: list[str],
              bindings: Bindings | None) -> None:
    """What a CSV trace marks unknown (:class:`fretc.logs.csv.source.CsvSource`: ``unknown``
    cells, ``gap`` rows), as a gap of a log leaves it (:func:`mark_gaps`): ``res.unknown``
    per variable (a variable bound over ``/csv`` columns is unknown where a column it reads
    is) and ``res.tick_gaps`` the ``gap`` rows, unknown for every variable."""
    rows: dict[str, list[int]] = getattr(source, "unknown_rows", {})
    gap_rows: list[int] = getattr(source, "gap_rows", [])
    n = len(res.times)
    if not (rows or gap_rows) or not n:
        return
    for name in names:
        if bindings is None or name not in bindings.variables:
            cols = [name]
        else:
            fields = bindings.variables[name].fields
            cols = ([f.path[0] for f in fields if f.path and isinstance(f.path[0], str)]
                    if all(f.path and isinstance(f.path[0], str) for f in fields)
                    else list(rows))
        idx = [i for c in cols for i in rows.get(c, ()) if i < n] + [i for i in gap_rows if i < n]
        if idx:
            mask = res.unknown.setdefault(name, np.zeros(n, np.bool_))
            mask[idx] = True
    res.tick_gaps = sorted(set(res.tick_gaps) | {i for i in gap_rows if i < n})


def cut_at_damage(res: ClockPass, source: LogSource, bindings: Bindings | None,
                  topics: frozenset = frozenset()) -> None:
    """Keep only the ticks before the cut at the end of the log (../shared/DESIGN.md "Damage
    is a gap"): those strictly before :attr:`fretc.logs.LogSource.cut_start`, the start of
    a gap nothing after which was read (a truncation); under the header time base
    ``header_lag_ns`` earlier, since a lost message's stamp may precede its log time by that
    much. Sets ``res.cut`` to the number of ticks dropped. Gaps the log was read on after
    are not cuts: they leave ticks unknown (:func:`mark_gaps`)."""
    end = getattr(source, "cut_start", None)
    if end is None:
        return
    if bindings is not None and bindings.time_base != "log" and source.kind != "csv":
        end -= bindings.header_lag_ns  # (a CSV trace's cut is at its own tick times)
    keep = int(np.searchsorted(res.times, end, side="left"))
    n = len(res.times)
    res.intact_end = end
    if keep >= n:
        return
    res.cut = n - keep
    res.times = res.times[:keep]
    res.columns = {k: v[:keep] for k, v in res.columns.items()}
    res.log_times = {k: v[:keep] for k, v in res.log_times.items()}


def _left_after_last_tick(res: ClockPass, gone: list) -> None:
    """``gone``: gaps of topics whose publisher left the watched run for good after the
    clock's last tick (:data:`fretc.logs.recorded_gaps.LEFT_FOR_GOOD`, ``start`` past it):
    the clock's judged span ends at the earliest start (``res.intact_end``), no tick
    dropped; an obligation open there is ``unknown`` (:func:`fretc.audit.finalize`'s rule
    for a cut)."""
    if not gone:
        return
    end = min(g.start for g in gone)
    res.intact_end = end if res.intact_end is None else min(end, res.intact_end)
    topics = sorted({t for g in gone for t in (g.topics or ())})
    res.lost = "; ".join(x for x in (res.lost, (
        f"the publisher of {', '.join(topics)} left (unadvertised) and did not come back "
        "before the run ended")) if x)


def mark_gaps(res: ClockPass, names: list[str], bindings: Bindings | None,
              gaps: list, topics: frozenset, lost: str = "", header: bool = False) -> None:
    """Set ``res.unknown`` (variable -> ticks it is unknown at) and ``res.gaps`` (the gaps
    that may hold messages of the clock's ``topics``) from the log's inner ``gaps``
    (:func:`fretc.audit.gaps.inner_gaps`, bridged ones removed).

    A gap reaching past the clock's last tick is a cut there (the run went on, unread:
    :func:`cut_at_damage`'s rule); one before its first tick leaves the start of the run
    unknown: one tick is put before the first, unknown for every variable; on a clock that
    ticks on a topic's messages, a gap of that topic is one unknown tick of its own, whether
    or not the clock's variables read the topic (:func:`fretc.audit.gaps.insert_gap_ticks`;
    KP-177). Inserted ticks are listed in
    ``res.tick_gaps`` (how many ticks they stand for is not known). ``lost``: the
    messages of the clock's topics present but not decoded, in words
    (:func:`lost_in_words`), for the reasons given. ``header``: the ticks are header
    stamps, and each gap is placed among them by the log times of the messages they hold
    (:func:`fretc.audit.gaps.placed`; KP-176), not by comparing its log times with them."""
    tick_topic = bindings.tick.topic if bindings is not None else None
    # (a gap of the tick topic lost ticks of the clock, whatever its variables read)
    own = gaps_of_clock(gaps, ([*topics, tick_topic] if tick_topic is not None else topics)
                        if bindings is not None else [CSV_TOPIC])
    res.gaps = own
    res.lost_words = lost
    if not own or not len(res.times):
        return
    cut = _cut_at_trailing_gap(res, own, header)
    if not len(res.times):
        return
    own = [g for g in own if id(g) not in cut]  # (placed ones: their ticks are cut)
    lag = bindings.header_lag_ns if bindings is not None and bindings.time_base != "log" else 0
    if tick_topic is not None:
        res.tick_gaps = insert_gap_ticks(res, own, tick_topic, header)
    res.unknown = unknown_masks(res.times, res.log_times, names, bindings, own, lag, header)
    first = int(res.times[0])
    early = [g.start for g in own if g.start is None or g.start - lag < first]
    if header and any(not p.before for g in own for p in (_placements(res, g) or ())):
        early.append(first - 1 + lag)  # (placed before every tick: KP-176)
    if early:
        at = min((s - lag for s in early if s is not None), default=first - 1)
        _insert_first(res, min(at, first - 1))
    for i in res.tick_gaps:
        for name in names:
            mask = res.unknown.setdefault(name, np.zeros(len(res.times), np.bool_))
            mask[i] = True


def _placements(res: ClockPass, g: Gap) -> list[Placed] | None:
    """Under a header time base, gap ``g`` placed among the clock's ticks by each topic it
    may hold that the ticks hold (:func:`fretc.audit.gaps.placed`); None: no such topic (the
    gap is then compared with the ticks' times)."""
    got = [placed(h, g) for t, h in sorted(res.log_times.items()) if g.affects(base_topic(t))]
    return got or None


def _cut_at_trailing_gap(res: ClockPass, own: list, header: bool = False) -> set[int]:
    """A gap that ends at or after the clock's last tick: nothing after its start was read
    for this clock, as after a cut; the ticks from its start on are dropped. A topic whose
    publisher left a watched run for good (:data:`fretc.logs.recorded_gaps.LEFT_FOR_GOOD`) is
    no cut where the clock ticks past its start: the run went on and was read, and the
    topic's variables are unknown there, so a violation the other topics show is kept. Past
    the clock's last tick it is the end of what this clock read while the run went on: a
    cut after its last tick (:func:`_left_after_last_tick`), as the same requirement watched
    alone is cut when its only publisher leaves (``publishers_left``). ``header``: a gap
    reaches past the last tick when no tick holds a message logged after it, of any topic it
    may hold, and the ticks are cut from the first that may hold a lost message
    (:func:`_placements`); returns the ``id`` of each gap so placed and cut (the ticks left
    hold nothing it lost)."""
    last = int(res.times[-1])
    _left_after_last_tick(res, [g for g in own if g.cause == LEFT_FOR_GOOD
                                and g.start is not None and g.start > last])
    own = [g for g in own if g.cause != LEFT_FOR_GOOD]
    n = len(res.times)
    places = {id(g): _placements(res, g) if header else None for g in own}
    trailing = [g for g in own if (g.end is None or g.end >= last) if places[id(g)] is None
                ] + [g for g in own if (ps := places[id(g)]) is not None
                     and all(p.last == n - 1 for p in ps)]
    starts = [g.start for g in trailing]
    if not starts:
        return set()
    end = -(2**63) if any(s is None for s in starts) else min(starts)
    keep = int(np.searchsorted(res.times, end, side="left"))
    cuts = [min(p.first for p in ps) for g in trailing if (ps := places[id(g)]) is not None]
    if cuts:  # (placed: the tick time where the cut begins)
        keep = min(cuts) if len(cuts) == len(trailing) else min(keep, *cuts)
        end = int(res.times[keep]) if keep < n else end
    res.intact_end = end if res.intact_end is None else min(end, res.intact_end)
    causes = sorted({g.cause or "gap" for g in trailing})
    where = (f"log time {end} ns" if not cuts else
             f"log time {min(starts) if None not in starts else end} ns (placed at tick "
             f"time {end} ns by the messages held)")
    res.lost = "; ".join(x for x in (res.lost, res.lost_words or (
        f"a gap ({', '.join(causes)}) from {where} to past its last tick")) if x)
    if keep < len(res.times):
        res.cut += len(res.times) - keep
        res.times = res.times[:keep]
        res.columns = {k: v[:keep] for k, v in res.columns.items()}
        res.log_times = {k: v[:keep] for k, v in res.log_times.items()}
    return {id(g) for g in trailing if places[id(g)] is not None}


def _insert_first(res: ClockPass, at: int) -> None:
    """One tick at time ``at`` before the first, standing for the unknown start of the run
    (its placeholder values are the first tick's; every variable unknown there)."""
    res.times = np.concatenate(([at], res.times)).astype(np.int64)
    res.columns = {k: np.concatenate((c[:1], c)) for k, c in res.columns.items()}
    res.log_times = {k: np.concatenate(([-1], c)).astype(c.dtype)
                     for k, c in res.log_times.items()}
    res.unknown = {k: np.concatenate(([True], m)) for k, m in res.unknown.items()}
    res.tick_gaps = [0] + [i + 1 for i in res.tick_gaps]


def lost_in_words(source: LogSource, topics: Iterable[str]) -> str:
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
