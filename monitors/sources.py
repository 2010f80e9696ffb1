"""Trace sources: recorded robot runs read as a stream of decoded messages in log-time order.

``open_log(path)`` picks a reader by what ``path`` is:

* ``*.mcap`` — any MCAP profile.  Messages on channels with ``cdr`` (ROS 2) or ``ros1``
  message encoding are deserialized with rosbags types built from the schema *embedded in the
  file* (``ros2msg``, ``ros2idl``, ``ros1msg`` schema encodings; MCAP spec, "Well-known
  encodings").  Chunk CRCs and the data-section CRC are checked.  A file with a valid footer
  and summary is read through its chunk indexes; a file without one (a crashed recording) is
  read record by record from the start, as far as it goes.
* ``*.bag`` — a ROS 1 bag (rosbags.rosbag1), types from the connection headers.
* a folder with ``metadata.yaml`` — a rosbag2 bag (rosbags.rosbag2, sqlite3 or mcap storage),
  types from the definitions stored in the bag (or a fallback typestore, see ``open_log``).
* ``*.csv`` — a trace of FRET variables: a header row of variable names, one row per tick.

Every source gives :class:`Message` tuples in non-decreasing log time, streaming: memory does
not grow with the length of the log.  Damage is recorded as :class:`~monitors.problems.DataProblem`
in ``source.problems`` and reading goes on; see :class:`LogSource`.

Times are integer nanoseconds since the epoch of the recording clock (MCAP ``log_time``,
rosbag ``timestamp``).
"""

from __future__ import annotations

import csv
import heapq
import io
import os
import re
import struct
import zlib
from decimal import Decimal, InvalidOperation
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Callable, Iterator, NamedTuple

from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, ChunkIndex, DataEnd, Footer, Header, Message as McapMessage
from mcap.records import Schema, Statistics
from mcap.stream_reader import CRCValidationError, breakup_chunk
from rosbags.interfaces import MessageDefinitionFormat
from rosbags.serde import SerdeError
from rosbags.typesys import Stores, TypesysError, get_types_from_idl, get_types_from_msg, get_typestore
from rosbags.typesys.msg import normalize_msgtype
from rosbags.typesys.store import Typestore

from fretish.units import NS_PER_S

from . import problems as P
from .problems import CsvError, DataProblem, LogError, ProblemLog
from .selective import chunk_messages

__all__ = [
    "Message",
    "LogSource",
    "schema_decoder",
    "McapSource",
    "BagSource",
    "CsvSource",
    "CsvRow",
    "open_log",
    "CSV_TOPIC",
    "CSV_TYPE",
    "LASER_SCAN",
    "REORDER_WINDOW_NS",
]

MCAP_MAGIC = b"\x89MCAP0\r\n"  # MCAP spec, "Magic"
_HEAD = struct.Struct("<BQ")  # opcode, record length (MCAP spec, "Records")
_FOOTER_LEN = 1 + 8 + 8 + 8 + 4  # opcode, length, summary_start, summary_offset_start, summary_crc
_DATA_END_LEN = 1 + 8 + 4  # opcode, length, data_section_crc
_MAX_UNCOMPRESSED = 4 * 2**30  # a chunk claiming more than this is treated as corrupt

#: Messages read without an index (linear pass) are held this long (log time) so that slightly
#: out-of-order chunks or loose messages are still delivered in log-time order.  A message later
#: than this is recorded as an ``out_of_order`` DataProblem and skipped.
REORDER_WINDOW_NS = NS_PER_S

#: Pseudo-topic of a CSV trace: one message per row; ``data`` has one attribute per column.
CSV_TOPIC = "/csv"
#: Type name reported by ``CsvSource.topics()``.
CSV_TYPE = "fretc/msg/CsvRow"
#: rosbags' normalized name of sensor_msgs/LaserScan (REP 117 applies to its ``ranges``).
LASER_SCAN = "sensor_msgs/msg/LaserScan"


class Message(NamedTuple):
    """One decoded message.

    Attributes:
        topic: the topic name (``/scan``), or :data:`CSV_TOPIC` for CSV rows.
        log_time: ns, when the recorder received it (MCAP ``log_time``; rosbag timestamp).
        publish_time: ns, when it was published (MCAP ``publish_time``; for bags and CSV, equal
            to ``log_time`` since they do not record it).
        header_stamp: ns, ``data.header.stamp`` (``sec * 1e9 + nanosec``) when the message has
            a std_msgs/Header, else None.
        data: the decoded message: a rosbags message object (attribute access:
            ``data.twist.linear.x``; primitive arrays are numpy arrays), or for CSV a
            SimpleNamespace of the row's values.
    """

    topic: str
    log_time: int
    publish_time: int
    header_stamp: int | None
    data: Any


def header_stamp(data: Any) -> int | None:
    """``data.header.stamp`` in ns (std_msgs/Header: ``stamp.sec * 1e9 + stamp.nanosec``), or None."""
    header = getattr(data, "header", None)
    stamp = getattr(header, "stamp", None)
    if stamp is None:
        return None
    try:
        return int(stamp.sec) * NS_PER_S + int(stamp.nanosec)
    except AttributeError:
        return None


class LogSource:
    """A recorded run, read as a stream of :class:`Message` in log-time order.

    Attributes:
        path: the file or folder given to :func:`open_log`.
        kind: ``"mcap"``, ``"bag"`` (ROS 1), ``"rosbag2"`` or ``"csv"``.
        counts: messages delivered per topic by the most recent :meth:`messages` pass
            (filled while iterating).
        partial: True when the log is damaged: it ends early (truncated or unreadable from
            some point on), a part of it was skipped (a chunk failing its CRC, a record that
            does not parse: a *gap*), or its summary or data-section CRC is damaged.
        damage_time: where the intact span ends: the log time (ns) of the last good message
            read before a truncation, or the first log time of the first gap; None when the
            damage loses no message (summary, data CRC) or when nothing was read before it.
            Only ticks strictly before it are judged (../shared/DESIGN.md "Damage is never evidence").
        gaps: ``(start, end)`` log-time spans (ns, inclusive; ``end`` None when unknown) of the
            data skipped in the latest pass, in the order found.
        damage_cut: True when the damage loses messages (truncation or gap), so that only the
            span before ``damage_time`` was read completely; False for damage that loses none
            (summary, data-section CRC).

    ``problems`` lists the damage found at open time and during the most recent pass (capped
    per kind and topic, see :mod:`monitors.problems`); ``problem_counts`` counts all of it.
    """

    path: str
    kind: str

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = str(path)
        self.counts: dict[str, int] = {}
        self.partial = False
        self.damage_time: int | None = None
        self.damage_cut = False
        self.gaps: list[tuple[int | None, int | None]] = []
        self._open_damage = False  # damage found at open time (summary): every pass is partial
        self._open_problems = ProblemLog()
        self._pass_problems = ProblemLog()
        self._start_time: int | None = None
        self._end_time: int | None = None

    # -- problems -------------------------------------------------------------------------------
    @property
    def problems(self) -> list[DataProblem]:
        """Damage found when opening and during the latest pass, in the order found."""
        return self._open_problems.problems + self._pass_problems.problems

    @property
    def problem_counts(self) -> dict[tuple[str, str | None], int]:
        """Number of problems per (kind, topic), including those beyond the kept cap."""
        out = dict(self._open_problems.counts)
        for k, v in self._pass_problems.counts.items():
            out[k] = out.get(k, 0) + v
        return out

    def _problem(self, kind: str, topic: str | None, log_time: int | None, detail: str,
                 end_time: int | None = None) -> None:
        self._pass_problems.add(DataProblem(kind, topic, log_time, detail, end_time))

    def _begin_pass(self) -> None:
        self.counts = {}
        self.partial = self._open_damage
        self.damage_time = None
        self.damage_cut = False
        self.gaps = []
        self._pass_problems = ProblemLog()

    def _gap(self, start: int | None, end: int | None = None) -> None:
        """Record data lost from log time ``start`` (None: unknown, then the intact span
        ends at ``start``'s best bound the caller passes) to ``end``: the log is partial and
        its intact span ends at the earliest gap."""
        self.partial = True
        self.damage_cut = True
        self.gaps.append((start, end))
        if start is not None and (self.damage_time is None or start < self.damage_time):
            self.damage_time = start

    @property
    def intact_end(self) -> int | None:
        """Exclusive log-time bound (ns) of the span read completely in the latest pass: None
        when no message was lost (``damage_cut`` False); a value below every log time when
        nothing before the damage is intact."""
        if not self.damage_cut:
            return None
        if self.damage_time is None or any(start is None for start, _ in self.gaps):
            return -(2**63)
        return self.damage_time

    # -- interface ------------------------------------------------------------------------------
    @property
    def start_time(self) -> int | None:
        """Log time (ns) of the first message, when known (index, or after a full pass)."""
        return self._start_time

    @property
    def end_time(self) -> int | None:
        """Log time (ns) of the last message, when known (index, or after a full pass)."""
        return self._end_time

    def topics(self) -> dict[str, str]:
        """Topic → message type name (rosbags' normalized ``pkg/msg/Type``), sorted by topic."""
        raise NotImplementedError

    def messages(self, topics: set[str] | frozenset[str] | None = None) -> Iterator[Message]:
        """Decoded messages of ``topics`` (all when None), in non-decreasing log time.

        Each call is a fresh pass over the log; ``counts``, ``partial``, ``damage_time`` and
        the pass's problems are reset at its start and filled while iterating.
        """
        raise NotImplementedError

    def close(self) -> None:
        """Release resources (sources open files only while iterating; this is a no-op)."""

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.kind} {self.path!r}>"


