"""Small hostile WebSocket servers for the watch tests and the fuzzer: a server on 127.0.0.1
that runs a script for each connection (Foxglove or rosbridge frames written by hand, so a
test can send what no real server sends), bounded in time.

A script is ``async def script(ws, k)``: ``ws`` the server side of the connection, ``k`` its
number (0 for the first). Helpers build the frames of the Foxglove protocol
(``github.com/foxglove/ws-protocol``, ``docs/spec.md``) and of rosbridge v2.
"""

from __future__ import annotations

import asyncio
import json
import struct
import threading

S = 1_000_000_000
T0 = 1_700_000_000 * S
F64_SCHEMA = "float64 data"
#: The requirements and bindings every hostile-server test watches: ``/a.data > 0``.
FRET = "@tick_period 100 ms\nRA: the robot shall always satisfy a_ok\n"
BINDINGS = '[tick]\nperiod = "100 ms"\ntime = "log"\n[variables]\na_ok = "/a.data > 0"\n'


def f64(x: float) -> bytes:
    """A CDR (little-endian) ``std_msgs/msg/Float64`` payload."""
    return b"\x00\x01\x00\x00" + struct.pack("<d", x)


def advertise(channels: list[tuple[int, str]]) -> str:
    """A Foxglove ``advertise`` frame of Float64 channels ``(id, topic)``."""
    return json.dumps({"op": "advertise", "channels": [
        {"id": cid, "topic": topic, "encoding": "cdr", "schemaName": "std_msgs/msg/Float64",
         "schema": F64_SCHEMA, "schemaEncoding": "ros2msg"} for cid, topic in channels]})


def message_data(sub_id: int, log_time: int, payload: bytes) -> bytes:
    """A Foxglove ``messageData`` binary frame (opcode 1, subscription id, log time)."""
    return struct.pack("<BIQ", 1, sub_id, log_time) + payload


async def subscription(ws, channel_id: int, timeout: float = 10.0) -> int:
    """Wait for the client's ``subscribe`` of ``channel_id``; its subscription id."""
    async def wait():
        async for frame in ws:
            msg = json.loads(frame)
            if msg.get("op") == "subscribe":
                for s in msg["subscriptions"]:
                    if s["channelId"] == channel_id:
                        return s["id"]
        raise ConnectionError("closed before subscribing")
    return await asyncio.wait_for(wait(), timeout)


async def publish_a(ws, sid: int, n: int = 20, start: int = T0) -> None:
    """``n`` Float64 messages of value 1.0 on subscription ``sid``, 50 ms of log time
    apart."""
    for k in range(n):
        await ws.send(message_data(sid, start + k * 50_000_000, f64(1.0)))
        await asyncio.sleep(0.002)


class ScriptServer:
    """Serve ``script`` on 127.0.0.1 (a free port) in a daemon thread until :meth:`stop` or
    ``lifetime`` seconds. ``subprotocol``: the one the server picks (None: none).

    Attributes:
        connections: how many connections were accepted so far.
        url: ``ws://127.0.0.1:PORT``.
    """

    def __init__(self, script, subprotocol: str | None = "foxglove.websocket.v1",
                 lifetime: float = 60.0) -> None:
        self.script = script
        self.subprotocol = subprotocol
        self.lifetime = lifetime
        self.connections = 0
        self.port = 0
        self._ready = threading.Event()
        self._loop = None
        self._stop = None
        self._thread = threading.Thread(target=lambda: asyncio.run(self._main()), daemon=True)
        self._thread.start()
        if not self._ready.wait(10):
            raise RuntimeError("the hostile server did not start")

    @property
    def url(self) -> str:
        """The server's address."""
        return f"ws://127.0.0.1:{self.port}"

    def stop(self) -> None:
        """Stop serving (idempotent)."""
        if self._loop is not None and not self._loop.is_closed():
            try:
                self._loop.call_soon_threadsafe(self._stop.set)
            except RuntimeError:
                pass
        self._thread.join(10)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()

    async def _handler(self, ws) -> None:
        k = self.connections
        self.connections += 1
        try:
            await self.script(ws, k)
        except Exception:  # the client went away: the script ends
            pass

    async def _main(self) -> None:
        import websockets

        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        protos = [self.subprotocol] if self.subprotocol else None
        async with websockets.serve(self._handler, "127.0.0.1", 0, max_size=None,
                                    subprotocols=protos, compression=None) as server:
            self.port = next(iter(server.sockets)).getsockname()[1]
            self._ready.set()
            try:
                await asyncio.wait_for(self._stop.wait(), self.lifetime)
            except TimeoutError:
                pass
