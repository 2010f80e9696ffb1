"""The tick clock of one log: :func:`sample` streams the :class:`Tick` objects of a log
under its bindings (memory flat in the log's length), one :class:`Clock` per group of
variables; the rules (time base, ticks, sample and hold, warm-up, CSV) are in
:mod:`fretc.signals`."""

from __future__ import annotations

import heapq
from collections import deque
from collections.abc import Iterable, Iterator
from types import SimpleNamespace
from typing import Any, cast

import numpy as np

from fretc.common import problems as P
from fretc.common.streams import log_topics
from fretc.signals.bindings.binding import EMPTY_FOLD, Binding, fold
from fretc.signals.between_ticks import folded_topics, single_topic
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.expression import TF_TOPICS, FuncCall, stateful_topics, walk
from fretc.signals.bindings.frames import TfBuffer
from fretc.signals.bindings.spec import (Bindings, TickSpec, grid_end, grid_start,
                                         tick_bound_error)
from fretc.signals.streams import Streams
from fretc.signals.tick_windows import one_clock
from fretc.signals.windows import push_message, sliding_windows, windows_complete
from fretc.common.problems import DataProblem, ProblemLog, SignalError
from fretc.logs.ros.selective import install as install_selective
from fretc.logs import CSV_TOPIC, CsvSource, LogSource

__all__ = ["Tick", "Sampling", "sample", "folded_topics", "unsampled_of"]


class Tick:
    """One evaluated tick.

    Attributes:
        index: 0-based among evaluated ticks (warm-up ticks are not numbered).
        time: ns in the time base (log time or header stamp).
        values: FRET variable → bool or float, in binding order.
        log_times: bound topic (and tick topic) → log time (ns) of the message held at this
            tick: the evidence to jump to in Foxglove.  For CSV: ``{"/csv": time}``.
        line: CSV only: the row's line number in the file, else None.
    """

    __slots__ = ("index", "time", "values", "log_times", "line")

    def __init__(self, index: int, time: int, values: dict[str, bool | float],
                 log_times: dict[str, int], line: int | None = None) -> None:
        self.index = index
        self.time = time
        self.values = values
        self.log_times = log_times
        self.line = line

    def __repr__(self) -> str:
        return f"Tick({self.index}, {self.time}, {self.values!r})"

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Tick) and self.index == other.index and self.time == other.time
                and self.values == other.values and self.log_times == other.log_times
                and self.line == other.line)


class Sampling:
    """The ticks of one log under one set of bindings (iterate once), with what was skipped.

    Attributes (filled while iterating; final once the iteration ends):
        source, bindings: what is sampled.
        ticks: number of evaluated ticks yielded.
        warmup_ticks: ticks before every bound topic had a message (not evaluated).
        waiting_for: bound topics without a message at the first tick (sorted).
        missing_topics: bound topics that never had a message (then no tick is evaluated).
        unsampled: topic -> messages no evaluated tick held: superseded by a newer message of
            the topic before the next tick sampled it (sample-and-hold keeps only the newest);
            the tick topic (one tick per message) and /tf, /tf_static (``tf()`` reads every
            transform) are not counted.
        missed_changes: variable -> how many of those messages would have changed its value
            (boolean bindings of one topic without aggregation: the binding's value on the
            skipped message differs from its value at the tick before;
            :func:`fretc.signals.between_ticks.is_boolean`).
        start_time: time of the first tick, evaluated or not; None if none.
        first_time: time of the first evaluated tick; None if none.
        end_time: time of the last tick; None if none.
        signal_problems: problems found by the clock (header stamps).
    """

    def __init__(self, source: LogSource, bindings: Bindings | None) -> None:
        self.source = source
        self.bindings = bindings
        self.ticks = 0
        self.warmup_ticks = 0
        self.waiting_for: list[str] = []
        self.missing_topics: list[str] = []
        self.unsampled: dict[str, int] = {}
        self.missed_changes: dict[str, int] = {}
        self.start_time: int | None = None
        self.first_time: int | None = None
        self.end_time: int | None = None
        self._problems = ProblemLog()
        self._iter: Iterator[Tick] | None = None

    @property
    def signal_problems(self) -> list[DataProblem]:
        """Problems found by the clock itself (header stamps backwards or late)."""
        return self._problems.problems

    @property
    def problems(self) -> list[DataProblem]:
        """The source's problems followed by the clock's."""
        return self.source.problems + self._problems.problems

    def __iter__(self) -> Iterator[Tick]:
        if self._iter is None:
            raise RuntimeError("Sampling is iterated once")
        it, self._iter = self._iter, None
        return one_clock(it, self)  # count_ticks(...) bindings counted


