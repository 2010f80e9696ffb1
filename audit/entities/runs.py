"""The ticks of a lean per-entity clock as runs (:class:`TickRuns`): a clock of a tick period
with no plain variable evaluates nothing per tick but the rows of the held key message
(:mod:`fretc.audit.entities.read`, :attr:`~fretc.audit.entities.read.EntityClock.lean`), so the
grid ticks between two messages are alike but for their time: :func:`grid_run` records
them as one run (first time, how many, the held message's rows, the log times held) with
the bookkeeping :class:`fretc.signals.clock.Clock` does tick by tick (warm-up, the
sampling's figures), and the judgement reads the runs as columns (no
:class:`~fretc.signals.clock.Tick` object per tick). :meth:`TickRuns.ticks` gives the same
ticks as objects (for tests: the tick-by-tick clock's ticks, equal by test).
"""

from __future__ import annotations

from array import array
from itertools import chain, repeat
from typing import Any

import numpy as np

from fretc.audit.entities.columns import EntityColumns
from fretc.common.problems import SignalError
from fretc.signals.bindings.spec import MAX_TICKS, tick_bound_error
from fretc.signals.clock import Tick

__all__ = ["TickRuns", "grid_run", "LEAN_BATCH", "lean_messages"]


class TickRuns:
    """Runs of evaluated ticks ``period`` ns apart: run ``r`` is ``counts[r]`` ticks from
    ``starts[r]`` (ns), each holding the rows ``rows[r]`` (a
    :class:`~fretc.audit.entities.columns.HeldRows`, or ``[]``: no entity held) and the log
    times ``log_times[topic][r]`` (ns; -1: no message of the topic held yet), one list a
    topic rather than a dict a run (a lean clock makes a run a key message)."""

    def __init__(self, period: int) -> None:
        self.period = period
        # (int64 arrays of the standard library: 8 bytes a run, not a Python int each)
        self.starts = array("q")
        self.counts = array("q")
        self.rows: list[Any] = []
        self.log_times: dict[str, array] = {}

    def add(self, start: int, n: int, rows: Any, log_times: dict[str, int]) -> None:
        """One more run (its ticks after those recorded), holding the log times
        ``log_times`` (topic -> ns; copied: the caller may change it after)."""
        self.extend([start], [n], [rows], log_times)

    def extend(self, starts: list[int], counts: list[int], rows: list[Any],
               log_times: dict[str, int], topic: str | None = None,
               topic_log_times: list[int] | None = None) -> None:
        """Runs ``starts``, ``counts``, ``rows`` after those recorded, each holding the log
        times ``log_times`` (topic -> ns) but for ``topic``, whose log time at each run is
        ``topic_log_times`` (as long as ``starts``)."""
        k, m = len(self.starts), len(starts)
        self.starts.extend(starts)
        self.counts.extend(counts)
        self.rows += rows
        cols = self.log_times
        also = () if topic is None else (topic,)
        for tp in dict.fromkeys([*log_times, *also, *cols]):
            col = cols.get(tp)
            if col is None:
                col = cols[tp] = array("q", [-1]) * k
            if tp == topic:
                col.extend(topic_log_times)  # type: ignore[arg-type]  # (given with topic)
            else:
                col.extend(array("q", [log_times.get(tp, -1)]) * m)

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
        return {tp: np.array(self.log_times[tp], np.int64)[run]
                for tp in sorted(self.log_times)}

    def columns(self, names: list[str], absent: tuple, n_entities: int) -> EntityColumns:
        """The per-entity variables ``names`` as columns (``absent``: their values for an
        entity not held, the same at every tick)."""
        counts = np.asarray(self.counts, np.int64)
        firsts = (np.cumsum(counts) - counts).tolist()
        return EntityColumns.of_runs(names, absent, firsts, self.counts, self.rows,
                                     int(counts.sum()), n_entities)

    def ticks(self, entities: str, absent: tuple) -> list[Tick]:
        """The runs' ticks as :class:`~fretc.signals.clock.Tick` objects (numbered from 0,
        ``values[entities]`` = ``(absent, rows)``), as the tick-by-tick clock makes them."""
        out: list[Tick] = []
        cols = self.log_times
        for r, (start, n, rows) in enumerate(zip(self.starts, self.counts, self.rows)):
            lt = {tp: col[r] for tp, col in cols.items() if col[r] != -1}
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
    c.runs.add(start, n, rows, c.log_times)
    c.index += n
    s.ticks += n


#: Messages of a lean clock's key topic recorded at once by :func:`lean_messages` (tests
#: patch it small, so that batches end anywhere; 0: one at a time by :func:`grid_run`, the
#: tick-by-tick bookkeeping the batches are tested against)
LEAN_BATCH = 256


def lean_messages(c: Any) -> None:
    """Record the key messages waiting in lean clock ``c`` (``c.waiting``: ``(t, log time,
    data)`` in push order) as :meth:`EntityClock._lean_push
    <fretc.audit.entities.read.EntityClock._lean_push>` does one at a time: each message's
    entities into the table, then the runs of ticks between the messages with numpy (the
    run before a message holds the one before it: ticks ``G, G + period, ...`` before its
    time, ``G`` the first multiple of the period at or after every earlier message), the
    sampling's figures (:func:`grid_run`'s), the held messages' rows evaluated by batch;
    the last message is held. A clock still waiting for another topic records them one at
    a time (``c._lean_one``).

    Raises:
        SignalError: a key that cannot be read (the messages before it recorded), or more
            ticks than the tick bound (none of the batch recorded): the clock stops there."""
    msgs, c.waiting = c.waiting, []
    topic = c.kind.topic
    if not msgs:
        return
    if c.missing - {topic}:
        for m in msgs:
            c._lean_one(topic, *m)
        return
    err = None
    fast = _batch_entities(c, msgs)
    gots, arrays = fast if fast is not None else ([], None)
    if fast is None:
        for t, _lt, data in msgs:
            try:
                gots.append(c._key_entities(topic, t, data))
            except SignalError as exc:
                err = exc
                break
        msgs = msgs[:len(gots)]
    if msgs:
        _runs(c, msgs, gots, arrays)
    if err is not None:
        raise err


