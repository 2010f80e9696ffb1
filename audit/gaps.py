"""Gaps in a log and the ticks they leave unknown (../shared/DESIGN.md, "Damage is a gap:
never evidence, never the end").

Design notes: ARCHITECTURE.md, `audit/gaps.py`."""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from fretc.common.streams import base_topic, log_topics
from fretc.logs.base import Gap
from fretc.logs.recorded_gaps import SILENT_CAUSES
from fretc.signals.bindings import Bindings
from fretc.signals.bindings.expression import age_only_topics, stateful_topics

if TYPE_CHECKING:
    from fretc.audit.columns import ClockPass
    from fretc.logs.base import LogSource

__all__ = ["split_bridged", "inner_gaps", "unknown_masks", "gap_json", "gaps_of_clock",
           "insert_gap_ticks", "merged_gaps", "Placed", "placed"]

_NEG, _POS = -(2**63), 2**63 - 1


def inner_gaps(source: LogSource) -> list[Gap]:
    """The gaps of ``source``'s latest pass that the log was read on after (every gap with
    an end, and its messages present but not decoded, one gap each:
    :meth:`fretc.logs.base.LogSource.lost_gaps`), in log-time order. A gap without an end is
    the cut at the end of the log (``source.cut_start``), judged as today's damage."""
    gaps = [g for g in getattr(source, "gaps", ()) if g.end is not None]
    lost = getattr(source, "lost_gaps", None)
    if lost is not None:
        gaps += lost()
    return sorted(gaps, key=lambda g: (_NEG if g.start is None else g.start, g.end, g.cause))


def split_bridged(gaps: Iterable[Gap], bridge_ns: int | None) -> tuple[list[Gap], list[Gap]]:
    """``(kept, bridged)``: the gaps shorter than ``bridge_ns`` (``--bridge-gaps``; known
    start and end, ``end - start < bridge_ns``) are bridged (values held over them, as
    sample-and-hold holds a value between messages); None bridges none."""
    kept: list[Gap] = []
    bridged: list[Gap] = []
    for g in gaps:
        short = (bridge_ns is not None and g.start is not None and g.end is not None
                 and g.end - g.start < bridge_ns)
        (bridged if short else kept).append(g)
    return kept, bridged


def gaps_of_clock(gaps: Iterable[Gap], topics: Iterable[str]) -> list[Gap]:
    """The gaps that may have held messages of any of ``topics`` (a stream's: of its
    topic)."""
    ts = sorted(log_topics(topics))
    return [g for g in gaps if any(g.affects(t) for t in ts)]


class Placed(NamedTuple):
    """Where a gap of one topic lies among a clock's ticks under a header time base, found
    from the log times of the messages the ticks hold (a topic's stamps taken to rise with
    its log times, as a publisher stamps what it sends in order; KP-176).

    Attributes:
        first: index of the first tick that may hold a lost message: the first holding the
            last message logged before the gap (0 where none is held).
        last: index of the last tick holding no message logged after the gap (-1: none;
            ``n - 1``: the gap reaches past the last tick).
        before: whether a tick holds a message logged before the gap (False: lost messages
            may precede the first tick).
    """

    first: int
    last: int
    before: bool


def placed(held: np.ndarray, g: Gap) -> Placed:
    """A gap placed among the ticks by ``held`` (int64, the log time in ns of the message
    of the gap's topic each tick holds, -1 none; :class:`Placed`)."""
    end = _POS if g.end is None else g.end
    pre = held[held < g.start] if g.start is not None else held[:0]
    h0 = int(pre.max()) if len(pre) else None
    first = int(np.argmax(held >= h0)) if h0 is not None else 0
    late = np.flatnonzero(held <= end)
    return Placed(first, int(late[-1]) if len(late) else -1, h0 is not None and h0 >= 0)


def _topic_mask(times: np.ndarray, held: np.ndarray, gaps: list[Gap], lag: int,
                stateful: bool, folded: bool, span: int | None = None,
                header: bool = False) -> np.ndarray:
    """Unknown ticks of one topic (module docstring); ``held`` the log time of the message
    each tick holds (-1: none); ``span`` a window's duration (ns; 0 a count of messages).
    ``header``: the ticks are header stamps, placed against a gap's log times by the
    messages they hold (:func:`placed`), as well as by ``lag``."""
    n = len(times)
    out = np.zeros(n, np.bool_)
    prev = np.concatenate(([_NEG], times[:-1])) if n else times
    for g in gaps:
        start = _NEG if g.start is None else g.start - lag
        end = _POS if g.end is None else g.end
        after = times >= start
        if header:  # (KP-176: stamps far from their log times)
            at = placed(held, g)
            after = after | (np.arange(n) >= at.first)
        stale = after & (held <= end)
        out |= stale
        if stateful:  # the first message after the gap has a lost previous one
            fresh = np.flatnonzero(after & (held > end))
            if len(fresh):
                out |= held == held[fresh[0]]
        if folded:  # the span since the previous tick meets the gap
            out |= (times >= start) & (prev < end)
            if header:
                out |= after & (np.arange(n) <= at.last + 1)
        if span is not None:  # the window (t - span, t] meets the gap
            out |= (times >= start) & ((times - span < end) if span else True)
            if header:
                nxt = np.append(times, _POS)[at.last + 1]  # (the first tick after the gap)
                out |= after & ((times - span < nxt) if span else True)
    return out


