"""A watch ends only when the run has ended: a publisher that restarts (its topic
unadvertised, then advertised again on a new channel, as foxglove_bridge shows a node
restart) continues the same run, the messages in between a gap; every publisher gone for
longer than the grace period cuts the run short (unknown, exit 3), never a clean pass. Live
input is bounded: a frame that cannot be read costs that frame, a schema too large is a data
problem of its topic, a flood cannot grow memory or outlast ``--duration``."""

from __future__ import annotations

import asyncio
import json
import queue
import time

import pytest

pytest.importorskip("websockets")

from hostile_ws import (BINDINGS, FRET, T0, ScriptServer, advertise, f64,  # noqa: E402
                        message_data, publish_a, subscription)
from fretc.audit import AuditConfig, load_plan  # noqa: E402
from fretc.audit.verdict import exit_code  # noqa: E402
from fretc.common.problems import MAX_PROBLEMS_PER_KIND  # noqa: E402
from fretc.live.events import EventQueue  # noqa: E402
from fretc.live.source import (CLOCK_BACKWARDS, PROTOCOL, PUBLISHER_RESTART,  # noqa: E402
                         PUBLISHERS_LEFT, QUEUE_OVERFLOW, SCHEMA_TOO_LARGE, WatchSource)
from fretc.live.watch import Watch, WatchOptions  # noqa: E402

pytestmark = pytest.mark.watch
MS = 1_000_000


@pytest.fixture()
def plan(tmp_path):
    (tmp_path / "w.fret").write_text(FRET, encoding="utf-8")
    (tmp_path / "w.bindings.toml").write_text(BINDINGS, encoding="utf-8")
    return load_plan(AuditConfig(requirements=(str(tmp_path / "w.fret"),)))


def _watch(plan, script, **options):
    """Watch ``script`` on 127.0.0.1 (``duration`` 20 s unless given); (watch, LogAudit,
    connections, seconds)."""
    options.setdefault("duration", 20)
    with ScriptServer(script) as srv:
        w = Watch(plan, WatchOptions(url=srv.url, wait=3.0, backoff=0.02, max_backoff=0.05,
                                     **options))
        t0 = time.monotonic()
        la = w.run()
        return w, la, srv.connections, time.monotonic() - t0


def _kinds(la) -> set[str]:
    return {p["kind"] for p in la.problems}


def _restart(value_after: float, hold: float = 0.0):
    """10 good messages on /a (channel 1); /a unadvertised and advertised again as channel 2
    (after ``hold`` s); 10 messages of ``value_after`` from 1 s of log time on; close."""
    async def script(ws, k):
        await ws.send(advertise([(1, "/a")]))
        sid = await subscription(ws, 1)
        await publish_a(ws, sid, n=10)
        await ws.send(json.dumps({"op": "unadvertise", "channelIds": [1]}))
        await asyncio.sleep(hold)
        await ws.send(advertise([(2, "/a")]))
        try:
            sid2 = await subscription(ws, 2, timeout=3)
        except (TimeoutError, ConnectionError):
            return  # the watch ended at the unadvertisement (grace 0)
        for i in range(10):
            await ws.send(message_data(sid2, T0 + 1000 * MS + i * 50 * MS, f64(value_after)))
            await asyncio.sleep(0.002)
        await asyncio.sleep(0.2)
        await ws.close(1000, "end of the run")
    return script


def test_a_publisher_restart_continues_the_run_and_the_violation_after_it_is_seen(plan):
    w, la, connections, _ = _watch(plan, _restart(-1.0))
    assert connections == 1
    assert la.messages == {"/a": 20}
    assert [v.verdict for v in la.verdicts] == ["violated"]
    assert la.verdicts[0].first_violation.at.time_ns == T0 + 1000 * MS
    assert PUBLISHER_RESTART in _kinds(la)
    gap = next(p for p in la.problems if p["kind"] == PUBLISHER_RESTART)
    assert "restarted" in gap["detail"] and "not evaluated" in gap["detail"]
    assert exit_code([la]) == 1


@pytest.mark.tor("TOR-WCH-002")
def test_the_messages_of_a_restart_are_a_gap_not_held_over(plan):
    # good values on both sides: the ticks between 450 ms and 1 s were not read, so the run
    # is incomplete (exit 3), and the verdict is never a clean satisfied with exit 0
    w, la, _, _ = _watch(plan, _restart(1.0))
    assert la.partial and PUBLISHER_RESTART in _kinds(la)
    assert la.damage_time_ns == T0 + 450 * MS + 1  # just after the last message before it
    assert w.unknown_ticks >= 4  # ticks 500..900 ms lie inside the gap
    assert exit_code([la]) == 3