# ------------------------------------------------------------------------------------------------
# Types from embedded schemas
# ------------------------------------------------------------------------------------------------

_IDL_SEP = "=" * 80 + "\n"


class _Unsupported(Exception):
    pass


def build_typestore(schema_encoding: str, name: str, text: str) -> tuple[Typestore, str]:
    """A fresh rosbags Typestore holding the types of one embedded schema.

    Args:
        schema_encoding: ``"ros2msg"``, ``"ros1msg"`` (concatenated .msg text with
            ``MSG: pkg/Type`` sections) or ``"ros2idl"`` (``IDL: pkg/msg/Type`` sections),
            per the MCAP spec's well-known schema encodings.
        name: the schema (message type) name, ROS 1 or ROS 2 spelling.
        text: the schema data as text.

    Returns:
        (typestore, normalized type name).

    Raises:
        _Unsupported: unknown schema encoding, or a definition rosbags cannot parse.
    """
    typename = normalize_msgtype(name)
    if not text.strip():
        raise _Unsupported(f"schema {name!r} is empty")
    try:
        if schema_encoding in ("ros2msg", "ros1msg"):
            typs = get_types_from_msg(text, typename)
        elif schema_encoding == "ros2idl":
            typs = {}
            if text.startswith(_IDL_SEP + "IDL: "):
                for part in text.split(_IDL_SEP)[1:]:
                    _hdr, idl = part.split("\n", 1)
                    typs.update(get_types_from_idl(idl))
            else:
                typs.update(get_types_from_idl(text))
        else:
            raise _Unsupported(f"schema encoding {schema_encoding!r} is not supported "
                               "(supported: ros2msg, ros2idl, ros1msg)")
        store = get_typestore(Stores.EMPTY)
        store.register(typs)
        store.get_msgdef(typename)  # fails now, not on the first message, if incomplete
    except _Unsupported:
        raise
    except (TypesysError, KeyError, ValueError, AssertionError, IndexError) as exc:
        raise _Unsupported(f"schema {name!r} ({schema_encoding}) cannot be parsed: {exc}") from None
    except Exception as exc:  # rosbags' PEG parser raises plain exceptions on bad text
        raise _Unsupported(f"schema {name!r} ({schema_encoding}) cannot be parsed: {exc}") from None
    return store, typename


def _decoder_for(store: Typestore, typename: str, message_encoding: str,
                 fields: Any = None) -> Callable[[bytes], Any]:
    if message_encoding == "cdr":
        deser = store.deserialize_cdr
    elif message_encoding == "ros1":
        deser = store.deserialize_ros1
    else:
        raise _Unsupported(f"message encoding {message_encoding!r} is not supported (cdr, ros1)")

    def decode(raw: bytes) -> Any:
        return deser(raw, typename)

    if fields is not None:  # only the fields the bindings read (monitors.selective)
        from .selective import selective_decoder
        return selective_decoder(store, typename, message_encoding, fields, decode) or decode
    return decode


_SCHEMA_FOR_ENCODING = {"cdr": ("ros2msg", "ros2idl"), "ros1": ("ros1msg",)}


def schema_decoder(message_encoding: str, schema_encoding: str | None, schema_name: str | None,
                   schema_text: str | None, fields: Any = None) -> Callable[[bytes], Any]:
    """A function ``bytes -> rosbags message`` for one channel, with its types built from the
    schema text the channel carries (an MCAP Schema record, or a Foxglove WebSocket
    ``advertise``): shared by the log readers and ``fretc watch``.

    Args:
        message_encoding: ``"cdr"`` (ROS 2) or ``"ros1"`` (MCAP well-known message encodings).
        schema_encoding: ``"ros2msg"``, ``"ros2idl"`` or ``"ros1msg"`` (well-known schema
            encodings), matching the message encoding; None or ``""`` when the channel has none.
        schema_name: the message type (``pkg/msg/Type`` or ``pkg/Type``).
        schema_text: the definition text (see :func:`build_typestore`).
        fields: field paths to decode (:mod:`monitors.selective`); None: every field.

    Raises:
        _Unsupported: an unsupported message encoding, a channel without schema, a schema
            encoding that does not go with the message encoding, or a schema rosbags cannot
            parse (the message says which).
    """
    if message_encoding not in _SCHEMA_FOR_ENCODING:
        raise _Unsupported(f"message encoding {message_encoding!r} is not supported (cdr, ros1)")
    if not schema_encoding or not schema_name or schema_text is None:
        raise _Unsupported("the channel has no schema")
    if schema_encoding not in _SCHEMA_FOR_ENCODING[message_encoding]:
        raise _Unsupported(f"schema encoding {schema_encoding!r} does not go with message "
                           f"encoding {message_encoding!r}")
    store, typename = build_typestore(schema_encoding, schema_name, schema_text)
    return _decoder_for(store, typename, message_encoding, fields)


#: Exceptions a decoder from :func:`schema_decoder` raises on a payload that does not match.
DECODE_ERRORS = _DECODE_ERRORS = (SerdeError, struct.error, IndexError, ValueError, AssertionError, UnicodeDecodeError,
                  KeyError, TypeError, OverflowError)


# ------------------------------------------------------------------------------------------------
# MCAP
# ------------------------------------------------------------------------------------------------


class _McapIndex(NamedTuple):
    schemas: dict[int, Schema]
    channels: dict[int, Channel]
    chunk_indexes: list[ChunkIndex]
    statistics: Statistics | None
    data_end_offset: int  # byte offset of the DataEnd record
    data_section_crc: int


def _parse_record(opcode: int, body: bytes) -> Any:
    """Parse one record body with the mcap package's record classes (None if not needed)."""
    stream = ReadDataStream(io.BytesIO(body))
    if opcode == Opcode.MESSAGE:
        return McapMessage.read(stream, len(body))
    cls = _RECORD_CLASSES.get(opcode)
    return cls.read(stream) if cls is not None else None


_RECORD_CLASSES = {Opcode.CHUNK: Chunk, Opcode.SCHEMA: Schema, Opcode.CHANNEL: Channel,
                   Opcode.HEADER: Header, Opcode.DATA_END: DataEnd, Opcode.FOOTER: Footer,
                   Opcode.CHUNK_INDEX: ChunkIndex, Opcode.STATISTICS: Statistics}


