"""MCAP files (any profile) as a :class:`~fretc.logs.base.LogSource`.

Messages on channels with ``cdr`` (ROS 2) or ``ros1`` message encoding are deserialized with
rosbags types built from the schema *embedded in the file* (``ros2msg``, ``ros2idl``,
``ros1msg`` schema encodings; MCAP spec, "Well-known encodings";
:mod:`fretc.logs.decoding`). Chunk CRCs and the data-section CRC are checked. A file
with a valid footer and summary is read through its chunk indexes; a file without one (a
crashed recording) is read record by record from the start, as far as it goes
(:mod:`fretc.logs.mcap.integrity` reads the damage).

Design notes: ARCHITECTURE.md, `logs/mcap/source.py`."""

from __future__ import annotations

import heapq
import os
import zlib
from collections.abc import Callable, Iterator
from typing import Any, BinaryIO

from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, ChunkIndex, Message as McapMessage, Schema
from mcap.stream_reader import CRCValidationError

from fretc.common import problems as P
from fretc.common.problems import DataProblem, LogError
from fretc.logs.base import Gap, LogSource, Message, header_stamp
from fretc.logs.decoding import (DECODE_ERRORS, SCHEMA_FOR_ENCODING, UnsupportedSchema,
                                 schema_decoder)
from fretc.logs.mcap.encodings import SELF_DESCRIBING, type_name
from fretc.logs.mcap.integrity import (GAP_NOTE, McapIndex, check_data_section, cut_record,
                                       ends_with_footer)
from fretc.logs.mcap.integrity import index_disagreement, missing_records, read_summary
from fretc.logs.mcap.columns import TopicBlock, column_pass
from fretc.logs.mcap.records import (MCAP_MAGIC, RECORD_ERRORS, RECORD_HEAD, chunk_messages,
                                     chunk_records)
from fretc.logs.mcap.records import crc_skip, data_follows, parse_record
from fretc.logs.recorded_gaps import (GAP_LIBRARIES, first_start, gap_problems, losses,
                                      read_recorded_gaps)
from fretc.logs.reorder import REORDER_WINDOW_NS, ReorderQueue

__all__ = ["McapSource"]

