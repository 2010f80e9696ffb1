"""The recorded messages of a run as they were, for the shielded recording of
``fretc shield-replay`` (:mod:`fretc.shield.replay`): every message's bytes, channel, schema
and log time, read with the formats' own libraries (``mcap`` for MCAP files, ``rosbags``
for ROS 1 bags and rosbag2 folders), and the MCAP file that holds them with the shield's
messages added (``mcap``'s writer; MCAP's well-known profiles, mcap.dev/spec/registry).

* **MCAP**: every message record with its channel (topic, message encoding, metadata) and
  schema (name, encoding, data) as the file holds them; the ids are the writer's.
* **ROS 1 bag**: each connection a channel of message encoding ``ros1`` with its
  ``ros1msg`` schema (``pkg/Type`` and the connection's full definition) and the
  ``md5sum``, ``callerid`` and ``latching`` metadata, as ``rosbag``'s conversion to MCAP
  writes them; a message's log time and publish time are its bag time.
* **rosbag2**: each connection a channel of message encoding ``cdr`` with its ``ros2msg``
  (or ``ros2idl``) schema as the bag stores it (ROS 2 Jazzy's definition from ``rosbags``
  when the bag stores none).

A recorded topic that the shield publishes on (the robot's own Safety System's output,
``/cmd_vel_filtered`` in a Safe-ROS recording) keeps its messages unchanged on a channel of
the topic :func:`recorded_topic` names, so the shield's messages are the only ones of its
topics and the audit of the shielded recording judges them alone.
"""

from __future__ import annotations

import heapq
import os
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import NamedTuple

from fretc.common.errors import FretcError
from fretc.common.outputs import open_output

__all__ = ["Record", "Channel", "recorded_records", "recorded_topic", "write_shielded",
           "RECORDED_PREFIX"]

#: the prefix of the topic a recorded message of a topic the shield publishes on is kept on
RECORDED_PREFIX = "/recorded"


class Channel(NamedTuple):
    """A channel of the shielded recording: ``topic``, ``encoding`` (MCAP message encoding:
    ``cdr``, ``ros1``, ...), ``schema`` (name, encoding, data bytes; None: a channel without
    a schema) and ``metadata``."""

    topic: str
    encoding: str
    schema: tuple[str, str, bytes] | None
    metadata: tuple[tuple[str, str], ...]


class Record(NamedTuple):
    """One message to write: ``log_time`` and ``publish_time`` (ns), the ``channel`` it
    goes on, its ``data`` bytes, its ``sequence`` number (as recorded; 0 when none)."""

    log_time: int
    publish_time: int
    channel: Channel
    data: bytes
    sequence: int = 0


class ReplayLogError(FretcError):
    """A recording whose messages cannot be copied as they were; the message names it."""


def recorded_topic(topic: str) -> str:
    """The topic a recorded message of ``topic`` is kept on when the shield publishes on
    ``topic``: ``/recorded/cmd_vel_filtered`` for ``/cmd_vel_filtered``."""
    return RECORDED_PREFIX + (topic if topic.startswith("/") else "/" + topic)


def recorded_records(path: str | os.PathLike[str], kind: str) -> Iterator[Record]:
    """The messages of the recording ``path`` (``kind`` as :func:`fretc.logs.open_log`
    names it: ``mcap``, ``bag`` or ``rosbag2``) as they were, in log-time order (module
    docstring).

    Raises:
        ReplayLogError: another kind of log, or records the format's library cannot read
            (named with the log)."""
    try:
        if kind == "mcap":
            yield from _mcap_records(path)
        elif kind == "bag":
            yield from _bag_records(path)
        elif kind == "rosbag2":
            yield from _rosbag2_records(path)
        else:
            raise ReplayLogError(f"{os.fspath(path)}: a {kind} log holds no ROS messages to "
                                 "replay a shield over (MCAP, ROS 1 bags and rosbag2 folders "
                                 "only)")
    except ReplayLogError:
        raise
    except Exception as exc:  # (the library's own error, whatever it is: the log's damage)
        raise ReplayLogError(f"{os.fspath(path)}: its records cannot be copied as they were "
                             f"({type(exc).__name__}: {exc}): a damaged log is audited by "
                             "fretc audit, not replayed") from None


