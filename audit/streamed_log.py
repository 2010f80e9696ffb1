"""A log's clocks judged as they are read (:class:`LogStreams`): a clock keeps its columns
for its first :data:`KEEP_TICKS` ticks; past them its requirements' streams
(:class:`fretc.audit.streamed.RequirementStreams`) are fed each block of ticks and the columns
are dropped; a violation's evidence is read again, its ticks alone (:class:`Picked`).
ARCHITECTURE.md ("stream") and docs/guide/audits.md say which requirements are taken and
when a clock is read again keeping its columns.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from fretc.audit.columns import TickColumns
from fretc.logs import open_log
from fretc.logs.allowance import with_allowance
from fretc.signals import sample_blocks
from fretc.audit.gaps import gaps_of_clock
from fretc.audit.streamed import (RequirementStreams, StreamedResult, feed_streams,
                                  streams_of, unstreamed_reason)
from fretc.monitors.evidence import Evidence
from fretc.monitors.robustness import ROBUSTNESS_CHUNK

if TYPE_CHECKING:
    from fretc.audit.model import AuditPlan, RequirementPlan
    from fretc.audit.passes import ClockKey
    from fretc.logs.base import LogSource
    from fretc.signals.bindings import Bindings
    from fretc.signals.blocks import TickBlock

__all__ = ["KEEP_TICKS", "FEED_TICKS", "ClockResult", "Picked", "Closed", "LogStreams",
           "wanted_ticks", "picked_times", "pick_ticks"]

#: Ticks a clock keeps as columns before its requirements are judged as the log is read
#: (a log this short is judged whole, as one chunk; tests set it to 0 to stream every tick).
KEEP_TICKS = 1 << 16
#: Ticks a streamed clock gathers (from the sampler's blocks) before it feeds them to its
#: streams as one chunk: fewer, longer chunks, in memory that does not grow with the log.
FEED_TICKS = 1 << 14


@dataclass
class ClockResult:
    """What the streams of one requirement decided over its clock's ``result.n`` ticks.

    Attributes:
        result: the interval verdict and evidence, LTL3 verdict and robustness
            (:class:`fretc.audit.streamed.StreamedResult`).
        held: the log time (ns) of the newest message the clock's topics held at the
            robustness's tick (None: none held), the ``robustness_at`` of the audit JSON.
    """

    result: StreamedResult
    held: int | None
    #: the log time its clock's topics held at the last tick (None: none)
    last_held: int | None = None
    #: a violation's: the ticks whose times, held log times and values its evidence shows
    #: (:func:`wanted_ticks`), read again (:class:`Picked`); empty when it holds
    wanted: frozenset[int] = frozenset()


@dataclass
class Picked:
    """Some ticks of a clock read again (a violation's evidence, :func:`wanted_ticks`): tick
    -> its time (ns), the newest log time its topics held (None: none), topic -> tick -> the
    held message's log time (-1: none yet), variable -> tick -> value."""

    times: dict[int, int] = field(default_factory=dict)
    held: dict[int, int | None] = field(default_factory=dict)
    log_times: dict[str, dict[int, int]] = field(default_factory=dict)
    values: dict[str, dict[int, Any]] = field(default_factory=dict)


class _PickedTimes(Mapping[int, int]):
    """The times of a clock's ``n`` ticks of which only some were read again: ``len`` is
    ``n``, an item a tick read (:func:`picked_times`)."""

    def __init__(self, n: int, times: dict[int, int]) -> None:
        self.n, self.times = n, times

    def __getitem__(self, tick: int) -> int:
        return self.times[tick]

    def __iter__(self) -> Iterator[int]:
        return iter(self.times)

    def __len__(self) -> int:
        return self.n


def picked_times(n: int, picked: Picked) -> Any:
    """The times of a clock of ``n`` ticks as :class:`fretc.audit.columns.ClockPass`'s
    ``times`` give them to the read of a violation's operands
    (:func:`fretc.audit.operands.operand_values`: ``len`` and the ticks shown), from the
    ticks read again (``picked``)."""
    return _PickedTimes(n, picked.times)


def wanted_ticks(ev: Evidence, n: int, window: int) -> frozenset[int] | None:
    """The ticks (of ``n``) a violation's evidence ``ev`` names (the first violation's
    trigger, scope interval, window and violation tick, each violation listed; the last
    tick, which the streams keep, left out) and those within ``window`` of its trigger and
    violation tick, whose values are shown (:func:`fretc.audit.finalize.shown_ticks`); None
    without a first violation."""
    w = ev.violation
    if w is None:
        return None
    named = [w.trigger_tick, *w.interval, *w.window, w.violation_tick]
    for x in ev.listed:
        named += [x.trigger_tick, x.violation_tick]
    out = {min(max(t, 0), n - 1) for t in named} - {n - 1}
    for c in (w.trigger_tick, min(w.violation_tick, n - 1)):
        out.update(i for i in range(c - window, c + window + 1) if 0 <= i < n)
    return frozenset(out)


class _Clock:
    """One clock's streams: the held log times of its last ticks (the robustness's tick is
    at most one robustness block behind the ticks fed) and what each requirement decided."""

    def __init__(self, topics: list[str], streams: list[RequirementStreams]) -> None:
        self.topics = topics
        self.streams = streams
        self.n = 0
        self.first_time: int | None = None
        self.last_time: int | None = None
        self.held0: int | None = None
        self.last_held: int | None = None
        self._held: deque[tuple[int, np.ndarray]] = deque()
        #: requirement index -> (robustness tick, held log time there)
        self.rob_held: dict[int, tuple[int, int | None]] = {}

    def feed(self, times: np.ndarray, values: dict[str, np.ndarray],
             log_times: dict[str, np.ndarray]) -> None:
        """The clock's next ``len(times)`` ticks (values and held log times by topic)."""
        k = len(times)
        if k == 0:
            return
        held = np.full(k, -1, np.int64)
        for t in self.topics:
            lt = log_times.get(t)
            if lt is not None:
                np.maximum(held, lt[:k], out=held)
        first = self.n
        if self.first_time is None:
            self.first_time = int(times[0])
            self.held0 = int(held[0]) if held[0] >= 0 else None
        self.last_time = int(times[-1])
        self.last_held = int(held[-1]) if held[-1] >= 0 else None
        self._held.append((first, held))
        self.n = first + k
        for s in self.streams:
            if s.gave_up is None:
                feed_streams(s, values, k, times, first)
                self._note_rob(s)
        while self._held and self._held[0][0] + len(self._held[0][1]) < self.n - ROBUSTNESS_CHUNK:
            self._held.popleft()

    def _note_rob(self, s: RequirementStreams) -> None:
        """Keep the held log time at ``s``'s robustness tick when it moved."""
        if s.gave_up is not None or s.rob is None:
            return
        t = s.rob.tick
        if t is None or self.rob_held.get(s.r.index, (None,))[0] == t:
            return
        if t == 0:
            self.rob_held[s.r.index] = (0, self.held0)
            return
        for start, held in self._held:
            if start <= t < start + len(held):
                self.rob_held[s.r.index] = (t, int(held[t - start]) if held[t - start] >= 0
                                            else None)
                return
        s.gave_up = "the robustness's tick is no longer held"

    def close(self, whole: str | None, window: int
              ) -> tuple[dict[int, ClockResult], list[int]]:
        """The results of the requirements the streams decided (a violation's with the
        ticks its evidence shows, ``window`` ticks around it), and the indexes of those
        judged over the columns after all (``whole``: a reason that takes every one)."""
        out: dict[int, ClockResult] = {}
        again: list[int] = []
        for s in self.streams:
            i = s.r.index
            if whole is not None or s.gave_up is not None or self.n == 0:
                again.append(i)
                continue
            ev, times = s.interval.finish()
            rob = s.rob.finish()
            self._note_rob(s)
            wanted = frozenset() if ev.holds else wanted_ticks(ev, self.n, window)
            if s.gave_up is not None or wanted is None:
                again.append(i)
                continue
            ltl3 = s.ltl3.finish() if s.ltl3 is not None else ("unknown", None, None)
            assert self.last_time is not None  # (n ticks)
            out[i] = ClockResult(StreamedResult(ev, times, ltl3, rob, self.n, self.last_time),
                                 self.rob_held[i][1], self.last_held, wanted)
        self.streams = []
        self._held.clear()
        return out, again


class LogStreams:
    """The clocks of one read of a log (:func:`fretc.audit.passes.run_passes`) judged as
    they are read: a clock keeps :data:`KEEP_TICKS` ticks as columns; past them, when the
    streams take every requirement of it, it feeds them those ticks and every later block.
    ``groups``: clock -> its requirements (none: no clock streamed); ``discard``: clocks
    decided by an earlier read, sampled again (so that the log's figures are those of the
    same read) but neither kept nor judged; ``pick``: clocks of which only some ticks are
    kept (:class:`Picked`: a violation's evidence, read again)."""

    def __init__(self, plan: AuditPlan | None = None,
                 groups: dict[ClockKey, list[RequirementPlan]] | None = None,
                 discard: frozenset = frozenset(),
                 pick: dict[ClockKey, frozenset[int]] | None = None) -> None:
        self.plan = plan
        self.groups = groups or {}
        self.discard = discard
        #: clock -> the ticks to read again (a violation's evidence), and what was read
        self.pick = pick or {}
        self.picked: dict[ClockKey, Picked] = {}
        self.keep = KEEP_TICKS
        self.clocks: dict[ClockKey, _Clock] = {}
        self._refused: set[ClockKey] = set()  # clocks some requirement of is judged whole

    @classmethod
    def of(cls, plan: AuditPlan, groups: dict[ClockKey, list[RequirementPlan]],
           bindings: Bindings | None, source: LogSource) -> LogStreams:
        """The clocks of ``groups`` (clock -> its requirements) that may be judged as read:
        with bindings, comparisons with NaN unknown (fretc's rule), not a CSV trace (whose
        rows :mod:`fretc.audit.streamed` streams)."""
        if bindings is None or source.kind == "csv" or bindings.tick.nan == "false":
            return cls()
        return cls(plan, groups)

    def _clock(self, key: ClockKey) -> _Clock | None:
        """The streams of clock ``key``, made when it first passes :attr:`keep` ticks (None:
        a requirement of it the streams do not take,
        :func:`fretc.audit.streamed.unstreamed_reason`)."""
        if key in self._refused or self.plan is None or key not in self.groups:
            return None
        made = [streams_of(r) if unstreamed_reason(self.plan, r) is None else ""
                for r in self.groups[key]]
        if not all(isinstance(m, RequirementStreams) for m in made):
            self._refused.add(key)
            return None
        c = self.clocks[key] = _Clock(sorted(key.topics), [m for m in made if isinstance(
            m, RequirementStreams)])
        return c

    def take(self, key: ClockKey, block: TickBlock, columns: TickColumns) -> bool:
        """Whether the block of clock ``key`` is taken here (else its columns keep it):
        discarded, or fed to the clock's streams (its ``columns`` so far fed first and
        emptied, once it passes :attr:`keep` ticks; then gathered in ``columns`` and fed
        every :data:`FEED_TICKS` ticks, :meth:`flush`)."""
        if key in self.discard:
            return True
        if key in self.pick:
            self._pick(key, block)
            return True
        c = self.clocks.get(key)
        if c is None:
            if columns.n + len(block.times) <= self.keep:
                return False
            c = self._clock(key)
            if c is None:
                return False
            for times, cols, lts in columns.drain():
                c.feed(times, cols, lts)
        columns.append_block(block)
        if columns.n >= FEED_TICKS:
            self.flush(key, columns)
        return True

    def flush(self, key: ClockKey, columns: TickColumns) -> None:
        """Feed the ticks of clock ``key`` gathered since its last chunk (``columns``, then
        empty) to its streams; nothing for a clock whose columns are kept."""
        c = self.clocks.get(key)
        if c is not None and columns.n:
            times, cols, lts = columns.finish()
            columns.n = 0
            c.feed(times, cols, lts)

    def _pick(self, key: ClockKey, block: TickBlock) -> None:
        """Keep the wanted ticks of ``block`` (:attr:`pick`)."""
        got = self.picked.setdefault(key, Picked())
        k = len(block.times)
        for i in sorted(t - block.start for t in self.pick[key]
                        if block.start <= t < block.start + k):
            tick = block.start + i
            got.times[tick] = int(block.times[i])
            held = -1
            for t in key.topics:
                lt = block.log_times.get(t)
                x = int(lt[i]) if lt is not None else -1
                got.log_times.setdefault(t, {})[tick] = x
                held = max(held, x)
            got.held[tick] = held if held >= 0 else None
            for name, col in block.values.items():
                got.values.setdefault(name, {})[tick] = col[i]

    def close(self, source: LogSource, gaps: list) -> Closed:
        """After the read: what the streams decided (:class:`Closed`). A clock is read
        again keeping its columns where a requirement of it the streams gave up, or the
        log's damage or a gap of the clock's topics makes ticks unknown (judged whole, as
        every log was; its violations then too); a violation's ticks shown are read again
        (:attr:`Closed.pick`)."""
        out = Closed(picked=self.picked)
        damaged = getattr(source, "cut_start", None) is not None
        for key, c in self.clocks.items():
            whole = ("damage" if damaged else "a gap" if gaps_of_clock(gaps, key.topics)
                     else None)
            assert self.plan is not None  # (a clock streamed: made with the plan)
            got, back = c.close(whole, self.plan.config.window)
            out.ticks[key] = c.n
            if back:
                out.again.add(key)
                got = {i: x for i, x in got.items() if not x.wanted}
            wanted = frozenset().union(*(x.wanted for x in got.values()))
            if wanted:
                out.pick[key] = wanted
            out.results.update(got)
        return out


@dataclass
class Closed:
    """What the streams of one read decided.

    Attributes:
        results: requirement index -> :class:`ClockResult`.
        ticks: clock -> its ticks, for the clocks judged as read.
        again: clocks to read again keeping their columns.
        pick: clock -> the ticks of its violations' evidence to read again.
        picked: clock -> those ticks, as a read with ``pick`` kept them.
    """

    results: dict[int, ClockResult] = field(default_factory=dict)
    ticks: dict[ClockKey, int] = field(default_factory=dict)
    again: set[ClockKey] = field(default_factory=set)
    pick: dict[ClockKey, frozenset[int]] = field(default_factory=dict)
    picked: dict[ClockKey, Picked] = field(default_factory=dict)


def pick_ticks(plan: AuditPlan, path: str, first: LogSource | None, bindings: Bindings,
               pick: dict[ClockKey, frozenset[int]], names: dict[ClockKey, list[str]]
               ) -> dict[ClockKey, Picked]:
    """The ticks of ``pick`` (clock -> the ticks its violations' evidence shows) read again
    from the log ``path`` (``first``: the audit's source, whose ``reopen()`` spares a flight
    log's second read), each clock sampled on its variables ``names`` as the audit sampled
    it; the read stops once every clock is past its last tick wanted (as the read of a
    violation's operands does, :func:`fretc.audit.operands.operand_values`).

    Raises:
        LogError, SignalError, OSError: the log cannot be read again as it was."""
    source = (first.reopen() if first is not None else None) or with_allowance(open_log(
        path, csv_period_ns=plan.csv_period_ns, msg_path=plan.config.msg_path),
        plan.bindings.allowance if plan.bindings is not None else None)
    taker = LogStreams(pick=pick)
    last = {key: max(ticks) for key, ticks in pick.items()}
    done: set[ClockKey] = set()
    blocks = iter(sample_blocks(source, bindings, {k: (names[k], k.topics) for k in pick}))
    for key, blk in blocks:
        taker._pick(key, blk)
        if blk.start + len(blk.times) > last[key]:
            done.add(key)
        if len(done) >= len(last):  # every tick wanted is read: the rest of the log is not
            break
    close = getattr(blocks, "close", None)
    if close is not None:  # the reader's file closed now, not when collected
        close()
    return taker.picked