#: Records the linear pass parses; the others are skipped (their bytes only go into the CRC).
_DATA_RECORDS = (Opcode.CHUNK, Opcode.MESSAGE, Opcode.SCHEMA, Opcode.CHANNEL)


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

    Args:
        path: the ``.mcap`` file.
        check_data_crc: check the DataEnd data-section CRC (one extra read of the data
            section after the first full indexed pass).

    Raises:
        LogError: the file cannot be read or does not start with the MCAP magic.
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
        found = read_summary(self.path, self._size)
        self.profile = found.profile
        if found.problem is not None:
            self._open_damage = True
            self._open_problems.add(found.problem)
        self._index: McapIndex | None = found.index
        if self._index is not None:
            why = index_disagreement(self.path, self._index)
            if why is not None:  # a hint that lies: the data section is read as written
                self._index = None
                self._open_problems.add(DataProblem(
                    P.INDEX_MISMATCH, None, None,
                    f"the summary's index disagrees with the data section ({why}); the "
                    "file is read record by record"))
        #: the gaps of a watched run its recording carries (:mod:`fretc.logs.recorded_gaps`)
        self.recorded_gaps: list[Gap] = []
        self._gaps_library = found.library
        if found.library in GAP_LIBRARIES and self._index is not None:
            try:
                self.recorded_gaps = read_recorded_gaps(self.path)
            except ValueError as exc:  # (where the watch lost messages is not known)
                self._open_damage = True
                self._open_problems.add(DataProblem(P.RECORDED_GAPS, None, None, str(exc)))
        self.partial = self._open_damage
        self._scanned: tuple[dict[int, Schema], dict[int, Channel]] | None = None
        self._data_crc_checked = False
        #: the chunks opened by any pass, and those written without a CRC (uncompressed_crc
        #: 0), each as (first and last message time, uncompressed size)
        self._chunks: set[tuple] = set()
        self._chunks_without_crc: set[tuple] = set()
        #: the DataEnd record's data_section_crc seen by a linear pass (None: not seen)
        self._data_section_crc: int | None = None
        if self._index is not None and missing_records(self._index) is not None:
            self._complete_index()
        if self._index is not None:
            st = self._index.statistics
            if st is not None and st.message_count:
                self._start_time, self._end_time = st.message_start_time, st.message_end_time
            elif self._index.chunk_indexes:
                self._start_time = min(c.message_start_time for c in self._index.chunk_indexes)
                self._end_time = max(c.message_end_time for c in self._index.chunk_indexes)


    def _begin_pass(self) -> None:
        super()._begin_pass()
        if self.recorded_gaps:
            self.gaps.extend(self.recorded_gaps)
            lost = losses(self.recorded_gaps)  # (a silence, a publisher away, loses nothing)
            if lost:  # a watched run with a gap is partial, as the watch said
                self.partial, self.damage_time = True, first_start(lost)
            for p in gap_problems(self.recorded_gaps, self._gaps_library):
                self._pass_problems.add(p)

    def _complete_index(self) -> None:
        """Add to the index the Schema and Channel records the summary does not repeat
        (optional there, MCAP spec "Summary Section"), from a scan of the data section
        (chunks decompressed, messages not decoded). Damage the scan meets is not kept: each
        pass reports it again."""
        assert self._index is not None
        for _ in _LinearPass(self, wanted=frozenset(), decode=False).run():
            pass
        assert self._scanned is not None
        schemas, channels = self._scanned
        for sid, sc in schemas.items():
            self._index.schemas.setdefault(sid, sc)
        for cid, ch in channels.items():
            self._index.channels.setdefault(cid, ch)
        self._scanned = None
        self._begin_pass()

    @property
    def indexed(self) -> bool:
        """True when the file is read through its summary's chunk indexes."""
        return self._index is not None

    def _channels(self) -> tuple[dict[int, Schema], dict[int, Channel]]:
        if self._index is not None:
            return self._index.schemas, self._index.channels
        if self._scanned is None:
            for _ in _LinearPass(self, wanted=frozenset(), decode=False).run():
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
            out.setdefault(ch.topic, _type_name(ch.message_encoding, sc))
        return dict(sorted(out.items()))

    # -- decoding -------------------------------------------------------------------------------
    def _decoder(self, channel: Channel, schemas: dict[int, Schema], log_time: int
                 ) -> Callable[[bytes], Any] | None:
        if channel.id in self._decoders:
            return self._decoders[channel.id]
        dec = None
        schema = schemas.get(channel.schema_id)
        try:
            if (channel.message_encoding in SCHEMA_FOR_ENCODING
                    and (channel.schema_id == 0 or schema is None)):
                raise UnsupportedSchema(f"channel {channel.id} has no schema (schema id "
                                        f"{channel.schema_id})")
            dec = schema_decoder(channel.message_encoding,
                                 None if schema is None else schema.encoding,
                                 None if schema is None else schema.name,
                                 None if schema is None else bytes(schema.data),
                                 self._fields_for(channel.topic))
        except UnsupportedSchema as exc:
            kind = (P.UNKNOWN_SCHEMA if channel.message_encoding in SCHEMA_FOR_ENCODING
                    or channel.message_encoding in SELF_DESCRIBING else P.UNKNOWN_ENCODING)
            self._no_decoder[channel.id] = (kind, str(exc))
        self._decoders[channel.id] = dec
        return dec

    def _deliver(self, channel: Channel, rec: McapMessage, schemas: dict[int, Schema]
                 ) -> Message | None:
        """``rec`` decoded and counted, or None: no decoder (``unknown_schema`` /
        ``unknown_encoding``) or a payload that does not deserialize (``undecodable``), a
        message lost (:meth:`LogSource._lose`)."""
        self.records[channel.topic] = self.records.get(channel.topic, 0) + 1
        dec = self._decoder(channel, schemas, rec.log_time)
        if dec is None:
            kind, why = self._no_decoder[channel.id]
            self._lose(kind, channel.topic, channel.id, rec.log_time, why)
            return None
        try:
            data = dec(rec.data)
        except DECODE_ERRORS as exc:
            self._lose(P.UNDECODABLE, channel.topic, channel.id, rec.log_time,
                       f"a payload of {len(rec.data)} bytes does not deserialize: "
                       f"{type(exc).__name__}: {exc}")
            return None
        topic = channel.topic
        self.counts[topic] = self.counts.get(topic, 0) + 1
        return Message(topic, rec.log_time, rec.publish_time, header_stamp(data), data)

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
            yield from _LinearPass(self, wanted=wanted, decode=True).run()

    def message_blocks(self, topics: set[str] | frozenset[str]
                       ) -> Iterator[list[TopicBlock]] | None:
        """The messages of ``topics`` as blocks of columns per topic
        (:func:`fretc.logs.mcap.columns.column_pass`: the same messages, order within
        each topic, damage and problems as :meth:`messages`), or None when that pass does
        not apply to this file and these topics (then use :meth:`messages`)."""
        return column_pass(self, topics)

    def _indexed(self, topics: set[str] | frozenset[str] | None) -> Iterator[Message]:
        """The indexed pass: chunks are opened when their message_start_time comes up in a
        heap merged with the messages of the chunks already open (as
        :meth:`mcap.reader.SeekingReader.iter_messages` merges them, with plain tuples
        instead of an object per message, and a damaged chunk skipped as a gap)."""
        index = self._index
        assert index is not None
        wanted = {cid for cid, ch in index.channels.items() if topics is None or ch.topic in topics}
        # every chunk is read whole: the channels a ChunkIndex lists (its MessageIndex
        # offsets) are a hint a forged summary can falsify, never a reason to skip a chunk
        # (log time, chunk offset, -1 and a ChunkIndex, or n and (channel id, message))
        heap: list[tuple[int, int, int, Any]] = [
            (ci.message_start_time, ci.chunk_start_offset, -1, ci) for ci in index.chunk_indexes]
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
                n = 0
                for rec in self._read_chunk(f, item, wanted):
                    if rec.channel_id in wanted:
                        heapq.heappush(heap, (rec.log_time, item.chunk_start_offset, n,
                                              (rec.channel_id, rec)))
                        n += 1
                    elif rec.channel_id not in index.channels:
                        self._gap(rec.log_time, rec.log_time, cause=P.UNKNOWN_CHANNEL)
                        self._problem(P.UNKNOWN_CHANNEL, None, rec.log_time,
                                      f"message on channel id {rec.channel_id} that the summary "
                                      "does not define; skipped")
        if self.check_data_crc and not self._data_crc_checked:
            self._check_data_crc()

    def _read_chunk(self, f: BinaryIO, ci: ChunkIndex, wanted: set[int]) -> list[McapMessage]:
        """The messages of the chunk ``ci`` points to on ``wanted`` (or unknown) channels; a
        damaged chunk is a gap (its ``chunk_crc`` / ``chunk_corrupt`` problem) and gives []."""
        index = self._index
        assert index is not None
        # only the messages of wanted (or unknown) channels are parsed
        return self._open_chunk(f, ci, lambda c: chunk_messages(c, wanted, index.channels), [])

    def _open_chunk(self, f: BinaryIO, ci: ChunkIndex, parse: Callable[[Chunk], Any],
                    damaged: Any) -> Any:
        """``parse`` of the Chunk record ``ci`` points to; a damaged chunk is a gap (its
        ``chunk_crc`` / ``chunk_corrupt`` problem) and gives ``damaged``."""
        try:
            f.seek(ci.chunk_start_offset)
            raw = f.read(ci.chunk_length)
            if len(raw) != ci.chunk_length:
                raise ValueError(f"file ends inside the chunk (need {ci.chunk_length} bytes)")
            opcode, length = RECORD_HEAD.unpack_from(raw)
            if opcode != Opcode.CHUNK or 9 + length != ci.chunk_length:
                raise ValueError(f"no Chunk record at byte {ci.chunk_start_offset}")
            chunk = parse_record(Opcode.CHUNK, raw[9:])
            self._note_chunk(chunk)
            return parse(chunk)
        except CRCValidationError as exc:
            self._gap(ci.message_start_time, ci.message_end_time, topics=self._chunk_topics(ci),
                      cause=P.CHUNK_CRC)
            self._problem(P.CHUNK_CRC, None, ci.message_start_time,
                          f"chunk at byte {ci.chunk_start_offset}: {exc}; its messages "
                          f"are skipped: a gap in the log{GAP_NOTE}", ci.message_end_time)
        except Exception as exc:  # mcap, struct, zstd and lz4 raise their own errors
            self._gap(ci.message_start_time, ci.message_end_time, topics=self._chunk_topics(ci),
                      cause=P.CHUNK_CORRUPT)
            self._problem(P.CHUNK_CORRUPT, None, ci.message_start_time,
                          f"chunk at byte {ci.chunk_start_offset} unreadable "
                          f"({type(exc).__name__}: {exc}); its messages are skipped: a "
                          f"gap in the log{GAP_NOTE}", ci.message_end_time)
        return damaged

    def _note_chunk(self, chunk: Any) -> None:
        """Note a chunk opened, and whether it carries a CRC."""
        key = (getattr(chunk, "message_start_time", None),
               getattr(chunk, "message_end_time", None), getattr(chunk, "uncompressed_size", 0))
        self._chunks.add(key)
        if getattr(chunk, "uncompressed_crc", 0) == 0:
            self._chunks_without_crc.add(key)

    def integrity_note(self) -> str | None:
        """None when every chunk read carried its CRC (or, without chunks, the data
        section has one); else what was not covered (MCAP spec: a writer may leave the
        CRCs 0, "not computed")."""
        if self._chunks:
            if not self._chunks_without_crc:
                return None
            return (f"{len(self._chunks_without_crc)} of {len(self._chunks)} chunks carry no "
                    "CRC (written without them): a changed byte there reads as data")
        crc = (self._index.data_section_crc if self._index is not None
               else self._data_section_crc)
        if crc:
            return None
        return ("the file has no chunk or data-section CRC: a changed byte reads as data")

    def _chunk_topics(self, ci: ChunkIndex) -> frozenset | None:
        """The topics of the channels whose messages the chunk ``ci`` holds, from the
        summary's ChunkIndex (its message index offsets, one per channel; the summary has
        its own CRC); None (any topic) when it names none or a channel the summary does not
        define."""
        index = self._index
        offsets = getattr(ci, "message_index_offsets", None) or {}
        if index is None or not offsets:
            return None
        topics = [index.channels[c].topic for c in offsets if c in index.channels]
        return frozenset(topics) if len(topics) == len(offsets) else None

    def _check_data_crc(self) -> None:
        """Check the DataEnd data_section_crc (MCAP spec): CRC-32 of bytes [0, DataEnd)."""
        self._data_crc_checked = True
        if self._index is None:
            return
        problem = check_data_section(self.path, self._index)
        if problem is not None:
            self._open_damage = True
            self.partial = True
            self._open_problems.add(problem)

    def _chunk_gap(self, chunk: Chunk, last_good: int | None) -> None:
        """A skipped chunk read without the index: its header's times are not covered by a
        CRC, so the gap starts no later than the last good message read before it."""
        start = chunk.message_start_time
        self._gap(start if last_good is None else min(start, last_good), chunk.message_end_time,
                  open_end=True, cause=P.CHUNK_CORRUPT)


