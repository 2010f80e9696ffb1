"""Reading a damaged MCAP file: the summary and its CRC, the data-section CRC, and what a
file cut short still holds.

* :func:`read_summary` reads the Footer, the summary section and the DataEnd record and
  checks the summary CRC (MCAP spec, "Footer", "Summary Section"); a damaged summary is a
  ``summary_corrupt`` problem and the file is read without its index.
* :func:`check_data_section` checks the DataEnd data_section_crc after an indexed pass.
* :func:`cut_record` describes a record cut short by the end of the file and recovers the
  complete records at the start of a cut Chunk.

The ``mcap`` library's :meth:`mcap.reader.SeekingReader.get_summary` reads the same
records but checks no summary CRC and, on damage, raises without saying where; so the
summary is framed here (the bodies are parsed by the library's record classes).
"""

from __future__ import annotations

import struct
import zlib
from typing import Any, BinaryIO, NamedTuple

from mcap.opcode import Opcode
from mcap.records import Channel, ChunkIndex, Message as McapMessage, Schema, Statistics

from fretc.common import problems as P
from fretc.common.problems import DataProblem
from fretc.logs.mcap.records import (DATA_END_LEN, FOOTER_LEN, MCAP_MAGIC, RECORD_ERRORS,
                                     RECORD_HEAD, crc_skip, decompress, parse_record)

__all__ = ["McapIndex", "SummaryRead", "read_summary", "check_data_section", "cut_record",
           "ends_with_footer", "GAP_NOTE"]

#: Appended to the detail of a chunk skipped as damaged.
GAP_NOTE = "; the log is audited up to its start (nothing is held across a gap)"


class McapIndex(NamedTuple):
    """The summary section of an MCAP file (MCAP spec, "Summary Section").

    Attributes:
        schemas: schema id -> Schema record.
        channels: channel id -> Channel record.
        chunk_indexes: ChunkIndex records sorted by (message_start_time, chunk_start_offset).
        statistics: the Statistics record, or None.
        data_end_offset: byte offset of the DataEnd record.
        data_section_crc: the DataEnd data_section_crc (0: none).
    """

    schemas: dict[int, Schema]
    channels: dict[int, Channel]
    chunk_indexes: list[ChunkIndex]
    statistics: Statistics | None
    data_end_offset: int
    data_section_crc: int


class SummaryRead(NamedTuple):
    """What :func:`read_summary` found: the Header ``profile`` (``""`` when unreadable), the
    ``index`` (None: read the file linearly), the ``summary_corrupt`` ``problem`` that made
    the index unusable (None when the summary is intact or absent) and the Header
    ``library`` (``""`` when unreadable)."""

    profile: str
    index: McapIndex | None  # type: ignore[assignment]  # the field shadows tuple.index
    problem: DataProblem | None
    library: str = ""


class _Unusable(Exception):
    """The summary is damaged; the message is the detail of the ``summary_corrupt`` problem."""


def read_summary(path: str, size: int) -> SummaryRead:
    """The Header profile and the summary of the MCAP file ``path`` of ``size`` bytes.

    The index is None when the file has no trailing magic (a crashed recording: the linear
    pass reports it), no summary, no ChunkIndex records (an unchunked file), or a damaged
    Footer or summary (then ``problem`` says what).
    """
    with open(path, "rb") as f:
        profile, library = _read_header(f, size)
        try:
            index = _read_index(f, size)
        except _Unusable as exc:
            return SummaryRead(profile, None, DataProblem(P.SUMMARY_CORRUPT, None, None, str(exc)),
                               library)
    return SummaryRead(profile, index, None, library)


def _read_header(f: BinaryIO, size: int) -> tuple[str, str]:
    """The Header record's profile and library (MCAP spec, "Header"), ``""`` when
    unreadable."""
    head = f.read(len(MCAP_MAGIC) + 9)
    if len(head) == len(MCAP_MAGIC) + 9 and head[8] == Opcode.HEADER:
        length = RECORD_HEAD.unpack_from(head, 8)[1]
        if length < size:
            try:
                header = parse_record(Opcode.HEADER, f.read(length))
                return header.profile, header.library
            except RECORD_ERRORS:
                pass
    return "", ""


