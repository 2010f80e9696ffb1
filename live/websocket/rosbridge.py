"""A client of the rosbridge v2 protocol (``rosbridge_suite``, ROS 1 and ROS 2), handing what
it receives to the watch engine as the Foxglove client does (:mod:`fretc.live.websocket.foxglove`).

Protocol (github.com/RobotWebTools/rosbridge_suite, ``ROSBRIDGE_PROTOCOL.md``): JSON text
frames, each an object with ``op``:

Design notes: ARCHITECTURE.md, `live/websocket/rosbridge.py`."""

from __future__ import annotations

import asyncio
import base64
import json
import time
from collections.abc import Callable
from typing import Any, TYPE_CHECKING

import numpy as np

from fretc.live.protocol import MAX_OTHER_CHANNELS, Advertised, frame_shape

from fretc.live.websocket.session import WebSocketClient, json_object

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = ["RosbridgeClient", "json_to_cdr", "ros_url", "CLOCK_TOPIC"]

#: The ROS clock topic (REP 2000 / ROS 1 ``use_sim_time``).
CLOCK_TOPIC = "/clock"
_DTYPES = {"bool": np.bool_, "byte": np.uint8, "char": np.uint8, "octet": np.uint8,
           "int8": np.int8, "uint8": np.uint8, "int16": np.int16, "uint16": np.uint16,
           "int32": np.int32, "uint32": np.uint32, "int64": np.int64, "uint64": np.uint64,
           "float32": np.float32, "float64": np.float64}
#: ROS 1 names of ROS 2 time fields (rosbridge on ROS 1 sends ``secs``/``nsecs``).
_ALIASES = {"sec": "secs", "nanosec": "nsecs"}
_STORE = None


def ros_url(url: str) -> str:
    """``rosbridge://host:port`` -> ``ws://host:port`` (``rosbridge+wss://`` -> ``wss://``)."""
    if url.startswith("rosbridge+wss://"):
        return "wss://" + url[len("rosbridge+wss://"):]
    if url.startswith("rosbridge://"):
        return "ws://" + url[len("rosbridge://"):]
    return url


def _store():
    global _STORE
    if _STORE is None:
        from rosbags.typesys import Stores, get_typestore

        _STORE = get_typestore(Stores.ROS2_HUMBLE)
    return _STORE


def _typename(name: str) -> str:
    from rosbags.typesys.msg import normalize_msgtype

    return normalize_msgtype(name)


def _value(store, node, value):
    kind, args = node
    kind = int(kind)
    if kind == 1:  # BASE: (type, string bound)
        t = args[0]
        if t == "string" or t == "wstring":
            return "" if value is None else str(value)
        if value is None:  # rosbridge writes NaN and infinities as null
            return float("nan") if t.startswith("float") else 0
        if t == "bool":
            return bool(value)
        return float(value) if t.startswith("float") else int(value)
    if kind == 2:  # NAME: a nested message
        return build_message(store, args, value or {})
    inner, _n = args  # ARRAY or SEQUENCE
    items = [] if value is None else value
    if int(inner[0]) == 1 and inner[1][0] in _DTYPES:
        dtype = _DTYPES[inner[1][0]]
        if isinstance(items, str):  # uint8[] / char[] as base64
            return np.frombuffer(base64.b64decode(items), dtype=np.uint8).astype(dtype)
        return np.array([np.nan if x is None else x for x in items], dtype=dtype)
    return [_value(store, inner, x) for x in items]


def build_message(store: Typestore, typename: str, doc: dict[str, Any]) -> Any:  # its message
    """The rosbags message of ``typename`` from rosbridge's JSON ``doc`` (missing fields
    zero; ROS 1 ``secs``/``nsecs`` accepted for ROS 2 times).

    Raises:
        KeyError: the type is not in ``store``; TypeError, ValueError: a field's value
        does not fit its type.
    """
    _consts, fields = store.fielddefs[typename]
    kwargs = {}
    for name, node in fields:
        value = doc.get(name, doc.get(_ALIASES.get(name, name)))
        kwargs[name] = _value(store, node, value)
    return store.types[typename](**kwargs)


def json_to_cdr(typename: str, doc: dict[str, Any], store: Typestore | None = None) -> bytes:
    """rosbridge's JSON message -> CDR bytes of ``typename`` (a ROS 2 ``pkg/msg/Type``), with
    the types of ``store`` (default: ROS 2 Humble's standard types)."""
    store = store if store is not None else _store()
    return bytes(store.serialize_cdr(build_message(store, typename, doc), typename))


