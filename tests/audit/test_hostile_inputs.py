"""Regression tests of hostile inputs (damaged logs, hostile text, tick limit,
duplicate ids). Each failed on the code before the fix."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from click.testing import CliRunner
from mcap.reader import make_reader

from fretc.cli import main
from fretc.common.textsafe import md_code, visible
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.verdict import EXIT_INCOMPLETE, exit_code

ROOT = Path(__file__).resolve().parents[2]
TRACES = ROOT / "traces"
REQS = ROOT / "requirements"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture(scope="module")
def plan():
    return load_plan(AuditConfig((str(REQS),)))


def _chunks(path: Path):
    with open(path, "rb") as f:
        return sorted(make_reader(f).get_summary().chunk_indexes,
                      key=lambda c: c.chunk_start_offset)


# --------------------------------------------------------------------------- item 8
def test_item8_a_cut_is_no_evidence_of_a_violation(tmp_path, plan):
    # nominal.mcap cut at 835,145 bytes: R1 ("eventually stopped") has a trigger pending at
    # the cut; it used to be reported violated at the last tick before the cut
    cut = tmp_path / "nominal_cut.mcap"
    cut.write_bytes((TRACES / "nominal.mcap").read_bytes()[:835_145])
    la = audit_log(plan, str(cut))
    v = {x.requirement: x for x in la.verdicts}
    assert la.partial and la.damage_cut
    assert v["R1"].verdict == "unknown", v["R1"]
    assert "open" in v["R1"].unknown_reason
    assert all(x.verdict != "violated" for x in la.verdicts)
    assert exit_code([la]) == EXIT_INCOMPLETE  # never 0 on a log cut short


def test_item8_a_violation_decided_before_the_cut_stands(tmp_path, plan):
    # interceptor_fault violates R3 at 28.4 s (decided there); cut inside the fourth chunk
    # (53.0 s on): the violation stays, with the same evidence
    src = TRACES / "interceptor_fault.mcap"
    full = audit_log(plan, str(src))
    r3 = next(v for v in full.verdicts if v.requirement == "R3")
    assert r3.verdict == "violated" and r3.ltl3.status == "violated"
    c = _chunks(src)[3]
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(src.read_bytes()[: c.chunk_start_offset + c.chunk_length // 2])
    la = audit_log(plan, str(cut))
    v = {x.requirement: x for x in la.verdicts}
    assert la.partial and la.damage_time_ns > r3.ltl3.time_ns
    assert v["R3"].verdict == "violated" and v["R3"].partial
    assert v["R3"].first_violation.at.time_ns == r3.first_violation.at.time_ns
    assert exit_code([la]) == 1


# --------------------------------------------------------------------------- item 9
def test_item9_a_chunk_failing_its_crc_is_a_gap(tmp_path, plan):
    src = TRACES / "nominal.mcap"
    chunks = _chunks(src)
    bad = chunks[2]
    data = bytearray(src.read_bytes())
    data[bad.chunk_start_offset + bad.chunk_length // 2] ^= 0x10  # one flipped bit
    damaged = tmp_path / "flipped.mcap"
    damaged.write_bytes(bytes(data))
    la = audit_log(plan, str(damaged))
    full = audit_log(plan, str(src))
    assert la.partial and la.damage_cut
    assert la.damage_time_ns == bad.message_start_time
    gap = [p for p in la.problems if p["kind"] in ("chunk_crc", "chunk_corrupt")]
    assert gap and gap[0]["log_time_ns"] == bad.message_start_time
    assert gap[0]["end_time_ns"] == bad.message_end_time  # the gap's time span
    # the gap is listed with the chunk's span, cause and topics (the summary's message
    # indexes); values are not held across it (its ticks are unknown), and the log is
    # judged on after it, to its end
    (g,) = la.gaps
    assert (g["start_ns"], g["end_ns"], g["cause"]) == (bad.message_start_time,
                                                        bad.message_end_time, gap[0]["kind"])
    assert "/scan" in g["topics"]
    assert la.end_time_ns == full.end_time_ns and la.ticks_after_damage == 0
    assert any(v.unknown_ticks > 0 for v in la.verdicts)
    for d, o in zip(la.verdicts, full.verdicts):
        assert d.verdict != "violated" or o.verdict == "violated", d.requirement
        assert d.verdict not in ("satisfied", "vacuous") or o.verdict in ("satisfied",
                                                                          "vacuous")
    assert exit_code([la]) != 0


def test_item9_partial_shows_in_terminal_json_and_junit(tmp_path):
    src = TRACES / "nominal.mcap"
    bad = _chunks(src)[1]
    data = bytearray(src.read_bytes())
    data[bad.chunk_start_offset + bad.chunk_length // 2] ^= 0x01
    damaged = tmp_path / "flipped.mcap"
    damaged.write_bytes(bytes(data))
    res = run("audit", "-r", REQS / "safe_ros.fret", damaged, "--json", tmp_path / "a.json",
              "--junit", tmp_path / "j.xml", "--no-progress")
    assert res.exit_code == EXIT_INCOMPLETE, res.output
    out = re.sub(r"\s+", " ", res.output)
    assert "partial" in out and ("chunk_crc over" in out or "chunk_corrupt over" in out), out
    doc = json.loads((tmp_path / "a.json").read_text())
    (log,) = doc["logs"]
    assert log["partial"] and log["damage_cut"] and doc["summary"]["exit_code"] == EXIT_INCOMPLETE
    assert 'name="partial" value="true"' in (tmp_path / "j.xml").read_text()


# --------------------------------------------------------------------------- item 10
def test_item10_the_reason_is_kept_when_the_only_chunk_is_cut(tmp_path, shared):
    src = shared / "data" / "logs" / "cmd_vel_scaled.mcap"
    (only,) = _chunks(src)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(src.read_bytes()[: only.chunk_start_offset + 100])
    plan = load_plan(AuditConfig((str(REQS / "real_logs" / "cmd_vel_scaled.fret"),)))
    la = audit_log(plan, str(cut))
    assert la.partial
    assert [p["kind"] for p in la.problems] == ["truncated"]
    for v in la.verdicts:
        assert v.verdict == "unknown"
        assert "truncated" in v.unknown_reason
    assert exit_code([la]) == EXIT_INCOMPLETE


# --------------------------------------------------------------------------- item 11
@pytest.mark.tor("TOR-TCK-009")
def test_item11_a_tick_period_giving_too_many_ticks_is_an_error(tmp_path):
    b = tmp_path / "b.bindings.toml"
    b.write_text('[tick]\nperiod = "1 ns"\ntime = "log"\n[variables]\n'
                 'too_close = "min(/scan.ranges) < 0.9"\n'
                 'stopped = "abs(/cmd_vel_filtered.linear.x) < 1e-3"\n')
    res = run("audit", "-r", REQS / "r1.fret", "-b", b, TRACES / "sif_disabled.mcap",
              "--no-progress")
    assert res.exit_code == 2
    out = re.sub(r"\s+", " ", res.output)
    assert re.search(r"would give [\d,]+ ticks", out) and "100,000,000" in out, out


# --------------------------------------------------------------------------- item 12
HOSTILE = "R1\x00\x1b[2J\u202e``<script>x</script>``"


def test_item12_textsafe_units():
    assert visible("a\x00b\x1b[2J\u202ec\u2066") == "a\\x00b\\x1b[2J\\u202ec\\u2066"
    assert visible("plain ünïcode") == "plain ünïcode"
    span = md_code("a``b`")
    fence = span.split(" ")[0]
    assert set(fence) == {"`"} and len(fence) == 3 and span.endswith(fence)


def test_item12_hostile_ids_are_escaped_in_every_output(tmp_path):
    r1 = (REQS / "r1.fret").read_text()
    text = re.search(r"^R1:\s*(.+)$", r1, re.M).group(1).strip()
    reqs = tmp_path / "hostile.json"
    reqs.write_text(json.dumps([{"reqid": HOSTILE, "fulltext": text,
                                 "rationale": "bad\x00\u202e"}]))
    binding = REQS / "safe_ros.bindings.toml"
    out = tmp_path / "report"
    res = run("report", "-r", reqs, "-b", binding, "--tick-period", "100 ms",
              TRACES / "sif_disabled.mcap", "-o", out)
    assert res.exit_code == 1, res.output
    res = run("audit", "-r", reqs, "-b", binding, "--tick-period", "100 ms",
              TRACES / "sif_disabled.mcap", "--junit", tmp_path / "j.xml", "--no-progress")
    assert res.exit_code == 1
    # terminal: no raw ESC or bidi override; shown escaped
    assert "\x1b" not in res.output and "\u202e" not in res.output and "\x00" not in res.output
    assert "\\x1b[2J" in res.output
    # XML: JUnit, the HTML page and every SVG parse
    ET.parse(tmp_path / "j.xml")
    ET.fromstring((out / "report.html").read_text(encoding="utf-8"))
    svgs = list((out / "timelines").glob("*.svg"))
    assert svgs
    for svg in svgs:
        ET.fromstring(svg.read_text(encoding="utf-8"))
    # Markdown: the id's backticks cannot close the code span, so no raw <script>
    md = (out / "report.md").read_text(encoding="utf-8")
    assert "<script>" not in _outside_code(md)
    assert "\x00" not in md and "\u202e" not in md


def _outside_code(md: str) -> str:
    """The Markdown text outside inline code spans (CommonMark: a run of n backticks closes
    only on a run of exactly n)."""
    out, i = [], 0
    while i < len(md):
        if md[i] == "`":
            j = i
            while j < len(md) and md[j] == "`":
                j += 1
            fence = md[i:j]
            k = md.find(fence, j)
            while k != -1 and (md[k + len(fence): k + len(fence) + 1] == "`"
                               or (k > 0 and md[k - 1] == "`")):
                k = md.find(fence, k + 1)
            if k == -1:
                out.append(fence)
                i = j
                continue
            i = k + len(fence)
            continue
        out.append(md[i])
        i += 1
    return "".join(out)


def test_item12_psl_comments_carry_no_control_or_bidi_characters(tmp_path):
    reqs = tmp_path / "hostile.json"
    reqs.write_text(json.dumps([{"reqid": HOSTILE,
                                 "fulltext": "the sw shall always satisfy p\u202e"}]))
    res = run(reqs, "--emit", "psl", "-o", tmp_path / "out.psl")  # one input: -o is a file
    texts = [(tmp_path / "out.psl").read_text(encoding="utf-8")]
    assert texts[0], res.output
    for t in texts:
        assert "\x00" not in t and "\u202e" not in t and "\x1b" not in t
        assert "\\x00" in t


# --------------------------------------------------------------------------- item 13
def test_item13_the_same_id_in_two_files_is_an_error_naming_both(tmp_path):
    (tmp_path / "a.fret").write_text("R1: the sw shall always satisfy p\n")
    (tmp_path / "b.fret").write_text("# other\nR1: the sw shall always satisfy q\n")
    res = run(tmp_path, "--emit", "ltl")
    assert res.exit_code == 2
    assert "b.fret:2:1" in res.output and "a.fret:1" in res.output, res.output
    res = run("audit", "-r", tmp_path, "--bind", "p=/csv.p", "--bind", "q=/csv.q",
              "--tick-period", "1 s", TRACES / "sif_disabled.mcap", "--no-progress")
    assert res.exit_code == 2 and "unique" in res.output


def test_item13_one_file_named_twice_is_read_once(tmp_path):
    res = run(REQS, REQS / "r1.fret", "--emit", "ltl", "--json")
    assert res.exit_code == 0, res.output
    ids = [r["id"] for r in json.loads(res.output)]
    assert len(ids) == len(set(ids))


# --------------------------------------------------------------------------- item 12, properties
from hypothesis import given, settings, strategies as st  # noqa: E402

from fretc.common.textsafe import is_unsafe, one_line, xml_text  # noqa: E402

_HOSTILE_CHARS = st.text(alphabet=st.one_of(
    st.sampled_from("`|<>&\\\x00\x1b\x7f\x85\u202e\u2066\u200b\u2028\ufeff\ufffe\n\t\r "),
    st.characters()), max_size=40)


@settings(max_examples=300, deadline=None)
@given(_HOSTILE_CHARS)
def test_item12_escaped_text_is_safe_and_keeps_the_safe_characters(s):
    out = visible(s)
    assert not is_unsafe(out)
    if "\\" not in s:  # the escapes decode back to the text: nothing lost or changed
        back = re.sub(r"\\x([0-9a-f]{2})|\\u([0-9a-f]{4})|\\U([0-9a-f]{8})",
                      lambda m: chr(int(next(g for g in m.groups() if g), 16)), out)
        assert back == s
    el = ET.Element("a", b=xml_text(s, keep=""))
    el.text = xml_text(s)
    ET.fromstring(ET.tostring(el, encoding="unicode"))  # a NUL would not parse
    assert "\n" not in one_line(s)


@settings(max_examples=300, deadline=None)
@given(_HOSTILE_CHARS)
def test_item12_a_markdown_code_span_holds_any_text(s):
    span = md_code(s.replace("\n", " "))
    fence = re.match(r"`+", span).group(0)
    inner = span[len(fence):-len(fence)]
    assert span.endswith(fence)
    # no backtick run of the fence's length inside: the span cannot be closed early
    assert all(len(run) != len(fence) for run in re.findall(r"`+", inner))


# --------------------------------------------------------------------------- newlines from logs
def test_a_newline_in_log_text_cannot_forge_a_terminal_line(tmp_path):
    """A joint name (log text) with a newline, shown in a terminal error line, is escaped;
    so are topics in the data problems line."""
    from _logs import ROS2, write_mcap

    JS = "sensor_msgs/msg/JointState"
    import numpy as np
    from _logs import header

    def js(ns):
        return ROS2.types[JS](header=header(ns), name=["arm\nFORGED: 0 violated"],
                              position=np.zeros(1), velocity=np.zeros(1), effort=np.zeros(1))
    log = write_mcap(tmp_path / "j.mcap", [("/joint_states", JS, i * 10**8, js(i * 10**8))
                                            for i in range(3)])
    (tmp_path / "r.fret").write_text("R1: arm shall always satisfy w < 5\n")
    res = run("audit", "-r", tmp_path / "r.fret", "--tick-period", "100 ms",
              "--bind", 'w=joint(/joint_states.velocity, "wheel")', log, "--no-progress")
    assert res.exit_code in (2, 3), res.output
    assert "arm\\x0aFORGED" in res.output, res.output
    assert not any(line.startswith("FORGED") for line in res.output.splitlines())


def test_a_tiny_log_whose_messages_are_hours_apart_is_refused_before_its_columns(tmp_path):
    """A 200-byte DataFlash log with two BAT records 50,000 s apart at a 1 ms tick: 5e7
    ticks, under the tick limit, took 5.25 GB; the columns are counted before they are made
    (1 GiB over the clocks of a log) and the requirement is an error saying how many, with
    the process's memory still small."""
    import resource
    import sys

    sys.path.insert(0, str(ROOT / "tests" / "logs"))
    from _dataflash import write_dataflash

    log = write_dataflash(tmp_path / "x.bin", [("BAT", [1_000_000, 0, 12.0, 1.0, 90]),
                                               ("BAT", [50_000_000_000, 0, 12.0, 1.0, 80])])
    assert log.stat().st_size < 1000
    (tmp_path / "r.fret").write_text("R: the drone shall always satisfy volt > 10\n")
    (tmp_path / "r.bindings.toml").write_text('[tick]\nperiod = "1 ms"\n[variables]\n'
                                              'volt = "BAT.Volt"\n')
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    la = audit_log(load_plan(AuditConfig((str(tmp_path / "r.fret"),))), str(log))
    (v,) = la.verdicts
    assert v.verdict == "error" and "49,999,001 ticks" in v.error and "GiB" in v.error, v.error
    # (not a measure of time: the peak the read reached, under a tenth of the columns)
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 100 * 1024


