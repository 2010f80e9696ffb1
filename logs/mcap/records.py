"""MCAP framing: the record layer under :class:`~fretc.logs.mcap.source.McapSource`.

Records are a 1-byte opcode, a u64 length and a body (MCAP spec, "Records"); bodies are
parsed with the ``mcap`` library's record classes (:mod:`mcap.records`). The framing itself
is ours, not :class:`mcap.stream_reader.StreamReader`'s: a reader of damaged logs must know
the byte offset of every record (problems name it), skip a record whose body does not parse
and go on with the next one, and keep the data-section CRC running over records it skips;
the library's stream stops at the first bad record.
"""

from __future__ import annotations

import io
import os
import struct
import zlib
from typing import Any, BinaryIO

import lz4.frame
import numpy as np
import zstandard
from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, ChunkIndex, DataEnd, Footer, Header, Message as McapMessage
from mcap.records import Schema, Statistics
from mcap.stream_reader import CRCValidationError

__all__ = ["MCAP_MAGIC", "RECORD_HEAD", "FOOTER_LEN", "DATA_END_LEN", "RECORD_ERRORS",
           "parse_record", "chunk_records", "chunk_messages", "chunk_message_table", "crc_skip",
           "decompress", "max_chunk_bytes", "data_follows"]

MCAP_MAGIC = b"\x89MCAP0\r\n"  # MCAP spec, "Magic"
RECORD_HEAD = struct.Struct("<BQ")  # opcode, record length (MCAP spec, "Records")
FOOTER_LEN = 1 + 8 + 8 + 8 + 4  # opcode, length, summary_start, summary_offset_start, summary_crc
DATA_END_LEN = 1 + 8 + 4  # opcode, length, data_section_crc
#: Default cap on one chunk's uncompressed size (bytes); the environment variable
#: ``FRETC_MAX_CHUNK_BYTES`` sets another. Recorders write chunks of a few MB (the mcap
#: writer's default is 1 MiB); a chunk declaring more is damage, not a reason to allocate it.
DEFAULT_MAX_CHUNK_BYTES = 512 * 2**20
_BLOCK = 1 << 20
_MESSAGE_HEAD = struct.Struct("<HIQQ")  # channel_id, sequence, log_time, publish_time
_OP_MESSAGE = int(Opcode.MESSAGE)

#: Errors of a record body that does not parse.
RECORD_ERRORS = (McapError, struct.error, UnicodeDecodeError, ValueError, EOFError, MemoryError,
                 OverflowError)

_RECORD_CLASSES: dict[int, Any] = {Opcode.CHUNK: Chunk, Opcode.SCHEMA: Schema, Opcode.CHANNEL: Channel,
                   Opcode.HEADER: Header, Opcode.DATA_END: DataEnd, Opcode.FOOTER: Footer,
                   Opcode.CHUNK_INDEX: ChunkIndex, Opcode.STATISTICS: Statistics}


def parse_record(opcode: int, body: bytes) -> Any:
    """One record body parsed with the mcap library's record classes: a Message, Chunk,
    Schema, Channel, Header, DataEnd, Footer, ChunkIndex or Statistics (None for other
    opcodes, which no reader here needs).

    Raises:
        one of :data:`RECORD_ERRORS`: the body does not parse.
    """
    stream = ReadDataStream(io.BytesIO(body))
    if opcode == Opcode.MESSAGE:
        return McapMessage.read(stream, len(body))
    cls = _RECORD_CLASSES.get(opcode)
    return cls.read(stream) if cls is not None else None


def max_chunk_bytes() -> int:
    """The cap on one chunk's uncompressed size: ``FRETC_MAX_CHUNK_BYTES`` (bytes, a positive
    integer) or :data:`DEFAULT_MAX_CHUNK_BYTES`.

    Raises:
        ValueError: the variable is set but not a positive integer.
    """
    text = os.environ.get("FRETC_MAX_CHUNK_BYTES")
    if text is None:
        return DEFAULT_MAX_CHUNK_BYTES
    if not text.strip().isdigit() or int(text) <= 0:
        raise ValueError(f"FRETC_MAX_CHUNK_BYTES={text!r}: a positive number of bytes")
    return int(text)


