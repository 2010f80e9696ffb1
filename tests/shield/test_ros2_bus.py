"""The docs' ROS 2 node on time on a real bus: the node the guide's command
generates (``fretc shield`` of the shipped Safety System, ``--emit ros2``) between a rclpy
controller proposing 0.3 m/s at 10 Hz and a rclpy LiDAR (an obstacle at 0.5 m from 3 s to
6 s, silent from 8 s), judged by an independent rclpy node on receipt
(tests/shield/_bus_peers.py):

* the first stopped command within 1 s of the first near scan (R2);
* no forward command while the obstacle is near (R9: within 0.55 m ahead), from the node's
  reaction allowance after the first near scan on: a proposal that reaches the node before
  its tick reads that scan is answered with the tick before's state (docs/guide/shield.md,
  "The bus allowance": one tick and the latency budget, 120 ms);
* the stop request within 0.8 s of the LiDAR's last scan (R6: stale after 0.3 s, then
  0.5 s);
* no non-zero command while the last stop request received is true (R3).

The node meets its deadlines early by the margin its tick period, a reader's sampling phase
and its latency budget give (no flag): measured on receipt, the first stop came 1,054 ms
after the first near scan and the stop request 894 ms after the last scan when the node met
each deadline at its last tick. Its latency is on ``/diagnostics``.
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

pytestmark = pytest.mark.xdist_group("ros2")

REPO = Path(__file__).resolve().parents[2]
PEERS = str(Path(__file__).with_name("_bus_peers.py"))
MS = 1_000_000
#: the node's reaction allowance: a tick (100 ms) and its latency budget (20 ms)
ALLOWANCE_NS = 120 * MS


def _package(tmp_path: Path) -> Path:
    """The ROS 2 package of the guide's "Safe-ROS end to end" command."""
    got = CliRunner().invoke(main, [
        "shield", str(REPO / "requirements" / "safe_ros.fret"),
        str(REPO / "requirements" / "shield" / "release.fret"),
        str(REPO / "requirements" / "shield" / "sensor_faults.fret"), "-b",
        str(REPO / "requirements" / "shield" / "safe_ros_shield.bindings.toml"), "--inputs",
        "too_close,scan_stale,clearance,obstacle_ahead,obstacle_behind,scan_invalid,"
        "scan_frozen,scan_stamp_stuck", "--outputs",
        "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed,linear_velocity",
        "--emit", "ros2", "-o", str(tmp_path / "shield")])
    assert got.exit_code == 0, got.output
    return tmp_path / "shield" / "safe_ros_shield_ros2"


def _checks(rows: list[dict]) -> dict[str, object]:
    """The four bus checks of the module docstring, from the checker's receipts."""
    scans = [r for r in rows if r["topic"] == "/scan"]
    near = [r["t"] for r in scans if r["min"] < 0.9]
    assert near, "no near scan received"
    first_near, last_scan = near[0], scans[-1]["t"]
    far_after = [r["t"] for r in scans if r["t"] > near[-1] and r["min"] >= 0.9]
    near_end = far_after[0] if far_after else last_scan
    cmds = [r for r in rows if r["topic"] == "/cmd_vel_filtered"]
    stops = [r["t"] for r in cmds if r["t"] > first_near
             and abs(r["x"]) < 1e-3 and abs(r["z"]) < 1e-3]
    forward = [r for r in cmds if first_near + ALLOWANCE_NS < r["t"] < near_end
               and r["x"] > 0]
    requests = [r["t"] for r in rows if r["topic"] == "/gwendolen_control"
                and r["data"] and r["t"] > last_scan]
    moving_while_stopped, stop = [], None
    for r in sorted((r for r in rows if r["topic"] in ("/cmd_vel_filtered",
                                                       "/gwendolen_control")),
                    key=lambda r: r["t"]):
        if r["topic"] == "/gwendolen_control":
            stop = r["data"]
        elif stop and (abs(r["x"]) >= 1e-3 or abs(r["z"]) >= 1e-3):
            moving_while_stopped.append(r)
    return {"stop_ms": (stops[0] - first_near) / MS if stops else None,
            "forward": forward,
            "request_ms": (requests[0] - last_scan) / MS if requests else None,
            "moving_while_stopped": moving_while_stopped}


def test_the_docs_node_meets_the_four_bus_checks(tmp_path):
    pkg = _package(tmp_path)
    env = {**os.environ, "ROS_DOMAIN_ID": str(40 + os.getpid() % 50)}
    log = tmp_path / "checker.jsonl"
    procs = [subprocess.Popen([sys.executable, "-m", "safe_ros_shield_ros2"],
                              env={**env, "PYTHONPATH": str(pkg)}, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE)]
    try:
        procs.append(subprocess.Popen([sys.executable, PEERS, "checker", "20", str(log)],
                                      env=env))
        lidar = subprocess.Popen([sys.executable, PEERS, "lidar", "11"], env=env)
        control = subprocess.Popen([sys.executable, PEERS, "controller", "12"], env=env)
        procs += [lidar, control]
        for p in procs[1:]:
            assert p.wait(120) == 0
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.wait(30)
    rows = [json.loads(line) for line in log.read_text().splitlines()]
    got = _checks(rows)
    assert got["stop_ms"] is not None and got["stop_ms"] <= 1000, got
    assert not got["forward"], got["forward"][:3]
    assert got["request_ms"] is not None and got["request_ms"] <= 800, got
    assert not got["moving_while_stopped"], got["moving_while_stopped"][:3]
    diags = [r for r in rows if r["topic"] == "/diagnostics" and "latency_ms" in r["values"]]
    assert diags and all(r["values"]["margin_ticks"] == "2" for r in diags)
