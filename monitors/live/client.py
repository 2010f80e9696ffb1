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

Needs ``websockets`` (the ``watch`` extra): :func:`require_websockets` says so in one line.
"""

from __future__ import annotations

import asyncio
import json
import queue
import struct
import threading
import time
from dataclasses import dataclass
from collections.abc import Callable

__all__ = ["SUBPROTOCOLS", "Advertised", "FoxgloveClient", "WebSocketClient", "WATCH_HINT",
           "MissingDependency", "require_websockets"]

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


def closed_in_order(ws) -> bool:
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

    @staticmethod
    def from_json(ch: dict) -> "Advertised":
        """An advertisement of the Foxglove protocol's ``advertise`` message."""
        return Advertised(int(ch["id"]), str(ch["topic"]), str(ch.get("encoding", "")),
                          str(ch.get("schemaName", "")), str(ch.get("schema", "")),
                          str(ch.get("schemaEncoding", "") or ""))


class WebSocketClient:
    """A WebSocket connection kept in a daemon thread, retried with backoff after a fault and
    ended by the server's orderly close; subclasses speak a protocol in :meth:`_session`
    and put its events on :attr:`events` (the module docstring's tuples).

    Args:
        url: the server's address.
        wanted: topic -> bool, asked once per advertised topic.
        backoff, max_backoff: seconds before the first retry after a drop, and the cap of
            the doubling.
        events: the queue to put events on (a new one by default).

    Call :meth:`start`, read :attr:`events`, call :meth:`stop` (idempotent). :meth:`drop`
    closes the current connection as a network fault would (tests).
    """

    #: subprotocols offered (None: none).
    subprotocols: tuple[str, ...] | None = None

    def __init__(self, url: str, wanted: Callable[[str], bool], *, backoff: float = 0.1,
                 max_backoff: float = 5.0, events: queue.Queue | None = None) -> None:
        self.url = url
        self.wanted = wanted
        self.backoff = backoff
        self.max_backoff = max_backoff
        self.events: queue.Queue = events if events is not None else queue.Queue()
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._ws = None
        self._started = threading.Event()

    # -- thread control --------------------------------------------------------------------
    def start(self) -> "WebSocketClient":
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
        while not self._stop.is_set():
            try:
                async with websockets.connect(
                        self.url, subprotocols=list(self.subprotocols or ()) or None,
                        max_size=None, open_timeout=5, ping_interval=5, ping_timeout=10,
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
                    reason = "the connection was lost without a close frame"
            except asyncio.CancelledError:  # pragma: no cover - loop shutdown
                return
            except Exception as exc:  # any network fault: report, back off, retry
                reason = f"{type(exc).__name__}: {exc}"
            finally:
                self._ws = None
            self._put("disconnected", time.time_ns(), reason)
            try:
                await asyncio.wait_for(self._stop.wait(), delay)
            except asyncio.TimeoutError:
                pass
            delay = min(self.max_backoff, delay * 2)

    async def _session(self, ws) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _put(self, *event) -> None:
        self.events.put(event)


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
        """Read frames until the connection closes (``ConnectionClosed`` ends the loop)."""
        from websockets.exceptions import ConnectionClosed  # (as websockets in _main)

        subs: dict[int, str] = {}  # subscription id -> topic
        by_channel: dict[int, int] = {}  # channel id -> subscription id
        next_id = 1
        put = self.events.put
        head, head_size = _HEAD.unpack_from, _HEAD.size
        try:
            async for frame in ws:
                now = time.time_ns()
                if not isinstance(frame, str):
                    frame = bytes(frame)
                    if len(frame) >= head_size and frame[0] == _MESSAGE_DATA:
                        _op, sid, log_time = head(frame)
                        topic = subs.get(sid)
                        if topic is not None:
                            put(("message", topic, log_time, frame[head_size:], now))
                    continue
                try:
                    msg = json.loads(frame)
                except ValueError:
                    continue
                op = msg.get("op")
                if op == "advertise":
                    chans = []
                    for ch in msg.get("channels", ()):
                        try:
                            chans.append(Advertised.from_json(ch))
                        except (KeyError, TypeError, ValueError):
                            continue
                    self._put("advertise", now, chans)
                    new = []
                    for ch in chans:
                        if ch.id in by_channel or not self.wanted(ch.topic):
                            continue
                        sid = next_id
                        next_id += 1
                        subs[sid] = ch.topic
                        by_channel[ch.id] = sid
                        new.append({"id": sid, "channelId": ch.id})
                    if new:
                        await ws.send(json.dumps({"op": "subscribe", "subscriptions": new}))
                elif op == "unadvertise":
                    topics = []
                    for cid in msg.get("channelIds", ()):
                        sid = by_channel.pop(cid, None)
                        if sid is not None:
                            topics.append(subs.pop(sid))
                    if topics:
                        self._put("unadvertise", now, topics)
                elif op == "serverInfo":
                    self._put("server", now, str(msg.get("name", "")))
                elif op == "status":
                    self._put("status", now, msg.get("level"), str(msg.get("message", "")))
        except ConnectionClosed:
            return
