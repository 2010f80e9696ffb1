"""``fretc watch`` against a foxglove-sdk server on 127.0.0.1: the same verdicts as the audit
of the same trace, a recorded watch audited offline equals the watch, and faults (a dropped
connection, an undecodable schema, a topic never advertised, an unadvertised topic, a clock
going backwards, a payload that does not decode) are data problems, never crashes."""

from __future__ import annotations

import json
import socket
import struct
import threading
import time
from pathlib import Path

import pytest

from _gaps import left_for_good  # noqa: E402

pytest.importorskip("foxglove")
pytest.importorskip("websockets")

from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402
from fretc.live.watch import CLOCK_BACKWARDS, CONNECTION_GAP, UNADVERTISED, Watch, WatchOptions
from fretc.live.websocket.serve import FoxgloveServer, advertise_mcap, replay_mcap  # noqa: E402

pytestmark = pytest.mark.watch

ROOT = Path(__file__).resolve().parents[2]
TRACES = sorted((ROOT / "traces").glob("*.mcap"))
REQS = str(ROOT / "requirements")
RATE = 40.0  # times real time (>= 10x)
S = 1_000_000_000


@pytest.fixture(scope="module")
def plan():
    return load_plan(AuditConfig(requirements=(REQS,)))


def _key(v):
    fv = v.first_violation
    return (v.requirement, v.verdict, v.error is None,
            None if fv is None else (fv.at.tick, fv.at.time_ns),
            None if fv is None or fv.trigger is None else fv.trigger.tick,
            v.ltl3.status, v.ltl3.tick, v.violations, v.triggers, v.ticks_evaluated,
            v.warmup_ticks)


def _watch_trace(plan, trace, rate=RATE, record=None, at=None, backoff=0.05):
    """Serve ``trace`` (its bound topics) at ``rate``, then stop the server: the watch ends
    by itself at the server's close (bounded: stopped after 60 s at most)."""
    server = FoxgloveServer(port=0)
    try:
        w = Watch(plan, WatchOptions(url=server.url, wait=5.0, record=record, backoff=backoff,
                                     max_backoff=0.2, duration=60))
        advertise_mcap(str(trace), server, topics=w.needed)
        done = {}

        def publish():
            try:
                server.wait_subscribed(w.needed & set(server.channels), timeout=60)
                done["sent"], done["last"] = replay_mcap(
                    str(trace), server, rate, topics=w.needed,
                    at=(lambda i: at(i, server, w)) if at else None)
                deadline = time.monotonic() + 30  # the last messages leave
                while (w.source._last_time or 0) < done["last"] and time.monotonic() < deadline:
                    time.sleep(0.02)
            finally:
                server.stop()  # the end of the run: an orderly close

        # same thread-run-join as _run_synthetic below (kept: a recorded trace served here,
        # synthetic messages there, other waits)
        t = threading.Thread(target=publish, daemon=True)
        t.start()
        la = w.run()
        t.join(30)
        return w, la, done
    finally:
        server.stop()


@pytest.mark.parametrize("trace", TRACES, ids=[t.stem for t in TRACES])
@pytest.mark.tor("TOR-WCH-001")
def test_watch_equals_audit(plan, trace):
    w, la, done = _watch_trace(plan, trace)
    ref = audit_log(plan, str(trace))
    assert done["sent"] > 0 and not la.partial and la.error is None
    assert w.source.end_reason.startswith("the server closed the connection")
    assert [_key(v) for v in la.verdicts] == [_key(v) for v in ref.verdicts]
    # the watch produced live events on the way: one ltl3 event per definite LTL3 verdict
    definite = {v.requirement: v.ltl3.status for v in ref.verdicts
                if v.ltl3.status in ("satisfied", "violated")}
    got = {e.requirement: e.verdict for e in w.events if e.kind == "ltl3"}
    assert got == definite
    finals = {e.requirement: e.verdict for e in w.events if e.kind == "final"}
    assert finals == {v.requirement: v.verdict for v in ref.verdicts}