_RECORD_ERRORS = (McapError, struct.error, UnicodeDecodeError, ValueError, EOFError, MemoryError,
                  OverflowError)


def _chunk_records(chunk: Chunk) -> list[Any]:
    """Records inside ``chunk``, CRC-checked (MCAP spec, "Chunk": uncompressed_crc)."""
    if chunk.uncompressed_size > _MAX_UNCOMPRESSED:
        raise ValueError(f"chunk claims {chunk.uncompressed_size} uncompressed bytes")
    return breakup_chunk(chunk, validate_crc=True)


class McapSource(LogSource):
    """An MCAP file (any profile); see the module docstring and :class:`LogSource`.

    Reading strategy:

    * A valid Footer with a summary holding ChunkIndex records (and a matching summary CRC):
      chunks are read through the index in ``message_start_time`` order and merged so messages
      come out in exact log-time order (ties: file position), skipping chunks holding none of
      the wanted topics.  A chunk that is damaged (bad record, CRC mismatch, undecompressable)
      is skipped with a DataProblem and reading goes on with the next chunk; it is a *gap*
      (``gaps``): the log is ``partial`` and its intact span ends where the gap starts
      (``intact_end``; the audit judges only the ticks before it).  After a full
      pass the data-section CRC (DataEnd record) is checked once.
    * Otherwise (no summary, crashed recording, bad footer): records are read one by one from
      the start (framing: 1-byte opcode, 8-byte length).  A record whose body is damaged is
      skipped; a record running past the end of the file ends the pass: ``partial`` is set,
      ``damage_time`` is the last good message's log time, and a ``truncated`` problem gives
      the byte offset.  Messages are held for :data:`REORDER_WINDOW_NS` to restore log-time
      order.

    Channels whose schema is missing, unparsable, or of an unsupported encoding yield an
    ``unknown_schema`` / ``unknown_encoding`` problem once and their messages are skipped;
    other topics go on.
    """

    kind = "mcap"

    def __init__(self, path: str | os.PathLike, *, check_data_crc: bool = True) -> None:
        super().__init__(path)
        self.check_data_crc = check_data_crc
        try:
            self._size = os.path.getsize(self.path)
            with open(self.path, "rb") as f:
                magic = f.read(len(MCAP_MAGIC))
        except OSError as exc:
            raise LogError(path, f"cannot read: {exc.strerror or exc}") from None
        if magic != MCAP_MAGIC:
            raise LogError(path, "not an MCAP file (bad magic at byte 0)")
        self.profile = ""
        self._index: _McapIndex | None = self._read_index()
        self.partial = self._open_damage
        self._scanned: tuple[dict[int, Schema], dict[int, Channel]] | None = None
        self._data_crc_checked = False
        self._decoders: dict[int, Callable[[bytes], Any] | None] = {}
        if self._index is not None:
            st = self._index.statistics
            if st is not None and st.message_count:
                self._start_time, self._end_time = st.message_start_time, st.message_end_time
            elif self._index.chunk_indexes:
                self._start_time = min(c.message_start_time for c in self._index.chunk_indexes)
                self._end_time = max(c.message_end_time for c in self._index.chunk_indexes)

    # -- index --------------------------------------------------------------------------------
    def _read_index(self) -> _McapIndex | None:
        """The summary section, or None when absent or unusable (then read linearly)."""
        with open(self.path, "rb") as f:
            head = f.read(len(MCAP_MAGIC) + 9)
            if len(head) == len(MCAP_MAGIC) + 9 and head[8] == Opcode.HEADER:
                length = _HEAD.unpack_from(head, 8)[1]
                if length < self._size:
                    try:
                        self.profile = _parse_record(Opcode.HEADER, f.read(length)).profile
                    except _RECORD_ERRORS:
                        pass
            if self._size < 2 * len(MCAP_MAGIC) + _FOOTER_LEN + _DATA_END_LEN:
                return None
            f.seek(self._size - len(MCAP_MAGIC))
            if f.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
                return None  # no trailing magic: crashed recording; the linear pass reports it
            footer_pos = self._size - len(MCAP_MAGIC) - _FOOTER_LEN
            f.seek(footer_pos)
            raw = f.read(_FOOTER_LEN)
            opcode, length = _HEAD.unpack_from(raw)
            if opcode != Opcode.FOOTER or length != _FOOTER_LEN - 9:
                self._open_damage = True
                self._open_problems.add(DataProblem(
                    P.SUMMARY_CORRUPT, None, None,
                    f"no Footer record at byte {footer_pos}; reading without the index"))
                return None
            footer = _parse_record(Opcode.FOOTER, raw[9:])
            if footer.summary_start == 0:
                data_end_offset = footer_pos - _DATA_END_LEN
                summary_bytes = b""
            else:
                if not (0 < footer.summary_start <= footer_pos):
                    self._open_damage = True
                    self._open_problems.add(DataProblem(
                        P.SUMMARY_CORRUPT, None, None,
                        f"Footer summary_start {footer.summary_start} is outside the file; "
                        "reading without the index"))
                    return None
                data_end_offset = footer.summary_start - _DATA_END_LEN
                f.seek(footer.summary_start)
                summary_bytes = f.read(footer_pos - footer.summary_start)
            if footer.summary_crc != 0:
                crc = zlib.crc32(raw[: _FOOTER_LEN - 4], zlib.crc32(summary_bytes))
                if crc != footer.summary_crc:
                    self._open_damage = True
                    self._open_problems.add(DataProblem(
                        P.SUMMARY_CORRUPT, None, None,
                        f"summary CRC mismatch (Footer says {footer.summary_crc:#010x}, "
                        f"computed {crc:#010x}); reading without the index"))
                    return None
            data_section_crc = 0
            if data_end_offset >= len(MCAP_MAGIC):
                f.seek(data_end_offset)
                raw_de = f.read(_DATA_END_LEN)
                if len(raw_de) == _DATA_END_LEN and raw_de[0] == Opcode.DATA_END:
                    data_section_crc = struct.unpack_from("<I", raw_de, 9)[0]
            if footer.summary_start == 0:
                return None  # valid file without a summary: linear pass
        schemas: dict[int, Schema] = {}
        channels: dict[int, Channel] = {}
        chunk_indexes: list[ChunkIndex] = []
        statistics = None
        pos = 0
        try:
            while pos < len(summary_bytes):
                opcode, length = _HEAD.unpack_from(summary_bytes, pos)
                body = summary_bytes[pos + 9: pos + 9 + length]
                if len(body) != length:
                    raise ValueError("record runs past the summary section")
                rec = _parse_record(opcode, body)
                if isinstance(rec, Schema):
                    schemas[rec.id] = rec
                elif isinstance(rec, Channel):
                    channels[rec.id] = rec
                elif isinstance(rec, ChunkIndex):
                    chunk_indexes.append(rec)
                elif isinstance(rec, Statistics):
                    statistics = rec
                pos += 9 + length
        except _RECORD_ERRORS as exc:
            self._open_damage = True
            self._open_problems.add(DataProblem(
                P.SUMMARY_CORRUPT, None, None,
                f"summary record at byte {footer.summary_start + pos} unreadable ({exc}); "
                "reading without the index"))
            return None
        if not chunk_indexes:
            return None  # unchunked file: the linear pass reads its loose messages
        chunk_indexes.sort(key=lambda c: (c.message_start_time, c.chunk_start_offset))
        return _McapIndex(schemas, channels, chunk_indexes, statistics, data_end_offset,
                          data_section_crc)

    @property
    def indexed(self) -> bool:
        """True when the file is read through its summary's chunk indexes."""
        return self._index is not None

    def _channels(self) -> tuple[dict[int, Schema], dict[int, Channel]]:
        if self._index is not None:
            return self._index.schemas, self._index.channels
        if self._scanned is None:
            for _ in self._linear(wanted=frozenset(), decode=False):
                pass
            assert self._scanned is not None
        return self._scanned

    def topics(self) -> dict[str, str]:
        """Topic → type name (normalized ``pkg/msg/Type``; ``""`` for a channel without schema).

        From the summary when there is one, else from a scan of the whole file (Channel and
        Schema records, chunks decompressed but messages not decoded).
        """
        schemas, channels = self._channels()
        out: dict[str, str] = {}
        for cid in sorted(channels):
            ch = channels[cid]
            sc = schemas.get(ch.schema_id)
            out.setdefault(ch.topic, normalize_msgtype(sc.name) if sc is not None and sc.name else "")
        return dict(sorted(out.items()))

    # -- decoding -------------------------------------------------------------------------------
    def _decoder(self, channel: Channel, schemas: dict[int, Schema], log_time: int
                 ) -> Callable[[bytes], Any] | None:
        if channel.id in self._decoders:
            return self._decoders[channel.id]
        dec = None
        schema = schemas.get(channel.schema_id)
        try:
            if (channel.message_encoding in _SCHEMA_FOR_ENCODING
                    and (channel.schema_id == 0 or schema is None)):
                raise _Unsupported(f"channel {channel.id} has no schema (schema id "
                                   f"{channel.schema_id})")
            dec = schema_decoder(channel.message_encoding, schema and schema.encoding,
                                 schema and schema.name,
                                 schema and schema.data.decode("utf-8", errors="replace"),
                                 (getattr(self, "_wanted_fields", None) or {}).get(channel.topic))
        except _Unsupported as exc:
            kind = (P.UNKNOWN_ENCODING if channel.message_encoding not in _SCHEMA_FOR_ENCODING
                    else P.UNKNOWN_SCHEMA)
            self._open_problems.add(DataProblem(
                kind, channel.topic, log_time,
                f"{exc}; messages on this topic are skipped"))
        self._decoders[channel.id] = dec
        return dec

    # -- passes ---------------------------------------------------------------------------------
    def messages(self, topics: set[str] | frozenset[str] | None = None) -> Iterator[Message]:
        """Decoded messages of ``topics`` (all when None) in non-decreasing log time.

        See the class docstring for damage handling.  ``counts`` is per topic.
        """
        self._begin_pass()
        if self._index is not None:
            yield from self._indexed(topics)
        else:
            wanted = None if topics is None else frozenset(topics)
            yield from self._linear(wanted=wanted, decode=True)

    def _deliver(self, channel: Channel, rec: McapMessage, schemas: dict[int, Schema]
                 ) -> Message | None:
        dec = self._decoder(channel, schemas, rec.log_time)
        if dec is None:
            return None
        try:
            data = dec(rec.data)
        except _DECODE_ERRORS as exc:
            self._problem(P.UNDECODABLE, channel.topic, rec.log_time,
                          f"payload of {len(rec.data)} bytes does not deserialize "
                          f"({type(exc).__name__}: {exc}); message skipped")
            return None
        topic = channel.topic
        self.counts[topic] = self.counts.get(topic, 0) + 1
        return Message(topic, rec.log_time, rec.publish_time, header_stamp(data), data)

    def _indexed(self, topics: set[str] | frozenset[str] | None) -> Iterator[Message]:
        index = self._index
        assert index is not None
        wanted = {cid for cid, ch in index.channels.items() if topics is None or ch.topic in topics}
        heap: list[tuple] = []
        for ci in index.chunk_indexes:
            if ci.message_index_offsets and not wanted.intersection(ci.message_index_offsets):
                continue
            heap.append((ci.message_start_time, ci.chunk_start_offset, -1, ci))
        heapq.heapify(heap)
        with open(self.path, "rb") as f:
            while heap:
                log_time, offset, seq, item = heapq.heappop(heap)
                if seq >= 0:
                    channel_id, rec = item
                    msg = self._deliver(index.channels[channel_id], rec, index.schemas)
                    if msg is not None:
                        yield msg
                    continue
                ci: ChunkIndex = item
                try:
                    f.seek(ci.chunk_start_offset)
                    raw = f.read(ci.chunk_length)
                    if len(raw) != ci.chunk_length:
                        raise ValueError(f"file ends inside the chunk (need {ci.chunk_length} bytes)")
                    opcode, length = _HEAD.unpack_from(raw)
                    if opcode != Opcode.CHUNK or 9 + length != ci.chunk_length:
                        raise ValueError(f"no Chunk record at byte {ci.chunk_start_offset}")
                    chunk = _parse_record(Opcode.CHUNK, raw[9:])
                    if chunk.uncompressed_size > _MAX_UNCOMPRESSED:
                        raise ValueError(f"chunk claims {chunk.uncompressed_size} uncompressed bytes")
                    # only the messages of wanted (or unknown) channels are parsed
                    records = chunk_messages(chunk, wanted, index.channels)
                except CRCValidationError as exc:
                    self._gap(ci.message_start_time, ci.message_end_time)
                    self._problem(P.CHUNK_CRC, None, ci.message_start_time,
                                  f"chunk at byte {ci.chunk_start_offset}: {exc}; its messages "
                                  f"are skipped: a gap in the log{_GAP_NOTE}", ci.message_end_time)
                    continue
                except Exception as exc:  # mcap, struct, zstd and lz4 raise their own errors
                    self._gap(ci.message_start_time, ci.message_end_time)
                    self._problem(P.CHUNK_CORRUPT, None, ci.message_start_time,
                                  f"chunk at byte {ci.chunk_start_offset} unreadable "
                                  f"({type(exc).__name__}: {exc}); its messages are skipped: a "
                                  f"gap in the log{_GAP_NOTE}", ci.message_end_time)
                    continue
                n = 0
                for rec in records:
                    if isinstance(rec, McapMessage) and rec.channel_id in wanted:
                        heapq.heappush(heap, (rec.log_time, ci.chunk_start_offset, n,
                                              (rec.channel_id, rec)))
                        n += 1
                    elif isinstance(rec, McapMessage) and rec.channel_id not in index.channels:
                        self._gap(rec.log_time, rec.log_time)
                        self._problem(P.UNKNOWN_CHANNEL, None, rec.log_time,
                                      f"message on channel id {rec.channel_id} that the summary "
                                      "does not define; skipped")
        if self.check_data_crc and not self._data_crc_checked:
            self._check_data_crc()

    def _check_data_crc(self) -> None:
        """Check the DataEnd data_section_crc (MCAP spec): CRC-32 of bytes [0, DataEnd)."""
        self._data_crc_checked = True
        index = self._index
        if index is None or index.data_section_crc == 0:
            return
        crc = 0
        remaining = index.data_end_offset
        with open(self.path, "rb") as f:
            while remaining > 0:
                block = f.read(min(remaining, 1 << 20))
                if not block:
                    break
                crc = zlib.crc32(block, crc)
                remaining -= len(block)
        if crc != index.data_section_crc:
            self._open_damage = True
            self.partial = True
            self._open_problems.add(DataProblem(
                P.DATA_CRC, None, None,
                f"data section CRC mismatch (DataEnd says {index.data_section_crc:#010x}, "
                f"computed {crc:#010x}): bytes outside the chunks are damaged"))

    def _chunk_gap(self, chunk: Chunk, last_good: int | None) -> None:
        """A skipped chunk read without the index: its header's times are not covered by a
        CRC, so the gap starts no later than the last good message read before it."""
        start = chunk.message_start_time
        self._gap(start if last_good is None else min(start, last_good), chunk.message_end_time)

    def _linear(self, wanted: frozenset[str] | None, decode: bool) -> Iterator[Message]:
        """Record-by-record pass from byte 0 (no usable index).

        ``wanted`` None means all topics; ``decode`` False only collects channels and times.
        """
        schemas: dict[int, Schema] = {}
        channels: dict[int, Channel] = {}
        heap: list[tuple] = []
        watermark: int | None = None
        released: int | None = None  # log time of the last message delivered
        last_good: int | None = None  # latest log time read intact (file order)
        first_time: int | None = None
        reported_channels: set[int] = set()
        seq = 0

        def take(rec: McapMessage, pos: int) -> None:
            nonlocal seq, last_good, first_time
            ch = channels.get(rec.channel_id)
            last_good = rec.log_time if last_good is None else max(last_good, rec.log_time)
            first_time = rec.log_time if first_time is None else min(first_time, rec.log_time)
            if ch is None:
                if decode:
                    self._gap(rec.log_time, rec.log_time)
                if rec.channel_id not in reported_channels:
                    reported_channels.add(rec.channel_id)
                    self._problem(P.UNKNOWN_CHANNEL, None, rec.log_time,
                                  f"message at byte {pos} on channel id {rec.channel_id}, which is "
                                  "not defined (its Channel record was lost?); its messages are "
                                  "skipped")
                return
            if not decode or (wanted is not None and ch.topic not in wanted):
                return
            heapq.heappush(heap, (rec.log_time, pos, seq, rec))
            seq += 1

        def absorb(records: list[Any], pos: int) -> int:
            """Take the schemas, channels and messages of one chunk; returns the number of
            messages."""
            n = 0
            for r in records:
                if isinstance(r, Schema):
                    schemas[r.id] = r
                elif isinstance(r, Channel):
                    channels[r.id] = r
                elif isinstance(r, McapMessage):
                    take(r, pos)
                    n += 1
            return n

        def release(limit: int | None) -> Iterator[Message]:
            nonlocal released
            while heap and (limit is None or heap[0][0] < limit):
                log_time, _pos, _seq, rec = heapq.heappop(heap)
                if released is not None and log_time < released:
                    # without an index only damage (a log time or chunk header changed) puts a
                    # message this far out of order: a gap at its log time
                    self._gap(log_time, log_time)
                    self._problem(P.OUT_OF_ORDER, channels[rec.channel_id].topic, log_time,
                                  f"message is {released - log_time} ns older than one already "
                                  f"delivered (beyond the {REORDER_WINDOW_NS} ns reorder window); "
                                  "skipped")
                    continue
                msg = self._deliver(channels[rec.channel_id], rec, schemas)
                if msg is not None:
                    released = log_time
                    yield msg

        with open(self.path, "rb") as f:
            f.seek(len(MCAP_MAGIC))
            crc = zlib.crc32(MCAP_MAGIC)
            while True:
                pos = f.tell()
                head = f.read(9)
                if len(head) < 9 or pos + 9 + _HEAD.unpack(head)[1] > self._size:
                    if len(head) == 0:
                        what = f"file ends at byte {pos} without DataEnd/Footer records"
                    else:
                        what = (f"file ends at byte {self._size} inside the record starting at "
                                f"byte {pos}")
                        if len(head) == 9 and head[0] == Opcode.CHUNK:
                            start = _peek_chunk_start(f, pos)
                            if start is not None:
                                what += f" (a Chunk whose messages start at log time {start})"
                            f.seek(pos + 9)
                            n_msgs = absorb(_truncated_chunk_records(f.read()), pos)
                            if n_msgs:
                                what += (f"; {n_msgs} complete messages recovered from the cut "
                                         "chunk (unverified: its CRC covers the whole chunk)")
                    self._gap(last_good)
                    self._problem(P.TRUNCATED, None, last_good,
                                  f"{what}; read up to there (crashed or cut recording)")
                    break
                opcode, length = _HEAD.unpack(head)
                if opcode == Opcode.DATA_END:
                    body = f.read(length)
                    try:
                        de = _parse_record(opcode, body)
                        if self.check_data_crc and de.data_section_crc not in (0, crc):
                            self.partial = True
                            self._problem(P.DATA_CRC, None, None,
                                          f"data section CRC mismatch (DataEnd says "
                                          f"{de.data_section_crc:#010x}, computed {crc:#010x})")
                    except _RECORD_ERRORS:
                        pass
                    break  # the data section is over; the summary is not needed here
                if opcode == Opcode.FOOTER:
                    break
                if opcode not in (Opcode.CHUNK, Opcode.MESSAGE, Opcode.SCHEMA, Opcode.CHANNEL):
                    crc = _skip(f, length, zlib.crc32(head, crc))
                    continue
                body = f.read(length)
                crc = zlib.crc32(body, zlib.crc32(head, crc))
                try:
                    rec = _parse_record(opcode, body)
                except _RECORD_ERRORS as exc:
                    kind = P.CHUNK_CORRUPT if opcode == Opcode.CHUNK else P.CORRUPT_RECORD
                    if opcode in (Opcode.CHUNK, Opcode.MESSAGE, Opcode.CHANNEL, Opcode.SCHEMA):
                        self._gap(last_good)  # what it held is lost; its times are unknown
                    self._problem(kind, None, last_good,
                                  f"{Opcode(opcode).name} record at byte {pos} unreadable "
                                  f"({type(exc).__name__}: {exc}); skipped")
                    continue
                if isinstance(rec, Schema):
                    schemas[rec.id] = rec
                elif isinstance(rec, Channel):
                    channels[rec.id] = rec
                elif isinstance(rec, McapMessage):
                    watermark = rec.log_time if watermark is None else max(watermark, rec.log_time)
                    yield from release(watermark - REORDER_WINDOW_NS)
                    take(rec, pos)
                elif isinstance(rec, Chunk):
                    try:
                        records = _chunk_records(rec)
                    except CRCValidationError as exc:
                        self._chunk_gap(rec, last_good)
                        self._problem(P.CHUNK_CRC, None, rec.message_start_time,
                                      f"chunk at byte {pos}: {exc}; its messages are skipped: "
                                      f"a gap in the log{_GAP_NOTE}", rec.message_end_time)
                        continue
                    except Exception as exc:  # decompression libraries raise their own errors
                        self._chunk_gap(rec, last_good)
                        self._problem(P.CHUNK_CORRUPT, None, rec.message_start_time,
                                      f"chunk at byte {pos} unreadable ({type(exc).__name__}: "
                                      f"{exc}); its messages are skipped: a gap in the log"
                                      f"{_GAP_NOTE}", rec.message_end_time)
                        continue
                    absorb(records, pos)
                    # the watermark comes from the messages (CRC-checked), not from the chunk
                    # header's message_start_time, which no CRC covers
                    if last_good is not None:
                        watermark = last_good if watermark is None else max(watermark, last_good)
                        yield from release(watermark - REORDER_WINDOW_NS)
        if decode and not self.damage_cut and not _ends_with_footer(f_size=self._size,
                                                                     path=self.path):
            self.partial = True
            self._problem(P.SUMMARY_CORRUPT, None, None,
                          "the file ends after its data section without a Footer and closing "
                          "magic (summary lost); every message was read")
        yield from release(None)
        self._scanned = (schemas, channels)
        if first_time is not None:
            self._start_time, self._end_time = first_time, last_good