def unknown_masks(times: np.ndarray, log_times: dict[str, np.ndarray], names: Iterable[str],
                  bindings: Bindings | None, gaps: list[Gap], header_lag_ns: int = 0,
                  header: bool = False) -> dict[str, np.ndarray]:
    """Variable -> bool array over ``times`` (the clock's ticks), True where the variable is
    unknown because of ``gaps`` (module docstring); only variables with an unknown tick.

    Args:
        times: the clock's tick times (ns, time base).
        log_times: topic -> log time (ns) of the message held at each tick (-1: none).
        names: the clock's variables.
        bindings: their bindings (None: a CSV trace read as its columns, topic ``/csv``).
        gaps: the log's gaps (:func:`inner_gaps`, bridged ones removed).
        header_lag_ns: under the header time base, how much earlier than its log time a
            message's stamp may be.
        header: the ticks are header stamps (:func:`placed` places a gap among them too).
    """
    if not gaps or not len(times):
        return {}
    masks: dict[tuple, np.ndarray] = {}
    out: dict[str, np.ndarray] = {}
    for name in names:
        b = bindings.variables.get(name) if bindings is not None else None
        topics = sorted(b.topics) if b is not None else sorted(log_times)
        stateful = stateful_topics(b.ast) if b is not None else set()
        aged = age_only_topics(b.ast) if b is not None else set()
        folded = b is not None and b.aggregate is not None
        w = b.window if b is not None else None
        span = None if w is None else (w.span_ns or 0)
        mask = np.zeros(len(times), np.bool_)
        for t in topics:
            # a stream: its topic's gaps; a silence leaves what age() reads known
            own = [g for g in gaps if g.affects(base_topic(t))
                   and not (t in aged and g.cause in SILENT_CAUSES)]
            held = log_times.get(t)
            if not own or held is None:
                continue
            key = (t, t in stateful, folded, span, t in aged)
            if key not in masks:
                masks[key] = _topic_mask(times, held, own, header_lag_ns, key[1], folded, span,
                                         header)
            mask |= masks[key]
        tw = getattr(b, "tick_window", None)
        if tw is not None and mask.any():  # count_ticks: unknown while such a tick is counted
            last = np.maximum.accumulate(np.where(mask, times, np.iinfo(np.int64).min))
            mask = last > times - tw.span_ns
        if mask.any():
            out[name] = mask
    return out


def insert_gap_ticks(res: ClockPass, gaps: list[Gap], tick_topic: str,
                     header: bool = False) -> list[int]:
    """On a clock that ticks on each message of ``tick_topic``, the ticks a gap of that topic
    lost are not known (not even how many): one tick is put in their place, at the gap's
    start, unknown for every variable (:func:`fretc.audit.passes.mark_gaps` marks it), so
    that nothing joins the ticks on both sides of the gap. Only gaps between two ticks of the
    clock get one. ``res`` (a :class:`fretc.audit.columns.ClockPass`) is changed in place:
    its times, columns and held log times (the tick before's values, which no verdict reads).
    ``header``: the ticks are header stamps, and a gap goes after the last tick whose own
    message was logged before it (:func:`placed`, on the tick topic's held log times).

    Returns:
        The indexes of the inserted ticks, ascending.
    """
    times = res.times
    if len(times) < 2:
        return []
    own = res.log_times.get(tick_topic)
    if header and own is not None:
        places = set()
        for g in gaps:
            if g.affects(tick_topic) and g.end is not None:
                p = placed(own, g)
                if p.before and p.last + 1 < len(times):
                    places.add((p.last + 1, min(int(times[p.last]) + 1, int(times[p.last + 1]))))
        pos = np.array(sorted(p for p, _ in places), np.int64)
        at = [t for _, t in sorted(places)]
    else:
        at = sorted({int(g.start) for g in gaps if g.affects(tick_topic) and g.start is not None
                     and g.end is not None and times[0] < g.start <= times[-1]})
        pos = np.searchsorted(times, np.array(at, np.int64), side="left")
    if not at:
        return []
    src = pos - 1  # the tick before each inserted one gives its placeholder values
    res.times = np.insert(times, pos, np.array(at, np.int64))
    res.columns = {k: np.insert(c, pos, c[src]) for k, c in res.columns.items()}
    res.log_times = {k: np.insert(c, pos, c[src]) for k, c in res.log_times.items()}
    return (pos + np.arange(len(pos))).tolist()


def gap_json(g: Gap, bridged: bool = False) -> dict:
    """A gap as the audit JSON gives it: ``start_ns``, ``end_ns`` (inclusive; None: unknown),
    ``topics`` (None: any topic), ``cause`` (the data problem kind), ``bridged``."""
    return {"start_ns": g.start, "end_ns": g.end,
            "topics": sorted(g.topics) if g.topics is not None else None,
            "cause": g.cause, "bridged": bridged}


def merged_gaps(gaps: list[Gap], bridged: list[Gap]) -> list[dict]:
    """The log's gaps as the audit JSON lists them (:func:`gap_json`), in log-time order,
    the point gaps of messages not decoded merged per topic and cause into one entry from
    the first to the last (``messages``: how many; a log of 712 undecodable messages lists
    one entry, not 712). The spans merged are a listing only: each message was its own gap."""
    out: list[dict] = []
    runs: dict[tuple, dict] = {}
    for g, is_bridged in sorted([(g, False) for g in gaps] + [(g, True) for g in bridged],
                                key=lambda x: (_NEG if x[0].start is None else x[0].start,
                                               _POS if x[0].end is None else x[0].end)):
        point = g.start is not None and g.start == g.end and g.topics is not None
        key = (g.cause, g.topics, is_bridged)
        if point and key in runs:
            run = runs[key]
            run["end_ns"] = g.end
            run["messages"] += 1
            continue
        entry = dict(gap_json(g, is_bridged), messages=1 if point else None)
        out.append(entry)
        if point:
            runs[key] = entry
    return out
