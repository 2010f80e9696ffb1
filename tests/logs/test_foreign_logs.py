"""Every robot and flight log of ``../shared/data/foreign_logs`` (real logs from public
repositories, their sources in its SOURCES.md) is read by ``fretc inspect`` without an
internal error, every topic read or named with its reason; an old ROS 1 bag with a
non-standard index is read record by record (its 2010 ``roslib/Header`` definitions
included); a bag of format 1.2 is refused by its format."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from _shared import SHARED, params  # noqa: E402
from fretc.cli import main  # noqa: E402
from fretc.logs import open_log  # noqa: E402

FOREIGN = SHARED / "data" / "foreign_logs"


def _logs():
    for p in sorted(FOREIGN.rglob("*")):
        if p.suffix in (".mcap", ".bag", ".ulg"):
            yield pytest.param(p, id=f"{p.parent.name}/{p.name}")


@pytest.mark.tor("TOR-LOG-001")
@pytest.mark.parametrize("log", params(_logs))
def test_inspect_reads_every_foreign_log(log):
    res = CliRunner().invoke(main, ["inspect", str(log)])
    assert res.exit_code == 0, res.output
    assert "internal error" not in res.output
    assert "(schema unknown)" not in res.output
    src = open_log(log)
    counts = {}
    for m in src.messages():
        counts[m.topic] = counts.get(m.topic, 0) + 1
    for topic in src.topics():  # every topic read, or its problem named
        named = any(p.topic == topic for p in src.problems)
        # a channel nothing was recorded on (rosbag2's /events/write_split) has nothing to read
        empty = getattr(src, "records", None) is not None and not src.records.get(topic, 0)
        assert counts.get(topic) or named or src.partial or empty, topic


@pytest.mark.tor("TOR-LOG-001")
@pytest.mark.parametrize("log", params(lambda: [FOREIGN / "ccny_lsm_crash" / "demo.bag"]))
def test_an_old_bag_with_a_non_standard_index_is_read_record_by_record(log):
    """Its span is that of the messages read without the index (it was unknown), and the
    problem names the reader's error even when the error has no message of its own."""
    src = open_log(log)
    assert (src.start_time, src.end_time) == (1282836371069930698, 1282836398700597077)
    scans = [m for m in src.messages({"/scan"})]
    assert len(scans) == 278 and len(scans[0].data.ranges) > 100
    assert (scans[0].log_time, scans[-1].log_time) == (src.start_time, src.end_time)
    assert scans[0].data.header.frame_id  # the 2010 roslib/Header, read as std_msgs/Header
    kinds = {p.kind for p in src.problems}
    assert "truncated" in kinds and src.partial
    (cut,) = [p for p in src.problems if p.kind == "truncated"]
    assert cut.detail.endswith("(rosbags' reader: AssertionError, without a message)")


@pytest.mark.tor("TOR-LOG-001")
def test_a_bag_of_format_1_2_is_refused_by_its_format(tmp_path):
    old = tmp_path / "old.bag"
    old.write_bytes(b"#ROSBAG V1.2\n" + bytes(range(256)) * 8)
    res = CliRunner().invoke(main, ["inspect", str(old)])
    assert res.exit_code == 2
    assert "format 1.2 is not supported" in res.output
