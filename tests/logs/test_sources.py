"""Trace sources: real logs, hand-made MCAPs, damaged copies, rosbag2, CSV."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st
from mcap.reader import make_reader
from mcap.writer import CompressionType
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import Writer as Rosbag2Writer
from rosbags.typesys import Stores

from fretc.common import problems as P
from fretc.common.problems import CsvError, LogError
from fretc.logs import CSV_TOPIC, REORDER_WINDOW_NS, open_log

from _shared import needs_shared
from _logs import (CMD_VEL_MCAP, MS, ROS1, ROS2, S, STAGE_BAG, boolean, float64, scan, twist,
                   twist_stamped, write_mcap)


# ------------------------------------------------------------------------------------------------
# Real logs
# ------------------------------------------------------------------------------------------------


@needs_shared
def test_real_mcap_counts_topics_and_values_match_independent_decode():
    src = open_log(CMD_VEL_MCAP)
    assert src.kind == "mcap" and src.indexed
    assert src.topics() == {"/scaled/cmd_vel": "geometry_msgs/msg/TwistStamped",
                            "/vehicle/cmd_vel": "geometry_msgs/msg/TwistStamped"}
    msgs = list(src.messages())
    assert src.counts == {"/scaled/cmd_vel": 50, "/vehicle/cmd_vel": 50}
    assert src.problems == [] and not src.partial
    # Independent decode: mcap's own reader + rosbags' bundled Humble types (not the file's schema).
    expected = []
    with open(CMD_VEL_MCAP, "rb") as f:
        for _schema, channel, m in make_reader(f).iter_messages(log_time_order=True):
            d = ROS2.deserialize_cdr(m.data, "geometry_msgs/msg/TwistStamped")
            expected.append((channel.topic, m.log_time, m.publish_time,
                             d.header.stamp.sec * S + d.header.stamp.nanosec,
                             d.twist.linear.x, d.twist.angular.z))
    got = [(m.topic, m.log_time, m.publish_time, m.header_stamp, m.data.twist.linear.x,
            m.data.twist.angular.z) for m in msgs]
    assert got == expected
    assert [m.log_time for m in msgs] == sorted(m.log_time for m in msgs)
    assert src.start_time == msgs[0].log_time and src.end_time == msgs[-1].log_time
    # The scaled command is never faster than the vehicle command it filters.
    assert max(m.data.twist.linear.x for m in msgs) > 0


@needs_shared
def test_real_mcap_topic_filter_reads_only_that_topic():
    src = open_log(CMD_VEL_MCAP)
    msgs = list(src.messages({"/vehicle/cmd_vel"}))
    assert {m.topic for m in msgs} == {"/vehicle/cmd_vel"}
    assert src.counts == {"/vehicle/cmd_vel": 50}


@needs_shared
def test_real_ros1_bag_counts_duration_and_values_match_anyreader():
    src = open_log(STAGE_BAG)
    assert src.kind == "bag"
    assert src.topics() == {"/base_pose_ground_truth": "nav_msgs/msg/Odometry",
                            "/base_scan": "sensor_msgs/msg/LaserScan"}
    msgs = list(src.messages())
    assert src.counts == {"/base_scan": 1727, "/base_pose_ground_truth": 1727}
    assert (src.end_time - src.start_time) == pytest.approx(172.6e9)
    scans = [m for m in msgs if m.topic == "/base_scan"]
    assert all(len(m.data.ranges) == 90 for m in scans)
    with AnyReader([STAGE_BAG]) as reader:
        ref = [(c.topic, t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages()]
    assert [(m.topic, m.log_time) for m in msgs] == [(t, lt) for t, lt, _ in ref]
    for m, (_topic, _t, d) in zip(msgs[::97], ref[::97]):
        if m.topic == "/base_scan":
            np.testing.assert_array_equal(m.data.ranges, d.ranges)
            assert m.data.range_max == d.range_max
        else:
            assert m.data.pose.pose.position.x == d.pose.pose.position.x
            assert m.data.twist.twist.angular.z == d.twist.twist.angular.z
        assert m.header_stamp == d.header.stamp.sec * S + d.header.stamp.nanosec


# ------------------------------------------------------------------------------------------------
# Hand-made MCAPs
# ------------------------------------------------------------------------------------------------


def _series(n=200, period=100 * MS, t0=5 * S):
    """Two topics, interleaved: /cmd (Twist, x = i) and /flag (Bool, every 3rd)."""
    out = []
    for i in range(n):
        out.append(("/cmd", "geometry_msgs/msg/Twist", t0 + i * period, twist(x=float(i), z=-i / 10)))
        if i % 3 == 0:
            out.append(("/flag", "std_msgs/msg/Bool", t0 + i * period + 7 * MS, boolean(i % 2 == 0)))
    return out


def _key(m):
    return (m.topic, m.log_time, m.data.linear.x if m.topic == "/cmd" else m.data.data)


def _expected(messages, keep=lambda t: True):
    out = []
    for topic, _typ, t, msg in sorted(messages, key=lambda x: x[2]):
        if keep(t):
            out.append((topic, t, msg.linear.x if topic == "/cmd" else msg.data))
    return out


@pytest.mark.parametrize("compression", [CompressionType.ZSTD, CompressionType.LZ4, CompressionType.NONE])
def test_mcap_roundtrip_compressions(tmp_path, compression):
    msgs = _series(60)
    path = write_mcap(tmp_path / "a.mcap", msgs, compression=compression, chunk_size=512,
                      publish_offset=-3)
    src = open_log(path)
    got = list(src.messages())
    assert [_key(m) for m in got] == _expected(msgs)
    assert all(m.publish_time == m.log_time - 3 for m in got)
    assert all(m.header_stamp is None for m in got)  # Twist and Bool have no header
    assert src.problems == []


def test_mcap_ros1_encoding(tmp_path):
    msgs = [("/scan", "sensor_msgs/msg/LaserScan", i * 100 * MS, scan([1.0 + i, 2.0], ns=i * 100 * MS, store=ROS1))
            for i in range(5)]
    path = write_mcap(tmp_path / "r1.mcap", msgs, ros1=True)
    src = open_log(path)
    assert src.topics() == {"/scan": "sensor_msgs/msg/LaserScan"}
    got = list(src.messages())
    assert [m.data.ranges[0] for m in got] == [1.0, 2.0, 3.0, 4.0, 5.0]
    assert [m.header_stamp for m in got] == [i * 100 * MS for i in range(5)]


def test_mcap_overlapping_chunks_come_out_in_log_time_order(tmp_path):
    msgs = _series(120)
    rng = np.random.default_rng(7)
    order = rng.permutation(len(msgs))
    shuffled = [msgs[i] for i in order]
    path = write_mcap(tmp_path / "shuffled.mcap", shuffled, chunk_size=300)
    got = list(open_log(path).messages())
    assert [_key(m) for m in got] == _expected(msgs)


def test_unchunked_mcap_small_disorder_is_reordered_large_is_reported(tmp_path):
    msgs = [("/f", "std_msgs/msg/Float64", t, float64(t)) for t in
            [0, 10 * MS, 5 * MS, 20 * MS, 3 * S, 4500 * MS, 1 * S, 5 * S]]
    path = write_mcap(tmp_path / "loose.mcap", msgs, use_chunking=False)
    src = open_log(path)
    assert not src.indexed
    got = list(src.messages())
    # 1 s arrives after 3 s was delivered (4.5 s is beyond the reorder window): skipped.
    assert [m.log_time for m in got] == [0, 5 * MS, 10 * MS, 20 * MS, 3 * S, 4500 * MS, 5 * S]
    assert [p.kind for p in src.problems] == [P.OUT_OF_ORDER]
    assert src.problems[0].log_time == 1 * S and src.problems[0].topic == "/f"
    assert REORDER_WINDOW_NS < 3 * S


# -- damage ---------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def chunked(tmp_path_factory):
    """An indexed MCAP with many small chunks, and its chunk layout from mcap's own reader."""
    path = tmp_path_factory.mktemp("chunked") / "good.mcap"
    msgs = _series(300)
    write_mcap(path, msgs, chunk_size=2048, compression=CompressionType.ZSTD)
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    chunks = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
    assert len(chunks) > 8
    return path, msgs, chunks


