"""`fretc watch` over the robot's own middleware: `fretc replay LOG --serve dds://D` (Cyclone
DDS) and `--serve zenoh://127.0.0.1:P` (rmw_zenoh's key expressions), each in its own
process, watched by `fretc watch` in another until the publishers leave: the JSON verdicts
and the exit code equal `fretc audit`'s of the same log. Independent subscribers written here
(their own IDL types for std_msgs/Bool and geometry_msgs/Twist, their own key expressions)
receive the replay's messages under ROS 2's wire names (more Zenoh cases:
tests/live/test_watch_zenoh.py). Everything on 127.0.0.1, multicast off."""

import json
import struct
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

from _gaps import left_for_good  # noqa: E402

pytest.importorskip("cyclonedds", reason="cyclonedds (Cyclone DDS) is not installed: "
                    "pip install 'fretc[watch]'")
pytest.importorskip("zenoh", reason="eclipse-zenoh is not installed: pip install 'fretc[watch]'")

from click.testing import CliRunner  # noqa: E402

from fretc.cli import main  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl.types import float64  # noqa: E402
from fretc.live.dds.idl_types import open_participant  # noqa: E402

from _bus import (FLOAT64, REQS, ROOT, T0, audit_json, bus_server, bus_url,  # noqa: E402
                  float64_cdr, free_port, replay, verdicts, watch_process, watch_while,
                  write_watch_files)
from _dds import fresh_domain  # noqa: E402

pytestmark = pytest.mark.watch

TRACES = sorted((ROOT / "traces").glob("*.mcap"))


def _watch_replayed(trace: Path, transport: str, tmp_path, dds_xml: str, *extra: str):
    """Replay ``trace`` over ``transport`` in one process, watch it in another until it ends
    by itself; (exit code, watch JSON, replay's stderr)."""
    url = bus_url(transport)
    out = tmp_path / f"watch-{transport}.json"
    rep = replay(trace, url, dds_xml)
    try:
        res = watch_process(url, ["-r", REQS], out, dds_xml, *extra)
        _o, err = rep.communicate(timeout=30)
    finally:
        rep.kill()
    assert out.exists(), res.stderr + res.stdout
    return res.returncode, json.loads(out.read_text()), err.decode()


def _assert_same(trace, transport, tmp_path, dds_xml, *extra):
    code, audit = audit_json(trace, tmp_path / "audit.json")
    wcode, watch, err = _watch_replayed(trace, transport, tmp_path, dds_xml, *extra)
    assert "sent" in err
    assert verdicts(watch) == verdicts(audit)
    assert watch["logs"][0].get("problems", []) == []
    assert wcode == code
    return audit


@pytest.mark.parametrize("transport", ["dds", "zenoh"])
def test_replayed_trace_watched_to_its_end_equals_the_audit(transport, tmp_path, dds_xml):
    """... and so does the audit of the watch's --record."""
    rec = tmp_path / "rec.mcap"
    audit = _assert_same(ROOT / "traces" / "stop_delay.mcap", transport, tmp_path, dds_xml,
                         "--record", str(rec))
    code, recorded = audit_json(rec, tmp_path / "audit.json")
    assert verdicts(recorded) == verdicts(audit)


@pytest.mark.slow
@pytest.mark.parametrize("transport", ["dds", "zenoh"])
@pytest.mark.parametrize("trace", TRACES, ids=[t.stem for t in TRACES])
def test_every_shipped_trace_over_each_transport_equals_the_audit(trace, transport, tmp_path,
                                                                  dds_xml):
    if trace.stem.endswith("_ros1"):
        pytest.skip("a ROS 1 log: its messages are not CDR, not published on ROS 2 transports")
    _assert_same(trace, transport, tmp_path, dds_xml)


# ------------------------------------------------------------- independent subscribers
def _mcap_values(trace: Path, topic: str, n: int) -> list[bytes]:
    from mcap.reader import make_reader

    with open(trace, "rb") as f:
        return [m.data for _s, c, m in make_reader(f).iter_messages(topics=[topic])][:n]


def _twist(payload: bytes) -> tuple:
    return struct.unpack_from("<6d", payload, 4)


