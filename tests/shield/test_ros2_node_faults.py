"""The generated ROS 2 node survives any message (the controller could kill the
Safety System that guards it).

The docs' Safe-ROS node (``--emit ros2``), built and run in a process of its own with ROS 2
Jazzy's rclpy, is given raw CDR messages as its subscriptions give them: a controller
proposing ``linear.x = inf``, then NaN (the node exited, ``TypeError: stopped must be a
boolean, not nan``), bytes that are no Twist; and a node whose input is a
``std_msgs/Float64`` topic given NaN (the ``ValueError`` escaped ``tick_once`` and ended the
spin). The node's publishers are replaced by recorders (no graph, no discovery: what it
would send). Every tick returns; each fault is an ERROR on ``/diagnostics``; the command
sent is the fallback's stop, never the proposal; the ticks after a fault are decided as
usual.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main
from _shared import RCLPY_MISSING

pytest.importorskip("rclpy", reason=RCLPY_MISSING)

REPO = Path(__file__).resolve().parents[2]

DRIVER = r'''
import json, math, sys
import rclpy
pkg, mod = sys.argv[1], sys.argv[2]
sys.path.insert(0, pkg)
node_mod = __import__(mod + ".shield_node", fromlist=["ShieldNode"])
rclpy.init()
node = node_mod.ShieldNode()
store, TYPES = node.store, node_mod.TYPES
sent, diag = [], []
for topic, pub in node.pubs.items():
    pub.publish = (lambda raw, topic=topic: sent.append(
        (topic, store.deserialize_cdr(bytes(raw), TYPES[topic]))))
node.diagnostics.publish = lambda m: diag.append((int.from_bytes(m.status[0].level, "little")
                                                  if isinstance(m.status[0].level, bytes)
                                                  else int(m.status[0].level),
                                                  m.status[0].message))

def raw(topic, **fields):
    from fretc.shield.messages import default_message
    msg = default_message(store, TYPES[topic])
    for k, v in fields.items():
        owner = msg
        path = k.split("__")
        for name in path[:-1]:
            owner = getattr(owner, name)
        setattr(owner, path[-1], v)
    return bytes(store.serialize_cdr(msg, TYPES[topic]))

out = []
t0 = node.now()
for step in json.loads(sys.argv[3]):
    sent.clear(); diag.clear()
    kind, topic, fields = step[:3]
    if len(step) > 3:  # (the node's time: ns after the first step's)
        node.now = (lambda now: lambda: now)(t0 + step[3])
    if kind == "garbage":
        node.hear(topic, b"\x00\x01\x00\x00\xff")
    else:
        if kind == "scan":
            import numpy as np
            fields = dict(fields, ranges=np.full(8, fields.pop("r"), dtype="float32"))
        node.hear(topic, raw(topic, **fields))
    if len(step) < 5:  # (a fifth item: the message alone, the node's own ticks only)
        node.tick_once(node.now())
    out.append({"sent": [(t, getattr(getattr(m, "linear", None), "x", None)
                          if hasattr(m, "linear") else getattr(m, "data", None))
                         for t, m in sent],
                "diag": diag[-1] if diag else None})
node.destroy_node()
rclpy.shutdown()
print(json.dumps(out))
'''


def _package(tmp_path: Path, reqs: Path | list[Path], bindings: Path, inputs: str,
             outputs: str) -> Path:
    files = [str(r) for r in (reqs if isinstance(reqs, list) else [reqs])]
    got = CliRunner().invoke(main, ["shield", *files, "-b", str(bindings), "--inputs",
                                    inputs, "--outputs", outputs, "--emit", "ros2", "-o",
                                    str(tmp_path)])
    assert got.exit_code == 0, got.output
    return tmp_path


def _drive(folder: Path, pkg: str, steps: list) -> list[dict]:
    # (no peer: the publishers are replaced; a domain and a range of their own all the same)
    env = {**os.environ, "ROS_DOMAIN_ID": str(5 + os.getpid() % 90),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    got = subprocess.run([sys.executable, "-c", DRIVER, str(folder / pkg), pkg,
                          json.dumps(steps)], capture_output=True, text=True, timeout=120,
                         env=env)
    assert got.returncode == 0, got.stderr[-3000:]
    out = json.loads(got.stdout.splitlines()[-1])
    for tick in out:
        tick["sent"] = [tuple(x) for x in tick["sent"]]
    return out


SCAN = ["scan", "/scan", {"range_min": 0.1, "range_max": 10.0, "r": 3.0}]


@pytest.mark.tor("TOR-SHD-005")
def test_the_safe_ros_node_survives_an_infinite_or_nan_proposal_and_stops(tmp_path):
    folder = _package(tmp_path, REPO / "requirements" / "safe_ros.fret",
                      REPO / "requirements" / "safe_ros.bindings.toml",
                      "too_close,scan_stale,clearance",
                      "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed")
    steps = [SCAN, ["cmd", "/cmd_vel", {"linear__x": 0.3}], SCAN,
             ["cmd", "/cmd_vel", {"linear__x": float("inf")}],
             ["cmd", "/cmd_vel", {"linear__x": float("nan")}],
             ["garbage", "/cmd_vel", {}], ["cmd", "/cmd_vel", {"linear__x": 0.2}]]
    out = _drive(folder, "safe_ros_shield_ros2", steps)
    ok, warn, error = 0, 1, 2
    # the proposal answered when it arrives; the tick after it sends it again only changed
    assert ("/cmd_vel_filtered", 0.3) in out[1]["sent"], out[1]
    assert out[2]["diag"][0] == ok and ("/cmd_vel_filtered", 0.3) not in out[2]["sent"]
    for k in (3, 4):  # inf, then NaN: the fallback's stop, an ERROR naming the proposal
        assert out[k]["diag"][0] == error and "proposal" in out[k]["diag"][1], out[k]
        assert ("/cmd_vel_filtered", 0.0) in out[k]["sent"], out[k]
    # bytes that are no Twist: reported, not held (the last proposal stays NaN: replaced)
    assert out[5]["diag"][0] == error and "not read" in out[5]["diag"][1], out[5]
    assert ("/cmd_vel_filtered", 0.2) in out[6]["sent"] and out[6]["diag"][0] in (ok, warn)


@pytest.mark.tor("TOR-SHD-005")
def test_a_node_whose_float64_input_is_nan_publishes_the_fallback_and_goes_on(tmp_path):
    reqs = tmp_path / "near.fret"
    reqs.write_text("@tick_period 100 ms\n"
                    "R1: whenever near sw shall immediately satisfy stopped\n"
                    "R2: the sw shall always satisfy speed <= 0.5\n", encoding="utf-8")
    bindings = tmp_path / "near.bindings.toml"
    bindings.write_text('''[tick]
period = "100 ms"
time = "log"
[variables]
near = "/dist.data < 0.5"
stopped = "abs(/cmd_vel_filtered.linear.x) < 1e-3"
speed = "abs(/cmd_vel_filtered.linear.x)"
[shield]
proposals = { "/cmd_vel_filtered" = "/cmd_vel" }
tick = "/dist"
types = { "/dist" = "std_msgs/msg/Float64", "/cmd_vel" = "geometry_msgs/msg/Twist", "/cmd_vel_filtered" = "geometry_msgs/msg/Twist" }
''', encoding="utf-8")
    folder = _package(tmp_path / "out", reqs, bindings, "near", "stopped,speed")
    steps = [["cmd", "/cmd_vel", {"linear__x": 0.4}], ["dist", "/dist", {"data": 2.0}],
             ["dist", "/dist", {"data": float("nan")}], ["dist", "/dist", {"data": 0.2}],
             ["dist", "/dist", {"data": 2.0}]]
    out = _drive(folder, "near_shield_ros2", steps)
    assert ("/cmd_vel_filtered", 0.4) in out[1]["sent"] and out[1]["diag"][0] == 0
    assert out[2]["diag"][0] == 2 and "input near" in out[2]["diag"][1], out[2]
    # (the NaN answered as it comes, then the tick: the fallback's stop alone)
    assert set(out[2]["sent"]) == {("/cmd_vel_filtered", 0.0)}, out[2]
    # R1's stop: the fallback's zero, sent at the tick before, is not sent again (the tick
    # sends a corrected topic again only when its message changed)
    assert out[3]["sent"] in ([], [("/cmd_vel_filtered", 0.0)]) and out[3]["diag"][0] == 1
    assert ("/cmd_vel_filtered", 0.4) in out[4]["sent"] and out[4]["diag"][0] == 0


@pytest.mark.tor("TOR-SHD-005")
def test_a_scan_between_two_ticks_is_answered_at_once(tmp_path):
    """A LiDAR faster than the tick (20 Hz under 100 ms), R7 (a stop at once while too
    close) enforced: a too-close scan 40 ms after the last tick is not a tick, and its stop goes out when it comes (it waited for the next
    proposal before, 50 ms), from the last tick's state, which it does not move."""
    folder = _package(tmp_path, [REPO / "requirements" / "safe_ros.fret",
                                 REPO / "requirements" / "shield" / "stay_stopped.fret"],
                      REPO / "requirements" / "safe_ros.bindings.toml",
                      "too_close,scan_stale,clearance",
                      "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed")
    far = ["scan", "/scan", {"range_min": 0.1, "range_max": 10.0, "r": 3.0}]
    near = ["scan", "/scan", {"range_min": 0.1, "range_max": 10.0, "r": 0.5}]
    ms = 1_000_000
    steps = [[*far, 0, "hear"], ["cmd", "/cmd_vel", {"linear__x": 0.3}, 10 * ms, "hear"],
             [*far, 100 * ms, "hear"], [*near, 140 * ms, "hear"]]
    out = _drive(folder, "safe_ros_shield_ros2", steps)
    assert ("/cmd_vel_filtered", 0.3) in out[1]["sent"], out[1]  # the proposal answered
    assert ("/cmd_vel_filtered", 0.0) in out[3]["sent"], out[3]  # the near scan: a stop