def _copy(src: Path, dst: Path, size: int | None = None, flip: list[int] = ()) -> Path:
    data = bytearray(src.read_bytes())
    if size is not None:
        data = data[:size]
    for off in flip:
        data[off] ^= 0xFF
    dst.write_bytes(bytes(data))
    return dst


def test_truncated_mcap_is_read_up_to_the_cut(tmp_path, chunked):
    path, msgs, chunks = chunked
    size = path.stat().st_size
    data_end = chunks[-1].chunk_start_offset + chunks[-1].chunk_length
    cuts = sorted({9, 40, chunks[0].chunk_start_offset + 5,
                   chunks[3].chunk_start_offset + chunks[3].chunk_length // 2,
                   chunks[6].chunk_start_offset + chunks[6].chunk_length - 1,
                   chunks[6].chunk_start_offset + chunks[6].chunk_length + 3,
                   chunks[-1].chunk_start_offset + 30, data_end + 2, size - 3})
    for cut in cuts:
        src = open_log(_copy(path, tmp_path / f"cut{cut}.mcap", size=cut))
        assert not src.indexed
        got = [_key(m) for m in src.messages()]
        complete = [c for c in chunks if c.chunk_start_offset + c.chunk_length <= cut]
        horizon = max((c.message_end_time for c in complete), default=-1)
        expected = _expected(msgs, keep=lambda t: t <= horizon)  # noqa: B023 (called at once)
        # every message of a complete chunk, plus what the cut chunk's prefix still holds
        everything = _expected(msgs)
        assert got[:len(expected)] == expected, cut
        assert got == everything[:len(got)], cut
        if cut >= data_end + 2:
            # Cut after the data section: every message is there.
            assert got == everything
        if cut <= data_end:
            assert src.partial, cut
            assert src.damage_time == (got[-1][1] if got else None)
            kinds = [p.kind for p in src.problems]
            assert kinds == [P.TRUNCATED], (cut, kinds)
            assert src.problems[0].log_time == src.damage_time
            assert str(cut) in src.problems[0].detail or "ends at byte" in src.problems[0].detail


