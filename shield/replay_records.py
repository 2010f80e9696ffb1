"""The recorded messages of a run as they were, for the shielded recording of
``fretc shield-replay`` (:mod:`fretc.shield.replay`): every message's bytes, channel, schema
and log time, read with the formats' own libraries (``mcap`` for MCAP files, ``rosbags``
for ROS 1 bags and rosbag2 folders), and the MCAP file that holds them with the shield's
messages added (``mcap``'s writer; MCAP's well-known profiles, mcap.dev/spec/registry).

Design notes: ARCHITECTURE.md, `shield/replay_records.py`."""

from __future__ import annotations

import heapq
import os
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any, NamedTuple

from fretc.common.errors import FretcError
from fretc.common.outputs import open_output
from fretc.logs.base import Gap
from fretc.logs.recorded_gaps import GAPS_METADATA, REPLAY_LIBRARY, gaps_json

__all__ = ["Record", "Channel", "RecordedLog", "recorded_records", "recorded_topic",
           "write_shielded", "RECORDED_PREFIX"]

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


class RecordedLog:
    """The recorded messages of ``path`` (``kind`` as :func:`fretc.logs.open_log` names it:
    ``mcap``, ``bag`` or ``rosbag2``) as they were (module docstring), read as far as they
    can be.

    Attributes:
        intact_end: after a pass of :meth:`records`, the exclusive log-time bound (ns) of the
            span read completely (as :attr:`fretc.logs.LogSource.intact_end`), or None when
            the recording was read to its end without losing a message.
        stopped: the reader's words on the damage (None when there was none).
    """

    def __init__(self, path: str | os.PathLike[str], kind: str) -> None:
        self.path = os.fspath(path)
        self.kind = kind
        self.intact_end: int | None = None
        self.stopped: str | None = None

    def records(self, until: int | None = None) -> Iterator[Record]:
        """The messages in log-time order, those of log time ``until`` (ns) or later left
        out.

        Raises:
            ReplayLogError: another kind of log (named with the log)."""
        self.intact_end, self.stopped = None, None
        if self.kind == "mcap":
            yield from self._mcap(until)
            return
        if self.kind not in ("bag", "rosbag2"):
            raise ReplayLogError(f"{self.path}: a {self.kind} log holds no ROS messages to "
                                 "replay a shield over (MCAP, ROS 1 bags and rosbag2 "
                                 "folders only)")
        if self.kind == "bag":
            from fretc.logs.ros.bags import BagSource

            bag = BagSource(self.path)
            if bag.linear is not None:  # (a crashed recording: no index, read as the audit)
                yield from self._ros1_linear(bag, until)
                return
        last: int | None = None
        try:
            for r in (_bag_records if self.kind == "bag" else _rosbag2_records)(self.path):
                if until is not None and r.log_time >= until:
                    return
                last = r.log_time
                yield r
        except Exception as exc:  # (the library's own error, whatever it is: the log's damage)
            self.intact_end = -(2**63) if last is None else last
            self.stopped = (f"reading stopped after log time {last} ns: "
                            f"{type(exc).__name__}: {exc}")

    def _ros1_linear(self, bag: Any, until: int | None) -> Iterator[Record]:
        """A ROS 1 bag whose index is damaged or missing, read record by record by the
        audit's reader (:meth:`fretc.logs.ros.bags.BagSource.raw_messages`), each
        connection a channel as :func:`_bag_records` makes it from its Connection record."""
        channels: dict[int, Channel] = {}
        for m in bag.raw_messages():
            if until is not None and m.log_time >= until:
                break
            conn, raw = m.data
            ch = channels.get(conn)
            if ch is None:
                f = bag.linear.fields[conn]
                kind = f.get(b"type", b"").decode("utf-8", "replace")
                pkg, _sep, name = kind.partition("/")
                meta = {"md5sum": f.get(b"md5sum", b"").decode("utf-8", "replace"),
                        "callerid": f.get(b"callerid", b"").decode("utf-8", "replace"),
                        "latching": str(int(f.get(b"latching", b"0") or b"0"))}
                ch = channels[conn] = Channel(
                    m.topic, "ros1", (f"{pkg}/{name.split('/')[-1]}", "ros1msg",
                                      f.get(b"message_definition", b"")),
                    tuple(sorted(meta.items())))
            yield Record(m.log_time, m.log_time, ch, raw)
        self.intact_end = bag.intact_end
        self.stopped = "; ".join(str(p) for p in bag.problems[:3])

    def _mcap(self, until: int | None) -> Iterator[Record]:
        source = _raw_mcap(self.path)
        for m in source.messages(None):
            if until is not None and m.log_time >= until:
                break
            yield m.data
        self.intact_end = source.intact_end
        if source.partial:
            self.stopped = "; ".join(str(p) for p in source.problems[:3])


def recorded_records(path: str | os.PathLike[str], kind: str) -> Iterator[Record]:
    """The messages of the recording ``path`` as they were, in log-time order, as far as
    they can be read (:class:`RecordedLog`).

    Raises:
        ReplayLogError: another kind of log than MCAP, ROS 1 bag or rosbag2."""
    return RecordedLog(path, kind).records()


def _raw_mcap(path: str) -> Any:
    """fretc's MCAP reader over ``path`` delivering each message as a :class:`Record` (its
    bytes, channel and schema) instead of decoding it.

    Raises:
        LogError: not an MCAP file (named)."""
    from fretc.logs.base import Message
    from fretc.logs.mcap.source import McapSource

    class _Raw(McapSource):
        def __init__(self, path: str) -> None:
            super().__init__(path)
            self._kept: dict[int, Channel] = {}

        def _deliver(self, channel: Any, rec: Any, schemas: dict[int, Any]) -> Message:
            ch = self._kept.get(channel.id)
            if ch is None:
                schema = schemas.get(channel.schema_id) if channel.schema_id else None
                ch = self._kept[channel.id] = Channel(
                    channel.topic, channel.message_encoding,
                    None if schema is None else (schema.name, schema.encoding,
                                                 bytes(schema.data)),
                    tuple(sorted(channel.metadata.items())))
            self.counts[ch.topic] = self.counts.get(ch.topic, 0) + 1
            return Message(ch.topic, rec.log_time, rec.publish_time, None,
                           Record(rec.log_time, rec.publish_time, ch, bytes(rec.data),
                                  rec.sequence))

    return _Raw(path)


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
                   shielded: Iterable[Record], renamed: dict[str, str],
                   gaps: Sequence[Gap] = ()) -> dict[str, int]:
    """Write the shielded recording ``path`` (through :func:`fretc.common.outputs.open_output`:
    a temporary file renamed over it, never through a link planted there): the
    ``recorded`` messages (each of a topic of ``renamed`` on the topic it maps to) merged
    with the ``shielded`` ones in log-time order (both given in it; a recorded message
    before a shield's message of the same log time, as the shield heard it before its
    tick). ``gaps``: the damage of the recording replayed, written in the Metadata record
    :data:`fretc.logs.recorded_gaps.GAPS_METADATA` (the Header's library
    :data:`fretc.logs.recorded_gaps.REPLAY_LIBRARY`), where the audit reads it. Returns the
    messages written per topic.

    Raises:
        OutputError: the file cannot be written."""
    from mcap.writer import CompressionType, Writer

    counts: dict[str, int] = {}
    with open_output(path, "wb", encoding=None) as f:
        writer = Writer(f, compression=CompressionType.ZSTD)
        writer.start(profile="", library=REPLAY_LIBRARY)
        if gaps:
            writer.add_metadata(GAPS_METADATA, {"gaps": gaps_json(gaps)})
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
