"""A client of the Foxglove WebSocket protocol (the one ``foxglove_bridge`` and
``foxglove-sdk`` serve), run in a background thread, that hands what it receives to the
watch engine through a queue.

Protocol (github.com/foxglove/ws-protocol, ``docs/spec.md``; ``foxglove-sdk`` servers speak
the same messages under the subprotocol ``foxglove.sdk.v1``):

* the client offers the subprotocols ``foxglove.websocket.v1`` and ``foxglove.sdk.v1``; the
  server picks one (a server that picks none is refused);
* the server sends JSON text frames: ``serverInfo``, ``advertise`` (``channels``: ``id``,
  ``topic``, ``encoding``, ``schemaName``, ``schema``, ``schemaEncoding``), ``unadvertise``
  (``channelIds``), ``status``;
* the client sends ``subscribe`` (``subscriptions``: ``id`` chosen by the client,
  ``channelId``) and ``unsubscribe``;
* message data arrive as binary frames: opcode ``0x01``, subscription id (uint32 LE), log
  time (uint64 LE, ns), then the payload in the channel's encoding.

A dropped connection is retried with exponential backoff (``backoff`` doubling up to
``max_backoff`` seconds); subscriptions are made again from the new advertisements.

Events put on :attr:`FoxgloveClient.events` (a :class:`queue.Queue`), each a tuple whose
first item names it:

* ``("connected", wall_ns, subprotocol, server_name)``
* ``("advertise", wall_ns, [Advertised, ...])``
* ``("unadvertise", wall_ns, [topic, ...])``
* ``("message", topic, log_time_ns, payload_bytes, wall_ns)``
* ``("disconnected", wall_ns, reason)`` (also when a connection attempt fails)
* ``("closed", wall_ns, reason)``: the server closed the connection in order (a WebSocket
  close frame, RFC 6455 section 5.5.1: the end of its run, e.g. ``fretc replay --serve``
  finishing); not retried
* ``("status", wall_ns, level, text)``
* ``("protocol", wall_ns, detail)``: a frame of the wrong shape (valid JSON that is not an
  object, a field of the wrong type, a truncated ``messageData``, more channels than
  :data:`MAX_OTHER_CHANNELS` no requirement reads): ignored, the session goes on
* ``("gave_up", wall_ns, reason)``: :data:`MAX_HOSTILE_SESSIONS` connections in a row sent
  frames of the wrong shape and dropped without a message: not retried

Needs ``websockets`` (the ``watch`` extra): :func:`require_websockets` says so in one line.
"""

from __future__ import annotations

import asyncio
import json
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from fretc.live.events import EventQueue

__all__ = ["SUBPROTOCOLS", "Advertised", "FoxgloveClient", "WebSocketClient", "WATCH_HINT",
           "MissingDependency", "require_websockets", "MAX_OTHER_CHANNELS",
           "MAX_HOSTILE_SESSIONS", "frame_shape", "json_object"]

#: Channels no requirement reads kept per connection (their topics name what a server
#: advertises in errors); more are counted in one ``protocol`` event, not kept.
MAX_OTHER_CHANNELS = 1000
#: Connections in a row that sent a frame of the wrong shape and then dropped before any
#: message after which the client stops retrying (``gave_up``).
MAX_HOSTILE_SESSIONS = 5
#: The largest WebSocket message accepted (bytes): a larger one closes the connection (code
#: 1009, "message too big"), which is reported and retried like any disconnection. Big enough
#: for camera images and point clouds; a bound so that one frame cannot take all memory.
MAX_FRAME_BYTES = 256 * 1024 * 1024

#: What to install for the live commands (``fretc watch``, ``fretc replay --serve``).
WATCH_HINT = "pip install 'fretc[watch]'"


class MissingDependency(RuntimeError):
    """An optional dependency of the live commands is not installed (the message names
    :data:`WATCH_HINT`)."""


def require_websockets() -> None:
    """Raise :class:`MissingDependency` when ``websockets`` cannot be imported."""
    import importlib.util  # lazy: only when a watch starts

    if importlib.util.find_spec("websockets") is None:
        raise MissingDependency(f"fretc watch needs the websockets package: {WATCH_HINT}")


def closed_in_order(ws: Any) -> bool:  # a websockets connection, new or legacy
    """The server sent a close frame (RFC 6455 section 5.5.1) before the connection ended:
    an orderly close, not a network fault. Works with websockets' new (``protocol``) and
    legacy (``close_rcvd``) connection objects."""
    proto = getattr(ws, "protocol", None)
    rcvd = getattr(proto, "close_rcvd", None) if proto is not None else None
    if rcvd is None:
        rcvd = getattr(ws, "close_rcvd", None)
    return rcvd is not None

