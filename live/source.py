"""The watched run as a log: :class:`WatchSource`, a :class:`fretc.logs.LogSource`
whose messages come from a Foxglove WebSocket server, and the verdict events
(:class:`WatchEvent`). The recording of a watch is :mod:`fretc.live.record`.

Faults are data problems of the run, never a crash: a dropped connection
(:data:`CONNECTION_GAP`), a publisher that left (:data:`PUBLISHER_RESTART`), a message that
does not decode (:data:`UNDECODABLE_GAP`), a clock going backwards (:data:`CLOCK_BACKWARDS`),
a frame of the wrong shape (:data:`PROTOCOL`), a log time out of range (:data:`TIME_RANGE`);
the ticks they leave are unknown, never held over. The end of the run is
:attr:`WatchSource.end_reason`. Each fault and end in full: ARCHITECTURE.md ("The watched
run as a log").
"""

from __future__ import annotations

import queue
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from rosbags.typesys.msg import normalize_msgtype

from fretc.common import problems as P
from fretc.logs import DECODE_ERRORS, LogSource, Message, _Unsupported, header_stamp, schema_decoder
from fretc.live.absence import Absences
from fretc.live.watch_event import WatchEvent

__all__ = ["WatchEvent", "WatchSource", "CONNECTION_GAP", "UNADVERTISED",
           "CLOCK_BACKWARDS", "NOT_ADVERTISED", "CONNECTION_CLOSED", "PROTOCOL", "TIME_RANGE",
           "PUBLISHER_RESTART", "PUBLISHERS_LEFT", "QUEUE_OVERFLOW", "SCHEMA_TOO_LARGE",
           "MAX_SCHEMA_BYTES", "RESTART_GRACE", "UNDECODABLE_GAP"]

#: The connection dropped: messages between the two log times were not received.
CONNECTION_GAP = "connection_gap"
#: A message of a watched topic was received but could not be decoded: a gap from the last
#: message used to the next one.
UNDECODABLE_GAP = "undecodable_gap"
#: The connection closed and nothing came after it until the watch ended.
CONNECTION_CLOSED = "connection_closed"
#: The server stopped advertising a subscribed topic.
UNADVERTISED = "unadvertised"
#: A message's time is before one already used; skipped.
CLOCK_BACKWARDS = "clock_backwards"
#: A bound topic the server does not advertise.
NOT_ADVERTISED = "not_advertised"
#: A frame of the wrong shape for the protocol; ignored.
PROTOCOL = "protocol"
#: A message's log time is outside the range the watch can tick on; skipped.
TIME_RANGE = "time_range"
#: A bound topic was unadvertised and advertised again (its publisher restarted) over a
#: client that subscribes again after the new advertisement: messages the new publisher
#: sent before that may not have been received.
PUBLISHER_RESTART = "publisher_restart"
#: Every publisher of the bound topics left (unadvertised) and none came back within the
#: grace period, before the watch's end: the run was cut short.
PUBLISHERS_LEFT = "publishers_left"
#: Messages dropped from the bounded queue because the watch fell behind the server.
QUEUE_OVERFLOW = "queue_overflow"
#: An advertised schema over :data:`MAX_SCHEMA_BYTES`: its topic is not read.
SCHEMA_TOO_LARGE = "schema_too_large"
#: Log times are int64 nanoseconds from here on (numpy columns, the clocks' grid).
TIME_LIMIT = 2**63
#: The largest advertised schema text parsed (bytes of UTF-8): message definitions of real
#: robots are a few kB; parsing costs about 30 us a line, so this bounds one parse near 1 s.
MAX_SCHEMA_BYTES = 1024 * 1024
#: Seconds the watch still reads what had already arrived after it was stopped or its
#: duration passed (a backlog is not drained without end).
DRAIN_SECONDS = 1.0
#: Seconds a restarting publisher has to advertise its topic again (``--restart-grace``).
RESTART_GRACE = 2.0