_GAP_NOTE = "; the log is audited up to its start (nothing is held across a gap)"


def _ends_with_footer(f_size: int, path: str) -> bool:
    """True when the file ends with a Footer record and the closing magic (MCAP spec)."""
    if f_size < len(MCAP_MAGIC) + _FOOTER_LEN:
        return False
    with open(path, "rb") as f:
        f.seek(f_size - len(MCAP_MAGIC) - _FOOTER_LEN)
        tail = f.read(len(MCAP_MAGIC) + _FOOTER_LEN)
    return tail[-len(MCAP_MAGIC):] == MCAP_MAGIC and tail[0] == Opcode.FOOTER


def _truncated_chunk_records(tail: bytes) -> list[Any]:
    """The complete records at the start of a Chunk record cut short by the end of the file.

    ``tail`` is what the file holds after the chunk's 9-byte record header. Layout (MCAP
    spec, "Chunk"): message_start_time u64, message_end_time u64, uncompressed_size u64,
    uncompressed_crc u32, compression (u32 length + bytes), records (u64 length + bytes).
    The compressed prefix is decompressed as a stream (zstd, lz4 frames or none) and parsed
    record by record until a record is incomplete. Returns [] when nothing can be recovered.
    """
    try:
        (clen,) = struct.unpack_from("<I", tail, 28)
        compression = tail[32:32 + clen].decode("ascii")
        data = tail[32 + clen + 8:]
        if compression == "":
            raw = data
        elif compression == "zstd":
            import zstandard

            raw = zstandard.ZstdDecompressor().decompressobj().decompress(data)
        elif compression == "lz4":
            import lz4.frame

            raw = lz4.frame.LZ4FrameDecompressor().decompress(data)
        else:
            return []
    except Exception:  # a cut header or a cut compressed stream: nothing to recover
        return []
    records: list[Any] = []
    at = 0
    while at + 9 <= len(raw):
        opcode, length = _HEAD.unpack_from(raw, at)
        if at + 9 + length > len(raw):
            break
        try:
            rec = _parse_record(opcode, raw[at + 9:at + 9 + length])
        except _RECORD_ERRORS:
            break
        if rec is not None:
            records.append(rec)
        at += 9 + length
    return records


