"""The layers of logs/ on their own: the reordering queue, MCAP chunk parsing
against the mcap library's, the summary and truncation readers, bag connection types."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader
from mcap.records import Chunk, Message as McapMessage
from mcap.stream_reader import breakup_chunk
from mcap.writer import CompressionType
from rosbags.interfaces import MessageDefinition, MessageDefinitionFormat

from fretc.common import problems as P
from fretc.logs.ros.bags import connection_typestore
from fretc.logs.decoding import UnsupportedSchema
from fretc.logs.mcap.integrity import check_data_section, cut_record, read_summary
from fretc.logs.mcap.records import RECORD_HEAD, chunk_messages, parse_record
from fretc.logs.reorder import REORDER_WINDOW_NS, ReorderQueue

from _logs import ROS2, S, twist, write_mcap

TRACES = sorted((Path(__file__).resolve().parents[2] / "traces").glob("*.mcap"))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 20 * S), st.integers(-2 * S, 2 * S)), max_size=60))
def test_reorder_queue_releases_in_log_time_order_within_the_window(items):
    """Messages pushed with a lag below the window come out sorted; with a watermark that
    follows the pushes, an item is late exactly when it is older than one delivered."""
    q = ReorderQueue()
    out: list[tuple[int, int]] = []
    late: list[int] = []

    def drain(watermark):
        for log_time, item in q.due(watermark):
            if q.late_by(log_time):
                late.append(item)
                continue
            q.delivered(log_time)
            out.append((log_time, item))

    watermark = None
    for pos, (t, jitter) in enumerate(items):
        t = max(0, t + jitter)
        watermark = t if watermark is None else max(watermark, t)
        drain(watermark)
        q.push(t, pos, pos)
    drain(None)
    assert len(q) == 0
    assert [t for t, _ in out] == sorted(t for t, _ in out)
    assert sorted([i for _, i in out] + late) == list(range(len(items)))
    times = [max(0, t + j) for t, j in items]
    # an item is late only if some earlier-pushed item is newer by more than the window
    for i in late:
        assert any(times[k] - times[i] > REORDER_WINDOW_NS for k in range(i))


def _chunks(path: Path) -> list[Chunk]:
    """The Chunk records of ``path`` (mcap's StreamReader opens chunks itself)."""
    data = path.read_bytes()
    out, pos = [], 8
    while pos + 9 <= len(data):
        opcode, length = RECORD_HEAD.unpack_from(data, pos)
        if opcode == 0x06:
            out.append(parse_record(opcode, data[pos + 9:pos + 9 + length]))
        pos += 9 + length
    return out


@pytest.mark.parametrize("path", TRACES[:3], ids=lambda p: p.name)
def test_chunk_messages_equal_the_mcap_librarys_breakup(path):
    """Our chunk parser (wanted channels only) gives the Message records mcap's
    ``breakup_chunk`` gives, in the same order, for every chunk and any wanted set."""
    with open(path, "rb") as f:
        channels = make_reader(f).get_summary().channels
    chunks = _chunks(path)
    assert chunks
    for chunk in chunks:
        theirs = [r for r in breakup_chunk(chunk, validate_crc=True) if isinstance(r, McapMessage)]
        assert chunk_messages(chunk, set(channels), channels) == theirs
        some = set(sorted(channels)[::2])
        assert chunk_messages(chunk, some, channels) == [r for r in theirs if r.channel_id in some]
        # a channel the summary does not know is returned for the caller to report
        assert chunk_messages(chunk, set(), {}) == theirs


def test_read_summary_reads_the_index_and_reports_a_damaged_summary(tmp_path):
    path = write_mcap(tmp_path / "a.mcap", [("/cmd_vel", "geometry_msgs/msg/Twist", i * S, twist(i))
                                            for i in range(5)])
    data = path.read_bytes()
    found = read_summary(str(path), len(data))
    assert found.profile == "ros2" and found.problem is None
    assert found.index is not None and [c.topic for c in found.index.channels.values()] == ["/cmd_vel"]
    assert check_data_section(str(path), found.index) is None
    # one flipped bit in the summary section: the summary CRC says so, no index
    bad = bytearray(data)
    bad[len(data) - 60] ^= 0x10
    (tmp_path / "b.mcap").write_bytes(bytes(bad))
    found = read_summary(str(tmp_path / "b.mcap"), len(bad))
    assert found.index is None and found.problem.kind == P.SUMMARY_CORRUPT
    # one flipped bit in the data section: the index is read, the data CRC differs
    bad = bytearray(data)
    bad[40] ^= 0x01
    (tmp_path / "c.mcap").write_bytes(bytes(bad))
    found = read_summary(str(tmp_path / "c.mcap"), len(bad))
    assert found.index is not None
    assert check_data_section(str(tmp_path / "c.mcap"), found.index).kind == P.DATA_CRC


def test_cut_record_recovers_the_complete_messages_of_a_cut_chunk(tmp_path):
    msgs = [("/cmd_vel", "geometry_msgs/msg/Twist", i * S, twist(i)) for i in range(40)]
    path = write_mcap(tmp_path / "a.mcap", msgs, compression=CompressionType.NONE)
    data = path.read_bytes()
    full = [r for c in _chunks(path) for r in breakup_chunk(c) if isinstance(r, McapMessage)]
    pos = 8 + 9 + RECORD_HEAD.unpack_from(data, 8)[1]  # the record after the Header
    assert data[pos] == 0x06  # a Chunk
    cut = pos + 9 + RECORD_HEAD.unpack_from(data, pos)[1] * 2 // 3  # inside the chunk
    (tmp_path / "cut.mcap").write_bytes(data[:cut])
    with open(tmp_path / "cut.mcap", "rb") as f:
        f.seek(pos)
        head = f.read(9)
        what, got = cut_record(f, pos, cut, head)
    got_msgs = [r for r in got if isinstance(r, McapMessage)]
    assert 0 < len(got_msgs) < len(full)
    assert got_msgs == full[:len(got_msgs)]
    assert what.startswith(f"file ends at byte {cut} inside the record starting at byte {pos}")
    assert f"{len(got_msgs)} complete messages recovered" in what


def test_connection_typestore_uses_the_bag_definition_or_the_fallback():
    text = ROS2.generate_msgdef("geometry_msgs/msg/Twist", ros_version=2)[0]
    conn = SimpleNamespace(msgtype="geometry_msgs/msg/Twist",
                           msgdef=MessageDefinition(MessageDefinitionFormat.MSG, text))
    store, typename = connection_typestore("rosbag2", conn, None)
    assert typename == "geometry_msgs/msg/Twist" and store is not ROS2
    assert store.get_msgdef(typename).fields == ROS2.get_msgdef(typename).fields
    bare = SimpleNamespace(msgtype="geometry_msgs/msg/Twist",
                           msgdef=MessageDefinition(MessageDefinitionFormat.NONE, ""))
    assert connection_typestore("rosbag2", bare, ROS2) == (ROS2, "geometry_msgs/msg/Twist")
    with pytest.raises(UnsupportedSchema, match="stores no definition"):
        connection_typestore("rosbag2", bare, None)


@pytest.mark.tor("TOR-LOG-001")
def test_a_service_event_with_a_definition_of_its_own_is_built_from_it():
    """A rosbag2 service event connection (``pkg/srv/Name_Event``) that carries its own
    definition is built from it, not from the one the bag stores for the service (which
    differs here: the request without ``b``); one without a definition is built from the
    service's."""
    from fretc.logs.decoding import service_event_text

    name = "example/srv/Add_Event"
    own = service_event_text(name, "int64 a\nint64 b\n---\nint64 sum\n")
    stored = {"example/srv/Add": ("ros2msg", "int64 a\n---\nint64 sum\n")}

    def request_fields(msgdef: MessageDefinition) -> list[str]:
        conn = SimpleNamespace(msgtype=name, msgdef=msgdef)
        store, _typename = connection_typestore("rosbag2", conn, None, stored)
        req = next(t for t in store.fielddefs if t.endswith("/Add_Request"))
        return [f[0] for f in store.get_msgdef(req).fields]

    assert request_fields(MessageDefinition(MessageDefinitionFormat.MSG, own)) == ["a", "b"]
    assert request_fields(MessageDefinition(MessageDefinitionFormat.NONE, "")) == ["a"]
