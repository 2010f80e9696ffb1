"""Damaged PX4 ULogs (the three real logs of ``../shared/data/foreign_logs/px4/``): cut in the
middle of a message at 10 % and 50 %, the tail zeroed, 64 KB zeroed in the middle. pyulog
reads each quietly as a shorter or thinner clean flight; fretc checks the framing
(:mod:`fretc.logs.flight.ulog_framing`): each is partial with a ``truncated`` or ``corrupt_record``
problem, and no verdict contradicts the intact log's (a verdict satisfied on the damaged copy
is satisfied on the intact log, a violated one violated there); a requirement the intact log
satisfies is never satisfied on a cut copy (what was cut was not checked)."""

from __future__ import annotations

import pytest

pytest.importorskip("pyulog")

from _shared import SHARED, needs_shared  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402
from fretc.logs.flight.ulog_framing import SYNC_BYTES, ulog_framing  # noqa: E402

PX4 = SHARED / "data" / "foreign_logs" / "px4"
NAMES = ["sample.ulg", "sample_log_small.ulg", "sample_px4_events.ulg"]
FRET = ("R1: the vehicle shall always satisfy vz < 0.15\n"
        "R2: the vehicle shall always satisfy vz < 100\n"
        "R3: the vehicle shall never satisfy error_logged\n")
BINDINGS = """[tick]
period = "100 ms"
[variables]
vz = 'abs("vehicle_local_position".vz)'
error_logged = '"Log".level >= ERROR'
"""


def _damaged(data: bytes) -> dict[str, bytes]:
    n = len(data)
    return {"cut10": data[:n // 10 + 1], "cut50": data[:n // 2 + 1],
            "tail_zeroed": data[:int(n * 0.6)] + bytes(n - int(n * 0.6)),
            "middle_zeroed": data[:n // 2] + bytes(65536) + data[n // 2 + 65536:]}


@pytest.fixture(scope="module")
def plan(tmp_path_factory):
    d = tmp_path_factory.mktemp("ulog")
    (d / "r.fret").write_text(FRET, encoding="utf-8")
    (d / "r.bindings.toml").write_text(BINDINGS, encoding="utf-8")
    return load_plan(AuditConfig(requirements=(str(d / "r.fret"),)))


@needs_shared
@pytest.mark.parametrize("name", NAMES)
def test_an_intact_ulog_has_sound_framing(name):
    framing = ulog_framing((PX4 / name).read_bytes())
    assert framing.damages == [] and len(framing.runs) == 1
    assert framing.runs[0][1] == (PX4 / name).stat().st_size


@needs_shared
@pytest.mark.parametrize("name", NAMES)
def test_a_cut_or_zeroed_ulog_is_damage_and_never_contradicts_the_intact_log(
        tmp_path, plan, name):
    data = (PX4 / name).read_bytes()
    intact = {v.requirement: v.verdict for v in audit_log(plan, str(PX4 / name)).verdicts}
    for label, damaged in _damaged(data).items():
        path = tmp_path / f"{label}.ulg"
        path.write_bytes(damaged)
        la = audit_log(plan, str(path))
        where = f"{name} {label}"
        assert la.error is None and la.partial and la.damage_cut, where
        kinds = {p["kind"] for p in la.problems}
        assert kinds & {"truncated", "corrupt_record"}, (where, kinds)
        for v in la.verdicts:
            if v.verdict in ("satisfied", "vacuous"):
                assert intact[v.requirement] in ("satisfied", "vacuous"), (where, v)
                assert not label.startswith("cut") and label != "tail_zeroed", (where, v)
            elif v.verdict == "violated":
                assert intact[v.requirement] == "violated", (where, v)


@needs_shared
def test_zeroed_bytes_in_the_middle_are_a_gap_and_the_flight_after_it_is_judged(tmp_path, plan):
    """sample_px4_events.ulg has sync messages: reading resumes after the next one, the span
    between is a gap of the log, and a violation in the messages after it is found."""
    data = (PX4 / "sample_px4_events.ulg").read_bytes()
    damaged = _damaged(data)["middle_zeroed"]
    framing = ulog_framing(damaged)
    (d,) = framing.damages
    assert d.kind == "corrupt_record" and d.next_time_us is not None
    assert d.next_time_us >= d.last_time_us and len(framing.runs) == 2
    assert damaged.find(SYNC_BYTES, d.offset) > d.offset
    path = tmp_path / "m.ulg"
    path.write_bytes(damaged)
    la = audit_log(plan, str(path))
    gaps = [g for g in la.gaps if g["cause"] == "corrupt_record"]
    assert [(g["start_ns"], g["end_ns"]) for g in gaps] == [
        (d.last_time_us * 1000, d.next_time_us * 1000)]
    assert la.cut_time_ns is None  # the log is read to its end
    r1 = next(v for v in la.verdicts if v.requirement == "R1")
    assert r1.verdict == "violated"


def test_framing_of_bytes_that_are_no_ulog_is_empty():
    assert ulog_framing(b"not a ulog at all").runs == []
    assert ulog_framing(b"").damages == []


def _data_messages(data: bytes, topic: str) -> list[tuple[int, int]]:
    """(offset, payload size) of every data message of ``topic`` (walking the framing)."""
    import struct

    pos, subs, out = 16, {}, []
    while pos + 3 <= len(data):
        size, typ = struct.unpack_from("<HB", data, pos)
        if typ == ord("A"):
            subs[struct.unpack_from("<H", data, pos + 4)[0]] = data[pos + 6:pos + 3 + size]
        elif typ == ord("D") and subs.get(struct.unpack_from("<H", data, pos + 3)[0]) == \
                topic.encode():
            out.append((pos, size))
        pos += 3 + size
    return out


@needs_shared
@pytest.mark.parametrize("big", [13459, 1722])
def test_a_data_message_whose_size_field_is_wrong_is_damage(tmp_path, big):
    """A ``battery_status`` message whose size field says more bytes than its format has
    swallows the messages after it, and where the size lands on a message boundary the
    framing went on: 7 of 157 messages lost, no problem, not partial. A data message whose
    size is not its format's is damage (resynchronised at the next sync message)."""
    import struct

    from fretc.logs import open_log

    data = bytearray((PX4 / "sample_px4_events.ulg").read_bytes())
    msgs = _data_messages(bytes(data), "battery_status")
    assert len(msgs) == 157
    at = msgs[0][0] if big == 13459 else msgs[10][0]
    struct.pack_into("<H", data, at, big)
    framing = ulog_framing(bytes(data))
    assert [d.kind for d in framing.damages] == ["corrupt_record"], framing.damages
    assert f"byte {at}" in framing.damages[0].detail
    path = tmp_path / "big.ulg"
    path.write_bytes(bytes(data))
    src = open_log(str(path))
    got = sum(1 for _ in src.messages({"battery_status"}))
    assert got < 157 and src.partial and any(p.kind == "corrupt_record" for p in src.problems)
