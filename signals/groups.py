"""Several clocks over one read of a log (:func:`sample_groups`): one per group of
variables (normally one requirement's), each on the clock of its own topics
(../shared/DESIGN.md, "Each verdict stands alone"); the clock rules are in
:mod:`fretc.signals`."""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import Any

from fretc.common.streams import log_topics
from fretc.signals.bindings.spec import Bindings, TickSpec
from fretc.common.problems import DataProblem, SignalError
from fretc.logs.ros.selective import install as install_selective
from fretc.logs import CsvSource, LogSource
from fretc.signals.streams import Streams
from fretc.signals.tick_windows import with_tick_windows
from fretc.signals.clock import Clock, HeaderBuffer, Sampling, Tick, check_topics, present_tf, sample

__all__ = ["GroupSampling", "sample_groups"]


class GroupSampling:
    """Several clocks over one read of a log: one per group of variables, each on the clock
    of its own topics (:func:`sample_groups`). Iterate once for ``(key, Tick)`` pairs.

    Attributes (final once the iteration ends):
        groups: key -> :class:`Sampling` of that group (ticks, warm-up, first/last time,
            missing topics, header problems).
        failed: key -> {variable: SignalError} of variables whose evaluation failed (dropped
            from that group from then on; the group's other variables go on).
        errors: key -> SignalError that stopped the whole group (e.g. no header.stamp under
            the header time base).
    """

    def __init__(self, source: LogSource) -> None:
        self.source = source
        self.groups: dict[Any, Sampling] = {}
        self.failed: dict[Any, dict[str, SignalError]] = {}
        self.errors: dict[Any, SignalError] = {}
        # (key, Tick); signals.blocks' sample_blocks: (key, TickBlock)
        self._iter: Iterator[tuple[Any, Any]] | None = None

    #: key -> the variables evaluated tick by tick (set by signals.blocks' sample_blocks)
    per_tick: dict[Any, set[str]]

    @property
    def signal_problems(self) -> list[DataProblem]:
        """Problems found by the clocks (header stamps), once each."""
        out: list[DataProblem] = []
        seen = set()
        for s in self.groups.values():
            for p in s.signal_problems:
                k = (p.kind, p.topic, p.log_time, p.detail)
                if k not in seen:
                    seen.add(k)
                    out.append(p)
        return out

    @property
    def problems(self) -> list[DataProblem]:
        """The source's problems followed by every clock's (once each)."""
        return list(self.source.problems) + self.signal_problems

    def __iter__(self) -> Iterator[tuple[Any, Any]]:  # Tick, or signals.blocks' TickBlock
        if self._iter is None:
            raise RuntimeError("GroupSampling is iterated once")
        it, self._iter = self._iter, None
        if self.source.kind == "csv":  # one clock, a Sampling of its own: counted there
            return it
        return with_tick_windows(it, self.groups, {  # count_ticks(...) bindings counted
            k: list(s.bindings.variables.values()) for k, s in self.groups.items()
            if s.bindings is not None})