@pytest.mark.tor("TOR-WCH-001")
def test_recorded_watch_audits_to_the_same_verdicts(plan, tmp_path):
    out = tmp_path / "watched.mcap"
    _w, la, _ = _watch_trace(plan, ROOT / "traces" / "stop_delay.mcap", record=str(out))
    again = audit_log(plan, str(out))
    assert [_key(v) for v in again.verdicts] == [_key(v) for v in la.verdicts]
    assert any(v.verdict == "violated" for v in la.verdicts)
    # the recording carries the verdict events, as `fretc report --annotate` writes them
    from mcap.reader import make_reader
    with open(out, "rb") as f:
        topics = {ch.topic for ch in make_reader(f).get_summary().channels.values()}
    assert "/fretc/verdicts" in topics


@pytest.mark.tor("TOR-WCH-002")
def test_dropped_connection_is_a_gap_and_the_watch_goes_on(plan):
    trace = ROOT / "traces" / "sif_disabled.mcap"
    state = {}

    def at(i, server, w):
        if i == 250 and not state:  # the network fails: no close frame, the server goes on
            state["drop"] = True
            w.client.drop()

    w, la, done = _watch_trace(plan, trace, rate=10.0, at=at)
    ref = audit_log(plan, str(trace))
    gaps = [p for p in la.problems if p["kind"] == CONNECTION_GAP]
    assert state and len(gaps) == 1
    g = gaps[0]
    assert g["end_time_ns"] > g["log_time_ns"] + 2 * 100_000_000  # longer than two ticks
    assert "connection lost" in g["detail"]
    assert la.partial and all(v.partial for v in la.verdicts)
    assert w.unknown_ticks > 0
    # ticks inside the gap are unknown, never held over it (the audit's rule for a gap), on
    # each requirement's own clock: as many ticks as the audit, the verdicts three-valued
    # (each the audit's, or unknown)
    for v, rv in zip(la.verdicts, ref.verdicts):
        assert v.unknown_ticks > 0, (v.requirement, v.notes)
        assert v.ticks_evaluated == rv.ticks_evaluated, v.requirement
        assert v.verdict in (rv.verdict, "unknown") or {v.verdict, rv.verdict} == {
            "satisfied", "vacuous"}, (v.requirement, v.verdict, rv.verdict)
    # the watch went on to the end of the run after the gap
    assert la.end_time_ns == ref.end_time_ns
    assert any(e.kind == "gap" for e in w.events)
    assert any(e.kind == "disconnected" for e in w.events)
    # R5 (contact at 15.1 s, after the gap) is still found violated
    r5 = next(v for v in la.verdicts if v.requirement == "R5")
    assert r5.verdict == "violated"


# --------------------------------------------------------------------------- synthetic servers
FLOAT64 = ("std_msgs/msg/Float64", "ros2msg", b"float64 data")


def _f64(x: float) -> bytes:
    return b"\x00\x01\x00\x00" + struct.pack("<d", x)  # CDR little-endian header + value


def _write_reqs(tmp_path, fret, bindings):
    (tmp_path / "w.fret").write_text(fret, encoding="utf-8")
    (tmp_path / "w.bindings.toml").write_text(bindings, encoding="utf-8")
    return load_plan(AuditConfig(requirements=(str(tmp_path / "w.fret"),)))


def _run_synthetic(plan, server, publish, wait=0.5, last=None):
    """Watch ``server`` while ``publish(server)`` runs; stop once the watch used the message
    at log time ``last`` (or 0.3 s after publishing)."""
    w = Watch(plan, WatchOptions(url=server.url, wait=wait))

    def go():
        try:
            server.wait_subscribed(timeout=60)
            publish(server)
            if last is None:
                time.sleep(0.3)
            else:
                deadline = time.monotonic() + 60
                while (w.source._last_time or 0) < last and time.monotonic() < deadline:
                    time.sleep(0.02)
        finally:
            w.stop()

    # same thread-run-join as _watch_trace above (kept: synthetic messages here, a recorded trace
    # there, other waits)
    t = threading.Thread(target=go, daemon=True)
    t.start()
    la = w.run()
    t.join(10)
    return w, la


def jsonl_finals(output: str) -> tuple[list[dict], dict[str, str]]:
    """The JSON lines of ``fretc watch --jsonl``'s output, and the final verdict of each
    requirement."""
    lines = [json.loads(x) for x in output.splitlines() if x.startswith("{")]
    return lines, {x["requirement"]: x["verdict"] for x in lines if x["event"] == "final"}


