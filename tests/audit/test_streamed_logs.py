"""A log's clocks judged as they are read (audit/streamed_log.py): past ``KEEP_TICKS`` ticks
a clock's requirements are fed its blocks of ticks and its columns dropped.

* Metamorphic: on every log the tests have (the cases of tests/audit/_metamorphic.py: the
  shipped runs, the real logs, the foreign bags, MCAP and ULog files; a damaged copy of a
  shipped run; a DataFlash log, a rosbag2 folder), streaming from tick 0, from tick 1 or
  past a few dozen ticks, in chunks of 1, 7 or the default ticks, gives the audit JSON of
  the whole clock judged as one chunk, byte for byte;
* memory: the audit of a long MCAP log does not grow with its ticks (the growth of the
  traced peak between two lengths of the same run, as tests/audit/test_csv_memory.py).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

import _metamorphic as M
from _logs import MS, boolean, twist, write_mcap
from test_metamorphic import ALL, SAMPLE, _case

import fretc.audit.streamed_log as streamed_log
from _peak import traced_audit
from fretc.audit import AuditConfig, audit_log, load_plan

ROOT = Path(__file__).resolve().parents[2]
#: (ticks kept before streaming, ticks a chunk gathers): from the first tick a tick a chunk,
#: from the second seven a chunk, past a few dozen the default chunks
KEEPS = ((0, 1), (1, 7), (37, streamed_log.FEED_TICKS))


def _audit(fret: Path, log: Path) -> str:
    plan = load_plan(AuditConfig(requirements=(str(fret),)))
    return json.dumps(audit_log(plan, str(log)).to_json(), sort_keys=True)


def _counted(monkeypatch) -> list[int]:
    """The requirements the streams decide, counted over the audits that follow."""
    decided: list[int] = []
    close = streamed_log.LogStreams.close

    def counting(self, source, gaps):
        got = close(self, source, gaps)
        decided.append(len(got.results))
        return got

    monkeypatch.setattr(streamed_log.LogStreams, "close", counting)
    return decided


def check_chunks(case: M.Case, tmp: Path, monkeypatch) -> list[int]:
    """The audit JSON streamed from each of :data:`KEEPS` ticks equals the whole clock's;
    the requirements the streams decided."""
    fret = M.write(tmp / "r", case)
    monkeypatch.setattr(streamed_log, "KEEP_TICKS", 1 << 40)  # (every clock one chunk)
    whole = _audit(fret, case.log)
    decided = _counted(monkeypatch)
    for keep, feed in KEEPS:
        monkeypatch.setattr(streamed_log, "KEEP_TICKS", keep)
        monkeypatch.setattr(streamed_log, "FEED_TICKS", feed)
        assert _audit(fret, case.log) == whole, f"{case.id}: streamed past {keep} ticks, " \
                                                f"{feed} a chunk"
    return decided


@pytest.mark.parametrize("case", SAMPLE)
@pytest.mark.tor("TOR-TCK-001")
def test_a_log_streamed_in_chunks_gives_the_whole_clocks_audit(case, tmp_path, monkeypatch):
    check_chunks(_case(case), tmp_path, monkeypatch)


@pytest.mark.slow
@pytest.mark.parametrize("case", ALL)
def test_a_log_streamed_in_chunks_gives_the_whole_clocks_audit_on_every_log(
        case, tmp_path, monkeypatch):
    check_chunks(_case(case), tmp_path, monkeypatch)


def test_the_shipped_runs_are_streamed_and_judged_alike(tmp_path, monkeypatch):
    """Every shipped run: the same JSON; the satisfied and vacuous requirements of a sound
    run decided by the streams (a violated one is judged over its columns, read again); a
    damaged copy (a chunk failing its CRC) judged over its columns, the same JSON."""
    total = 0
    for case in M.shipped_cases():
        total += sum(check_chunks(case, tmp_path / case.log.stem, monkeypatch))
    assert total > 0
    case = M.shipped_cases()[0]
    bad = tmp_path / "bad.mcap"
    if M.corrupt_chunk(M.rechunked(case.log, tmp_path / "re.mcap"), bad, 0.5) is None:
        pytest.skip("too few chunks")
    check_chunks(M.Case(case.id, bad, case.fret, case.bindings), tmp_path / "bad", monkeypatch)


def _case_of(tmp: Path, log: Path, fret: str, bindings: str) -> M.Case:
    return M.Case(log.name, log, fret, bindings)


def test_a_dataflash_log_and_a_rosbag2_folder_streamed_give_the_whole_clocks_audit(
        tmp_path, monkeypatch):
    """The formats the cases above do not hold: an ArduPilot DataFlash log (a violation on
    a clock of two instances' messages), the same cut short (damage: its clocks read again
    keeping their columns), and a rosbag2 folder (a violation with its deadline)."""
    pytest.importorskip("pymavlink")
    sys.path.insert(0, str(ROOT / "tests" / "logs"))
    from _dataflash import write_dataflash
    from test_flight_logs import DF_BINDINGS, DF_FRET, _dataflash_rows
    from rosbags.rosbag2 import Writer as Rosbag2Writer

    from _logs import ROS2, scan

    log = write_dataflash(tmp_path / "flight.bin", _dataflash_rows())
    cut = tmp_path / "cut.bin"
    cut.write_bytes(log.read_bytes()[:-40])
    for path in (log, cut):
        check_chunks(_case_of(tmp_path, path, DF_FRET, DF_BINDINGS),
                     tmp_path / path.stem, monkeypatch)
    bag = tmp_path / "run_bag"
    with Rosbag2Writer(bag, version=9) as w:
        cs = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=ROS2)
        cc = w.add_connection("/cmd", "geometry_msgs/msg/Twist", typestore=ROS2)
        for k in range(60):
            t = k * 100 * MS
            w.write(cs, t, ROS2.serialize_cdr(scan([0.3 if k in (10, 40) else 2.0], t),
                                              "sensor_msgs/msg/LaserScan"))
            w.write(cc, t, ROS2.serialize_cdr(twist(0.0 if k > 42 else 0.5),
                                              "geometry_msgs/msg/Twist"))
    fret = ("@tick_period 100 ms\n"
            "A1: whenever near the bot shall within 500 milliseconds satisfy halted\n"
            "A2: the bot shall always satisfy speed <= 1\n")
    bindings = ('[tick]\nperiod = "100 ms"\n[variables]\nnear = "min(/scan.ranges) < 0.5"\n'
                'halted = "abs(/cmd.linear.x) < 1e-3"\nspeed = "abs(/cmd.linear.x)"\n')
    decided = check_chunks(_case_of(tmp_path, bag, fret, bindings), tmp_path / "bag",
                           monkeypatch)
    assert sum(decided) > 0


# --------------------------------------------------------------------------- memory
REQUIREMENTS = """\
R1: the robot shall always satisfy speed <= 0.5
R2: upon blocked the robot shall within 200 ticks satisfy stopped
R3: the robot shall always satisfy speed <= 0.2
"""
BINDINGS = """\
[tick]
period = "1 ms"
[variables]
speed = "abs(/cmd_vel.linear.x)"
stopped = "abs(/cmd_vel.linear.x) < 0.01"
blocked = "/blocked.data"
"""
#: The growth allowed a tick when clocks are judged as they are read: none but noise.
BYTES_PER_TICK = 1
#: The whole clock's columns: the times, two held log times, a number and two booleans.
WHOLE_BYTES_PER_TICK = 20


def _write_run(path: Path, ticks: int) -> None:
    """A run of ``ticks`` ticks of 1 ms: ``/cmd_vel`` every 10 ms (stopped for 300 ms of
    every 1000 ms), ``/blocked`` true at the start of each stop (R1 and R2 hold; R3 is
    violated whenever the robot moves: its evidence read again)."""
    msgs = []
    for k in range(ticks // 10 + 1):
        t = k * 10 * MS
        phase = k % 100
        msgs.append(("/cmd_vel", "geometry_msgs/msg/Twist", t,
                     twist(0.0 if phase < 30 else 0.2 + 0.001 * (k % 50))))
        if phase in (0, 1):
            msgs.append(("/blocked", "std_msgs/msg/Bool", t + 1, boolean(phase == 0)))
    write_mcap(path, msgs, chunk_size=64 * 1024)  # (many chunks, in both lengths)


def _peak(plan, path: Path) -> int:
    la, peak = traced_audit(plan, path)
    assert [v.verdict for v in la.verdicts] == ["satisfied", "satisfied", "violated"], \
        la.verdicts
    return peak


@pytest.mark.tor("TOR-TCK-001")
def test_the_audit_of_a_long_mcap_does_not_grow_with_its_ticks(tmp_path):
    (tmp_path / "r.fret").write_text(REQUIREMENTS)
    (tmp_path / "r.bindings.toml").write_text(BINDINGS)
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),)))
    short, long = 140_000, 420_000  # (both past KEEP_TICKS and a robustness block)
    _write_run(tmp_path / "short.mcap", short)
    _write_run(tmp_path / "long.mcap", long)
    _peak(plan, tmp_path / "short.mcap")  # caches filled, as for the runs

    def growth() -> float:
        return (_peak(plan, tmp_path / "long.mcap")
                - _peak(plan, tmp_path / "short.mcap")) / (long - short)

    streamed = growth()
    assert streamed <= BYTES_PER_TICK, f"{streamed:.1f} bytes a tick"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(streamed_log, "KEEP_TICKS", 1 << 40)  # (every clock kept whole)
        whole = growth()
    assert whole >= WHOLE_BYTES_PER_TICK, f"the whole clock: {whole:.1f} bytes a tick"


def _closed(monkeypatch) -> list:
    """What the streams decided (:class:`fretc.audit.streamed_log.Closed`), kept over the
    audits that follow."""
    out: list = []
    close = streamed_log.LogStreams.close

    def keeping(self, source, gaps):
        got = close(self, source, gaps)
        out.append(got)
        return got

    monkeypatch.setattr(streamed_log.LogStreams, "close", keeping)
    return out


def test_a_violation_is_decided_as_read_and_its_evidence_read_again(tmp_path, monkeypatch):
    """A violation on a long log: decided by the streams, the ticks its evidence shows (its
    trigger, scope, window, violation, the ticks around them) read again, no column kept;
    sif_disabled.mcap streamed from tick 0, the same JSON as its clocks judged whole."""
    case = next(c for c in M.shipped_cases() if c.log.name == "sif_disabled.mcap")
    fret = M.write(tmp_path / "r", case)
    monkeypatch.setattr(streamed_log, "KEEP_TICKS", 1 << 40)
    whole = _audit(fret, case.log)
    closed = _closed(monkeypatch)
    monkeypatch.setattr(streamed_log, "KEEP_TICKS", 0)
    assert _audit(fret, case.log) == whole
    got = closed[0]
    violated = [r for r in json.loads(whole)["verdicts"] if r["verdict"] == "violated"]
    assert violated and got.pick and not got.again
    assert len(got.results) == len(json.loads(whole)["verdicts"])
    assert all(len(p.times) <= 200 for p in got.picked.values())  # (some ticks, not all)


def test_a_clock_the_streams_leave_undecided_is_read_again_keeping_its_columns(
        tmp_path, monkeypatch):
    """What still holds a clock's columns on a long log (KP-127): the log's damage, a gap
    of its topics or a NaN; such a clock is read a second time keeping its columns. A
    shipped run with a chunk failing its CRC, streamed from tick 0: every clock goes back,
    the same JSON as its clocks judged whole."""
    case = M.shipped_cases()[0]
    bad = tmp_path / "bad.mcap"
    if M.corrupt_chunk(M.rechunked(case.log, tmp_path / "re.mcap"), bad, 0.5) is None:
        pytest.skip("too few chunks")
    fret = M.write(tmp_path / "r", case)
    monkeypatch.setattr(streamed_log, "KEEP_TICKS", 1 << 40)
    whole = _audit(fret, bad)
    closed = _closed(monkeypatch)
    monkeypatch.setattr(streamed_log, "KEEP_TICKS", 0)
    assert _audit(fret, bad) == whole
    assert closed[0].again and not closed[0].results
