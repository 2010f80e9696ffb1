"""Exit codes of fretc audit: 0 complete and satisfied, 1 violated, 2 input error,
3 no violation but a log is partial or had data problems (``--allow-partial``: 0); JUnit
marks a partial log as an error case; first-violation times say which clock they are on
(``log_time_ns`` is a real message log time, the tick's own time is ``tick_time_ns``)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.reports.junit import junit_xml
from fretc.audit.verdict import EXIT_INCOMPLETE, exit_code

from _logs import MS, S, twist_stamped, write_mcap

ROOT = Path(__file__).resolve().parents[2]
TRACES = sorted((ROOT / "traces").glob("*.mcap"))


@pytest.fixture(scope="module")
def plan():
    return load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))


def _cut(tmp_path, log, frac):
    data = log.read_bytes()
    out = tmp_path / f"{log.stem}_cut{int(frac * 100)}.mcap"
    out.write_bytes(data[:int(len(data) * frac)])
    return out


@pytest.mark.parametrize("log", TRACES, ids=lambda p: p.name)
def test_a_truncated_copy_of_every_trace_exits_with_the_partial_code(tmp_path, plan, log):
    """Cut at 30 % of the bytes: before any violation of any shipped run. Today's code
    exited 0 there: a CI gate passed a recording that lost most of its minutes."""
    la = audit_log(plan, str(_cut(tmp_path, log, 0.3)))
    assert la.partial and la.damage_time_ns is not None
    assert not any(v.verdict == "violated" for v in la.verdicts)
    assert exit_code([la]) == EXIT_INCOMPLETE == 3
    assert exit_code([la], allow_partial=True) == 0
    # JUnit: no test case of a partial log passes
    root = ET.fromstring(junit_xml([la]))
    cases = root.findall(".//testcase")
    assert cases and all(c.find("error") is not None or c.find("failure") is not None
                         for c in cases)
    assert int(root.get("errors")) == len(la.verdicts)


@pytest.mark.parametrize("log", [ROOT / "traces" / "sif_disabled.mcap",
                                 ROOT / "traces" / "stop_delay.mcap"], ids=lambda p: p.name)
@pytest.mark.tor("TOR-DMG-003")
def test_violations_decided_before_the_damage_are_kept(tmp_path, plan, log):
    """A violation whose obligation was missed before the damage stands on the truncated
    copy, with the same trigger and missed tick times (the partial code does not hide it:
    exit 1)."""
    whole = {v.requirement: v for v in audit_log(plan, str(log)).verdicts}
    la = audit_log(plan, str(_cut(tmp_path, log, 0.9)))
    assert la.partial
    kept = 0
    for v in la.verdicts:
        w = whole[v.requirement]
        if w.verdict == "violated" and w.first_violation.at.time_ns < la.damage_time_ns:
            assert v.verdict == "violated"
            assert v.first_violation.trigger.time_ns == w.first_violation.trigger.time_ns
            assert v.first_violation.at.time_ns == w.first_violation.at.time_ns
            kept += 1
    assert kept >= 1
    assert exit_code([la]) == 1


@pytest.mark.tor("TOR-VER-006", "TOR-DMG-001")
def test_cli_partial_exit_code_allow_partial_and_json(tmp_path):
    cut = _cut(tmp_path, ROOT / "traces" / "unmapped_obstacles.mcap", 0.5)
    run = CliRunner().invoke
    args = ["audit", "-r", str(ROOT / "requirements"), str(cut), "--no-progress"]
    res = run(main, args + ["--json", str(tmp_path / "a.json"), "--junit",
                            str(tmp_path / "j.xml")])
    assert res.exit_code == 3, res.output
    assert "partial" in res.output and "exit 3" in res.output
    doc = json.loads((tmp_path / "a.json").read_text())
    assert doc["summary"]["exit_code"] == 3 and doc["summary"]["incomplete_logs"] == 1
    assert 'type="partial"' in (tmp_path / "j.xml").read_text()
    res = run(main, args + ["--allow-partial"])
    assert res.exit_code == 0, res.output
    assert "Exit codes" in run(main, ["audit", "--help"]).output


@pytest.mark.tor("TOR-VER-006")
def test_exit_codes_are_in_the_docs_and_the_help():
    page = (ROOT / "docs" / "guide" / "audits.md").read_text(encoding="utf-8")
    assert "## Exit codes" in page and "--allow-partial" in page
    help_text = CliRunner().invoke(main, ["audit", "--help"]).output
    for code in ("0 ", "1 ", "2 ", "3 "):
        assert f"  {code}" in help_text
    assert "docs/bindings.md" in help_text


# ---------------------------------------------------------------- time fields
HEADER_FRET = "@tick_period 100 ms\nH1: the bot shall always satisfy speed < 1\n"
HEADER_BINDINGS = """[tick]
period = "100 ms"
time = "header"
header_lag = "200 ms"
[variables]
speed = "abs(/cmd.twist.linear.x)"
"""


def test_first_violation_log_time_is_a_message_log_time_under_header_time(tmp_path):
    """Header stamps run 3.7 s behind log time. ``log_time_ns`` must be the log time of
    a real message (today it held the tick's header-stamp time, which is no message's log
    time); the tick's own time is ``tick_time_ns`` on the ``header`` base."""
    msgs = []
    for k in range(60):
        stamp = 10 * S + k * 100 * MS + 3 * MS
        msgs.append(("/cmd", "geometry_msgs/msg/TwistStamped", stamp + 3700 * MS,
                     twist_stamped(stamp, 2.0 if k >= 30 else 0.1)))
    write_mcap(tmp_path / "h.mcap", msgs)
    (tmp_path / "h.fret").write_text(HEADER_FRET)
    (tmp_path / "h.bindings.toml").write_text(HEADER_BINDINGS)
    res = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "h.fret"),
                                    str(tmp_path / "h.mcap"), "--json", "-", "--no-progress"])
    assert res.exit_code == 1, res.output
    doc = json.loads(res.output[res.output.index("{"):])
    fv = doc["logs"][0]["verdicts"][0]["first_violation"]
    log_times = {m[2] for m in msgs}
    assert fv["log_time_ns"] in log_times
    assert fv["log_time_ns"] == 10 * S + 30 * 100 * MS + 3 * MS + 3700 * MS
    # the first tick that holds message 30: the multiple of 100 ms after its stamp
    assert fv["tick_time_ns"] == 10 * S + 31 * 100 * MS
    assert fv["tick_time_base"] == "header"
