"""Gaps under the header time base (KP-176): a gap's span is in log time, the ticks are header
stamps; the gap is placed among the ticks by the log times of the messages they hold, so the
verdicts do not depend on how far the stamps lie from their log times."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.log import audit_keeping_passes

from _logs import S, twist_stamped, write_mcap

REQS = {"RD": "RD: the sys shall always satisfy dv < 5",
        "RV": "RV: the sys shall always satisfy v < 1000",
        "RE": "RE: the sys shall eventually satisfy v > 298",
        "RW": "RW: the sys shall always satisfy w < 5",
        "RN": "RN: upon v > 100 the sys shall within 2 seconds satisfy w > 0"}
BINDINGS = ('dv = "/v.twist.linear.x@delta"\nv = "/v.twist.linear.x"\n'
            'w = "/w.twist.linear.x"\n')
#: offsets of the log times from the stamps (a simulation clock from 1 s logged on another)
OFFSETS = (5 * S, 3_600 * S, 1_700_000_000 * S)


def _log(folder: Path, offset: int, lost: tuple[str, int] | None,
         order: tuple[str, str] = ("/v", "/w"), fill: Any = None) -> Path:
    """/v and /w at 10 Hz for 30 s, stamped 1 s + k * 100 ms and logged ``offset`` later,
    /v's x is k (each change 1.0), /w's 1.0; written a topic at a time in ``order`` (one
    topic a chunk); ``lost``: (topic, k) the chunk of that topic holding message k fails its
    CRC; ``fill(topic, log_time)``: x instead, or None."""
    def x(t: str, k: int) -> float:
        got = fill(t, offset + S + k * S // 10) if fill is not None else None
        return got if got is not None else float(k) if t == "/v" else 1.0

    msgs = [(t, "geometry_msgs/msg/TwistStamped", offset + S + k * S // 10,
             twist_stamped(S + k * S // 10, x=x(t, k))) for t in order for k in range(300)]
    folder.mkdir(parents=True, exist_ok=True)
    log = write_mcap(folder / "run.mcap", msgs, chunk_size=1024)
    if lost is not None:
        topic, k = lost
        with open(log, "rb") as f:
            summary = make_reader(f).get_summary()
        at = offset + S + k * S // 10
        bad = next(c for c in summary.chunk_indexes
                   if {summary.channels[i].topic for i in c.message_index_offsets} == {topic}
                   and c.message_start_time <= at <= c.message_end_time)
        data = bytearray(log.read_bytes())
        data[bad.chunk_start_offset + bad.chunk_length // 2] ^= 0x20
        log.write_bytes(bytes(data))
    return log


def _audit(folder: Path, log: Path, tick: str, names: list[str], time: str = "header"
           ) -> dict:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "r.fret").write_text("".join(REQS[n] + "\n" for n in names))
    (folder / "r.bindings.toml").write_text(
        f'[tick]\n{tick}\ntime = "{time}"\n[variables]\n{BINDINGS}')
    plan = load_plan(AuditConfig(requirements=(str(folder / "r.fret"),)))
    return {v.requirement: (v.verdict, v.ticks_evaluated, v.unknown_ticks,
                            v.first_violation and v.first_violation.at.time_ns)
            for v in audit_log(plan, str(log)).verdicts}


CASES = [(tick, lost) for tick in ('period = "100 ms"', 'topic = "/w"')
         for lost in (("/v", 150), ("/v", 12), ("/v", 288), ("/w", 150), ("/w", 12))]


@pytest.mark.tor("TOR-DMG-002")
@pytest.mark.parametrize("tick,lost", CASES)
def test_a_gap_under_header_stamps_is_judged_alike_whatever_the_log_times(tmp_path, tick, lost):
    """The same stamps logged 5 s, 1 h or 1.7e9 s later (a simulation clock logged at
    wall-clock times): the same verdicts, ticks and unknown ticks, each requirement alone as
    in the set; a requirement reading the lost topic is never decided across the gap (KP-176:
    @delta across a lost /v chunk was violated with no tick unknown)."""
    got = {}
    for off in OFFSETS:
        log = _log(tmp_path / str(off), off, lost)
        got[off] = _audit(tmp_path / str(off), log, tick, list(REQS))
        for name in REQS:
            alone = _audit(tmp_path / str(off) / name, log, tick, [name])
            assert alone[name] == got[off][name], (off, name)
    first = got[OFFSETS[0]]
    assert all(got[o] == first for o in OFFSETS), got
    ticks_lost = tick == 'topic = "/w"' and lost[0] == "/w"
    readers = ("RD", "RV") if lost[0] == "/v" else ("RW",)
    for name in readers:  # (lost ticks of the clock: one unknown tick in their place)
        verdict, _ticks, unknown, _at = first[name]
        assert verdict == "unknown" and unknown >= (1 if ticks_lost else 10), (name, first)
    if ticks_lost:  # unknown for every requirement on the clock (KP-177)
        assert all(first[n][2] >= 1 for n in ("RD", "RV", "RW")), first


@pytest.mark.tor("TOR-DMG-002")
def test_kp176_a_lost_chunk_under_stamps_far_from_log_times_leaves_its_ticks_unknown(tmp_path):
    """KP-176's log: /v's chunk holding message 150 lost, stamps 1.7e9 s before their log
    times. Before the fix @delta read across the gap (x 142 to 153: 11): violated with 0
    unknown ticks; now unknown over the lost messages' ticks, as the same log audited on its
    log times is."""
    off = 1_700_000_000 * S
    intact = _audit(tmp_path / "i", _log(tmp_path / "i", off, None), 'period = "100 ms"', ["RD"])
    assert intact["RD"][0] == "satisfied"
    log = _log(tmp_path / "d", off, ("/v", 150))
    header = _audit(tmp_path / "h", log, 'period = "100 ms"', ["RD"])
    logged = _audit(tmp_path / "l", log, 'period = "100 ms"', ["RD"], time="log")
    assert header["RD"][0] == logged["RD"][0] == "unknown", (header, logged)
    assert header["RD"][3] is None and header["RD"][2] >= 10, header


@pytest.mark.tor("TOR-DMG-002")
def test_a_gap_at_the_end_under_header_stamps_is_a_cut_where_it_is_placed(tmp_path):
    """The last /v chunk lost, stamps far from their log times: the ticks from the first that
    may hold a lost /v message on are not judged for /v's requirements (a cut: 'always' is
    unknown, 'eventually v > 298' is not satisfied by what was read), /w's are judged whole."""
    log = _log(tmp_path, 1_700_000_000 * S, ("/v", 299), order=("/w", "/v"))
    got = _audit(tmp_path / "a", log, 'period = "100 ms"', ["RV", "RE", "RW"])
    assert got["RV"][0] == "unknown" and got["RE"][0] == "unknown", got
    assert got["RV"][1] < 295 and got["RW"][:3] == ("satisfied", 300, 0), got


