"""``fretc watch`` against hostile servers written in the test (tests/live/hostile_ws.py,
127.0.0.1, bounded in time), Foxglove and rosbridge: a frame of the wrong shape is a reported
``protocol`` problem and the session goes on; a server that keeps sending one and dropping is
given up on after a bounded number of connections; a flood of advertised channels is bounded
and reported; a log time at or above 2**63 (or a jump of billions of ticks) is a
``time_range`` problem, the message skipped. None of them passes the run silently."""

from __future__ import annotations

import asyncio
import json
import time

import pytest

pytest.importorskip("websockets")

from hostile_ws import (BINDINGS, FRET, S, T0, ScriptServer, advertise, f64,  # noqa: E402
                        message_data, publish_a, subscription)
from fretc.audit import AuditConfig, load_plan  # noqa: E402
from fretc.live.protocol import MAX_OTHER_CHANNELS  # noqa: E402
from fretc.live.websocket.session import MAX_HOSTILE_SESSIONS  # noqa: E402
from fretc.live.source import PROTOCOL, TIME_RANGE  # noqa: E402
from fretc.live.watch import Watch, WatchOptions  # noqa: E402
from fretc.audit.verdict import exit_code  # noqa: E402

pytestmark = pytest.mark.watch


@pytest.fixture()
def plan(tmp_path):
    (tmp_path / "w.fret").write_text(FRET, encoding="utf-8")
    (tmp_path / "w.bindings.toml").write_text(BINDINGS, encoding="utf-8")
    return load_plan(AuditConfig(requirements=(str(tmp_path / "w.fret"),)))


def _watch(plan, script, url_of=lambda srv: srv.url, subprotocol="foxglove.websocket.v1",
           wait=3.0):
    """Watch ``script`` served on 127.0.0.1 (at most 20 s); (watch, LogAudit, connections,
    seconds)."""
    with ScriptServer(script, subprotocol=subprotocol) as srv:
        w = Watch(plan, WatchOptions(url=url_of(srv), wait=wait, duration=20, backoff=0.02,
                                     max_backoff=0.05))
        t0 = time.monotonic()
        la = w.run()
        return w, la, srv.connections, time.monotonic() - t0


def _kinds(la) -> dict:
    return {p["kind"]: p["detail"] for p in la.problems}


# --------------------------------------------------------------------------- Foxglove
WRONG_SHAPES = ["[]", "1", '"x"', "null", "{not json",
                json.dumps({"op": "advertise", "channels": 5}),
                json.dumps({"op": "advertise", "channels": [[], {"id": 1e300, "topic": "/q"},
                                                            {"id": 9, "topic": 3}]}),
                json.dumps({"op": "unadvertise", "channelIds": "x"}),
                json.dumps({"op": "unadvertise", "channelIds": [[1], {"a": 1}]})]


def test_frames_of_the_wrong_shape_are_protocol_problems_and_the_session_goes_on(plan):
    async def script(ws, k):
        await ws.send(advertise([(1, "/a")]))
        sid = await subscription(ws, 1)
        for frame in WRONG_SHAPES:
            await ws.send(frame)
        await ws.send(b"\x01\x00\x00")  # a messageData frame cut inside its header
        await publish_a(ws, sid)
        await ws.close(1000, "end of the run")

    w, la, connections, _ = _watch(plan, script)
    assert connections == 1  # never dropped
    assert la.messages == {"/a": 20}
    assert [v.verdict for v in la.verdicts] == ["satisfied"]
    assert PROTOCOL in _kinds(la)
    n = sum(c for k, c in la.problem_counts.items() if k.startswith(PROTOCOL))
    assert n >= len(WRONG_SHAPES) + 1
    assert "JSON array" in " ".join(p["detail"] for p in la.problems)
    assert exit_code([la]) == 3  # not a clean run: frames were ignored


def test_a_server_repeating_a_bad_frame_and_dropping_is_given_up_on(plan):
    async def script(ws, k):
        await ws.send(advertise([(1, "/a")]))
        await ws.send("[]")
        await asyncio.sleep(0.05)  # the frame leaves before the connection is cut
        ws.transport.abort()  # no close frame: a network fault to the client

    w, la, connections, took = _watch(plan, script)
    assert connections == MAX_HOSTILE_SESSIONS
    assert took < 10  # not retried until the 20 s duration
    assert "not retried" in w.source.end_reason
    assert PROTOCOL in _kinds(la)
    assert [v.verdict for v in la.verdicts] == ["error"]
    assert exit_code([la]) == 2


def test_a_frame_over_the_size_limit_closes_the_connection_with_the_reason(plan, monkeypatch):
    from fretc.live.websocket import session
    monkeypatch.setattr(session, "MAX_FRAME_BYTES", 4096)

    async def script(ws, k):
        await ws.send(advertise([(1, "/a")]) if k else "x" * 10_000)
        await asyncio.sleep(0.5)
        await ws.close(1000, "end of the run")

    w, la, connections, _took = _watch(plan, script, wait=1.0)
    assert connections >= 2  # the oversized frame cut the first connection; retried
    assert any(e.kind == "disconnected" and "over 4,096 bytes" in e.detail for e in w.events), \
        [(e.kind, e.detail) for e in w.events]