@pytest.mark.parametrize("compression", [CompressionType.ZSTD, CompressionType.LZ4,
                                         CompressionType.NONE])
def test_messages_before_the_cut_inside_a_chunk_are_recovered(tmp_path, compression):
    # one big chunk, as a recorder writes before it flushes: a crash cuts it in the middle
    # (compressed streams decode block by block: the chunk spans several 64-128 KiB blocks)
    msgs = _series(6000)
    path = write_mcap(tmp_path / "one.mcap", msgs, chunk_size=1 << 24, compression=compression)
    with open(path, "rb") as f:
        (chunk,) = make_reader(f).get_summary().chunk_indexes
    cut = chunk.chunk_start_offset + chunk.chunk_length * 3 // 4
    src = open_log(_copy(path, tmp_path / "cut.mcap", size=cut))
    got = [_key(m) for m in src.messages()]
    everything = _expected(msgs)
    assert 0 < len(got) < len(everything)
    assert got == everything[:len(got)]
    assert src.partial and src.damage_time == got[-1][1]
    assert "recovered from the cut chunk" in src.problems[0].detail


def test_truncated_inside_magic_is_not_an_mcap(tmp_path, chunked):
    path, _msgs, _chunks = chunked
    with pytest.raises(LogError, match="not an MCAP file"):
        open_log(_copy(path, tmp_path / "tiny.mcap", size=5))


@pytest.mark.parametrize("compression", [CompressionType.ZSTD, CompressionType.NONE])
def test_flipped_bytes_in_a_chunk_skip_that_chunk_only(tmp_path, compression):
    msgs = _series(300)
    path = write_mcap(tmp_path / "good.mcap", msgs, chunk_size=2048, compression=compression)
    with open(path, "rb") as f:
        chunks = sorted(make_reader(f).get_summary().chunk_indexes, key=lambda c: c.chunk_start_offset)
    bad = chunks[4]
    middle = bad.chunk_start_offset + bad.chunk_length // 2 + 20
    keep = lambda t: not (bad.message_start_time <= t <= bad.message_end_time)  # noqa: E731
    damaged = _copy(path, tmp_path / "flipped.mcap", flip=[middle, middle + 1])
    for label, log in [("indexed", damaged),
                       ("linear", _copy(damaged, tmp_path / "flipped_cut.mcap",
                                        size=chunks[-1].chunk_start_offset + chunks[-1].chunk_length))]:
        src = open_log(log)
        assert src.indexed == (label == "indexed")
        got = [_key(m) for m in src.messages()]
        assert got == _expected(msgs, keep=keep), label
        kinds = [p.kind for p in src.problems if p.kind != P.DATA_CRC]
        # Uncompressed: the CRC catches it; zstd: decompression may fail first.
        allowed = [P.CHUNK_CRC] if compression == CompressionType.NONE else [P.CHUNK_CRC, P.CHUNK_CORRUPT]
        assert kinds[0] in allowed, (label, kinds)
        # The linear copy also lacks everything after the last chunk: partial, at its end.
        assert kinds[1:] == ([] if label == "indexed" else [P.TRUNCATED]), (label, kinds)
        # A skipped chunk is a gap: the log is partial and its intact span
        # ends where the gap starts.
        assert src.partial and src.damage_cut, label
        # (without the index the chunk header's start time is not CRC-covered: the gap
        # starts no later than the last good message before it)
        start = src.gaps[0][0]
        assert chunks[3].message_end_time <= start <= bad.message_start_time, label
        if label == "indexed":  # the summary's times, and the chunk's topics
            assert src.gaps[0][1] == bad.message_end_time, label
            assert src.gaps[0].topics is not None and src.gaps[0].topics, label
        else:  # the header's end, or the first message read after it, whichever is later
            nxt = min(m[2] for m in msgs if m[2] > bad.message_end_time)
            assert bad.message_end_time <= src.gaps[0][1] <= nxt, label
            assert src.gaps[0].topics is None, label
        assert src.intact_end == start, label
        prob = next(p for p in src.problems if p.kind in allowed)
        assert (prob.log_time, prob.end_time) == (bad.message_start_time, bad.message_end_time)