def test_with_no_grace_the_unadvertisement_cuts_the_run_short(plan):
    w, la, _, _ = _watch(plan, _restart(-1.0), restart_grace=0.0)
    assert la.messages == {"/a": 10}  # nothing after the cut is used
    assert [v.verdict for v in la.verdicts] == ["unknown"]
    assert PUBLISHERS_LEFT in _kinds(la) and la.partial
    assert exit_code([la]) == 3


def test_publishers_gone_past_the_grace_period_end_the_run_unknown(plan):
    async def script(ws, k):
        await ws.send(advertise([(1, "/a")]))
        sid = await subscription(ws, 1)
        await publish_a(ws, sid, n=10)
        await ws.send(json.dumps({"op": "unadvertise", "channelIds": [1]}))
        await asyncio.sleep(8)  # connection kept open, no publisher

    w, la, _, took = _watch(plan, script, restart_grace=0.5)
    assert took < 8
    assert "none came back within 0.5 s" in w.source.end_reason
    assert [v.verdict for v in la.verdicts] == ["unknown"]
    assert exit_code([la]) == 3
    # the user who said the run ends when the robot goes quiet gets that end
    w, la, _, _ = _watch(plan, script, restart_grace=0.5, until_idle=5.0)
    assert [v.verdict for v in la.verdicts] == ["satisfied"]
    assert PUBLISHERS_LEFT not in _kinds(la)


def test_a_deep_json_frame_costs_one_frame_not_the_session(plan):
    async def script(ws, k):
        await ws.send(advertise([(1, "/a")]))
        sid = await subscription(ws, 1)
        await publish_a(ws, sid, n=10)
        await ws.send("[" * 200_000 + "]" * 200_000)
        await ws.send('{"op": "status", "level": ' + "[" * 100_000 + "]" * 100_000 + "}")
        await publish_a(ws, sid, n=10, start=T0 + 500 * MS)
        await ws.close(1000, "end of the run")

    w, la, connections, _ = _watch(plan, script)
    assert connections == 1
    assert la.messages == {"/a": 20}
    assert [v.verdict for v in la.verdicts] == ["satisfied"]
    assert PROTOCOL in _kinds(la)
    assert "nested too deep" in " ".join(p["detail"] for p in la.problems)


def test_a_schema_over_the_limit_is_a_problem_of_its_topic(plan, monkeypatch):
    from fretc.live import source
    monkeypatch.setattr(source, "MAX_SCHEMA_BYTES", 4096)

    async def script(ws, k):
        big = json.loads(advertise([(1, "/a")]))
        big["channels"][0]["schema"] = "float64 data\n" + "# padding\n" * 1000
        await ws.send(json.dumps(big))
        await asyncio.sleep(0.5)
        await ws.close(1000, "end of the run")

    w, la, _, _ = _watch(plan, script)
    assert [v.verdict for v in la.verdicts] == ["error"]
    assert SCHEMA_TOO_LARGE in la.verdicts[0].error
    assert SCHEMA_TOO_LARGE in _kinds(la)


def test_a_flood_of_old_log_times_is_capped_and_the_duration_holds(plan):
    async def script(ws, k):
        await ws.send(advertise([(1, "/a")]))
        sid = await subscription(ws, 1)
        await publish_a(ws, sid, n=10, start=T0 + 10 * 1000 * MS)
        old = message_data(sid, T0, f64(1.0))
        while True:  # log time going backwards, as fast as the socket takes it
            for _ in range(1000):
                await ws.send(old)
            await asyncio.sleep(0)

    w, la, _, took = _watch(plan, script, duration=3)
    assert took < 3 + 10
    n = la.problem_counts.get(f"{CLOCK_BACKWARDS} /a", 0)
    assert n > MAX_PROBLEMS_PER_KIND  # every one counted ...
    shown = [e for e in w.events if e.kind == "problem" and CLOCK_BACKWARDS in (e.detail or "")]
    assert len(shown) <= MAX_PROBLEMS_PER_KIND  # ... but only so many printed
    assert exit_code([la]) == 3


class _Client:
    def __init__(self, events):
        self.events = events