def test_a_flood_of_advertised_channels_is_bounded_and_reported(plan):
    async def script(ws, k):
        await ws.send(advertise([(i + 2, f"/x{i}") for i in range(100_000)] + [(1, "/a")]))
        sid = await subscription(ws, 1)
        await publish_a(ws, sid)
        await ws.close(1000, "end of the run")

    # /a comes in the flood's frame: the watch sees it once the 100,000 advertisements are
    # read, which takes seconds on a loaded machine; a generous wait costs nothing here
    w, la, _, _ = _watch(plan, script, wait=15.0)
    assert [v.verdict for v in la.verdicts] == ["satisfied"]
    assert len(w.source.advertised) == MAX_OTHER_CHANNELS + 1
    assert "more than 1000 channels" in _kinds(la)[PROTOCOL]


def test_a_missing_topic_among_a_flood_names_a_bounded_list(plan):
    async def script(ws, k):
        await ws.send(advertise([(i + 2, f"/x{i}") for i in range(100_000)]))
        await asyncio.sleep(12)
        await ws.close(1000, "end of the run")

    # the watch gives up waiting for /a after 8 s (decoding the 100,000 advertisements takes
    # seconds on a loaded 2-core machine: a shorter wait could end before them)
    w, la, _, _ = _watch(plan, script, wait=8.0)
    assert len(w.source.advertised) == MAX_OTHER_CHANNELS
    err = la.verdicts[0].error
    assert "/a was not advertised" in err and "and 980 more" in err
    assert len(err) < 1000


def test_log_times_outside_int64_and_huge_jumps_are_time_range_problems(plan):
    async def script(ws, k):
        await ws.send(advertise([(1, "/a")]))
        sid = await subscription(ws, 1)
        await publish_a(ws, sid, n=10)
        for t in (2**63, 2**64 - 1, T0 + 10**7 * S):  # the last: 10**8 ticks of 100 ms on
            await ws.send(message_data(sid, t, f64(1.0)))
        await publish_a(ws, sid, n=10, start=T0 + 10 * 50_000_000)
        await ws.close(1000, "end of the run")

    w, la, _, took = _watch(plan, script)
    assert took < 10
    assert la.problem_counts.get(f"{TIME_RANGE} /a") == 3
    assert [v.verdict for v in la.verdicts] == ["satisfied"]
    assert la.verdicts[0].ticks_evaluated == 11  # 0..1 s (the last message at 950 ms), as
    # without them
    assert exit_code([la]) == 3


# --------------------------------------------------------------------------- rosbridge
def _rosbridge(frames_after_subscribe, topics=("/a",), extra_topics=0, rosapi_values=None,
               clock=True):
    """A rosbridge script: rosapi lists ``topics`` (Float64, plus /clock and
    ``extra_topics`` others), then after /a is subscribed sends ``frames_after_subscribe``
    and 20 Float64 messages on /a, each after a /clock at its log time, then closes."""
    async def script(ws, k):
        subscribed = asyncio.Event()

        async def serve():
            async for frame in ws:
                msg = json.loads(frame)
                if msg.get("op") == "call_service":
                    names = list(topics) + ["/clock"] * clock + [
                        f"/x{i}" for i in range(extra_topics)]
                    values = rosapi_values if rosapi_values is not None else {
                        "topics": names, "types": ["std_msgs/msg/Float64"] * len(names)}
                    await ws.send(json.dumps({"op": "service_response", "id": msg["id"],
                                              "result": True, "values": values}))
                elif msg.get("op") == "subscribe" and msg.get("topic") == "/a":
                    subscribed.set()

        reader = asyncio.ensure_future(serve())
        await asyncio.wait_for(subscribed.wait(), 10)
        for frame in frames_after_subscribe:
            await ws.send(frame)
        for i in range(20):
            sec, nsec = divmod(T0 + i * 50_000_000, S)
            await ws.send(json.dumps({"op": "publish", "topic": "/clock",
                                      "msg": {"clock": {"sec": sec, "nanosec": nsec}}}))
            await ws.send(json.dumps({"op": "publish", "topic": "/a", "msg": {"data": 1.0}}))
            await asyncio.sleep(0.002)
        await ws.close(1000, "end of the run")
        reader.cancel()
    return script


def _ros_url(srv) -> str:
    return srv.url.replace("ws://", "rosbridge://")


