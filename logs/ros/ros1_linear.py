"""Reading a ROS 1 bag without its index, as a crashed recording leaves it.

ROS bag format 2.0 (ROS wiki, "Bags/Format/2.0"): after the ``#ROSBAG V2.0`` line, records of
a header (u32 length, then ``name=value`` fields each with a u32 length) and data (u32
length, bytes); the header field ``op`` gives the kind: 0x05 Chunk (bz2, lz4 or uncompressed
records), 0x07 Connection, 0x02 Message data (``time``: sec, nsec u32). Everything up to the
first record cut short or unreadable is delivered in log-time order (held back by the
:class:`~fretc.logs.reorder.ReorderQueue`); what follows is a truncation.

rosbags' reader needs the index at the end of the bag, so the records are framed here.
"""

from __future__ import annotations

import bz2
import functools
import struct
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import lz4.frame
from rosbags.typesys.msg import normalize_msgtype

from fretc.common.units import NS_PER_S

from fretc.common import problems as P
from fretc.logs.base import LogSource, Message, header_stamp
from fretc.logs.decoding import DECODE_ERRORS, UnsupportedSchema, build_typestore, decoder_for
from fretc.logs.reorder import ReorderQueue

__all__ = ["Ros1Linear", "is_ros1_bag"]

_ROS1_MAGIC = b"#ROSBAG V2.0\n"
_OP_MSG, _OP_CHUNK, _OP_CONN = b"\x02", b"\x05", b"\x07"


def is_ros1_bag(path: Path) -> bool:
    """True when ``path`` starts with the ROS bag 2.0 magic line."""
    try:
        with open(path, "rb") as f:
            return f.read(len(_ROS1_MAGIC)) == _ROS1_MAGIC
    except OSError:
        return False


def _fields(raw: bytes) -> dict[bytes, bytes]:
    """The ``name=value`` fields of a record header (or of a Connection record's data).

    Raises:
        ValueError: a field that runs past the header or has no ``=``.
    """
    out: dict[bytes, bytes] = {}
    pos = 0
    while pos + 4 <= len(raw):
        (n,) = struct.unpack_from("<I", raw, pos)
        if pos + 4 + n > len(raw):
            raise ValueError("a header field runs past its record header")
        name, eq, value = raw[pos + 4: pos + 4 + n].partition(b"=")
        if not eq:
            raise ValueError("a header field without '='")
        out[name] = value
        pos += 4 + n
    return out


def _record_at(buf: bytes, pos: int) -> tuple[dict[bytes, bytes], bytes, int] | None:
    """(header fields, data, offset after it) of the record at ``pos`` of ``buf``; None when
    the record is cut short by the end of ``buf``.

    Raises:
        ValueError: a header that does not parse.
    """
    if pos + 4 > len(buf):
        return None
    (hlen,) = struct.unpack_from("<I", buf, pos)
    if pos + 8 + hlen > len(buf):
        return None
    header = _fields(buf[pos + 4: pos + 4 + hlen])
    (dlen,) = struct.unpack_from("<I", buf, pos + 4 + hlen)
    start = pos + 8 + hlen
    if start + dlen > len(buf):
        return None
    return header, buf[start: start + dlen], start + dlen


def _chunk_records(header: dict[bytes, bytes], body: bytes
                   ) -> Iterator[tuple[dict[bytes, bytes], bytes]]:
    """The complete records of a Chunk record (stops at the first one cut short).

    Raises:
        ValueError: an unknown compression or a record header that does not parse; bz2
            and lz4 raise their own errors on damaged data.
    """
    comp = header.get(b"compression", b"none").decode()
    if comp == "none":
        raw = body
    elif comp == "bz2":
        raw = bz2.decompress(body)
    elif comp == "lz4":
        raw = lz4.frame.decompress(body)
    else:
        raise ValueError(f"unknown chunk compression {comp!r}")
    pos = 0
    while (rec := _record_at(raw, pos)) is not None:
        h, b, pos = rec
        yield h, b


class Ros1Linear:
    """Record-by-record reading of the ROS 1 bag of ``source`` (a
    :class:`~fretc.logs.ros.bags.BagSource`) without its index; ``why`` is the
    reader's error that made the index unusable (quoted in the problems)."""

    def __init__(self, source: LogSource, why: str) -> None:
        self.src = source
        self.why = why
        self.conns: dict[int, tuple[str, str, str]] = {}  # conn -> (topic, type, definition)
        #: conn -> the Connection record's fields (topic, type, md5sum, message_definition,
        #: callerid, latching: ROS bag format 2.0), as the record gives them
        self.fields: dict[int, dict[bytes, bytes]] = {}

    def scan(self) -> dict[str, str]:
        """Topic -> type name, from a pass that decodes nothing."""
        for _ in _Ros1Pass(self, None, decode=False).run():
            pass
        return {t: normalize_msgtype(ty) for t, ty, _d in self.conns.values()}

    def messages(self, topics: set[str] | frozenset[str] | None) -> Iterator[Message]:
        """Decoded messages of ``topics`` (all when None), in log-time order."""
        yield from _Ros1Pass(self, topics, decode=True).run()

    def raw_messages(self) -> Iterator[Message]:
        """Every message undecoded, in log-time order, with the damage of :meth:`messages`:
        ``data`` is ``(connection id, the message's bytes)`` (its connection's fields in
        :attr:`fields`), ``header_stamp`` None."""
        yield from _Ros1Pass(self, None, decode=True, raw=True).run()