def test_damage_outside_chunks_fails_the_data_crc_only(tmp_path, chunked):
    path, msgs, chunks = chunked
    # The bytes right after chunk 2 are its MessageIndex records (outside any chunk).
    off = chunks[2].chunk_start_offset + chunks[2].chunk_length + 12
    src = open_log(_copy(path, tmp_path / "mi.mcap", flip=[off]))
    assert src.indexed
    assert [_key(m) for m in src.messages()] == _expected(msgs)
    assert [p.kind for p in src.problems] == [P.DATA_CRC]
    # The good file passes the data CRC check.
    good = open_log(path)
    list(good.messages())
    assert good.problems == []



@pytest.mark.tor("TOR-DMG-001")
def test_a_chunk_whose_record_length_is_damaged_is_a_gap(tmp_path, chunked):
    """A Chunk record whose length field is damaged (its highest byte flipped: the record
    would run past the data section, so the index is not compared and the file is read
    through it) is damage, not evidence, though its body still passes its CRC: its messages
    are skipped, its span listed as chunk_corrupt and the log is partial."""
    path, msgs, chunks = chunked
    bad = chunks[4]
    src = open_log(_copy(path, tmp_path / "length.mcap", flip=[bad.chunk_start_offset + 8]))
    assert src.indexed
    keep = lambda t: not (bad.message_start_time <= t <= bad.message_end_time)  # noqa: E731
    assert [_key(m) for m in src.messages()] == _expected(msgs, keep=keep)
    spans = [(p.log_time, p.end_time) for p in src.problems if p.kind == P.CHUNK_CORRUPT]
    assert spans == [(bad.message_start_time, bad.message_end_time)]
    assert src.partial and src.gaps[0][0] == bad.message_start_time


@pytest.mark.tor("TOR-DMG-001")
@pytest.mark.parametrize("opcode", [0x02, 0x0F], ids=["footer", "data_end"])
def test_a_chunk_opcode_flipped_to_an_end_record_is_not_the_end(tmp_path, chunked, opcode):
    """A Chunk record whose opcode reads Footer or DataEnd with records after it is a damaged
    record, not the end of the data: read record by record, its messages are a gap (a
    corrupt_record problem) and every message after it is still read."""
    path, msgs, chunks = chunked
    bad = chunks[4]
    data = bytearray(path.read_bytes())
    data[bad.chunk_start_offset] = opcode
    (tmp_path / "end.mcap").write_bytes(bytes(data))
    src = open_log(tmp_path / "end.mcap")
    assert not src.indexed
    keep = lambda t: not (bad.message_start_time <= t <= bad.message_end_time)  # noqa: E731
    assert [_key(m) for m in src.messages()] == _expected(msgs, keep=keep)
    assert P.CORRUPT_RECORD in [p.kind for p in src.problems] and src.partial


def _float64_mcap(path: Path, index: object, **options: object) -> None:
    """Two Float64 topics (/a every 10 ms, /b every 30 ms) written by the mcap writer with
    ``index`` (an ``IndexType``) and ``options``."""
    from mcap.writer import Writer

    with open(path, "wb") as f:
        w = Writer(f, index_types=index, **options)
        w.start("ros2", "fretc-tests")
        sid = w.register_schema("std_msgs/msg/Float64", "ros2msg", b"float64 data")
        ids = {t: w.register_channel(t, "cdr", sid) for t in ("/a", "/b")}
        for i in range(120):
            for topic in ("/a",) if i % 3 else ("/a", "/b"):
                w.add_message(ids[topic], log_time=i * 10 * MS, publish_time=i * 10 * MS,
                              data=b"\x00\x01\x00\x00" + struct.pack("<d", float(i)))
        w.finish()