def test_rosbridge_frames_of_the_wrong_shape_are_protocol_problems(plan):
    frames = ["[]", "1", '"x"', json.dumps({"op": "publish", "topic": ["/a"]}),
              json.dumps({"op": "publish", "topic": "/clock", "msg": {"clock": {"sec": "x"}}})]
    w, la, connections, _ = _watch(plan, _rosbridge(frames), url_of=_ros_url,
                                   subprotocol=None)
    assert connections == 1
    assert la.messages == {"/a": 20}
    assert [v.verdict for v in la.verdicts] == ["satisfied"]
    n = sum(c for k, c in la.problem_counts.items() if k.startswith(PROTOCOL))
    assert n == len(frames)
    assert exit_code([la]) == 3


def test_rosbridge_clock_at_or_above_2_63_is_a_time_range_problem(plan):
    big = json.dumps({"op": "publish", "topic": "/clock",
                      "msg": {"clock": {"sec": 2**40, "nanosec": 0}}})
    after = json.dumps({"op": "publish", "topic": "/a", "msg": {"data": 1.0}})
    w, la, connections, took = _watch(plan, _rosbridge([big, after]), url_of=_ros_url,
                                      subprotocol=None)
    assert took < 10
    assert la.problem_counts.get(f"{TIME_RANGE} /a") == 1
    assert [v.verdict for v in la.verdicts] == ["satisfied"]


def test_rosbridge_flood_of_topics_and_a_rosapi_answer_of_the_wrong_shape(plan):
    w, la, _, _ = _watch(plan, _rosbridge([], extra_topics=100_000), url_of=_ros_url,
                         subprotocol=None)
    assert [v.verdict for v in la.verdicts] == ["satisfied"]
    assert "more than 1000 topics" in _kinds(la)[PROTOCOL]
    w, la, _, _ = _watch(plan, _rosbridge([], rosapi_values=[1, 2]), url_of=_ros_url,
                         subprotocol=None, wait=1.0)
    assert "/rosapi/topics answer" in _kinds(la)[PROTOCOL]
    assert [v.verdict for v in la.verdicts] == ["error"]


POINT_STAMPED = ("std_msgs/Header header\ngeometry_msgs/Point point\n"
                 "================================================================================\n"
                 "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
                 "================================================================================\n"
                 "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
                 "================================================================================\n"
                 "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n")


def _point_stamped(stamp_ns: int, x: float) -> bytes:
    """A CDR ``geometry_msgs/msg/PointStamped`` with frame_id "m" (sec, nanosec, the string
    with its NUL, padding to 8, then x, y, z)."""
    import struct
    body = struct.pack("<iII", stamp_ns // S, stamp_ns % S, 2) + b"m\x00"
    body += b"\x00" * (-len(body) % 8)
    return b"\x00\x01\x00\x00" + body + struct.pack("<ddd", x, 0.0, 0.0)


def test_a_header_stamp_jump_is_skipped_as_a_header_jump_problem(tmp_path):
    """Under the header time base, a stamp 10^7 s past the newest (10^8 ticks of 100 ms) is
    skipped and reported; the watch goes on and ends in time."""
    (tmp_path / "w.fret").write_text(FRET, encoding="utf-8")
    (tmp_path / "w.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\ntime = "header"\nheader_lag = "10 ms"\n'
        '[variables]\na_ok = "/a.point.x > 0"\n', encoding="utf-8")
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "w.fret"),)))

    async def script(ws, k):
        await ws.send(json.dumps({"op": "advertise", "channels": [
            {"id": 1, "topic": "/a", "encoding": "cdr",
             "schemaName": "geometry_msgs/msg/PointStamped", "schema": POINT_STAMPED,
             "schemaEncoding": "ros2msg"}]}))
        sid = await subscription(ws, 1)
        stamps = [T0 + i * 50_000_000 for i in range(10)] + [T0 + 10**7 * S] + \
            [T0 + (10 + i) * 50_000_000 for i in range(10)]
        for i, st in enumerate(stamps):
            await ws.send(message_data(sid, T0 + i * 50_000_000, _point_stamped(st, 1.0)))
            await asyncio.sleep(0.002)
        await ws.close(1000, "end of the run")

    w, la, _, took = _watch(plan, script)
    assert took < 10
    assert la.problem_counts.get("header_jump /a") == 1, la.problem_counts
    assert [v.verdict for v in la.verdicts] == ["satisfied"]


def test_rosbridge_a_deep_frame_costs_one_frame(plan):
    """A JSON frame nested 200,000 deep (and one whose member is): one problem each, and
    every message after them judged."""
    frames = ["[" * 200_000 + "]" * 200_000,
              '{"op": "publish", "topic": "/a", "msg": ' + "[" * 100_000 + "]" * 100_000 + "}"]
    w, la, connections, _ = _watch(plan, _rosbridge(frames), url_of=_ros_url,
                                   subprotocol=None)
    assert connections == 1
    assert la.messages == {"/a": 20}
    assert [v.verdict for v in la.verdicts] == ["satisfied"]
    assert "nested too deep" in " ".join(p["detail"] for p in la.problems)
