"""The ticks of a lean per-entity clock as runs (:class:`TickRuns`): a clock of a tick period
with no plain variable evaluates nothing per tick but the rows of the held key message
(:mod:`fretc.audit.entity_read`, :attr:`~fretc.audit.entity_read.EntityClock.lean`), so the
grid ticks between two messages are alike but for their time: :func:`grid_run` records
them as one run (first time, how many, the held message's rows, the log times held) with
the bookkeeping :class:`fretc.signals.clock.Clock` does tick by tick (warm-up, the
sampling's figures), and the judgement reads the runs as columns (no
:class:`~fretc.signals.clock.Tick` object per tick). :meth:`TickRuns.ticks` gives the same
ticks as objects (for tests: the tick-by-tick clock's ticks, equal by test).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fretc.audit.entity_columns import EntityColumns
from fretc.common.problems import SignalError
from fretc.signals.bindings.spec import tick_bound_error
from fretc.signals.clock import Tick

__all__ = ["TickRuns", "grid_run"]


class TickRuns:
    """Runs of evaluated ticks ``period`` ns apart: run ``r`` is ``counts[r]`` ticks from
    ``starts[r]`` (ns), each holding the rows ``rows[r]`` (a
    :class:`~fretc.audit.entity_columns.HeldRows`, or ``[]``: no entity held) and the log
    times ``log_times[r]`` (topic -> ns)."""

    def __init__(self, period: int) -> None:
        self.period = period
        self.starts: list[int] = []
        self.counts: list[int] = []
        self.rows: list[Any] = []
        self.log_times: list[dict[str, int]] = []

    def add(self, start: int, n: int, rows: Any, log_times: dict[str, int]) -> None:
        """One more run (its ticks after those recorded)."""
        self.starts.append(start)
        self.counts.append(n)
        self.rows.append(rows)
        self.log_times.append(log_times)

    def _run_of(self) -> np.ndarray:
        """The run of each tick (int64, one per tick)."""
        return np.repeat(np.arange(len(self.counts), dtype=np.int64),
                         np.asarray(self.counts, np.int64))

    def times(self) -> np.ndarray:
        """Every tick's time (ns, int64)."""
        counts = np.asarray(self.counts, np.int64)
        run = self._run_of()
        firsts = np.cumsum(counts) - counts
        return (np.asarray(self.starts, np.int64)[run]
                + (np.arange(len(run), dtype=np.int64) - firsts[run]) * self.period)

    def log_time_columns(self) -> dict[str, np.ndarray]:
        """Topic -> the log time held at each tick (-1: none yet), int64, topics sorted."""
        run = self._run_of()
        topics = sorted({tp for lt in self.log_times for tp in lt})
        return {tp: np.array([lt.get(tp, -1) for lt in self.log_times], np.int64)[run]
                for tp in topics}

    def columns(self, names: list[str], absent: tuple, n_entities: int) -> EntityColumns:
        """The per-entity variables ``names`` as columns (``absent``: their values for an
        entity not held, the same at every tick)."""
        spans, k = [], 0
        for n, rows in zip(self.counts, self.rows):
            spans.append((k, n, rows))
            k += n
        return EntityColumns.of_runs(names, absent, spans, k, n_entities)

    def ticks(self, entities: str, absent: tuple) -> list[Tick]:
        """The runs' ticks as :class:`~fretc.signals.clock.Tick` objects (numbered from 0,
        ``values[entities]`` = ``(absent, rows)``), as the tick-by-tick clock makes them."""
        out: list[Tick] = []
        for start, n, rows, lt in zip(self.starts, self.counts, self.rows, self.log_times):
            for j in range(n):
                out.append(Tick(len(out), start + j * self.period,
                                {entities: (absent, rows)},  # type: ignore[dict-item]
                                dict(lt)))
        return out


def grid_run(c: Any, end: int) -> None:
    """Clock ``c``'s grid ticks before ``end`` (ns) as one run into ``c.runs``, with the
    bookkeeping of :meth:`fretc.signals.clock.Clock._grid_ticks` and ``_emit`` for a clock
    without variables: the tick bound, the warm-up (every tick of the run is one while a
    required topic is missing: no message comes between them), the sampling's start, end,
    first time, ticks and unsampled messages; the held key message's rows as the clock's
    ``_entity_values`` gives them at the run's first tick.

    Raises:
        SignalError: more ticks than the tick bound."""
    start, period, s = c.next_grid, c.period, c.s
    if start >= end:
        return
    n = -(-(end - start) // period)
    why = tick_bound_error(str(getattr(s.source, "path", "")), period, start, end,
                           s.ticks + s.warmup_ticks + n, 0)
    if why is not None:
        raise SignalError(why)
    last = start + (n - 1) * period
    c.next_grid = start + n * period
    if s.start_time is None:
        s.start_time = start
        s.waiting_for = sorted(c.missing)
    s.end_time = last
    if c.missing:
        s.warmup_ticks += n
        return
    if s.first_time is None:
        s.first_time = start
    elif c.since:
        for topic, k in c.since.items():
            if k > 1:
                s.unsampled[topic] = s.unsampled.get(topic, 0) + k - 1
    c.since = {}
    c.state.now = start
    _absent, rows = c._entity_values()
    c.state.now = last
    c.last_values = {}
    c.runs.add(start, n, rows, dict(c.log_times))
    c.index += n
    s.ticks += n