def _read_index(f: BinaryIO, size: int) -> McapIndex | None:
    if size < 2 * len(MCAP_MAGIC) + FOOTER_LEN + DATA_END_LEN:
        return None
    f.seek(size - len(MCAP_MAGIC))
    if f.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
        return None  # no trailing magic: crashed recording; the linear pass reports it
    footer, summary_bytes = _read_footer(f, size - len(MCAP_MAGIC) - FOOTER_LEN)
    if footer.summary_start == 0:
        return None  # valid file without a summary: linear pass
    data_end_offset = footer.summary_start - DATA_END_LEN
    data_section_crc = 0
    if data_end_offset >= len(MCAP_MAGIC):
        f.seek(data_end_offset)
        raw_de = f.read(DATA_END_LEN)
        if len(raw_de) == DATA_END_LEN and raw_de[0] == Opcode.DATA_END:
            data_section_crc = struct.unpack_from("<I", raw_de, 9)[0]
    schemas, channels, chunk_indexes, statistics = _parse_summary(summary_bytes,
                                                                  footer.summary_start)
    if not chunk_indexes:
        return None  # unchunked file: the linear pass reads its loose messages
    chunk_indexes.sort(key=lambda c: (c.message_start_time, c.chunk_start_offset))
    return McapIndex(schemas, channels, chunk_indexes, statistics, data_end_offset,
                     data_section_crc)


def _read_footer(f: BinaryIO, footer_pos: int) -> tuple[Any, bytes]:
    """The Footer record at ``footer_pos`` and the summary bytes it points to, CRC-checked.

    Raises:
        _Unusable: no Footer there, a summary_start outside the file, a summary CRC mismatch.
    """
    f.seek(footer_pos)
    raw = f.read(FOOTER_LEN)
    opcode, length = RECORD_HEAD.unpack_from(raw)
    if opcode != Opcode.FOOTER or length != FOOTER_LEN - 9:
        raise _Unusable(f"no Footer record at byte {footer_pos}; reading without the index")
    footer = parse_record(Opcode.FOOTER, raw[9:])
    summary_bytes = b""
    if footer.summary_start != 0:
        if not (0 < footer.summary_start <= footer_pos):
            raise _Unusable(f"Footer summary_start {footer.summary_start} is outside the file; "
                            "reading without the index")
        f.seek(footer.summary_start)
        summary_bytes = f.read(footer_pos - footer.summary_start)
    if footer.summary_crc != 0:
        crc = zlib.crc32(raw[: FOOTER_LEN - 4], zlib.crc32(summary_bytes))
        if crc != footer.summary_crc:
            raise _Unusable(f"summary CRC mismatch (Footer says {footer.summary_crc:#010x}, "
                            f"computed {crc:#010x}); reading without the index")
    return footer, summary_bytes


def _parse_summary(summary: bytes, start: int
                   ) -> tuple[dict[int, Schema], dict[int, Channel], list[ChunkIndex],
                              Statistics | None]:
    """The Schema, Channel, ChunkIndex and Statistics records of the summary section (which
    starts at byte ``start`` of the file).

    Raises:
        _Unusable: a record that does not parse or runs past the section.
    """
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    chunk_indexes: list[ChunkIndex] = []
    statistics = None
    pos = 0
    try:
        while pos < len(summary):
            opcode, length = RECORD_HEAD.unpack_from(summary, pos)
            body = summary[pos + 9: pos + 9 + length]
            if len(body) != length:
                raise ValueError("record runs past the summary section")
            rec = parse_record(opcode, body)
            if isinstance(rec, Schema):
                schemas[rec.id] = rec
            elif isinstance(rec, Channel):
                channels[rec.id] = rec
            elif isinstance(rec, ChunkIndex):
                chunk_indexes.append(rec)
            elif isinstance(rec, Statistics):
                statistics = rec
            pos += 9 + length
    except RECORD_ERRORS as exc:
        raise _Unusable(f"summary record at byte {start + pos} unreadable ({exc}); "
                        "reading without the index") from None
    return schemas, channels, chunk_indexes, statistics


