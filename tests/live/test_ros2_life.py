"""`fretc watch dds://` through a ROS 2 robot's ordinary life, with ROS 2 itself (ROS 2
Jazzy's rclpy on Fast DDS, each node in a process of its own): the watch started before the
nodes (the usual order) gives the verdicts the run deserves, and a LiDAR node that dies
while the rest of the graph runs on is judged by R6 (violated without a stop request,
satisfied with one; never unknown), as `fretc audit` judges an independent recording of the
same run."""

from __future__ import annotations

import json
import time

import pytest

from _ros2 import REQ34, ROOT, fretc_run, fretc_start, kill_peers, peer, ros2_domain
from _shared import CYCLONEDDS_MISSING, RCLPY_MISSING

pytest.importorskip("rclpy", reason=RCLPY_MISSING)
pytest.importorskip("cyclonedds", reason=CYCLONEDDS_MISSING)

pytestmark = [pytest.mark.watch, pytest.mark.xdist_group("ros2")]

R6 = """@tick_period 100 ms
R6: whenever scan_stale safety_system shall within 500 milliseconds satisfy stop_requested
"""


@pytest.fixture(autouse=True)
def _no_peer_left_behind():
    yield
    kill_peers()


def _files(tmp_path, text: str) -> tuple[str, str]:
    req = tmp_path / "r.fret"
    req.write_text(text, encoding="utf-8")
    b = tmp_path / "r.bindings.toml"
    b.write_text((ROOT / "requirements" / "safe_ros.bindings.toml").read_text(),
                 encoding="utf-8")
    return str(req), str(b)


def _verdicts(doc: dict) -> dict:
    return {v["requirement"]: v["verdict"] for log in doc["logs"] for v in log["verdicts"]}


def test_a_watch_started_six_seconds_before_the_nodes_judges_the_run(tmp_path):
    """The defaults (--wait 3) and --until-idle 2: the talker (R3 violated by its one
    command during a stop, R4 satisfied) starts 6 s after the watch."""
    d = ros2_domain()
    req, b = _files(tmp_path, REQ34)
    out = tmp_path / "w.json"
    watch = fretc_start("watch", f"dds://{d}", "-r", req, "-b", b, "--until-idle", "2",
                        "--no-live", "--json", str(out))
    time.sleep(6)
    talker = peer("talker", 8, d)
    try:
        _o, err = watch.communicate(timeout=90)
    finally:
        watch.kill()
        talker.wait(30)
    assert out.exists(), err[-3000:]
    doc = json.loads(out.read_text())
    assert _verdicts(doc) == {"R3": "violated", "R4": "satisfied"}, (doc, err[-2000:])
    assert watch.returncode == 1, err[-2000:]
    assert "waiting" not in doc["logs"][0].get("problem_counts", {})


@pytest.mark.parametrize("stop", [True, False], ids=["stop-requested", "no-stop"])
def test_a_lidar_that_dies_is_judged_live_as_its_recording_is_audited(tmp_path, stop):
    d = ros2_domain()
    req, b = _files(tmp_path, R6)
    out, rec = tmp_path / "w.json", tmp_path / "independent.mcap"
    watch = fretc_start("watch", f"dds://{d}", "-r", req, "-b", b, "--duration", "12",
                        "--wait", "10", "--no-live", "--json", str(out))
    recorder = peer("record_control", 30, d, str(rec))
    control = peer("control", 16, d, "stop" if stop else "")
    time.sleep(1)
    lidar = peer("lidar", 3, d)  # publishes for 3 s and exits
    try:
        _o, err = watch.communicate(timeout=90)
    finally:
        watch.kill()
        for p in (lidar, control, recorder):
            p.wait(60)
    doc = json.loads(out.read_text())
    got = _verdicts(doc)
    assert got == {"R6": "satisfied" if stop else "violated"}, (doc, err[-2000:])
    assert watch.returncode == (0 if stop else 1), err[-2000:]
    # partial only for a message a loaded machine delivered later than the watch's merge
    # holds one (live/merge.py: skipped and reported as clock_backwards; seen once in 250
    # long tests beside the other live tests, 134 ms late), never for anything else
    log = doc["logs"][0]
    assert not log["partial"] or all(k.split()[0] == "clock_backwards"
                                     for k in log["problem_counts"]), log.get("problems")
    audit = fretc_run("audit", "-r", req, "-b", b, str(rec), "--no-progress", "--json", "-")
    assert _verdicts(json.loads(audit.stdout)) == got, audit.stderr[-2000:]