class _Ros1Pass:
    """One pass over the records of the bag (``decode`` False: connections and times only;
    ``raw``: the messages' bytes delivered undecoded, :meth:`Ros1Linear.raw_messages`)."""

    def __init__(self, bag: Ros1Linear, topics: set[str] | frozenset[str] | None,
                 decode: bool, raw: bool = False) -> None:
        self.bag = bag
        self.src = bag.src
        self.topics = topics
        self.decode = decode
        self.raw = raw
        self.queue = ReorderQueue()
        self.last_good: int | None = None
        self.first_time: int | None = None  # the least log time of a message read
        self.decoders: dict[int, Callable[[bytes], Any] | None] = {}
        self.why: dict[int, str] = {}  # connection -> why it has no decoder

    def run(self) -> Iterator[Message]:
        src = self.src
        data = Path(src.path).read_bytes()
        pos = len(_ROS1_MAGIC)
        reason = None
        while pos < len(data):
            try:
                rec = _record_at(data, pos)
            except ValueError:
                rec = None
            if rec is None:
                reason = (f"the record at byte {pos} reaches past the end of the file at byte "
                          f"{len(data)} (cut short, or its length fields are damaged)")
                break
            header, body, nxt = rec
            op = header.get(b"op", b"\x00")[:1]
            try:
                if op == _OP_CHUNK:
                    for h, b in _chunk_records(header, body):
                        self._take(h, b)
                elif op in (_OP_CONN, _OP_MSG):
                    self._take(header, body)
            except Exception as exc:  # bz2/lz4/struct errors: the record's body is damaged
                # its framing held: what it held is a gap from the last message read to the
                # next one, and the read goes on after it
                self.src._gap(self.last_good, open_end=True, cause=P.CORRUPT_RECORD)
                self.src._problem(P.CORRUPT_RECORD, None, self.last_good,
                                  f"record at byte {pos} unreadable ({type(exc).__name__}: "
                                  f"{exc}); skipped: a gap in the log")
                pos = nxt
                continue
            if self.last_good is not None:
                yield from self._release(self.last_good)
            pos = nxt
        if self.decode:
            yield from self._release(None)
        self._finish(reason)

    def _finish(self, reason: str | None) -> None:
        """Record how the pass ended: cut short (``truncated``) or complete without the index
        (``summary_corrupt``)."""
        src = self.src
        if reason is not None:
            src._gap(self.last_good, cause=P.TRUNCATED)
            src._problem(P.TRUNCATED, None, self.last_good,
                         f"{reason}; read up to there without the bag index ({self.bag.why})")
        else:
            src._problem(P.SUMMARY_CORRUPT, None, None,
                         f"the bag index is damaged or missing ({self.bag.why}); every record "
                         "was read without it")
        if not self.decode and self.last_good is not None:
            src._start_time, src._end_time = self.first_time, self.last_good

    def _take(self, header: dict[bytes, bytes], body: bytes) -> None:
        """Note a Connection record, or queue a Message data record."""
        op = header.get(b"op", b"\x00")[:1]
        if op == _OP_CONN:
            conn = struct.unpack("<I", header[b"conn"])[0]
            f = _fields(body)
            self.bag.fields.setdefault(conn, {b"topic": header.get(b"topic", b""), **f})
            self.bag.conns.setdefault(conn, (header.get(b"topic", f.get(b"topic", b"")).decode(),
                                             f.get(b"type", b"").decode(),
                                             f.get(b"message_definition", b"").decode(
                                                 "utf-8", "replace")))
        elif op == _OP_MSG:
            conn = struct.unpack("<I", header[b"conn"])[0]
            sec, nsec = struct.unpack("<II", header[b"time"])
            t = sec * NS_PER_S + nsec
            if self.src._open_gaps:
                self.src._close_gaps(t)
            self.last_good = t if self.last_good is None else max(self.last_good, t)
            self.first_time = t if self.first_time is None else min(self.first_time, t)
            if self.decode:
                self.queue.push(t, 0, (conn, body))

    def _release(self, watermark: int | None) -> Iterator[Message]:
        """Deliver the queued messages the watermark has passed (all when None)."""
        src = self.src
        for t, (conn, body) in self.queue.due(watermark):
            c = self.bag.conns.get(conn)
            if c is None or (self.topics is not None and c[0] not in self.topics):
                continue
            if self.queue.late_by(t):
                src._gap(t, t, topics=frozenset((c[0],)), cause=P.OUT_OF_ORDER)
                src._problem(P.OUT_OF_ORDER, c[0], t, "message older than one already "
                             "delivered beyond the reorder window (no index); skipped")
                continue
            dec = self._decoder(conn, c, t)
            if dec is None:
                src._lose(P.UNKNOWN_SCHEMA, c[0], conn, t, self.why[conn])
                continue
            try:
                msg = dec(body)
            except DECODE_ERRORS as exc:
                src._lose(P.UNDECODABLE, c[0], conn, t, f"a payload of {len(body)} bytes "
                          f"does not deserialize: {type(exc).__name__}")
                continue
            self.queue.delivered(t)
            src.counts[c[0]] = src.counts.get(c[0], 0) + 1
            yield Message(c[0], t, t, header_stamp(msg), msg)

    def _decoder(self, conn: int, c: tuple[str, str, str], t: int
                 ) -> Callable[[bytes], Any] | None:
        """The decoder of connection ``conn`` (built once per pass; None: ``unknown_schema``)."""
        if conn not in self.decoders and self.raw:
            self.decoders[conn] = functools.partial(_undecoded, conn)
        if conn not in self.decoders:
            try:
                store, typename = build_typestore("ros1msg", c[1], c[2])
                self.decoders[conn] = decoder_for(store, typename, "ros1")
            except UnsupportedSchema as exc:
                self.decoders[conn] = None
                self.why[conn] = str(exc)
        return self.decoders[conn]


def _undecoded(conn: int, body: bytes) -> tuple[int, bytes]:
    """A raw pass's "decoding": the message's connection and bytes."""
    return conn, bytes(body)
