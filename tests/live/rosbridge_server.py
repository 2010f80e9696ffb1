"""A local rosbridge-protocol server for the tests, fed from a recorded MCAP (no ROS install).

It speaks the part of the rosbridge v2 protocol (rosbridge_suite ``ROSBRIDGE_PROTOCOL.md``)
a watching client uses: ``call_service`` of rosapi's ``/rosapi/topics`` and
``/rosapi/topic_type`` (answered with ``service_response``), ``subscribe``, and ``publish``
of every recorded message as JSON (ROS field names; ROS 1 logs with ``secs``/``nsecs``
times, as rosbridge on ROS 1; ``uint8[]`` as base64). Before each message it publishes
``/clock`` (``rosgraph_msgs/Clock``) with the message's log time, as a robot on simulated
time (``ros2 bag play --clock``) does. Publishing starts once a client subscribed to every
served topic, is paced at ``rate`` times real time, and ends with an orderly WebSocket close
(code 1000): the end of the run.

The messages are decoded with rosbags (``mcap``'s reader and
:func:`fretc.logs.schema_decoder`) - the client side builds them back from JSON with
rosbags' type store, so the round trip is checked, not assumed.
"""

from __future__ import annotations

import asyncio
import base64
import json
import threading
import time

import numpy as np
from mcap.reader import make_reader

from fretc.logs import schema_decoder

CLOCK = "/clock"


def to_json(msg, ros1: bool):
    """A rosbags message as rosbridge's JSON object."""
    if isinstance(msg, np.ndarray):
        if msg.dtype == np.uint8:
            return base64.b64encode(msg.tobytes()).decode("ascii")
        return msg.tolist()
    if isinstance(msg, (list, tuple)):
        return [to_json(x, ros1) for x in msg]
    fields = getattr(msg, "__dataclass_fields__", None)
    if fields is None:
        return msg.item() if isinstance(msg, np.generic) else msg
    out = {}
    for name in fields:
        key = {"sec": "secs", "nanosec": "nsecs"}.get(name, name) if ros1 else name
        out[key] = to_json(getattr(msg, name), ros1)
    return out


def _read(path: str, topics: set[str]):
    """(types, messages): topic -> type name, and [(topic, log time, JSON text)]."""
    types, decoders, out = {}, {}, []
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(log_time_order=True):
            t = channel.topic
            if t not in topics:
                continue
            if t not in decoders:
                types[t] = schema.name
                decoders[t] = schema_decoder(channel.message_encoding, schema.encoding,
                                             schema.name, schema.data.decode("utf-8"))
            ros1 = channel.message_encoding == "ros1"
            doc = to_json(decoders[t](message.data), ros1)
            out.append((t, message.log_time, json.dumps({"op": "publish", "topic": t,
                                                         "msg": doc})))
    return types, out, ros1


class RosbridgeTestServer:
    """Serve ``topics`` of the MCAP at ``path`` over the rosbridge protocol on 127.0.0.1
    (a free port; :attr:`url` is ``rosbridge://127.0.0.1:PORT``). ``rosapi``: answer the
    rosapi services (False: refuse them, so the client must be given the types).
    Use as a context manager; the server thread ends within a few seconds of :meth:`stop`."""

    def __init__(self, path: str, topics: set[str], rate: float = 40.0,
                 rosapi: bool = True) -> None:
        self.types, self.messages, self.ros1 = _read(path, set(topics))
        self.rate = rate
        self.rosapi = rosapi
        self.sent = 0
        self._ready = threading.Event()
        self._loop = None
        self._stop = None
        self.port = None
        self._thread = threading.Thread(target=self._run, daemon=True)

    @property
    def url(self) -> str:
        return f"rosbridge://127.0.0.1:{self.port}"

    def __enter__(self):
        self._thread.start()
        assert self._ready.wait(10), "the rosbridge test server did not start"
        return self

    def __exit__(self, *exc):
        self.stop()

    def stop(self) -> None:
        if self._loop is not None and not self._loop.is_closed():
            try:
                self._loop.call_soon_threadsafe(self._stop.set)
            except RuntimeError:
                pass
        self._thread.join(10)

    def _run(self) -> None:
        asyncio.run(self._main())

    async def _main(self) -> None:
        import websockets

        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        async with websockets.serve(self._client, "127.0.0.1", 0, max_size=None,
                                    compression=None) as server:
            self.port = next(iter(server.sockets)).getsockname()[1]
            self._ready.set()
            try:
                await asyncio.wait_for(self._stop.wait(), 120)  # bounded in time
            except TimeoutError:
                pass

    def _service(self, msg: dict) -> dict:
        reply = {"op": "service_response", "service": msg.get("service"),
                 "id": msg.get("id"), "result": self.rosapi}
        if not self.rosapi:
            reply["values"] = "rosapi is not running"
        elif msg.get("service") == "/rosapi/topics":
            topics = sorted(self.types) + [CLOCK]
            types = [self.types.get(t, "rosgraph_msgs/msg/Clock") for t in topics]
            reply["values"] = {"topics": topics, "types": types}
        elif msg.get("service") == "/rosapi/topic_type":
            topic = (msg.get("args") or {}).get("topic")
            reply["values"] = {"type": self.types.get(topic, "")}
        else:
            reply["result"], reply["values"] = False, "unknown service"
        return reply

    async def _client(self, ws) -> None:
        subscribed: set[str] = set()
        publisher = None
        try:
            async for frame in ws:
                msg = json.loads(frame)
                if msg.get("op") == "call_service":
                    await ws.send(json.dumps(self._service(msg)))
                elif msg.get("op") == "subscribe":
                    subscribed.add(msg["topic"])
                    if publisher is None and set(self.types) <= subscribed:
                        publisher = asyncio.ensure_future(self._publish(ws))
        finally:
            if publisher is not None:
                publisher.cancel()

    async def _publish(self, ws) -> None:
        await asyncio.sleep(0.1)
        t0, w0 = None, time.perf_counter()
        for _topic, log_time, text in self.messages:
            if t0 is None:
                t0 = log_time
            due = w0 + (log_time - t0) / 1e9 / self.rate
            left = due - time.perf_counter()
            if left > 0:
                await asyncio.sleep(left)
            sec, nsec = divmod(log_time, 1_000_000_000)
            stamp = {"secs": sec, "nsecs": nsec} if self.ros1 else {"sec": sec, "nanosec": nsec}
            await ws.send(json.dumps({"op": "publish", "topic": CLOCK,
                                      "msg": {"clock": stamp}}))
            await ws.send(text)
            self.sent += 1
        await ws.close(1000, "end of the run")
