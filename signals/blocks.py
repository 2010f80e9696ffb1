"""Several clocks over one read of a log, evaluated block by block with numpy
(:func:`sample_blocks`): the audit's sampling.

The rules (time base, ticks, sample and hold, warm-up) are those of :mod:`fretc.signals`
and the values equal :func:`fretc.signals.sample_groups`'s tick by tick (tested): messages
are buffered per topic; every :data:`BLOCK` messages, each clock places its ticks that are due
(those before the newest message of its own topics, as a streaming clock would emit them), finds
the message each topic holds at each tick with ``np.searchsorted``, and evaluates each binding
over all those ticks at once (:class:`~fretc.signals.columns.HeldColumns`; a binding whose
values do not fit columns is evaluated tick by tick). Then the buffers keep only the messages
a later tick may still hold, so memory stays flat in the log's length.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right
from collections.abc import Iterator
from typing import Any, NamedTuple

import numpy as np

from fretc.signals.bindings.binding import Binding
from fretc.signals.between_ticks import folded, missed_changes, windows_of
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.expression import TF_TOPICS, stateful_topics
from fretc.signals.bindings.frames import TfBuffer
from fretc.signals.bindings.spec import Bindings, TickSpec
from fretc.common.problems import SignalError
from fretc.common.streams import log_topics
from fretc.signals.streams import Streams
from fretc.logs.ros.selective import install as install_selective
from fretc.logs import CsvSource, LogSource
from fretc.signals.bindings.spec import MAX_TICKS, grid_end, grid_start, tick_bound_error
from fretc.signals.windows import message_value, sliding_windows, window_block
from fretc.signals.clock import (HeaderBuffer, Sampling, Tick, check_topics, folded_topics,
                                 present_tf, silence_end)
from fretc.signals.columns import HeldColumns, Irregular, MessageColumns, SegmentList
from fretc.signals.groups import GroupSampling, _restrict, csv_clock

__all__ = ["BLOCK", "MAX_TICKS", "TickBlock", "sample_blocks", "blocks_of_ticks"]

#: Messages read between two evaluations of the clocks.
BLOCK = 4096
#: At most this many ticks in one block (a long gap at a short period gives many ticks).
MAX_BLOCK_TICKS = 1 << 16


class TickBlock(NamedTuple):
    """Consecutive evaluated ticks of one clock.

    Attributes:
        start: index of the first of them among the clock's evaluated ticks.
        times: int64 tick times (ns, time base).
        values: variable -> 1-D bool or float64 array (variables that failed are absent).
        log_times: bound topic (and the tick topic of a clock ticking on one) -> int64 log
            time (ns) of the message held at each tick.
    """

    start: int
    times: np.ndarray
    values: dict[str, np.ndarray]
    log_times: dict[str, np.ndarray]


class _Buffer:
    """Messages of one topic not yet released: times (time base), log times, data; ``base``
    counts the messages dropped before them."""

    __slots__ = ("times", "log_times", "data", "base")

    def __init__(self) -> None:
        self.times: list[int] = []
        self.log_times: list[int] = []
        self.data: list[Any] = []
        self.base = 0

    def trim(self, k: int) -> None:
        if k > 0:
            del self.times[:k], self.log_times[:k], self.data[:k]
            self.base += k


class _Stream:
    """The buffered messages that some clocks read (one shared stream under the log time
    base; one per clock under the header time base, each in its own stamp order)."""

    def __init__(self) -> None:
        self.buffers: dict[str, _Buffer] = {}
        self._arrays: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self._messages: MessageColumns | None = None

    def add(self, topic: str, t: int, log_time: int, data: Any) -> None:
        b = self.buffers[topic]
        b.times.append(t)
        b.log_times.append(log_time)
        b.data.append(data)

    def add_block(self, topic: str, log_times: list[int], segment: Any) -> None:
        """Messages of ``topic`` from the columnar pass (log time base): their buffer holds a
        :class:`SegmentList`."""
        b = self.buffers[topic]
        if not isinstance(b.data, SegmentList):
            assert not b.data
            b.data = SegmentList()  # type: ignore[assignment]  # indexed as a list is
        b.times.extend(log_times)
        b.log_times.extend(log_times)
        b.data.add(segment)  # type: ignore[attr-defined]  # (a SegmentList, above)

    def arrays(self, topic: str) -> tuple[np.ndarray, np.ndarray]:
        """int64 (times, log times) of the buffered messages of ``topic``."""
        a = self._arrays.get(topic)
        if a is None:
            b = self.buffers[topic]
            a = self._arrays[topic] = (np.array(b.times, dtype=np.int64),
                                       np.array(b.log_times, dtype=np.int64))
        return a

    def messages(self) -> MessageColumns:
        """The buffered messages as columns (one per evaluation round)."""
        if self._messages is None:
            self._messages = MessageColumns({t: b.data for t, b in self.buffers.items()})
        return self._messages

    def changed(self) -> None:
        """Forget the arrays and columns (messages were added or dropped)."""
        self._arrays.clear()
        self._messages = None


class _Group:
    """One clock: its variables, topics and where its ticks are."""

    def __init__(self, sub: Bindings, required: set[str], tick: TickSpec, sampling: Sampling,
                 stream: _Stream) -> None:
        self.variables: list[Binding] = list(sub.variables.values())
        self.required = sorted(required)
        self.own = sorted(set(required) | ({tick.topic} if tick.topic else set()))
        self.period = tick.period_ns
        self.tick_topic = tick.topic
        self.sampling = sampling
        self.stream = stream
        self.next_grid: int | None = None
        #: the log's end, where a clock reading age() ticks to (None: its own last message)
        self.silence_end = silence_end(sampling.source, sampling.bindings, self.variables)
        #: bytes of columns a tick of this clock takes (time, values, held log times), and
        #: the bytes made so far by every clock of the read (one list, shared)
        self.bytes_per_tick = 8 * (1 + len(self.variables) + len(self.required))
        self.committed = [0]
        self.next_seq = 0
        self.index = 0
        self.last_held: dict[str, int] = {}  # topic -> number of the message held last
        self.failed: dict[str, SignalError] = {}
        self.per_tick: set[str] = set()
        #: topics whose previous message a binding reads (@delta ...): one more message kept
        #: in the buffer, and warm-up until their second message
        self.stateful: set[str] = set().union(*(stateful_topics(b.ast) for b in self.variables))
        #: per aggregated binding's topic: the number of the message held at the previous
        #: grid tick (-1: none yet); its window at a tick starts after it
        self.window_start: dict[str, int] = {next(iter(b.topics)): -1 for b in self.variables
                                             if b.aggregate is not None}
        #: per binding that reads ``tf()``: its transforms so far and, per TF topic, the
        #: count of that topic's messages already added (tf() reads every message, not the
        #: held one: they are added in time order up to each tick)
        #: window bindings (mean(x, 2s) ...): name -> window; topic -> last message pushed
        self.sliding = sliding_windows(self.variables)
        self.window_fed: dict[str, int] = {}
        self.tf: dict[str, tuple[TfBuffer, dict[str, int]]] = {
            b.name: (TfBuffer(), {t: 0 for t in TF_TOPICS}) for b in self.variables
            if getattr(b, "uses_tf", False)}

    def next_time(self) -> float:
        """Time of its next tick not yet evaluated (inf: none is known yet)."""
        if self.period is not None:
            return self.next_grid if self.next_grid is not None else float("inf")
        assert self.tick_topic is not None  # (no period: per-topic ticks)
        b = self.stream.buffers[self.tick_topic]
        p = self.next_seq - b.base
        return b.times[p] if p < len(b.times) else float("inf")


def sample_blocks(source: LogSource, bindings: Bindings,
                  groups: dict[Any, tuple[list[str], frozenset[str]]],
                  until_ns: int | None = None) -> GroupSampling:
    """Per-requirement clocks in one read of the log, as :func:`fretc.signals.sample_groups`
    (same ticks, values, warm-up and errors), but yielding ``(key, TickBlock)`` pairs. The
    result's ``per_tick`` (key -> variable names) says which bindings were evaluated tick by
    tick in some block (values that do not fit columns). ``until_ns``: on the log time base,
    the read stops at the first message past that log time (ns): the ticks up to it are
    those of the whole read (a tick reads the messages at or before it), the ticks after
    it are not (the operands of a violation are read only up to the last tick shown).

    Raises:
        SignalError: (at the call) a topic of some group missing from the log.  Evaluation
            errors while iterating are kept per group (``failed`` / ``errors``), never raised.
    """
    g = GroupSampling(source)
    g.per_tick = {key: set() for key in groups}
    if source.kind == "csv":
        assert isinstance(source, CsvSource)
        whole = csv_clock(g, source, bindings, groups)
        variables = list(whole.bindings.variables) if whole.bindings is not None else []
        csv_topics = sorted({t for _n, ts in groups.values() for t in ts})
        g._iter = ((key, blk) for blk in blocks_of_ticks(iter(whole), variables, csv_topics)
                   for key in groups)
        return g
    tick = bindings.tick
    shared = _Stream() if bindings.time_base == "log" else None
    clocks: dict[Any, _Group] = {}
    committed = [0]  # the column bytes of every clock (MAX_COLUMN_BYTES)
    buffers: dict[Any, HeaderBuffer] = {}
    fed: dict[str, list[Any]] = {}
    available = source.topics()
    for key, (names, topics) in groups.items():
        sub = _restrict(bindings, names)
        s = Sampling(source, sub)
        g.groups[key] = s
        stream = shared if shared is not None else _Stream()
        clocks[key] = c = _Group(sub, present_tf(topics, available), tick, s, stream)
        c.committed = committed
        g.failed[key] = c.failed
        g.per_tick[key] = c.per_tick
        if shared is None:
            buffers[key] = HeaderBuffer(source, sub, s._problems)
        if until_ns is not None:  # (the grid ticks to it, as the whole read's does: it
            c.silence_end = until_ns  # is one of its ticks; none past it is read)
        for t in c.own:
            stream.buffers.setdefault(t, _Buffer())
            fed.setdefault(t, []).append(key)
    check_topics(source, _restrict(bindings, []), extra=set(fed), users=bindings)
    install_selective(source, _restrict(bindings, [n for names, _t in groups.values()
                                                   for n in names]))
    g._iter = _run(g, source, clocks, buffers, fed, shared,
                   until_ns if shared is not None else None)
    return g


def _run(g: GroupSampling, source: LogSource, clocks: dict[Any, _Group],
         buffers: dict[Any, HeaderBuffer], fed: dict[str, list[Any]], shared: _Stream | None,
         until_ns: int | None = None) -> Iterator[tuple[Any, TickBlock]]:
    """One read of the log, evaluating every clock each :data:`BLOCK` messages (up to the
    first message past log time ``until_ns``: :func:`sample_blocks`)."""
    count = 0
    by_blocks = getattr(source, "message_blocks", None)
    streams = Streams([b for c in clocks.values() for b in c.variables])

    def stream_failed(stream: str, exc: SignalError) -> None:
        for key in fed[stream]:
            g.errors.setdefault(key, exc)

    if (shared is not None and by_blocks is not None and not streams
            and not any(c.tf for c in clocks.values())):
        released = by_blocks(set(fed))
        if released is not None:  # the columnar pass (the log time base reads no header)
            for blocks in released:
                past = False
                for topic, log_times, segment in blocks:
                    shared.add_block(topic, log_times, segment)
                    count += len(log_times)
                    past = past or (until_ns is not None and len(log_times) > 0
                                    and int(log_times[-1]) > until_ns)
                if past:  # (the blocks up to a message past it: every tick up to it read)
                    break
                if count >= BLOCK:
                    count = 0
                    yield from _evaluate_all(g, clocks, False)
            yield from _evaluate_all(g, clocks, True)
            _missing(clocks)
            return
    for m in streams.messages(source.messages(log_topics(fed)), fed, stream_failed):
        if until_ns is not None and m.log_time > until_ns:
            break
        if shared is not None:
            shared.add(m.topic, m.log_time, m.log_time, m.data)
        else:
            for key in fed[m.topic]:
                if key in g.errors:
                    continue
                try:
                    items = buffers[key].push(m)
                except SignalError as exc:
                    g.errors[key] = exc
                    continue
                for item in items:
                    clocks[key].stream.add(*item)
        count += 1
        if count >= BLOCK:
            count = 0
            yield from _evaluate_all(g, clocks, False)
    for key, b in buffers.items():
        if key not in g.errors:
            for item in b.drain():
                clocks[key].stream.add(*item)
    yield from _evaluate_all(g, clocks, True)
    _missing(clocks)


def _missing(clocks: dict[Any, _Group]) -> None:
    for c in clocks.values():
        # the newest message of a topic is never trimmed: an empty buffer never had one
        c.sampling.missing_topics = [t for t in c.required if not c.stream.buffers[t].times]


def _evaluate_all(g: GroupSampling, clocks: dict[Any, _Group], final: bool
                  ) -> Iterator[tuple[Any, TickBlock]]:
    """Every clock's due ticks, then the buffers trimmed to what later ticks may hold."""
    streams = {id(c.stream): c.stream for c in clocks.values()}
    for stream in streams.values():
        stream.changed()
    for key, c in clocks.items():
        if key in g.errors:
            continue
        for blk in _due(c, final):
            yield key, blk
    for stream in streams.values():
        readers = [c for key, c in clocks.items() if c.stream is stream and key not in g.errors]
        for topic, b in stream.buffers.items():
            keep = len(b.times) - 1  # the newest message is always kept
            for c in readers:
                if topic not in c.own:
                    continue
                keep = min(keep, bisect_right(b.times, c.next_time()) - 1
                           - (topic in c.stateful))
                if topic == c.tick_topic and c.period is None:
                    keep = min(keep, c.next_seq - b.base)
                if topic in c.last_held:  # the messages since the one held last: the next
                    # ticks read those they skip (missed changes), whatever other clocks keep
                    keep = min(keep, c.last_held[topic] - b.base)
                if topic in c.window_fed:  # a window's messages not yet pushed
                    keep = min(keep, c.window_fed[topic] + 1 - b.base)
                if c.window_start.get(topic, -1) >= 0:  # an aggregation's next window:
                    # the messages after the one held at the last tick (and that one)
                    keep = min(keep, c.window_start[topic] - b.base)
                for _buf, added in c.tf.values():
                    if topic in added:
                        keep = min(keep, added[topic] - b.base)
            b.trim(keep)
        stream.changed()


