"""Serve robot data over the Foxglove WebSocket protocol with ``foxglove-sdk``'s server:
a recorded MCAP log (``fretc replay LOG.mcap --serve``) or the live simulator
(``python -m fretc.sim serve``), so the Foxglove app and ``fretc watch`` can connect.

Messages keep their bytes, their channel's message encoding and their schema (name,
encoding, text) as recorded, and their log time: a client sees what ``foxglove_bridge``
would serve for the same robot. Publishing is paced on the wall clock: a message of log time
``t`` leaves ``(t - t0) / rate`` seconds after the first one (``rate`` times real time).

Needs the ``watch`` extra (``pip install 'fretc[watch]'``).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable
from typing import Any

from mcap.reader import make_reader

__all__ = ["FoxgloveServer", "Pacer", "replay_mcap", "advertise_mcap", "DEFAULT_HOST",
           "DEFAULT_PORT"]

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8765
#: Outgoing messages buffered per client before the server drops the oldest: large, so a
#: briefly busy client does not silently lose data.
BACKLOG = 1 << 17


def _foxglove():
    try:
        import foxglove  # optional (the watch extra): imported only when serving
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise RuntimeError("serving needs foxglove-sdk: pip install 'fretc[watch]'") from exc
    return foxglove


class _Listener:
    """foxglove-sdk ServerListener: records which topics clients subscribed to."""

    def __init__(self) -> None:
        self.subscribed: set[str] = set()
        self.cond = threading.Condition()

    def on_subscribe(self, client, channel) -> None:
        with self.cond:
            self.subscribed.add(channel.topic)
            self.cond.notify_all()

    def on_unsubscribe(self, client, channel) -> None:
        pass

    def on_client_advertise(self, client, channel) -> None:
        pass

    def on_client_unadvertise(self, client, client_channel_id) -> None:
        pass

    def on_message_data(self, client, client_channel_id, data) -> None:
        pass

    def on_get_parameters(self, client, param_names, request_id=None):
        return []

    def on_set_parameters(self, client, parameters, request_id=None):
        return parameters

    def on_parameters_subscribe(self, param_names) -> None:
        pass

    def on_parameters_unsubscribe(self, param_names) -> None:
        pass

    def on_connection_graph_subscribe(self) -> None:
        pass

    def on_connection_graph_unsubscribe(self) -> None:
        pass


class FoxgloveServer:
    """A foxglove-sdk WebSocket server with its own logging context.

    Args:
        host: interface to bind (loopback by default: nothing leaves the machine unless
            asked).
        port: TCP port; 0 picks a free one (see :attr:`port`, known once started).
        name: the server name clients see.
        start: listen at once; False: :meth:`start` later, after the channels are created,
            so that a client connecting at once is advertised every channel in its first
            ``advertise`` (else it may subscribe, and a server waiting for a subscription
            may start sending, before the last channels are advertised).

    Channels are created with :meth:`channel` and messages sent with :meth:`log`.
    :meth:`restart` stops the server and starts a new one on the same port with the same
    channels (a dropped connection, for tests). Raises RuntimeError without foxglove-sdk.
    """

    def __init__(self, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT,
                 name: str = "fretc", start: bool = True) -> None:
        fg = _foxglove()
        self._fg = fg
        self.host = host
        self.name = name
        self.context = fg.Context()
        self.listener = _Listener()
        self.channels: dict[str, Any] = {}  # topic -> the library's channel or writer
        self._server: Any = None
        self._stopping = threading.Lock()  # one thread stops the library's server
        self.port = port
        if start:
            self.start()

    def start(self) -> None:
        """Listen on :attr:`port` (nothing when listening already)."""
        if self._server is None:
            self._server = self._start(self.port)
            self.port = self._server.port

    def _start(self, port: int):
        return self._fg.start_server(name=self.name, host=self.host, port=port,
                                     context=self.context, server_listener=self.listener,
                                     message_backlog_size=BACKLOG)

    @property
    def url(self) -> str:
        """``ws://host:port`` of the server."""
        return f"ws://{self.host}:{self.port}"

    def channel(self, topic: str, message_encoding: str, schema_name: str,
                schema_encoding: str, schema_data: bytes) -> Any:  # a foxglove Channel
        """The channel of ``topic`` (created on first use with this schema)."""
        ch = self.channels.get(topic)
        if ch is None:
            fg = self._fg
            schema = fg.Schema(name=schema_name, encoding=schema_encoding, data=schema_data)
            ch = fg.Channel(topic, schema=schema, message_encoding=message_encoding,
                            context=self.context)
            self.channels[topic] = ch
        return ch

    def log(self, topic: str, data: bytes, log_time: int) -> None:
        """Publish one message on ``topic``'s channel at ``log_time`` (ns)."""
        self.channels[topic].log(data, log_time=int(log_time))

    def wait_subscribed(self, topics: Iterable[str] | None = None, timeout: float = 30.0,
                        settle: float = 0.2) -> bool:
        """Block until clients subscribed to all of ``topics`` (None: to any topic), then
        ``settle`` seconds more. False on timeout."""
        need = set(topics) if topics is not None else None
        deadline = time.monotonic() + timeout
        with self.listener.cond:
            while True:
                have = self.listener.subscribed
                if (need is None and have) or (need is not None and need <= have):
                    break
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self.listener.cond.wait(left)
        time.sleep(settle)
        return True

    def restart(self, down: float = 0.0) -> None:
        """Stop the server (clients are disconnected), wait ``down`` seconds, start it again
        on the same port with the same channels."""
        self.stop()
        with self.listener.cond:
            self.listener.subscribed.clear()
        if down:
            time.sleep(down)
        for _ in range(50):
            try:
                self._server = self._start(self.port)
                return
            except Exception:  # the port may take a moment to free
                time.sleep(0.05)
        self._server = self._start(self.port)

    def stop(self) -> None:
        """Stop the server (nothing when it never started or is stopped already). Safe from
        several threads at once: the library's server is taken by one of them, since two
        concurrent ``stop`` calls on it raise RuntimeError ("Already borrowed")."""
        with self._stopping:
            server, self._server = self._server, None
        if server is not None:
            server.stop()