def check_data_section(path: str, index: McapIndex) -> DataProblem | None:
    """A ``data_crc`` problem when the CRC-32 of bytes [0, DataEnd) differs from the DataEnd
    record's data_section_crc (MCAP spec, "DataEnd"); None when it matches or is 0."""
    if index.data_section_crc == 0:
        return None
    with open(path, "rb") as f:
        crc = crc_skip(f, index.data_end_offset, 0)
    if crc == index.data_section_crc:
        return None
    return DataProblem(P.DATA_CRC, None, None,
                       f"data section CRC mismatch (DataEnd says {index.data_section_crc:#010x}, "
                       f"computed {crc:#010x}): bytes outside the chunks are damaged")


def cut_record(f: BinaryIO, pos: int, size: int, head: bytes) -> tuple[str, list[Any]]:
    """The record at byte ``pos`` (its first bytes ``head``) runs past the end of a file of
    ``size`` bytes: the text of the ``truncated`` problem, and the complete records
    recovered from the start of a cut Chunk (unverified: the chunk CRC covers all of it)."""
    if not head:
        return f"file ends at byte {pos} without DataEnd/Footer records", []
    what = f"file ends at byte {size} inside the record starting at byte {pos}"
    if len(head) < 9 or head[0] != Opcode.CHUNK:
        return what, []
    start = _peek_chunk_start(f, pos)
    if start is not None:
        what += f" (a Chunk whose messages start at log time {start})"
    f.seek(pos + 9)
    records = _truncated_chunk_records(f.read())
    n_msgs = sum(isinstance(r, McapMessage) for r in records)
    if n_msgs:
        what += (f"; {n_msgs} complete messages recovered from the cut chunk (unverified: its "
                 "CRC covers the whole chunk)")
    return what, records


def ends_with_footer(path: str, size: int) -> bool:
    """True when the file ends with a Footer record and the closing magic (MCAP spec)."""
    if size < len(MCAP_MAGIC) + FOOTER_LEN:
        return False
    with open(path, "rb") as f:
        f.seek(size - len(MCAP_MAGIC) - FOOTER_LEN)
        tail = f.read(len(MCAP_MAGIC) + FOOTER_LEN)
    return tail[-len(MCAP_MAGIC):] == MCAP_MAGIC and tail[0] == Opcode.FOOTER


def _truncated_chunk_records(tail: bytes) -> list[Any]:
    """The complete records at the start of a Chunk record cut short by the end of the file.

    ``tail`` is what the file holds after the chunk's 9-byte record header. Layout (MCAP
    spec, "Chunk"): message_start_time u64, message_end_time u64, uncompressed_size u64,
    uncompressed_crc u32, compression (u32 length + bytes), records (u64 length + bytes).
    The compressed prefix is decompressed as a stream (zstd, lz4 frames or none; at most the
    chunk's declared uncompressed size, :func:`fretc.logs.mcap.records.decompress`) and parsed
    record by record until a record is incomplete. Returns [] when nothing can be recovered.
    """
    try:
        (declared,) = struct.unpack_from("<Q", tail, 16)
        (clen,) = struct.unpack_from("<I", tail, 28)
        compression = tail[32:32 + clen].decode("ascii")
        data = tail[32 + clen + 8:]
        raw = decompress(compression, data, declared, partial=True)
    except Exception:  # a cut header or a cut compressed stream: nothing to recover
        return []
    records: list[Any] = []
    at = 0
    while at + 9 <= len(raw):
        opcode, length = RECORD_HEAD.unpack_from(raw, at)
        if at + 9 + length > len(raw):
            break
        try:
            rec = parse_record(opcode, raw[at + 9:at + 9 + length])
        except RECORD_ERRORS:
            break
        if rec is not None:
            records.append(rec)
        at += 9 + length
    return records


def _peek_chunk_start(f: BinaryIO, pos: int) -> int | None:
    """message_start_time of the (truncated) Chunk record at ``pos``, if its first field is there."""
    here = f.tell()
    try:
        f.seek(pos + 9)
        raw = f.read(8)
        return struct.unpack("<Q", raw)[0] if len(raw) == 8 else None
    finally:
        f.seek(here)


