"""Messages of several subscriptions merged into log-time order before the watch reads them.

A DDS reader or a Zenoh subscriber per topic hands messages over on its own thread (or in
its own batch), so two topics' messages can reach the watch in an order other than their log
times' even when the robot sent them in order, and :class:`~fretc.live.source.WatchSource` skips a
message older than one already used (``clock_backwards``). :class:`MergeBuffer` holds each
message for :data:`HOLD_SECONDS` of wall time after it arrived and releases the held ones in
log-time order (equal times in arrival order): a message overtaken by less than the hold
reaches the watch in order; one later than that is still skipped and reported. The hold is
the latency a verdict gains on these transports.

Design notes: ARCHITECTURE.md, `live/merge.py`."""

from __future__ import annotations

import heapq
import threading
import time
from collections.abc import Hashable, Mapping, Set

__all__ = ["MergeBuffer", "HOLD_SECONDS", "MAX_HELD"]

#: Wall-clock seconds a message is held before it is released in log-time order.
HOLD_SECONDS = 0.1
#: Messages held at most: past it (a flood) the oldest held message is released at once, so
#: memory stays bounded by the event queue's own bounds (:mod:`fretc.live.events`).
MAX_HELD = 10_000


class MergeBuffer:
    """Hold ``("message", topic, log_time_ns, payload, wall_ns)`` events and put them on
    ``events`` (an :class:`~fretc.live.events.EventQueue`) in log-time order, :data:`HOLD_SECONDS`
    (``hold``) after each arrived, or earlier at the watermark (module docstring) when the
    transport calls :meth:`sync`. Thread-safe: any number of producer threads.

    Call :meth:`start`, :meth:`put` messages (and :meth:`sync`), :meth:`stop` (releases what
    is held).
    """

    def __init__(self, events, hold: float = HOLD_SECONDS) -> None:
        self.events = events
        self.hold = hold
        self._heap: list[tuple[int, int, float, tuple]] = []
        self._seq = 0
        self._cond = threading.Condition()
        #: held by whoever takes due events and puts them on the queue (the releasing thread,
        #: or :meth:`sync` at the watermark), so they go on in log-time order
        self._order = threading.Lock()
        self._stopped = False
        self._thread: threading.Thread | None = None
        #: (topic, writer) -> the latest log time (ns) it delivered
        self._latest: dict[tuple[str, Hashable], int] = {}
        #: log time (ns) at or before which held messages may go now; None: hold only
        self._watermark: int | None = None

    def start(self) -> MergeBuffer:
        """Start the releasing thread."""
        self._thread = threading.Thread(target=self._run, daemon=True, name="fretc-merge")
        self._thread.start()
        return self

    def put(self, topic: str, log_time: int, payload: bytes, wall_ns: int,
            writer: Hashable = None) -> None:
        """Hold one message (past :data:`MAX_HELD` held, the oldest goes on at once).
        ``writer``: the id of the writer that sent it, as :meth:`sync`'s ``matched`` names it
        (None: unknown; a topic with such messages never has a watermark)."""
        spill = None
        with self._cond:
            self._seq += 1
            heapq.heappush(self._heap, (log_time, self._seq, time.monotonic(),
                                        ("message", topic, log_time, payload, wall_ns)))
            key = (topic, writer)
            self._latest[key] = max(log_time, self._latest.get(key, log_time))
            if len(self._heap) > MAX_HELD:
                spill = heapq.heappop(self._heap)[3]
            self._cond.notify()
        if spill is not None:
            self.events.put(spill)

    def sync(self, matched: Mapping[str, Set[Hashable]] | None) -> None:
        """Set the watermark from the messages put so far: ``matched`` is topic -> the ids of
        the writers the transport's subscription of it is matched with *now*, read after
        those messages were put (a writer matched later writes after this call). The
        watermark is the oldest latest log time over every writer that delivered (none
        forgotten), defined only when each writer in ``matched`` has delivered and no
        message came without a writer id; else (and for ``matched`` None: the transport
        cannot tell) the hold alone releases."""
        with self._order:  # released here at once: no wait for the releasing thread
            with self._cond:
                ok = matched is not None \
                    and all((t, w) in self._latest for t, ws in matched.items() for w in ws) \
                    and all(w is not None for _, w in self._latest)
                self._watermark = min(self._latest.values()) if ok and self._latest else None
                out = self._due() if self._watermark is not None else []
            for ev in out:
                self.events.put(ev)

    def forget(self, topic: str) -> None:
        """``topic``'s writers are all gone and their messages put: they no longer hold the
        watermark back (from the next :meth:`sync`)."""
        with self._cond:
            for key in [k for k in self._latest if k[0] == topic]:
                del self._latest[key]

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
        """The events to release now (lock held): every one at or before the watermark or
        the log time of the newest message whose hold passed, in log-time order."""
        if self._stopped:
            upto = None
        else:
            now = time.monotonic()
            ripe = [e[0] for e in self._heap if now - e[2] >= self.hold]
            marks = ripe + ([self._watermark] if self._watermark is not None else [])
            if not marks:
                return []
            upto = max(marks)
        out = []
        while self._heap and (upto is None or self._heap[0][0] <= upto):
            out.append(heapq.heappop(self._heap)[3])
        return out

    def _release(self, wait: float = 0.0) -> bool:
        """Wait up to ``wait`` seconds for a put, a sync or the stop, then put the due events
        on the queue (by one thread: the releasing one); True when stopped and empty."""
        with self._cond:
            if wait > 0:
                self._cond.wait(wait)
        with self._order:
            with self._cond:
                out = self._due()
                done = self._stopped and not self._heap
            for ev in out:
                self.events.put(ev)
        return done

    def _run(self) -> None:
        while not self._release(self.hold / 10):  # released within a tenth of the hold
            pass

    def stop(self) -> None:
        """Release everything held and end the thread."""
        with self._cond:
            self._stopped = True
            self._cond.notify()
        if self._thread is not None:
            self._thread.join(2)
        with self._order:
            with self._cond:  # what the thread did not release (never started, or stuck)
                rest = [heapq.heappop(self._heap)[3] for _ in range(len(self._heap))]
            for ev in rest:
                self.events.put(ev)
