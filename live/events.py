"""The bounded queue between a live transport's thread and the watch: the transport puts
events (the tuples of :mod:`fretc.live.protocol`), the watch takes them in order.

A server can send faster than the monitors step (a flood, or a backlog after a stall). The
queue holds at most :data:`MAX_QUEUED_MESSAGES` messages and :data:`MAX_QUEUED_BYTES` bytes of
payload; past either, the **oldest** queued message is dropped (the newest data is what a live
verdict needs), and the drop is counted per topic with its first and last log time.
:meth:`EventQueue.take_dropped` hands the counts to the watch, which makes the dropped span a
gap of the run (ticks inside it unknown, never held over). Other events (connects,
advertisements, closes) are never dropped; ``status`` and ``protocol`` events past
:data:`MAX_QUEUED_OTHER` queued are dropped and counted (:attr:`EventQueue.dropped_other`).
Memory is therefore bounded whatever the server sends.
"""

from __future__ import annotations

import queue
import threading
from collections import deque

__all__ = ["EventQueue", "MAX_QUEUED_MESSAGES", "MAX_QUEUED_BYTES", "MAX_QUEUED_OTHER"]

#: Messages queued at most (each a few hundred bytes of Python objects beside its payload).
MAX_QUEUED_MESSAGES = 50_000
#: Payload bytes queued at most.
MAX_QUEUED_BYTES = 64 * 1024 * 1024
#: ``status`` and ``protocol`` events queued at most.
MAX_QUEUED_OTHER = 10_000
_DROPPABLE = ("status", "protocol")


class EventQueue:
    """A FIFO of transport events with :class:`queue.Queue`'s ``put``/``get``/``get_nowait``
    (``get`` raises :class:`queue.Empty` after ``timeout`` seconds), bounded as the module
    docstring says. Thread-safe: one producer thread, one consumer.

    Args:
        max_messages, max_bytes, max_other: the bounds (defaults: the module constants).
    """

    def __init__(self, max_messages: int = MAX_QUEUED_MESSAGES,
                 max_bytes: int = MAX_QUEUED_BYTES, max_other: int = MAX_QUEUED_OTHER) -> None:
        self.max_messages, self.max_bytes, self.max_other = max_messages, max_bytes, max_other
        self._items: deque = deque()
        self._cond = threading.Condition()
        self._messages = 0
        self._bytes = 0
        self._other = 0
        self._dropped: dict[str, list[int]] = {}
        #: ``status``/``protocol`` events dropped over :data:`MAX_QUEUED_OTHER`
        self.dropped_other = 0

    def put(self, event: tuple) -> None:
        """Queue ``event``; drops the oldest message(s) when a message would pass a bound."""
        with self._cond:
            kind = event[0]
            if kind == "message":
                self._messages += 1
                self._bytes += len(event[3])
                self._items.append(event)
                while self._messages > 1 and (self._messages > self.max_messages
                                              or self._bytes > self.max_bytes):
                    self._drop_oldest_message()
            elif kind in _DROPPABLE and self._other >= self.max_other:
                self.dropped_other += 1
                return
            else:
                if kind in _DROPPABLE:
                    self._other += 1
                self._items.append(event)
            self._cond.notify()

    def _drop_oldest_message(self) -> None:
        for i, ev in enumerate(self._items):
            if ev[0] == "message":
                del self._items[i]
                self._messages -= 1
                self._bytes -= len(ev[3])
                got = self._dropped.get(ev[1])
                if got is None:
                    self._dropped[ev[1]] = [1, ev[2], ev[2]]
                else:
                    got[0] += 1
                    got[1] = min(got[1], ev[2])
                    got[2] = max(got[2], ev[2])
                return

    def get(self, block: bool = True, timeout: float | None = None) -> tuple:
        """The oldest event; waits up to ``timeout`` s (None: forever) when ``block``.
        Raises :class:`queue.Empty` when none came."""
        with self._cond:
            if block and not self._items:
                self._cond.wait_for(lambda: bool(self._items), timeout)
            if not self._items:
                raise queue.Empty
            ev = self._items.popleft()
            if ev[0] == "message":
                self._messages -= 1
                self._bytes -= len(ev[3])
            elif ev[0] in _DROPPABLE:
                self._other -= 1
            return ev

    def empty(self) -> bool:
        """No event queued now (:class:`queue.Queue`'s ``empty``)."""
        with self._cond:
            return not self._items

    def get_nowait(self) -> tuple:
        """:meth:`get` without waiting."""
        return self.get(block=False)

    def qsize(self) -> int:
        """Events queued now."""
        with self._cond:
            return len(self._items)

    def take_dropped(self) -> dict[str, tuple[int, int, int]]:
        """Messages dropped since the last call: topic -> (count, first log time, last log
        time) in ns; empty when none."""
        if not self._dropped:  # (read without the lock: a drop seen a message late is
            return {}          # taken at the next call, before its gap would close)
        with self._cond:
            out = {t: (c, a, b) for t, (c, a, b) in self._dropped.items()}
            self._dropped.clear()
            return out