def sample_groups(source: LogSource, bindings: Bindings,
                  groups: dict[Any, tuple[list[str], frozenset[str]]]) -> GroupSampling:
    """Per-requirement clocks in one read of the log (../shared/DESIGN.md, "Each verdict
    stands alone"): each group ``key -> (variable names, topics)`` gets its own tick grid, start,
    end and warm-up from ``topics`` alone (normally the topics of one requirement's
    variables) and the bindings' tick, exactly as :func:`sample` with bindings restricted to
    those variables would give it; header-stamp ordering is buffered per group too. So a
    group's ticks never depend on which other groups are sampled.

    Raises:
        SignalError: (at the call) a topic of some group missing from the log, as
            :func:`sample`.  Evaluation errors while iterating are kept per group
            (:class:`GroupSampling` ``failed`` / ``errors``), never raised.
    """
    g = GroupSampling(source)
    if source.kind == "csv":
        assert isinstance(source, CsvSource)
        return _csv_groups(g, source, bindings, groups)
    tick: TickSpec = bindings.tick
    clocks: dict[Any, Clock] = {}
    buffers: dict[Any, HeaderBuffer] = {}
    fed: dict[str, list[Any]] = {}
    available = source.topics()
    for key, (names, topics) in groups.items():
        sub = _restrict(bindings, names)
        s = Sampling(source, sub)
        g.groups[key] = s
        clocks[key] = c = Clock(s, list(sub.variables.values()),
                                present_tf(topics, available), tick,
                                keep_going=True)
        g.failed[key] = c.failed
        if bindings.time_base != "log":
            buffers[key] = HeaderBuffer(source, sub, s._problems)
        for t in set(topics) | ({tick.topic} if tick.topic else set()):
            fed.setdefault(t, []).append(key)
    check_topics(source, _restrict(bindings, []), extra=set(fed), users=bindings)
    install_selective(source, _restrict(bindings, [n for names, _t in groups.values()
                                                   for n in names]))
    g._iter = _run(g, source, clocks, buffers, fed)
    return g


def _restrict(bindings: Bindings, names: list[str]) -> Bindings:
    """``bindings`` with only the variables ``names`` (in that order, once each)."""
    return Bindings({n: bindings.variables[n] for n in names}, bindings.tick,
                    bindings.time_base, bindings.header_lag_ns, bindings.source)


def _csv_groups(g: GroupSampling, source: CsvSource, bindings: Bindings,
                groups: dict[Any, tuple[list[str], frozenset[str]]]) -> GroupSampling:
    """A CSV trace has one clock (a tick per row): every group shares it."""
    whole = csv_clock(g, source, bindings, groups)

    def csv_iter() -> Iterator[tuple[Any, Tick]]:
        for tick in whole:
            for key in groups:
                yield key, tick
    g._iter = csv_iter()
    return g


def csv_clock(g: GroupSampling, source: CsvSource, bindings: Bindings,
              groups: dict[Any, tuple[list[str], frozenset[str]]]) -> Sampling:
    """The one clock of a CSV trace (a tick per row) over the variables of every group,
    recorded in ``g`` as each group's sampling."""
    names = [n for n in bindings.variables if any(n in v[0] for v in groups.values())]
    whole = sample(source, _restrict(bindings, names))
    for key in groups:
        g.groups[key] = whole
        g.failed[key] = {}
    return whole


def _run(g: GroupSampling, source: LogSource, clocks: dict[Any, Clock],
         buffers: dict[Any, HeaderBuffer], fed: dict[str, list[Any]]
         ) -> Iterator[tuple[Any, Tick]]:
    """One read of the log feeding every group's clock; ``(key, Tick)`` pairs. A group whose
    header buffer fails stops (``g.errors``); the others go on, as do those not reading a
    stream (``/track{id==3}``) whose filter fails on a message."""
    def stream_failed(stream: str, exc: SignalError) -> None:
        for key in fed[stream]:
            g.errors.setdefault(key, exc)

    streams = Streams([b for c in clocks.values() for b in c.variables])
    for m in streams.messages(source.messages(log_topics(fed)), fed, stream_failed):
        for key in fed[m.topic]:
            if key in g.errors:
                continue
            c = clocks[key]
            items: Iterable[tuple[str, int, int, Any]]  # (topic, time, log time, data)
            if key in buffers:
                try:
                    items = buffers[key].push(m)
                except SignalError as exc:
                    g.errors[key] = exc
                    continue
            else:
                items = ((m.topic, m.log_time, m.log_time, m.data),)
            for item in items:
                for t in c.push(*item):
                    yield key, t
    for key, c in clocks.items():
        if key in g.errors:
            continue
        if key in buffers:
            for item in buffers[key].drain():
                for t in c.push(*item):
                    yield key, t
        for t in c.finish():
            yield key, t