def _peek_chunk_start(f: io.BufferedReader, pos: int) -> int | None:
    """message_start_time of the (truncated) Chunk record at ``pos``, if its first field is there."""
    here = f.tell()
    try:
        f.seek(pos + 9)
        raw = f.read(8)
        return struct.unpack("<Q", raw)[0] if len(raw) == 8 else None
    finally:
        f.seek(here)


def _skip(f: io.BufferedReader, length: int, crc: int) -> int:
    """Read past ``length`` bytes in blocks (for the data CRC) without holding them."""
    while length > 0:
        block = f.read(min(length, 1 << 20))
        if not block:
            break
        crc = zlib.crc32(block, crc)
        length -= len(block)
    return crc


# ------------------------------------------------------------------------------------------------
# ROS 1 bags and rosbag2 folders
# ------------------------------------------------------------------------------------------------


def _bag_errors() -> tuple[type[BaseException], ...]:
    from rosbags.rosbag1 import ReaderError as ReaderError1
    from rosbags.rosbag2 import ReaderError as ReaderError2

    return (ReaderError1, ReaderError2, OSError, struct.error, EOFError, ValueError, KeyError,
            IndexError, zlib.error)


_BAG_ERRORS = _bag_errors()


class BagSource(LogSource):
    """A ROS 1 ``.bag`` file (kind ``"bag"``) or a rosbag2 folder (kind ``"rosbag2"``).

    Read with rosbags.rosbag1.Reader / rosbags.rosbag2.Reader.  Each connection's type is built
    from the definition stored in the bag (ROS 1 connection header ``message_definition``;
    rosbag2 ``message_definition`` / mcap schema).  A connection without one uses
    ``fallback_typestore`` if given, else its topic gets an ``unknown_schema`` problem.
    Bags do not record a publish time: ``Message.publish_time == log_time``.

    Raises:
        LogError: the bag cannot be opened (e.g. an unindexed ROS 1 bag from a crashed
            recording: run ``rosbag reindex`` first).
    """

    def __init__(self, path: str | os.PathLike, *, fallback_typestore: Typestore | None = None) -> None:
        super().__init__(path)
        p = Path(path)
        self.kind = "rosbag2" if p.is_dir() else "bag"
        self._fallback = fallback_typestore
        self._decoders: dict[int, Callable[[bytes], Any] | None] = {}
        self._topics: dict[str, str] = {}
        self._linear_bag: _Ros1Linear | None = None
        try:
            with self._reader() as reader:
                for c in reader.connections:
                    self._topics.setdefault(c.topic, c.msgtype)
                if reader.message_count:
                    self._start_time = reader.start_time
                    self._end_time = reader.end_time - 1  # rosbags' end_time is one past the last
        except LogError:
            raise
        except Exception as exc:  # rosbags ReaderError and friends
            if self.kind != "bag" or not _is_ros1_bag(p):
                raise LogError(path, f"cannot open {self.kind}: {exc}") from None
            # a ROS 1 bag whose index (at its end) is damaged or missing, as a crashed
            # recording leaves it: read its records from the start, as far as they go
            self._linear_bag = _Ros1Linear(self, str(exc))
            self._open_damage = True
            self.partial = True
            self._topics = self._linear_bag.scan()

    def _reader(self) -> Any:
        if self.kind == "bag":
            from rosbags.rosbag1 import Reader
        else:
            from rosbags.rosbag2 import Reader
        return Reader(Path(self.path))

    def topics(self) -> dict[str, str]:
        """Topic → type name (normalized ``pkg/msg/Type``)."""
        return dict(sorted(self._topics.items()))

    def _decoder(self, conn: Any, log_time: int) -> Callable[[bytes], Any] | None:
        if conn.id in self._decoders:
            return self._decoders[conn.id]
        dec = None
        encoding = "ros1" if self.kind == "bag" else getattr(conn.ext, "serialization_format", "cdr")
        try:
            fmt, text = conn.msgdef.format, conn.msgdef.data
            if fmt == MessageDefinitionFormat.NONE or not text.strip():
                if self._fallback is None or conn.msgtype not in self._fallback.fielddefs:
                    raise _Unsupported(f"the bag stores no definition of {conn.msgtype!r} "
                                       "(pass a fallback typestore)")
                store, typename = self._fallback, conn.msgtype
            else:
                schema_encoding = ("ros1msg" if self.kind == "bag" else
                                   "ros2idl" if fmt == MessageDefinitionFormat.IDL else "ros2msg")
                store, typename = build_typestore(schema_encoding, conn.msgtype, text)
            dec = _decoder_for(store, typename, encoding,
                               (getattr(self, "_wanted_fields", None) or {}).get(conn.topic))
        except _Unsupported as exc:
            kind = P.UNKNOWN_ENCODING if encoding not in _SCHEMA_FOR_ENCODING else P.UNKNOWN_SCHEMA
            self._open_problems.add(DataProblem(kind, conn.topic, log_time,
                                                f"{exc}; messages on this topic are skipped"))
        self._decoders[conn.id] = dec
        return dec

    def messages(self, topics: set[str] | frozenset[str] | None = None) -> Iterator[Message]:
        """Decoded messages of ``topics`` (all when None) in non-decreasing log time.

        A read error part-way (damaged bag) ends the pass with ``partial`` set.
        """
        self._begin_pass()
        if self._linear_bag is not None:
            yield from self._linear_bag.messages(topics)
            return
        last: int | None = None
        try:
            with self._reader() as reader:
                conns = [c for c in reader.connections if topics is None or c.topic in topics]
                if not conns:
                    return
                for conn, log_time, raw in reader.messages(connections=conns):
                    if last is not None and log_time < last:
                        self._problem(P.OUT_OF_ORDER, conn.topic, log_time,
                                      f"message is {last - log_time} ns older than the previous "
                                      "one; skipped")
                        continue
                    dec = self._decoder(conn, log_time)
                    if dec is None:
                        continue
                    try:
                        data = dec(raw)
                    except _DECODE_ERRORS as exc:
                        self._problem(P.UNDECODABLE, conn.topic, log_time,
                                      f"payload of {len(raw)} bytes does not deserialize "
                                      f"({type(exc).__name__}: {exc}); message skipped")
                        continue
                    last = log_time
                    self.counts[conn.topic] = self.counts.get(conn.topic, 0) + 1
                    yield Message(conn.topic, log_time, log_time, header_stamp(data), data)
        except _BAG_ERRORS as exc:  # data corrupt part-way
            self._gap(last)
            self._problem(P.CORRUPT_RECORD, None, last,
                          f"reading stopped: {type(exc).__name__}: {exc}")