@pytest.mark.tor("TOR-DMG-001")
def test_a_data_section_crc_mismatch_read_without_an_index_makes_the_log_partial(tmp_path):
    """A file without a summary (read record by record, ending with its Footer) whose data
    section no longer matches its DataEnd CRC (a byte of its Header changed): every message
    is read, the data_crc problem is listed and the log is partial."""
    from mcap.writer import IndexType

    path = tmp_path / "plain.mcap"
    _float64_mcap(path, IndexType.NONE, use_statistics=False, use_summary_offsets=False,
                  repeat_channels=False, repeat_schemas=False, enable_data_crcs=True)
    good = open_log(path)
    assert len(list(good.messages())) == 160 and not good.indexed and not good.partial
    data = path.read_bytes().replace(b"fretc-tests", b"fretc-testz", 1)
    (tmp_path / "crc.mcap").write_bytes(data)
    src = open_log(tmp_path / "crc.mcap")
    assert len(list(src.messages())) == 160
    assert [p.kind for p in src.problems] == [P.DATA_CRC] and src.partial


@pytest.mark.tor("TOR-DMG-002")
def test_a_damaged_chunk_without_message_indexes_is_a_gap_of_every_topic(tmp_path):
    """A summary whose ChunkIndex records name no channel (written without message indexes)
    says nothing of a damaged chunk's topics: its gap may hold any topic (topics None),
    never none."""
    from mcap.writer import IndexType

    path = tmp_path / "chunk_index.mcap"
    _float64_mcap(path, IndexType.CHUNK, chunk_size=512)
    with open(path, "rb") as f:
        chunks = sorted(make_reader(f).get_summary().chunk_indexes,
                        key=lambda c: c.chunk_start_offset)
    assert len(chunks) > 3 and not chunks[2].message_index_offsets
    middle = chunks[2].chunk_start_offset + chunks[2].chunk_length // 2
    src = open_log(_copy(path, tmp_path / "damaged.mcap", flip=[middle, middle + 1]))
    assert src.indexed
    list(src.messages())
    assert len(src.gaps) == 1 and src.gaps[0].topics is None and src.partial


def test_corrupt_summary_falls_back_to_linear_read(tmp_path, chunked):
    path, msgs, _chunks = chunked
    size = path.stat().st_size
    src = open_log(_copy(path, tmp_path / "summary.mcap", flip=[size - 8 - 29 - 40]))
    assert not src.indexed
    assert [p.kind for p in src.problems] == [P.SUMMARY_CORRUPT]
    assert [_key(m) for m in src.messages()] == _expected(msgs)
    # damaged, so partial (never exit 0 on it), but no message lost: nothing is cut
    assert src.partial and not src.damage_cut and src.intact_end is None


def test_unknown_schema_or_encoding_is_an_error_for_that_topic_only(tmp_path):
    msgs = _series(30) + [("/odd", "std_msgs/msg/Float64", 5 * S + i * MS, float64(i)) for i in range(5)] \
        + [("/json", "std_msgs/msg/Float64", 6 * S + i * MS, float64(i)) for i in range(4)] \
        + [("/fb", "std_msgs/msg/Float64", 7 * S + i * MS, float64(i)) for i in range(3)]
    path = write_mcap(tmp_path / "schema.mcap", msgs,
                      schema_override={"/odd": ("protobuf", b"\x0a\x03abc")},
                      encoding_override={"/json": "json", "/fb": "flatbuffer"})
    src = open_log(path)
    got = list(src.messages())
    assert {m.topic for m in got} == {"/cmd", "/flag"}
    assert [_key(m) for m in got] == _expected([m for m in msgs if m[0] in ("/cmd", "/flag")])
    kinds = {(p.kind, p.topic) for p in src.problems}
    # json messages under a ros2msg schema: the schema does not go with the encoding;
    # flatbuffer: an encoding fretc does not read
    assert kinds == {(P.UNKNOWN_SCHEMA, "/odd"), (P.UNKNOWN_SCHEMA, "/json"),
                     (P.UNKNOWN_ENCODING, "/fb")}
    # the messages lost are counted, with the channel and first and last log time
    assert src.problem_counts[(P.UNKNOWN_SCHEMA, "/odd")] == 5
    assert src.problem_counts[(P.UNKNOWN_SCHEMA, "/json")] == 4
    assert src.problem_counts[(P.UNKNOWN_ENCODING, "/fb")] == 3
    odd = next(p for p in src.problems if p.topic == "/odd")
    assert (odd.log_time, odd.end_time) == (5 * S, 5 * S + 4 * MS)
    assert "5 messages on channel" in odd.detail
    odd = next(p for p in src.problems if p.topic == "/odd")
    assert odd.log_time == 5 * S and "protobuf" in odd.detail


