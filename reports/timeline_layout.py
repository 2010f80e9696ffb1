"""The layout of a violation's timeline (:mod:`fretc.reports.timeline` draws it): from one verdict
of the audit JSON and its log object, the marks (trigger, violation, LTL3 verdict), the
scope interval, response window and damage, the lanes, the detail windows of sampled ticks
and the broken time axis that maps log time (ns) to pixels. No drawing here.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from fretc.common.units import format_offset

__all__ = ["Threshold", "Segment", "Axis", "Timeline", "plan_timeline", "nice_step_ns",
           "step_decimals", "lane_label", "cells", "cells_by_segment"]

WIDTH = 980
LABEL_MIN_W = 120      # lane labels on the left: as wide as the longest label needs
LABEL_MAX_W = 300
MONO_CHAR_W = 6.7      # width of a character of the 11 px monospace lane labels
RIGHT_PAD = 24
PLOT_X1 = WIDTH - RIGHT_PAD
BREAK_W = 34           # width of an axis break between two detail windows
MIN_SEG_W = 150        # narrowest detail window
BOOL_H = 26
NUM_H = 64
TOPIC_H = 20
LANE_GAP = 8


@dataclass(frozen=True)
class Threshold:
    """A comparison of a numeric variable with a constant in the requirement (``clearance >
    0``): drawn as a dashed line in that variable's lane. ``op`` is FRET's comparison
    operator, ``value`` the constant."""

    variable: str
    op: str
    value: float


@dataclass
class Segment:
    """One detail window: ticks ``t0..t1`` (inclusive), times ``a..b`` ns (b = end of the
    last tick's cell), pixels ``p..q``."""

    t0: int
    t1: int
    a: int
    b: int
    p: float = 0.0
    q: float = 0.0


def nice_step_ns(span_ns: float, px: float, min_px: float = 72.0) -> int:
    """The smallest 1-2-5 step (ns) that keeps tick labels at least ``min_px`` apart."""
    if span_ns <= 0 or px <= 0:
        return 10**9
    per_px = span_ns / px
    for exp in range(3, 13):          # 1 us .. 1000 s
        for m in (1, 2, 5):
            step = m * 10**exp
            if step / per_px >= min_px:
                return step
    return 10**12


def step_decimals(step_ns: int) -> int:
    """The decimals of seconds a tick label needs at this step (0..6)."""
    return max(0, min(6, -int(math.floor(math.log10(step_ns / 1e9) + 1e-9))))


def _tick_times(values: dict[str, list], sources: dict[str, list]) -> dict[int, int]:
    """tick -> time_ns over every sampled row."""
    out: dict[int, int] = {}
    for rows in list(values.values()) + list(sources.values()):
        for r in rows:
            if isinstance(r, dict) and r.get("tick") is not None and r.get("time_ns") is not None:
                out[int(r["tick"])] = int(r["time_ns"])
    return out


def _period_ns(ticks: dict[int, int], period_ns: int | None) -> int:
    if period_ns:
        return int(period_ns)
    ks = sorted(ticks)
    diffs = sorted(ticks[b] - ticks[a] for a, b in zip(ks, ks[1:]) if b == a + 1)
    if diffs:
        return max(1, diffs[len(diffs) // 2])
    return 10**8


def _segments(ticks: dict[int, int], period: int) -> list[Segment]:
    ks = sorted(ticks)
    segs: list[Segment] = []
    for k in ks:
        if segs and k == segs[-1].t1 + 1:
            segs[-1].t1 = k
        else:
            segs.append(Segment(k, k, ticks[k], 0))
    for s in segs:
        s.b = ticks[s.t1] + period
    return segs


def _layout(segs: list[Segment], x0: float) -> None:
    """Give each detail window its pixels: widths proportional to duration, none narrower
    than MIN_SEG_W, BREAK_W between windows."""
    n = len(segs)
    avail = (PLOT_X1 - x0) - BREAK_W * (n - 1)
    durs = [max(1, s.b - s.a) for s in segs]
    widths = [avail * d / sum(durs) for d in durs]
    small = [i for i, w in enumerate(widths) if w < MIN_SEG_W]
    if small and len(small) < n:
        rest = avail - MIN_SEG_W * len(small)
        big = [i for i in range(n) if i not in small]
        tot = sum(durs[i] for i in big)
        widths = [MIN_SEG_W if i in small else rest * durs[i] / tot for i in range(n)]
    elif small:
        widths = [avail / n] * n
    x = x0
    for s, w in zip(segs, widths):
        s.p, s.q = x, x + w
        x += w + BREAK_W


class Axis:
    """Log time (ns) -> x over the broken detail axis. ``clip`` tells whether a time fell
    outside every window (before the first, after the last: clamped to the edge; in a break:
    placed proportionally inside the break)."""

    def __init__(self, segs: list[Segment], x0: float):
        self.segs = segs
        self.x0 = x0

    def x(self, ns: int) -> tuple[float, str]:
        """The plot x of log time ``ns`` and where it falls: in a segment of the (broken) axis,
        ``before`` its first or after its last."""
        segs = self.segs
        if ns < segs[0].a:
            return segs[0].p, "before"
        for i, s in enumerate(segs):
            if s.a <= ns <= s.b:
                return s.p + (s.q - s.p) * (ns - s.a) / max(1, s.b - s.a), ""
            if i + 1 < len(segs) and s.b < ns < segs[i + 1].a:
                nxt = segs[i + 1]
                return s.q + (nxt.p - s.q) * (ns - s.b) / max(1, nxt.a - s.b), "break"
        return segs[-1].q, "after"


def lane_label(kind: str, name: str) -> str:
    """The label of a lane: the variable, or ``topic msgs``."""
    return f"{name} msgs" if kind == "topic" else name


def cells(rows: list[dict], ticks: dict[int, int], period: int) -> list[tuple[int, int, Any]]:
    """(start_ns, end_ns, value) of each sampled tick: a tick's cell ends at the next tick's
    time, or one period later when the next tick was not sampled."""
    out = []
    for r in rows:
        k, ns = int(r["tick"]), int(r["time_ns"])
        nxt = ticks.get(k + 1)
        out.append((ns, nxt if nxt is not None else ns + period, r.get("value")))
    return out


def cells_by_segment(segs: list[Segment], cs: list[tuple[int, int, Any]]
                     ) -> Iterator[tuple[Segment, list[tuple[int, int, Any]]]]:
    """Cells grouped by detail window, in time order."""
    for s in segs:
        yield s, [c for c in cs if s.a <= c[0] < s.b]


@dataclass
class Timeline:
    """The layout of one violation's timeline, all times in log time (ns).

    Attributes:
        start, end: the log's first tick and the end of the picture's time (its last tick,
            or the violation); ``log_end`` = ``end`` + one ``period`` (the last cell).
        viol_ns: where the violation is drawn (:func:`violation_time_ns`).
        ticks: tick -> time of every sampled tick; ``segs`` the detail windows over them.
        marks: (kind: trigger | violation | ltl3, ns, label).
        scope_ab, win_ab: the scope interval and the response window as ``(a, b)`` ns (None
            when absent); ``win_past_end`` the window reaches past the end of the log.
        window: the first violation's ``window`` object.
        damage: log time of the damage of a partial log, or None.
        lanes: (kind: bool | num | topic, name, rows) in drawing order; ``thresholds`` per
            variable.
        x0, axis: where the plot starts (after the lane labels) and the detail axis.
    """

    start: int
    end: int
    log_end: int
    period: int
    viol_ns: int
    ticks: dict[int, int]
    segs: list[Segment]
    marks: list[tuple[str, int, str]]
    scope_ab: tuple[int, int] | None
    win_ab: tuple[int, int] | None
    win_past_end: bool
    window: dict | None
    damage: int | None
    lanes: list[tuple[str, str, Any]]
    thresholds: dict[str, list[Threshold]]
    x0: float
    axis: Axis


def violation_time_ns(fv: dict) -> int:
    """Where a first violation is drawn: its tick's time (``tick_time_ns``, on the bindings'
    time base), the one time the terminal, the JSON's ``tick_time_s`` and the report give
    the event; the trigger and the LTL3 mark are tick times too, so the marks keep the
    ticks' order (the log time of the message that decided the tick, earlier than the tick
    on a fixed period, is the report's "in Foxglove" seek time, not this). Logs audited
    before ``tick_time_ns`` existed: the log time."""
    if fv.get("tick_time_ns") is not None:
        return int(fv["tick_time_ns"])
    return int(fv["log_time_ns"])


def _marks(fv: dict, ltl3: dict, start: int) -> list[tuple[str, int, str]]:
    """The vertical marks: trigger, violation, LTL3 verdict time (when definitive)."""
    marks: list[tuple[str, int, str]] = []   # (kind, ns, label)
    trig = fv.get("trigger")
    viol_ns = violation_time_ns(fv)
    ltl3_ns = ltl3.get("time_ns") if ltl3.get("status") in ("violated", "satisfied") else None
    if trig:
        trig_ns = int(trig["time_ns"])
        marks.append(("trigger", trig_ns,
                      f"trigger {format_offset(trig_ns, start)} (#{trig['tick']})"))
    marks.append(("violation", viol_ns,
                  f"violation {format_offset(viol_ns, start)} (#{fv['tick']})"))
    if ltl3_ns is not None:
        ltl3_ns = int(ltl3_ns)
        marks.append(("ltl3", ltl3_ns, f"LTL3 {ltl3['status']} {format_offset(ltl3_ns, start)} "
                                       f"(#{ltl3['tick']})"))
    return marks


def _lanes(values: dict[str, list], sources: dict[str, list]) -> list[tuple[str, str, Any]]:
    """One lane per sampled variable (audit order: the monitor's VARIABLES; ``bool`` when
    every value is a boolean, else ``num``), then one per topic (sorted)."""
    lanes: list[tuple[str, str, Any]] = []   # (kind, name, rows)
    for name in values:
        rows = [r for r in values[name] if isinstance(r, dict)]
        kind = "bool" if rows and all(isinstance(r.get("value"), bool) for r in rows) else "num"
        lanes.append((kind, name, rows))
    for topic in sorted(sources):
        lanes.append(("topic", topic, [r for r in sources[topic] if isinstance(r, dict)]))
    return lanes


def plan_timeline(verdict: dict, log: dict, period_ns: int | None,
                  thresholds: Sequence[Threshold]) -> Timeline:
    """The :class:`Timeline` of a violated verdict (arguments as
    :func:`fretc.reports.timeline.timeline_svg`).

    Raises:
        ValueError: the verdict has no ``first_violation`` or the log no ``start_time_ns``.
    """
    fv = verdict.get("first_violation")
    if not fv:
        raise ValueError(f"{verdict.get('requirement')}: not violated, no timeline")
    start = log.get("start_time_ns")
    if start is None:
        raise ValueError(f"{log.get('log')}: no start time")
    start = int(start)
    end = int(log.get("end_time_ns") or fv["log_time_ns"])
    values: dict[str, list] = verdict.get("values") or {}
    sources: dict[str, list] = verdict.get("sources") or {}
    ticks = _tick_times(values, sources)
    period = _period_ns(ticks, period_ns)
    if not ticks:  # no sampled values: one window around the violation
        ticks = {int(fv["tick"]): violation_time_ns(fv)}
    segs = _segments(ticks, period)
    log_end = end + period
    scope = fv.get("scope_interval")
    window = fv.get("window")
    scope_ab = None
    if scope:
        scope_ab = (int(scope["start"]["time_ns"]), int(scope["end"]["time_ns"]) + period)
    win_ab = None
    win_past_end = False
    if window and window.get("start_time_ns") is not None:
        hi = window.get("end_time_ns")
        win_past_end = hi is None or int(hi) > end
        hi_ns = (int(hi) if hi is not None else end) + period
        win_ab = (int(window["start_time_ns"]), min(hi_ns, log_end))
    th_by_var: dict[str, list[Threshold]] = {}
    for t in thresholds:
        th_by_var.setdefault(t.variable, []).append(t)
    lanes = _lanes(values, sources)
    longest = max([len(lane_label(k, n)) for k, n, _ in lanes] + [10])
    x0 = min(LABEL_MAX_W, max(LABEL_MIN_W, MONO_CHAR_W * longest + 26))
    _layout(segs, x0)
    damage = log.get("damage_time_ns")
    return Timeline(start=start, end=end, log_end=log_end, period=period,
                    viol_ns=violation_time_ns(fv), ticks=ticks, segs=segs,
                    marks=_marks(fv, verdict.get("ltl3") or {}, start), scope_ab=scope_ab,
                    win_ab=win_ab, win_past_end=win_past_end, window=window,
                    damage=int(damage) if damage is not None else None, lanes=lanes,
                    thresholds=th_by_var, x0=x0, axis=Axis(segs, x0))