def _batch_entities(c: Any, msgs: list[tuple[int, int, Any]]
                    ) -> tuple[list[list[int]], list[list]] | None:
    """The entities each of ``msgs`` carries and its items, recorded in the table as
    :meth:`EntityClock._key_entities <fretc.audit.entities.read.EntityClock._key_entities>` records
    them one message at a time, when the keys are integers read by the clock's
    :class:`~fretc.audit.entities.rows.KeyReader`
    (:meth:`~fretc.audit.entities.rows.KeyReader.batch`), no key pattern selects them, and the
    table's bound is not met in the batch; else None (and nothing recorded)."""
    kind, table, reader = c.kind, c.table, c.read_keys
    if reader is None or kind.matching is not None or kind.stream:
        return None
    got = reader.batch([m[2] for m in msgs])
    if got is None:
        return None
    keys, arrays = got
    lens = list(map(len, arrays))
    index = table.index
    found = list(map(index.get, keys))
    times = list(chain.from_iterable(repeat(m[0], n) for m, n in zip(msgs, lens)))
    if None in found:
        new = [p for p, i in enumerate(found) if i is None]
        if len(table.keys) + len({keys[p] for p in new}) > c.bound:
            return None  # (the bound is met: one message at a time, as the table cuts)
        for p in new:
            i = index.get(keys[p])
            found[p] = i if i is not None else table.see(keys[p], times[p], c.bound)
    last = table.last
    for i, t in zip(found, times):
        last[i] = t
    out, a = [], 0
    for n in lens:
        out.append(found[a:a + n])
        a += n
    return out, arrays


def _runs(c: Any, msgs: list[tuple[int, int, Any]], gots: list[list[int]],
          arrays: list[list] | None) -> None:
    """:func:`lean_messages`' runs and holds of ``msgs`` (their entities ``gots``, their
    items ``arrays`` when the entities were read from them in order, else None)."""
    topic, s, period, st = c.kind.topic, c.s, c.period, c.state
    times = np.fromiter((m[0] for m in msgs), np.int64, len(msgs))
    held = st.msgs.get(topic)
    if c.next_grid is None:
        c.next_grid = -(-int(times[0]) // period) * period
    # the grid's next tick before each message's push, and the ticks due before it
    after = np.maximum(np.maximum.accumulate(-(-times // period) * period), c.next_grid)
    before = np.concatenate(([c.next_grid], after[:-1]))
    counts = np.maximum(-(-(times - before) // period), 0)
    if held is None:
        counts[0] = 0
    at = np.flatnonzero(counts).tolist()
    if at:
        total = s.ticks + s.warmup_ticks + np.cumsum(counts[at])
        over = np.flatnonzero(total > MAX_TICKS)
        if len(over):
            j = at[int(over[0])]
            raise SignalError(tick_bound_error(str(getattr(s.source, "path", "")), period,
                                               int(before[j]), int(times[j]), int(total[over[0]]),
                                               0) or "")
        _record(c, msgs, gots, arrays, at, before[at].tolist(), counts[at].tolist())
    t, lt, data = msgs[-1]
    st.msgs[topic], st.times[topic], c.log_times[topic] = data, t, lt
    c.missing.discard(topic)
    if topic in c.counted:
        c.since[topic] = c.since.get(topic, 0) + len(msgs) - (at[-1] if at else 0)
    c.last = t
    c.next_grid = int(after[-1])
    c.present, c.msg_rows = {id(data): gots[-1]}, {}
    c.held_items = arrays[-1] if arrays is not None else None


def _record(c: Any, msgs: list, gots: list[list[int]], arrays: list[list] | None,
            at: list[int], starts: list[int], counts: list[int]) -> None:
    """The runs before the messages ``at`` (``starts``, ``counts``), each holding the
    message before it (the held one before ``msgs[0]``), into ``c.runs``."""
    topic, s, period, st = c.kind.topic, c.s, c.period, c.state
    counted = topic in c.counted
    h = st.msgs.get(topic)  # (the message held before msgs[0])
    prev_got = c.present.get(id(h), ())
    prev_lt = c.log_times.get(topic)
    since = c.since.get(topic, 0)
    last_at = 0
    rows, lts = [], []
    for j, start in zip(at, starts):
        if j:
            data, got, lt = msgs[j - 1][2], gots[j - 1], msgs[j - 1][1]
            items = arrays[j - 1] if arrays is not None else None
        else:
            data, got, lt, items = h, prev_got, prev_lt, c.held_items
        if c.absent_once is None:  # (as the clock's first tick evaluates it)
            st.msgs[topic], st.now = data, start
            c.absent_once = c._absent(st)
            st.msgs[topic] = h
        if s.start_time is None:
            s.start_time = start
            s.waiting_for = []
        if s.first_time is None:
            s.first_time = start
        elif counted:
            k = since + j - last_at
            if k > 1:
                s.unsampled[topic] = s.unsampled.get(topic, 0) + k - 1
        since, last_at = 0, j
        lts.append(lt)
        rows.append(c.held_rows(data, got, items) if got else [])
    c.runs.extend(starts, counts, rows, c.log_times, topic, lts)
    n = sum(counts)
    c.index += n
    s.ticks += n
    c.since = {}
    last = starts[-1] + (counts[-1] - 1) * period
    s.end_time = last
    st.now = last
    c.last_values = {}