def test_unparsable_schema_text_is_unknown_schema(tmp_path):
    msgs = [("/a", "std_msgs/msg/Float64", i, float64(i)) for i in range(3)]
    path = write_mcap(tmp_path / "bad.mcap", msgs, schema_override={"/a": ("ros2msg", b"float64 data\n!!! nonsense ???\n")})
    src = open_log(path)
    assert list(src.messages()) == []
    assert [(p.kind, p.topic) for p in src.problems] == [(P.UNKNOWN_SCHEMA, "/a")]


def test_undecodable_message_is_skipped(tmp_path):
    msgs = [("/scan", "sensor_msgs/msg/LaserScan", i * MS, scan([1.0, 2.0, 3.0], ns=i * MS)) for i in range(6)]
    path = write_mcap(tmp_path / "undec.mcap", msgs, raw_override={3: b"\x00\x01\x00\x00\x07"})
    src = open_log(path)
    got = list(src.messages())
    assert [m.log_time for m in got] == [0, 1 * MS, 2 * MS, 4 * MS, 5 * MS]
    assert [(p.kind, p.topic, p.log_time) for p in src.problems] == [(P.UNDECODABLE, "/scan", 3 * MS)]
    assert src.counts == {"/scan": 5}


def test_problems_are_capped_per_kind_and_topic(tmp_path):
    n = P.MAX_PROBLEMS_PER_KIND + 20
    msgs = [("/f", "std_msgs/msg/Float64", i * MS, float64(i)) for i in range(n)]
    path = write_mcap(tmp_path / "many.mcap", msgs, raw_override={i: b"\x00\x01" for i in range(n)})
    src = open_log(path)
    assert list(src.messages()) == []
    # messages not decoded: one problem per channel, counting them all
    assert len(src.problems) == 1
    assert src.problem_counts[(P.UNDECODABLE, "/f")] == n
    assert (src.problems[0].log_time, src.problems[0].end_time) == (0, (n - 1) * MS)
    log = P.ProblemLog()
    for i in range(n):
        log.add(P.DataProblem(P.OUT_OF_ORDER, "/f", i, "late"))
    assert len(log.problems) == P.MAX_PROBLEMS_PER_KIND
    assert log.counts[(P.OUT_OF_ORDER, "/f")] == n


def test_linear_topics_scan_and_start_end(tmp_path, chunked):
    path, msgs, chunks = chunked
    cut = _copy(path, tmp_path / "cut.mcap", size=chunks[5].chunk_start_offset + 100)
    src = open_log(cut)
    assert src.topics() == {"/cmd": "geometry_msgs/msg/Twist", "/flag": "std_msgs/msg/Bool"}
    assert src.start_time == msgs[0][2]


# ------------------------------------------------------------------------------------------------
# Bags
# ------------------------------------------------------------------------------------------------


def test_rosbag2_folder(tmp_path):
    bag = tmp_path / "run"
    with Rosbag2Writer(bag, version=9) as w:
        c1 = w.add_connection("/cmd_vel", "geometry_msgs/msg/TwistStamped", typestore=ROS2)
        c2 = w.add_connection("/stop", "std_msgs/msg/Bool", typestore=ROS2)
        for i in range(10):
            t = 1 * S + i * 50 * MS
            w.write(c1, t, ROS2.serialize_cdr(twist_stamped(t - MS, x=0.1 * i), "geometry_msgs/msg/TwistStamped"))
            if i % 2:
                w.write(c2, t + MS, ROS2.serialize_cdr(boolean(i > 5), "std_msgs/msg/Bool"))
    src = open_log(bag)
    assert src.kind == "rosbag2"
    assert src.topics() == {"/cmd_vel": "geometry_msgs/msg/TwistStamped", "/stop": "std_msgs/msg/Bool"}
    got = list(src.messages())
    assert src.counts == {"/cmd_vel": 10, "/stop": 5}
    cmd = [m for m in got if m.topic == "/cmd_vel"]
    assert [m.data.twist.linear.x for m in cmd] == pytest.approx([0.1 * i for i in range(10)])
    assert [m.header_stamp for m in cmd] == [1 * S + i * 50 * MS - MS for i in range(10)]
    assert [m.data.data for m in got if m.topic == "/stop"] == [False, False, False, True, True]
    assert [m.log_time for m in got] == sorted(m.log_time for m in got)


