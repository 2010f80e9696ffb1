"""A WebSocket connection kept in a background thread (:class:`WebSocketClient`): retried
with exponential backoff after a fault (``backoff`` doubling up to ``max_backoff`` seconds),
ended by the server's orderly close (RFC 6455 section 5.5.1), bounded in frame size; the
base of the WebSocket transports of ``fretc watch`` (the Foxglove WebSocket protocol,
:mod:`fretc.live.websocket.foxglove`; rosbridge v2, :mod:`fretc.live.websocket.rosbridge`),
which speak their protocol in a session and put the events of :mod:`fretc.live.protocol`
on an :class:`~fretc.live.events.EventQueue`.

Needs ``websockets`` (the ``watch`` extra): :func:`require_websockets` says so in one line.
"""

from __future__ import annotations

import asyncio
import json
import threading
import time
from collections.abc import Callable
from typing import Any

from fretc.live.events import EventQueue
from fretc.live.protocol import WATCH_HINT, MissingDependency, frame_shape

__all__ = ["WebSocketClient", "require_websockets", "closed_in_order", "json_object",
           "MAX_HOSTILE_SESSIONS", "MAX_FRAME_BYTES"]

#: Connections in a row that sent a frame of the wrong shape and then dropped before any
#: message after which the client stops retrying (``gave_up``).
MAX_HOSTILE_SESSIONS = 5
#: The largest WebSocket message accepted (bytes): a larger one closes the connection (code
#: 1009, "message too big"), which is reported and retried like any disconnection. Big enough
#: for camera images and point clouds; a bound so that one frame cannot take all memory.
MAX_FRAME_BYTES = 256 * 1024 * 1024


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
