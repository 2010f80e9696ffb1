"""What every live transport of ``fretc watch`` hands the watch: the events it puts on its
:class:`~fretc.live.events.EventQueue` (below), the channels it advertises
(:class:`Advertised`), and the error of a transport whose optional package is missing
(:class:`MissingDependency`, naming :data:`WATCH_HINT`). The Foxglove WebSocket client
(:mod:`fretc.live.websocket.foxglove`) was the first transport and its events are the
protocol's; rosbridge, DDS and Zenoh put the same tuples.

Design notes: ARCHITECTURE.md, `live/protocol.py`."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Advertised", "MissingDependency", "WATCH_HINT", "MAX_OTHER_CHANNELS", "frame_shape"]

#: Channels no requirement reads kept per connection (their topics name what a server
#: advertises in errors); more are counted in one ``protocol`` event, not kept.
MAX_OTHER_CHANNELS = 1000

#: What to install for the live commands (``fretc watch``, ``fretc replay --serve``).
WATCH_HINT = "pip install 'fretc[watch]'"


class MissingDependency(RuntimeError):
    """An optional dependency of the live commands is not installed (the message names
    :data:`WATCH_HINT`)."""


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
