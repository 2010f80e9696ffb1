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
    assert "/tf.transforms[:].transform.translation.x" in tf
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


def test_every_path_inspect_prints_binds_as_printed(tmp_path):
    """quoted topics (``"ORB-SLAM".pose...``), ``[:]`` for items; each printed
    path parses as a binding field and resolves in the log's schema; text fields list their
    values, enum fields their constants, numbers are in plain notation."""
    import _robot_logs as rl
    from fretc.signals.bindings.expression import ExprLocation, Field
    from fretc.signals.bindings.parse import parse_expression
    from fretc.logs import open_log
    from fretc.logs.schema import log_schemas
    log = rl.write_robot_log(tmp_path)
    res = CliRunner().invoke(main, ["inspect", str(log.path), "--json"])
    assert res.exit_code == 0, res.output
    topics = {t["topic"]: t for t in json.loads(res.output)[0]["topics"]}
    schemas = log_schemas(open_log(str(log.path)))
    n = 0
    for topic, t in topics.items():
        for path in t["fields"]:
            node, _ = parse_expression(path, ExprLocation("inspect", None, None, None))
            assert isinstance(node, Field) and node.topic == topic, path
            schemas[topic].resolve(node.path)  # raises when it does not bind
            n += 1
    assert n > 100
    assert '"ORB-SLAM".pose.position.x' in topics["ORB-SLAM"]["fields"]
    assert '"groundtruth".pose.position.x' in topics["groundtruth"]["fields"]
    assert topics["/mode"]["fields"]["/mode.data"]["values"] == ["charging", "navigating"]
    status = topics["/battery"]["fields"]["/battery.power_supply_status"]["constants"]
    assert status["POWER_SUPPLY_STATUS_CHARGING"] == 1 and len(status) == 5
    level = topics["/diagnostics"]["fields"]["/diagnostics.status[:].level"]["constants"]
    assert level == {"OK": 0, "WARN": 1, "ERROR": 2, "STALE": 3}
    assert topics["/joint_states"]["fields"]["/joint_states.name"]["values"] == list(rl.JOINTS)
    text = CliRunner().invoke(main, ["inspect", str(log.path)]).output
    assert "/battery.header.stamp.sec  int32  min 1700000000 max 1700000009" in text
    assert "e+" not in text
    assert '/mode.data  string  values "charging", "navigating"' in text


def test_plain_numbers_keep_the_digits_that_tell_them_apart():
    from fretc.cli.inspect import plain
    assert plain(1.000158) == "1.000158" and plain(1432240000.25) == "1432240000.25"
    assert plain(1.5e-7) == "0.00000015" and plain(-2.0) == "-2"


def test_a_missing_array_field_counts_as_empty():
    # a message without a field its schema declares (getattr's None) is an empty array for
    # the field's statistics: arrays of messages and of bools raised TypeError before
    from types import SimpleNamespace

    from fretc.cli.inspect import _Stat, _visit

    msgs, flags = _Stat("Item[]"), _Stat("bool[]")
    plan = [("items", "array", "message", msgs, []), ("flags", "array", "bool", flags, None)]
    _visit(plan, SimpleNamespace())
    assert msgs.lengths == {0} and flags.lengths == {0}
    assert flags.true == flags.false == 0
    _visit(plan, SimpleNamespace(items=[SimpleNamespace()], flags=[True, False, True]))
    assert msgs.lengths == {0, 1} and (flags.true, flags.false) == (2, 1)


def _json_log(path: Path, schema: dict | None, messages: list[dict]) -> None:
    from mcap.writer import Writer

    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        sid = (w.register_schema("Thing", "jsonschema", json.dumps(schema).encode())
               if schema is not None else 0)
        cid = w.register_channel("/thing", "json", sid)
        for i, m in enumerate(messages):
            w.add_message(cid, log_time=i * 100_000_000, publish_time=i * 100_000_000,
                          data=json.dumps(m).encode())
        w.finish()


def test_json_topics_without_a_field_list_get_their_fields_from_the_messages(tmp_path):
    msgs = [{"x": i, "ok": i % 2 == 0, "mode": "auto" if i < 3 else "manual",
             "nested": {"y": 2.5 * i}, "arr": [i, -i], "tracks": [{"d": 1.0 + i}],
             "maybe": [] if i == 0 else [1.5], "bag": [1, "a"] if i == 4 else [1, 2]}
            for i in range(5)]
    for schema in (None, {"type": "object"}):
        log = tmp_path / f"j{schema is not None}.mcap"
        _json_log(log, schema, msgs)
        res = CliRunner().invoke(main, ["inspect", str(log), "--json"])
        assert res.exit_code == 0, res.output
        (topic,) = json.loads(res.output)[0]["topics"]
        assert topic["fields_from_messages"] is True
        f = topic["fields"]
        assert {p: s["type"] for p, s in f.items()} == {
            "/thing.x": "number", "/thing.ok": "boolean", "/thing.mode": "string",
            "/thing.nested.y": "number", "/thing.arr": "number[]",
            "/thing.tracks": "object[]", "/thing.tracks[:].d": "number",
            "/thing.maybe": "number[]", "/thing.bag": "mixed[]"}
        assert (f["/thing.x"]["min"], f["/thing.x"]["max"]) == (0, 4)
        assert (f["/thing.arr"]["min"], f["/thing.arr"]["max"]) == (-4, 4)
        assert (f["/thing.ok"]["true"], f["/thing.ok"]["false"]) == (3, 2)
        assert f["/thing.mode"]["values"] == ["auto", "manual"]
        assert f["/thing.maybe"]["lengths"] == [0, 1]
        # the paths listed bind: the audit reads the maxima inspect printed
        for path, hi in (("/thing.nested.y", 10.0), ("/thing.x", 4)):
            (tmp_path / "r.fret").write_text(f"R: the thing shall always satisfy v < {hi}\n")
            (tmp_path / "r.bindings.toml").write_text(
                f'[tick]\nperiod = "100 ms"\n[variables]\nv = "{path}"\n')
            got = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"), "-b",
                                            str(tmp_path / "r.bindings.toml"), str(log),
                                            "--no-progress", "--json", "-"])
            (v,) = json.loads(got.stdout)["logs"][0]["verdicts"]
            assert v["verdict"] == "violated" and v["first_violation"]["tick"] == 4, v
        text = CliRunner().invoke(main, ["inspect", str(log)])
        assert "fields from the messages" in text.output