_ROS1_MAGIC = b"#ROSBAG V2.0\n"
_OP_MSG, _OP_BAG_HEADER, _OP_CHUNK, _OP_CONN = 0x02, 0x03, 0x05, 0x07


def _is_ros1_bag(path: Path) -> bool:
    try:
        with open(path, "rb") as f:
            return f.read(len(_ROS1_MAGIC)) == _ROS1_MAGIC
    except OSError:
        return False


def _ros1_fields(raw: bytes) -> dict[bytes, bytes]:
    """The ``name=value`` fields of a ROS 1 bag record header (ROS bag format 2.0)."""
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


def _ros1_records(buf: bytes, base: int) -> Iterator[tuple[int, dict[bytes, bytes], bytes]]:
    """(offset, header fields, data) of the complete records in ``buf``; stops at the first
    record cut short (ValueError for a record that does not parse)."""
    pos = 0
    while pos + 4 <= len(buf):
        (hlen,) = struct.unpack_from("<I", buf, pos)
        if pos + 4 + hlen + 4 > len(buf):
            return
        header = _ros1_fields(buf[pos + 4: pos + 4 + hlen])
        (dlen,) = struct.unpack_from("<I", buf, pos + 4 + hlen)
        start = pos + 8 + hlen
        if start + dlen > len(buf):
            return
        yield base + pos, header, buf[start: start + dlen]
        pos = start + dlen


