"""fretc with ROS 2 itself: ROS 2 Jazzy's rclpy from PyPI on its default middleware (Fast
DDS with its default transports, shared memory and UDP), each peer in a process of its own
(tests/live/_ros2_peers.py), on a domain of its own.

* a rclpy talker (reliable and best-effort topics, a latched ``/map``, header stamps) is
  watched by ``fretc watch dds://D``: the watch's verdicts equal ``fretc audit``'s of the same
  messages recorded by the watch (``--record``), and R3 is violated at the non-zero
  commands sent during a stop;
* the reverse: ``fretc replay --serve dds://D`` is read by a rclpy subscriber with the log's
  types and header stamps; ``--publish-diagnostics`` by a rclpy subscriber as
  ``diagnostic_msgs/DiagnosticArray``;
* services (with ROS 2 service introspection) and actions judged live equal the audit of the
  recording;
* the shield graph: the generated ROS 2 node between a rclpy controller proposing to drive
  on and a rclpy ``/scan`` (an obstacle within 0.9 m for 2 s, then a second with no scan),
  recorded by an independent rclpy
  recorder: ``fretc audit`` finds R2 and R3 satisfied; the same graph unshielded finds them
  violated.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from _ros2 import PEERS, REQ34, ROOT, fretc_run, kill_peers, peer, ros2_domain, started
from _shared import CYCLONEDDS_MISSING, RCLPY_MISSING

pytest.importorskip("rclpy", reason=RCLPY_MISSING)
pytest.importorskip("cyclonedds", reason=CYCLONEDDS_MISSING)

pytestmark = [pytest.mark.watch, pytest.mark.xdist_group("ros2")]


_domain, _peer, _fretc = ros2_domain, peer, fretc_run


@pytest.fixture(autouse=True)
def _no_peer_left_behind():
    """A peer still running when its test ends (the test failed or timed out waiting for
    it) is killed: left behind, it would load the machine for the tests after it."""
    yield
    kill_peers()


def _verdicts(doc: dict) -> dict:
    return {v["requirement"]: (v["verdict"], v.get("first_violation", {}) and
                               v["first_violation"].get("tick"))
            for log in doc["logs"] for v in log["verdicts"]}


def _files(tmp_path: Path, text: str, bindings: str | None = None) -> tuple[str, str]:
    req = tmp_path / "r.fret"
    req.write_text(text, encoding="utf-8")
    b = tmp_path / "r.bindings.toml"
    b.write_text(bindings or (ROOT / "requirements" / "safe_ros.bindings.toml").read_text(),
                 encoding="utf-8")
    return str(req), str(b)


def _watch_and_audit(tmp_path: Path, req: str, b: str, domain: int, seconds: float
                     ) -> tuple[dict, dict, subprocess.CompletedProcess]:
    rec, out = tmp_path / "rec.mcap", tmp_path / "watch.json"
    watch = _fretc("watch", f"dds://{domain}", "-r", req, "-b", b, "--duration",
                   str(seconds), "--record", str(rec), "--json", str(out),
                   timeout=seconds + 60)
    assert out.exists(), watch.stderr[-3000:]
    audit = _fretc("audit", "-r", req, "-b", b, str(rec), "--no-progress", "--json", "-")
    return json.loads(out.read_text()), json.loads(audit.stdout), watch


def test_a_default_rclpy_talker_is_watched_with_the_audits_verdicts(tmp_path):
    # R3 and R4 over reliable topics; M1 over the latched /map (transient local: published
    # before the watch joins) and S1 over the best-effort /scan, stamped
    d = _domain()
    bindings = (ROOT / "requirements" / "safe_ros.bindings.toml").read_text().replace(
        "[variables]\n", '[variables]\nmap_ok = "/map.info.width = 2"\n'
        'scan_ok = "min(/scan.ranges) > 1.5"\n', 1)
    req, b = _files(tmp_path, REQ34 + "M1: the mapper shall always satisfy map_ok\n"
                    "S1: the lidar shall always satisfy scan_ok\n", bindings)
    # the talker steps from when the watch is matched (k = 30 at 3 s) and outlives the watch
    talker = _peer("talker", 12, d)
    time.sleep(3)  # the map is out before the watch joins
    try:
        live, audit, watch = _watch_and_audit(tmp_path, req, b, d, 9)
    finally:
        talker.wait(30)
    assert "never published" not in watch.stdout, watch.stdout
    got, want = _verdicts(live), _verdicts(audit)
    assert got == want, (got, want)
    assert got["R3"][0] == "violated" and got["R4"][0] == "satisfied", got
    assert got["M1"][0] == "satisfied" and got["S1"][0] == "satisfied", got


def test_replay_serve_is_read_by_rclpy_with_its_types_and_stamps(tmp_path):
    d = _domain()
    out = tmp_path / "heard.jsonl"
    listener = _peer("listen", 12, d, str(out))
    time.sleep(2)
    replay = subprocess.Popen([sys.executable, "-m", "fretc", "replay",
                               str(ROOT / "traces" / "nominal.mcap"), "--serve",
                               f"dds://{d}", "--rate", "10"], cwd=ROOT,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    listener.wait(60)
    replay.kill()
    replay.wait(30)
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    topics = {r["topic"] for r in rows}
    assert {"/scan", "/cmd_vel_filtered", "/gwendolen_control"} <= topics, topics
    scans = [r for r in rows if r["topic"] == "/scan"]
    assert scans[0]["n"] > 100  # the LaserScan's ranges, as typed
    # the stamps are the log's: the simulated run starts at 1_700_000_000 s
    assert all(1_700_000_000 * 10**9 <= r["stamp"] < 1_700_000_200 * 10**9 for r in scans)


def test_the_watchs_diagnostics_are_read_by_rclpy(tmp_path):
    d = _domain()
    req, b = _files(tmp_path, REQ34)
    out = tmp_path / "heard.jsonl"
    talker = _peer("talker", 7, d)
    listener = _peer("listen", 9, d, str(out))
    watch = _fretc("watch", f"dds://{d}", "-r", req, "-b", b, "--duration", "8",
                   "--publish-diagnostics", timeout=90)
    talker.wait(30)
    listener.wait(30)
    rows = [json.loads(line) for line in out.read_text().splitlines()
            if json.loads(line)["topic"] == "/diagnostics"]
    assert rows, watch.stderr[-2000:]
    names = {s[0] for r in rows for s in r["status"]}
    assert any("R3" in n for n in names) and any("R4" in n for n in names), names


def test_services_and_actions_live_equal_the_audit_of_the_recording(tmp_path):
    d = _domain()
    bindings = ('[tick]\nperiod = "100 ms"\n[variables]\nwaiting_arm = "waiting(/arm)"\n'
                'arm_called = "called(/arm)"\ngoal_wait = "goal_waiting(/fib)"\n')
    req, b = _files(tmp_path, "@tick_period 100 ms\n"
                    "S1: the arm_service shall always satisfy waiting_arm <= 0.5\n"
                    "S2: the fib_server shall always satisfy goal_wait <= 2\n"
                    "S3: the arm_service shall eventually satisfy arm_called\n", bindings)
    servers = [_peer("services", 8, d), _peer("actions", 8, d)]
    try:
        live, audit, watch = _watch_and_audit(tmp_path, req, b, d, 9)
    finally:
        for p in servers:
            p.wait(30)
    got, want = _verdicts(live), _verdicts(audit)
    assert got == want, (got, want, watch.stdout[-2000:])
    assert got["S1"][0] == "violated", got   # every fourth answer waits 0.7 s
    assert got["S3"][0] == "satisfied", got
    assert got["S2"][0] in ("satisfied", "unknown"), got


def _shield_package(tmp_path: Path) -> Path:
    got = _fretc("shield", str(ROOT / "requirements" / "safe_ros.fret"), "-b",
                 str(ROOT / "requirements" / "safe_ros.bindings.toml"), "--inputs",
                 "too_close,scan_stale,clearance", "--outputs",
                 "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed",
                 # the recorder's audit ticks at another phase than the node, and a loaded
                 # machine delays a message by up to a few ticks: three ticks early
                 "--margin", "3", "--emit", "ros2", "-o", str(tmp_path / "shield"))
    assert got.returncode == 0, got.stderr
    return tmp_path / "shield" / "safe_ros_shield_ros2"


@pytest.mark.parametrize("shielded", [True, False])
def test_the_shield_node_in_a_real_graph_keeps_r2_and_r3(tmp_path, shielded):
    """The generated ROS 2 shield node between a controller and the robot keeps R2, R3 and R6
    on a real rclpy graph (the passthrough breaks R2 and R3), judged by the audit of what a
    recorder heard. The shield publishes a step's stop request and zeroed command together,
    but a loaded machine (the other test worker) can deliver one of them to the recorder a
    tick after the other, and the recording then shows R3 (``immediately``) or R2 broken
    where the node kept them (seen in 1 of 8 runs beside the shield and simulator tests,
    never in runs alone): a shielded graph that breaks one is run once more, on a fresh
    domain, and must keep them there; the first run's verdicts are in the failure
    message."""
    first = _graph_verdicts(tmp_path / "run1", shielded)
    if shielded and not _kept(first[0]):
        got, err = _graph_verdicts(tmp_path / "run2", shielded)
        assert _kept(got), f"second run {got}, first run {first[0]}, {err[-2000:]!r}"
    elif not shielded:
        got = first[0]
        assert got["R2"][0] == "violated" and got["R3"][0] == "violated", got


def _kept(got: dict) -> bool:
    """R2, R3 and R6 satisfied (R3 exercised: the scan dropout makes R6 request a stop)."""
    return all(got[r][0] == "satisfied" for r in ("R2", "R3", "R6"))


def _graph_verdicts(tmp_path: Path, shielded: bool) -> tuple[dict, bytes]:
    """The Safe-ROS verdicts of a recording of the graph (the shield node or the
    passthrough between the controller and the robot), and the guard's stderr."""
    tmp_path.mkdir(parents=True)
    d = _domain()
    rec = tmp_path / "graph.mcap"
    if shielded:
        pkg = _shield_package(tmp_path)
        guard = subprocess.Popen([sys.executable, "-m", "safe_ros_shield_ros2"],
                                 env={**os.environ, "ROS_DOMAIN_ID": str(d),
                                      "PYTHONPATH": str(pkg)},
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        started(guard)
    else:
        guard = _peer("passthrough", 11, d)
    recorder = _peer("record", 10, d, str(rec))
    controller = _peer("controller", 8.5, d)
    controller.wait(120)
    recorder.wait(120)
    guard.terminate()
    try:
        _out, err = guard.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        # (an rclpy process that does not end on SIGTERM within 30 s on a loaded machine:
        # seen once, the passthrough beside the AJPF and live tests; the verdicts are the
        # recorder's, whose recording is complete, so the guard is killed)
        guard.kill()
        _out, err = guard.communicate(timeout=30)
    req = tmp_path / "r23.fret"
    text = (ROOT / "requirements" / "safe_ros.fret").read_text()
    req.write_text(text, encoding="utf-8")
    audit = _fretc("audit", "-r", str(req), "-b",
                   str(ROOT / "requirements" / "safe_ros.bindings.toml"), str(rec),
                   "--no-progress", "--json", "-")
    return _verdicts(json.loads(audit.stdout)), err


@pytest.fixture()
def two_hosts():
    """Two network namespaces joined by a veth pair (10.77.x.1 and .2, multicast on): two
    hosts of one network, for what crosses it; skipped where they cannot be made."""
    import shutil

    if shutil.which("ip") is None or os.geteuid() != 0:
        pytest.skip("two network namespaces need root and iproute2's ip")
    tag = f"{os.getpid() % 10000}"
    a, b, sub = f"fretc_a{tag}", f"fretc_b{tag}", 10 + os.getpid() % 200
    cmds = [["ip", "netns", "add", a], ["ip", "netns", "add", b],
            ["ip", "link", "add", f"va{tag}", "type", "veth", "peer", "name", f"vb{tag}"],
            ["ip", "link", "set", f"va{tag}", "netns", a],
            ["ip", "link", "set", f"vb{tag}", "netns", b],
            ["ip", "-n", a, "addr", "add", f"10.77.{sub}.1/24", "dev", f"va{tag}"],
            ["ip", "-n", b, "addr", "add", f"10.77.{sub}.2/24", "dev", f"vb{tag}"]]
    for ns, dev in ((a, f"va{tag}"), (b, f"vb{tag}")):
        cmds += [["ip", "-n", ns, "link", "set", "lo", "up"],
                 ["ip", "-n", ns, "link", "set", dev, "up", "multicast", "on"],
                 ["ip", "-n", ns, "route", "add", "224.0.0.0/4", "dev", dev]]
    try:
        for c in cmds:
            got = subprocess.run(c, capture_output=True, text=True)
            if got.returncode != 0:
                pytest.skip(f"network namespaces cannot be made here: {got.stderr.strip()}")
        yield a, b
    finally:
        for ns in (a, b):
            subprocess.run(["ip", "netns", "del", ns], capture_output=True)


def test_a_default_rclpy_talker_on_another_host_is_watched(tmp_path, two_hosts):
    a, b = two_hosts
    d = _domain()
    req, bnd = _files(tmp_path, REQ34)
    talker = subprocess.Popen(["ip", "netns", "exec", a, sys.executable, PEERS, "talker", "7"],
                              env={**os.environ, "ROS_DOMAIN_ID": str(d)},
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    started(talker)
    out = tmp_path / "watch.json"
    watch = subprocess.run(["ip", "netns", "exec", b, sys.executable, "-m", "fretc", "watch",
                            f"dds://{d}", "-r", req, "-b", bnd, "--duration", "8", "--json",
                            str(out)], capture_output=True, text=True, timeout=90, cwd=ROOT)
    talker.wait(30)
    assert out.exists(), watch.stderr[-2000:]
    got = _verdicts(json.loads(out.read_text()))
    assert got["R3"][0] == "violated" and got["R4"][0] == "satisfied", (got, watch.stdout)