#: the bindings of /a and /b (tests/live/test_watch_run_end.py too)
AB_BINDINGS = """[tick]
period = "100 ms"
time = "log"
[variables]
a_ok = "/a.data > 0"
b_ok = "/b.data > 0"
"""
BINDINGS = AB_BINDINGS + 'ghost_ok = "/ghost.data > 0"\n'
FRET = """@tick_period 100 ms
RA: the robot shall always satisfy a_ok
RB: the robot shall always satisfy b_ok
RG: the robot shall always satisfy ghost_ok
"""


def test_unknown_topic_and_undecodable_schema_are_errors_for_their_requirements_only(tmp_path):
    plan = _write_reqs(tmp_path, FRET, BINDINGS)
    server = FoxgloveServer(port=0)
    try:
        server.channel("/a", "cdr", *FLOAT64)
        # /b advertises a schema rosbags cannot parse
        server.channel("/b", "cdr", "std_msgs/msg/Float64", "ros2msg", b"float64[[ data !!")

        def publish(srv):
            t0 = 1_700_000_000 * S
            for k in range(20):
                srv.log("/a", _f64(1.0 if k != 12 else -1.0), t0 + k * 50_000_000)
                srv.log("/b", _f64(1.0), t0 + k * 50_000_000)
                time.sleep(0.005)

        w, la = _run_synthetic(plan, server, publish, last=1_700_000_000 * S + 19 * 50_000_000)
    finally:
        server.stop()
    by = {v.requirement: v for v in la.verdicts}
    assert by["RG"].verdict == "error" and "/ghost was not advertised" in by["RG"].error
    assert by["RB"].verdict == "error" and "/b cannot be read" in by["RB"].error
    assert "unknown_schema" in by["RB"].error
    # RA does not depend on the others being broken
    assert by["RA"].verdict == "violated"
    assert by["RA"].first_violation.at.tick == 6  # message 12 at 600 ms, 100 ms ticks
    kinds = {p["kind"] for p in la.problems}
    assert {"unknown_schema", "not_advertised"} <= kinds


def test_bad_payload_and_clock_backwards_are_data_problems_a_publisher_leaving_is_not(
        tmp_path):
    plan = _write_reqs(tmp_path, FRET.replace("RG:", "# RG:"), BINDINGS)
    server = FoxgloveServer(port=0)
    try:
        server.channel("/a", "cdr", *FLOAT64)
        server.channel("/b", "cdr", *FLOAT64)

        def publish(srv):
            t0 = 1_700_000_000 * S
            for k in range(30):
                t = t0 + k * 50_000_000
                srv.log("/a", _f64(1.0), t)
                if k == 10:
                    srv.log("/b", b"\x00\x01", t)  # truncated payload
                elif k == 15:
                    srv.log("/b", _f64(1.0), t - 400_000_000)  # the clock jumps back
                elif k < 20:
                    srv.log("/b", _f64(1.0), t)
                time.sleep(0.005)
                if k == 20:
                    srv.channels["/b"].close()  # unadvertised
                    time.sleep(0.1)

        w, la = _run_synthetic(plan, server, publish, last=1_700_000_000 * S + 29 * 50_000_000)
    finally:
        server.stop()
    kinds = {p["kind"] for p in la.problems}
    assert {"undecodable", CLOCK_BACKWARDS} <= kinds
    # /b's publisher left at k = 20 and the run went on with /a: with no publisher nothing
    # was sent, so its leaving is a "publisher" event, no data problem
    assert UNADVERTISED not in kinds
    assert any(e.kind == "publisher" and UNADVERTISED in (e.detail or "") and "/b" in e.detail
               for e in w.events), [(e.kind, e.detail) for e in w.events]
    by = {v.requirement: v for v in la.verdicts}
    # RB ("always") has an obligation open where /b's publisher left, so it is unknown,
    # never judged on a held value; RA, which does not read /b, is not affected
    assert by["RA"].verdict == "satisfied"
    assert by["RB"].verdict == "unknown"
    assert left_for_good(by["RB"].unknown_reason, "/b"), by["RB"].unknown_reason
    assert la.partial  # (the message not decoded and the one skipped: a loss)
    assert la.ticks_evaluated == 16  # 0 .. 1.5 s: the watch went on to the first tick at or
    # after the last message (1.45 s)


