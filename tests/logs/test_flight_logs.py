"""Flight logs audited like robot logs: PX4 ULog (the three real logs of
``../shared/data/foreign_logs/px4/``, read with pyulog) and ArduPilot DataFlash (written here
with pymavlink's own record classes). Every verdict is recomputed independently from the
library's plain read with numpy (sample-and-hold at the 100 ms ticks)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pyulog")
pytest.importorskip("pymavlink")

from _dataflash import write_dataflash  # noqa: E402
from _shared import SHARED, needs_shared  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402
from fretc.logs import open_log  # noqa: E402
from fretc.logs.schema import log_schemas  # noqa: E402
from fretc.logs.flight.ulog import DROPOUT, EARLY_TIMESTAMP  # noqa: E402
from fretc.audit.verdict import exit_code  # noqa: E402

PX4 = SHARED / "data" / "foreign_logs" / "px4"
TICK = 100_000_000

PX4_FRET = """@tick_period 100 ms
PB: the drone shall always satisfy battery_high
PL: the drone shall never satisfy error_logged
PO: whenever armed the drone shall immediately satisfy outputs_in_range
PR: upon rtl the drone shall within 10 seconds satisfy disarmed
PR5: upon rtl the drone shall within 5 seconds satisfy disarmed
"""
PX4_BINDINGS = """[tick]
period = "100 ms"
[variables]
battery_high = '"battery_status".remaining > 0.9'
error_logged = '"Log".level >= ERROR'
armed = '"vehicle_status".arming_state = 2'
outputs_in_range = 'max("actuator_outputs".output[0:4]) <= 2000'
rtl = '"vehicle_status".nav_state = 5'
disarmed = '"vehicle_status".arming_state = 1'
"""


def _plan(tmp_path, fret: str, bindings: str):
    (tmp_path / "r.fret").write_text(fret, encoding="utf-8")
    (tmp_path / "r.bindings.toml").write_text(bindings, encoding="utf-8")
    return load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),)))


def _by_id(la) -> dict:
    return {v.requirement: v for v in la.verdicts}


def _first_tick_at_or_after(first_tick: int, t: int) -> int:
    return first_tick + max(0, math.ceil((t - first_tick) / TICK)) * TICK


def _ulog(name: str, topics: list[str]):
    from pyulog import ULog

    u = ULog(str(PX4 / name), message_name_filter_list=topics)
    start = u.start_timestamp
    out = {}
    for d in u.data_list:  # a topic's first row (stamped at its publication) is data
        t = d.data["timestamp"]
        keep = (t >= start) & (t != 0)
        keep[0] = t[0] != 0
        out[(d.name, d.multi_id)] = {k: v[keep] for k, v in d.data.items()}
    return u, out


@needs_shared
def test_px4_requirements_on_a_sitl_flight_match_an_independent_recomputation(tmp_path):
    la = audit_log(_plan(tmp_path, PX4_FRET, PX4_BINDINGS), str(PX4 / "sample_px4_events.ulg"))
    v = _by_id(la)
    u, data = _ulog("sample_px4_events.ulg", ["battery_status", "vehicle_status",
                                              "actuator_outputs"])
    bat, st = data[("battery_status", 0)], data[("vehicle_status", 0)]
    first = v["PB"].first_tick_ns
    # PB: remaining <= 0.9 from some message on: violated at the first tick holding it
    bad = int(bat["timestamp"][np.argmax(bat["remaining"] <= 0.9)]) * 1000
    assert v["PB"].verdict == "violated"
    assert v["PB"].first_violation.at.time_ns == _first_tick_at_or_after(first, bad)
    # PL: no logged message at ERROR or worse (syslog level <= 3)
    assert max(int(m.log_level) for m in u.logged_messages) > 3
    assert v["PL"].verdict == "satisfied"
    # PO: every output of the first four channels is within range while armed
    out = data[("actuator_outputs", 0)]
    assert np.stack([out[f"output[{k}]"] for k in range(4)]).max() <= 2000
    assert v["PO"].verdict == "satisfied"
    # PR: RTL (nav_state 5) to disarmed (arming_state 1): 8 s, within 10 s but not within 5
    t = st["timestamp"].astype(np.int64) * 1000
    rtl = int(t[np.argmax(st["nav_state"] == 5)])
    after = (t > rtl) & (st["arming_state"] == 1)
    disarm = int(t[np.argmax(after)])
    assert 5e9 < disarm - rtl <= 10e9
    assert v["PR"].verdict == "satisfied"
    assert v["PR5"].verdict == "violated"
    trig = v["PR5"].first_violation.trigger.time_ns
    assert trig == _first_tick_at_or_after(v["PR5"].first_tick_ns, rtl)
    assert v["PR5"].first_violation.at.time_ns == trig + 50 * TICK
    # the vehicle_status sample stamped before the log's start is data, not skipped
    assert not any(p["kind"] == EARLY_TIMESTAMP for p in la.problems)


@needs_shared
def test_px4_first_samples_stamped_before_the_header_are_data(tmp_path):
    """PX4's logger writes each topic's last sample when it subscribes, stamped when it was
    published: vehicle_status 220 ms before the ULog header's start in this SITL flight.
    A requirement reading it starts at its first sample (the first tick at or after it),
    not at the header's start; a timestamp of 0 (rtl_time_estimate, never set) is skipped
    and reported."""
    from pyulog import ULog

    u = ULog(str(PX4 / "sample_px4_events.ulg"), message_name_filter_list=["vehicle_status"])
    first = int(u.data_list[0].data["timestamp"][0]) * 1000
    start = int(u.start_timestamp) * 1000
    assert start - first == 220_000_000
    fret = "@tick_period 100 ms\nS: the drone shall always satisfy nav_state < 100\n"
    binds = '[tick]\nperiod = "100 ms"\n[variables]\nnav_state = \'"vehicle_status".nav_state\'\n'
    (s,) = audit_log(_plan(tmp_path, fret, binds), str(PX4 / "sample_px4_events.ulg")).verdicts
    assert s.verdict == "satisfied"
    assert first <= s.first_tick_ns < first + TICK and s.first_tick_ns < start
    src = open_log(PX4 / "sample_px4_events.ulg")
    rtl = list(src.messages({"rtl_time_estimate"}))
    zeros = [p for p in src.problems if p.kind == EARLY_TIMESTAMP]
    assert len(zeros) == 1 and zeros[0].topic == "rtl_time_estimate"
    assert all(m.log_time != 0 for m in rtl)


@needs_shared
def test_px4_inspect_gives_the_span_from_the_first_sample_and_the_headers_start():
    """inspect's span starts at the first sample (stamped before the ULog header's start,
    data as the audit reads it) and says where the header starts the recording, by pyulog's
    header; a log without such a header says nothing of it (an MCAP here)."""
    import json

    from click.testing import CliRunner
    from pyulog import ULog

    from fretc.cli import main

    path = PX4 / "sample_px4_events.ulg"
    res = CliRunner().invoke(main, ["inspect", "--json", str(path)])
    assert res.exit_code == 0, res.output
    (doc,) = json.loads(res.output)
    header = int(ULog(str(path), message_name_filter_list=[]).start_timestamp) * 1000
    assert doc["header_start_ns"] == header > doc["start_time_ns"]
    res = CliRunner().invoke(main, ["inspect", str(path)])
    first = res.output.splitlines()[0]
    assert f"{doc['duration_s']:.3f} s (from the first sample; the ULog header starts the " \
           f"recording {(header - doc['start_time_ns']) / 1e9:.3f} s after it)" in first
    mcap = Path(__file__).resolve().parents[2] / "traces" / "stop_delay.mcap"
    res = CliRunner().invoke(main, ["inspect", "--json", str(mcap)])
    assert json.loads(res.output)[0]["header_start_ns"] is None
    assert "first sample" not in CliRunner().invoke(main, ["inspect", str(mcap)]).output


@needs_shared
def test_px4_instances_are_topics_of_their_own_with_every_field():
    src = open_log(PX4 / "sample_log_small.ulg")
    topics = src.topics()
    assert topics["battery_status"] == topics["battery_status/1"] == "px4_msgs/msg/BatteryStatus"
    u, data = _ulog("sample_log_small.ulg", ["battery_status"])
    counts = {}
    volts = {}
    for m in src.messages({"battery_status", "battery_status/1"}):
        counts[m.topic] = counts.get(m.topic, 0) + 1
        volts.setdefault(m.topic, []).append(m.data.voltage_v)
        assert len(m.data.voltage_cell_v) == 10
    for k, topic in ((0, "battery_status"), (1, "battery_status/1")):
        assert counts[topic] == len(data[("battery_status", k)]["timestamp"])
        assert np.allclose(volts[topic], data[("battery_status", k)]["voltage_v"])
    schema = log_schemas(src)["vehicle_status"]
    assert dict(schema.fields())["arming_state"].name == "uint8"
    assert schema.constants() == {}
    assert log_schemas(src)["Log"].constants()["ERROR"] == 8


@needs_shared
def test_px4_dropouts_are_damage_never_held_over(tmp_path):
    la = audit_log(_plan(tmp_path, PX4_FRET, PX4_BINDINGS), str(PX4 / "sample.ulg"))
    assert la.partial
    assert any(p["kind"] == DROPOUT for p in la.problems)
    # each dropout is said to be what it is: a gap, the log read on after it
    assert all(p["detail"].endswith("a gap (its ticks are unknown), the log is read on after "
                                    "it") for p in la.problems if p["kind"] == DROPOUT)
    v = _by_id(la)
    # the logger's ERROR message at 45.6 s is read after the dropouts: violated there
    assert v["PL"].verdict == "violated"
    assert v["PL"].first_violation.at.log_time_ns == 158_215_813_000
    assert "battery_status" in v["PB"].error  # this older PX4 logs no battery


@needs_shared
def test_px4_a_violation_after_the_dropouts_is_violated(tmp_path):
    """The flight's logger dropped messages for 0, 26 and 31 ms near its start and for
    62 ms at 41 s; the vertical speed breaks 0.15 m/s at 3.74 s in the messages recorded
    (log time 116.2428 s): violated at the first tick after it (exit 1), on a fixed period
    and on one tick per message, every dropout a gap of the log (every topic)."""
    fret = "R1: the vehicle shall always satisfy vz < 0.15\n"
    vz = 'vz = \'abs("vehicle_local_position".vz)\'\n'
    for tick in ('period = "100 ms"', 'topic = "vehicle_local_position"',
                 'topic = \'"vehicle_local_position"\''):
        la = audit_log(_plan(tmp_path, fret, f"[tick]\n{tick}\n[variables]\n{vz}"),
                       str(PX4 / "sample.ulg"))
        (r1,) = la.verdicts
        assert r1.verdict == "violated", (tick, r1.verdict, r1.unknown_reason)
        fv = r1.first_violation
        assert fv.at.log_time_ns == 116_242_849_000 and fv.at.time_ns >= 116_242_849_000
        assert [(g["cause"], g["topics"]) for g in la.gaps] == [(DROPOUT, None)] * 4
        assert sorted(g["end_ns"] - g["start_ns"] for g in la.gaps) == [
            0, 26_000_000, 31_000_000, 62_000_000]
        assert exit_code([la]) == 1


@needs_shared
@pytest.mark.parametrize("name", ["sample.ulg", "sample_log_small.ulg",
                                  "sample_px4_events.ulg"])
def test_px4_reopen_gives_what_a_new_open_gives(name):
    """The operands pass reads a ULog again through ``reopen()`` (no second pyulog read):
    the same messages, counts, problems, gaps and times as the file opened anew, and the
    first source's pass is left as it was."""
    def one_pass(src, topics):
        msgs = [(m.topic, m.log_time, repr(vars(m.data)) if hasattr(m.data, "__dict__")
                 else repr(m.data)) for m in src.messages(topics)]
        return (msgs, dict(src.counts), [repr(p) for p in src.problems], list(src.gaps),
                src.start_time, src.end_time, src.partial)

    first = open_log(str(PX4 / name))
    topics = set(list(first.topics())[:4])
    before = one_pass(first, None)
    again = first.reopen()
    assert one_pass(again, topics) == one_pass(open_log(str(PX4 / name)), topics)
    assert (dict(first.counts), first.end_time) == (before[1], before[5])


