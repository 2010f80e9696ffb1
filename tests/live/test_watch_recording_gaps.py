"""``fretc audit`` of a watch's recording gives the watch's verdicts when the run has gaps: a
publisher that left for good while the run went on (a silence: no loss, the run not
partial), one that restarted (over the Foxglove protocol a loss: partial). The recording carries
the run's gaps (an MCAP Metadata record, :mod:`fretc.logs.recorded_gaps`); without them the
audit of the recording held the topic's last value to the end of the run and judged what the
watch had not (a violation the watch cut off, a satisfied where the watch said unknown)."""

from __future__ import annotations

import asyncio
import json

import pytest

pytest.importorskip("websockets")

from hostile_ws import T0, ScriptServer, advertise, f64, message_data, subscription  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402
from fretc.audit.verdict import exit_code  # noqa: E402
from fretc.common import problems as P  # noqa: E402
from fretc.live.watch import Watch, WatchOptions  # noqa: E402
from fretc.logs import McapSource  # noqa: E402
from fretc.logs.recorded_gaps import GAPS_METADATA, gaps_json, parse_gaps  # noqa: E402

pytestmark = pytest.mark.watch
MS = 1_000_000
FRET = ("@tick_period 100 ms\n"
        "RA: the robot shall always satisfy a_ok\n"
        "RB: the robot shall always satisfy a_ok & b_ok\n"
        "RC: upon !a_ok the robot shall within 300 milliseconds satisfy b_ok\n"
        "RD: the robot shall always satisfy b_ok\n")
BINDINGS = ('[tick]\nperiod = "100 ms"\ntime = "log"\n[variables]\na_ok = "/a.data > 0"\n'
            'b_ok = "/b.data > 0"\n')


@pytest.fixture()
def plan(tmp_path):
    (tmp_path / "w.fret").write_text(FRET, encoding="utf-8")
    (tmp_path / "w.bindings.toml").write_text(BINDINGS, encoding="utf-8")
    return load_plan(AuditConfig(requirements=(str(tmp_path / "w.fret"),)))


def _run(b_until: int, b_back: int | None, restart: bool, b_leave: int | None = None,
         b_only: bool = False):
    """/a every 50 ms for 2 s, false from 1.5 s on; /b true every 50 ms until ``b_until``
    ms, then silent, unadvertised at ``b_leave`` ms (default ``b_until``); advertised again
    (``restart``) from ``b_back`` ms on. ``b_only``: a watch that subscribes to /b alone
    (then the run goes on for 0.6 s of wall time after /b left for good, past the grace a
    publisher has to come back in, as the run goes on with /a in the set)."""
    leave = b_until if b_leave is None else b_leave

    async def script(ws, k):
        await ws.send(advertise([(1, "/a"), (2, "/b")]))
        sa, sb = (None, *await _subscriptions(ws, (2,))) if b_only else \
            await _subscriptions(ws, (1, 2))
        for i in range(40):
            t = i * 50
            if sa is not None:
                await ws.send(message_data(sa, T0 + t * MS, f64(1.0 if t < 1500 else -1.0)))
            if t < b_until:
                await ws.send(message_data(sb, T0 + t * MS, f64(1.0)))
            elif t == leave:
                await ws.send(json.dumps({"op": "unadvertise", "channelIds": [2]}))
                if restart:
                    await ws.send(advertise([(3, "/b")]))
                    sb = await subscription(ws, 3)
                elif b_only:  # the run goes on past the grace without its one topic
                    await asyncio.sleep(0.6)
            elif b_back is not None and t >= b_back:
                await ws.send(message_data(sb, T0 + t * MS, f64(1.0)))
            await asyncio.sleep(0.003)
        await asyncio.sleep(0.2)
        await ws.close(1000, "end of the run")
    return script


async def _subscriptions(ws, channels: tuple[int, ...]) -> list[int]:
    """The client's subscription ids of ``channels`` (in one frame or several)."""
    got: dict[int, int] = {}

    async def wait():
        async for frame in ws:
            msg = json.loads(frame)
            if msg.get("op") == "subscribe":
                got.update((s["channelId"], s["id"]) for s in msg["subscriptions"])
                if all(c in got for c in channels):
                    return [got[c] for c in channels]
        raise ConnectionError("closed before subscribing")
    return await asyncio.wait_for(wait(), 10)


def _verdicts(la) -> dict:
    return {v.requirement: (v.verdict, v.first_violation.at.time_ns if v.first_violation
                            else None) for v in la.verdicts}