def missing_topics(need: Iterable[str], available: Iterable[str]) -> list[str]:
    """The topics of ``need`` the log does not have (sorted). ``tf()`` reads /tf and
    /tf_static together: a transform tree on either alone is complete (ROS 1 tf, and bags
    from before tf2, have no /tf_static; a static tree may have no /tf), so the pair is missing
    only when both are."""
    return sorted(present_tf(need, available) - set(available))


def present_tf(topics: Iterable[str], available: Iterable[str]) -> set[str]:
    """``topics`` less the one of /tf and /tf_static the log does not have when it has the
    other (:func:`missing_topics`): the clock then waits for and reads the one there is."""
    out = set(topics)
    tf = set(TF_TOPICS)
    absent = (out & tf) - set(available)
    if absent and len(absent) < len(out & tf):
        out -= absent
    return out


def check_topics(source: LogSource, bindings: Bindings, extra: set[str] | None = None,
                  users: Bindings | None = None) -> set[str]:
    """The topics to read: the bound ones (a stream: itself, its topic read for it),
    ``extra`` and the tick topic. Raises SignalError when some of them are not in the log
    (naming the variables that use them, from ``users`` if given)."""
    available = source.topics()
    need = set(bindings.topics) | (extra or set())
    if bindings.tick.topic is not None:
        need.add(bindings.tick.topic)
    missing = missing_topics(log_topics(need), available)
    if missing:
        by = users if users is not None else bindings
        who = {t: sorted(n for n, b in by.variables.items() if t in log_topics(b.topics)) for t in missing}
        detail = "; ".join(f"{t} (used by {', '.join(who[t]) or 'the [tick]'})" for t in missing)
        raise SignalError(f"{source.path}: the log has no topic {detail}; it has "
                          f"{', '.join(available) or 'no topics'}"
                          + (f" (bindings: {bindings.source})" if bindings.source else ""))
    return need


class HeaderBuffer:
    """Header-stamp ordering of one clock's messages (module docstring, "Time base")."""

    def __init__(self, source: LogSource, bindings: Bindings, problems: ProblemLog) -> None:
        self.source, self.bindings, self.problems = source, bindings, problems
        self.lag = bindings.header_lag_ns
        self.heap: list[tuple[int, int, Any]] = []
        self.newest: int | None = None
        self.released: int | None = None
        self.last_stamp: dict[str, int] = {}
        self.seq = 0

    def push(self, m: Any) -> list[tuple[str, int, int, Any]]:
        """Buffer message ``m``; the messages now ``lag`` behind the newest stamp, in stamp
        order, as (topic, stamp, log time, data).

        Raises:
            SignalError: ``m`` has no header stamp.
        """
        s = m.header_stamp
        if s is None and self.bindings.time_base == "header-where-stamped":
            s = m.log_time  # a message without a header is placed at its log time
        if s is None:
            raise SignalError(f"{self.source.path}: time = \"header\" but {m.topic} messages "
                              f"({type(m.data).__name__}) have no header.stamp (log time "
                              f"{m.log_time}); use time = \"header-where-stamped\" (its "
                              "log time for messages without a header) or \"log\""
                              + (f" in {self.bindings.source}" if self.bindings.source else ""))
        # live sources bound how far time may jump at once (the ticks in between are made
        # one by one): a stamp further past the newest one is skipped, as a log time is
        jump = getattr(self.source, "max_jump_ns", None)
        if jump is not None and self.newest is not None and s - self.newest > jump:
            self.problems.add(DataProblem(P.HEADER_JUMP, m.topic, m.log_time,
                                          f"header.stamp {s} is {(s - self.newest) / 1e9:.6g} s "
                                          f"after the newest stamp, more than the "
                                          f"{jump / 1e9:.6g} s ticked over at once; skipped"))
            return []
        prev = self.last_stamp.get(m.topic)
        if prev is not None and s < prev:
            self.problems.add(DataProblem(P.HEADER_BACKWARDS, m.topic, m.log_time,
                                          f"header.stamp {s} is {prev - s} ns before the previous "
                                          "stamp on this topic; placed in stamp order"))
        self.last_stamp[m.topic] = s if prev is None else max(prev, s)
        if self.released is not None and s < self.released:
            self.problems.add(DataProblem(P.HEADER_LATE, m.topic, m.log_time,
                                          f"header.stamp {s} is {self.released - s} ns older than "
                                          f"a message already used (more than header_lag "
                                          f"{self.lag} ns late); skipped"))
            return []
        heapq.heappush(self.heap, (s, self.seq, m))
        self.seq += 1
        self.newest = s if self.newest is None else max(self.newest, s)
        out = []
        while self.heap and self.heap[0][0] <= self.newest - self.lag:
            s0, _, m0 = heapq.heappop(self.heap)
            self.released = s0
            out.append((m0.topic, s0, m0.log_time, m0.data))
        return out

    def drain(self) -> list[tuple[str, int, int, Any]]:
        """The messages still buffered, in stamp order (at the end of the log)."""
        out = []
        while self.heap:
            s0, _, m0 = heapq.heappop(self.heap)
            out.append((m0.topic, s0, m0.log_time, m0.data))
        return out


