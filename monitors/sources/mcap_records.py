"""MCAP framing: the record layer under :class:`~monitors.sources.mcap_source.McapSource`.

Records are a 1-byte opcode, a u64 length and a body (MCAP spec, "Records"); bodies are
parsed with the ``mcap`` library's record classes (:mod:`mcap.records`). The framing itself
is ours, not :class:`mcap.stream_reader.StreamReader`'s: a reader of damaged logs must know
the byte offset of every record (problems name it), skip a record whose body does not parse
and go on with the next one, and keep the data-section CRC running over records it skips;
the library's stream stops at the first bad record.
"""

from __future__ import annotations

import io
import struct
import zlib
from typing import Any, BinaryIO

import lz4.frame
import zstandard
from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, ChunkIndex, DataEnd, Footer, Header, Message as McapMessage
from mcap.records import Schema, Statistics
from mcap.stream_reader import CRCValidationError, breakup_chunk

__all__ = ["MCAP_MAGIC", "RECORD_HEAD", "FOOTER_LEN", "DATA_END_LEN", "RECORD_ERRORS",
           "parse_record", "chunk_records", "chunk_messages", "crc_skip"]

MCAP_MAGIC = b"\x89MCAP0\r\n"  # MCAP spec, "Magic"
RECORD_HEAD = struct.Struct("<BQ")  # opcode, record length (MCAP spec, "Records")
FOOTER_LEN = 1 + 8 + 8 + 8 + 4  # opcode, length, summary_start, summary_offset_start, summary_crc
DATA_END_LEN = 1 + 8 + 4  # opcode, length, data_section_crc
MAX_UNCOMPRESSED = 4 * 2**30  # a chunk claiming more than this is treated as corrupt
_MESSAGE_HEAD = struct.Struct("<HIQQ")  # channel_id, sequence, log_time, publish_time
_OP_MESSAGE = int(Opcode.MESSAGE)

#: Errors of a record body that does not parse.
RECORD_ERRORS = (McapError, struct.error, UnicodeDecodeError, ValueError, EOFError, MemoryError,
                 OverflowError)

_RECORD_CLASSES = {Opcode.CHUNK: Chunk, Opcode.SCHEMA: Schema, Opcode.CHANNEL: Channel,
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


def chunk_records(chunk: Chunk) -> list[Any]:
    """The Schema, Channel and Message records inside ``chunk``, CRC-checked (MCAP spec,
    "Chunk": uncompressed_crc), by :func:`mcap.stream_reader.breakup_chunk`.

    Raises:
        CRCValidationError: the uncompressed bytes do not match the chunk's CRC.
        ValueError: a chunk claiming more than 4 GiB uncompressed; the decompression
            libraries and the record classes raise their own errors on damaged bytes.
    """
    if chunk.uncompressed_size > MAX_UNCOMPRESSED:
        raise ValueError(f"chunk claims {chunk.uncompressed_size} uncompressed bytes")
    return breakup_chunk(chunk, validate_crc=True)


def chunk_messages(chunk: Chunk, wanted: set[int] | dict, known: set[int] | dict
                   ) -> list[McapMessage]:
    """The Message records of an MCAP ``chunk`` on channels in ``wanted``, and those on
    channels not in ``known`` (the caller reports them), as ``mcap.records.Message``; other
    records are skipped without being parsed (MCAP spec, "Chunk" and "Message").

    The chunk is decompressed (zstd, lz4 or none) and its ``uncompressed_crc`` checked as
    ``mcap.stream_reader.breakup_chunk(validate_crc=True)`` does; ``breakup_chunk`` itself
    is not used here because it builds an object for every record of the chunk (most of
    them on topics no requirement reads) and reads an unknown compression as none.

    Raises:
        CRCValidationError: the uncompressed bytes do not match the chunk's CRC.
        ValueError: an unknown compression, a chunk claiming more than 4 GiB uncompressed,
            or a record that runs past the chunk's end.
    """
    if chunk.uncompressed_size > MAX_UNCOMPRESSED:
        raise ValueError(f"chunk claims {chunk.uncompressed_size} uncompressed bytes")
    if chunk.compression == "zstd":
        data = zstandard.decompress(chunk.data, chunk.uncompressed_size)
    elif chunk.compression == "lz4":
        data = lz4.frame.decompress(chunk.data)
    elif chunk.compression == "":
        data = bytes(chunk.data)
    else:
        raise ValueError(f"unknown chunk compression {chunk.compression!r}")
    if chunk.uncompressed_crc != 0:
        crc = zlib.crc32(data)
        if crc != chunk.uncompressed_crc:
            raise CRCValidationError(expected=chunk.uncompressed_crc, actual=crc, record=chunk)
    out: list[McapMessage] = []
    head = RECORD_HEAD.unpack_from
    mhead = _MESSAGE_HEAD.unpack_from
    pos = 0
    end = len(data)
    while pos < end:
        opcode, length = head(data, pos)
        body = pos + 9
        pos = body + length
        if pos > end:
            raise ValueError(f"record at byte {body - 9} of the chunk runs past its end")
        if opcode != _OP_MESSAGE:
            continue
        cid, seq, log_time, publish_time = mhead(data, body)
        if cid in wanted or cid not in known:
            # positional, in the dataclass's field order (keywords cost more)
            out.append(McapMessage(cid, log_time, data[body + 22:pos], publish_time, seq))
    return out


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
