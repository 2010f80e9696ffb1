"""The scaffolding of the tests that run ROS 2 itself (ROS 2 Jazzy's rclpy on Fast DDS, each
peer of tests/live/_ros2_peers.py in a process of its own): a domain of this worker's own, a
peer started (and killed when its test ends, pass or fail: left behind it would load the
machine for the tests after it), and fretc run as the user runs it."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from _dds import fresh_domain

ROOT = Path(__file__).resolve().parents[2]
PEERS = str(Path(__file__).with_name("_ros2_peers.py"))

#: R3 and R4 of the Safe-ROS set, over the topics the talker peer publishes
REQ34 = """@tick_period 100 ms
R3: whenever stop_requested cmd_vel_interceptor shall immediately satisfy forwarded_zero
R4: the scout_mini shall always satisfy linear_speed <= 0.5 & angular_speed <= 0.5
"""

_started: list[subprocess.Popen] = []


def ros2_domain() -> int:
    """A ROS_DOMAIN_ID no other test of this worker uses now (1..99)."""
    return fresh_domain(1, 99)


def peer(role: str, seconds: float, domain: int, out: str = "",
         extra_env: dict | None = None) -> subprocess.Popen:
    """Start the rclpy peer ``role`` of tests/live/_ros2_peers.py for ``seconds`` on
    ``domain``; :func:`kill_peers` ends it if it outlives its test."""
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain), **(extra_env or {})}
    p = subprocess.Popen([sys.executable, PEERS, role, str(seconds), out], env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    _started.append(p)
    return p


def started(p: subprocess.Popen) -> subprocess.Popen:
    """Count ``p`` (a process of the test's own: a generated node, a peer in another network
    namespace) among the peers :func:`kill_peers` ends."""
    _started.append(p)
    return p


def kill_peers() -> None:
    """Kill every peer still running (the tests' autouse fixture calls it at their end)."""
    while _started:
        p = _started.pop()
        if p.poll() is None:
            p.kill()
            p.wait(30)


def fretc_run(*args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    """``python -m fretc ARGS`` from the clone's top, to its end."""
    return subprocess.run([sys.executable, "-m", "fretc", *args], capture_output=True,
                          text=True, timeout=timeout, cwd=ROOT,
                          env={**os.environ, "PYTHONPATH": str(ROOT / "src")})


def fretc_start(*args: str) -> subprocess.Popen:
    """``python -m fretc ARGS`` from the clone's top, in the background (text pipes)."""
    return subprocess.Popen([sys.executable, "-m", "fretc", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=ROOT,
                            env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