class _Ros1Linear:
    """Record-by-record reading of a ROS 1 bag without its index (ROS bag format 2.0:
    records of a header of ``name=value`` fields and data; ``op`` 0x05 Chunk - bz2, lz4 or
    uncompressed records; 0x07 Connection; 0x02 Message data, ``time`` = sec, nsec u32).
    Everything up to the first record cut short or unreadable is delivered (in log-time
    order, :data:`REORDER_WINDOW_NS` held back); what follows is a truncation."""

    def __init__(self, source: BagSource, why: str) -> None:
        self.src = source
        self.why = why
        self.conns: dict[int, tuple[str, str, str]] = {}  # conn -> (topic, type, definition)

    def scan(self) -> dict[str, str]:
        for _ in self._walk(None, decode=False):
            pass
        return {t: normalize_msgtype(ty) for t, ty, _d in self.conns.values()}

    def messages(self, topics) -> Iterator[Message]:
        yield from self._walk(topics, decode=True)

    def _walk(self, topics, decode: bool) -> Iterator[Message]:
        src = self.src
        data = Path(src.path).read_bytes()
        heap: list[tuple] = []
        seq = 0
        last_good: int | None = None
        released: int | None = None
        decoders: dict[int, Any] = {}

        def take(header: dict[bytes, bytes], body: bytes) -> None:
            nonlocal seq, last_good
            op = header.get(b"op", b"\x00")[:1]
            if op == bytes([_OP_CONN]):
                conn = struct.unpack("<I", header[b"conn"])[0]
                f = _ros1_fields(body)
                self.conns.setdefault(conn, (header.get(b"topic", f.get(b"topic", b"")).decode(),
                                             f.get(b"type", b"").decode(),
                                             f.get(b"message_definition", b"").decode(
                                                 "utf-8", "replace")))
            elif op == bytes([_OP_MSG]):
                conn = struct.unpack("<I", header[b"conn"])[0]
                sec, nsec = struct.unpack("<II", header[b"time"])
                t = sec * NS_PER_S + nsec
                last_good = t if last_good is None else max(last_good, t)
                if decode:
                    heapq.heappush(heap, (t, seq, conn, body))
                    seq += 1

        def release(limit: int | None) -> Iterator[Message]:
            nonlocal released
            while heap and (limit is None or heap[0][0] < limit):
                t, _s, conn, body = heapq.heappop(heap)
                c = self.conns.get(conn)
                if c is None or (topics is not None and c[0] not in topics):
                    continue
                if released is not None and t < released:
                    src._gap(t, t)
                    src._problem(P.OUT_OF_ORDER, c[0], t, "message older than one already "
                                 "delivered beyond the reorder window (no index); skipped")
                    continue
                if conn not in decoders:
                    try:
                        store, typename = build_typestore("ros1msg", c[1], c[2])
                        decoders[conn] = _decoder_for(store, typename, "ros1")
                    except _Unsupported as exc:
                        decoders[conn] = None
                        src._problem(P.UNKNOWN_SCHEMA, c[0], t,
                                     f"{exc}; messages on this topic are skipped")
                dec = decoders[conn]
                if dec is None:
                    continue
                try:
                    msg = dec(body)
                except _DECODE_ERRORS as exc:
                    src._problem(P.UNDECODABLE, c[0], t, f"payload of {len(body)} bytes does "
                                 f"not deserialize ({type(exc).__name__}); message skipped")
                    continue
                released = t
                src.counts[c[0]] = src.counts.get(c[0], 0) + 1
                yield Message(c[0], t, t, header_stamp(msg), msg)

        pos = len(_ROS1_MAGIC)
        reason = None
        while pos < len(data):
            recs = list(_ros1_records_one(data, pos))
            if not recs:
                reason = f"file ends at byte {len(data)} inside the record at byte {pos}"
                break
            (_off, header, body, nxt), = recs
            op = header.get(b"op", b"\x00")[:1]
            try:
                if op == bytes([_OP_CHUNK]):
                    comp = header.get(b"compression", b"none").decode()
                    if comp == "none":
                        raw = body
                    elif comp == "bz2":
                        import bz2

                        raw = bz2.decompress(body)
                    elif comp == "lz4":
                        import lz4.frame

                        raw = lz4.frame.decompress(body)
                    else:
                        raise ValueError(f"unknown chunk compression {comp!r}")
                    for _o, h, b in _ros1_records(raw, 0):
                        take(h, b)
                elif op in (bytes([_OP_CONN]), bytes([_OP_MSG])):
                    take(header, body)
            except Exception as exc:  # bz2/lz4/struct errors: the record is damaged
                reason = f"record at byte {pos} unreadable ({type(exc).__name__}: {exc})"
                break
            if last_good is not None:
                yield from release(last_good - REORDER_WINDOW_NS)
            pos = nxt
        if decode:
            yield from release(None)
        if reason is not None or pos < len(data):
            src._gap(last_good)
            src._problem(P.TRUNCATED, None, last_good,
                         f"{reason or 'records end early'}; read up to there without the bag "
                         f"index ({self.why})")
        else:
            src._problem(P.SUMMARY_CORRUPT, None, None,
                         f"the bag index is damaged or missing ({self.why}); every record was "
                         "read without it")
        if not decode and last_good is not None:
            src._end_time = last_good


def _ros1_records_one(data: bytes, pos: int) -> Iterator[tuple[int, dict, bytes, int]]:
    """The one complete record at ``pos`` of ``data`` with the offset after it, or nothing."""
    if pos + 4 > len(data):
        return
    (hlen,) = struct.unpack_from("<I", data, pos)
    if pos + 8 + hlen > len(data):
        return
    try:
        header = _ros1_fields(data[pos + 4: pos + 4 + hlen])
    except ValueError:
        return
    (dlen,) = struct.unpack_from("<I", data, pos + 4 + hlen)
    start = pos + 8 + hlen
    if start + dlen > len(data):
        return
    yield pos, header, data[start: start + dlen], start + dlen


# ------------------------------------------------------------------------------------------------
# CSV traces
# ------------------------------------------------------------------------------------------------

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_BOOL_WORDS = {"true": True, "false": False, "1": True, "0": False}


class CsvRow(NamedTuple):
    """One CSV row.

    Attributes:
        index: 0-based row number among data rows (the tick index).
        line: 1-based line number in the file.
        time: ns from the ``time`` column (seconds, decimal), or None without one.
        values: column name → bool (boolean column) or float (numeric column).
    """

    index: int
    line: int
    time: int | None
    values: dict[str, bool | float]