def _dataflash_rows():
    rows = []
    for i in range(50):
        t = 1_000_000 + i * 100_000
        rows.append(("BAT", [t, 0, 12.0 - i * 0.05, 5.0, 90.0 - i]))
        rows.append(("BAT", [t + 10, 1, 11.0, 1.0, 50.0]))
    rows += [("MODE", [1_500_000, 4, 4, 1]), ("MSG", [2_000_000, "Arming motors"]),
             ("ERR", [3_000_000, 6, 1])]
    return sorted(rows, key=lambda r: r[1][0])


DF_FRET = """@tick_period 100 ms
B0: the copter shall always satisfy volt_ok
B1: the copter shall always satisfy volt1_ok
E: the copter shall never satisfy radio_failsafe
"""
DF_BINDINGS = """[tick]
period = "100 ms"
[variables]
volt_ok = '"BAT".Volt > 10.0'
volt1_ok = '"BAT/1".Volt > 10.0'
radio_failsafe = '"ERR".Subsys = 5'
"""


def test_dataflash_written_by_pymavlink_audits_by_type_and_instance(tmp_path):
    from pymavlink import DFReader

    log = write_dataflash(tmp_path / "flight.bin", _dataflash_rows())
    la = audit_log(_plan(tmp_path, DF_FRET, DF_BINDINGS), str(log))
    v = _by_id(la)
    assert la.problems == []
    # independent: pymavlink's own read of BAT instance 0
    r = DFReader.DFReader_binary(str(log), zero_time_base=False)
    bat0 = []
    while (m := r.recv_match(type="BAT")) is not None:
        if m.Inst == 0:
            bat0.append((m.TimeUS * 1000, m.Volt))
    bad = next(t for t, volt in bat0 if volt <= 10.0)
    assert v["B0"].verdict == "violated"
    assert v["B0"].first_violation.at.time_ns == _first_tick_at_or_after(
        v["B0"].first_tick_ns, bad)
    assert v["B1"].verdict == "satisfied"  # instance 1 holds 11 V: never mixed with 0
    assert v["E"].verdict == "satisfied"  # ERR subsystem 6, not 5


