"""Gaps of a log (../shared/DESIGN.md, "Damage is a gap"): a gap leaves unknown only the ticks
of the topics it may hold, the log is judged on after it, ``--bridge-gaps`` holds values over
the gaps shorter than it (each listed as bridged), and the JSON, terminal and report list
them."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from mcap.reader import make_reader

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.cli import main

from _logs import S, float64, write_mcap

FRET = ("RV: the sys shall always satisfy v < 5\n"
        "RW: the sys shall always satisfy w < 5\n")
BINDINGS = '[tick]\nperiod = "100 ms"\n[variables]\nv = "/v.data"\nw = "/w.data"\n'


def _log(tmp_path: Path) -> tuple[Path, object]:
    """/v and /w at 10 Hz for 30 s, every value 1.0; /v's messages written first (so each
    chunk holds one topic); one /v chunk in the middle fails its CRC. Returns the damaged
    log and its bad chunk's index."""
    msgs = [("/v", "std_msgs/msg/Float64", S + k * S // 10, float64(1.0)) for k in range(300)]
    msgs += [("/w", "std_msgs/msg/Float64", S + k * S // 10, float64(1.0)) for k in range(300)]
    log = write_mcap(tmp_path / "run.mcap", msgs, chunk_size=1024)
    with open(log, "rb") as f:
        summary = make_reader(f).get_summary()
    chunks = sorted((c for c in summary.chunk_indexes
                     if {summary.channels[i].topic for i in c.message_index_offsets} == {"/v"}),
                    key=lambda c: c.message_start_time)
    bad = chunks[len(chunks) // 2]
    data = bytearray(log.read_bytes())
    data[bad.chunk_start_offset + bad.chunk_length // 2] ^= 0x20
    log.write_bytes(bytes(data))
    (tmp_path / "r.fret").write_text(FRET)
    (tmp_path / "r.bindings.toml").write_text(BINDINGS)
    return log, bad


def _audit(tmp_path: Path, log: Path, bridge_ns: int | None = None):
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),),
                                 bridge_gaps_ns=bridge_ns))
    la = audit_log(plan, str(log))
    return la, {v.requirement: v for v in la.verdicts}


@pytest.mark.tor("TOR-DMG-002")
def test_a_gap_leaves_unknown_only_the_topics_it_may_hold(tmp_path):
    log, bad = _log(tmp_path)
    la, v = _audit(tmp_path, log)
    (g,) = la.gaps
    assert g["topics"] == ["/v"] and not g["bridged"] and g["cause"] == "chunk_crc"
    assert (g["start_ns"], g["end_ns"]) == (bad.message_start_time, bad.message_end_time)
    assert v["RV"].verdict == "unknown" and v["RV"].unknown_ticks > 0
    assert "chunk_crc" in v["RV"].unknown_reason
    # /w lost nothing: judged as on the intact log
    assert v["RW"].verdict == "satisfied" and v["RW"].unknown_ticks == 0
    assert la.partial and la.cut_time_ns is None and la.end_time_ns >= S + 299 * S // 10


@pytest.mark.tor("TOR-DMG-006")
def test_bridge_gaps_holds_values_over_the_short_gaps_only(tmp_path):
    log, bad = _log(tmp_path)
    length = bad.message_end_time - bad.message_start_time
    la, v = _audit(tmp_path, log, bridge_ns=length)  # not shorter than itself: kept
    assert v["RV"].verdict == "unknown" and not la.gaps[0]["bridged"]
    la, v = _audit(tmp_path, log, bridge_ns=length + 1)
    assert v["RV"].verdict == "satisfied" and v["RV"].unknown_ticks == 0
    (g,) = la.gaps
    assert g["bridged"] and g["topics"] == ["/v"]
    # the command line: the option, the JSON and the terminal's list
    res = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"), str(log),
                                    "--bridge-gaps", f"{(length + 10**6) / 1e9} s",
                                    "--no-progress", "--json", str(tmp_path / "a.json")])
    out = " ".join(res.output.split())
    assert res.exit_code == 3, res.output  # a partial log, bridged or not
    assert "1 gap bridged, the value before held over it (chunk_crc over" in out
    doc = json.loads((tmp_path / "a.json").read_text())
    assert doc["logs"][0]["gaps"][0]["bridged"] is True
    bad_value = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"), str(log),
                                          "--bridge-gaps", "soon"])
    assert bad_value.exit_code == 2 and "--bridge-gaps" in bad_value.output