def _due(c: _Group, final: bool) -> Iterator[TickBlock]:
    """The blocks of ``c``'s ticks before the newest message of its own topics (when
    ``final``, all of them: to the first grid tick at or after the last message,
    :func:`~fretc.signals.bindings.spec.grid_end`)."""
    bufs = [c.stream.buffers[t] for t in c.own]
    lasts = [b.times[-1] for b in bufs if b.times]
    if not lasts:
        return
    last = max(lasts)
    if final and c.period is not None and c.silence_end is not None:
        last = max(last, c.silence_end)  # (a topic silent to the log's end: stale there)
    while True:
        if c.period is not None:
            if c.next_grid is None:
                c.next_grid = grid_start(min(b.times[0] for b in bufs if b.times), c.period)
            end = grid_end(last, c.period) + 1 if final else last
            due = 0 if c.next_grid >= end else -(-(end - c.next_grid) // c.period)
            made = c.index + c.sampling.warmup_ticks
            why = tick_bound_error(c.sampling.source.path, c.period, c.next_grid, last,
                                   made + due, c.committed[0] + due * c.bytes_per_tick)
            if why is not None:
                raise SignalError(why)
            n = min(due, MAX_BLOCK_TICKS)
            c.committed[0] += n * c.bytes_per_tick
            times = c.next_grid + c.period * np.arange(n, dtype=np.int64)
            own = None
            c.next_grid += n * c.period
        else:
            assert c.tick_topic is not None  # (no period: per-topic ticks)
            tb = c.stream.buffers[c.tick_topic]
            p = c.next_seq - tb.base
            q = len(tb.times) if final else bisect_left(tb.times, last, lo=p)
            n = max(0, min(q, p + MAX_BLOCK_TICKS) - p)
            times = np.array(tb.times[p:p + n], dtype=np.int64)
            own = np.arange(p, p + n, dtype=np.int64)
            c.next_seq += n
        if n == 0:
            return
        blk = _evaluate(c, times, own)
        if blk is not None:
            yield blk
        if n < MAX_BLOCK_TICKS:
            return


def _evaluate(c: _Group, times: np.ndarray, own: np.ndarray | None) -> TickBlock | None:
    """The values at ticks ``times`` of clock ``c`` (``own``: per-topic ticks, the index of
    each tick's own message of the tick topic); warm-up ticks counted, not evaluated."""
    stream, s = c.stream, c.sampling
    idx = {t: np.searchsorted(stream.arrays(t)[0], times, side="right") - 1 for t in c.own}
    if own is not None:
        assert c.tick_topic is not None  # (own: per-topic ticks)
        idx[c.tick_topic] = own
    if s.start_time is None:
        s.start_time = int(times[0])
        s.waiting_for = sorted(t for t in c.required if idx[t][0] < _first_held(c, t))
    s.end_time = int(times[-1])
    warm = max((int(np.count_nonzero(idx[t] < _first_held(c, t))) for t in c.required),
               default=0)
    wwarm, wvals = 0, dict[str, Any]()
    if c.sliding:
        held_abs = {w.spec.topic: idx[w.spec.topic] + stream.buffers[w.spec.topic].base
                    for w in c.sliding.values()}
        wwarm, wvals = window_block(c.sliding, c.window_fed, c.variables, times, held_abs,
                                    lambda b, f, la: _message_values(stream, b, f, la), warm)
        warm = max(warm, wwarm)
    windows = windows_of(c, times, warm)
    s.warmup_ticks += warm
    if warm == len(times):
        return None
    times = times[warm:]
    idx = {t: i[warm:] for t, i in idx.items()}
    if s.first_time is None:
        s.first_time = int(times[0])
    _count_unsampled(c, idx)
    held = {t: i for t, i in idx.items() if t in c.required or i[0] >= 0}
    cols = HeldColumns(stream.messages(), times, {t: stream.arrays(t)[0] for t in held}, held)
    values: dict[str, np.ndarray] = {}
    for b in list(c.variables):
        try:
            if b.aggregate is not None:
                values[b.name] = folded(b, stream, windows[next(iter(b.topics))])
                continue
            if b.name in wvals:
                vals = wvals[b.name][warm - wwarm:]
                for v in vals:
                    if isinstance(v, SignalError):
                        raise v
                values[b.name] = np.array(vals, dtype=np.float64)
                continue
            values[b.name] = _values(b, cols, stream, times, held, c.per_tick,
                                     c.tf.get(b.name))
        except SignalError as err:
            c.failed[b.name] = err
            c.variables.remove(b)
    log_times = {t: stream.arrays(t)[1][idx[t]] for t in c.own}
    blk = TickBlock(c.index, times, values, log_times)
    c.index += len(times)
    s.ticks += len(times)
    return blk


def _message_values(stream: _Stream, b: Binding, first: int, last: int) -> tuple[list, list]:
    """(times, values) of the messages numbered ``first..last`` of a window binding's topic
    (by numpy over them, else message by message; an evaluation error is the value of its
    message, named with its log time)."""
    topic = b.window.topic  # type: ignore[union-attr]
    buf = stream.buffers[topic]
    times = stream.arrays(topic)[0]
    at = np.arange(first, last + 1) - buf.base
    if len(at) and at[0] < 0:  # released from the buffer: never read others in their place
        raise AssertionError(f"messages of {topic} were released before their window")
    try:
        if b.window.func == "goal_waiting":  # type: ignore[union-attr]
            raise Irregular("arrays of a status array: message by message")
        with np.errstate(all="ignore"):
            cols = HeldColumns(stream.messages(), times[at], {topic: times}, {topic: at})
            if b.parts:  # waiting(): a tuple of fields per message
                return times[at].tolist(), list(zip(*(p.evaluate_columns(cols).tolist()
                                                      for p in b.parts)))
            return times[at].tolist(), b.evaluate_columns(cols).tolist()
    except (SignalError, Irregular):
        pass
    st, vals = EvalState(), []
    with np.errstate(all="ignore"):
        for j in at.tolist():
            st.msgs[topic], st.times[topic], st.now = buf.data[j], buf.times[j], buf.times[j]
            try:
                vals.append(message_value(b, lambda x, raw=False: x.raw(st) if raw
                                          else x.evaluate(st)))
            except SignalError as exc:
                vals.append(SignalError(f"{exc} (message of {topic} at log time "
                                        f"{buf.log_times[j]})", variable=exc.variable))
    return times[at].tolist(), vals


def _first_held(c: _Group, topic: str) -> int:
    """The smallest buffer index of ``topic`` a tick may be evaluated with: its first
    message, or its second for a topic whose previous message a binding reads."""
    return 1 - c.stream.buffers[topic].base if topic in c.stateful else 0


def _count_unsampled(c: _Group, idx: dict[str, np.ndarray]) -> None:
    """Add to ``c``'s :attr:`~fretc.signals.clock.Sampling.unsampled` the messages between two
    evaluated ticks that neither held (the held message's number in its topic jumps by more
    than one), from the first evaluated tick on (as :class:`fretc.signals.clock.Clock`)."""
    s, stream = c.sampling, c.stream
    folded = folded_topics(c.variables)
    for t in c.required:
        if t in TF_TOPICS or t == c.tick_topic or t in folded:
            continue
        a = idx[t] + stream.buffers[t].base
        prev = c.last_held.get(t, int(a[0]))
        gaps = np.diff(a, prepend=prev) - 1
        n = int(gaps[gaps > 0].sum())
        if n:
            s.unsampled[t] = s.unsampled.get(t, 0) + n
            missed_changes(c.variables, stream, t, np.concatenate(([prev], a[:-1])), a,
                           s.missed_changes)
        c.last_held[t] = int(a[-1])


def _values(b: Binding, cols: HeldColumns, stream: _Stream, times: np.ndarray,
            idx: dict[str, np.ndarray], per_tick: set[str],
            tf: tuple[TfBuffer, dict[str, int]] | None = None) -> np.ndarray:
    """``b`` at every tick: by numpy over the columns, else tick by tick (same values and
    errors as :class:`fretc.signals.clock.Clock`).

    Raises:
        SignalError: the evaluation fails at some tick (named with its held messages).
    """
    try:
        with np.errstate(all="ignore"):
            return b.evaluate_columns(cols)
    except (SignalError, Irregular):
        per_tick.add(b.name)
    st = EvalState()
    if tf is not None:
        st.tf = tf[0]
    out: list[Any] = []
    with np.errstate(all="ignore"):
        for i in range(len(times)):
            if tf is not None:
                _add_transforms(tf, stream, int(times[i]))
            for t, ix in idx.items():
                k = int(ix[i])
                buf = stream.buffers[t]
                st.msgs[t], st.times[t] = buf.data[k], buf.times[k]
                if k >= 1:  # the message before (@delta ...; kept for the topics that need it)
                    st.prev_msgs[t], st.prev_times[t] = buf.data[k - 1], buf.times[k - 1]
                else:
                    st.prev_msgs.pop(t, None)
            st.now = int(times[i])
            try:
                out.append(b.evaluate(st))
            except SignalError as exc:
                held = ", ".join(f"{t} @ log time {stream.buffers[t].log_times[int(ix[i])]}"
                                 for t, ix in sorted(idx.items()))
                raise SignalError(f"{exc} (tick at {st.now} ns; held: {held})",
                                  variable=exc.variable) from None
    if all(type(v) is bool for v in out):
        return np.array(out, dtype=np.bool_)
    return np.array(out, dtype=np.float64)


def _add_transforms(tf: tuple[TfBuffer, dict[str, int]], stream: _Stream, upto: int) -> None:
    """Add to ``tf``'s buffer the messages of /tf and /tf_static with time <= ``upto`` not
    added yet, in time order (as the streaming clock adds them)."""
    buf, added = tf
    pending: list[Any] = []
    for topic in TF_TOPICS:
        b = stream.buffers.get(topic)
        if b is None:
            continue
        p = max(added[topic] - b.base, 0)
        q = bisect_right(b.times, upto, lo=p)
        pending.extend((b.times[k], topic, b.data[k]) for k in range(p, q))
        added[topic] = b.base + q
    for t, topic, data in sorted(pending, key=lambda x: x[0]):
        buf.add(topic, data, t)


def blocks_of_ticks(ticks: Iterator[Tick], names: list[str], topics: list[str],
                    size: int = BLOCK) -> Iterator[TickBlock]:
    """:class:`Tick` objects (a CSV trace, or a log without bindings) as blocks of ``size``."""
    index = 0
    while True:
        chunk = [t for _i, t in zip(range(size), ticks)]
        if not chunk:
            return
        values = {}
        for n in names:
            vals = [t.values[n] for t in chunk if n in t.values]
            if len(vals) == len(chunk):
                values[n] = np.array(vals, dtype=np.bool_ if all(type(v) is bool for v in vals)
                                     else np.float64)
        log_times = {tp: np.array([t.log_times.get(tp, -1) for t in chunk], dtype=np.int64)
                     for tp in topics}
        yield TickBlock(index, np.array([t.time for t in chunk], dtype=np.int64), values,
                        log_times)
        index += len(chunk)
