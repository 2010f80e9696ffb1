"""Index forgeries and schemas that lie (../shared/DESIGN.md "Damage is never evidence"):
MessageIndex records and the channel lists of ChunkIndex records are hints fretc never
follows (every chunk is read whole), so forging them changes nothing that is read; a schema
whose definition of a standard ROS type is not ROS's (fields swapped, retyped, dropped) makes
its topic unreadable with the reason, never a value read from another field; a payload whose
size does not fit its declared layout is ``undecodable``."""

from __future__ import annotations

import random
import struct
from pathlib import Path

from mcap.writer import CompressionType, IndexType

from fretc.logs import open_log
from test_mcap_variants import _write

TWIST = ("Vector3 linear\nVector3 angular\n" + "=" * 80 + "\nMSG: geometry_msgs/Vector3\n"
         "float64 x\nfloat64 y\nfloat64 z\n")


def _records(data: bytes, start: int, end: int):
    """(position, opcode, length) of the records between byte ``start`` and ``end``."""
    pos = start
    while pos < end:
        opcode, length = struct.unpack_from("<BQ", data, pos)
        yield pos, opcode, length
        pos += 9 + length


def _summary_start(data: bytes) -> int:
    return struct.unpack_from("<Q", data, len(data) - 8 - 20)[0]


def _read(path: Path, topics=None) -> tuple[dict, list]:
    src = open_log(str(path))
    try:
        got: dict = {}
        for m in src.messages(topics):
            got.setdefault(m.topic, []).append(m.log_time)
        return got, [p.kind for p in src.problems]
    finally:
        src.close()


def test_forged_message_index_records_change_nothing_read(tmp_path):
    path = tmp_path / "v.mcap"
    written = _write(path, True, CompressionType.ZSTD, IndexType.ALL, True, False)
    data = bytearray(path.read_bytes())
    rng = random.Random(7)
    forged = 0
    for pos, opcode, length in _records(bytes(data), 8, _summary_start(data)):
        if opcode == 0x07:  # MessageIndex: channel id, then (log time, offset) pairs
            struct.pack_into("<H", data, pos + 9, rng.choice((1, 2, 3, 999)))
            for k in range(pos + 9 + 2 + 4, pos + 9 + length, 8):
                struct.pack_into("<Q", data, k, rng.getrandbits(64))
            forged += 1
    assert forged > 3
    path.write_bytes(bytes(data))
    got, problems = _read(path)
    assert got == {t: written[t] for t in ("/a", "/b", "/j")}  # /j: JSON, read too
    assert problems == []


def test_a_chunk_index_listing_other_channels_does_not_drop_the_chunk(tmp_path):
    path = tmp_path / "v.mcap"
    written = _write(path, True, CompressionType.ZSTD, IndexType.ALL, True, False)
    data = bytearray(path.read_bytes())
    start = _summary_start(data)
    for pos, opcode, _length in _records(bytes(data), start, len(data) - 8 - 29):
        if opcode == 0x08:  # ChunkIndex: 4 u64, then the map channel id -> offset
            n = struct.unpack_from("<I", data, pos + 9 + 32)[0]
            for k in range(pos + 9 + 36, pos + 9 + 36 + n, 10):
                struct.pack_into("<H", data, k, 3)  # every entry names /j only
    path.write_bytes(bytes(data))  # the summary CRC is 0: "not computed" (MCAP spec)
    got, _ = _read(path, {"/a"})
    assert got == {"/a": written["/a"]}


def _twist_log(tmp_path: Path, schema: str, name: str = "geometry_msgs/msg/Twist") -> Path:
    """Ten ROS Twist payloads on /cmd_vel under the schema ``name`` with text ``schema``."""
    from _logs import ROS2, twist, write_mcap

    raw = {k: bytes(ROS2.serialize_cdr(twist(1.0 + k, -5.0), "geometry_msgs/msg/Twist"))
           for k in range(10)}
    msgs = [("/cmd_vel", name, 10**9 + k * 10**8, None) for k in range(10)]
    return write_mcap(tmp_path / "t.mcap", msgs, raw_override=raw,
                      schema_override={"/cmd_vel": ("ros2msg", schema.encode())})


def _problems(path: Path) -> tuple[int, list]:
    src = open_log(str(path))
    try:
        n = sum(1 for _ in src.messages(None))
        return n, [(p.kind, p.detail) for p in src.problems]
    finally:
        src.close()


def test_a_schema_with_twist_fields_swapped_makes_the_topic_unreadable(tmp_path):
    assert _problems(_twist_log(tmp_path, TWIST))[1] == []  # ROS's own layout is read
    swapped = TWIST.replace("Vector3 linear\nVector3 angular", "Vector3 angular\nVector3 linear")
    for lie in (swapped, TWIST.replace("float64 x\nfloat64 y", "float64 y\nfloat64 x"),
                TWIST.replace("float64 x", "int64 x")):
        n, problems = _problems(_twist_log(tmp_path, lie))
        assert n == 0, lie
        assert problems[0][0] == "unknown_schema"
        assert "not ROS's" in problems[0][1]
    assert "'angular' where ROS has 'linear'" in _problems(_twist_log(tmp_path, swapped))[1][0][1]


def test_a_payload_that_does_not_fit_a_custom_layout_is_undecodable(tmp_path):
    text = TWIST.replace("geometry_msgs/Vector3", "my_pkg/Vector3").replace(
        "Vector3 linear", "my_pkg/Vector3 linear").replace("float64", "float32")
    n, problems = _problems(_twist_log(tmp_path, text, "my_pkg/msg/Pair"))
    assert n == 0
    assert {k for k, _ in problems} == {"undecodable"}


def test_the_binding_type_check_reads_a_bomb_with_bounded_memory(tmp_path):
    """The schemas the bindings are type-checked against come from the source's own bounded
    reading: a chunk of 64 MiB of zeros declaring 100 bytes is not decompressed."""
    import random
    import sys
    import tracemalloc

    from fretc.logs.schema import log_schemas

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
    import fuzz_hostile

    data = fuzz_hostile.small_mcap()
    path = tmp_path / "bomb.mcap"
    path.write_bytes(fuzz_hostile.bomb(random.Random(0), data, 64 * 2**20, "zstd", 100))
    src = open_log(str(path))
    tracemalloc.start()
    try:
        log_schemas(src)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
        src.close()
    assert peak < 16 * 2**20