def feed(source: LogSource, bindings: Bindings, topics: set[str], problems: ProblemLog
          ) -> Iterator[tuple[str, int, int, Any]]:
    """(topic, time, log_time, data) in non-decreasing time (time base applied); a stream's
    messages (``/a{id==3}``) follow their topic's (:class:`fretc.signals.streams.Streams`)."""
    msgs = Streams(bindings.variables.values()).messages(source.messages(log_topics(topics)),
                                                         topics)
    if bindings.time_base == "log":
        for m in msgs:
            yield m.topic, m.log_time, m.log_time, m.data
        return
    buf = HeaderBuffer(source, bindings, problems)
    for m in msgs:
        yield from buf.push(m)
    yield from buf.drain()


def s_first(s: Sampling) -> bool:
    """Whether ``s`` has evaluated a tick (skipped messages count from then on)."""
    return s.first_time is not None


def unsampled_of(s: Sampling, names: list[str], bindings: Bindings | None) -> dict[str, int]:
    """The unsampled messages of clock ``s`` that count for variables ``names`` (one
    requirement's): those of topics its non-aggregated bindings read, sorted by topic."""
    own = [bindings.variables[n] for n in names
           if bindings is not None and n in bindings.variables]
    folded = folded_topics(own)
    return {t: n for t, n in sorted(s.unsampled.items()) if t not in folded}


def silence_end(source: Any, bindings: Bindings | None, variables: Iterable[Binding]
                ) -> int | None:
    """Where a fixed-period clock whose variables read ``age(/topic)`` ends besides its own
    topics' last message: the log's last log time (ns), when the log states it before it is
    read (an MCAP summary, a bag's index: the same whichever requirements are audited) and
    the clock ticks on log time; for a watched run (``source.kind == "watch"``), asked at
    its end, the last message the watch received. A topic that falls silent before the log
    ends is then judged stale to the end, as the log shows it (a LiDAR that dies while the
    recording goes on); ticking only to its own last message, a staleness requirement over
    that topic alone was satisfied. A flight log (PX4 ULog, ArduPilot DataFlash) is read
    whole when opened and states its end as ``log_end`` (the last log time of a message of
    any topic; issue 91: a GPS that died before the end of a flight was never stale), used
    before ``end_time`` (which a flight log knows only once a pass has read it, and then
    of the topics that pass read). None otherwise (the clock ends at its topics' last
    message: a log that states its end only once read whole)."""
    if bindings is None or bindings.time_base != "log" or bindings.tick.period_ns is None:
        return None
    if not any(isinstance(n, FuncCall) and n.func == "age" for b in variables
               for n in walk(b.ast)):
        return None
    end = getattr(source, "log_end", None)
    if end is None:
        end = getattr(source, "end_time", None)
    return int(end) if end is not None else None