# --------------------------------------------------------------------------- the source
class WatchSource(LogSource):
    """Messages of a Foxglove WebSocket server as a :class:`LogSource` (kind ``"watch"``).

    :meth:`messages` blocks on the client's queue and ends when :meth:`stop` is called or
    the deadline passes. Decoders are built from each advertisement's schema. See the module
    docstring for the faults it reports.
    """

    kind = "watch"

    def __init__(self, url: str, client, *, deadline: float | None = None,
                 idle: float | None = None,
                 on_event: Callable[[WatchEvent], None] | None = None,
                 on_message: Callable[[str, int, bytes], None] | None = None,
                 restart_grace: float = RESTART_GRACE) -> None:
        super().__init__(url)
        self.restart_grace = restart_grace
        #: topic -> the message type the bindings' ``[types]`` declare (``--topic-type``)
        self.declared_types: dict[str, str] = {}
        #: monotonic time at which every subscribed topic was unadvertised (None: some is
        #: advertised)
        self._all_left_at: float | None = None
        #: the run ended because every bound publisher left before the watch's end
        self.publishers_left = False
        self.client = client
        self.deadline = deadline
        self.idle = idle
        self.end_reason: str | None = None
        self._ended = False
        self._server_ended = False  # the server ended the run (close, all unadvertised)
        self._last_wall: float | None = None  # monotonic time of the last message used (--until-idle counts from the first)
        self._pending_unadvertised: list[tuple[str, int | None]] = []
        self.on_event = on_event or (lambda e: None)
        self.on_message = on_message
        #: topics whose messages are used (:attr:`on_message`) even when the iteration of
        #: :meth:`messages` does not ask for them (a watch's per-entity requirements)
        self.keep: set[str] = set()
        self.advertised: dict[str, Any] = {}  # topic -> Advertised
        self.decoders: dict[str, Callable[[bytes], Any] | None] = {}
        self.schema_errors: dict[str, str] = {}
        self.connected = False
        self.ever_connected = False
        self.first_connect_wall: float | None = None
        self.last_reason = ""
        #: connection attempts that failed before the first connection (an ``unreachable``
        #: event each: no server, or not yet)
        self.failed_connects = 0
        # (last log time before, first after): a connection's gaps, not a log's Gap records
        self.gaps: list[tuple[int, int]] = []  # type: ignore[assignment]  # (the pairs above)
        #: the run ended inside an undecodable gap: the last log time used before it
        self.lost_after: int | None = None
        self.undecodable_end: int | None = None
        self._gap_open: tuple[float, str, str] | None = None  # wall start, reason, kind
        self._last_time: int | None = None
        self._early: deque[tuple] = deque()
        self._stop = threading.Event()
        self.unadvertised: set[str] = set()
        self._wanted: set[str] | None = None
        #: the longest jump of log time (ns) from one message used to the next; None: no
        #: bound (the watch sets it from the tick period)
        self.max_jump_ns: int | None = None
        self._reported: dict[str, int] = {}  # problem events sent per kind (capped)
        #: the bound topics' spans without a publisher (:mod:`fretc.live.absence`)
        self.absent = Absences()
        #: bound topics not advertised yet that the run waits for (the watch sets them)
        self.awaited: set[str] = set()
        #: per topic, its last payload and the message decoded from it: a message of the
        #: same bytes is that message again (read-only: no binding changes a message), not
        #: decoded again (a robot's commands and flags repeat at tens of kHz)
        self._decoded: dict[str, tuple[bytes, Any]] = {}
        #: called with each topic advertised for the first time (the watch's late checks)
        self.on_advertised: Callable[[str], None] | None = None
        self._delivered = 0

    def stop(self) -> None:
        """End :meth:`messages` (thread-safe; the Ctrl-C handler calls it)."""
        self._stop.set()

    @property
    def stopped(self) -> bool:
        """The run ended: stopped, past the deadline, idle too long, closed by the server or
        every subscribed topic unadvertised (:attr:`end_reason` says which)."""
        if self._ended:
            return True
        now = time.monotonic()
        if self._stop.is_set():
            self._end("stopped")
        elif self.deadline is not None and now >= self.deadline:
            self._end("the watch's duration passed")
        elif (self.idle is not None and self._last_wall is not None
              and now - self._last_wall >= self.idle):
            self._end(f"no message for {self.idle:g} s")
        elif (self._all_left_at is not None
              and now - self._all_left_at >= self.restart_grace):
            self._publishers_left()
        return self._ended

    def _publishers_left(self) -> None:
        """Every subscribed topic stayed unadvertised for the grace period: the run ends.
        Under ``--until-idle`` (:attr:`idle` set), and on transports without a close of their
        own (DDS, Zenoh: the client's ``leaving_ends_run``), that is the run's end; otherwise
        the watch was cut short (:data:`PUBLISHERS_LEFT`, the watch's partial end)."""
        self._server_ended = True
        grace = f"{self.restart_grace:g} s"
        if self.idle is not None or getattr(self.client, "leaving_ends_run", False):
            self._end("every publisher of the bound topics left (unadvertised; none came back "
                      f"within {grace})")
            return
        self.publishers_left = True
        detail = ("every publisher of the bound topics left (unadvertised) and none came back "
                  f"within {grace}, before the watch's end: the run was cut short here "
                  "(--until-idle takes such an end as the run's)")
        self._report(PUBLISHERS_LEFT, None, self._last_time, detail)
        self._end(detail)

    def _end(self, reason: str) -> None:
        if not self._ended:
            self._ended = True
            self.end_reason = reason

    def topics(self) -> dict[str, str]:
        """Advertised topic -> its message type (ROS name); a bound topic the watch still
        awaits (:attr:`awaited`: not advertised yet, any start order) is there with no type,
        as a topic of a log whose first message is still to come."""
        out = dict.fromkeys(self.awaited, "")
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
                first = ch.topic not in self.advertised
                self.advertised[ch.topic] = ch
                if ch.topic in self.unadvertised:
                    self.unadvertised.discard(ch.topic)
                    self._readvertised(ch)
                self._build(ch)
                if first and self.on_advertised is not None:
                    self.on_advertised(ch.topic)
        elif kind == "unadvertise":
            for t in ev[2]:
                self.unadvertised.add(t)
                # a problem only if the run goes on without it (_flush_unadvertised)
                self._pending_unadvertised.append((t, self._last_time))
                if self._wanted is None or t in self._wanted:
                    self.absent.left(t, self._last_time, self._delivered)
            subscribed = set(self.advertised) & (self._wanted or set(self.advertised))
            if subscribed and subscribed <= self.unadvertised and self._all_left_at is None:
                self._all_left_at = time.monotonic()  # ends the run after the grace period
                if self.restart_grace <= 0:
                    self._publishers_left()
        elif kind == "protocol":
            self._report(PROTOCOL, None, self._last_time, f"{ev[2]} (from {self.path})")
        elif kind == "gave_up":
            self.last_reason = ev[2]
            self._report(PROTOCOL, None, self._last_time, ev[2])
            self._end(ev[2])
        elif kind == "closed":
            self.connected = False
            self.last_reason = ev[2]
            self._server_ended = True
            self._end(ev[2])
            self.on_event(WatchEvent("closed", self._last_time, ev[1], detail=ev[2]))
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
                    self._gap_open = (time.monotonic(), ev[2], CONNECTION_GAP)
                self.on_event(WatchEvent("disconnected", self._last_time, ev[1],
                                         detail=ev[2]))
            elif not self.ever_connected:  # no server (yet): said at once, then counted
                self.failed_connects += 1
                self.on_event(WatchEvent("unreachable", None, ev[1],
                                         detail=f"cannot connect to {self.path}: {ev[2]}",
                                         extra={"attempts": self.failed_connects}))

    def _readvertised(self, ch) -> None:
        """A topic advertised again after it was unadvertised (its publisher restarted, as
        foxglove_bridge shows a node restart: a new channel id): the same run goes on; the
        topic's span without a publisher (:attr:`absent`) lasts until its next message, and
        its ticks are not evaluated for the requirements that read it, never held over."""
        self._all_left_at = None
        self._pending_unadvertised = [(t, at) for t, at in self._pending_unadvertised
                                      if t != ch.topic]
        span = self.absent.open_span(ch.topic)
        if span is not None:
            span.append(ch.id)  # advertised again: the channel it came back on

    def left_for_good(self, topics: Iterable[str]) -> int | None:
        """:meth:`fretc.live.absence.Absences.left_for_good` of this run."""
        return self.absent.left_for_good(topics, self._delivered)

    @property
    def hears_new_publishers(self) -> bool:
        """Whether the client reads a topic's new publisher from its first message (DDS,
        Zenoh: the span without a publisher is a silence), or subscribes again after its
        advertisement (WebSocket: a restart may lose messages; :mod:`fretc.live.absence`)."""
        return bool(getattr(self.client, "hears_new_publishers", False))

    def _report(self, kind: str, topic: str | None, log_time: int | None,
                detail: str, record: bool = True) -> None:
        """A data problem and its ``problem`` event (events capped per kind at
        :data:`fretc.common.problems.MAX_PROBLEMS_PER_KIND`, as the problems kept; all counted).
        ``record`` False: the event alone (the problem is counted elsewhere, as a message
        lost: :meth:`_skipped`)."""
        if record:
            self._problem(kind, topic, log_time, detail)
        n = self._reported.get(kind, 0)
        if n < P.MAX_PROBLEMS_PER_KIND:
            self._reported[kind] = n + 1
            self.on_event(WatchEvent("problem", log_time, time.time_ns(),
                                     detail=f"{kind}: {detail}" if topic is None
                                     else f"{kind}: {topic}"))

    def _build(self, ch) -> None:
        if self._wanted is not None and ch.topic not in self._wanted:
            return
        size = len(ch.schema.encode("utf-8", "surrogatepass"))
        if size > MAX_SCHEMA_BYTES:
            self.decoders[ch.topic] = None
            why = (f"its advertised schema is {size:,} bytes, over the {MAX_SCHEMA_BYTES:,} "
                   "bytes read; messages on this topic are skipped")
            self.schema_errors[ch.topic] = f"{SCHEMA_TOO_LARGE}: {why}"
            self._report(SCHEMA_TOO_LARGE, ch.topic, self._last_time, why)
            return
        unreadable = ch.unreadable or self._type_mismatch(ch)
        if unreadable:
            self.decoders[ch.topic] = None
            self.schema_errors[ch.topic] = f"{P.UNKNOWN_SCHEMA}: {unreadable}"
            self._problem(P.UNKNOWN_SCHEMA, ch.topic, self._last_time,
                          f"{unreadable}; messages on this topic are skipped")
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

    def _type_mismatch(self, ch) -> str | None:
        """Why a channel advertised with another message type than the bindings' ``[types]``
        declare for its topic is not read (its fields would be read under the wrong names or
        types), or None."""
        declared = self.declared_types.get(ch.topic)
        if not declared or not ch.schema_name:
            return None
        try:
            same = normalize_msgtype(declared) == normalize_msgtype(ch.schema_name)
        except Exception:  # noqa: BLE001 - a name rosbags cannot normalize: compare as written
            same = declared == ch.schema_name
        return None if same else (f"advertised as {ch.schema_name}, but the bindings' [types] "
                                  f"declare {declared}")

    def want(self, topics: set[str]) -> None:
        """Decode only ``topics`` from now on (decoders of advertised ones are built)."""
        self._wanted = set(topics)
        for t in topics:
            ch = self.advertised.get(t)
            if ch is not None and t not in self.decoders:
                self._build(ch)

    # -- the stream ------------------------------------------------------------------------
    def messages(self, topics: Iterable[str] | None = None) -> Iterator[Message]:
        """The watched messages of ``topics`` (all wanted by default) as they arrive,
        until stopped."""
        self.counts = {}
        wanted = None if topics is None else set(topics)
        drain_until = None
        while True:
            if self._early:
                ev = self._early.popleft()
            else:
                if self.stopped:
                    if self.publishers_left:
                        break  # cut short there: what comes after is not this run's
                    # what already arrived is still used, for DRAIN_SECONDS at most
                    now = time.monotonic()
                    drain_until = drain_until or now + DRAIN_SECONDS
                    try:
                        if now >= drain_until:
                            raise queue.Empty
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
                if topic in self.keep:  # used (recorded), read by no clock of this pass
                    self._deliver(topic, log_time, payload)
                continue
            msg = self._deliver(topic, log_time, payload)
            if msg is not None:
                yield msg
        if not self._server_ended:
            # the watch ended with some topics unadvertised and the run going on: reported
            self._flush_unadvertised()
        if (self._gap_open is not None and self._gap_open[2] == UNDECODABLE_GAP
                and self._last_time is not None):
            # messages were lost at the end of the run: judged up to the last one used
            _w, reason, _k = self._gap_open
            self._gap_open = None
            self.lost_after = self._last_time
            detail = (f"{reason}; nothing decodable came after it until the watch ended: the "
                      f"run is judged up to log time {self._last_time}")
            self._problem(UNDECODABLE_GAP, None, self._last_time, detail,
                          end_time=self.undecodable_end)
            self.on_event(WatchEvent("gap", self._last_time, time.time_ns(), detail=detail))
        if self._gap_open is not None and self._last_time is not None:
            # the run ends here: nothing came after the connection closed (the end of the
            # robot's run, or of its network - the watch cannot tell), so no tick is missing
            # from inside the run; reported, not a gap
            wall0, reason, kind = self._gap_open
            self._gap_open = None
            what = f"connection lost ({reason})" if kind == CONNECTION_GAP else reason
            detail = (f"{what} {time.monotonic() - wall0:.2f} s before the "
                      f"watch ended; nothing was received after log time {self._last_time}: "
                      "the watched run ends there")
            self._problem(CONNECTION_CLOSED, None, self._last_time, detail)
            self.on_event(WatchEvent("problem", self._last_time, time.time_ns(),
                                     detail=f"{CONNECTION_CLOSED}: {detail}"))

    def _skipped(self, topic: str, log_time: int, kind: str, why: str,
                 at: int | None) -> None:
        """A message of ``topic`` received but not used: a ``kind`` problem, and what it
        said is not known, so nothing is judged as if it had not been sent. A message
        whose log time is before one already used (``at``: its log time; a clock reset)
        is a message lost at that log time (:meth:`fretc.logs.base.LogSource.lost_gaps`,
        as an offline log's message out of order): the ticks its value would have held at
        are unknown, never a pass over it. One whose time cannot be placed (``at`` None)
        opens a gap from the last message used to the next one, as a message not
        decoded. Either is one ``kind`` problem per message (a message lost is counted as
        one, :attr:`fretc.logs.LogSource.problem_counts`, never again as reported)."""
        self._report(kind, topic, at, f"{why}; its value is not held over it",
                     record=at is None)
        if at is not None:
            self._lose(kind, topic, None, at, why)
        elif self._gap_open is None:
            self._gap_open = (time.monotonic(), f"a message of {topic} at log time {log_time} "
                              f"was skipped ({kind})", UNDECODABLE_GAP)

    def _undecodable(self, topic: str, log_time: int, why: str) -> None:
        """A message of ``topic`` that was received but not decoded: an ``undecodable``
        problem (counted per message) and a gap up to the next message used."""
        self._report(P.UNDECODABLE, topic, log_time,
                     f"{why}; message lost: its value is not held over it")
        if self._gap_open is None:
            self._gap_open = (time.monotonic(), f"a message of {topic} at log time "
                              f"{log_time} could not be decoded", UNDECODABLE_GAP)
        self.undecodable_end = log_time

    def _dropped_gap(self) -> None:
        """Messages the bounded queue dropped (:mod:`fretc.live.events`) open a gap up to the next
        message used: the watch fell behind, and what it did not read is not held over."""
        take = getattr(self.client.events, "take_dropped", None)
        dropped = take() if take is not None else None
        if not dropped:
            return
        n = sum(c for c, _a, _b in dropped.values())
        for topic, (count, first, last) in sorted(dropped.items()):
            self._report(QUEUE_OVERFLOW, topic, first,
                         f"{count} message(s) between log times {first} and {last} dropped: "
                         "the watch fell behind the server (its queue is bounded)")
        if self._gap_open is None:
            self._gap_open = (time.monotonic(), f"{n} message(s) dropped from the full queue",
                              QUEUE_OVERFLOW)

    def _flush_unadvertised(self) -> None:
        """The run went on after topics were unadvertised: each is a ``publisher`` event
        (:data:`UNADVERTISED`), no data problem: with no publisher nothing was sent."""
        for t, at in self._pending_unadvertised:
            held = ("its values are not held: ticks after it are not evaluated for the "
                    "requirements that read them until its next message; the time since its "
                    "last message (age) is known"
                    if self._wanted is None or t in self._wanted else "no requirement reads it")
            self.on_event(WatchEvent("publisher", at, time.time_ns(),
                                     detail=f"{UNADVERTISED}: {t}: the server stopped "
                                     f"advertising it (its publisher left); {held}"))
        self._pending_unadvertised.clear()

    def _time_problem(self, topic: str, log_time: int) -> str | None:
        """Why ``log_time`` cannot be ticked on (module docstring), or None."""
        if not 0 <= log_time < TIME_LIMIT:
            return (f"log time {log_time} ns is outside [0, 2**63) ns, the range of the "
                    "watch's clocks; message skipped")
        last, jump = self._last_time, self.max_jump_ns
        if last is not None and jump is not None and log_time - last > jump:
            return (f"log time {log_time} ns is {(log_time - last) / 1e9:.6g} s after the "
                    f"last message used, more than the {jump / 1e9:.6g} s the watch ticks "
                    "over at once; message skipped")
        return None

    def _deliver(self, topic: str, log_time: int, payload: bytes) -> Message | None:
        self._last_wall = time.monotonic()
        if self._pending_unadvertised:
            self._flush_unadvertised()
        dec = self.decoders.get(topic)
        if dec is None:
            if topic in self.schema_errors and (self._wanted is None or topic in self._wanted):
                self._undecodable(topic, log_time, f"payload of {len(payload)} bytes on a "
                                  f"channel whose schema could not be read "
                                  f"({self.schema_errors[topic]})")
            return None
        why = self._time_problem(topic, log_time)
        if why is not None:
            self._skipped(topic, log_time, TIME_RANGE, why, None)
            return None
        last = self._decoded.get(topic)
        if last is not None and last[0] == payload:
            data = last[1]  # the same bytes as the topic's last message: the same message
        else:
            try:
                data = dec(payload)
            except DECODE_ERRORS as exc:
                self._undecodable(topic, log_time, f"payload of {len(payload)} bytes does not "
                                  f"deserialize ({type(exc).__name__}: {exc})")
                return None
            self._decoded[topic] = (payload, data)
        if self._last_time is not None and log_time < self._last_time:
            self._skipped(topic, log_time, CLOCK_BACKWARDS,
                          f"log time {log_time} is {self._last_time - log_time} ns before a "
                          "message already used (a clock reset?); message skipped", log_time)
            return None
        self._dropped_gap()
        if self._gap_open is not None:
            wall0, reason, kind = self._gap_open
            self._gap_open = None
            if self._last_time is not None:
                before = self._last_time
                self.gaps.append((before, log_time))
                wall = time.monotonic() - wall0
                what = (f"connection lost ({reason}) for {wall:.2f} s of wall time"
                        if kind == CONNECTION_GAP else reason)
                detail = (f"{what}; no "
                          f"message between log times {before} and {log_time} "
                          f"({(log_time - before) / 1e9:.3f} s): ticks inside are not "
                          "evaluated (unknown), the monitors keep their state")
                self._problem(kind, None, before, detail, end_time=log_time)
                self.on_event(WatchEvent("gap", before, time.time_ns(), detail=detail,
                                         extra={"end_time_ns": log_time,
                                                "length_s": (log_time - before) / 1e9}))
        back = self.absent.back(topic, log_time, self.hears_new_publishers)
        if back is not None:  # its publisher had left: the span without it is reported
            if not self.hears_new_publishers:  # (a silence loses nothing: no data problem)
                self._problem(PUBLISHER_RESTART, topic, back[0], back[1], end_time=log_time)
            self.on_event(WatchEvent("gap" if not self.hears_new_publishers else "publisher",
                                     back[0], time.time_ns(), detail=back[1],
                                     extra={"end_time_ns": log_time}))
        self._last_time = log_time
        self._delivered += 1
        self.counts[topic] = self.counts.get(topic, 0) + 1
        if self._start_time is None:
            self._start_time = log_time
        self._end_time = log_time
        if self.on_message is not None:
            self.on_message(topic, log_time, payload)
        return Message(topic, log_time, log_time, header_stamp(data), data)
