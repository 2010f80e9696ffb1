"""Counts of ticks in a window (docs/bindings.md, "Windows over time"):
``count_ticks(COND, 1min)`` at a tick ``t`` is the number of ticks of the requirement's clock
in ``(t - span, t]`` at which COND held. COND reads any variables and topics; the sampling
evaluates it at every tick as the binding's value (sample and hold), and
:func:`with_tick_windows` turns those values into the counts as the ticks leave the sampling,
the same way for the audit's blocks of ticks and the watch's ticks.

* **Unknown.** A tick in the window whose COND is NaN (unread: a NaN operand, an unknown
  value) makes the count NaN (unknown) for as long as the tick is in the window: never a
  silent 0.
* **Warm-up.** The count is complete at ``t`` once its window starts at or after the
  clock's first evaluated tick (``t - span >= first``); the ticks before are warm-up of the
  clock that reads it (only the requirements whose variables read the count: each
  requirement has its clock), counted in its ``warmup_ticks`` and not judged.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Iterator
from typing import Any

import numpy as np

from fretc.signals.bindings.windowing import WindowSpec
from fretc.signals.windows import SlidingWindow

__all__ = ["TickCount", "TickWindows", "with_tick_windows", "one_clock"]


class TickCount:
    """The window of one ``count_ticks`` binding on one clock: a ``count`` window
    (:class:`fretc.signals.windows.SlidingWindow`) over the clock's ticks instead of a
    topic's messages. :meth:`push` each tick's COND value in time order; it returns the
    count at that tick (float; NaN unknown), or None while the window is incomplete
    (warm-up).

    Args:
        spec: the binding's ``tick_window`` (its span, ns).
    """

    def __init__(self, spec: WindowSpec) -> None:
        self.window = SlidingWindow(dataclasses.replace(spec, func="count"))

    def push(self, t: int, v: Any) -> float | None:
        """Add tick ``t`` (ns) whose COND is ``v`` (bool; a float: NaN unknown, else held
        when non-zero); the count at ``t`` or None (warm-up)."""
        w = self.window
        w.push(t, v if v != v else float(bool(v)))
        return w.value(t) if w.complete(t) else None


class TickWindows:
    """The ``count_ticks`` windows of several clocks: :meth:`apply` turns each tick (or
    block of ticks) of a clock into its counts (module docstring).

    Args:
        samplings: key -> the clock's :class:`~fretc.signals.clock.Sampling` (its
            ``warmup_ticks``, ``ticks`` and ``first_time`` count the window's warm-up).
        names: key -> the clock's bindings (those with a ``tick_window`` are counted).
    """

    def __init__(self, samplings: dict[Any, Any], names: dict[Any, list]) -> None:
        self.samplings = samplings
        self.counts = {key: {b.name: TickCount(b.tick_window) for b in bs
                             if getattr(b, "tick_window", None) is not None}
                       for key, bs in names.items()}
        self.dropped = {key: 0 for key in names}

    def __bool__(self) -> bool:
        return any(self.counts.values())

    def apply(self, key: Any, item: Any) -> Any:
        """``item`` (a Tick or a TickBlock of clock ``key``) with its counts, renumbered
        after the window's warm-up; None when all of it is warm-up."""
        tc = self.counts.get(key)
        if not tc:
            return item
        out = _block(item, tc) if hasattr(item, "start") else _tick(item, tc)
        s = self.samplings[key]
        if out is None:
            _warm(s, 1 if not hasattr(item, "start") else len(item.times))
            self.dropped[key] += 1 if not hasattr(item, "start") else len(item.times)
            return None
        out, warm = out
        if warm:
            _warm(s, warm)
            self.dropped[key] += warm
        if self.dropped[key]:
            out = _renumbered(out, self.dropped[key])
            if s.first_time is None:
                s.first_time = int(out.times[0]) if hasattr(out, "start") else out.time
        return out


def with_tick_windows(pairs: Iterator[tuple[Any, Any]], samplings: dict[Any, Any],
                      names: dict[Any, list]) -> Iterator[tuple[Any, Any]]:
    """``pairs`` of a group sampling (``(key, Tick)`` or ``(key, TickBlock)``) with the
    ``count_ticks`` bindings' values turned into their counts (:class:`TickWindows`): ticks
    of a warm-up are left out and counted in ``samplings[key]``, the ticks after
    renumbered. ``pairs`` itself when no clock counts ticks (nothing added per tick)."""
    tw = TickWindows(samplings, names)
    return _counted(pairs, tw) if tw else pairs


def _counted(pairs: Iterator[tuple[Any, Any]], tw: TickWindows) -> Iterator[tuple[Any, Any]]:
    for key, item in pairs:
        out = tw.apply(key, item)
        if out is not None:
            yield key, out


def one_clock(ticks: Iterator[Any], s: Any) -> Iterator[Any]:
    """The ticks of one clock (a :class:`~fretc.signals.clock.Sampling` ``s`` of them) with
    its ``count_ticks`` bindings counted, as :func:`with_tick_windows`; ``ticks`` itself
    when none of its bindings counts ticks."""
    if s.bindings is None or all(getattr(b, "tick_window", None) is None
                                 for b in s.bindings.variables.values()):
        return ticks
    pairs = with_tick_windows(((None, t) for t in ticks), {None: s},
                              {None: list(s.bindings.variables.values())})
    return (t for _k, t in pairs)


def _warm(s: Any, n: int) -> None:
    s.warmup_ticks += n
    s.ticks -= n
    s.first_time = None  # set again by the first tick kept


def _tick(tick: Any, tc: dict[str, TickCount]) -> tuple[Any, int] | None:
    values = dict(tick.values)
    warm = False
    for name, w in tc.items():
        if name in values:
            c = w.push(tick.time, values[name])
            warm = warm or c is None
            values[name] = c
    if warm:
        return None
    tick = copy.copy(tick)  # a CSV trace's tick is shared by the clocks
    tick.values = values
    return tick, 0


def _block(blk: Any, tc: dict[str, TickCount]) -> tuple[Any, int] | None:
    times = blk.times.tolist()
    counted: dict[str, list] = {}
    for name, w in tc.items():
        if name in blk.values:
            counted[name] = [w.push(t, v) for t, v in zip(times, blk.values[name].tolist())]
    warm = max((sum(1 for c in got if c is None) for got in counted.values()), default=0)
    if warm == len(times):
        return None
    values = {k: (np.array(counted[k][warm:], dtype=np.float64) if k in counted else v[warm:])
              for k, v in blk.values.items()}
    return blk._replace(times=blk.times[warm:], values=values,
                        log_times={k: v[warm:] for k, v in blk.log_times.items()}), warm


def _renumbered(item: Any, dropped: int) -> Any:
    if hasattr(item, "start"):
        return item._replace(start=item.start - dropped)
    item.index -= dropped  # a copy (_tick)
    return item
