"""Messages of several subscriptions merged into log-time order before the watch reads them.

A DDS reader or a Zenoh subscriber per topic hands messages over on its own thread (or in
its own batch), so two topics' messages can reach the watch in an order other than their log
times' even when the robot sent them in order, and :class:`~fretc.live.source.WatchSource` skips a
message older than one already used (``clock_backwards``). :class:`MergeBuffer` holds each
message for :data:`HOLD_SECONDS` of wall time after it arrived and releases the held ones in
log-time order (equal times in arrival order): a message overtaken by less than the hold
reaches the watch in order; one later than that is still skipped and reported. The hold is
the latency a verdict gains on these transports.
"""

from __future__ import annotations

import heapq
import threading
import time

__all__ = ["MergeBuffer", "HOLD_SECONDS", "MAX_HELD"]

#: Wall-clock seconds a message is held before it is released in log-time order.
HOLD_SECONDS = 0.1
#: Messages held at most: past it (a flood) the oldest held message is released at once, so
#: memory stays bounded by the event queue's own bounds (:mod:`fretc.live.events`).
MAX_HELD = 10_000


class MergeBuffer:
    """Hold ``("message", topic, log_time_ns, payload, wall_ns)`` events and put them on
    ``events`` (an :class:`~fretc.live.events.EventQueue`) in log-time order, :data:`HOLD_SECONDS`
    (``hold``) after each arrived. Thread-safe: any number of producer threads.

    Call :meth:`start`, :meth:`put` messages, :meth:`stop` (releases what is held).
    """

    def __init__(self, events, hold: float = HOLD_SECONDS) -> None:
        self.events = events
        self.hold = hold
        self._heap: list[tuple[int, int, float, tuple]] = []
        self._seq = 0
        self._cond = threading.Condition()
        self._stopped = False
        self._thread: threading.Thread | None = None

    def start(self) -> MergeBuffer:
        """Start the releasing thread."""
        self._thread = threading.Thread(target=self._run, daemon=True, name="fretc-merge")
        self._thread.start()
        return self

    def put(self, topic: str, log_time: int, payload: bytes, wall_ns: int) -> None:
        """Hold one message (past :data:`MAX_HELD` held, the oldest goes on at once)."""
        spill = None
        with self._cond:
            self._seq += 1
            heapq.heappush(self._heap, (log_time, self._seq, time.monotonic(),
                                        ("message", topic, log_time, payload, wall_ns)))
            if len(self._heap) > MAX_HELD:
                spill = heapq.heappop(self._heap)[3]
            self._cond.notify()
        if spill is not None:
            self.events.put(spill)

    def put_event(self, event: tuple) -> None:
        """Hold another event (an ``unadvertise``: a publisher left) behind every message
        held now, released with them: the messages that publisher sent before it left reach
        the watch before its leaving does."""
        with self._cond:
            self._seq += 1
            after = max((e[0] for e in self._heap), default=-(2**63))
            heapq.heappush(self._heap, (after, self._seq, time.monotonic(), event))
            self._cond.notify()

    def _due(self) -> list[tuple]:
        """The messages to release now (lock held): every message at or before the log time of
        the newest one whose hold passed, in log-time order."""
        now = time.monotonic()
        ripe = [e for e in self._heap if now - e[2] >= self.hold]
        if not ripe and not self._stopped:
            return []
        upto = max(e[0] for e in ripe) if ripe and not self._stopped else None
        out = []
        while self._heap and (upto is None or self._heap[0][0] <= upto):
            out.append(heapq.heappop(self._heap)[3])
        return out

    def _run(self) -> None:
        while True:
            with self._cond:
                self._cond.wait(self.hold / 10)  # released within a tenth of the hold
                out = self._due()
                done = self._stopped and not self._heap
            for ev in out:
                self.events.put(ev)
            if done:
                return

    def stop(self) -> None:
        """Release everything held and end the thread."""
        with self._cond:
            self._stopped = True
            self._cond.notify()
        if self._thread is not None:
            self._thread.join(2)
        with self._cond:  # what the thread did not release (never started, or stuck)
            rest = [heapq.heappop(self._heap)[3] for _ in range(len(self._heap))]
        for ev in rest:
            self.events.put(ev)