def test_cli_watch_jsonl_and_exit_code(tmp_path):
    """The command end to end (in-process click runner): JSON lines and the audit's exit
    code (1: sif_disabled violates R1, R2, R5)."""

    from click.testing import CliRunner

    from fretc.cli import main

    trace = ROOT / "traces" / "sif_disabled.mcap"
    server = FoxgloveServer(port=0)
    try:
        needed = {"/scan", "/cmd_vel_filtered", "/gwendolen_control", "/ground_truth/clearance"}
        advertise_mcap(str(trace), server, topics=needed)

        def publish():
            try:
                server.wait_subscribed(needed, timeout=20)
                replay_mcap(str(trace), server, 40.0, topics=needed)
                time.sleep(0.3)
            finally:
                server.stop()  # the end of the run: the watch ends without --duration

        t = threading.Thread(target=publish, daemon=True)
        t.start()
        res = CliRunner().invoke(main, ["watch", server.url, "-r", REQS, "--jsonl",
                                        "--no-live", "--duration", "60"])
        t.join(20)
    finally:
        server.stop()
    assert res.exit_code == 1, res.output
    lines, finals = jsonl_finals(res.output)
    assert finals == {"R1": "violated", "R2": "violated", "R3": "vacuous", "R4": "satisfied",
                      "R5": "violated", "R6": "vacuous"}
    assert any(x["event"] == "pt" and x["verdict"] == "violated" for x in lines)
    ends = [x for x in lines if x["event"] == "end"]
    assert len(ends) == 1 and ends[0]["detail"].startswith("the server closed")


def test_live_simulator_equals_the_recorded_trace(plan):
    """``python -m fretc.sim serve``'s engine: the simulator run live on a foxglove-sdk server and
    watched gives the verdicts of the audit of the recorded trace of that scenario."""
    from fretc.sim.serve import serve

    server = FoxgloveServer(port=0)
    try:
        w = Watch(plan, WatchOptions(url=server.url, wait=5.0))
        out = {}

        def run():
            try:
                out["res"] = serve("sif_disabled", rate=20.0, server=server, wait=True)
                time.sleep(0.3)
            finally:
                w.stop()

        t = threading.Thread(target=run, daemon=True)
        t.start()
        la = w.run()
        t.join(30)
    finally:
        server.stop()
    ref = audit_log(plan, str(ROOT / "traces" / "sif_disabled.mcap"))
    assert out["res"].outcome == "contact"
    assert [_key(v) for v in la.verdicts] == [_key(v) for v in ref.verdicts]


def _watch_a_ok(tmp_path, bindings: str, then=None):
    """The watch's audit of ``RA: always a_ok`` over ``bindings``: /a (Float64) published 10
    times at 1.0, 50 ms apart from ``t0``, then ``then(server, t0)`` if given."""
    plan = _write_reqs(tmp_path, "@tick_period 100 ms\nRA: the robot shall always satisfy "
                                 "a_ok\n", bindings)
    server = FoxgloveServer(port=0)
    t0 = 1_700_000_000 * S
    try:
        server.channel("/a", "cdr", *FLOAT64)

        def publish(srv):
            for k in range(10):
                srv.log("/a", _f64(1.0), t0 + k * 50_000_000)
                time.sleep(0.005)
            if then is not None:
                then(srv, t0)

        _w, la = _run_synthetic(plan, server, publish, last=t0 + 9 * 50_000_000)
    finally:
        server.stop()
    return la


def test_a_clock_reset_is_never_a_pass_over_the_messages_it_skipped(tmp_path):
    """The run's clock goes back (a simulator reset): the messages stamped before the last
    one used are skipped, and they held violating values. Was: 'satisfied' (exit 3) over
    them. Each is a message lost at its log time, so the ticks it would have held at are
    unknown: never satisfied."""
    def reset(srv, t0):
        for k in range(10):  # the clock starts again from t0: violating values
            srv.log("/a", _f64(-1.0), t0 + k * 40_000_000)
            time.sleep(0.005)

    la = _watch_a_ok(tmp_path, BINDINGS, then=reset)
    (ra,) = la.verdicts
    assert CLOCK_BACKWARDS in {p["kind"] for p in la.problems}
    assert ra.verdict == "unknown", (ra.verdict, ra.unknown_reason)
    assert la.partial


@pytest.mark.parametrize("args", [["--duration", "nan"], ["--duration", "inf"],
                                  ["--wait", "nan"], ["--connect-timeout", "-inf"]])
