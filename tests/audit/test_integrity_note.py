"""What the audit says of a log whose bytes it cannot check (the safety manual's limit: a
changed byte of a log without checksums reads as data): an MCAP file written with its CRCs
is checked (``integrity`` null in the JSON, no line); the same file written without them,
and a CSV trace, say so in the JSON and in the terminal's summary, whatever the verdict."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner
from mcap.writer import Writer

from fretc.cli import main

from _logs import S, float64

REQ = "R: the sw shall always satisfy x < 5\n"
BIND = '[tick]\nperiod = "100 ms"\n[variables]\nx = "/x.data"\n'


def _mcap(path: Path, crcs: bool, values: list[float]) -> Path:
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=256, enable_crcs=crcs)
        w.start(profile="ros2", library="test")
        schema = w.register_schema("std_msgs/msg/Float64", "ros2msg", store.generate_msgdef(
            "std_msgs/msg/Float64", ros_version=2)[0].encode())
        channel = w.register_channel("/x", "cdr", schema)
        for k, v in enumerate(values):
            w.add_message(channel, log_time=S + k * S // 10, publish_time=S + k * S // 10,
                          data=bytes(store.serialize_cdr(float64(v), "std_msgs/msg/Float64")))
        w.finish()
    return path


def _audit(tmp_path: Path, log: Path) -> tuple[int, dict, str]:
    (tmp_path / "r.fret").write_text(REQ)
    (tmp_path / "r.bindings.toml").write_text(BIND)
    out = tmp_path / f"{log.stem}.json"
    got = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"), str(log),
                                    "--json", str(out), "--no-progress"])
    return got.exit_code, json.loads(out.read_text()), " ".join(got.output.split())


def test_an_mcap_file_with_crcs_is_checked_one_without_says_so(tmp_path):
    code, doc, text = _audit(tmp_path, _mcap(tmp_path / "crc.mcap", True, [1.0] * 30))
    assert code == 0 and doc["logs"][0]["integrity"] is None
    assert "integrity not checked" not in text
    code, doc, text = _audit(tmp_path, _mcap(tmp_path / "plain.mcap", False, [1.0] * 30))
    note = doc["logs"][0]["integrity"]
    assert code == 0 and "chunks carry no CRC" in note
    assert "integrity not checked in 1 of 1 log (" in text


def test_a_violation_in_a_log_without_checksums_comes_with_the_note(tmp_path):
    """A value changed in a file without CRCs is a confident violation: the audit cannot
    tell it from data, and says that it could not check."""
    code, doc, text = _audit(tmp_path, _mcap(tmp_path / "flip.mcap", False,
                                             [1.0] * 10 + [9.0] + [1.0] * 10))
    assert code == 1 and doc["logs"][0]["verdicts"][0]["verdict"] == "violated"
    assert doc["logs"][0]["integrity"] and "integrity not checked" in text


def test_a_csv_trace_says_it_carries_no_checksum(tmp_path):
    (tmp_path / "t.csv").write_text("x\n1\n2\n")
    (tmp_path / "r.fret").write_text(REQ)
    out = tmp_path / "a.json"
    got = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"),
                                    str(tmp_path / "t.csv"), "--json", str(out),
                                    "--no-progress"])
    assert got.exit_code == 0
    assert json.loads(out.read_text())["logs"][0]["integrity"].startswith(
        "a CSV trace carries no checksum")