def test_the_tick_by_tick_clock_counts_its_ticks_before_it_makes_them(tmp_path):
    """The clock of the watch and of ``--write-csv`` made every tick due before a message
    into one list: two DataFlash records 10^6 s apart at 1 ms (10^9 ticks) took gigabytes
    before any bound; the 10^8-tick bound is counted before the ticks are made, and ticks
    are handed on one at a time."""
    import sys
    import tracemalloc

    from fretc.audit.sampled.csv import write_sampled_csv
    from fretc.common.problems import SignalError

    sys.path.insert(0, str(ROOT / "tests" / "logs"))
    from _dataflash import write_dataflash

    log = write_dataflash(tmp_path / "x.bin", [("BAT", [1_000_000, 0, 12.0, 1.0, 90]),
                                               ("BAT", [10**12, 0, 12.0, 1.0, 80])])
    (tmp_path / "r.fret").write_text("R: the drone shall always satisfy volt > 10\n")
    (tmp_path / "r.bindings.toml").write_text('[tick]\nperiod = "1 ms"\n[variables]\n'
                                              'volt = "BAT.Volt"\n')
    plan = load_plan(AuditConfig((str(tmp_path / "r.fret"),)))
    tracemalloc.start()
    try:
        with pytest.raises(SignalError, match="more than 100,000,000 ticks"):
            write_sampled_csv(plan, str(log), tmp_path / "x.csv")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 50 * 2**20, peak
