"""A LiDAR that fails while it keeps publishing is never a clear path (docs/bindings.md, "A
sensor that fails"): every beam NaN makes ``min(/scan.ranges) < 0.9`` unknown (it was +inf,
false: the audit said satisfied over a blind run), ``invalid()`` counts REP 117's invalid
measurements on a LiDAR of any beam count, ``unchanged()`` sees a frozen frame with fresh
stamps, and a stamp that repeats the scan before's a stuck clock; the shipped Safety System's
requirements (R12, R13, R14) stop the robot on each."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.cli import main

from _logs import scan, write_mcap

REPO = Path(__file__).resolve().parents[2]
PERIOD = 100_000_000


def _run(tmp_path: Path, frames: list[list[float]]) -> Path:
    msgs = [("/scan", "sensor_msgs/msg/LaserScan", 10**9 + k * PERIOD,
             scan(r, 10**9 + k * PERIOD)) for k, r in enumerate(frames)]
    return write_mcap(tmp_path / "run.mcap", msgs)


def _audit(tmp_path: Path, frames, reqs: str, bindings: str) -> tuple[int, dict]:
    import json

    log = _run(tmp_path, frames)
    (tmp_path / "r.fret").write_text("@tick_period 100 ms\n" + reqs)
    (tmp_path / "r.bindings.toml").write_text('[tick]\nperiod = "100 ms"\n[variables]\n'
                                              + bindings)
    got = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"), "-b",
                                    str(tmp_path / "r.bindings.toml"), str(log),
                                    "--no-progress", "--json", str(tmp_path / "a.json")])
    doc = json.loads((tmp_path / "a.json").read_text())
    return got.exit_code, {v["requirement"]: v["verdict"] for v in doc["logs"][0]["verdicts"]}


@pytest.mark.tor("TOR-BND-002")
def test_a_blind_lidar_is_never_judged_a_clear_path(tmp_path):
    """Ten good scans at 3 m, then ten of every beam NaN: ``always !too_close`` was
    satisfied (min of no valid return +inf); now unknown, exit 3 (never 0)."""
    frames = [[3.0 + 0.01 * (k % 3)] * 8 for k in range(10)] + [[math.nan] * 8] * 10
    code, got = _audit(tmp_path, frames, "B: the lidar shall always satisfy !too_close\n",
                       'too_close = "min(/scan.ranges) < 0.9"\n')
    assert got == {"B": "unknown"} and code != 0, got
    # (every beam +inf, no return within range: REP 117's clear view, still satisfied)
    (tmp_path / "clear").mkdir()
    frames = [[3.0 + 0.01 * (k % 3)] * 8 for k in range(10)] + [[math.inf] * 8] * 10
    code, got = _audit(tmp_path / "clear", frames,
                       "B: the lidar shall always satisfy !too_close\n",
                       'too_close = "min(/scan.ranges) < 0.9"\n')
    assert got == {"B": "satisfied"} and code == 0, got


def test_a_frozen_frame_and_a_covered_sector_are_seen(tmp_path):
    """A frame republished bit for bit (fresh log times) makes ``unchanged`` true from the
    second copy; a sector of 3 of 8 beams NaN makes the invalid share 3/8, over a tenth."""
    good = [[3.0 + 0.01 * (k % 3), 2.0, 2.5, 4.0, 3.0, 3.5, 2.2, 2.8] for k in range(6)]
    frames = good + [good[-1]] * 4 + [[math.nan] * 3 + [2.0] * 5] * 3
    code, got = _audit(
        tmp_path, frames,
        "F: the lidar shall always satisfy !scan_frozen\n"
        "I: the lidar shall always satisfy !scan_invalid\n",
        'scan_frozen = "unchanged(/scan.ranges)"\n'
        'scan_invalid = "invalid(/scan.ranges) > 0.1 * (len(/scan.ranges) + '
        'invalid(/scan.ranges))"\n')
    assert got == {"F": "violated", "I": "violated"} and code == 1, got


@settings(max_examples=60, deadline=None)
@given(n=st.integers(4, 1440), share=st.floats(0.0, 1.0))
def test_the_invalid_share_means_the_same_on_any_beam_count(n, share):
    """``invalid(...) > 0.1 * (len(...) + invalid(...))`` is true exactly when more than a
    tenth of the measured beams (valid or invalid; +inf, no return, not counted) are invalid,
    whatever the LiDAR's beam count."""
    from fretc.signals.bindings.files import parse_bindings
    from fretc.signals.bindings.compile import EvalState

    k = int(share * n)
    ranges = [math.nan] * k + [2.0] * (n - k - n // 4) + [math.inf] * (n // 4)
    b = parse_bindings('[tick]\nperiod = "100 ms"\n[variables]\nbad = "invalid(/scan.ranges)'
                       ' > 0.1 * (len(/scan.ranges) + invalid(/scan.ranges))"\n')
    s = EvalState()
    s.msgs["/scan"], s.times["/scan"] = scan(np.array(ranges)), 0
    measured = n - n // 4
    want = k > 0.1 * measured if measured else False
    assert b.variables["bad"].evaluate(s) is want


@pytest.mark.parametrize("fault", ["blind", "frozen", "sector", "stale_stamp"])
def test_the_shipped_safety_system_requests_a_stop_on_each_fault(fault):
    """The shipped bindings and requirements (safe_ros.fret, release.fret, sensor_faults.fret)
    as a shield over messages: a scan that goes blind, freezes, loses a sector or keeps its
    clock's last stamp while the controller drives on at 0.3 m/s gets a stop request and a
    zero command at once (R7 for the unknown too_close, R12, R13, R14 with R3)."""
    from rosbags.typesys import Stores, get_typestore

    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements
    from fretc.shield.build import build_shield
    from fretc.shield.emit_python import tables
    from fretc.shield.messages import MessageShield, default_message
    from fretc.shield.runtime import ShieldRuntime
    from fretc.signals.bindings.files import load_bindings

    reqs = [REPO / "requirements" / "safe_ros.fret",
            REPO / "requirements" / "shield" / "stay_stopped.fret",
            REPO / "requirements" / "shield" / "sensor_faults.fret"]
    b = load_bindings(REPO / "requirements" / "shield" / "safe_ros_shield.bindings.toml")
    shield = build_shield(compile_entries(load_requirements(reqs)),
                          ["too_close", "scan_stale", "clearance", "scan_invalid",
                           "scan_frozen", "scan_stamp_stuck"],
                          ["stopped", "stop_requested", "forwarded_zero", "linear_speed",
                           "angular_speed"], bindings=b, fork=False, name="safe_ros")
    store = get_typestore(Stores.ROS2_JAZZY)
    types = {"/scan": "sensor_msgs/msg/LaserScan", "/cmd_vel": "geometry_msgs/msg/Twist",
             "/cmd_vel_filtered": "geometry_msgs/msg/Twist",
             "/gwendolen_control": "std_msgs/msg/Bool",
             "/ground_truth/clearance": "std_msgs/msg/Float64"}
    ms = MessageShield(ShieldRuntime(tables(shield)), b, {"/cmd_vel_filtered": "/cmd_vel"},
                       lambda t: default_message(store, types[t]))
    rng = np.random.default_rng(0)
    last = None
    for k in range(12):
        t = (k + 1) * PERIOD
        m = default_message(store, types["/scan"])
        m.range_min, m.range_max = 0.1, 10.0
        stamp = t if k < 6 or fault != "stale_stamp" else 6 * PERIOD
        m.header.stamp.sec, m.header.stamp.nanosec = divmod(stamp, 10**9)
        ranges = (3.0 + rng.normal(0, 0.01, 720)).astype("float32")
        if k >= 6:
            if fault == "blind":
                ranges = np.full(720, np.nan, dtype="float32")
            elif fault == "frozen":
                ranges = last
            else:
                ranges = ranges.copy()
                ranges[270:451] = np.nan
        last = ranges
        m.ranges = ranges
        ms.hear("/scan", m, t)
        c = default_message(store, types["/ground_truth/clearance"])
        c.data = 2.0
        ms.hear("/ground_truth/clearance", c, t)
        cmd = default_message(store, types["/cmd_vel"])
        cmd.linear.x = 0.3
        ms.hear("/cmd_vel", cmd, t)
        d, msgs = ms.tick(t)
        out = dict(msgs)
        stop = out["/gwendolen_control"].data
        moving = out["/cmd_vel_filtered"].linear.x
        if k == 0:  # (no scan before the first: scan_frozen unread, any value: a stop)
            assert stop and moving == 0.0 and "scan_frozen" in d.fault, d
        elif k < 6:
            assert not stop and moving == pytest.approx(0.3), (k, d)
        elif k >= 7 or fault not in ("frozen", "stale_stamp"):  # (seen from the 2nd copy)
            assert stop and moving == 0.0, (fault, k, d)
