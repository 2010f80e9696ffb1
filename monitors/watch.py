"""``fretc watch``: the audit's monitors on a running robot, over the Foxglove WebSocket
protocol.

One engine, three places (../shared/DESIGN.md): the watch runs the *same* pieces as an audit of a
recorded log, only fed live:

* :class:`WatchSource` is a :class:`monitors.sources.LogSource` whose messages come from a
  :class:`monitors.watch_client.FoxgloveClient` instead of a file; each channel is decoded
  with rosbags from the schema text the server advertised
  (:func:`monitors.sources.schema_decoder`, shared with the MCAP reader);
* the ticks come from :func:`monitors.signals.sample` with the same bindings (tick, time
  base: the server's log time or ``header.stamp``, sample and hold, warm-up) as an audit;
* every tick steps the generated monitors the audit loads (:func:`monitors.audit.load_plan`);
* at the end the verdicts and evidence are made by the audit's own code
  (``monitors.audit._finalize``) over the columns kept while watching.

So the same messages give the same verdicts as ``fretc audit`` (tested: each shipped trace
served by foxglove-sdk and watched equals its audit; a ``--record``\\ ed watch audited offline
equals the watch).

Faults, each a data problem of the run, never a crash:

* a dropped connection is retried with backoff; the messages lost in between are a
  :data:`CONNECTION_GAP` problem (log time of the last message before, of the first after,
  the wall-clock length). Ticks strictly inside the gap are **not evaluated** (counted as
  unknown, never held over the gap); the monitors keep their state and go on from the next
  message. A run with a gap is ``partial`` and cannot exit 0. A connection that closes with
  nothing after it before the watch ends is the end of the watched run
  (:data:`CONNECTION_CLOSED`, reported, not a gap);
* a topic the server stops advertising: :data:`UNADVERTISED` (its last message is then held
  like any silent topic, and the problem says since when);
* a message that does not decode: ``undecodable`` (skipped), as in logs;
* a log time (or, under the header time base, what the clock sees) going backwards:
  :data:`CLOCK_BACKWARDS` (the message is skipped: the past is not rewritten);
* a bound topic not advertised within ``wait`` seconds of connecting, or advertised with a
  schema that cannot be decoded: the requirements reading it are ``error`` (as a topic
  missing from a log in an audit); the others are watched.

Verdict events (:class:`WatchEvent`) are produced while watching: ``pt`` (the past-time
verdict changed), ``ltl3`` (the LTL3 verdict became definite), ``problem``, ``gap`` and, at the
end, ``final`` (one per requirement). ``--jsonl`` prints them; ``--record`` writes them to
the ``/fretc/verdicts`` channel of the recording (foxglove.Log, like ``fretc report
--annotate``) beside every message the watch used.
"""

from __future__ import annotations

import json
import queue
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Callable, Deque, Dict, Iterator, List, Optional, Set, Tuple

import numpy as np

from fretish.units import NS_PER_S

from . import problems as P
from .problems import DataProblem
from .sources import DECODE_ERRORS, LogSource, Message, _Unsupported, header_stamp, schema_decoder

__all__ = ["WatchOptions", "WatchEvent", "WatchSource", "Watch", "CONNECTION_GAP",
           "UNADVERTISED", "CLOCK_BACKWARDS", "NOT_ADVERTISED", "CONNECTION_CLOSED"]

#: The connection dropped: messages between the two log times were not received.
CONNECTION_GAP = "connection_gap"
#: The connection closed and nothing came after it until the watch ended.
CONNECTION_CLOSED = "connection_closed"
#: The server stopped advertising a subscribed topic.
UNADVERTISED = "unadvertised"
#: A message's time is before one already used; skipped.
CLOCK_BACKWARDS = "clock_backwards"
#: A bound topic the server does not advertise.
NOT_ADVERTISED = "not_advertised"


