"""Sliding windows over the messages of one topic (docs/bindings.md, "Windows over time"):
the value at a tick of ``mean(/battery.current, 2s)`` and the other window functions of
:data:`fretc.signals.bindings.windowing.WINDOW_FUNCS`, computed incrementally as the
messages arrive in time order.

Design notes: ARCHITECTURE.md, `signals/windows.py`."""

from __future__ import annotations

import math
from collections import deque
from typing import Any

from sortedcontainers import SortedList

from fretc.common.problems import SignalError
from fretc.signals.bindings.windowing import WindowSpec

__all__ = ["SlidingWindow", "PendingCalls", "OpenGoals", "message_value", "sliding_windows",
           "push_message",
           "windows_complete", "window_block", "MAX_PENDING_CALLS"]

#: Calls of one service waiting for their response that ``waiting()`` keeps (memory bound).
MAX_PENDING_CALLS = 100_000


class SlidingWindow:
    """The window of one binding: :meth:`push` each message's value in time order, then
    :meth:`value` at a tick (at or after the last pushed message's time).

    Args:
        spec: the window (function, span in ns or count of messages, percentile).
    """

    def __init__(self, spec: WindowSpec) -> None:
        self.spec = spec
        self.items: deque[tuple[int, float]] = deque()  # (time ns, value) in the window
        self.seen = 0  # messages pushed since the start
        self.first: int | None = None  # time of the first message pushed
        self.error: Exception | None = None  # an evaluation error, raised at the next tick
        self.nans = 0
        self.total = 0.0  # Neumaier's compensated running sum: total + comp
        self.comp = 0.0
        self.mean = 0.0  # Welford: mean and sum of squared deviations of the window
        self.m2 = 0.0
        self.lo: deque[tuple[int, float]] = deque()  # (sequence, value), values increasing
        self.hi: deque[tuple[int, float]] = deque()  # (sequence, value), values decreasing
        self.ordered = SortedList() if spec.func in ("median", "percentile") else None

    def push(self, t: int, v: Any) -> None:
        """Add the value ``v`` (bool, float; NaN unread; an exception: the message failed to
        evaluate, raised by :meth:`value`) of a message at time ``t`` (ns)."""
        if isinstance(v, Exception):  # the binding fails at the next tick (warm-up counts it)
            self.error = v
            self.first = t if self.first is None else self.first
            self.seen += 1
            return
        x = float(v)
        if self.first is None:
            self.first = t
        seq = self.seen
        self.seen += 1
        self.items.append((t, x))
        if x != x:
            self.nans += 1
            return
        self._add_sum(x)
        kind = self.spec.func
        if kind == "variance":
            n = len(self.items) - self.nans
            d = x - self.mean
            self.mean += d / n
            self.m2 += d * (x - self.mean)
        elif kind == "min":
            while self.lo and self.lo[-1][1] >= x:
                self.lo.pop()
            self.lo.append((seq, x))
        elif kind == "max":
            while self.hi and self.hi[-1][1] <= x:
                self.hi.pop()
            self.hi.append((seq, x))
        elif kind in ("median", "percentile"):
            self.ordered.add(x)  # type: ignore[union-attr]

    def _add_sum(self, x: float) -> None:
        s = self.total + x
        if abs(self.total) >= abs(x):
            self.comp += (self.total - s) + x
        else:
            self.comp += (x - s) + self.total
        self.total = s

    def _evict(self, t: int) -> None:
        """Drop the messages that left the window at tick ``t``."""
        spec, items = self.spec, self.items
        while items and (items[0][0] <= t - spec.span_ns if spec.span_ns is not None
                         else len(items) > spec.count):  # type: ignore[operator]
            _, x = items.popleft()
            oldest = self.seen - len(items) - 1  # the sequence number of the dropped one
            if x != x:
                self.nans -= 1
                continue
            self._add_sum(-x)
            kind = spec.func
            if kind == "variance":
                n = len(items) - self.nans
                if n == 0:
                    self.mean = self.m2 = 0.0
                else:
                    d = x - self.mean
                    self.mean -= d / n
                    self.m2 -= d * (x - self.mean)
            elif kind == "min" and self.lo and self.lo[0][0] == oldest:
                self.lo.popleft()
            elif kind == "max" and self.hi and self.hi[0][0] == oldest:
                self.hi.popleft()
            elif kind in ("median", "percentile"):
                self.ordered.remove(x)  # type: ignore[union-attr]
        if len(items) == self.nans:  # empty of numbers: restart the sums exactly
            self.total = self.comp = self.mean = self.m2 = 0.0

    def complete(self, t: int) -> bool:
        """Whether the window at tick ``t`` lies wholly after the topic's first message (a
        span) or holds ``count`` messages (module docstring)."""
        if self.spec.span_ns is not None:
            return self.first is not None and t - self.spec.span_ns >= self.first
        return self.seen >= self.spec.count  # type: ignore[operator]

    def value(self, t: int) -> float:
        """The window's value at tick ``t`` (module docstring for the rules).

        Raises:
            Exception: the evaluation error of a message pushed since the last tick.
        """
        if self.error is not None:
            err, self.error = self.error, None
            raise err
        self._evict(t)
        kind, n = self.spec.func, len(self.items)
        if self.nans:
            return math.nan
        if kind in ("sum", "count"):
            return self.total + self.comp if n else 0.0
        if kind == "rate":
            return n / (self.spec.span_ns / 1e9)  # type: ignore[operator]
        if n == 0:
            return math.nan
        if kind == "mean":
            return (self.total + self.comp) / n
        if kind == "min":
            return self.lo[0][1]
        if kind == "max":
            return self.hi[0][1]
        if kind == "variance":
            return max(self.m2, 0.0) / (n - 1) if n > 1 else math.nan
        q = 0.5 if kind == "median" else self.spec.q / 100.0  # type: ignore[operator]
        pos = q * (n - 1)
        i = int(math.floor(pos))
        j = min(i + 1, n - 1)
        a, b = self.ordered[i], self.ordered[j]  # type: ignore[index]
        return a + (b - a) * (pos - i)