def test_rosbag2_without_definitions_reads_standard_types_and_names_the_others(tmp_path):
    bag = tmp_path / "old"
    with Rosbag2Writer(bag, version=8) as w:
        c = w.add_connection("/stop", "std_msgs/msg/Bool", msgdef="", rihs01="RIHS01_unknown")
        d = w.add_connection("/mine", "my_msgs/msg/Bool", msgdef="", rihs01="RIHS01_unknown")
        for i in range(3):
            w.write(c, i * MS, ROS2.serialize_cdr(boolean(i == 1), "std_msgs/msg/Bool"))
            w.write(d, i * MS, ROS2.serialize_cdr(boolean(i == 1), "std_msgs/msg/Bool"))
    # a standard type the bag does not define: ROS 2 Humble's definition (logs.msg_path)
    src = open_log(bag)
    assert [m.data.data for m in src.messages({"/stop"})] == [False, True, False]
    assert src.problems == []
    # a team's own type: an unknown_schema problem naming --msg-path
    assert list(src.messages({"/mine"})) == []
    assert [(p.kind, p.topic, p.log_time) for p in src.problems] == [(P.UNKNOWN_SCHEMA, "/mine", 0)]
    assert "--msg-path" in src.problems[0].detail
    src = open_log(bag, fallback_typestore=Stores.EMPTY)  # an explicit store is used alone
    assert list(src.messages({"/stop"})) == []


@needs_shared
def test_truncated_ros1_bag_is_read_up_to_the_cut(tmp_path):
    # the index of a ROS 1 bag is at its end: a cut bag is read record by record
    cut = tmp_path / "cut.bag"
    cut.write_bytes(STAGE_BAG.read_bytes()[:200_000])
    src = open_log(cut)
    got = [(m.topic, m.log_time) for m in src.messages()]
    full = [(m.topic, m.log_time) for m in open_log(STAGE_BAG).messages()]
    assert 0 < len(got) < len(full) and got == full[:len(got)]
    assert src.partial and src.damage_cut and src.damage_time == got[-1][1]
    assert [p.kind for p in src.problems] == [P.TRUNCATED]
    assert "without the bag index" in src.problems[0].detail


@needs_shared
def test_ros1_bag_without_its_index_is_read_completely(tmp_path):
    data = STAGE_BAG.read_bytes()
    header = data[13 + 4: 13 + 4 + struct.unpack_from("<I", data, 13)[0]]
    index_pos = struct.unpack_from("<Q", header, header.index(b"index_pos=") + 10)[0]
    cut = tmp_path / "noindex.bag"
    cut.write_bytes(data[:index_pos])
    src = open_log(cut)
    got = [(m.topic, m.log_time) for m in src.messages()]
    assert got == [(m.topic, m.log_time) for m in open_log(STAGE_BAG).messages()]
    assert src.partial and not src.damage_cut
    assert [p.kind for p in src.problems] == [P.SUMMARY_CORRUPT]


def test_open_log_errors(tmp_path):
    with pytest.raises(LogError, match="no such file"):
        open_log(tmp_path / "nope.mcap")
    (tmp_path / "x.txt").write_text("hi")
    with pytest.raises(LogError, match="unknown log kind"):
        open_log(tmp_path / "x.txt")
    (tmp_path / "folder").mkdir()
    with pytest.raises(LogError, match="not a rosbag2"):
        open_log(tmp_path / "folder")
    (tmp_path / "fake.mcap").write_bytes(b"not an mcap at all")
    with pytest.raises(LogError, match=r"fake\.mcap: not an MCAP file"):
        open_log(tmp_path / "fake.mcap")


# ------------------------------------------------------------------------------------------------
# CSV
# ------------------------------------------------------------------------------------------------


