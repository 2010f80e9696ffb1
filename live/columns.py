"""The columns a watch keeps while it runs: per tick, every variable's value, the log time
each topic's held message had, and the tick's time (the audit's columns of
:mod:`fretc.audit.columns`, grown one tick at a time), read back as numpy arrays for the judge;
what the watch hands its judge (:class:`WatchPasses`) and the live table's pending count
(:func:`split_pending`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, TYPE_CHECKING

import numpy as np

from fretc.audit.columns import column_array

if TYPE_CHECKING:
    from fretc.signals.clock import Tick
    from fretc.monitors.interval import Evidence

__all__ = ["LiveColumns", "WatchPasses", "split_pending"]


class LiveColumns:
    """Per-tick values, times and held log times kept while watching (the audit's columns,
    as growing lists; :meth:`arrays` gives numpy views of everything so far)."""

    def __init__(self, names: list[str], topics: list[str]) -> None:
        self.names = names
        self.topics = topics
        self.n = 0
        self.vals: dict[str, list] = {n: [] for n in names}
        self.lts: dict[str, list] = {t: [] for t in topics}
        self.times: list = []

    def append(self, tick: Tick) -> None:
        """Keep one :class:`~fretc.signals.clock.Tick`: its values, held log times and time.
        A variable absent from it (its evaluation failed: its requirements are errors) reads
        False, as in the audit's columns."""
        v = tick.values
        for name in self.names:
            self.vals[name].append(v.get(name, False))
        lt = tick.log_times
        for t in self.topics:
            self.lts[t].append(lt.get(t, -1))
        self.times.append(tick.time)
        self.n += 1

    def arrays(self, n: int | None = None
               ) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
        """(times, variable -> values, topic -> held log times) of the first ``n`` ticks
        (all by default; a snapshot of ``n`` taken first is safe while another thread
        appends)."""
        n = self.n if n is None else n
        times = np.array(self.times[:n], dtype=np.int64)
        cols = {k: column_array(v[:n]) for k, v in self.vals.items()}
        lts = {t: np.array(v[:n], dtype=np.int64) for t, v in self.lts.items()}
        return times, cols, lts


def split_pending(ev: Evidence, n: int) -> tuple[int, int]:
    """(violated, pending) of the failed obligations of ``ev`` (an
    :class:`~fretc.monitors.interval.Evidence` over the first ``n`` ticks of a run): pending
    when its window reaches the last tick and it failed only there (FRET's finite-trace
    semantics reads the end of the ticks so far as the end of the run; a later tick may still
    meet it), violated otherwise. Counted over the listed failures
    (:data:`~fretc.monitors.interval.MAX_LISTED`); unlisted ones count as violated."""
    total = ev.violations or 0
    pending = sum(1 for x in (getattr(ev, "listed", ()) or ())
                  if x.window[1] >= n - 1 and x.violation_tick >= n - 1)
    return total - pending, pending


@dataclass
class WatchPasses:
    """The watch's ticks, one :class:`fretc.audit.columns.ClockPass` per requirement's
    clock."""

    sampling: Any
    by_req: dict[int, Any]
    failed: dict[Any, dict[str, Any]]
    group: dict[int, Any]
