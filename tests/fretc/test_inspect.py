"""``fretc inspect``: topics, types, counts, rates, span, field paths with types,
array lengths and numeric min/max; a binding written from its output audits."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_inspect_lists_fields_and_a_binding_from_it_audits(tmp_path, shared):
    log, logs = ROOT / "traces" / "sif_disabled.mcap", shared / "data" / "logs"
    res = CliRunner().invoke(main, ["inspect", str(log), str(logs / "stage_mapping1.bag"),
                                    str(logs / "cmd_vel_scaled.mcap"), "--json"])
    assert res.exit_code == 0, res.output
    docs = json.loads(res.output)
    assert [Path(d["log"]).name for d in docs] == ["sif_disabled.mcap", "stage_mapping1.bag",
                                                   "cmd_vel_scaled.mcap"]
    topics = {t["topic"]: t for t in docs[0]["topics"]}
    scan = topics["/scan"]
    assert scan["type"] == "sensor_msgs/msg/LaserScan" and scan["messages"] == 158
    assert abs(scan["rate_hz"] - 10) < 0.1
    assert scan["fields"]["/scan.ranges"]["lengths"] == [720, 720]
    assert scan["fields"]["/scan.ranges"]["type"] == "float32[]"
    clearance = topics["/ground_truth/clearance"]["fields"]["/ground_truth/clearance.data"]
    assert clearance["type"] == "float64" and clearance["min"] <= 0 < clearance["max"]
    assert "true" in topics["/gwendolen_control"]["fields"]["/gwendolen_control.data"]
    tf = topics["/tf"]["fields"]
    assert "/tf.transforms[i].transform.translation.x" in tf
    odom = {t["topic"]: t for t in docs[1]["topics"]}["/base_pose_ground_truth"]["fields"]
    assert "/base_pose_ground_truth.twist.twist.linear.y" in odom
    # a binding written from the listing audits (R5 is violated at contact, 15.2 s)
    (tmp_path / "c.fret").write_text("C1: the scout_mini shall always satisfy clearance > 0\n")
    (tmp_path / "c.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[variables]\nclearance = "/ground_truth/clearance.data"\n')
    res = CliRunner().invoke(main, ["audit", "--no-progress", "-r", str(tmp_path / "c.fret"),
                                    str(log)])
    assert res.exit_code == 1 and "15.200 s" in res.output, res.output


def test_inspect_text_output_and_bad_file(tmp_path, shared):
    res = CliRunner().invoke(main, ["inspect", str(shared / "data/logs/cmd_vel_scaled.mcap")])
    assert res.exit_code == 0
    assert "/scaled/cmd_vel.twist.linear.x  float64  min" in res.output
    (tmp_path / "x.mcap").write_bytes(b"not a log")
    res = CliRunner().invoke(main, ["inspect", str(tmp_path / "x.mcap")])
    assert res.exit_code == 2 and "not an MCAP" in res.output