def advertisement(cid: int, topic: str, type_name: str, store: Typestore | None = None
                  ) -> Advertised:
    """The :class:`~fretc.live.protocol.Advertised` of a rosbridge topic: CDR with the
    type's ``ros2msg`` definition, or no schema when the type store (``store``, default ROS
    2 Humble's standard types) does not know it."""
    try:
        name = _typename(type_name)
        text = (store if store is not None else _store()).generate_msgdef(name,
                                                                           ros_version=2)[0]
    except Exception:  # an unknown type: no schema (the watch reports the topic unreadable)
        return Advertised(cid, topic, "json", type_name, "", "")
    return Advertised(cid, topic, "cdr", name, text, "ros2msg")


class RosbridgeClient(WebSocketClient):
    """Connect to a rosbridge server (``rosbridge://host:port`` or ``ws://``), learn the
    topics' types from rosapi (or ``types``), subscribe to the wanted ones and put the
    module docstring's events of :mod:`fretc.live.websocket.foxglove` on :attr:`events` (messages as
    CDR with their log time on the ROS clock).

    Args:
        url: the server.
        wanted: topic -> bool.
        types: topic -> message type for topics rosapi does not type.
        poll: seconds between two rosapi queries while a wanted topic is not yet listed.
        msg_path: folders of the ``.msg``/``.idl`` files of the robot's own types
            (``--msg-path``; :mod:`fretc.logs.ros.msg_path`), beside ROS 2 Humble's standard ones.
        backoff, max_backoff, events: as :class:`~fretc.live.websocket.session.WebSocketClient`.
    """

    def __init__(self, url: str, wanted: Callable[[str], bool], *,
                 types: dict[str, str] | None = None, poll: float = 1.0,
                 msg_path: tuple[str, ...] = (), **kw) -> None:
        super().__init__(ros_url(url), wanted, **kw)
        self.types = dict(types or {})
        self.poll = poll
        self.store = None
        if msg_path:
            from fretc.logs.ros.msg_path import msg_path_typestore

            self.store = msg_path_typestore(tuple(msg_path))

    async def _call(self, ws, replies: dict, service: str, args: dict, timeout: float = 3.0):
        """Call a rosapi service; its ``values`` or None (no rosapi, refused, timeout)."""
        cid = f"fretc:{service}:{len(replies)}"
        fut = asyncio.get_running_loop().create_future()
        replies[cid] = fut
        await ws.send(json.dumps({"op": "call_service", "service": service, "args": args,
                                  "id": cid}))
        try:
            msg = await asyncio.wait_for(fut, timeout)
        except TimeoutError:
            return None
        finally:
            replies.pop(cid, None)
        return msg.get("values") if msg.get("result", True) else None

    async def _session(self, ws) -> None:
        """Query types, subscribe, and read frames until the connection closes."""
        from websockets.exceptions import ConnectionClosed  # (as websockets in _main)

        replies: dict[str, asyncio.Future] = {}
        state: dict[str, Any] = {"clock": None, "types": {}}
        reader = asyncio.ensure_future(self._read(ws, replies, state))
        try:
            await self._subscribe_loop(ws, replies, state, reader)
            await reader
        except ConnectionClosed:
            return
        finally:
            reader.cancel()

    async def _subscribe_loop(self, ws, replies, state, reader) -> None:
        """Type and subscribe to the wanted topics (and /clock), querying rosapi again every
        :attr:`poll` seconds while some given type's topic is not listed."""
        advertised: dict[str, str] = state["types"]
        while not reader.done():
            listed = await self._call(ws, replies, "/rosapi/topics", {})
            types = self._listed_types(listed)
            for t, ty in self.types.items():
                types.setdefault(t, ty)
            new = [t for t in sorted(types) if t not in advertised
                   and (self.wanted(t) or t == CLOCK_TOPIC)]
            chans = []
            for t in new:
                advertised[t] = types[t]
                if t == CLOCK_TOPIC and not self.wanted(t):
                    state["clock"] = 0  # use sim time from now on
                else:
                    chans.append(advertisement(len(advertised), t, types[t], self.store))
                await ws.send(json.dumps({"op": "subscribe", "topic": t, "type": types[t],
                                          "id": f"fretc:{t}"}))
            chans += self._others(types, state)
            if chans:
                self._put("advertise", time.time_ns(), chans)
            if listed is None:  # no rosapi: the given types are all there is
                return
            await asyncio.sleep(self.poll)

    def _others(self, types: dict[str, str], state: dict) -> list[Advertised]:
        """The listed topics no requirement reads, not subscribed, not seen before: kept (to
        name what the server has) up to :data:`~fretc.live.protocol.MAX_OTHER_CHANNELS`
        per connection, one ``protocol`` event when more are listed."""
        seen: set[str] = state.setdefault("others", set())
        out = []
        for t in types:
            if t in seen or t in state["types"] or self.wanted(t) or t == CLOCK_TOPIC:
                continue
            if len(seen) >= MAX_OTHER_CHANNELS:
                if not state.get("others_reported"):
                    state["others_reported"] = True
                    self._protocol(f"the server lists more than {MAX_OTHER_CHANNELS} topics "
                                   "no requirement reads; the others are not kept")
                break
            seen.add(t)
            out.append(Advertised(-len(seen), t, "", types[t], "", ""))
        return out

    def _listed_types(self, listed) -> dict[str, str]:
        """topic -> type of rosapi's ``/rosapi/topics`` answer (two parallel lists of
        strings); an answer of another shape is a ``protocol`` event and lists nothing."""
        if not listed:
            return {}
        topics = listed.get("topics") if isinstance(listed, dict) else None
        types = listed.get("types") if isinstance(listed, dict) else None
        if not isinstance(topics, list) or not isinstance(types, list):
            self._protocol("a /rosapi/topics answer without the lists topics and types; "
                           "ignored")
            return {}
        pairs = [(t, ty) for t, ty in zip(topics, types)
                 if isinstance(t, str) and isinstance(ty, str)]
        if len(pairs) < max(len(topics), len(types)):
            self._protocol("a /rosapi/topics answer whose lists differ in length or hold "
                           "other values than strings; those entries are ignored")
        return dict(pairs)

    async def _read(self, ws, replies: dict, state: dict) -> None:
        async for frame in ws:
            now = time.time_ns()
            msg, problem = json_object(frame)
            if problem is not None:
                self._protocol(problem)
                continue
            assert msg is not None  # (no problem: an object)
            try:
                self._frame(msg, replies, state, now)
            except Exception as exc:  # a field of the wrong shape
                self._protocol(f"a {str(msg.get('op'))[:40]!r} frame of the wrong shape "
                               f"({type(exc).__name__}: {str(exc)[:200]}); ignored")

    def _frame(self, msg: dict, replies: dict, state: dict, now: int) -> None:
        """Handle one JSON object frame (module docstring); raises on a field of the wrong
        shape (the caller reports it)."""
        op = msg.get("op")
        if op == "publish":
            topic = msg.get("topic")
            if not isinstance(topic, str):
                raise ValueError(f"topic is a JSON {frame_shape(topic)}, not a string")
            doc = msg.get("msg") or {}
            if topic == CLOCK_TOPIC and state["clock"] is not None:
                state["clock"] = _clock_ns(doc)
                if not self.wanted(topic):
                    return
            type_name = state["types"].get(topic)
            if type_name is None:
                return
            log_time = state["clock"] if state["clock"] else now
            try:
                payload = json_to_cdr(_typename(type_name), doc, self.store)
            except Exception:  # unknown type or a value that does not fit: undecodable
                payload = b""
            self._session_messages += 1
            self.events.put(("message", topic, log_time, payload, now))
        elif op == "service_response":
            cid = msg.get("id")
            fut = replies.get(cid) if isinstance(cid, str) else None
            if fut is not None and not fut.done():
                fut.set_result(msg)
        elif op == "status":
            self._put("status", now, msg.get("level"), str(msg.get("msg", "")))


def _clock_ns(doc) -> int:
    """The time (ns) of a ``rosgraph_msgs/Clock`` message as rosbridge sends it (ROS 2
    ``sec``/``nanosec``, ROS 1 ``secs``/``nsecs``). Raises ValueError or TypeError when
    they are not integers."""
    c = doc.get("clock") if isinstance(doc, dict) else None
    if not isinstance(c, dict):
        raise ValueError("a /clock message without a clock object")
    sec, nsec = c.get("sec", c.get("secs", 0)), c.get("nanosec", c.get("nsecs", 0))
    if type(sec) is not int or type(nsec) is not int:
        raise ValueError("a /clock time whose sec and nanosec are not integers")
    return sec * 1_000_000_000 + nsec