@pytest.mark.tor("TOR-DMG-006")
def test_a_gap_is_listed_in_the_report(tmp_path):
    log, _bad = _log(tmp_path)
    res = CliRunner().invoke(main, ["report", "-r", str(tmp_path / "r.fret"), str(log),
                                    "-o", str(tmp_path / "rep")])
    assert res.exit_code == 3, res.output
    html = (tmp_path / "rep" / "report.html").read_text()
    assert "chunk_crc over" in html and "their ticks are unknown" in html


TICK_ON_W = '[tick]\ntopic = "/w"\n[variables]\nv = "/v.data"\nw = "/w.data"\n'


def _two_topics(tmp_path: Path, lost: list[tuple[str, int]], high_w: int = -1) -> Path:
    """/v and /w at 10 Hz for 30 s, each value 1.0 (/w's ``high_w``-th 9.0); the messages
    ``lost`` (topic, index) written undecodable."""
    msgs = [(t, "std_msgs/msg/Float64", S + k * S // 10,
             float64(9.0 if (t, k) == ("/w", high_w) else 1.0))
            for k in range(300) for t in ("/v", "/w")]
    raw = {2 * k + (t == "/w"): b"\x00" for t, k in lost}
    (tmp_path / "r.fret").write_text(FRET)
    (tmp_path / "r.bindings.toml").write_text(TICK_ON_W)
    return write_mcap(tmp_path / f"run{len(lost)}.mcap", msgs, raw_override=raw)


@pytest.mark.tor("TOR-DMG-002")
def test_on_a_topics_clock_its_gaps_are_unknown_ticks_of_their_own(tmp_path):
    """A clock ticking on /w's messages: /v's undecodable message leaves unknown the one tick
    that holds the /v message before it and puts no tick of its own on /w's clock; /w's two
    undecodable messages are each one unknown tick put in its place, and only those ticks
    are unknown for what reads /w (a /w value of 9 two messages before the second stays a
    violation)."""
    _la, v = _audit(tmp_path, _two_topics(tmp_path, [("/v", 50)]))
    assert (v["RV"].verdict, v["RV"].ticks_evaluated, v["RV"].unknown_ticks) == ("unknown", 300, 1)
    assert (v["RW"].verdict, v["RW"].unknown_ticks) == ("satisfied", 0)
    _la, v = _audit(tmp_path, _two_topics(tmp_path, [("/w", 100), ("/w", 200)], high_w=198))
    assert v["RW"].ticks_evaluated == 300 and v["RW"].unknown_ticks == 2
    assert v["RW"].verdict == "violated"
    assert v["RW"].first_violation.at.time_ns == S + 198 * S // 10


def _verdicts(folder: Path, log: Path) -> dict:
    """requirement id -> its verdict, the requirements of ``folder/r.fret`` audited on ``log``."""
    plan = load_plan(AuditConfig(requirements=(str(folder / "r.fret"),)))
    return {v.requirement: v for v in audit_log(plan, str(log)).verdicts}


@pytest.mark.tor("TOR-DMG-002")
def test_a_gap_of_the_tick_topic_is_a_gap_tick_of_every_requirement_on_its_clock(tmp_path):
    """KP-177, fixed: a clock ticking on /w's messages; /w's messages 100 and 200
    undecodable (two gaps of /w), /v intact and 9.0 at its message 100 (the intact log
    violates both requirements there). A requirement reading /v alone gets the clock's two
    gap ticks as the one reading /w does: unknown on 300 ticks, 2 unknown; it was
    satisfied on 298 ticks read as if consecutive."""
    def log(lost: list[int]) -> Path:
        msgs = [(t, "std_msgs/msg/Float64", S + k * S // 10,
                 float64(9.0 if (t, k) == ("/v", 100) else 1.0))
                for k in range(300) for t in ("/v", "/w")]
        raw = {2 * k + 1: b"\x00" for k in lost}
        return write_mcap(tmp_path / f"run{len(lost)}.mcap", msgs, raw_override=raw)
    (tmp_path / "r.fret").write_text("RV: the sys shall always satisfy v < 5\n"
                                     "RVW: the sys shall always satisfy v < 5 & w < 5\n")
    (tmp_path / "r.bindings.toml").write_text(
        '[tick]\ntopic = "/w"\n[variables]\nv = "/v.data"\nw = "/w.data"\n')
    intact = _verdicts(tmp_path, log([]))
    assert intact["RV"].verdict == "violated" and intact["RVW"].verdict == "violated"
    v = _verdicts(tmp_path, log([100, 200]))
    assert (v["RVW"].verdict, v["RVW"].ticks_evaluated, v["RVW"].unknown_ticks) == \
        ("unknown", 300, 2)
    assert (v["RV"].verdict, v["RV"].ticks_evaluated, v["RV"].unknown_ticks) == \
        ("unknown", 300, 2)
