"""An open known problem of the gaps of a log (src/fretc/qualification/known_problems.toml):
its test asserts the wrong result a user gets today, beside the log that shows it (the same
log intact, or a requirement that reads what the wrong one does not). When a problem is
fixed, its test is turned into the right result and the problem's entry is closed (KP-177's
is now tests/audit/test_gaps.py::test_a_gap_of_the_tick_topic_is_a_gap_tick_of_every_requirement_on_its_clock)."""

from __future__ import annotations

from pathlib import Path

from mcap.reader import make_reader

from fretc.audit import AuditConfig, audit_log, load_plan

from _logs import S, twist_stamped, write_mcap

WALL = 1_700_000_000 * S  # log times on the wall clock; header stamps from 0 (a simulation)


def _verdicts(folder: Path, log: Path) -> dict:
    plan = load_plan(AuditConfig(requirements=(str(folder / "r.fret"),)))
    return {v.requirement: v for v in audit_log(plan, str(log)).verdicts}


def _header_log(folder: Path, damaged: bool) -> Path:
    """/v and /w at 10 Hz for 30 s, stamped 1 s + k * 100 ms and logged WALL later; /v's x
    is k (each change 1.0); /v's messages written first (one topic a chunk), the /v chunk
    holding message 150 fails its CRC when ``damaged``."""
    msgs = [(t, "geometry_msgs/msg/TwistStamped", WALL + S + k * S // 10,
             twist_stamped(S + k * S // 10, x=float(k) if t == "/v" else 1.0))
            for t in ("/v", "/w") for k in range(300)]
    log = write_mcap(folder / f"run{int(damaged)}.mcap", msgs, chunk_size=1024)
    if damaged:
        with open(log, "rb") as f:
            summary = make_reader(f).get_summary()
        at = WALL + S + 150 * S // 10
        bad = next(c for c in summary.chunk_indexes
                   if {summary.channels[i].topic for i in c.message_index_offsets} == {"/v"}
                   and c.message_start_time <= at <= c.message_end_time)
        data = bytearray(log.read_bytes())
        data[bad.chunk_start_offset + bad.chunk_length // 2] ^= 0x20
        log.write_bytes(bytes(data))
    (folder / "r.fret").write_text("RD: the sys shall always satisfy dv < 5\n")
    (folder / "r.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\ntime = "header"\n[variables]\n'
        'dv = "/v.twist.linear.x@delta"\n')
    return log


def test_a_gap_under_header_stamps_far_from_log_times_leaves_no_tick_unknown(tmp_path):
    """KP-176: under time = "header", a gap's log times are compared with the ticks' stamp
    times; stamps 1.7e9 s before their log times put the gap past every tick, so no tick is
    unknown and @delta reads across the lost chunk (x 142 to 153: 11): violated, where the
    intact log is satisfied and a log whose stamps are its log times is unknown."""
    intact = _verdicts(tmp_path, _header_log(tmp_path, damaged=False))
    assert intact["RD"].verdict == "satisfied"
    v = _verdicts(tmp_path, _header_log(tmp_path, damaged=True))["RD"]
    assert (v.verdict, v.unknown_ticks) == ("violated", 0)  # the right result: unknown
    assert v.first_violation.at.time_ns == S + 153 * S // 10  # the first /v after the gap