class PendingCalls:
    """``waiting(/arm)``: the calls of a service not answered yet, from its rosbag2 event
    topic (``/arm/_service_event``, ROS 2 Jazzy's service introspection). Each event message
    pushes ``(event_type, sequence_number, *client_gid)``; a request (REQUEST_SENT 0,
    REQUEST_RECEIVED 1) opens its call, keyed by its client's gid and sequence number (the
    ids ``service_msgs/msg/ServiceEventInfo`` gives), a response (RESPONSE_SENT 2,
    RESPONSE_RECEIVED 3) with the same key closes it. The value at a tick is the wait of the
    oldest open call in seconds (0 when none): ``waiting_arm <= 0.1`` is "every call to /arm
    is answered within 100 ms", its margin in seconds. Memory: the open calls, at most
    :data:`MAX_PENDING_CALLS` (past it, an error naming the topic).
    """

    def __init__(self, spec: WindowSpec) -> None:
        self.spec = spec
        # key (a tuple; a goal's id bytes for actions) -> time of its first request, oldest first
        self.open: dict[tuple | bytes, int] = {}
        self.error: Exception | None = None

    def push(self, t: int, v: Any) -> None:
        """Add the event ``v`` (a tuple as above, or an evaluation error) at time ``t``."""
        if isinstance(v, Exception):
            self.error = v
            return
        etype, key = v[0], (v[1],) + tuple(v[2:])
        if etype != etype or any(x != x for x in key):
            return  # an unread id: nothing to match (NaN)
        if etype <= 1:
            if key not in self.open:
                if len(self.open) >= MAX_PENDING_CALLS:
                    self.error = SignalError(
                        f"{self.spec.topic}: more than {MAX_PENDING_CALLS:,} calls wait for "
                        "their response (the limit of waiting())")
                    return
                self.open[key] = t
        else:
            self.open.pop(key, None)

    def complete(self, t: int) -> bool:
        """Always: no warm-up (a call before the log's start is not known to exist)."""
        return True

    def _evict(self, t: int) -> None:
        """Nothing leaves by time."""

    def value(self, t: int) -> float:
        """Seconds the oldest open call has waited at tick ``t`` (0 when none).

        Raises:
            Exception: an evaluation error of an event since the last tick, or the limit.
        """
        if self.error is not None:
            err, self.error = self.error, None
            raise err
        for since in self.open.values():
            return (t - since) / 1e9
        return 0.0


class OpenGoals(PendingCalls):
    """``goal_waiting(/navigate)``: the goals of an action not finished yet, from its status
    topic (``/navigate/_action/status``, action_msgs/msg/GoalStatusArray). Each message
    pushes ``(statuses, goal uuids)`` of its ``status_list``; a goal listed ACCEPTED 1,
    EXECUTING 2 or CANCELING 3 is open from the first message that lists it so, until one
    lists it SUCCEEDED 4, CANCELED 5 or ABORTED 6 (action_msgs/msg/GoalStatus); a finished
    goal never opens again. The value at a tick is the wait of the oldest open goal in
    seconds (0 when none): ``goal_waiting_nav <= 60`` is "every accepted goal ends with a
    result within 60 s". Memory: the open goals and the finished ones still listed, each at
    most :data:`MAX_PENDING_CALLS`.
    """

    def __init__(self, spec: WindowSpec) -> None:
        super().__init__(spec)
        self.done: dict[bytes, None] = {}

    def push(self, t: int, v: Any) -> None:
        """Add one status array ``v`` (statuses, uuids; or an evaluation error) at ``t``."""
        if isinstance(v, Exception):
            self.error = v
            return
        statuses = v[0].data if hasattr(v[0], "data") else v[0]
        for s, u in zip(list(statuses), list(v[1])):
            key = bytes(bytearray(int(x) for x in u))
            if key in self.done or s != s:
                continue
            if 1 <= s <= 3:
                if key not in self.open and len(self.open) >= MAX_PENDING_CALLS:
                    self.error = SignalError(f"{self.spec.topic}: more than "
                                             f"{MAX_PENDING_CALLS:,} goals are open (the "
                                             "limit of goal_waiting())")
                    return
                self.open.setdefault(key, t)
            elif s >= 4:
                self.open.pop(key, None)
                self.done[key] = None
                if len(self.done) > MAX_PENDING_CALLS:
                    del self.done[next(iter(self.done))]