def _csv(tmp_path, text, name="t.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_csv_types_times_and_messages(tmp_path):
    p = _csv(tmp_path, "# a FRET trace\ntime,too_close,stopped,speed\n0.0,false,1,0.5\n\n0.1,TRUE,0,1\n0.25,0,1,-2e-1\n")
    src = open_log(p)
    assert src.kind == "csv" and src.columns == ["too_close", "stopped", "speed"]
    assert src.types == {"too_close": "bool", "stopped": "bool", "speed": "float"}
    rows = list(src.rows())
    assert [r.line for r in rows] == [3, 5, 6]
    assert [r.time for r in rows] == [0, 100_000_000, 250_000_000]
    assert rows[1].values == {"too_close": True, "stopped": False, "speed": 1.0}
    assert type(rows[0].values["stopped"]) is bool and type(rows[0].values["speed"]) is float
    msgs = list(src.messages())
    assert src.topics() == {CSV_TOPIC: "fretc/msg/CsvRow"}
    assert [m.topic for m in msgs] == [CSV_TOPIC] * 3
    assert msgs[2].data.speed == -0.2 and msgs[2].log_time == 250_000_000


def test_csv_without_time_column_uses_period(tmp_path):
    src = open_log(_csv(tmp_path, "a,b\n1,2\n0,3\n"), csv_period_ns=10 * MS)
    assert [m.log_time for m in src.messages()] == [0, 10 * MS]
    src = open_log(_csv(tmp_path, "a,b\n1,2\n0,3\n", "u.csv"))
    assert [m.log_time for m in src.messages()] == [0, S]


@pytest.mark.parametrize("text, where, what", [
    ("a,b\n1,0\n1\n", ":3", "expected 2 cells"),
    ("a,b\n1,0\n1,x\n", ":3 (column 'b')", "cannot read 'x'"),
    ("a,b\n1,0\n1,\n", ":3 (column 'b')", "empty cell"),
    ("a,b\ntrue,0\n0.5,0\n", ":3 (column 'a')", "mixes true/false"),
    # the mixing cell's kind already known from another column (it was an internal error)
    ("a,b\n0.5,true\ntrue,0.5\n", ":3 (column 'a')", "mixes true/false"),
    ("time,a\n0.0,1\n0.2,1\n0.1,0\n", ":4 (column 'time')", "goes backwards"),
    ("time,a\n0.0,1\nsoon,1\n", ":3 (column 'time')", "not a number of seconds"),
    ("a,a\n1,1\n", ":1 (column 'a')", "appears twice"),
    ("a,2b\n1,1\n", ":1 (column '2b')", "not an identifier"),
    ("# only a comment\n", ":1", "empty file"),
])
def test_csv_bad_input_names_file_line(tmp_path, text, where, what):
    p = _csv(tmp_path, text)
    with pytest.raises(CsvError) as err:
        open_log(p)
    assert str(err.value).startswith(f"{p}{where}: ")
    assert what in str(err.value)


def test_csv_nan_and_inf_cells(tmp_path):
    src = open_log(_csv(tmp_path, "x\nnan\ninf\n-inf\n1\n"))
    vals = [r.values["x"] for r in src.rows()]
    assert np.isnan(vals[0]) and vals[1:] == [np.inf, -np.inf, 1.0]


def test_a_time_past_a_float_in_a_row_of_another_clock_is_an_error_not_a_crash(tmp_path):
    """A sampled trace's row of another clock at 1e400 s, then one going back: the read of
    clock 1 says where time goes backwards (the previous row's time was printed as a float:
    an internal OverflowError)."""
    from fretc.common.problems import CsvError

    p = _csv(tmp_path, "# fretc sampled trace of x\n# fretc clock 1: A\n# fretc clock 2: B\n"
             "time,tick,a,b\n0,1,1,\n1e400,2,,1\n0.1,1,0,\n", "s.csv")
    with pytest.raises(CsvError) as err:
        open_log(str(p))  # (a trace of several clocks read whole)
    assert str(err.value).startswith(f"{p}:7 (column 'time'): ") and "goes backwards" in str(err.value)


@given(st.text(max_size=20))
def test_an_escaped_id_reads_back_and_a_malformed_escape_stands_for_itself(rid):
    """escape_id/unescape_id round trip; ``\\x`` followed by anything but two lowercase
    hex digits (a tab, a sign, upper case: Python's int() took ``\\x\\t5`` for byte 5) is
    text, as the C monitors' runner reads it."""
    from fretc.logs.csv.source import escape_id, unescape_id

    assert unescape_id(escape_id(rid)) == rid.encode("utf-8", "replace").decode("utf-8", "replace")
    for bad in ("\\x\t5", "\\x+5", "\\x5", "\\xAB", "\\x 5"):
        assert unescape_id(f"a{bad}z") == f"a{bad}z"