#: Subprotocols offered, in order of preference.
SUBPROTOCOLS = ("foxglove.websocket.v1", "foxglove.sdk.v1")
_MESSAGE_DATA = 0x01
_HEAD = struct.Struct("<BIQ")  # opcode, subscription id, log time


@dataclass(frozen=True)
class Advertised:
    """One advertised channel: server channel ``id``, ``topic``, message ``encoding``
    (``cdr``, ``ros1``, ``json``, ...), ``schema_name``, ``schema`` text and
    ``schema_encoding`` (``ros2msg``, ``ros2idl``, ``ros1msg``, ...; may be empty)."""

    id: int
    topic: str
    encoding: str
    schema_name: str
    schema: str
    schema_encoding: str
    #: why the channel cannot be read although advertised (DDS, Zenoh: a type other than the
    #: bindings', a type fretc has no definition of); empty when it can
    unreadable: str = ""

    @staticmethod
    def from_json(ch: dict) -> Advertised:
        """An advertisement of the Foxglove protocol's ``advertise`` message.

        Raises:
            ValueError: ``ch`` is not an object with an integer ``id`` and a string
                ``topic`` (ws-protocol ``docs/spec.md``, "Advertise").
        """
        if not isinstance(ch, dict):
            raise ValueError(f"a channel is a JSON {frame_shape(ch)}, not an object")
        cid, topic = ch.get("id"), ch.get("topic")
        if type(cid) is not int or not isinstance(topic, str):
            raise ValueError("a channel without an integer id and a string topic")
        return Advertised(cid, topic, str(ch.get("encoding", "")),
                          str(ch.get("schemaName", "")), str(ch.get("schema", "")),
                          str(ch.get("schemaEncoding", "") or ""))


def frame_shape(value: object) -> str:
    """The JSON kind of a decoded frame or field (``array``, ``number``, ``string``, ...),
    for protocol problems."""
    return {dict: "object", list: "array", str: "string", int: "number", float: "number",
            bool: "boolean", type(None): "null"}.get(type(value), type(value).__name__)


def json_object(frame: str | bytes) -> tuple[dict | None, str | None]:
    """A text frame of a JSON protocol (Foxglove WebSocket, rosbridge v2: every text frame
    is one JSON object) decoded: ``(object, None)``, or ``(None, problem)`` with the
    sentence of the protocol problem when it is not JSON text or not an object."""
    try:
        msg = json.loads(frame)
    except (ValueError, TypeError):
        return None, "a text frame that is not JSON; ignored"
    except RecursionError:  # nesting deeper than Python's stack: one bad frame, not the session
        return None, "a JSON text frame nested too deep to decode; ignored"
    if not isinstance(msg, dict):
        return None, f"a JSON {frame_shape(msg)} where the protocol sends an object; ignored"
    return msg, None


