"""``fretc audit`` on the command line: the summary, --json, --junit, -j, inline bindings and
the exit codes (0 all satisfied, 1 a violation, 2 usage or input errors)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main

from test_audit import SYN_BINDINGS, SYN_FRET, TRACES, _readme_expectations, _synthetic

ROOT = Path(__file__).resolve().parents[2]


def run(*args):
    res = CliRunner().invoke(main, ["audit", "--no-progress", *map(str, args)])
    if res.exception and not isinstance(res.exception, SystemExit):
        raise res.exception
    return res


def test_main_job_on_the_shipped_traces(tmp_path):
    if not (TRACES / "README.md").exists():
        pytest.skip("traces/ not recorded")
    out_json, out_xml = tmp_path / "a.json", tmp_path / "a.xml"
    res = run("--requirements", ROOT / "requirements", TRACES, "--json", out_json,
              "--junit", out_xml, "-j", "2")
    assert res.exit_code == 1, res.output
    assert "VIOLATED" in res.output and "sif_disabled" in res.output
    doc = json.loads(out_json.read_text())
    assert doc["schema"] == "fretc-audit/1"
    assert [r["id"] for r in doc["requirements"]] == ["R1", "R2", "R3", "R4", "R5", "R6"]
    assert doc["bindings"]["tick"] == {"period_ns": 100_000_000}
    logs = {Path(l["log"]).name: l for l in doc["logs"]}
    r1 = next(v for v in logs["sif_disabled.mcap"]["verdicts"] if v["requirement"] == "R1")
    assert r1["verdict"] == "violated"
    assert r1["first_violation"]["trigger"]["time_s"] == pytest.approx(8.8)
    assert r1["first_violation"]["scope_interval"]["start"]["tick"] == 0
    assert r1["values"]["too_close"] and r1["sources"]["/scan"]
    assert r1["warmup_ticks"] == 1 and r1["waiting_for"] == ["/cmd_vel_filtered"]
    n_violated = sum(v["verdict"] == "violated" for l in doc["logs"] for v in l["verdicts"])
    readme = _readme_expectations()
    expected_violated = sum(v == "violated" for exp in readme.values() for v, _ in exp.values())
    assert doc["summary"]["violated"] == n_violated == expected_violated
    assert doc["summary"]["exit_code"] == 1
    suites = ET.parse(out_xml).getroot()
    assert int(suites.get("tests")) == 6 * len(doc["logs"]) and len(doc["logs"]) >= 8
    assert int(suites.get("failures")) == n_violated and suites.get("errors") == "0"
    case = suites.find(".//testsuite[@name='traces/sif_disabled.mcap']/testcase[@name='R1']")
    if case is None:  # run from another working directory: absolute names
        case = next(s for s in suites if s.get("name").endswith("sif_disabled.mcap")
                    ).find("testcase[@name='R1']")
    assert case.find("failure") is not None
    assert "8.800 s" in case.find("failure").get("message")
    # deterministic: the same audit gives the same JSON
    run("--requirements", ROOT / "requirements", TRACES, "--json", tmp_path / "b.json")
    assert (tmp_path / "b.json").read_text() == out_json.read_text()


@pytest.mark.tor("TOR-VER-006")
def test_exit_0_when_everything_holds_and_json_to_stdout(tmp_path):
    log = _synthetic(tmp_path)
    with open(tmp_path / "syn.fret", "a") as f:  # free-form: kept, not audited, no error
        f.write('F1: "The operator is told when the robot stops."\n')
    res = run("-r", tmp_path / "syn.fret", log, "--json", "-")
    assert res.exit_code == 0, res.output
    assert "free-form, not audited: F1" in res.stderr
    doc = json.loads(res.stdout[res.stdout.index("{"):])
    assert doc["summary"]["satisfied"] == 3 and doc["summary"]["exit_code"] == 0


def test_exit_1_on_a_violation_with_inline_bindings(tmp_path):
    log = _synthetic(tmp_path)
    (tmp_path / "syn.bindings.toml").unlink()
    fret = tmp_path / "v.fret"
    fret.write_text("V1: the bot shall always satisfy speed < 0.4\n")
    res = run("-r", fret, log, "--tick-period", "100 ms", "--bind", "speed=abs(/cmd.linear.x)")
    assert res.exit_code == 1, res.output
    assert "V1 violated" in res.output and "speed" in res.output


def test_exit_2_on_input_errors(tmp_path):
    log = _synthetic(tmp_path)
    assert run("-r", tmp_path / "syn.fret", tmp_path / "nope.mcap").exit_code == 2
    # a binding file that does not parse
    (tmp_path / "syn.bindings.toml").write_text(SYN_BINDINGS + "oops = \n")
    res = run("-r", tmp_path / "syn.fret", log)
    assert res.exit_code == 2 and "syn.bindings.toml" in res.output
    (tmp_path / "syn.bindings.toml").write_text(SYN_BINDINGS)
    # a requirement that does not parse: reported, the others still audited
    (tmp_path / "syn.fret").write_text(SYN_FRET + "A9: the bot shall sometimes satisfy halted\n")
    res = run("-r", tmp_path / "syn.fret", log)
    assert res.exit_code == 2 and "A9" in res.output and "satisfied" in res.output
    # a ROS log without bindings
    (tmp_path / "syn.bindings.toml").unlink()
    (tmp_path / "syn.fret").write_text(SYN_FRET)
    res = run("-r", tmp_path / "syn.fret", log)
    assert res.exit_code == 2 and "needs signal bindings" in res.output
    # both tick options
    res = run("-r", tmp_path / "syn.fret", log, "--tick-period", "1 s", "--tick-topic", "/scan")
    assert res.exit_code == 2


def test_csv_trace_and_junit(tmp_path):
    (tmp_path / "t.fret").write_text(
        "C1: upon cc the sw shall within 2 ticks satisfy rr\n"
        "C2: in mm the sw shall always satisfy rr\n")
    (tmp_path / "t.csv").write_text("mm,cc,rr\n0,0,0\n1,1,0\n1,0,1\n0,0,0\n")
    xml = tmp_path / "j.xml"
    res = run("-r", tmp_path / "t.fret", tmp_path / "t.csv", "--junit", xml)
    assert res.exit_code == 1, res.output
    root = ET.parse(xml).getroot()
    assert root.get("tests") == "2" and root.get("failures") == "1"
    failed = [c.get("name") for c in root.iter("testcase") if c.find("failure") is not None]
    assert failed == ["C2"]


def test_violations_are_listed_and_annotated(tmp_path):
    """Every failed trigger is counted, the first ones are listed with their times, and the
    annotated MCAP carries one ERROR event per listed violation."""
    import json as _json

    from click.testing import CliRunner
    from mcap.reader import make_reader

    from fretc.cli import main as fretc_main
    from fretc.monitors.interval import MAX_LISTED

    root = Path(__file__).resolve().parents[2]
    res = CliRunner().invoke(fretc_main, [
        "report", "-r", str(root / "requirements"), str(root / "traces" / "interceptor_fault.mcap"),
        "-o", str(tmp_path / "report"), "--annotate", str(tmp_path / "annotated")])
    assert res.exit_code == 1, res.output
    doc = _json.loads((tmp_path / "report" / "audit.json").read_text())
    r3 = next(v for v in doc["logs"][0]["verdicts"] if v["requirement"] == "R3")
    listed = r3["violation_list"]
    assert r3["violations"] > MAX_LISTED and len(listed) == MAX_LISTED
    assert listed[0]["violation"]["tick"] == r3["first_violation"]["tick"]
    ticks = [item["violation"]["tick"] for item in listed]
    assert ticks == sorted(ticks) and len(set(ticks)) == len(ticks)
    with open(tmp_path / "annotated" / "interceptor_fault.mcap", "rb") as f:
        events = [_json.loads(m.data) for _s, _c, m in make_reader(f).iter_messages(
            topics=["/fretc/verdicts"])]
    r3_violations = [e for e in events if e["message"].startswith(("R3 VIOLATED",
                                                                     "R3 violation "))]
    assert len(r3_violations) == MAX_LISTED
    assert all(e["level"] == 4 for e in r3_violations)  # foxglove.Log ERROR


def test_numbers_behind_a_violated_boolean_are_shown(tmp_path):
    """R2 on sif_disabled: besides too_close (true/false), the audit shows the minimum valid
    /scan range behind it at the same ticks; checked against the scans decoded here."""
    import numpy as np
    from mcap.reader import make_reader
    from rosbags.typesys import Stores, get_typestore

    root = Path(__file__).resolve().parents[2]
    log = root / "traces" / "sif_disabled.mcap"
    out = tmp_path / "a.json"
    res = CliRunner().invoke(main, ["audit", "-r", str(root / "requirements"), str(log),
                                    "--no-progress", "--json", str(out)])
    assert res.exit_code == 1, res.output
    doc = json.loads(out.read_text())
    r2 = next(v for v in doc["logs"][0]["verdicts"] if v["requirement"] == "R2")
    rows = r2["values"]["too_close: min(/scan.ranges)"]
    flags = {r["tick"]: r["value"] for r in r2["values"]["too_close"]}
    assert len(rows) >= 10
    store = get_typestore(Stores.ROS2_HUMBLE)
    scans = []
    with open(log, "rb") as f:
        for _s, _c, m in make_reader(f).iter_messages(topics=["/scan"]):
            msg = store.deserialize_cdr(m.data, "sensor_msgs/msg/LaserScan")
            r = np.asarray(msg.ranges, dtype=np.float64)
            r = np.where(np.isneginf(r), msg.range_min, r)
            ok = r[(r >= msg.range_min) & (r <= msg.range_max)]
            scans.append((m.log_time, ok.min() if ok.size else np.inf))
    for row in rows:
        held = [v for t, v in scans if t <= row["time_ns"]][-1]
        assert row["value"] == pytest.approx(held)
        assert flags[row["tick"]] == (held < 0.9)


def test_abs_in_a_requirement_hints_fret_spelling_and_its_variable_is_not_unused(tmp_path):
    """``abs(...)`` in a requirement: a hint that FRET spells it absReal/absInt,
    and the variable inside is not reported unused (its requirement failed to parse)."""
    log = _synthetic(tmp_path)
    (tmp_path / "syn.bindings.toml").unlink()
    fret = tmp_path / "a.fret"
    for text, hint in [("abs(speed) < 0.4", "FRET spells it absReal(...) or absInt(...)"),
                       ("fabs(speed) < 0.4", "FRET spells it absReal(...) or absInt(...)"),
                       ("ABS(speed) < 0.4", "FRET spells it absReal(...) or absInt(...)")]:
        fret.write_text(f"A1: the bot shall always satisfy {text}\n")
        res = run("-r", fret, log, "--tick-period", "100 ms", "--bind", "speed=/cmd.linear.x")
        out = " ".join(res.output.split())
        assert res.exit_code == 2 and hint in out, out
        assert "no requirement uses it" not in out
        assert "bindings (None)" not in out
    # a variable that no requirement names is still reported
    fret.write_text("A1: the bot shall always satisfy abs(speed) < 0.4\n")
    res = run("-r", fret, log, "--tick-period", "100 ms", "--bind", "speed=/cmd.linear.x",
              "--bind", "other=/cmd.linear.x")
    assert "'other' is bound but no requirement uses it" in res.output


def test_r_dir_reads_fret_exports_by_content_and_skips_other_json(tmp_path):
    """Before, ``--json audit.json`` written into the requirements folder broke the next
    ``-r DIR`` run (exit 2, nothing audited): a JSON file is read as requirements only when
    it is a FRET export by its content; others are skipped with a note."""
    log = _synthetic(tmp_path)
    out = tmp_path / "audit.json"
    first = run("-r", tmp_path, log, "--json", out)
    assert first.exit_code == 0 and out.is_file(), first.output
    second = run("-r", tmp_path, log, "--json", tmp_path / "again.json")
    assert second.exit_code == 0, second.output
    assert f"{out}: skipped: a JSON file that is not a FRET export" in " ".join(
        second.output.split())
    assert json.loads((tmp_path / "again.json").read_text())["summary"]["satisfied"] == 3
    # a FRET export (whatever its name) is read by content
    (tmp_path / "export.json").write_text(json.dumps(
        [{"reqid": "E1", "fulltext": "the bot shall always satisfy speed <= 0.4"}]))
    third = run("-r", tmp_path, log)
    assert third.exit_code == 1 and "E1 violated" in third.output, third.output