def decompress(compression: str, data: bytes, declared: int, *, partial: bool = False
               ) -> bytes:
    """A chunk's records decompressed (``""``, ``"zstd"`` or ``"lz4"``; MCAP spec, "Chunk"),
    never more than ``declared`` bytes (its ``uncompressed_size``) plus one, so a
    decompression bomb or a lying size costs at most that much memory.

    Args:
        compression: the chunk's compression field.
        data: the compressed records.
        declared: the chunk's uncompressed_size (bytes).
        partial: ``data`` is cut short (a truncated file): return what decompresses, up to
            ``declared`` bytes, instead of requiring exactly ``declared``.

    Raises:
        ValueError: an unknown compression; ``declared`` above :func:`max_chunk_bytes`; the
            output is longer than ``declared`` (or, unless ``partial``, shorter). The
            decompression libraries raise their own errors on damaged bytes.
    """
    cap = max_chunk_bytes()
    if declared > cap:
        raise ValueError(f"chunk declares {declared} uncompressed bytes, above the cap of "
                         f"{cap} (FRETC_MAX_CHUNK_BYTES)")
    if compression == "":
        out = bytes(data[:declared + 1])
    elif compression == "zstd":
        out = _zstd(data, declared + 1, partial)
    elif compression == "lz4":
        d = lz4.frame.LZ4FrameDecompressor()
        try:
            out = d.decompress(data, max_length=declared + 1)
        except RuntimeError:
            if not partial:
                raise
            out = b""
    else:
        raise ValueError(f"unknown chunk compression {compression!r}")
    if len(out) > declared or (len(out) < declared and not partial):
        raise ValueError(f"chunk decompresses to {'more' if len(out) > declared else 'fewer'}"
                         f" bytes than the {declared} it declares")
    return out


def _zstd(data: bytes, limit: int, partial: bool) -> bytes:
    """At most ``limit`` bytes of a zstd stream, read in blocks (bounded memory)."""
    reader = zstandard.ZstdDecompressor().stream_reader(io.BytesIO(data))
    parts, size = [], 0
    try:
        while size < limit:
            block = reader.read(min(_BLOCK, limit - size))
            if not block:
                break
            parts.append(block)
            size += len(block)
    except zstandard.ZstdError:
        if not partial:
            raise
    return b"".join(parts)


def _records(data: bytes) -> list[Any]:
    """The records of decompressed chunk bytes, parsed (MCAP spec, "Records").

    Raises:
        ValueError: a record runs past the end; one of :data:`RECORD_ERRORS` for a body that
            does not parse.
    """
    out, pos, end = [], 0, len(data)
    while pos < end:
        if pos + 9 > end:
            raise ValueError(f"record header at byte {pos} of the chunk runs past its end")
        opcode, length = RECORD_HEAD.unpack_from(data, pos)
        if pos + 9 + length > end:
            raise ValueError(f"record at byte {pos} of the chunk runs past its end")
        rec = parse_record(opcode, data[pos + 9:pos + 9 + length])
        if rec is not None:
            out.append(rec)
        pos += 9 + length
    return out


def _checked(chunk: Chunk) -> bytes:
    """The chunk's records decompressed (bounded, :func:`decompress`) and CRC-checked."""
    data = decompress(chunk.compression, chunk.data, chunk.uncompressed_size)
    if chunk.uncompressed_crc != 0:
        crc = zlib.crc32(data)
        if crc != chunk.uncompressed_crc:
            raise CRCValidationError(expected=chunk.uncompressed_crc, actual=crc, record=chunk)
    return data


def chunk_records(chunk: Chunk) -> list[Any]:
    """The Schema, Channel and Message records inside ``chunk``, CRC-checked (MCAP spec,
    "Chunk": uncompressed_crc), decompressed within its declared size (:func:`decompress`).

    Raises:
        CRCValidationError: the uncompressed bytes do not match the chunk's CRC.
        ValueError: as :func:`decompress`, or a record that runs past the chunk's end; the
            decompression libraries and the record classes raise their own errors on
            damaged bytes.
    """
    return _records(_checked(chunk))