#: a value, the previous message's, a fold since the previous tick, windows of a duration and
#: of a count of messages: each reads the lost messages differently
FOLDS = ('v = "/v.twist.linear.x"\ndv = "/v.twist.linear.x@delta"\n'
         'mx = "max_of_messages(/v.twist.linear.x)"\nmn = "mean(/v.twist.linear.x, 1s)"\n'
         'sc = "sum(/v.twist.linear.x, 5 messages)"\nw = "/w.twist.linear.x"\n')
FOLD_REQS = ("RV: the sys shall always satisfy v < 500\n"
             "RD: the sys shall always satisfy dv < 500 & dv > -500\n"
             "RM: the sys shall always satisfy mx < 500\n"
             "RA: the sys shall always satisfy mn < 500\n"
             "RC: the sys shall always satisfy sc < 2000\n"
             "RW: the sys shall always satisfy w < 500\n"
             "RX: the sys shall always satisfy v + dv + mx + mn + sc + w > -1e9\n")


def _kept(folder: Path, log: Path, tick: str) -> tuple[dict, Any]:
    """(requirement -> verdict, the clock of RX, which reads every variable)."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "r.fret").write_text(FOLD_REQS)
    (folder / "r.bindings.toml").write_text(
        f'[tick]\n{tick}\ntime = "header"\n[variables]\n{FOLDS}')
    kept = audit_keeping_passes(load_plan(AuditConfig(requirements=(str(folder / "r.fret"),))),
                                str(log))
    assert kept.passes is not None
    clock = next(res for key, res in kept.passes.passes.items() if len(key.variables) == 6)
    return {v.requirement: v.verdict for v in kept.audit.verdicts}, clock


@pytest.mark.tor("TOR-DMG-002")
@pytest.mark.parametrize("offset", [0, 1_700_000_000 * S], ids=["near", "far"])
@pytest.mark.parametrize("tick,lost,order", [
    (tick, lost, order) for tick in ('period = "100 ms"', 'topic = "/w"')
    for lost, order in ((("/v", 12), ("/v", "/w")), (("/v", 150), ("/v", "/w")),
                        (("/v", 299), ("/w", "/v")), (("/w", 150), ("/v", "/w")),
                        (("/w", 299), ("/v", "/w")))])
def test_a_tick_known_over_a_gap_under_header_stamps_is_what_every_filling_gives(
        tmp_path, offset, tick, lost, order):
    """Soundness at each tick: the lost messages filled with the intact values, with 1000
    and with -1000 (each a log of its own); a tick the damaged log's audit leaves known has,
    for every variable (a value, @delta, max_of_messages, a 1 s mean, a sum of 5 messages),
    the value every filling gives at that tick; a requirement decided on the damaged log is
    decided alike on every filling. Stamps equal to their log times and 1.7e9 s before them."""
    damaged = _log(tmp_path / "d", offset, lost, order)
    verdicts, clock = _kept(tmp_path / "d", damaged, tick)
    gaps = clock.gaps
    assert gaps, "the damage is a gap of the clock"

    def lost_at(t: str, log_time: int) -> bool:
        return any(g.affects(t) and g.start <= log_time <= g.end for g in gaps)

    fills = [None, 1000.0, -1000.0]
    for i, value in enumerate(fills):
        fill = None if value is None else (
            lambda t, lt, value=value: value if lost_at(t, lt) else None)
        other = _log(tmp_path / f"f{i}", offset, None, order, fill)
        want, full = _kept(tmp_path / f"f{i}", other, tick)
        at = {int(t): j for j, t in enumerate(full.times)}
        for name, col in clock.columns.items():
            unknown = clock.unknown.get(name)
            for j, t in enumerate(clock.times):
                if (unknown is not None and unknown[j]) or int(t) not in at:
                    continue
                a, b = float(col[j]), float(full.columns[name][at[int(t)]])
                assert a == b or (math.isnan(a) and math.isnan(b)), \
                    (name, int(t), a, b, value, verdicts)
        for r, v in verdicts.items():
            assert v == "unknown" or v == want[r], (r, v, want[r], value)


@pytest.mark.tor("TOR-DMG-002")
def test_a_gap_tick_under_header_stamps_goes_after_the_tick_of_the_last_message_before_it():
    """On a clock ticking on /w's messages (stamps 11 to 41 ns, odd), /w's message logged
    between 1031 and 1051 lost: one gap tick between the third tick and the last, its time
    strictly between theirs, the tick before's values held in it; none for a gap before every
    tick of /w's (the start of the run: mark_gaps' unknown first tick)."""
    import numpy as np

    from fretc.audit.columns import ClockPass
    from fretc.audit.gaps import insert_gap_ticks
    from fretc.logs.base import Gap

    def res() -> ClockPass:
        return ClockPass(None, np.array([11, 21, 31, 41], np.int64),
                         {"w": np.array([1.0, 2.0, 3.0, 4.0])},
                         {"/w": np.array([1011, 1021, 1031, 1051], np.int64)})

    r = res()
    assert insert_gap_ticks(r, [Gap(1035, 1045, frozenset({"/w"}), "chunk_crc")], "/w",
                            header=True) == [3]
    assert r.times.tolist()[:3] == [11, 21, 31] and r.times[4] == 41
    assert 31 < r.times[3] < 41 and r.columns["w"].tolist() == [1.0, 2.0, 3.0, 3.0, 4.0]
    r = res()
    assert insert_gap_ticks(r, [Gap(1000, 1005, frozenset({"/w"}), "chunk_crc")], "/w",
                            header=True) == []
    assert insert_gap_ticks(r, [Gap(1035, 1045, frozenset({"/v"}), "chunk_crc")], "/w",
                            header=True) == []
