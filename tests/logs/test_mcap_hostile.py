"""Hostile MCAP files: decompression bombs and lying sizes cost bounded memory and are damage,
never a crash or a verdict (../shared/DESIGN.md "Damage is never evidence")."""

from __future__ import annotations

import io
import struct
import tracemalloc
from pathlib import Path

import lz4.frame
import pytest
import zstandard
from mcap.writer import CompressionType, Writer

from fretc.logs import open_log
from fretc.logs.mcap.records import RECORD_HEAD, decompress

_MB = 2**20


def _zstd_zeros(n: int) -> bytes:
    """A zstd stream of ``n`` zero bytes without holding them (a few KB per 100 MB)."""
    out = io.BytesIO()
    with zstandard.ZstdCompressor().stream_writer(out, closefd=False) as w:
        block = bytes(_MB)
        for _ in range(n // _MB):
            w.write(block)
    return out.getvalue()


def _peak(fn) -> int:
    """Peak bytes allocated by Python while ``fn`` runs (tracemalloc)."""
    tracemalloc.start()
    try:
        fn()
    except ValueError:
        pass
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak


@pytest.mark.parametrize("codec", ["zstd", "lz4"])
@pytest.mark.tor("TOR-DMG-005")
def test_a_bomb_is_stopped_at_the_declared_size(codec):
    data = (_zstd_zeros(64 * _MB) if codec == "zstd"
            else lz4.frame.compress(bytes(64 * _MB)))
    with pytest.raises(ValueError, match="more bytes than the 1000 it declares"):
        decompress(codec, data, 1000)
    assert _peak(lambda: decompress(codec, data, 1000)) < 4 * _MB


@pytest.mark.tor("TOR-DMG-005")
def test_a_declared_size_above_the_cap_is_damage_without_allocation(monkeypatch):
    data = _zstd_zeros(4 * _MB)
    with pytest.raises(ValueError, match="above the cap"):
        decompress("zstd", data, 3 * 2**30)
    monkeypatch.setenv("FRETC_MAX_CHUNK_BYTES", str(_MB))
    with pytest.raises(ValueError, match="above the cap of 1048576"):
        decompress("zstd", data, 4 * _MB)
    monkeypatch.setenv("FRETC_MAX_CHUNK_BYTES", "lots")
    with pytest.raises(ValueError, match="FRETC_MAX_CHUNK_BYTES"):
        decompress("zstd", data, 10)


def test_fewer_bytes_than_declared_is_damage_unless_the_file_is_cut():
    data = zstandard.ZstdCompressor().compress(b"x" * 100)
    with pytest.raises(ValueError, match="fewer bytes"):
        decompress("zstd", data, 200)
    assert decompress("zstd", data, 200, partial=True) == b"x" * 100


def _write(path: Path, chunks: int = 3, per_chunk: int = 50) -> None:
    """An MCAP with ``chunks`` zstd chunks of ``per_chunk`` std_msgs/Float64 messages."""
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.ZSTD, chunk_size=per_chunk * 16)
        w.start("ros2", "test")
        sid = w.register_schema("std_msgs/msg/Float64", "ros2msg", b"float64 data")
        cid = w.register_channel("/x", "cdr", sid)
        for i in range(chunks * per_chunk):
            payload = b"\x00\x01\x00\x00" + struct.pack("<d", float(i))
            w.add_message(cid, log_time=10**9 + i * 10**7, data=payload,
                          publish_time=10**9 + i * 10**7)
        w.finish()


def _chunk_offsets(data: bytes) -> list[int]:
    """Byte offsets of the Chunk records of the data section."""
    out, pos = [], 8
    while pos + 9 <= len(data):
        opcode, length = RECORD_HEAD.unpack_from(data, pos)
        if opcode == 0x06:
            out.append(pos)
        if opcode == 0x0F:  # DataEnd
            break
        pos += 9 + length
    return out


def test_a_chunk_with_a_lying_size_is_a_gap_not_a_crash(tmp_path):
    path = tmp_path / "ok.mcap"
    _write(path)
    data = bytearray(path.read_bytes())
    second = _chunk_offsets(bytes(data))[1]
    struct.pack_into("<Q", data, second + 9 + 16, 2**30)  # uncompressed_size of chunk 2: 1 GiB
    bad = tmp_path / "lying.mcap"
    bad.write_bytes(bytes(data))
    src = open_log(str(bad))
    try:
        times = [m.log_time for m in src.messages({"/x"})]
    finally:
        src.close()
    # the other chunks are read; the lying one is a gap where the log's intact span ends
    assert src.partial and 0 < len(times) < 150
    assert src.intact_end is not None and src.intact_end <= 10**9 + 150 * 10**7
    assert any("above the cap" in p.detail for p in src.problems), src.problems


@pytest.mark.parametrize("opcode", [0x02, 0x0F])  # Footer, DataEnd
def test_an_end_record_followed_by_data_is_damage_not_the_end(tmp_path, opcode):
    """A chunk's opcode flipped into a Footer or DataEnd (one bit: 0x06 -> 0x02) mid-file,
    the summary damaged too: the linear reader does not stop there as at the end of the
    data (which would judge the rest as never written); the record is a gap and the chunks
    after it are read."""
    from _logs import float64, write_mcap

    msgs = [("/f", "std_msgs/msg/Float64", i * 10**8, float64(i)) for i in range(60)]
    path = write_mcap(tmp_path / "c.mcap", msgs, chunk_size=200)
    data = bytearray(path.read_bytes())
    chunks, pos = [], 8
    while pos + 9 <= len(data):
        op, length = RECORD_HEAD.unpack_from(data, pos)
        if op == 0x06:
            chunks.append(pos)
        if op == 0x0F:
            break
        pos += 9 + length
    data[chunks[1]] = opcode
    data[-12] ^= 0xFF  # the summary CRC: the file is read without its index
    path.write_bytes(bytes(data))
    src = open_log(path)
    got = [m.log_time for m in src.messages()]
    assert src.partial and src.damage_cut
    assert any(p.kind == "corrupt_record" for p in src.problems)
    assert got[-1] == 59 * 10**8  # read past the damaged record
    assert src.intact_end is not None and src.intact_end <= got[0] + 10**9
