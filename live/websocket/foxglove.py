"""A client of the Foxglove WebSocket protocol (the one ``foxglove_bridge`` and
``foxglove-sdk`` serve), run in a background thread, that hands what it receives to the
watch engine through a queue.

Design notes: ARCHITECTURE.md, `live/websocket/foxglove.py`."""

from __future__ import annotations

import json
import struct
import time

from fretc.live.protocol import MAX_OTHER_CHANNELS, Advertised, frame_shape
from fretc.live.websocket.session import WebSocketClient, json_object

__all__ = ["SUBPROTOCOLS", "FoxgloveClient"]

#: Subprotocols offered, in order of preference.
SUBPROTOCOLS = ("foxglove.websocket.v1", "foxglove.sdk.v1")
_MESSAGE_DATA = 0x01
_HEAD = struct.Struct("<BIQ")  # opcode, subscription id, log time


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
