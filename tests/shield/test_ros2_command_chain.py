"""The generated ROS 2 node in the command chain, on a real bus (rclpy, Fast DDS): an
independent rclpy node records what reaches it (tests/shield/_bus_peers.py).

* **Commands at the controller's rate.** A controller proposes at 20 Hz (Nav2's), each
  proposal its own number; the LiDAR ticks the shield at 10 Hz. Every proposal is answered
  once, when it arrives (a tick sends a command again only when its message changed): the
  node forwarded at the scan's rate before, 14 commands for 28 proposals, each waiting p50
  51 ms.
* **A controller that dies.** It falls silent: within the node's proposal timeout and a
  tick the command is the fallback's stop, and the last proposal is never sent again (the
  node re-sent it at every tick before, so the base's own command timeout never fired).
  The graph recorded beside the node (receipt times) and audited with the node's allowance
  (``T1: whenever cmd_silent ... within 2 ticks satisfy stopped``, ``cmd_silent`` the
  command's age past the 300 ms timeout) and against S1..S3: 0 violated.
* **An input bound to the proposal topic** (``proposed_velocity = "/cmd_vel.linear.x"``,
  speed and separation's S3) is read from the proposals: no tick reports it unread.
* **A node started before its LiDAR** whose shield lost its state (its belief bounded to 4
  states here, so that the second without scans loses it at every start) knows its state
  again once scans have been read for as long as its requirements look back (R2's 11
  ticks), and releases: it stayed stopped for good before.

Times are the checker's receipt times (the middleware's ``received_timestamp``); the
allowance for the bus is the node's (docs/guide/shield.md, "The node in the command chain"):
its latency budget (20 ms) and one tick of a reader's sampling phase.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
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
#: the node's defaults: proposal timeout (3 ticks of 100 ms), latency budget, tick
TIMEOUT_MS, BUDGET_MS, TICK_MS = 300, 20, 100


def _package(out: Path, reqs: list[str], bindings: str, inputs: str | None = None,
             outputs: str | None = None) -> Path:
    args = ["shield", *(str(REPO / r) for r in reqs), "-b", str(REPO / bindings)]
    args += ["--inputs", inputs] if inputs else []
    args += ["--outputs", outputs] if outputs else []
    got = CliRunner().invoke(main, [*args, "--emit", "ros2", "-o", str(out)])
    assert got.exit_code == 0, got.output
    return next(out.glob("*_shield_ros2"))


def _graph(pkg: Path, log: Path, peers: list[tuple[float, list[str]]], seconds: float
           ) -> list[dict]:
    """Run the node, the checker (``seconds``) and each peer (started ``delay`` s after the
    node: ``(delay, argv)``); the checker's rows."""
    env = {**os.environ, "ROS_DOMAIN_ID": str(10 + os.getpid() % 80)}
    node = subprocess.Popen([sys.executable, "-m", pkg.name],
                            env={**env, "PYTHONPATH": str(pkg)},
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    procs = [subprocess.Popen([sys.executable, PEERS, "checker", str(seconds), str(log)],
                              env=env)]
    try:
        t0 = time.monotonic()
        for delay, argv in sorted(peers, key=lambda p: p[0]):
            time.sleep(max(0.0, delay - (time.monotonic() - t0)))
            procs.append(subprocess.Popen([sys.executable, PEERS, *argv], env=env))
        for p in procs:
            assert p.wait(120) == 0
    finally:
        for p in [node, *procs]:
            if p.poll() is None:
                p.kill()
                p.wait(30)
    return [json.loads(line) for line in log.read_text().splitlines()]


def _of(rows: list[dict], topic: str) -> list[dict]:
    return [r for r in rows if r["topic"] == topic]


@pytest.mark.tor("TOR-SHD-005")
def test_proposals_pass_at_the_controllers_rate_and_a_dead_controller_gets_a_stop(tmp_path):
    pkg = _package(tmp_path / "speed", ["requirements/shield/speed_separation.fret"],
                   "requirements/shield/speed_separation.bindings.toml")
    mcap = tmp_path / "graph.mcap"
    rows = _graph(pkg, tmp_path / "checker.jsonl",
                  [(0.0, ["recorder", "16", str(mcap)]),
                   (0.5, ["sector_lidar", "14", "far:360:360"]),
                   (0.5, ["controller20", "6", "3"])], 16)
    proposals, commands = _of(rows, "/cmd_vel"), _of(rows, "/cmd_vel_filtered")
    assert len(proposals) >= 100, len(proposals)
    last = proposals[-1]["t"]
    # every proposal answered once, when it arrives (3 m ahead: S1..S3 keep each one)
    scans = _of(rows, "/scan")
    assert scans, "no scan"
    # (before the LiDAR's first scan the inputs are unread: the fallback's stop answers)
    steady = [p for p in proposals if p["t"] > max(proposals[0]["t"], scans[0]["t"]) + 500 * MS]
    # (enough to judge the rate by; a loaded machine starts the nodes late: 53 seen once)
    assert len(steady) >= 40, len(steady)
    answers = {p["x"]: [c for c in commands if abs(c["x"] - p["x"]) < 1e-9] for p in steady}
    # (best effort both ways: under load the odd message is lost on the bus, never answered
    # twice; at the scan's rate half of them were never answered)
    twice = {x: len(v) for x, v in answers.items() if len(v) > 1}
    never = [x for x, got in answers.items() if not got]
    assert not twice and len(never) <= 0.1 * len(steady), (twice, never)
    waits = sorted((got[0]["t"] - p["t"]) / MS for p in steady
                   for got in [answers[p["x"]]] if got)
    assert waits[len(waits) // 2] < 15, waits  # p50: not a tick's wait (51 ms before)
    # the input bound to the proposal topic is fed: no tick reports it unread once the
    # controller runs
    diags = [r for r in _of(rows, "/diagnostics")
             if max(proposals[0]["t"], scans[0]["t"]) + 200 * MS < r["t"] < last]
    assert diags and not [r for r in diags if "proposed_velocity" in r["message"]], \
        [r["message"] for r in diags if "proposed_velocity" in r["message"]][:3]
    # the controller dies: a stop within the timeout, a tick and the allowance; the last
    # proposal never again
    after = [c for c in commands if c["t"] > last + 50 * MS]
    stops = [c for c in after if abs(c["x"]) < 1e-9 and abs(c["z"]) < 1e-9]
    assert stops and (stops[0]["t"] - last) / MS <= TIMEOUT_MS + TICK_MS + BUDGET_MS, \
        (stops[:1], last)
    assert not [c for c in after if c["x"] != 0.0], [c for c in after if c["x"] != 0.0][:3]
    # (while the LiDAR still sends: once it has stopped, the scans' staleness is the fault
    # said, which a checker started late on a loaded machine hears before it stops)
    told = [r for r in _of(rows, "/diagnostics")
            if last + TIMEOUT_MS * MS < r["t"] <= scans[-1]["t"]]
    assert told and all("proposal absent" in r["message"] for r in told), told[:2]
    _audit_with_the_allowance(tmp_path, mcap)


def _audit_with_the_allowance(tmp_path: Path, mcap: Path) -> None:
    """The recorded graph audited with the node's reaction allowance (``--allowance
    /cmd_vel_filtered=120ms``: a tick and the latency budget, the answers read that much
    earlier) and the rule as it is stated: once the command is older than the proposal
    timeout (300 ms), the output is the stop at once; and S1..S3 as the node enforced them."""
    reqs = tmp_path / "chain.fret"
    reqs.write_text("@tick_period 100 ms\n"
                    "T1: whenever cmd_silent collision_monitor shall immediately "
                    "satisfy stopped\n", encoding="utf-8")
    bindings = tmp_path / "chain.bindings.toml"
    bindings.write_text('[tick]\nperiod = "100 ms"\ntime = "log"\n[variables]\n'
                        f'cmd_silent = "age(/cmd_vel) > {TIMEOUT_MS / 1000}"\n'
                        'stopped = "abs(/cmd_vel_filtered.linear.x) < 1e-9"\n',
                        encoding="utf-8")
    speed = REPO / "requirements" / "shield" / "speed_separation"
    allowance = f"/cmd_vel_filtered={TICK_MS + BUDGET_MS}ms"
    got = CliRunner().invoke(main, ["audit", "-r", str(speed.with_suffix(".fret")), "-r",
                                    str(reqs), "-b", str(speed) + ".bindings.toml", "-b",
                                    str(bindings), "--allowance", allowance, str(mcap)])
    assert got.exit_code == 0 and "0 violated" in got.output, got.output  # S1..S3, T1
    assert "allowance: /cmd_vel_filtered read 120 ms earlier" in " ".join(
        got.output.split()), got.output


@pytest.mark.tor("TOR-SHD-005")
def test_a_node_started_before_its_lidar_knows_its_state_again_and_releases(tmp_path):
    pkg = _package(tmp_path / "docs", ["requirements/safe_ros.fret",
                                       "requirements/shield/release.fret",
                                       "requirements/shield/sensor_faults.fret"],
                   "requirements/shield/safe_ros_shield.bindings.toml",
                   "too_close,scan_stale,clearance,obstacle_ahead,obstacle_behind,"
                   "scan_invalid,scan_frozen,scan_stamp_stuck",
                   "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed,"
                   "linear_velocity")
    module = pkg / pkg.name / "safe_ros_shield.py"
    text = module.read_text(encoding="utf-8")
    assert "\nBELIEF_LIMIT = 256\n" in text
    # (a belief of 4 states: the second without scans loses the state at every start)
    module.write_text(text.replace("\nBELIEF_LIMIT = 256\n", "\nBELIEF_LIMIT = 4\n"),
                      encoding="utf-8")
    rows = _graph(pkg, tmp_path / "checker.jsonl",
                  [(0.5, ["controller20", "12"]),
                   (2.5, ["sector_lidar", "9", "far:360:360"])], 16)
    scans = _of(rows, "/scan")
    assert scans, "no scan"
    moving = [c for c in _of(rows, "/cmd_vel_filtered")
              if c["t"] > scans[0]["t"] and c["x"] > 0]
    # R2's 11 ticks of look-back, then the first proposal answered
    assert moving and (moving[0]["t"] - scans[0]["t"]) / MS <= 2500, \
        (moving[:1], scans[0]["t"])
    lost = [r for r in _of(rows, "/diagnostics") if "state unknown" in r["message"]]
    assert lost and lost[0]["values"].get("recovery", "").startswith("by itself"), lost[:1]
    assert [r for r in _of(rows, "/diagnostics") if "state known again" in r["message"]]