class WebSocketClient:
    """A WebSocket connection kept in a daemon thread, retried with backoff after a fault and
    ended by the server's orderly close; subclasses speak a protocol in :meth:`_session`
    and put its events on :attr:`events` (the module docstring's tuples).

    Args:
        url: the server's address.
        wanted: topic -> bool, asked once per advertised topic.
        backoff, max_backoff: seconds before the first retry after a drop, and the cap of
            the doubling.
        events: the queue to put events on (a new bounded :class:`~fretc.live.events.EventQueue`
            by default).

    Call :meth:`start`, read :attr:`events`, call :meth:`stop` (idempotent). :meth:`drop`
    closes the current connection as a network fault would (tests).
    """

    #: subprotocols offered (None: none).
    subprotocols: tuple[str, ...] | None = None

    def __init__(self, url: str, wanted: Callable[[str], bool], *, backoff: float = 0.1,
                 max_backoff: float = 5.0, events: EventQueue | None = None) -> None:
        self.url = url
        self.wanted = wanted
        self.backoff = backoff
        self.max_backoff = max_backoff
        self.events: EventQueue = events if events is not None else EventQueue()
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._ws: Any = None  # the open websockets connection
        self._started = threading.Event()
        self._session_messages = 0  # messages put in the current session
        self._session_problems = 0  # protocol problems in the current session

    # -- thread control --------------------------------------------------------------------
    def start(self) -> WebSocketClient:
        """Connect in a background thread (returns at once). Raises
        :class:`MissingDependency` without ``websockets``."""
        require_websockets()
        self._thread = threading.Thread(target=self._run, name="fretc-watch-client",
                                        daemon=True)
        self._thread.start()
        self._started.wait(5)
        return self

    def stop(self) -> None:
        """Close the connection and end the thread."""
        loop, stop = self._loop, self._stop
        if loop is not None and stop is not None and not loop.is_closed():
            try:
                loop.call_soon_threadsafe(stop.set)
            except RuntimeError:
                pass
        if self._thread is not None:
            self._thread.join(5)

    def drop(self) -> None:
        """Close the current connection abruptly (the client then reconnects)."""
        loop, ws = self._loop, self._ws
        if loop is not None and ws is not None:
            def _abort():
                transport = getattr(ws, "transport", None)
                if transport is not None:
                    transport.abort()
            loop.call_soon_threadsafe(_abort)

    def _run(self) -> None:
        loop = asyncio.new_event_loop()
        self._loop = loop
        try:
            loop.run_until_complete(self._main())
        finally:
            loop.close()

    # -- connection ------------------------------------------------------------------------
    def _check(self, ws) -> None:
        """Refuse a connection (raise ConnectionError) the protocol cannot use."""

    async def _main(self) -> None:
        import websockets  # optional (the watch extra): imported only when connecting

        self._stop = asyncio.Event()
        self._started.set()
        delay = self.backoff
        hostile = 0  # connections in a row with a protocol problem and no message
        while not self._stop.is_set():
            self._session_messages = self._session_problems = 0
            try:
                async with websockets.connect(
                        self.url, subprotocols=list(self.subprotocols or ()) or None,  # type: ignore[arg-type]  # (Subprotocol is a str)
                        max_size=MAX_FRAME_BYTES, open_timeout=5, ping_interval=5, ping_timeout=10,
                        compression=None) as ws:
                    self._check(ws)
                    self._ws = ws
                    delay = self.backoff
                    self._put("connected", time.time_ns(), ws.subprotocol or "", "")
                    session = asyncio.ensure_future(self._session(ws))
                    stopper = asyncio.ensure_future(self._stop.wait())
                    await asyncio.wait({session, stopper}, return_when=asyncio.FIRST_COMPLETED)
                    if self._stop.is_set():
                        session.cancel()
                        await ws.close()
                        return
                    stopper.cancel()
                    session.result()
                    if closed_in_order(ws):
                        self._put("closed", time.time_ns(),
                                  f"the server closed the connection (code {ws.close_code})")
                        return
                    reason = ("the connection was lost without a close frame"
                              if not _too_big(ws) else
                              f"a message over {MAX_FRAME_BYTES:,} bytes (the limit of one "
                              "frame) closed the connection")
            except asyncio.CancelledError:  # pragma: no cover - loop shutdown
                return
            except Exception as exc:  # any network fault: report, back off, retry
                reason = f"{type(exc).__name__}: {exc}"
            finally:
                self._ws = None
            self._put("disconnected", time.time_ns(), reason)
            hostile = hostile + 1 if self._session_problems and not self._session_messages else 0
            if hostile >= MAX_HOSTILE_SESSIONS:
                self._put("gave_up", time.time_ns(),
                          f"{hostile} connections in a row sent frames of the wrong shape and "
                          "dropped before any message; not retried")
                return
            try:
                await asyncio.wait_for(self._stop.wait(), delay)
            except TimeoutError:
                pass
            delay = min(self.max_backoff, delay * 2)

    async def _session(self, ws) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _put(self, *event) -> None:
        self.events.put(event)

    def _protocol(self, detail: str) -> None:
        """Report a frame of the wrong shape (a ``protocol`` event); the session goes on."""
        self._session_problems += 1
        self.events.put(("protocol", time.time_ns(), detail))


def _too_big(ws) -> bool:
    """Whether the client closed ``ws`` for a message over :data:`MAX_FRAME_BYTES` (close
    code 1009, RFC 6455 section 7.4.1)."""
    sent = getattr(getattr(ws, "protocol", None), "close_sent", None)
    return getattr(sent, "code", None) == 1009