@pytest.mark.tor("TOR-WCH-002")
def test_the_bounded_queue_drops_the_oldest_messages_and_the_watch_makes_them_a_gap():
    q = EventQueue(max_messages=5)
    q.put(("connected", 0, "foxglove.websocket.v1", ""))
    for i in range(20):
        q.put(("message", "/a", T0 + i * 100 * MS, f64(1.0), 0))
    q.put(("closed", 0, "end"))
    kinds = []
    while True:
        try:
            kinds.append(q.get_nowait())
        except queue.Empty:
            break
    assert [e[0] for e in kinds] == ["connected"] + ["message"] * 5 + ["closed"]
    assert [e[2] for e in kinds[1:6]] == [T0 + i * 100 * MS for i in range(15, 20)]
    q2 = EventQueue(max_messages=5)
    for i in range(20):
        q2.put(("message", "/a", T0 + i * 100 * MS, f64(1.0), 0))
    assert q2.take_dropped() == {"/a": (15, T0, T0 + 1400 * MS)}
    assert q2.take_dropped() == {}

    # the source: a dropped span is a gap between the last message used and the next
    q3 = EventQueue(max_messages=3)
    src = WatchSource("ws://test", _Client(q3), restart_grace=0)
    src.advertised["/a"] = None
    src.decoders["/a"] = lambda payload: object()
    q3.put(("message", "/a", T0, f64(1.0), 0))
    first = src._deliver(*q3.get_nowait()[1:4])
    assert first is not None
    for i in range(1, 11):
        q3.put(("message", "/a", T0 + i * 100 * MS, f64(1.0), 0))
    got = [src._deliver(*q3.get_nowait()[1:4]) for _ in range(3)]
    assert [m.log_time for m in got] == [T0 + i * 100 * MS for i in (8, 9, 10)]
    assert src.gaps == [(T0, T0 + 800 * MS)]
    kinds = {p.kind for p in src.problems}
    assert QUEUE_OVERFLOW in kinds


def _bad_cdr_after_good(resume: bool):
    """10 good /a messages; 10 whose CDR payload is cut short (undecodable); then, if
    ``resume``, 10 good ones again; close."""
    async def script(ws, k):
        await ws.send(advertise([(1, "/a")]))
        sid = await subscription(ws, 1)
        await publish_a(ws, sid, n=10)
        for i in range(10):
            await ws.send(message_data(sid, T0 + 500 * MS + i * 50 * MS, b"\x00\x01\x00\x00\x00"))
            await asyncio.sleep(0.002)
        if resume:
            await publish_a(ws, sid, n=10, start=T0 + 1000 * MS)
        await asyncio.sleep(0.2)
        await ws.close(1000, "end of the run")
    return script


@pytest.mark.parametrize("resume", [False, True])
def test_undecodable_messages_are_a_gap_never_held_over(plan, resume):
    """Live: the last readable value is not carried over the messages that could
    not be decoded; the run is partial and never exits 0."""
    w, la, _c, _s = _watch(plan, _bad_cdr_after_good(resume))
    (v,) = la.verdicts
    assert v.verdict == "unknown", (v.verdict, la.problems)
    assert la.partial and exit_code([la]) == 3
    assert la.problem_counts.get("undecodable /a") == 10, la.problem_counts
    assert "undecodable_gap" in _kinds(la) or resume


def test_a_nan_tick_stops_the_live_monitor_and_the_run_is_judged_before_it(plan):
    """NaN is unread live too: no pt event is made from a NaN value (``!(NaN > 0)`` would be
    a violation in Python), and the final verdict is the audit's: judged before it."""
    async def script(ws, k):
        await ws.send(advertise([(1, "/a")]))
        sid = await subscription(ws, 1)
        await publish_a(ws, sid, n=6)
        await ws.send(message_data(sid, T0 + 300 * MS, f64(float("nan"))))
        await publish_a(ws, sid, n=6, start=T0 + 350 * MS)
        await asyncio.sleep(0.2)
        await ws.close(1000, "end of the run")

    events = []
    with ScriptServer(script) as srv:
        w = Watch(plan, WatchOptions(url=srv.url, wait=3.0, duration=20, backoff=0.02,
                                     max_backoff=0.05), on_event=events.append)
        la = w.run()
    assert [v.verdict for v in la.verdicts] == ["unknown"]
    assert not [e for e in events if e.kind == "pt" and e.verdict == "violated"]
    assert la.problem_counts.get("nan RA") == 1
