"""The reordering queue of the passes that read a log without its index.

Without an index a recording's messages come in file order, which is log-time order only
up to the recorder's buffering: chunks and loose messages may overlap a little. The queue
holds messages for :data:`REORDER_WINDOW_NS` of log time behind the latest log time read
(the *watermark*) and releases them in log-time order; a message older than one already
delivered is *late*: only damage (a changed log time or chunk header) puts a message that
far out of order, and the reader records it as an ``out_of_order`` problem.

(The ``mcap`` library's log-time queue orders the messages of an indexed file exactly, with
an object per message; it has no window, and it is private to the library, so not used.)
"""

from __future__ import annotations

import heapq
from collections.abc import Iterator
from typing import Any

from fretc.common.units import NS_PER_S

__all__ = ["REORDER_WINDOW_NS", "ReorderQueue"]

#: Messages read without an index (linear pass) are held this long (log time) so that slightly
#: out-of-order chunks or loose messages are still delivered in log-time order.  A message later
#: than this is recorded as an ``out_of_order`` DataProblem and skipped.
REORDER_WINDOW_NS = NS_PER_S


class ReorderQueue:
    """Messages held until the watermark passes them by :data:`REORDER_WINDOW_NS`.

    Items are released in ``(log_time, position, arrival)`` order: equal log times keep file
    order. ``released`` is the log time of the last message the reader delivered (it sets it
    through :meth:`delivered`, since a message that does not decode is not delivered).
    """

    def __init__(self) -> None:
        self._heap: list[tuple[int, int, int, Any]] = []
        self._seq = 0
        self.released: int | None = None

    def push(self, log_time: int, position: int, item: Any) -> None:
        """Hold ``item`` read at log time ``log_time`` (ns) and byte ``position``."""
        heapq.heappush(self._heap, (log_time, position, self._seq, item))
        self._seq += 1

    def due(self, watermark: int | None) -> Iterator[tuple[int, Any]]:
        """``(log_time, item)`` of the items older than ``watermark`` minus the window, in
        log-time order; every item when ``watermark`` is None (the end of the pass)."""
        heap = self._heap
        limit = None if watermark is None else watermark - REORDER_WINDOW_NS
        while heap and (limit is None or heap[0][0] < limit):
            log_time, _pos, _seq, item = heapq.heappop(heap)
            yield log_time, item

    def late_by(self, log_time: int) -> int:
        """How many ns ``log_time`` is older than the last delivered message (0: in order)."""
        if self.released is not None and log_time < self.released:
            return self.released - log_time
        return 0

    def delivered(self, log_time: int) -> None:
        """Note that the message at ``log_time`` was delivered."""
        self.released = log_time

    def __len__(self) -> int:
        return len(self._heap)