def index_disagreement(path: str, index: McapIndex) -> str | None:
    """Where the summary's index disagrees with the data section, or None when it accounts
    for every chunk and message. The index is a hint, never the truth (MCAP spec: the summary
    only repeats what the data section holds): the data section's record headers are read
    (bodies skipped, only each chunk's own start and end times read) and compared. Where the
    framing itself is broken (a record running past the DataEnd record), the data is damaged
    and nothing is compared: the reader's checks of each chunk report that damage.

    Disagreements: a Chunk record no ChunkIndex points to, or a ChunkIndex pointing at no
    Chunk record of its length; a ChunkIndex whose times differ from its chunk's or run
    backwards; a Message record outside chunks (no index covers it). A channel or schema
    the summary does not repeat is none: the MCAP specification makes the summary's Schema
    and Channel records optional (the mcap writer's ``repeat_channels=False``,
    ``repeat_schemas=False``); :func:`missing_records` says when the reader must take them
    from the data section.
    """
    chunks: dict[int, tuple[int, int, int]] = {}  # offset -> (record length, start, end)
    with open(path, "rb") as f:
        pos = len(MCAP_MAGIC)
        while pos < index.data_end_offset:
            f.seek(pos)
            head = f.read(9 + 16)
            if len(head) < 9:
                return f"the data section ends at byte {pos}, before the DataEnd record"
            opcode, length = RECORD_HEAD.unpack_from(head)
            if pos + 9 + length > index.data_end_offset:
                # the framing itself is damaged from here on: nothing to compare the index
                # with; the indexed reader checks each chunk it reads (CRC, record layout)
                # and reports the damage as gaps
                return None
            if opcode == Opcode.MESSAGE:
                return f"a Message record at byte {pos} lies outside every chunk"
            if opcode == Opcode.CHUNK and len(head) == 25:
                chunks[pos] = (9 + length, *struct.unpack_from("<QQ", head, 9))
            pos += 9 + length
    return _compare_chunks(chunks, index)


def _compare_chunks(chunks: dict[int, tuple[int, int, int]], index: McapIndex) -> str | None:
    """The first ChunkIndex that disagrees with the chunks found, or a chunk it misses."""
    seen = set()
    for ci in index.chunk_indexes:
        found = chunks.get(ci.chunk_start_offset)
        at = f"the ChunkIndex of the chunk at byte {ci.chunk_start_offset}"
        if found is None or found[0] != ci.chunk_length:
            return f"{at} points at no Chunk record of its length"
        if ci.message_start_time > ci.message_end_time:
            return f"{at} ends before it starts ({ci.message_start_time} > {ci.message_end_time})"
        if (ci.message_start_time, ci.message_end_time) != found[1:]:
            return f"{at} gives other times than the chunk itself"
        seen.add(ci.chunk_start_offset)
    missed = sorted(set(chunks) - seen)
    if missed:
        return f"the chunk at byte {missed[0]} has no ChunkIndex"
    return None


def missing_records(index: McapIndex) -> str | None:
    """A channel or schema the index needs that the summary does not hold (channels named by
    the chunks' message indexes or by the Statistics record; a chunked summary with no Channel
    record at all cannot name the topics), in words; None when the summary holds them all.
    Not damage: the reader takes them from the data section."""
    if index.chunk_indexes and not index.channels:
        return "the summary holds no Channel record"
    st = index.statistics
    for cid in (st.channel_message_counts if st is not None else {}):
        if cid not in index.channels:
            return f"the summary does not hold channel {cid}, which its statistics count"
    for ci in index.chunk_indexes:
        for cid in ci.message_index_offsets:
            if cid not in index.channels:
                return f"the summary does not hold channel {cid}, which a chunk holds"
    for ch in index.channels.values():
        if ch.schema_id != 0 and ch.schema_id not in index.schemas:
            return f"the summary does not hold schema {ch.schema_id} of channel {ch.id}"
    return None