def test_watch_time_options_refuse_nan_and_infinities(args):
    """``--duration nan`` compared false with every bound and watched forever."""
    from click.testing import CliRunner

    from fretc.cli import main

    res = CliRunner().invoke(main, ["watch", "ws://127.0.0.1:9", "-r", REQS, *args])
    # fretc's refusal naming the option, not click's wording around it
    assert res.exit_code == 2 and f"'{args[0]}'" in res.output, res.output


def test_a_topic_advertised_with_another_type_than_the_bindings_declare_is_not_read(tmp_path):
    """[types] says std_msgs/msg/Bool, the server advertises /a as Float64: its fields were
    read under the declared names (1.0 as true: satisfied); the audit of such a log is an
    error. Now the topic is unreadable with the reason, its requirement an error."""
    b = ('[tick]\nperiod = "100 ms"\ntime = "log"\n[types]\n"/a" = "std_msgs/Bool"\n'
         '[variables]\na_ok = "/a.data"\n')
    la = _watch_a_ok(tmp_path, b)
    (ra,) = la.verdicts
    assert ra.verdict == "error" and "advertised as std_msgs/msg/Float64" in ra.error


def _first_advertise(url: str) -> set[str]:
    """The topics of the first ``advertise`` frame a Foxglove WebSocket client connecting to
    ``url`` receives (retrying the connection for up to 60 s); it then subscribes to the
    first of them (a server waiting for a subscription goes on)."""
    import json

    from websockets.sync.client import connect

    from fretc.live.websocket.foxglove import SUBPROTOCOLS

    deadline = time.monotonic() + 60
    while True:
        try:
            ws = connect(url, subprotocols=SUBPROTOCOLS, open_timeout=10)
            break
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.01)
    with ws:
        while True:
            frame = ws.recv(timeout=30)
            msg = json.loads(frame) if isinstance(frame, str) else {}
            if msg.get("op") == "advertise":
                first = msg["channels"][0]["id"]
                ws.send(json.dumps({"op": "subscribe",
                                    "subscriptions": [{"id": 0, "channelId": first}]}))
                time.sleep(0.3)  # (the server sees the subscription before the close)
                return {ch["topic"] for ch in msg["channels"]}


def _slow_channels(monkeypatch) -> None:
    """Each channel of a FoxgloveServer takes 0.1 s more to create (a loaded machine): a
    client connecting meanwhile would see only the first ones."""
    make = FoxgloveServer.channel

    def slow(self, *args, **kwargs):
        time.sleep(0.1)
        return make(self, *args, **kwargs)

    monkeypatch.setattr(FoxgloveServer, "channel", slow)


def test_the_simulator_server_advertises_every_topic_in_its_first_frame(monkeypatch):
    """``python -m fretc.sim serve`` starts a run once a client subscribed: a client
    connecting at once must be advertised every topic in one frame, else it subscribes to
    the first ones, the run starts and the others are missed (seen under load: requirements
    in error, "topic /ground_truth/clearance is not advertised")."""
    from fretc.sim.recording import TOPICS
    from fretc.sim.serve import serve

    _slow_channels(monkeypatch)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    t = threading.Thread(target=serve, args=("nominal",), daemon=True,
                         kwargs={"rate": 1000.0, "port": port})
    t.start()
    topics = _first_advertise(f"ws://127.0.0.1:{port}")
    t.join(60)
    assert topics == {topic for topic, _type in TOPICS}


def test_the_replay_server_advertises_every_topic_of_the_log_in_its_first_frame(monkeypatch):
    """``fretc replay LOG --serve`` listens once the log's channels exist (same reason as
    above): the first client is advertised them all in one frame."""
    from click.testing import CliRunner
    from mcap.reader import make_reader

    from fretc.cli import main

    _slow_channels(monkeypatch)
    trace = ROOT / "traces" / "sif_disabled.mcap"
    with open(trace, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    t = threading.Thread(target=CliRunner().invoke, daemon=True, args=(main, [
        "replay", str(trace), "--serve", "--port", str(port), "--rate", "1000"]))
    t.start()
    topics = _first_advertise(f"ws://127.0.0.1:{port}")
    t.join(60)
    assert topics == {ch.topic for ch in summary.channels.values()}