def _mcap_records(path: str | os.PathLike[str]) -> Iterator[Record]:
    from mcap.reader import make_reader

    channels: dict[int, Channel] = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            ch = channels.get(channel.id)
            if ch is None:
                ch = channels[channel.id] = Channel(
                    channel.topic, channel.message_encoding,
                    None if schema is None else (schema.name, schema.encoding,
                                                 bytes(schema.data)),
                    tuple(sorted(channel.metadata.items())))
            yield Record(message.log_time, message.publish_time, ch, bytes(message.data),
                         message.sequence)


def _bag_records(path: str | os.PathLike[str]) -> Iterator[Record]:
    from rosbags.rosbag1 import Reader

    with Reader(Path(path)) as reader:
        channels = {}
        for c in reader.connections:
            pkg, _msg, name = c.msgtype.split("/")
            ext = c.ext  # (a ROS 1 bag's: ConnectionExtRosbag1)
            meta = {"md5sum": c.digest, "callerid": getattr(ext, "callerid", None) or "",
                    "latching": str(int(getattr(ext, "latching", 0) or 0))}
            channels[c.id] = Channel(c.topic, "ros1",
                                     (f"{pkg}/{name}", "ros1msg", c.msgdef.data.encode()),
                                     tuple(sorted(meta.items())))
        for c, t, raw in reader.messages():
            yield Record(int(t), int(t), channels[c.id], bytes(raw))


def _rosbag2_records(path: str | os.PathLike[str]) -> Iterator[Record]:
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    store = None
    with Reader(Path(path)) as reader:
        channels = {}
        for c in reader.connections:
            fmt = getattr(c.msgdef.format, "name", "NONE")
            if fmt == "IDL":
                schema = (c.msgtype, "ros2idl", c.msgdef.data.encode())
            elif fmt == "MSG" and c.msgdef.data:
                schema = (c.msgtype, "ros2msg", c.msgdef.data.encode())
            else:  # (a bag that stores no definition: ROS 2 Jazzy's, as the audit reads it)
                store = store or get_typestore(Stores.ROS2_JAZZY)
                schema = (c.msgtype, "ros2msg",
                          store.generate_msgdef(c.msgtype, ros_version=2)[0].encode())
            qos = getattr(c.ext, "offered_qos_profiles", "")
            meta = {"offered_qos_profiles": qos} if isinstance(qos, str) and qos else {}
            channels[c.id] = Channel(c.topic, "cdr", schema, tuple(sorted(meta.items())))
        for c, t, raw in reader.messages():
            yield Record(int(t), int(t), channels[c.id], bytes(raw))


def write_shielded(path: str | os.PathLike[str], recorded: Iterable[Record],
                   shielded: Iterable[Record], renamed: dict[str, str]) -> dict[str, int]:
    """Write the shielded recording ``path`` (through :func:`fretc.common.outputs.open_output`:
    a temporary file renamed over it, never through a link planted there): the
    ``recorded`` messages (each of a topic of ``renamed`` on the topic it maps to) merged
    with the ``shielded`` ones in log-time order (both given in it; a recorded message
    before a shield's message of the same log time, as the shield heard it before its
    tick). Returns the messages written per topic.

    Raises:
        OutputError: the file cannot be written."""
    from mcap.writer import CompressionType, Writer

    counts: dict[str, int] = {}
    with open_output(path, "wb", encoding=None) as f:
        writer = Writer(f, compression=CompressionType.ZSTD)
        writer.start(profile="", library="fretc shield-replay")
        schemas: dict[tuple[str, str, bytes], int] = {}
        channels: dict[tuple[Channel, str], int] = {}
        merged = heapq.merge(((r.log_time, 0, n, r) for n, r in enumerate(recorded)),
                             ((r.log_time, 1, n, r) for n, r in enumerate(shielded)))
        for _t, _side, _n, r in merged:
            ch = r.channel
            topic = renamed.get(ch.topic, ch.topic) if _side == 0 else ch.topic
            key = (ch, topic)
            cid = channels.get(key)
            if cid is None:
                sid = 0
                if ch.schema is not None:
                    sid = schemas.get(ch.schema, 0)
                    if not sid:
                        sid = schemas[ch.schema] = writer.register_schema(*ch.schema)
                cid = channels[key] = writer.register_channel(topic, ch.encoding, sid,
                                                              dict(ch.metadata))
            writer.add_message(cid, r.log_time, r.data, r.publish_time, r.sequence)
            counts[topic] = counts.get(topic, 0) + 1
        writer.finish()  # type: ignore[no-untyped-call]  # (mcap's writer is not annotated)
    return dict(sorted(counts.items()))
