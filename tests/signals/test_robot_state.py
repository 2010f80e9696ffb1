"""Bindings that reach what robots log, end to end: ``fretc audit`` of a log
written with rosbags' writers (tests/_robot_logs.py) with a FRET mode scope bound to a text
topic, a quoted topic name, a TF pose, a joint by name and a diagnostic by name; each
verdict and first violation compared with the test's own computation from the values it
wrote (not from fretc's code)."""

from __future__ import annotations

import json
import math

import pytest
from click.testing import CliRunner

from fretc.cli import main

import _robot_logs as rl

FRET = """\
M1: in charging mode the robot shall always satisfy battery_charging
S1: the slam shall always satisfy slam_error < 0.3
T1: the robot shall always satisfy map_x < 3.0
T2: the robot shall always satisfy absReal(laser_yaw - expected_laser_yaw) < 0.001
J1: the robot shall always satisfy left_wheel <= 6.0
D1: the robot shall always satisfy ! battery_error
"""

BINDINGS = """\
[tick]
period = "100 ms"

[variables]
charging = '/mode.data = "charging"'
battery_charging = "/battery.power_supply_status = POWER_SUPPLY_STATUS_CHARGING"
slam_error = 'abs("ORB-SLAM".pose.position.x - "groundtruth".pose.position.x)'
map_x = 'tf("map", "base_link").x'
laser_yaw = 'tf("map", "laser").yaw'
expected_laser_yaw = 'tf("map", "laser").yaw'
left_wheel = 'joint(/joint_states.velocity, "wheel_left_joint")'
battery_error = 'max(/diagnostics.status[:]{name=="battery"}.level) >= ERROR'
"""


def _expected(log: rl.RobotLog) -> dict[str, int | None]:
    """Requirement -> the time (ns) of its first violation, None when satisfied."""
    h = rl.held

    def m1(t):
        return h(log, "/mode", t) != "charging" or h(log, "/battery", t) == 1

    def s1(t):
        return abs(h(log, "ORB-SLAM", t)[0] - h(log, "groundtruth", t)[0]) < 0.3

    def j1(t):
        return h(log, "/joint_states", t)["wheel_left_joint"] <= 6.0

    def d1(t):
        return not h(log, "/diagnostics", t) >= 2

    tf = ["/tf", "/tf_static"]
    return {"M1": rl.first_false(log, ["/mode", "/battery"], m1),
            "S1": rl.first_false(log, ["ORB-SLAM", "groundtruth"], s1),
            "T1": rl.first_false(log, tf, lambda t: rl.pose_in_map(log, t)[0] < 3.0),
            "T2": None,
            "J1": rl.first_false(log, ["/joint_states"], j1),
            "D1": rl.first_false(log, ["/diagnostics"], d1)}


@pytest.fixture(scope="module", params=["rosbag2-mcap", "ros1"])
def robot_log(request, tmp_path_factory):
    return rl.write_robot_log(tmp_path_factory.mktemp(request.param),
                              ros1=request.param == "ros1")


def _audit(tmp_path, log_path, fret=FRET, bindings=BINDINGS, codes=(0, 1)):
    req = tmp_path / "req"
    req.mkdir()
    (req / "robot.fret").write_text(fret)
    (req / "robot.bindings.toml").write_text(bindings)
    out = tmp_path / "audit.json"
    res = CliRunner().invoke(main, ["audit", "--no-progress", "-r", str(req), str(log_path),
                                    "--json", str(out)])
    assert res.exit_code in codes, res.output
    doc = json.loads(out.read_text())
    return {v["requirement"]: v for v in doc["logs"][0]["verdicts"]}, res


def test_verdicts_equal_an_independent_computation(tmp_path, robot_log):
    got, res = _audit(tmp_path, robot_log.path)
    want = _expected(robot_log)
    # the log was made so that every requirement but T2 is violated, at different times
    assert [r for r, t in want.items() if t is None] == ["T2"]
    for rid, first in want.items():
        v = got[rid]
        assert v["verdict"] == ("satisfied" if first is None else "violated"), (rid, v)
        if first is not None:
            assert v["first_violation"]["tick_time_ns"] == first, rid
            # one time per event: the terminal gives the JSON's tick time
            assert f"VIOLATED {v['first_violation']['tick_time_s']:.3f} s" in res.output


def test_mode_scope_on_text_judges_only_the_charging_ticks(tmp_path, robot_log):
    """The fault (DISCHARGING at 4.2 s) is inside the charging mode; the same status outside
    it (before 3 s, after 6 s) is no violation."""
    got, _ = _audit(tmp_path, robot_log.path, fret=FRET.splitlines()[0] + "\n")
    fv = got["M1"]["first_violation"]["tick_time_ns"]
    assert 4.2 < (fv - rl.T0) / rl.S <= 4.31  # the first tick after the 4.213 s message