def test_dataflash_cut_short_is_partial_and_garbage_is_an_input_error(tmp_path):
    log = write_dataflash(tmp_path / "flight.bin", _dataflash_rows())
    cut = tmp_path / "cut.bin"
    cut.write_bytes(log.read_bytes()[:-40])
    la = audit_log(_plan(tmp_path, DF_FRET, DF_BINDINGS), str(cut))
    v = _by_id(la)
    assert la.partial and any(p["kind"] == "truncated" for p in la.problems)
    assert v["B1"].verdict == "unknown"  # satisfied so far, but the log was cut short
    assert v["B0"].verdict == "violated"  # decided before the cut: stands
    # a record whose header is damaged (DataFlash has no checksum: a damaged body cannot
    # be seen, a damaged header can): its bytes are skipped, a gap from the message before
    data = bytearray(log.read_bytes())
    mid = data.find(b"\xa3\x95", len(data) // 2)
    data[mid:mid + 2] = b"\xff\xff"
    bad = tmp_path / "bad.bin"
    bad.write_bytes(bytes(data))
    la = audit_log(_plan(tmp_path, DF_FRET, DF_BINDINGS), str(bad))
    assert la.partial and any(p["kind"] == "corrupt_record" for p in la.problems)
    assert _by_id(la)["B1"].verdict == "unknown"
    junk = tmp_path / "junk.bin"
    junk.write_bytes(b"\x00\x01not a log" * 100)
    la = audit_log(_plan(tmp_path, DF_FRET, DF_BINDINGS), str(junk))
    assert all(x.verdict == "error" for x in la.verdicts)


def test_dataflash_cut_at_any_byte_inside_its_last_record_is_partial(tmp_path, capfd):
    """A cut 3 bytes into a record (its header read, no body) read as a complete, shorter
    log (pymavlink had already stepped past the header); and pymavlink's C indexer printed
    a line per bad byte on the terminal."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
    from fuzz_flight import boundaries

    data = write_dataflash(tmp_path / "flight.bin", _dataflash_rows()).read_bytes()
    starts = sorted(boundaries(data, ".bin"))
    last = starts[-2]  # the last record's start (the last entry is the end)
    plan = _plan(tmp_path, DF_FRET, DF_BINDINGS)
    for cut in range(last + 1, len(data)):
        path = tmp_path / f"cut{cut}.bin"
        path.write_bytes(data[:cut])
        la = audit_log(plan, str(path))
        assert la.partial and any(p["kind"] == "truncated" for p in la.problems), cut
    zeroed = tmp_path / "zeroed.bin"
    zeroed.write_bytes(data[:last] + bytes(4000) + data[last:])
    audit_log(plan, str(zeroed))
    assert "bad header" not in "".join(capfd.readouterr())


@pytest.mark.parametrize("bit", [0x40, 0x01, 0x80])
def test_dataflash_a_bit_flipped_in_timeus_names_the_record(tmp_path, bit):
    """A bit flipped in one record's TimeUS dates it centuries (or minutes) after the records
    around it: the audit stopped on "more than 100,000,000 ticks" naming no record. The
    record is a ``corrupt_record`` problem naming its type, offset and TimeUS, skipped, and
    the log is judged around it (a gap where it was)."""
    rows = [("BAT", [1_000_000 + k * 100_000, 0, 12.0 if k != 30 else 9.0, 1.0, 90])
            for k in range(50)]
    log = write_dataflash(tmp_path / "x.bin", rows)
    data = bytearray(log.read_bytes())
    bat = [i for i in range(len(data) - 2) if data[i:i + 3] == bytes([0xA3, 0x95, 130])]
    at = bat[20]
    data[at + 3 + (7 if bit != 0x01 else 4)] ^= bit  # a high byte of the uint64 TimeUS
    flipped = tmp_path / "flip.bin"
    flipped.write_bytes(bytes(data))
    (tmp_path / "r.fret").write_text("R: the drone shall always satisfy volt > 10\n")
    (tmp_path / "r.bindings.toml").write_text('[tick]\nperiod = "100 ms"\n[variables]\n'
                                              'volt = "BAT.Volt"\n')
    la = audit_log(load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),))),
                   str(flipped))
    (v,) = la.verdicts
    named = [p for p in la.problems if p["kind"] == "corrupt_record"]
    assert named and f"offset {at}" in named[0]["detail"] and "BAT" in named[0]["detail"], \
        la.problems
    assert v.verdict == "violated", v.error  # the record at 4.0 s read, the flipped one not
    assert v.first_violation.at.time_ns == 4_000_000_000 and la.partial


def test_dataflash_times_count_from_the_logs_start_whatever_is_audited(tmp_path):
    """The ``*_s`` times of a verdict count from the log's first record of any type, so a
    requirement audited alone prints the seconds it prints in its set (they counted from
    the first message of the topics the audit read: 0.5 s apart here)."""
    rows = [("MSG", [500_000, "boot"])] + [
        ("BAT", [1_000_000 + i * 100_000, 0, 12.0 - i * 0.1, 5.0, 90.0]) for i in range(30)]
    log = write_dataflash(tmp_path / "f.bin", rows)
    fret = "@tick_period 100 ms\nB: the copter shall always satisfy volt_ok\n"
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    alone = audit_log(_plan(tmp_path / "a", fret, DF_BINDINGS), str(log)).to_json()
    both = audit_log(_plan(tmp_path / "b", fret + "E: the copter shall never satisfy "
                           "radio_failsafe\n", DF_BINDINGS), str(log)).to_json()
    assert alone["start_time_ns"] == both["start_time_ns"] == 500_000_000
    va, vb = alone["verdicts"][0], both["verdicts"][0]
    assert va["first_violation"]["tick_time_s"] == vb["first_violation"]["tick_time_s"]
    assert va["first_violation"]["tick_time_s"] == pytest.approx(2.5)