class _LinearPass:
    """One record-by-record pass over an MCAP file from byte 0, for a file without a usable
    index (framing: 1-byte opcode, 8-byte length; MCAP spec, "Records").

    A record whose body is damaged is skipped; a record running past the end of the file
    ends the pass (``truncated``). Messages are held in a :class:`ReorderQueue` to restore
    log-time order. ``wanted`` None means all topics; ``decode`` False only collects the
    channels and the times (for :meth:`McapSource.topics`).
    """

    def __init__(self, src: McapSource, wanted: frozenset[str] | None, decode: bool) -> None:
        self.src = src
        self.wanted = wanted
        self.decode = decode
        self.schemas: dict[int, Schema] = {}
        self.channels: dict[int, Channel] = {}
        self.queue = ReorderQueue()
        self.watermark: int | None = None  # latest log time read, for the queue
        self.last_good: int | None = None  # latest log time read intact (file order)
        self.first_time: int | None = None
        self.reported_channels: set[int] = set()
        self.crc = zlib.crc32(MCAP_MAGIC)  # of the data section read so far

    def run(self) -> Iterator[Message]:
        src = self.src
        with open(src.path, "rb") as f:
            f.seek(len(MCAP_MAGIC))
            while True:
                pos = f.tell()
                head = f.read(9)
                if len(head) < 9 or pos + 9 + RECORD_HEAD.unpack(head)[1] > src._size:
                    self._truncated(f, pos, head)
                    break
                opcode, length = RECORD_HEAD.unpack(head)
                if opcode in (Opcode.DATA_END, Opcode.FOOTER) and \
                        data_follows(f, pos + 9 + length, src._size):
                    self._false_end(opcode, pos)  # a flipped opcode, not the end
                    self.crc = crc_skip(f, length, zlib.crc32(head, self.crc))
                    continue
                if opcode == Opcode.DATA_END:
                    self._data_end(f.read(length))
                    break  # the data section is over; the summary is not needed here
                if opcode == Opcode.FOOTER:
                    break
                if opcode not in _DATA_RECORDS:
                    self.crc = crc_skip(f, length, zlib.crc32(head, self.crc))
                    continue
                body = f.read(length)
                self.crc = zlib.crc32(body, zlib.crc32(head, self.crc))
                yield from self._record(opcode, body, pos)
        if self.decode and not src.damage_cut and not ends_with_footer(src.path, src._size):
            src.partial = True
            src._problem(P.SUMMARY_CORRUPT, None, None,
                         "the file ends after its data section without a Footer and closing "
                         "magic (summary lost); every message was read")
        yield from self._release(None)
        src._scanned = (self.schemas, self.channels)
        if self.first_time is not None:
            src._start_time, src._end_time = self.first_time, self.last_good

    def _record(self, opcode: int, body: bytes, pos: int) -> Iterator[Message]:
        """Take one Schema, Channel, Message or Chunk record read at byte ``pos``."""
        try:
            rec = parse_record(opcode, body)
        except RECORD_ERRORS as exc:
            kind = P.CHUNK_CORRUPT if opcode == Opcode.CHUNK else P.CORRUPT_RECORD
            # what it held is lost; its times are unknown: from the last message read to
            # the next one
            self.src._gap(self.last_good, open_end=True, cause=kind)
            self.src._problem(kind, None, self.last_good,
                              f"{Opcode(opcode).name} record at byte {pos} unreadable "
                              f"({type(exc).__name__}: {exc}); skipped")
            return
        if isinstance(rec, Schema):
            self.schemas[rec.id] = rec
        elif isinstance(rec, Channel):
            self.channels[rec.id] = rec
        elif isinstance(rec, McapMessage):
            self.watermark = (rec.log_time if self.watermark is None
                              else max(self.watermark, rec.log_time))
            yield from self._release(self.watermark)
            self._take(rec, pos)
        elif isinstance(rec, Chunk):
            yield from self._chunk(rec, pos)

    def _chunk(self, chunk: Chunk, pos: int) -> Iterator[Message]:
        src = self.src
        src._note_chunk(chunk)
        try:
            records = chunk_records(chunk)
        except CRCValidationError as exc:
            src._chunk_gap(chunk, self.last_good)
            src._problem(P.CHUNK_CRC, None, chunk.message_start_time,
                         f"chunk at byte {pos}: {exc}; its messages are skipped: "
                         f"a gap in the log{GAP_NOTE}", chunk.message_end_time)
            return
        except Exception as exc:  # decompression libraries raise their own errors
            src._chunk_gap(chunk, self.last_good)
            src._problem(P.CHUNK_CORRUPT, None, chunk.message_start_time,
                         f"chunk at byte {pos} unreadable ({type(exc).__name__}: "
                         f"{exc}); its messages are skipped: a gap in the log"
                         f"{GAP_NOTE}", chunk.message_end_time)
            return
        self._absorb(records, pos)
        # the watermark comes from the messages (CRC-checked), not from the chunk
        # header's message_start_time, which no CRC covers
        if self.last_good is not None:
            self.watermark = (self.last_good if self.watermark is None
                              else max(self.watermark, self.last_good))
            yield from self._release(self.watermark)

    def _absorb(self, records: list[Any], pos: int) -> None:
        """Take the schemas, channels and messages of one chunk."""
        for r in records:
            if isinstance(r, Schema):
                self.schemas[r.id] = r
            elif isinstance(r, Channel):
                self.channels[r.id] = r
            elif isinstance(r, McapMessage):
                self._take(r, pos)

    def _take(self, rec: McapMessage, pos: int) -> None:
        """Note a message's log time; queue it when its topic is wanted."""
        t = rec.log_time
        if self.src._open_gaps:
            self.src._close_gaps(t)
        self.last_good = t if self.last_good is None else max(self.last_good, t)
        self.first_time = t if self.first_time is None else min(self.first_time, t)
        ch = self.channels.get(rec.channel_id)
        if ch is None:
            if self.decode:
                self.src._gap(t, t, cause=P.UNKNOWN_CHANNEL)
            if rec.channel_id not in self.reported_channels:
                self.reported_channels.add(rec.channel_id)
                self.src._problem(P.UNKNOWN_CHANNEL, None, t,
                                  f"message at byte {pos} on channel id {rec.channel_id}, which "
                                  "is not defined (its Channel record was lost?); its messages "
                                  "are skipped")
            return
        if not self.decode or (self.wanted is not None and ch.topic not in self.wanted):
            return
        self.queue.push(t, pos, rec)

    def _release(self, watermark: int | None) -> Iterator[Message]:
        """Deliver the queued messages the watermark has passed (all when None)."""
        src = self.src
        for log_time, rec in self.queue.due(watermark):
            late = self.queue.late_by(log_time)
            if late:
                # without an index only damage (a log time or chunk header changed) puts a
                # message this far out of order: a gap at its log time
                topic = self.channels[rec.channel_id].topic
                src._gap(log_time, log_time, topics=frozenset((topic,)), cause=P.OUT_OF_ORDER)
                src._problem(P.OUT_OF_ORDER, topic, log_time,
                             f"message is {late} ns older than one already delivered (beyond "
                             f"the {REORDER_WINDOW_NS} ns reorder window); skipped")
                continue
            msg = src._deliver(self.channels[rec.channel_id], rec, self.schemas)
            if msg is not None:
                self.queue.delivered(log_time)
                yield msg

    def _false_end(self, opcode: int, pos: int) -> None:
        """A DataEnd or Footer record at ``pos`` with Chunk or Message records after it:
        damage (MCAP spec: no data record follows the data section), skipped as a record
        whose content is lost; what it held is a gap from the last good message on."""
        self.src._gap(self.last_good, open_end=True, cause=P.CORRUPT_RECORD)
        self.src._problem(P.CORRUPT_RECORD, None, self.last_good,
                          f"{Opcode(opcode).name} record at byte {pos} is followed by Chunk "
                          "or Message records (a damaged record, not the end of the data); "
                          "skipped")

    def _truncated(self, f: BinaryIO, pos: int, head: bytes) -> None:
        """The record at ``pos`` runs past the end of the file: the pass ends here."""
        what, records = cut_record(f, pos, self.src._size, head)
        self._absorb(records, pos)
        self.src._gap(self.last_good, cause=P.TRUNCATED)
        self.src._problem(P.TRUNCATED, None, self.last_good,
                          f"{what}; read up to there (crashed or cut recording)")

    def _data_end(self, body: bytes) -> None:
        """Check the DataEnd record's data_section_crc against the CRC read so far."""
        try:
            de = parse_record(Opcode.DATA_END, body)
        except RECORD_ERRORS:
            return
        self.src._data_section_crc = de.data_section_crc
        if self.src.check_data_crc and de.data_section_crc not in (0, self.crc):
            self.src.partial = True
            self.src._problem(P.DATA_CRC, None, None,
                              f"data section CRC mismatch (DataEnd says "
                              f"{de.data_section_crc:#010x}, computed {self.crc:#010x})")


def _type_name(message_encoding: str, schema: Schema | None) -> str:
    """The message type a channel's schema names: ROS's normalized ``pkg/msg/Type`` for the
    ROS encodings, :func:`fretc.logs.mcap.encodings.type_name` for the self-describing ones, ``""``
    without a schema."""
    if schema is None or not schema.name:
        return ""
    if message_encoding in SELF_DESCRIBING:
        return type_name(schema.name)
    from rosbags.typesys.msg import normalize_msgtype  # lazy: ROS logs only (start-up)

    return normalize_msgtype(schema.name)