# The test's own IDL types (ROS 2's DDS mapping of geometry_msgs/Twist and std_msgs/Bool,
# members named as rosidl_generator_dds_idl names them: ``data_``), not fretc's run-time
# ones; read with DDS's default type consistency, which compares member names
@dataclass
class Vector3_(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x_: float64
    y_: float64
    z_: float64


@dataclass
class Twist_(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear_: Vector3_
    angular_: Vector3_


@dataclass
class Bool_(IdlStruct, typename="std_msgs::msg::dds_::Bool_"):
    data_: bool


def test_an_independent_dds_subscriber_reads_ros2_wire_names(tmp_path, dds_xml):
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    domain = fresh_domain()
    dp = open_participant(domain, dds_xml)  # configures the domain as the replay's own
    qos = Qos(Policy.Reliability.Reliable(max_blocking_time=10**8), Policy.History.KeepAll)
    tw = DataReader(dp, Topic(dp, "rt/cmd_vel_filtered", Twist_), qos=qos)
    bo = DataReader(dp, Topic(dp, "rt/gwendolen_control", Bool_), qos=qos)
    trace = ROOT / "traces" / "stop_delay.mcap"
    rep = replay(trace, f"dds://{domain}", dds_xml, rate="60")
    twists, bools = [], []
    deadline = time.monotonic() + 40
    while rep.poll() is None and time.monotonic() < deadline:
        twists += tw.take(256)
        bools += bo.take(256)
        time.sleep(0.01)
    twists += tw.take(4096)
    bools += bo.take(4096)
    rep.kill()
    twists = [t for t in twists if t.sample_info.valid_data]  # not the writer's disposal
    bools = [b for b in bools if b.sample_info.valid_data]
    want = _mcap_values(trace, "/cmd_vel_filtered", 10_000)
    assert len(twists) == len(want)
    got = [(t.linear_.x_, t.linear_.y_, t.linear_.z_, t.angular_.x_, t.angular_.y_,
            t.angular_.z_) for t in twists]
    assert got == [_twist(p) for p in want]
    assert [b.data_ for b in bools] == [bool(p[4]) for p in
                                       _mcap_values(trace, "/gwendolen_control", 10_000)]


def test_an_independent_zenoh_subscriber_reads_rmw_zenoh_key_expressions(tmp_path, dds_xml):
    import zenoh

    port = free_port()
    trace = ROOT / "traces" / "stop_delay.mcap"
    rep = replay(trace, f"zenoh://127.0.0.1:{port}?domain=3", dds_xml, rate="60")
    cfg = zenoh.Config()
    cfg.insert_json5("mode", '"peer"')
    cfg.insert_json5("scouting/multicast/enabled", "false")
    cfg.insert_json5("connect/endpoints", f'["tcp/127.0.0.1:{port}"]')
    keys, payloads, tokens = set(), [], set()
    with zenoh.open(cfg) as session:
        session.declare_subscriber("3/cmd_vel_filtered/**",
                                   lambda s: (keys.add(str(s.key_expr)),
                                              payloads.append(s.payload.to_bytes())))
        session.liveliness().declare_subscriber("@ros2_lv/3/**",
                                                lambda s: tokens.add(str(s.key_expr)),
                                                history=True)
        rep.communicate(timeout=60)
        time.sleep(0.3)
    from rosbags.typesys import Stores, get_typestore

    rihs = get_typestore(Stores.ROS2_HUMBLE).hash_rihs01("geometry_msgs/msg/Twist")
    assert keys == {f"3/cmd_vel_filtered/geometry_msgs::msg::dds_::Twist_/{rihs}"}
    assert [_twist(p) for p in payloads] == [
        _twist(p) for p in _mcap_values(trace, "/cmd_vel_filtered", 10_000)]
    assert any(t.split("/")[5] == "MP" and t.split("/")[9] == "%cmd_vel_filtered"
               for t in tokens)


# ------------------------------------------------------------- bad input
def test_a_malformed_url_is_a_usage_error():
    res = CliRunner().invoke(main, ["watch", "dds://999", "-r", REQS, "--no-live"])
    assert res.exit_code == 2
    assert "0..232" in res.output


@pytest.mark.parametrize("transport", ["dds", "zenoh"])
def test_one_publisher_leaving_while_the_run_goes_on_is_unknown_not_held(transport, tmp_path,
                                                                        dds_xml):
    """/b's publisher leaves after 10 messages while /a's goes on for 30: the requirement
    reading /b is ``unknown`` (its "always" obligation is open where /b's publisher left;
    its last value is never held over the rest of the run), the one reading only /a is
    ``satisfied`` (not affected); the run is not partial (nothing was lost: with no
    publisher nothing was sent) and the exit code is 3 (a verdict the run did not decide)."""
    fret = write_watch_files(tmp_path, "RA: the robot shall always satisfy a_ok\n"
                             "RB: the robot shall always satisfy b_ok\n",
                             'a_ok = "/a.data > 0"\nb_ok = "/b.data > 0"\n')
    url = bus_url(transport)
    server = bus_server(url, dds_xml, ("/a", "/b"))
    one = float64_cdr(1.0)

    def publish():
        server.wait_subscribed(["/a", "/b"], timeout=30)
        for k in range(30):
            server.log("/a", one, T0 + k * 100_000_000)
            if k < 10:
                server.log("/b", one, T0 + k * 100_000_000 + 1)
            if k == 10:
                server.unpublish("/b")
            time.sleep(0.05)
        time.sleep(0.3)
        server.stop()

    res, log = watch_while(publish, url, fret, dds_xml)
    by = {v["requirement"]: v for v in log["verdicts"]}
    assert log["messages"] == {"/a": 30, "/b": 10}
    assert by["RA"]["verdict"] == "satisfied"
    assert by["RB"]["verdict"] == "unknown", by["RB"]
    assert left_for_good(by["RB"]["unknown_reason"], "/b"), by["RB"]
    # with no publisher nothing was sent: a silence, not a loss (the run is whole)
    assert not log["partial"] and not log.get("problems"), log.get("problems")
    assert res.exit_code == 3, res.output  # (RB unknown: the run did not decide it)


def test_a_qos_that_cannot_match_is_reported_and_its_requirement_is_not_judged(tmp_path,
                                                                              dds_xml,
                                                                              monkeypatch):
    """A ``/tf_static`` publisher that is not transient-local (REP 105 latches it; the
    watch's reader asks for transient-local) cannot match: a ``protocol`` problem naming
    the topic and the incompatible QoS; the requirement reading it is ``error`` (no
    message), the one reading ``/a`` is judged as usual."""
    from cyclonedds.qos import Policy, Qos
    from fretc.live.dds import idl_types as dds_types

    monkeypatch.setattr(dds_types, "writer_qos", lambda topic="": Qos(
        Policy.Reliability.Reliable(max_blocking_time=10**9), Policy.History.KeepAll,
        Policy.Durability.Volatile))
    fret = write_watch_files(tmp_path, "RA: the robot shall always satisfy a_ok\n"
                             "RT: the robot shall always satisfy t_ok\n",
                             'a_ok = "/a.data > 0"\nt_ok = "/tf_static.data > 0"\n')
    url = bus_url("dds")
    server = bus_server(url, dds_xml, ("/a", "/tf_static"))
    one = float64_cdr(1.0)

    def publish():
        server.wait_subscribed(["/a"], timeout=30)
        time.sleep(0.5)
        for k in range(20):
            server.log("/a", one, T0 + k * 100_000_000)
            server.log("/tf_static", one, T0 + k * 100_000_000 + 1)
            time.sleep(0.02)
        time.sleep(0.3)
        server.stop()

    res, log = watch_while(publish, url, fret, dds_xml)
    by = {v["requirement"]: v for v in log["verdicts"]}
    assert by["RA"]["verdict"] == "satisfied"
    assert by["RT"]["verdict"] == "error" and "/tf_static" in by["RT"]["error"]
    qos = [p for p in log["problems"] if p["kind"] == "protocol" and "QoS" in p["detail"]]
    assert qos and "/tf_static" in qos[0]["detail"], log["problems"]
    assert res.exit_code == 2, res.output


@pytest.mark.parametrize("transport", ["dds", "zenoh"])
def test_on_simulated_time_log_times_come_from_clock(transport, tmp_path, dds_xml):
    """A robot on simulated time publishes ``/clock`` (rosgraph_msgs/Clock): the watch's
    log times are the last ``/clock`` received, not the samples' source timestamps (here a
    wall clock 1.7e9 s away): the violation at simulated second 100.5 is reported there."""
    fret = write_watch_files(tmp_path, "RA: the robot shall always satisfy a_ok\n",
                             'a_ok = "/a.data > 0"\n')
    url = bus_url(transport)
    server = bus_server(url, dds_xml)
    server.channel("/clock", "cdr", "rosgraph_msgs/msg/Clock", "ros2msg",
                   b"builtin_interfaces/Time clock\n" + b"=" * 80
                   + b"\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n")
    assert "/clock" not in server.skipped
    server.channel("/a", *FLOAT64)
    wall = 1_700_000_000 * 10**9

    def publish():
        server.wait_subscribed(["/a"], timeout=30)
        time.sleep(0.5)
        for k in range(20):
            sec, ns = divmod(100 * 10**9 + k * 100_000_000, 10**9)
            server.log("/clock", b"\x00\x01\x00\x00" + struct.pack("<iI", sec, ns), wall)
            time.sleep(0.03)  # the clock first, then the message it dates
            server.log("/a", float64_cdr(-1.0 if k >= 5 else 1.0), wall + k)
            time.sleep(0.03)
        time.sleep(0.3)
        server.stop()

    res, log = watch_while(publish, url, fret, dds_xml)
    (v,) = log["verdicts"]
    assert v["verdict"] == "violated", v
    # on /clock's time (a message may, under load, overtake the /clock before it: one tick)
    assert abs(v["first_violation"]["tick_time_ns"] - (100 * 10**9 + 500_000_000)) <= 10**8
    assert abs(v["first_tick_ns"] - 100 * 10**9) <= 10**8
    assert res.exit_code == 1, res.output



STRING_BINDINGS = {
    "as_variable": ("auto = '/mode.data'", "a variable must be a boolean or a number"),
    "as_number": ("auto = '/mode.data > 3'", "compares numbers"),
    "len_of_string": ("auto = 'len(/mode.data) > 3'", "len() takes an array"),
    "string_with_number": ("auto = '/mode.data == 3'", "compares a string with"),
    "compared": ("auto = '/mode.data == \"auto\"'", None),
}


@pytest.mark.parametrize("transport,case", [
    pytest.param(t, c, marks=[pytest.mark.slow] if t != "ws" and c != "as_variable" else [])
    for t in ("ws", "dds", "zenoh") for c in sorted(STRING_BINDINGS)])
def test_a_string_typed_bound_topic_is_watched_as_it_is_audited(transport, case, tmp_path,
                                                                  dds_xml):
    """A std_msgs/String topic read by a binding that types it wrong: the watch stopped
    with an internal error (KeyError) or judged what the audit refuses; it is the same
    type error as the audit's, and a binding that compares the string is judged as there."""
    import sys as _sys

    _sys.path.insert(0, str(ROOT / "tests"))
    from _logs import MS, ROS2, T, float64, write_mcap

    t0 = 1_700_000_000 * 10**9
    msgs = []
    for k in range(30):
        msgs.append(("/mode", "std_msgs/msg/String", t0 + k * 100 * MS,
                     T(ROS2, "std_msgs/msg/String")(data="auto" if k < 25 else "manual")))
        msgs.append(("/v", "std_msgs/msg/Float64", t0 + k * 100 * MS + MS,
                     float64(9.0 if k == 12 else 1.0)))
    log = write_mcap(tmp_path / "s.mcap", msgs)
    bind, why = STRING_BINDINGS[case]
    (tmp_path / "s.fret").write_text("@tick_period 100 ms\n"
                                     "M: in auto mode the robot shall always satisfy v < 5\n")
    (tmp_path / "s.bindings.toml").write_text(
        f'[tick]\nperiod = "100 ms"\n[variables]\n{bind}\nv = "/v.data"\n')
    reqs = ["-r", str(tmp_path / "s.fret")]
    out = tmp_path / "a.json"
    CliRunner().invoke(main, ["audit", *reqs, str(log), "--json", str(out)])
    audit = json.loads(out.read_text())
    url = bus_url(transport)
    rep = replay(log, url, dds_xml, "10")
    wout = tmp_path / "w.json"
    try:
        res = watch_process(url, reqs, wout, dds_xml, duration="60", timeout=120)
    finally:  # (the watch has ended: the replay is done, or, when the watch refused the
        rep.kill()  # bindings before it subscribed, waits for a subscriber in vain)
    assert "internal error" not in res.stderr + res.stdout, res.stderr
    (v,) = json.loads(wout.read_text())["logs"][0]["verdicts"]
    (a,) = audit["logs"][0]["verdicts"]
    assert (v["verdict"], v["error"]) == (a["verdict"], a["error"]), (v, a)
    if why is None:
        assert v["verdict"] == "violated"
    else:
        assert v["verdict"] == "error" and why in v["error"], v["error"]