@pytest.mark.parametrize("b_until, b_back, restart, b_leave", [
    (500, None, False, None),   # /b's publisher leaves for good at 0.5 s, the run goes on
    (0, None, False, None),     # ... before its first message was used
    (500, 1200, True, None),    # /b restarts: no message of it from 0.5 s to 1.2 s
    # /b silent from 0.5 s, its publisher gone for good at 1 s: past RD's last tick
    (500, None, False, 1000),
])
@pytest.mark.tor("TOR-WCH-001", "TOR-WCH-002")
def test_the_audit_of_the_recording_equals_the_watch_when_a_publisher_leaves(
        plan, tmp_path, b_until, b_back, restart, b_leave):
    rec = tmp_path / "run.mcap"
    with ScriptServer(_run(b_until, b_back, restart, b_leave)) as srv:
        w = Watch(plan, WatchOptions(url=srv.url, wait=3.0, duration=20, record=str(rec),
                                     restart_grace=3.0 if restart else 0.3))
        live = w.run()
    offline = audit_log(plan, str(rec))
    assert _verdicts(offline) == _verdicts(live), (live.problems, offline.problems)
    # a publisher gone for good sent nothing more: a silence, no loss, so neither run is
    # partial for it; a restart over the Foxglove protocol may have lost the new
    # publisher's first messages (it is subscribed to again after its advertisement)
    assert offline.partial == live.partial == restart
    assert exit_code([offline]) == exit_code([live])
    kinds = {p["kind"] for p in offline.problems}
    assert ("publisher_left" in kinds) == restart
    assert "publisher_left_for_good" not in kinds
    got = _verdicts(live)
    assert got["RA"] == ("violated", T0 + 1500 * MS)  # /a is not affected
    if b_until == 0:  # /b never had a message: its requirements cannot be judged
        assert got["RB"][0] == got["RC"][0] == got["RD"][0] == "error", got
    else:  # a false decides RB without /b; RC needs /b, unknown once it left for good
        assert got["RB"] == ("violated", T0 + 1500 * MS), got
        assert got["RC"][0] == ("satisfied" if restart else "unknown"), got
        # RD reads /b alone: gone for good, its clock is cut where the publisher left (past
        # its last tick when /b fell silent first); restarted, the hole's ticks are unknown
        assert got["RD"][0] == "unknown", got
    if b_until:  # RD watched alone (/b its only topic) is judged as in the set
        (tmp_path / "rd.fret").write_text("@tick_period 100 ms\nRD: the robot shall always "
                                          "satisfy b_ok\n", encoding="utf-8")
        (tmp_path / "rd.bindings.toml").write_text(BINDINGS, encoding="utf-8")
        alone = load_plan(AuditConfig(requirements=(str(tmp_path / "rd.fret"),)))
        with ScriptServer(_run(b_until, b_back, restart, b_leave, b_only=True)) as srv:
            w = Watch(alone, WatchOptions(url=srv.url, wait=3.0, duration=20,
                                          restart_grace=3.0 if restart else 0.3))
            assert _verdicts(w.run())["RD"] == got["RD"]
    src = McapSource(rec)
    assert src.recorded_gaps and all(g.topics == frozenset({"/b"}) for g in src.recorded_gaps)
    assert {g.cause for g in src.recorded_gaps} == {
        "publisher_left" if restart else "publisher_left_for_good"}


@pytest.mark.tor("TOR-DMG-001")
def test_a_record_of_gaps_that_cannot_be_read_is_a_problem_not_a_crash(tmp_path):
    from mcap.writer import Writer

    for bad in ("not json", "[{}]", '[{"start": 1, "end": 0, "topics": null, "cause": ""}]',
                '[{"start": null, "end": 1e3, "topics": null, "cause": ""}]',
                '[{"start": 0, "end": null, "topics": null, "cause": ""}]'):
        with pytest.raises(ValueError):
            parse_gaps(bad)
        path = tmp_path / "r.mcap"
        with open(path, "wb") as f:
            w = Writer(f)
            w.start(profile="", library="fretc watch")
            sid = w.register_schema("std_msgs/msg/Float64", "ros2msg", b"float64 data")
            cid = w.register_channel("/a", "cdr", sid)
            w.add_message(cid, log_time=T0, data=f64(1.0), publish_time=T0)
            w.add_metadata(GAPS_METADATA, {"gaps": bad})
            w.finish()
        src = McapSource(path)
        assert src.partial and src.recorded_gaps == []
        assert [p.kind for p in src.problems] == [P.RECORDED_GAPS], src.problems
    from fretc.logs.base import Gap

    gaps = [Gap(None, 5, frozenset({"/b"}), "publisher_left"), Gap(3, 9, None, "connection_gap")]
    assert parse_gaps(gaps_json(gaps)) == gaps
