"""Every variant of an MCAP file the spec allows is read as written: the variants of the MCAP
conformance suite (chunked or not, each compression, with or without CRCs, statistics, summary
offsets, repeated schemas and channels, chunk and message indexes), made here with the mcap
writer. Counts are independent of decoding (a channel in an encoding fretc cannot decode is
counted, not decoded), and a summary index that lies is a hint the reader does not follow."""

from __future__ import annotations

import itertools
import struct
from pathlib import Path

import pytest
from mcap.writer import CompressionType, IndexType, Writer

from fretc.logs import open_log

#: (topic, log times) written per channel: a decodable ROS 2 channel, a second one on the same
#: schema, and a JSON channel fretc reads but cannot decode
CHANNELS = (("/a", range(0, 300, 3)), ("/b", range(1, 300, 7)), ("/j", range(2, 300, 11)))
VARIANTS = list(itertools.product(
    (True, False),                                    # use_chunking
    (CompressionType.NONE, CompressionType.ZSTD, CompressionType.LZ4),
    (IndexType.ALL, IndexType.NONE, IndexType.CHUNK),
    (True, False),                                    # repeat_channels and repeat_schemas
    (True, False),                                    # statistics, summary offsets, CRCs
))


def _write(path: Path, chunking, compression, index, repeat, extras) -> dict[str, list[int]]:
    written: dict[str, list[int]] = {}
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=512, compression=compression, index_types=index,
                   repeat_channels=repeat, repeat_schemas=repeat, use_chunking=chunking,
                   use_statistics=extras, use_summary_offsets=extras, enable_crcs=extras,
                   enable_data_crcs=extras)
        w.start("ros2", "fretc-test")
        sid = w.register_schema("std_msgs/msg/Float64", "ros2msg", b"float64 data")
        ids = {"/a": w.register_channel("/a", "cdr", sid),
               "/b": w.register_channel("/b", "cdr", sid),
               "/j": w.register_channel("/j", "json", 0)}
        events = sorted((t, topic) for topic, times in CHANNELS for t in times)
        for t, topic in events:
            data = (b'{"data": %d}' % t if topic == "/j"
                    else b"\x00\x01\x00\x00" + struct.pack("<d", float(t)))
            ns = 10**9 + t * 10**6
            w.add_message(ids[topic], log_time=ns, data=data, publish_time=ns)
            written.setdefault(topic, []).append(ns)
        w.finish()
    return written


@pytest.mark.tor("TOR-LOG-001")
@pytest.mark.parametrize("variant", VARIANTS, ids=lambda v: "-".join(map(str, v)))
def test_every_writer_variant_is_read_as_written(tmp_path, variant):
    path = tmp_path / "v.mcap"
    written = _write(path, *variant)
    src = open_log(str(path))
    try:
        assert sorted(src.topics()) == ["/a", "/b", "/j"]
        got: dict[str, list[int]] = {}
        for m in src.messages(None):
            got.setdefault(m.topic, []).append(m.log_time)
        assert got == written  # decoded (/j: JSON), in log-time order
        assert src.records == {t: len(v) for t, v in written.items()}
        assert not src.partial
    finally:
        src.close()


def _chunk_index_times_forged(data: bytearray) -> None:
    """Set the first ChunkIndex's (message_start_time, message_end_time) to (2^64-1, 0),
    leaving the summary CRC at 0 ("not computed", which the MCAP spec allows)."""
    summary_start = struct.unpack_from("<Q", data, len(data) - 8 - 20)[0]
    pos = summary_start
    while pos < len(data) - 8 - 29:
        opcode, length = struct.unpack_from("<BQ", data, pos)
        if opcode == 0x08:  # ChunkIndex
            struct.pack_into("<QQ", data, pos + 9, 2**64 - 1, 0)
            return
        pos += 9 + length
    raise AssertionError("no ChunkIndex")


def test_a_forged_chunk_index_is_not_followed(tmp_path):
    path = tmp_path / "v.mcap"
    written = _write(path, True, CompressionType.ZSTD, IndexType.ALL, True, False)
    data = bytearray(path.read_bytes())
    _chunk_index_times_forged(data)
    path.write_bytes(bytes(data))
    src = open_log(str(path))
    try:
        got = {}
        for m in src.messages(None):
            got.setdefault(m.topic, []).append(m.log_time)
        assert got == written  # no chunk dropped
        assert any(p.kind == "index_mismatch" for p in src.problems), src.problems
    finally:
        src.close()