class FoxgloveClient(WebSocketClient):
    """A client of the Foxglove WebSocket protocol (module docstring): subscribes, on every
    advertisement, to the channels whose topic ``wanted(topic)`` accepts. Arguments as
    :class:`WebSocketClient`."""

    subprotocols = SUBPROTOCOLS

    def _check(self, ws) -> None:
        if ws.subprotocol not in SUBPROTOCOLS:
            raise ConnectionError(f"the server chose no Foxglove subprotocol "
                                  f"({ws.subprotocol!r})")

    async def _session(self, ws) -> None:
        """Read frames until the connection closes (``ConnectionClosed`` ends the loop); a
        frame of the wrong shape, or one whose reading fails in any way, is a ``protocol``
        event and the loop goes on."""
        from websockets.exceptions import ConnectionClosed  # (as websockets in _main)

        st = _FoxgloveState()
        try:
            async for frame in ws:
                now = time.time_ns()
                try:
                    await self._frame(ws, frame, st, now)
                except ConnectionClosed:
                    raise
                except Exception as exc:  # whatever a frame holds, it costs that frame only
                    self._protocol(f"a frame that could not be read ({type(exc).__name__}: "
                                   f"{str(exc)[:200]}); ignored")
        except ConnectionClosed:
            return

    async def _frame(self, ws, frame, st: _FoxgloveState, now: int) -> None:
        """Handle one frame: a binary ``messageData`` (other binary opcodes, such as time and
        service responses, are not read) or a JSON text frame."""
        from websockets.exceptions import ConnectionClosed

        if not isinstance(frame, str):
            frame = bytes(frame)
            if frame[:1] != b"\x01":
                return
            if len(frame) < _HEAD.size:
                self._protocol(f"a messageData frame of {len(frame)} bytes, shorter than its "
                               f"{_HEAD.size}-byte header; ignored")
                return
            _op, sid, log_time = _HEAD.unpack_from(frame)
            topic = st.subs.get(sid)
            if topic is not None:
                self._session_messages += 1
                self.events.put(("message", topic, log_time, frame[_HEAD.size:], now))
            return
        msg, problem = json_object(frame)
        if problem is not None:
            self._protocol(problem)
            return
        assert msg is not None  # (no problem: an object)
        try:
            await self._text(ws, msg, st, now)
        except ConnectionClosed:
            raise
        except Exception as exc:  # a field of the wrong shape
            self._protocol(f"a {str(msg.get('op'))[:40]!r} frame of the wrong shape "
                           f"({type(exc).__name__}: {str(exc)[:200]}); ignored")

    async def _text(self, ws, msg: dict, st: _FoxgloveState, now: int) -> None:
        """Handle one JSON object frame (module docstring); raises on a field of the wrong
        shape (the caller reports it)."""
        op = msg.get("op")
        if op == "advertise":
            chans = st.advertised(self, msg.get("channels", ()))
            self._put("advertise", now, chans)
            new = []
            for ch in chans:
                if ch.id in st.by_channel or not self.wanted(ch.topic):
                    continue
                sid = st.next_id
                st.next_id += 1
                st.subs[sid] = ch.topic
                st.by_channel[ch.id] = sid
                new.append({"id": sid, "channelId": ch.id})
            if new:
                await ws.send(json.dumps({"op": "subscribe", "subscriptions": new}))
        elif op == "unadvertise":
            topics, ids = [], _items(msg, "channelIds")
            if any(type(cid) is not int for cid in ids):
                raise ValueError("channelIds holds other values than integers")
            for cid in ids:
                gone = st.by_channel.pop(cid, -1)  # (subscription ids are >= 0)
                if gone >= 0:
                    topics.append(st.subs.pop(gone))
            if topics:
                self._put("unadvertise", now, topics)
        elif op == "serverInfo":
            self._put("server", now, str(msg.get("name", "")))
        elif op == "status":
            self._put("status", now, msg.get("level"), str(msg.get("message", "")))


def _items(msg: dict, key: str) -> list:
    """``msg[key]`` as a list (missing: empty). Raises ValueError when it is not an array."""
    value = msg.get(key, [])
    if not isinstance(value, list):
        raise ValueError(f"{key} is a JSON {frame_shape(value)}, not an array")
    return value


class _FoxgloveState:
    """One connection's subscriptions and the count of channels no requirement reads."""

    def __init__(self) -> None:
        self.subs: dict[int, str] = {}  # subscription id -> topic
        self.by_channel: dict[int, int] = {}  # channel id -> subscription id
        self.next_id = 1
        self.others = 0  # channels advertised that no requirement reads

    def advertised(self, client: WebSocketClient, channels) -> list[Advertised]:
        """The channels of an ``advertise`` frame to hand on: each wanted one, and others up
        to :data:`MAX_OTHER_CHANNELS` per connection (one ``protocol`` event when more come);
        a channel of the wrong shape is a ``protocol`` event."""
        if not isinstance(channels, list):
            raise ValueError(f"channels is a JSON {frame_shape(channels)}, not an array")
        out, bad, dropped = [], 0, 0
        for ch in channels:
            try:
                adv = Advertised.from_json(ch)
            except ValueError:
                bad += 1
                continue
            if not client.wanted(adv.topic):
                self.others += 1
                if self.others > MAX_OTHER_CHANNELS:
                    dropped += 1
                    continue
            out.append(adv)
        if bad:
            client._protocol(f"{bad} advertised channel(s) without an integer id and a string "
                             "topic; ignored")
        if dropped and self.others - dropped <= MAX_OTHER_CHANNELS:
            client._protocol(f"the server advertises more than {MAX_OTHER_CHANNELS} channels "
                             "no requirement reads; the others are not kept")
        return out