_KINDS = {"waiting": PendingCalls, "goal_waiting": OpenGoals}


def sliding_windows(variables: list) -> dict[str, Any]:
    """A fresh :class:`SlidingWindow` (:class:`PendingCalls` for ``waiting``,
    :class:`OpenGoals` for ``goal_waiting``) per window binding among ``variables``
    (Bindings): variable name -> its window."""
    return {b.name: _KINDS.get(b.window.func, SlidingWindow)(b.window)
            for b in variables if getattr(b, "window", None) is not None}


def message_value(b: Any, evaluate: Any) -> Any:
    """What one message gives a window binding ``b``: ``evaluate(binding)`` of it, or of
    each of its parts (a tuple); ``goal_waiting`` takes its parts' arrays as read
    (``evaluate(part, raw=True)``: :meth:`~fretc.signals.bindings.binding.Binding.raw`)."""
    if b.window.func == "goal_waiting":
        return tuple(evaluate(p, raw=True) for p in b.parts)
    return tuple(evaluate(p) for p in b.parts) if b.parts else evaluate(b)


def push_message(windows: dict[str, SlidingWindow], variables: list, topic: str, t: int,
                 evaluate: Any) -> None:
    """Add the message of ``topic`` at time ``t`` (ns) to the windows of the bindings that
    read it; ``evaluate(binding, raw=False)`` gives its value on that message (``raw``: as
    read, arrays too; :func:`message_value`); an exception it raises is kept and raised at
    the next tick, as the folds between ticks do."""
    for b in variables:
        w = windows.get(b.name)
        if w is None or w.spec.topic != topic:
            continue
        try:
            w.push(t, message_value(b, evaluate))
        except Exception as exc:  # noqa: BLE001 - SignalError, kept for the tick
            w.push(t, exc)


def windows_complete(windows: dict[str, SlidingWindow], t: int) -> bool:
    """Whether every window is complete at tick ``t`` (else the tick is warm-up)."""
    return all(w.complete(t) for w in windows.values())


def window_block(windows: dict[str, SlidingWindow], fed: dict[str, int], variables: list,
                 times: Any, held: dict[str, Any], values_of: Any, warm_before: int = 0
                 ) -> tuple[int, dict]:
    """The windows of one clock over a block of ticks (the block sampler,
    :mod:`fretc.signals.blocks`; the same values as :class:`fretc.signals.clock.Clock` pushing
    message by message).

    Args:
        windows: name -> window (:func:`sliding_windows`), advanced in place.
        fed: topic -> number of the last message pushed (counted from the topic's first
            message; -1 none), advanced in place.
        variables: the clock's bindings.
        times: the block's tick times (ns, int64 array).
        held: topic -> per tick, the number of the message held (counted as ``fed``).
        values_of: ``values_of(binding, first, last)`` -> (times, values) of the messages
            numbered ``first..last`` of its topic (values: list, an exception kept as a value).
        warm_before: the block's first ticks that are warm-up anyway (a topic without a
            message yet): not evaluated, so an error stays for the first evaluated tick.

    Returns:
        (ticks at the start that are warm-up because a window is not complete, name -> list
        of values per tick from there on; an exception as a value is the error of that tick
        on).
    """
    names = [b.name for b in variables if b.name in windows]
    msgs = {}
    for b in variables:
        if b.name in windows:
            w = windows[b.name]
            first = fed.get(w.spec.topic, -1) + 1
            last = int(held[w.spec.topic][-1])
            msgs[b.name] = (first, values_of(b, first, last) if last >= first else ([], []))
    for topic in {windows[n].spec.topic for n in names}:
        fed[topic] = max(fed.get(topic, -1), int(held[topic][-1]))
    out: dict[str, list] = {n: [] for n in names}
    pos = {n: 0 for n in names}
    warm = 0
    for i, t in enumerate(times.tolist()):
        for n in names:
            w = windows[n]
            base, (ts, vs) = msgs[n]
            upto = int(held[w.spec.topic][i]) - base + 1
            while pos[n] < upto:
                w.push(ts[pos[n]], vs[pos[n]])
                pos[n] += 1
        if warm == i and (i < warm_before or not all(windows[n].complete(t) for n in names)):
            warm += 1
            for n in names:
                windows[n]._evict(t)
            continue
        for n in names:
            try:
                out[n].append(windows[n].value(t))
            except Exception as exc:  # noqa: BLE001 - the binding's error from this tick
                out[n].append(exc)
    return warm, out