@dataclass
class WatchOptions:
    """How to watch.

    Attributes:
        url: the server (``ws://host:8765``).
        duration: stop after this many seconds of wall time (None: until :meth:`Watch.stop`,
            e.g. on Ctrl-C).
        wait: seconds, after the first connection, to wait for every bound topic to be
            advertised; topics still missing then make their requirements ``error``.
        connect_timeout: seconds to keep trying to connect at all before giving up (None:
            until stopped).
        record: MCAP path to write the watched messages and the verdict events to.
        backoff, max_backoff: reconnection delays (s), doubling.
    """

    url: str
    duration: Optional[float] = None
    wait: float = 3.0
    connect_timeout: Optional[float] = None
    record: Optional[str] = None
    backoff: float = 0.1
    max_backoff: float = 5.0


@dataclass
class WatchEvent:
    """One verdict event.

    Attributes:
        kind: ``pt`` | ``ltl3`` | ``problem`` | ``gap`` | ``final`` | ``connected`` |
            ``disconnected``.
        time_ns: on the run's clock (log time or header stamp), when known.
        wall_ns: wall clock (``time.time_ns()``) when the event was produced.
        requirement: the requirement id (verdict events).
        tick: the tick index (verdict events).
        verdict: ``pt``: ``holds`` / ``violated``; ``ltl3``: ``satisfied`` / ``violated``;
            ``final``: the final verdict.
        detail: free text (problems, gaps).
        depends_on: log time (ns) of the newest message the tick's values came from (the
            latency benchmark's join key).
    """

    kind: str
    time_ns: Optional[int] = None
    wall_ns: int = 0
    requirement: Optional[str] = None
    tick: Optional[int] = None
    verdict: Optional[str] = None
    detail: Optional[str] = None
    depends_on: Optional[int] = None
    extra: Dict[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict:
        out = {"event": self.kind, "time_ns": self.time_ns, "wall_ns": self.wall_ns}
        for k in ("requirement", "tick", "verdict", "detail", "depends_on"):
            val = getattr(self, k)
            if val is not None:
                out[k] = val
        out.update(self.extra)
        return out


# --------------------------------------------------------------------------- the source
class WatchSource(LogSource):
    """Messages of a Foxglove WebSocket server as a :class:`LogSource` (kind ``"watch"``).

    :meth:`messages` blocks on the client's queue and ends when :meth:`stop` is called or
    the deadline passes. Decoders are built from each advertisement's schema. See the module
    docstring for the faults it reports.
    """

    kind = "watch"

    def __init__(self, url: str, client, *, deadline: Optional[float] = None,
                 on_event: Optional[Callable[[WatchEvent], None]] = None,
                 on_message: Optional[Callable[[str, int, bytes], None]] = None) -> None:
        super().__init__(url)
        self.client = client
        self.deadline = deadline
        self.on_event = on_event or (lambda e: None)
        self.on_message = on_message
        self.advertised: Dict[str, Any] = {}  # topic -> Advertised
        self.decoders: Dict[str, Optional[Callable[[bytes], Any]]] = {}
        self.schema_errors: Dict[str, str] = {}
        self.connected = False
        self.ever_connected = False
        self.first_connect_wall: Optional[float] = None
        self.last_reason = ""
        self.gaps: List[Tuple[int, int]] = []  # (last log time before, first after)
        self._gap_open: Optional[Tuple[float, str]] = None  # wall start, reason
        self._last_time: Optional[int] = None
        self._early: Deque[tuple] = deque()
        self._stop = threading.Event()
        self.unadvertised: Set[str] = set()
        self._wanted: Optional[Set[str]] = None

    def stop(self) -> None:
        """End :meth:`messages` (thread-safe; the Ctrl-C handler calls it)."""
        self._stop.set()

    @property
    def stopped(self) -> bool:
        return self._stop.is_set() or (self.deadline is not None
                                       and time.monotonic() >= self.deadline)

    def topics(self) -> Dict[str, str]:
        from rosbags.typesys.msg import normalize_msgtype

        out = {}
        for t, ch in self.advertised.items():
            try:
                out[t] = normalize_msgtype(ch.schema_name) if ch.schema_name else ""
            except Exception:
                out[t] = ch.schema_name
        return dict(sorted(out.items()))

    # -- events -------------------------------------------------------------------------
    def pump(self, timeout: float) -> bool:
        """Handle one event of the client (waiting up to ``timeout`` s); messages are kept
        for :meth:`messages`. False when nothing came."""
        try:
            ev = self.client.events.get(timeout=timeout)
        except queue.Empty:
            return False
        self._handle(ev)
        return True

    def _handle(self, ev: tuple) -> None:
        kind = ev[0]
        if kind == "message":
            self._early.append(ev)
        elif kind == "advertise":
            for ch in ev[2]:
                self.advertised[ch.topic] = ch
                if ch.topic in self.unadvertised:
                    self.unadvertised.discard(ch.topic)
                self._build(ch)
        elif kind == "unadvertise":
            for t in ev[2]:
                self.unadvertised.add(t)
                self._problem(UNADVERTISED, t, self._last_time,
                              "the server stopped advertising this topic; its last message is "
                              "held from here on")
                self.on_event(WatchEvent("problem", self._last_time, ev[1],
                                         detail=f"{UNADVERTISED}: {t}"))
        elif kind == "connected":
            self.connected = self.ever_connected = True
            if self.first_connect_wall is None:
                self.first_connect_wall = time.monotonic()
            self.on_event(WatchEvent("connected", self._last_time, ev[1],
                                     detail=f"subprotocol {ev[2]}"))
        elif kind == "disconnected":
            self.last_reason = ev[2]
            if self.connected:
                self.connected = False
                if self._gap_open is None:
                    self._gap_open = (time.monotonic(), ev[2])
                self.on_event(WatchEvent("disconnected", self._last_time, ev[1],
                                         detail=ev[2]))

    def _build(self, ch) -> None:
        if self._wanted is not None and ch.topic not in self._wanted:
            return
        try:
            self.decoders[ch.topic] = schema_decoder(ch.encoding, ch.schema_encoding,
                                                     ch.schema_name, ch.schema)
            self.schema_errors.pop(ch.topic, None)
        except _Unsupported as exc:
            self.decoders[ch.topic] = None
            kind = P.UNKNOWN_SCHEMA if ch.encoding in ("cdr", "ros1") else P.UNKNOWN_ENCODING
            self.schema_errors[ch.topic] = f"{kind}: {exc}"
            self._problem(kind, ch.topic, self._last_time,
                          f"{exc}; messages on this topic are skipped")

    def want(self, topics: Set[str]) -> None:
        """Decode only ``topics`` from now on (decoders of advertised ones are built)."""
        self._wanted = set(topics)
        for t in topics:
            ch = self.advertised.get(t)
            if ch is not None and t not in self.decoders:
                self._build(ch)

    # -- the stream ------------------------------------------------------------------------
    def messages(self, topics=None) -> Iterator[Message]:
        self.counts = {}
        wanted = None if topics is None else set(topics)
        while True:
            if self._early:
                ev = self._early.popleft()
            else:
                if self.stopped:
                    try:  # what already arrived is still used
                        ev = self.client.events.get_nowait()
                    except queue.Empty:
                        break
                else:
                    try:
                        ev = self.client.events.get(timeout=0.05)
                    except queue.Empty:
                        continue
            if ev[0] != "message":
                self._handle(ev)
                continue
            _k, topic, log_time, payload, wall = ev
            if wanted is not None and topic not in wanted:
                continue
            msg = self._deliver(topic, log_time, payload)
            if msg is not None:
                yield msg
        if self._gap_open is not None and self._last_time is not None:
            # the run ends here: nothing came after the connection closed (the end of the
            # robot's run, or of its network - the watch cannot tell), so no tick is missing
            # from inside the run; reported, not a gap
            wall0, reason = self._gap_open
            self._gap_open = None
            detail = (f"connection lost ({reason}) {time.monotonic() - wall0:.2f} s before the "
                      f"watch ended; nothing was received after log time {self._last_time}: "
                      "the watched run ends there")
            self._problem(CONNECTION_CLOSED, None, self._last_time, detail)
            self.on_event(WatchEvent("problem", self._last_time, time.time_ns(),
                                     detail=f"{CONNECTION_CLOSED}: {detail}"))

    def _deliver(self, topic: str, log_time: int, payload: bytes) -> Optional[Message]:
        dec = self.decoders.get(topic)
        if dec is None:
            return None
        try:
            data = dec(payload)
        except DECODE_ERRORS as exc:
            self._problem(P.UNDECODABLE, topic, log_time,
                          f"payload of {len(payload)} bytes does not deserialize "
                          f"({type(exc).__name__}: {exc}); message skipped")
            self.on_event(WatchEvent("problem", log_time, time.time_ns(),
                                     detail=f"{P.UNDECODABLE}: {topic}"))
            return None
        if self._last_time is not None and log_time < self._last_time:
            self._problem(CLOCK_BACKWARDS, topic, log_time,
                          f"log time {log_time} is {self._last_time - log_time} ns before a "
                          "message already used; message skipped")
            self.on_event(WatchEvent("problem", log_time, time.time_ns(),
                                     detail=f"{CLOCK_BACKWARDS}: {topic}"))
            return None
        if self._gap_open is not None:
            wall0, reason = self._gap_open
            self._gap_open = None
            if self._last_time is not None:
                before = self._last_time
                self.gaps.append((before, log_time))
                wall = time.monotonic() - wall0
                detail = (f"connection lost ({reason}) for {wall:.2f} s of wall time; no "
                          f"message between log times {before} and {log_time} "
                          f"({(log_time - before) / 1e9:.3f} s): ticks inside are not "
                          "evaluated (unknown), the monitors keep their state")
                self._problem(CONNECTION_GAP, None, before, detail, end_time=log_time)
                self.on_event(WatchEvent("gap", before, time.time_ns(), detail=detail,
                                         extra={"end_time_ns": log_time,
                                                "length_s": (log_time - before) / 1e9}))
        self._last_time = log_time
        self.counts[topic] = self.counts.get(topic, 0) + 1
        if self._start_time is None:
            self._start_time = log_time
        self._end_time = log_time
        if self.on_message is not None:
            self.on_message(topic, log_time, payload)
        return Message(topic, log_time, log_time, header_stamp(data), data)


# --------------------------------------------------------------------------- recording
class _Recorder:
    """MCAP of the watched messages (schemas and encodings as advertised) plus the
    ``/fretc/verdicts`` foxglove.Log channel, written at the end."""

    def __init__(self, path: str, source: WatchSource) -> None:
        from mcap.writer import CompressionType, Writer

        self.path = path
        self.source = source
        self._f = open(path, "wb")
        self.writer = Writer(self._f, compression=CompressionType.ZSTD)
        self.writer.start(profile="", library="fretc watch")
        self.channels: Dict[str, int] = {}
        self.seq: Dict[str, int] = {}

    def message(self, topic: str, log_time: int, payload: bytes) -> None:
        cid = self.channels.get(topic)
        if cid is None:
            ch = self.source.advertised[topic]
            sid = self.writer.register_schema(ch.schema_name, ch.schema_encoding,
                                              ch.schema.encode("utf-8"))
            cid = self.writer.register_channel(topic, ch.encoding, sid)
            self.channels[topic] = cid
            self.seq[topic] = 0
        self.writer.add_message(cid, log_time=log_time, data=payload, publish_time=log_time,
                                sequence=self.seq[topic])
        self.seq[topic] += 1

    def finish(self, la) -> int:
        from .annotate import FOXGLOVE_LOG_SCHEMA, VERDICT_TOPIC, verdict_events

        events = verdict_events(la.to_json())
        sid = self.writer.register_schema("foxglove.Log", "jsonschema",
                                          json.dumps(FOXGLOVE_LOG_SCHEMA).encode("utf-8"))
        cid = self.writer.register_channel(VERDICT_TOPIC, "json", sid)
        for i, e in enumerate(sorted(events, key=lambda e: e.time_ns)):
            self.writer.add_message(cid, log_time=int(e.time_ns), publish_time=int(e.time_ns),
                                    data=json.dumps(e.to_json()).encode("utf-8"), sequence=i)
        self.writer.add_metadata("fretc.verdicts",
                                 {v.requirement: v.verdict for v in la.verdicts})
        self.writer.finish()
        self._f.close()
        return len(events)


# --------------------------------------------------------------------------- the engine
class _Live:
    """Per-requirement live state (read by the table)."""

    __slots__ = ("pt", "status", "status_tick", "status_time", "violations", "last_trigger",
                 "first_violation", "error", "offline")

    def __init__(self) -> None:
        self.pt: Optional[bool] = None
        self.status = "unknown"
        self.status_tick: Optional[int] = None
        self.status_time: Optional[int] = None
        self.violations = 0
        self.last_trigger: Optional[int] = None
        self.first_violation: Optional[int] = None
        self.error: Optional[str] = None
        self.offline = False


class Watch:
    """Watch a server against the requirements of ``plan`` (from
    :func:`monitors.audit.load_plan`).

    Args:
        plan: compiled requirements and bindings (bindings are required).
        options: :class:`WatchOptions`.
        on_event: called with every :class:`WatchEvent` (``--jsonl``, the live table).

    :meth:`run` blocks until the duration passes or :meth:`stop` is called, then returns
    the :class:`~monitors.report_model.LogAudit` of the run (``log`` = the URL, ``kind``
    ``"watch"``): final verdicts and evidence exactly as an audit of the same messages.
    """

    #: Seconds between two recomputations of "violations so far" / "last trigger".
    EVIDENCE_EVERY = 1.0

    def __init__(self, plan, options: WatchOptions,
                 on_event: Optional[Callable[[WatchEvent], None]] = None) -> None:
        from .watch_client import FoxgloveClient

        if plan.bindings is None:
            from .audit import AuditInputError
            raise AuditInputError("fretc watch needs signal bindings (*.bindings.toml next to "
                                  "the requirements, --bindings or --bind)")
        self.plan = plan
        self.options = options
        self.on_event = on_event or (lambda e: None)
        self.events: List[WatchEvent] = []
        self.live: Dict[int, _Live] = {r.index: _Live() for r in plan.requirements}
        self.ticks = 0
        self.unknown_ticks = 0
        self.last_tick_time: Optional[int] = None
        self.start_time: Optional[int] = None
        self.status_line = "connecting"
        b = plan.bindings
        self.needed: Set[str] = set()
        for r in plan.requirements:
            if r.error is None:
                for v in r.variables:
                    if v in b.variables:
                        self.needed |= set(b.variables[v].topics)
        if b.tick.topic is not None:
            self.needed.add(b.tick.topic)
        self.client = FoxgloveClient(options.url, lambda t: t in self.needed,
                                     backoff=options.backoff, max_backoff=options.max_backoff)
        deadline = (time.monotonic() + options.duration) if options.duration else None
        self.source = WatchSource(options.url, self.client, deadline=deadline,
                                  on_event=self._event)
        self.recorder: Optional[_Recorder] = None
        self._lock = threading.Lock()
        self._evidence_at = 0.0
        self._cols = {}
        self._group = {}
        self._unknown = {}
        #: called after every evaluated tick's monitors stepped, with (tick index, tick
        #: time, log time of the newest message its values use, log time of the message
        #: whose arrival closed it): the latency benchmark's hook.
        self.on_tick: Optional[Callable[[int, int, Optional[int], Optional[int]], None]] = None

    def stop(self) -> None:
        """Stop watching (thread-safe): :meth:`run` finishes with the final verdicts."""
        self.source.stop()

    def _event(self, e: WatchEvent) -> None:
        with self._lock:
            self.events.append(e)
        if e.kind == "connected":
            self.status_line = f"connected to {self.options.url} ({e.detail})"
        elif e.kind == "disconnected":
            self.status_line = f"disconnected: {e.detail}; retrying"
        self.on_event(e)

    # -- the run -----------------------------------------------------------------------------
    def run(self):
        from .audit import _collect_problems, _restrict
        from .report_model import LogAudit, Verdict
        from .signals import sample

        plan, src = self.plan, self.source
        url = self.options.url
        la = LogAudit(log=url, kind="watch")
        b = plan.bindings
        la.tick = ({"period_ns": b.tick.period_ns} if b.tick.period_ns
                   else {"topic": b.tick.topic})
        la.time_base = b.time_base
        verdicts: Dict[int, Verdict] = {}
        for r in plan.requirements:
            verdicts[r.index] = Verdict(log=url, requirement=r.id, text=r.text,
                                        source=r.source, notes=list(r.notes))
            if r.error is not None:
                verdicts[r.index].error = r.error
        src.want(self.needed)
        self.client.start()
        try:
            self._await_topics()
            if self.options.record:
                self.recorder = _Recorder(self.options.record, src)
                src.on_message = self.recorder.message
            if not src.ever_connected:
                la.error = (f"{url}: could not connect"
                            + (f" ({src.last_reason})" if src.last_reason else ""))
                for v in verdicts.values():
                    v.error = v.error or f"not watched: {la.error}"
                return self._finish(la, verdicts, None)
            active = []
            for r in plan.requirements:
                v = verdicts[r.index]
                if v.error is not None:
                    continue
                missing = [n for n in r.variables if n not in b.variables]
                if missing:
                    v.error = f"no binding for {', '.join(map(repr, missing))} in bindings " \
                              f"({b.source})"
                    continue
                topics = sorted({t for n in r.variables for t in b.variables[n].topics})
                bad = []
                for t in topics:
                    if t not in src.advertised:
                        bad.append(f"topic {t} is not advertised by {url} (it advertises "
                                   f"{', '.join(sorted(src.advertised)) or 'no topics'})")
                    elif src.decoders.get(t) is None:
                        bad.append(f"topic {t} cannot be read "
                                   f"({src.schema_errors.get(t, 'no decoder')})")
                if bad:
                    v.error = "; ".join(bad)
                    continue
                active.append(r)
            for t in sorted(self.needed - set(src.advertised)):
                src._problem(NOT_ADVERTISED, t, None,
                             f"not advertised by {url} within {self.options.wait:g} s of "
                             "connecting")
            for r in plan.requirements:
                if verdicts[r.index].error is not None:
                    self.live[r.index].error = verdicts[r.index].error
            if b.tick.topic is not None and b.tick.topic not in src.advertised:
                la.error = f"the tick topic {b.tick.topic} is not advertised by {url}"
                for r in active:
                    verdicts[r.index].error = la.error
                active = []
            result = None
            if active:
                names = sorted({v for r in active for v in r.variables})
                rb = _restrict(b, names)
                src.want(set(rb.topics) | ({b.tick.topic} if b.tick.topic else set()))
                result = self._run_pass(active, rb)
        finally:
            self.client.stop()
        problems: Dict[Tuple, DataProblem] = {}
        counts: Dict[str, int] = {}
        _collect_problems(src, result.sampling if result is not None else None, problems,
                          counts)
        la.messages = dict(sorted(src.counts.items()))
        la.problems = [{"kind": p.kind, "topic": p.topic, "log_time_ns": p.log_time,
                        "end_time_ns": p.end_time, "detail": p.detail}
                       for p in problems.values()]
        la.problem_counts = dict(sorted(counts.items()))
        if src.gaps:
            la.partial = True
            la.damage_time_ns = src.gaps[0][0]
        return self._finish(la, verdicts, result, active if result is not None else [])

    def _await_topics(self) -> None:
        """Connect, then wait (``options.wait`` s) for the bound topics' advertisements."""
        src, opt = self.source, self.options
        t0 = time.monotonic()
        while not src.stopped:
            if src.ever_connected:
                if self.needed <= set(src.advertised):
                    break
                if time.monotonic() - src.first_connect_wall >= opt.wait:
                    break
            elif opt.connect_timeout is not None and time.monotonic() - t0 >= opt.connect_timeout:
                break
            src.pump(0.05)

    def _run_pass(self, active, bindings):
        """Step the monitors over the live ticks, each requirement on its own clock (the
        topics of its variables, :func:`monitors.signals.sample_groups`, as the audit)."""
        from .audit import _Pass, _clock_key
        from .signals import sample_groups

        src = self.source
        engine = {r.index: ("interval" if r.offline else "stepwise") for r in active}
        monitors = {r.index: r.monitor_cls() for r in active if engine[r.index] == "stepwise"}
        for r in active:
            self.live[r.index].offline = r.offline
        groups: Dict[frozenset, list] = {}
        for r in active:
            groups.setdefault(_clock_key(r, bindings), []).append(r)
        spec = {}
        self._cols = {}
        self._group = {}
        order = {}
        for key, rs in groups.items():
            names: List[str] = []
            for r in rs:
                for v in r.variables:
                    if v not in names:
                        names.append(v)
            spec[key] = (names, key)
            self._cols[key] = _LiveColumns(names, sorted(key))
            order[key] = [(r, monitors.get(r.index), self.live[r.index]) for r in rs]
            for r in rs:
                self._group[r.index] = key
        self._active = active
        self._unknown = {key: 0 for key in groups}
        sampling = sample_groups(src, bindings, spec)
        gaps = src.gaps
        self.status_line = f"watching {self.options.url}"
        for key, tick in sampling:
            t = tick.time
            if gaps and any(a < t < e for a, e in gaps[-4:]):
                self._unknown[key] += 1
                # ticks skipped on the busiest clock (each requirement counts its own)
                self.unknown_ticks = max(self.unknown_ticks, self._unknown[key])
                continue
            vals = tick.values
            cols = self._cols[key]
            i = cols.n
            dep = max(tick.log_times.values()) if tick.log_times else None
            for r, mon, st in order[key]:
                if mon is None or any(v not in vals for v in r.variables):
                    continue
                pt = mon.step(vals)
                if pt != st.pt:
                    if st.pt is not None or not pt:
                        self._event(WatchEvent("pt", t, time.time_ns(), r.id, i,
                                               "holds" if pt else "violated",
                                               depends_on=dep))
                    if not pt and st.first_violation is None:
                        st.first_violation = i
                    st.pt = pt
                if mon.status != st.status:
                    st.status = mon.status
                    st.status_tick = mon.status_tick
                    st.status_time = t
                    self._event(WatchEvent("ltl3", t, time.time_ns(), r.id, i, mon.status,
                                           depends_on=dep,
                                           extra={"status_tick": mon.status_tick}))
            cols.append(tick)
            self.ticks += 1
            if self.on_tick is not None:
                self.on_tick(i, t, dep, src._last_time)
            self.last_tick_time = t
            if self.start_time is None:  # the run's time 0, as in the audit's tables
                self.start_time = (src.start_time if src.start_time is not None
                                   else sampling.groups[key].start_time)
        passes = {}
        for key in groups:
            times, columns, log_times = self._cols[key].arrays()
            passes[key] = _Pass(sampling.groups[key], times, columns, log_times, monitors,
                                engine)
        self._live_evidence()
        return _WatchPasses(sampling, {r.index: passes[self._group[r.index]] for r in active},
                            sampling.failed, self._group)

    def tick_times(self, index: int):
        """Tick times seen so far on the clock of the requirement at ``index``."""
        cols = (getattr(self, "_cols", None) or {}).get(getattr(self, "_group", {}).get(index))
        return cols.times if cols is not None else []

    def refresh_evidence(self) -> None:
        """Update "violations so far" and "last trigger" of the live table (at most every
        :data:`EVIDENCE_EVERY` s; called by the table's refresh thread, so the monitors are
        never held up by it)."""
        now = time.monotonic()
        if now - self._evidence_at < self.EVIDENCE_EVERY or getattr(self, "_cols", None) is None:
            return
        self._evidence_at = now
        try:
            self._live_evidence()
        except Exception:  # a display helper: never let it stop the watch
            pass

    def _live_evidence(self) -> None:
        """Violations so far and the last trigger, by the audit's interval semantics over
        the ticks seen (:func:`monitors.evidence.evaluate_requirement`)."""
        from .evidence import evaluate_requirement

        arrays = {}
        for key, cols in self._cols.items():
            if cols.n:
                arrays[key] = (cols.n, cols.arrays(cols.n)[1])
        for r in self._active:
            if self._group.get(r.index) not in arrays:
                continue
            n, columns = arrays[self._group[r.index]]
            st = self.live[r.index]
            try:
                ev = evaluate_requirement(r.requirement, columns, n, r.formalization.ticks)
            except Exception:  # evidence unsupported for this requirement: pt only
                continue
            st.violations = ev.violations or 0
            trig = None
            for x in getattr(ev, "listed", ()) or ():
                trig = x.trigger_tick
            if ev.violation is not None and trig is None:
                trig = ev.violation.trigger_tick
            st.last_trigger = trig

    def _finish(self, la, verdicts, result, active=()):
        from .audit import _finalize, _operand_values

        if result is not None:
            src = self.source
            groups = [res.sampling for res in result.by_req.values()]
            starts = [g.start_time for g in groups if g.start_time is not None]
            la.start_time_ns = (src.start_time if src.start_time is not None
                                else (min(starts) if starts else None))
            ends = [g.end_time for g in groups if g.end_time is not None]
            la.end_time_ns = max(ends) if ends else None
            la.missing_topics = sorted({t for g in groups for t in g.missing_topics})
            la.engine = "stepwise"
            ok = []
            for r in active:
                res = result.by_req[r.index]
                g, v = res.sampling, verdicts[r.index]
                unknown = self._unknown.get(self._group[r.index], 0)
                v.ticks_evaluated = g.ticks - unknown
                v.warmup_ticks = g.warmup_ticks
                v.first_tick_ns, v.last_tick_ns = g.first_time, g.end_time
                v.waiting_for = list(g.waiting_for)
                bad = [n for n in r.variables
                       if n in result.failed.get(self._group[r.index], {})]
                if bad:
                    v.error = str(result.failed[self._group[r.index]][bad[0]])
                    continue
                if g.missing_topics:
                    v.error = "; ".join(f"topic {t} has no message in the run"
                                        for t in g.missing_topics)
                    continue
                _finalize(self.plan, r, res, self.plan.bindings, v, la)
                ok.append(r)
                if unknown:
                    v.notes.append(f"{unknown} ticks inside connection gaps were not "
                                   "evaluated (unknown)")
            if ok:
                la.ticks_evaluated = max(verdicts[r.index].ticks_evaluated for r in ok)
                la.warmup_ticks = max(verdicts[r.index].warmup_ticks for r in ok)
                firsts = [verdicts[r.index].first_tick_ns for r in ok
                          if verdicts[r.index].first_tick_ns is not None]
                la.first_time_ns = min(firsts) if firsts else None
                la.waiting_for = sorted({t for r in ok for t in verdicts[r.index].waiting_for})
            active = ok
        la.verdicts = [verdicts[r.index] for r in self.plan.requirements]
        for v in la.verdicts:
            if v.error is not None:
                v.verdict = "error"
            v.partial = la.partial
        if self.recorder is not None:
            self.recorder.finish(la)
            if result is not None and not self.source.gaps:
                # the numbers behind violated boolean variables: the audit's second pass,
                # over the recording
                _operand_values(self.recorder.path, self.plan, self.plan.bindings,
                                list(active), verdicts, result.by_req)
        for v in la.verdicts:
            e = WatchEvent("final", la.end_time_ns, time.time_ns(), v.requirement,
                           verdict=v.verdict,
                           detail=v.error,
                           extra={"ltl3": v.ltl3.status, "violations": v.violations})
            self._event(e)
        return la


@dataclass
class _WatchPasses:
    """The watch's ticks, one :class:`monitors.audit._Pass` per requirement's clock."""

    sampling: Any
    by_req: Dict[int, Any]
    failed: Dict[Any, Dict[str, Any]]
    group: Dict[int, Any]


class _LiveColumns:
    """Per-tick values, times and held log times kept while watching (the audit's columns,
    as growing lists; :meth:`arrays` gives numpy views of everything so far)."""

    def __init__(self, names: List[str], topics: List[str]) -> None:
        self.names = names
        self.topics = topics
        self.n = 0
        self.vals: Dict[str, list] = {n: [] for n in names}
        self.lts: Dict[str, list] = {t: [] for t in topics}
        self.times: list = []

    def append(self, tick) -> None:
        v = tick.values
        for name in self.names:
            self.vals[name].append(v[name])
        lt = tick.log_times
        for t in self.topics:
            self.lts[t].append(lt.get(t, -1))
        self.times.append(tick.time)
        self.n += 1

    def arrays(self, n: Optional[int] = None):
        """(times, variable -> values, topic -> held log times) of the first ``n`` ticks
        (all by default; a snapshot of ``n`` taken first is safe while another thread
        appends)."""
        n = self.n if n is None else n
        def arr(values):
            if values and all(type(x) is bool for x in values):
                return np.array(values, dtype=np.bool_)
            if not values:
                return np.zeros(0, dtype=np.bool_)
            return np.array(values, dtype=np.float64)

        times = np.array(self.times[:n], dtype=np.int64)
        cols = {k: arr(v[:n]) for k, v in self.vals.items()}
        lts = {t: np.array(v[:n], dtype=np.int64) for t, v in self.lts.items()}
        return times, cols, lts