class Clock:
    """The ticks of one group of variables on the clock of its own topics (module docstring):
    the grid (:func:`grid_start`) starts at or after the first message of ``topics`` (or
    the tick topic's messages), the warm-up waits for every one of ``required``, and the
    grid ends at or after their last message (:func:`grid_end`), or the log's last one when
    a variable reads ``age()`` (:func:`silence_end`).

    Messages are pushed in non-decreasing time (:meth:`push`); ticks come back one at a
    time (generators: iterate each to its end).
    With ``keep_going``, a variable whose evaluation fails is dropped (its error kept in
    ``failed``) and the others go on; otherwise the SignalError propagates.
    """

    def __init__(self, s: Sampling, variables: list[Binding], required: set[str],
                 tick: TickSpec, keep_going: bool = False) -> None:
        self.s = s
        self.variables = list(variables)
        self.missing = set(required)
        self.state = EvalState()
        if any(b.uses_tf for b in self.variables):  # tf(): every transform, not the held
            self.state.tf = TfBuffer()
        self.log_times: dict[str, int] = {}
        self.period = tick.period_ns
        self.tick_topic = tick.topic
        self.pending: deque[tuple[int, Any, int, Any, int | None]] = deque()
        self.next_grid: int | None = None
        self.last: int | None = None
        #: the log's end, where a clock reading age() ticks to (None: its own last message;
        #: a watched run's is asked at its end)
        self.silence_end = silence_end(s.source, s.bindings, self.variables)
        self.index = 0
        self.keep_going = keep_going
        self.failed: dict[str, SignalError] = {}
        #: messages of each counted topic since the last evaluated tick (Sampling.unsampled)
        self.since: dict[str, int] = {}
        self.counted = (set(required) - set(TF_TOPICS) - {tick.topic}
                        - folded_topics(self.variables))
        #: aggregated bindings (``any_of_messages`` ...): name -> the values (or the error)
        #: of their topic's messages since the previous tick, and the topic
        self.window: dict[str, list[Any]] = {b.name: [] for b in self.variables
                                             if b.aggregate is not None}
        self.window_topic = {b.name: next(iter(b.topics)) for b in self.variables
                             if b.aggregate is not None}
        #: boolean bindings of one topic without aggregation (topic -> them), whose value on
        #: a message no tick samples is compared with their value at the tick before
        self.watched: dict[str, list[Binding]] = {}
        for b in self.variables:
            t = single_topic(b)
            if t is not None and t in self.counted:
                self.watched.setdefault(t, []).append(b)
        self.last_values: dict[str, Any] = {}
        #: topic -> (the message :meth:`_missed` last evaluated, the tick index then, the
        #: bindings it changed)
        self._missed_memo: dict[str, tuple[Any, int, list[str]]] = {}
        #: topics whose previous message a binding reads (@delta ...): held too, and
        #: waited for (warm-up) until the second message
        self.stateful: set[str] = set().union(*(stateful_topics(b.ast) for b in self.variables))
        self.sliding = sliding_windows(self.variables)  # window bindings: name -> window

    def _value(self, b: Binding, window: dict[str, list[Any]]) -> bool | float:
        """``b`` at the tick: the held message's value, or its aggregation over the
        messages since the previous tick (:func:`fretc.signals.bindings.binding.fold`)."""
        if b.name in self.sliding:
            return self.sliding[b.name].value(self.state.now)
        if b.aggregate is None:
            return b.evaluate(self.state)
        vals = window.get(b.name) or []
        for v in vals:
            if isinstance(v, SignalError):
                raise v
        if not vals:
            empty = EMPTY_FOLD[b.aggregate]
            return b.evaluate(self.state) if empty is None else empty
        return fold(b.aggregate, vals)

    def _emit(self, t: int) -> Tick | None:
        s = self.s
        window = self.window
        if window:  # every grid tick (warm-up ones too) starts a new window
            self.window = {k: [] for k in window}
        if s.start_time is None:
            s.start_time = t
            s.waiting_for = sorted(self.missing)
        s.end_time = t
        if self.missing or (self.sliding and not windows_complete(self.sliding, t)):
            s.warmup_ticks += 1
            return None
        if s.first_time is None:
            s.first_time = t
        elif self.since:
            for topic, n in self.since.items():
                if n > 1:
                    s.unsampled[topic] = s.unsampled.get(topic, 0) + n - 1
        self.since = {}
        state = self.state
        state.now = t
        values: dict[str, bool | float] = {}
        with np.errstate(all="ignore"):
            for b in list(self.variables):
                try:
                    values[b.name] = self._value(b, window)
                except SignalError as exc:
                    err = SignalError(f"{exc}{_context(state, self.log_times)}",
                                      variable=exc.variable)
                    if not self.keep_going:
                        raise err from None
                    self.failed[b.name] = err
                    self.variables.remove(b)
        tick = Tick(self.index, t, values, dict(self.log_times))
        self.last_values = values
        self.index += 1
        s.ticks += 1
        return tick

    def _emit_own(self, t: int, data: Any, log_time: int, prev: Any = None,
                  prev_t: int | None = None) -> Tick | None:
        """A per-topic tick, evaluated with its own message of the tick topic (and the one
        before it, for @delta and the like)."""
        st, lt, tt = self.state, self.log_times, cast(str, self.tick_topic)  # per-topic: set
        held = (st.msgs[tt], st.times[tt], lt[tt], st.prev_msgs.get(tt), st.prev_times.get(tt))
        st.msgs[tt], st.times[tt], lt[tt] = data, t, log_time
        if prev is not None:
            st.prev_msgs[tt], st.prev_times[tt] = prev, prev_t  # type: ignore[assignment]
        try:
            return self._emit(t)
        finally:
            st.msgs[tt], st.times[tt], lt[tt] = held[:3]
            if held[3] is not None:
                st.prev_msgs[tt], st.prev_times[tt] = held[3], held[4]  # type: ignore[assignment]

    def _grid_ticks(self, end: int) -> Iterator[Tick]:
        """The grid ticks before ``end`` (ns), counted against the tick bound before any is
        made (:func:`~fretc.signals.bindings.spec.tick_bound_error`) and handed on one at
        a time."""
        assert self.next_grid is not None and self.period is not None
        due = max(0, -(-(end - self.next_grid) // self.period))
        why = tick_bound_error(str(getattr(self.s.source, "path", "")), self.period,
                               self.next_grid, end, self.s.ticks + self.s.warmup_ticks + due,
                               0) if due else None
        if why is not None:
            raise SignalError(why)
        while self.next_grid < end:
            tick = self._emit(self.next_grid)
            self.next_grid += self.period
            if tick is not None:
                yield tick

    def push(self, topic: str, t: int, log_time: int, data: Any) -> Iterator[Tick]:
        """Hold message ``data`` of ``topic`` at time ``t`` after yielding the ticks due
        before it (iterate to the end: the message is held then)."""
        if self.period is not None:
            if self.next_grid is None:
                self.next_grid = grid_start(t, self.period)
            yield from self._grid_ticks(t)
        else:
            while self.pending and self.pending[0][0] < t:
                tick = self._emit_own(*self.pending.popleft())
                if tick is not None:
                    yield tick
        st = self.state
        if self.since.get(topic) and topic in self.watched and s_first(self.s):
            self._missed(topic)  # the held message is superseded before a tick sampled it
        prev = st.msgs.get(topic) if topic in self.stateful else None
        if prev is not None:
            st.prev_msgs[topic], st.prev_times[topic] = prev, st.times[topic]
        st.msgs[topic] = data
        st.times[topic] = t
        if st.tf is not None and topic in TF_TOPICS:
            st.tf.add(topic, data, t)
        self.log_times[topic] = log_time
        if topic not in self.stateful or topic in st.prev_msgs:
            self.missing.discard(topic)
        if self.window:
            self._fold_in(topic)
        if self.sliding:
            with np.errstate(all="ignore"):
                push_message(self.sliding, self.variables, topic, t,
                             lambda b, raw=False: b.raw(st) if raw else b.evaluate(st))
        if topic in self.counted:
            self.since[topic] = self.since.get(topic, 0) + 1
        if topic == self.tick_topic:
            self.pending.append((t, data, log_time, prev, st.prev_times.get(topic)))
        self.last = t

    def _missed(self, topic: str) -> None:
        """Count a change of a watched binding on the held message of ``topic``, which no
        tick sampled (:attr:`Sampling.missed_changes`). A watched binding reads that
        message's fields alone (:func:`fretc.signals.between_ticks.single_topic`), so the
        same message object held again since the last tick (a live source gives one object
        for a repeated payload) changes the same bindings: counted without evaluating."""
        mc = self.s.missed_changes
        data = self.state.msgs.get(topic)
        memo = self._missed_memo.get(topic)
        if memo is not None and memo[0] is data and memo[1] == self.index:
            changed = memo[2]
        else:
            changed = []
            for b in self.watched[topic]:
                if b.name not in self.last_values or b not in self.variables:
                    continue
                with np.errstate(all="ignore"):
                    try:
                        v = b.evaluate(self.state)
                    except SignalError:
                        continue
                w = self.last_values[b.name]
                if not (v == w or (v != v and w != w)):
                    changed.append(b.name)
            self._missed_memo[topic] = (data, self.index, changed)
        for name in changed:
            mc[name] = mc.get(name, 0) + 1

    def _fold_in(self, topic: str) -> None:
        """The value of the message of ``topic`` just held, for the aggregated bindings
        that read it (an evaluation error is kept and raised at the tick)."""
        for b in self.variables:
            if b.aggregate is None or self.window_topic[b.name] != topic:
                continue
            with np.errstate(all="ignore"):
                try:
                    self.window[b.name].append(b.evaluate(self.state))
                except SignalError as exc:
                    self.window[b.name].append(exc)

    def finish(self) -> Iterator[Tick]:
        """The ticks left at the end of the log (iterate to the end)."""
        if self.last is not None:
            if self.period is not None:  # to the grid tick at or after the last message
                end = (silence_end(self.s.source, self.s.bindings, self.variables)
                       if self.s.source.kind == "watch" else self.silence_end)
                last = max(self.last, end or self.last)
                yield from self._grid_ticks(grid_end(last, self.period) + 1)
            else:
                while self.pending:
                    tick = self._emit_own(*self.pending.popleft())
                    if tick is not None:
                        yield tick
        self.s.missing_topics = sorted(self.missing)


def _context(state: EvalState, log_times: dict[str, int]) -> str:
    held = ", ".join(f"{t} @ log time {lt}" for t, lt in sorted(log_times.items()))
    return f" (tick at {state.now} ns; held: {held})"


def sample(source: LogSource, bindings: Bindings | None = None) -> Sampling:
    """Stream the ticks of ``source`` under ``bindings`` (see the module docstring).

    Args:
        source: an open log (:func:`fretc.logs.open_log`).
        bindings: required for ROS logs; for CSV optional (columns are the variables).

    Returns:
        A :class:`Sampling`: iterate it (once) for :class:`Tick` objects; its counters
        (warm-up, first time, problems) are final when the iteration ends.

    Raises:
        SignalError: (at the call) no bindings for a ROS log, or a bound topic missing from
            the log; (while iterating) a field missing from a message, an array-valued
            variable, or header time base on a topic without header — naming the binding
            file:line:col, the variable and the tick / log times.
    """
    s = Sampling(source, bindings)
    if source.kind == "csv":
        assert isinstance(source, CsvSource)
        s._iter = _sample_csv(s, source, bindings)
        return s
    if bindings is None:
        raise SignalError(f"{source.path}: a {source.kind} log needs bindings (signals are declared, "
                          "never guessed)")
    topics = check_topics(source, bindings)
    install_selective(source, bindings)  # decode only the fields the bindings read
    s._iter = _sample_stream(s, source, bindings, topics)
    return s


def csv_bindings_check(source: CsvSource, bindings: Bindings) -> None:
    """Raises SignalError when bindings read a topic other than the CSV pseudo-topic."""
    bad = sorted(bindings.topics - {CSV_TOPIC})
    if bad:
        raise SignalError(f"{source.path}: a CSV trace has only the pseudo-topic {CSV_TOPIC} "
                          f"(columns: {', '.join(source.columns)}); bindings use {', '.join(bad)}")


def csv_period(source: CsvSource, bindings: Bindings | None) -> int:
    """The CSV tick period (ns): the bindings' fixed period if given, else the source's."""
    if bindings is not None and bindings.tick.period_ns is not None:
        return bindings.tick.period_ns
    return source.period_ns


def _sample_csv(s: Sampling, source: CsvSource, bindings: Bindings | None) -> Iterator[Tick]:
    period = csv_period(source, bindings)
    use = bindings is not None and bool(bindings.variables)
    if use:
        assert bindings is not None
        csv_bindings_check(source, bindings)
        state = EvalState()
        variables = list(bindings.variables.values())
    source._begin_pass()
    for row in source.rows():
        t = row.time if row.time is not None else row.index * period
        if s.start_time is None:
            s.start_time = s.first_time = t
        if use:
            state.msgs[CSV_TOPIC] = SimpleNamespace(**row.values)
            state.times[CSV_TOPIC] = t
            state.now = t
            ctx = f" ({source.path}:{row.line})"
            values = {b.name: b.evaluate(state, ctx) for b in variables}
        else:
            values = dict(row.values)
        source.counts[CSV_TOPIC] = source.counts.get(CSV_TOPIC, 0) + 1
        s.ticks += 1
        s.end_time = t
        yield Tick(row.index, t, values, {CSV_TOPIC: t}, row.line)


def _sample_stream(s: Sampling, source: LogSource, bindings: Bindings, topics: set[str]
                   ) -> Iterator[Tick]:
    clock = Clock(s, list(bindings.variables.values()),
                  present_tf(bindings.topics, source.topics()), bindings.tick)
    for topic, t, log_time, data in feed(source, bindings, topics, s._problems):
        yield from clock.push(topic, t, log_time, data)
    yield from clock.finish()