class CsvSource(LogSource):
    """A CSV trace of FRET variables.

    Format: a header row of variable names (identifiers), then one row per tick.  Blank lines
    and lines starting with ``#`` are ignored.  Cells hold ``true``/``false`` (any case),
    ``1``/``0`` or numbers (``nan``/``inf`` allowed).  A column whose every cell is
    true/false/1/0 is boolean (values ``bool``); any other column is numeric (values
    ``float``) and then must not hold true/false.  An optional ``time`` column gives each row's
    time in seconds (decimal, non-decreasing); without it row *k* is at ``k * period_ns``
    (default 1 s: one tick is one time unit).

    The file is checked completely when opened (two streaming passes: types, then rows).

    As a LogSource it yields one :class:`Message` per row on topic :data:`CSV_TOPIC` whose
    ``data`` has one attribute per column (so bindings may say ``/csv.speed``); signals.py
    uses :meth:`rows` directly so columns are variables without bindings.

    Raises:
        CsvError: bad header (empty, duplicate or non-identifier name), a row with the wrong
            number of cells, an unreadable cell, or time going backwards; the message names
            ``file:line`` and the column.
    """

    kind = "csv"

    def __init__(self, path: str | os.PathLike, *, period_ns: int = NS_PER_S) -> None:
        super().__init__(path)
        if period_ns <= 0:
            raise ValueError("period_ns must be positive")
        self.period_ns = period_ns
        self.columns: list[str] = []
        self.types: dict[str, str] = {}
        self.has_time = False
        self.row_count = 0
        self._check()

    def _lines(self) -> Iterator[tuple[int, list[str]]]:
        try:
            f = open(self.path, newline="", encoding="utf-8")
        except OSError as exc:
            raise LogError(self.path, f"cannot read: {exc.strerror or exc}") from None
        with f:
            reader = csv.reader(f)
            try:
                for cells in reader:
                    line = reader.line_num
                    if not cells or all(not c.strip() for c in cells):
                        continue
                    if cells[0].lstrip().startswith("#"):
                        continue
                    yield line, [c.strip() for c in cells]
            except csv.Error as exc:
                raise CsvError(self.path, reader.line_num, f"malformed CSV: {exc}") from None
            except UnicodeDecodeError as exc:
                raise CsvError(self.path, reader.line_num + 1, f"not UTF-8 text: {exc}") from None

    def _check(self) -> None:
        lines = self._lines()
        try:
            line, header = next(lines)
        except StopIteration:
            raise CsvError(self.path, 1, "empty file: expected a header row of variable names") from None
        self._header_line = line
        seen: set[str] = set()
        for name in header:
            if not name:
                raise CsvError(self.path, line, "empty column name in the header")
            if not _IDENT.match(name):
                raise CsvError(self.path, line, f"column name {name!r} is not an identifier",
                               column=name)
            if name in seen:
                raise CsvError(self.path, line, f"column {name!r} appears twice", column=name)
            seen.add(name)
        self._header = header
        self.has_time = "time" in header
        self.columns = [c for c in header if c != "time"]
        numeric_at: dict[str, int] = {}  # first line with a non-boolean cell
        word_at: dict[str, int] = {}  # first line with true/false
        count = 0
        last_time: int | None = None
        for line, cells in lines:
            if len(cells) != len(header):
                raise CsvError(self.path, line,
                               f"expected {len(header)} cells ({', '.join(header)}), got {len(cells)}")
            for name, cell in zip(header, cells):
                if name == "time":
                    t = _csv_time(self.path, line, cell)
                    if last_time is not None and t < last_time:
                        raise CsvError(self.path, line, f"time {cell} s goes backwards "
                                       f"(previous row at {last_time / NS_PER_S} s)", column="time")
                    last_time = t
                    continue
                if not cell:
                    raise CsvError(self.path, line, "empty cell", column=name)
                low = cell.lower()
                if low in ("true", "false"):
                    word_at.setdefault(name, line)
                elif low not in _BOOL_WORDS:
                    try:
                        float(cell)
                    except ValueError:
                        raise CsvError(self.path, line, f"cannot read {cell!r} as true/false or a "
                                       "number", column=name) from None
                    numeric_at.setdefault(name, line)
                if name in word_at and name in numeric_at:
                    raise CsvError(self.path, max(word_at[name], numeric_at[name]),
                                   f"column mixes true/false (line {word_at[name]}) with numbers "
                                   f"(line {numeric_at[name]})", column=name)
            count += 1
        self.row_count = count
        self.types = {c: ("float" if c in numeric_at else "bool") for c in self.columns}

    def topics(self) -> dict[str, str]:
        """``{CSV_TOPIC: CSV_TYPE}``."""
        return {CSV_TOPIC: CSV_TYPE}

    def rows(self) -> Iterator[CsvRow]:
        """The data rows, typed (see the class docstring), in file order."""
        lines = self._lines()
        next(lines)  # header, checked in __init__
        header = self._header
        types = self.types
        for index, (line, cells) in enumerate(lines):
            time = None
            values: dict[str, bool | float] = {}
            for name, cell in zip(header, cells):
                if name == "time":
                    time = _csv_time(self.path, line, cell)
                elif types[name] == "bool":
                    values[name] = _BOOL_WORDS[cell.lower()]
                else:
                    values[name] = float(cell)
            yield CsvRow(index, line, time, values)

    def messages(self, topics: set[str] | frozenset[str] | None = None) -> Iterator[Message]:
        """One Message per row on :data:`CSV_TOPIC`; log time = ``time`` column or index × period."""
        self._begin_pass()
        if topics is not None and CSV_TOPIC not in topics:
            return
        first = last = None
        for row in self.rows():
            t = row.time if row.time is not None else row.index * self.period_ns
            first = t if first is None else first
            last = t
            self.counts[CSV_TOPIC] = self.counts.get(CSV_TOPIC, 0) + 1
            yield Message(CSV_TOPIC, t, t, None, SimpleNamespace(**row.values))
        self._start_time, self._end_time = first, last


def _csv_time(path: str, line: int, cell: str) -> int:
    try:
        value = Decimal(cell)
        if not value.is_finite():
            raise InvalidOperation
        return int((value * NS_PER_S).to_integral_value())
    except (InvalidOperation, ValueError):
        raise CsvError(path, line, f"time {cell!r} is not a number of seconds", column="time") from None


# ------------------------------------------------------------------------------------------------


def open_log(path: str | os.PathLike, *, fallback_typestore: Typestore | Stores | None = None,
             check_data_crc: bool = True, csv_period_ns: int = NS_PER_S) -> LogSource:
    """Open a recorded run for reading.

    Args:
        path: ``*.mcap`` file, ROS 1 ``*.bag`` file, rosbag2 folder (with ``metadata.yaml``),
            or ``*.csv`` trace.
        fallback_typestore: types for rosbag connections that carry no definition (e.g. old
            rosbag2 sqlite3 bags): a rosbags Typestore or a ``rosbags.typesys.Stores`` member.
            Never used when the log embeds its definitions.
        check_data_crc: MCAP only: check the DataEnd data-section CRC (one extra read of the
            data section after a full indexed pass).
        csv_period_ns: CSV only: time step between rows when there is no ``time`` column.

    Returns:
        A :class:`LogSource` (McapSource, BagSource or CsvSource).

    Raises:
        LogError: missing path, unknown kind, or a file that cannot be opened as that kind.
        CsvError: a bad CSV trace (names file:line).
    """
    p = Path(path)
    if not p.exists():
        raise LogError(path, "no such file or folder")
    if isinstance(fallback_typestore, Stores):
        fallback_typestore = get_typestore(fallback_typestore)
    suffix = p.suffix.lower()
    if p.is_dir():
        if not (p / "metadata.yaml").exists():
            raise LogError(path, "a folder but not a rosbag2 bag (no metadata.yaml)")
        return BagSource(p, fallback_typestore=fallback_typestore)
    if suffix == ".mcap":
        return McapSource(p, check_data_crc=check_data_crc)
    if suffix == ".bag":
        return BagSource(p, fallback_typestore=fallback_typestore)
    if suffix == ".csv":
        return CsvSource(p, period_ns=csv_period_ns)
    raise LogError(path, "unknown log kind (expected .mcap, .bag, .csv or a rosbag2 folder)")