class Pacer:
    """Wall-clock pacing of log times: :meth:`wait` (log time ns) returns when the message
    is due, ``rate`` times real time (``rate`` <= 0: as fast as possible)."""

    def __init__(self, rate: float) -> None:
        self.rate = rate
        self._t0: int | None = None
        self._w0 = 0.0

    def wait(self, log_time: int) -> None:
        """Sleep until the message of ``log_time`` is due on the wall clock."""
        if self.rate <= 0:
            return
        if self._t0 is None:
            self._t0, self._w0 = log_time, time.perf_counter()
            return
        due = self._w0 + (log_time - self._t0) / 1e9 / self.rate
        left = due - time.perf_counter()
        if left > 0:
            time.sleep(left)


def advertise_mcap(path: str, server: FoxgloveServer,
                   topics: set[str] | None = None) -> dict[str, str]:
    """Create on ``server`` a channel for every channel of the MCAP at ``path`` (all, or
    those of ``topics``), with its schema and message encoding; returns topic -> schema
    name. Reads the summary (or scans the file when it has none)."""
    out: dict[str, str] = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        if summary is not None:
            pairs = [(ch, summary.schemas.get(ch.schema_id)) for ch in summary.channels.values()]
        else:
            seen: dict[int, tuple[Any, Any]] = {}  # channel id -> (channel, schema)
            for schema, channel, _m in reader.iter_messages():
                seen.setdefault(channel.id, (channel, schema))
            pairs = list(seen.values())
    for ch, sc in sorted(pairs, key=lambda p: p[0].id):
        if topics is not None and ch.topic not in topics:
            continue
        server.channel(ch.topic, ch.message_encoding, sc.name if sc else "",
                       sc.encoding if sc else "", sc.data if sc else b"")
        out[ch.topic] = sc.name if sc else ""
    return out


def replay_mcap(path: str, server: FoxgloveServer, rate: float = 1.0, *,
                topics: set[str] | None = None,
                on_message: Callable[[str, int], None] | None = None,
                stop: threading.Event | None = None,
                at: Callable[[int], None] | None = None) -> tuple[int, int]:
    """Publish the messages of the MCAP at ``path`` on ``server`` in log-time order, paced
    at ``rate`` times real time, each with its recorded log time, bytes, message encoding
    and schema.

    Args:
        topics: only these topics (None: all).
        on_message: called with (topic, log time) just before each message is sent (the
            latency benchmark's send clock).
        stop: set to stop early.
        at: called with the index of each message before it is sent (tests: fault
            injection).

    Returns:
        (messages sent, log time of the last one, or -1).

    Raises:
        OSError, mcap's errors: the file cannot be read.
    """
    pacer = Pacer(rate)
    sent, last = 0, -1
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            if topics is not None and channel.topic not in topics:
                continue
            if stop is not None and stop.is_set():
                break
            if channel.topic not in server.channels:
                server.channel(channel.topic, channel.message_encoding,
                               schema.name if schema else "",
                               schema.encoding if schema else "",
                               schema.data if schema else b"")
            pacer.wait(message.log_time)
            if at is not None:
                at(sent)
            if on_message is not None:
                on_message(channel.topic, message.log_time)
            server.log(channel.topic, message.data, message.log_time)
            sent += 1
            last = message.log_time
    return sent, last