def test_tf_values_equal_an_independent_composition(robot_log):
    """tf() at every tick: x, y and yaw of base_link in map, and the chain's age."""
    from fretc.signals.bindings import TickSpec, make_bindings
    from fretc.signals import sample
    from fretc.logs import open_log
    b = make_bindings({"x": 'tf("map", "base_link").x', "y": 'tf("/map", "base_link").y',
                       "yaw": 'tf("map", "base_link").yaw', "age": 'tf("map", "base_link").age',
                       "back": 'tf("base_link", "map").x', "laser": 'tf("odom", "laser").x'},
                      TickSpec(period_ns=100 * rl.MS))
    n = 0
    for tick in sample(open_log(str(robot_log.path)), b):
        x, y, yaw = rl.pose_in_map(robot_log, tick.time)
        v = tick.values
        assert v["x"] == pytest.approx(x, abs=1e-9) and v["y"] == pytest.approx(y, abs=1e-9)
        assert math.remainder(v["yaw"] - yaw, 2 * math.pi) == pytest.approx(0, abs=1e-9)
        inv = -complex(x, y) * complex(math.cos(-yaw), math.sin(-yaw))  # map in base_link
        assert v["back"] == pytest.approx(inv.real, abs=1e-9)
        ox, oy, oyaw = rl.odom_base(max(tm for tm, _ in robot_log.data["/tf"]
                                        if tm <= tick.time and _[0][0] == "odom"))
        lx, ly, _ = rl.BASE_LASER
        assert v["laser"] == pytest.approx(ox + math.cos(oyaw) * lx - math.sin(oyaw) * ly,
                                           abs=1e-9)
        assert v["age"] == pytest.approx(rl.tf_age(robot_log, tick.time))
        n += 1
    assert n > 90


def test_frames_that_do_not_connect_are_an_error_naming_them(tmp_path, robot_log):
    got, res = _audit(tmp_path, robot_log.path,
                      fret="T9: the robot shall always satisfy far < 1\n",
                      bindings=BINDINGS + 'far = \'tf("map", "gps").x\'\n', codes=(2,))
    assert got["T9"]["verdict"] == "error"
    assert "frames 'map' and 'gps' do not connect" in got["T9"]["error"]
    assert "base_link, laser, map, odom" in got["T9"]["error"]


def test_a_joint_missing_from_the_message_is_an_error(tmp_path, robot_log):
    got, _ = _audit(tmp_path, robot_log.path, fret="J9: the robot shall always satisfy w < 1\n",
                    bindings=BINDINGS + 'w = \'joint(/joint_states.velocity, "arm")\'\n',
                    codes=(2,))
    assert got["J9"]["verdict"] == "error"
    assert "no joint 'arm' (its joints: wheel_" in got["J9"]["error"]


def test_an_unknown_constant_names_the_ones_the_type_declares(tmp_path, robot_log):
    got, _ = _audit(tmp_path, robot_log.path, fret="E9: the robot shall always satisfy e\n",
                    bindings=BINDINGS + "e = '/battery.power_supply_status = CHARGING'\n",
                    codes=(2,))
    assert got["E9"]["verdict"] == "error"
    assert "CHARGING is not a variable of this binding file nor a constant of " \
           "sensor_msgs/msg/BatteryState" in got["E9"]["error"]
    assert "POWER_SUPPLY_STATUS_CHARGING" in got["E9"]["error"]


def test_all_ticks_at_once_equal_the_streamed_ticks(robot_log):
    """sample_arrays (numpy over all ticks; falls back to the stream for text, filters,
    joints and TF) gives the values of sample() for every new form."""
    import numpy as np
    from fretc.signals.bindings import parse_bindings
    from fretc.signals import sample, sample_arrays
    from fretc.logs import open_log
    extra = ('names = \'count(/joint_states.name = "wheel_left_joint")\'\n'
             'first_level = "/diagnostics.status[0].level"\n')
    from fretc.signals.bindings import check_types
    from fretc.logs.schema import log_schemas
    b = parse_bindings(BINDINGS + extra)
    schemas = log_schemas(open_log(str(robot_log.path)))
    for v in b.variables.values():  # named constants from the log's schemas, as the audit
        check_types(v, schemas)
    arrays = sample_arrays(open_log(str(robot_log.path)), b)
    ticks = list(sample(open_log(str(robot_log.path)), b))
    assert list(arrays.times) == [t.time for t in ticks]
    for name in b.variables:
        want = np.array([t.values[name] for t in ticks], dtype=np.float64)
        assert np.array_equal(arrays.columns[name].astype(np.float64), want), name
    assert set(arrays.columns["names"]) == {1.0}