def chunk_messages(chunk: Chunk, wanted: set[int] | dict, known: set[int] | dict
                   ) -> list[McapMessage]:
    """The Message records of an MCAP ``chunk`` on channels in ``wanted``, and those on
    channels not in ``known`` (the caller reports them), as ``mcap.records.Message``; other
    records are skipped without being parsed (MCAP spec, "Chunk" and "Message").

    The chunk is decompressed within its declared size (:func:`decompress`) and its
    ``uncompressed_crc`` checked (0: not computed, as the spec allows).

    Raises:
        CRCValidationError: the uncompressed bytes do not match the chunk's CRC.
        ValueError: as :func:`decompress`, or a record that runs past the chunk's end.
    """
    data = _checked(chunk)
    out: list[McapMessage] = []
    head = RECORD_HEAD.unpack_from
    mhead = _MESSAGE_HEAD.unpack_from
    pos = 0
    end = len(data)
    while pos < end:
        if pos + 9 > end:
            raise ValueError(f"record header at byte {pos} of the chunk runs past its end")
        opcode, length = head(data, pos)
        body = pos + 9
        pos = body + length
        if pos > end:
            raise ValueError(f"record at byte {body - 9} of the chunk runs past its end")
        if opcode != _OP_MESSAGE:
            continue
        if length < _MESSAGE_HEAD.size:
            raise ValueError(f"message record at byte {body - 9} of the chunk is too short")
        cid, seq, log_time, publish_time = mhead(data, body)
        if cid in wanted or cid not in known:
            # positional, in the dataclass's field order (keywords cost more)
            out.append(McapMessage(cid, log_time, data[body + 22:pos], publish_time, seq))
    return out


def chunk_message_table(chunk: Chunk) -> tuple[bytes, np.ndarray, np.ndarray]:
    """The Message records of an MCAP ``chunk`` as a table: the decompressed bytes and the
    int64 byte offsets and lengths of every Message record's body in them, in file order
    (other records skipped). Checks and errors are :func:`chunk_messages`'s.

    Raises:
        CRCValidationError: the uncompressed bytes do not match the chunk's CRC.
        ValueError: as :func:`decompress`, or a record that runs past the chunk's end.
    """
    data = _checked(chunk)
    starts: list[int] = []
    lengths: list[int] = []
    head = RECORD_HEAD.unpack_from
    pos, end, least = 0, len(data), _MESSAGE_HEAD.size
    while pos < end:
        if pos + 9 > end:
            raise ValueError(f"record header at byte {pos} of the chunk runs past its end")
        opcode, length = head(data, pos)
        if pos + 9 + length > end:
            raise ValueError(f"record at byte {pos} of the chunk runs past its end")
        if opcode == _OP_MESSAGE:
            if length < least:
                raise ValueError(f"message record at byte {pos} of the chunk is too short")
            starts.append(pos + 9)
            lengths.append(length)
        pos += 9 + length
    return data, np.array(starts, dtype=np.int64), np.array(lengths, dtype=np.int64)


def crc_skip(f: BinaryIO, length: int, crc: int) -> int:
    """Read past ``length`` bytes of ``f`` in blocks, without holding them; returns ``crc``
    (CRC-32) continued over them."""
    while length > 0:
        block = f.read(min(length, 1 << 20))
        if not block:
            break
        crc = zlib.crc32(block, crc)
        length -= len(block)
    return crc


def data_follows(f: BinaryIO, at: int, size: int) -> bool:
    """Whether a Chunk or Message record starts at or after byte ``at`` (record headers
    walked to the end of the file, bodies skipped); the file position is restored."""
    back = f.tell()
    try:
        while at + 9 <= size:
            f.seek(at)
            head = f.read(9)
            if len(head) < 9:
                return False
            opcode, length = RECORD_HEAD.unpack(head)
            if opcode in (Opcode.CHUNK, Opcode.MESSAGE) and at + 9 + length <= size:
                return True
            at += 9 + length
        return False
    finally:
        f.seek(back)
