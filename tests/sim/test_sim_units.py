"""Unit tests of the simulator's parts: ray casting, clearance, LiDAR encoding, SIF state
machine, interceptor, planner, recorder."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from mcap.reader import make_reader

from fretc.sim.navigation import GlobalPlanner, INSPECTION_POINTS
from fretc.sim.recording import McapRecorder
from fretc.sim.robot import Lidar, LidarParams, ScoutMini, ScoutMiniParams, min_valid_range
from fretc.sim.safety import ARMED, MONITORED, STOPPED, CmdVelInterceptor, SafetyAgent, SafetyParams
from fretc.sim.scenarios import SCENARIOS, get_scenario
from fretc.sim.world import Barrel, MovingObstacle, OccupancyMap, RemovedObject, World


@pytest.fixture(scope="module")
def omap():
    return OccupancyMap.load()


@pytest.fixture(scope="module")
def world(omap):
    return World(omap)


def brute_ray(world, x, y, a, step=2e-4, max_range=30.0):
    m = world.omap
    ts = np.arange(0.0, max_range, step)
    r, c = m.cell_of(x + ts * math.cos(a), y + ts * math.sin(a))
    ins = m.inside(r, c)
    hit = np.zeros(ts.shape, bool)
    hit[ins] = world.solid[r[ins], c[ins]]
    return ts[hit.argmax()] if hit.any() else math.inf


def test_map_thresholds(omap):
    # map_server trinary: 0 -> occupied, 205 -> unknown, 254 -> free
    assert omap.grid.shape == (560, 560)
    assert (omap.grid == 100).sum() == 5400
    assert (omap.grid == -1).sum() == 24815
    # row 0 is the bottom of the image (y = origin_y)
    r, c = omap.cell_of(2.61, 2.42)
    assert omap.grid[r, c] == 0
    x, y = omap.cell_centers(r, c)
    assert abs(x - 2.61) <= 0.025 and abs(y - 2.42) <= 0.025


def test_point3_is_closer_to_a_wall_than_the_threshold(omap):
    rows, cols = np.nonzero(omap.grid == 100)
    x, y = omap.cell_centers(rows, cols)
    d = np.hypot(x - 2.61, y - 2.42).min()
    assert 0.55 < d < 0.65


@pytest.mark.parametrize("pose", [(2.61, 2.42, 0.3), (3.4, 1.9, 2.0), (-1.2, -0.8, -1.0)])
def test_raycast_matches_brute_force(world, pose):
    x, y, yaw = pose
    ang = yaw + (-math.pi + np.arange(0, 720, 9) * math.pi / 360)
    got = world.raycast(x, y, ang, 0.0, 30.0)
    want = np.array([brute_ray(world, x, y, a) for a in ang])
    assert np.allclose(got, want, atol=5e-4)


def test_raycast_circles_and_ranges(omap):
    w = World(omap, barrels=(Barrel(1.0, 0.0, 0.15),))
    ang = -math.pi + np.arange(720) * math.pi / 360
    r = w.raycast(0.0, 0.0, ang, 0.0, 30.0)
    assert r[360] == pytest.approx(0.85)  # beam 360 points along +x
    r = World(omap).raycast(0.0, 0.0, ang, 0.0, 0.5)
    assert np.isinf(r).all()  # nothing within 0.5 m of the origin


def test_removed_object_is_gone(omap):
    w = World(omap, removed=(RemovedObject(4.80, -3.55, 0.25),))
    r, c = omap.cell_of(4.80, -3.50)
    assert World(omap).solid[r, c] and not w.solid[r, c]


def test_moving_obstacle_position():
    mv = MovingObstacle(((0.0, 0.0), (1.0, 0.0), (1.0, 1.0)), 0.5, 0.2, 2.0)
    assert mv.position(0.0) == (0.0, 0.0)
    assert mv.position(3.0) == pytest.approx((0.5, 0.0))
    assert mv.position(5.0) == pytest.approx((1.0, 0.5))
    assert mv.position(100.0) == pytest.approx((1.0, 1.0))
    with pytest.raises(ValueError):
        MovingObstacle(((0.0, 0.0),), 0.5, 0.2, 0.0)


def test_clearance_exact(omap):
    w = World(omap, barrels=(Barrel(1.0, 0.0, 0.15),))
    # facing the drum: front edge at x = 0.21, drum surface at x = 0.85
    assert w.clearance(0.0, 0.0, 0.0, 0.0, 0.21, 0.165) == pytest.approx(0.64)
    assert w.clearance(0.64, 0.0, 0.0, 0.0, 0.21, 0.165) == pytest.approx(0.0, abs=1e-12)
    assert w.clearance(0.70, 0.0, 0.0, 0.0, 0.21, 0.165) < 0
    # against the wall cell nearest point 3 (square corner at (3.0, 2.85))
    c = World(omap).clearance(2.61, 2.42, 0.0, 0.0, 0.21, 0.165)
    assert c == pytest.approx(math.hypot(3.0 - 2.82, 2.85 - 2.585), abs=1e-9)
    assert w.clearance_lower_bound(0.0, 0.0, 0.0, 0.27) <= 0.64


def test_lidar_rep117(omap):
    w = World(omap, barrels=(Barrel(0.12, 0.0, 0.05),))  # closer than range_min
    lid = Lidar(LidarParams(p_invalid=0.05), np.random.default_rng(0))
    r = lid.scan(w, 0.0, 0.0, 0.0, 0.0)
    assert r.dtype == np.float32 and r.shape == (720,)
    assert np.isneginf(r).any() and np.isnan(r).any()
    assert min_valid_range(r, 0.1, 30.0) == pytest.approx(0.1)
    lid = Lidar(LidarParams(range_max=1.2, p_invalid=0.0), np.random.default_rng(0))
    r = lid.scan(World(omap), 0.0, 0.0, 0.0, 0.0)
    assert np.isposinf(r).any()
    fin = r[np.isfinite(r)]
    assert fin.max() <= 1.2 and np.allclose(fin / 0.002, np.round(fin / 0.002), atol=1e-3)


def test_min_valid_range():
    assert min_valid_range(np.array([np.nan, np.inf, 2.0, 0.05, 31.0]), 0.1, 30.0) == 2.0
    assert min_valid_range(np.array([np.nan, np.inf]), 0.1, 30.0) == math.inf
    assert min_valid_range(np.array([-np.inf, 3.0]), 0.1, 30.0) == 0.1


def test_base_limits():
    b = ScoutMini(ScoutMiniParams(), 0.0, 0.0, 0.0)
    for _ in range(10):
        b.step(2.0, -2.0, 0.01)
    assert b.state.v == pytest.approx(0.05) and b.state.w == pytest.approx(-0.05)
    for _ in range(200):
        b.step(2.0, 0.0, 0.01)
    assert b.state.v == 0.5
    for _ in range(100):
        b.step(0.0, 0.0, 0.01)
    assert b.state.v == 0.0  # exactly at rest


def test_sif_state_machine():
    a = SafetyAgent(SafetyParams())
    assert a.on_scan(0.0, 2.0, 0.3, 0.0) is None
    assert a.on_scan(0.1, 0.85, 0.3, 0.0) is True and a.state == STOPPED
    assert a.on_scan(0.2, 0.84, 0.1, 0.0) is None           # still braking
    assert a.on_scan(0.3, 0.84, 0.0, 0.0) is None           # at rest from 0.3 s
    assert a.on_scan(1.2, 0.84, 0.0, 0.0) is None           # held 0.9 s
    assert a.on_scan(1.3, 0.84, 0.0, 0.0) is False and a.state == MONITORED
    assert a.on_scan(1.4, 0.80, 0.1, 0.0) is None           # 4 cm closer: allowed
    assert a.on_scan(1.5, 0.78, 0.1, 0.0) is True           # 6 cm closer: stop again
    # below the release floor the stop is never released
    b = SafetyAgent(SafetyParams())
    b.on_scan(0.0, 0.40, 0.0, 0.0)
    for k in range(1, 50):
        assert b.on_scan(0.1 * k, 0.40, 0.0, 0.0) is None
    assert b.state == STOPPED
    # back above the floor (the object moved away): released, then re-armed silently
    assert b.on_scan(6.0, 0.92, 0.0, 0.0) is False and b.state == MONITORED
    assert b.on_scan(6.1, 0.96, 0.0, 0.0) is None and b.state == ARMED
    # clear with hysteresis straight from STOPPED
    c = SafetyAgent(SafetyParams())
    assert c.on_scan(0.0, 0.85, 0.3, 0.0) is True
    assert c.on_scan(0.1, 0.93, 0.2, 0.0) is None
    assert c.on_scan(0.2, 0.96, 0.2, 0.0) is False and c.state == ARMED


def test_sif_monitored_rising_edge_and_speed():
    a = SafetyAgent(SafetyParams())
    assert a.on_scan(0.0, 0.89, 0.0, 0.0) is True
    assert a.on_scan(0.1, 0.91, 0.0, 0.0) is None
    assert a.on_scan(1.1, 0.91, 0.0, 0.0) is False            # release at 0.91 >= threshold
    assert a.on_scan(1.2, 0.899, 0.05, 0.0) is True            # new rising edge: stop
    a.on_scan(2.3, 0.88, 0.0, 0.0)
    assert a.on_scan(3.3, 0.88, 0.0, 0.0) is False
    assert a.on_scan(3.4, 0.88, 0.2, 0.0) is True              # too fast while released
    off = SafetyAgent(SafetyParams(enabled=False))
    assert off.on_scan(0.0, 0.1, 0.5, 0.0) is None


def test_interceptor():
    i = CmdVelInterceptor()
    assert i.on_cmd_vel(0.3, 0.1) == (0.3, 0.1)
    assert i.on_control(True) == (0.0, 0.0)
    assert i.on_cmd_vel(0.3, 0.1) == (0.0, 0.0)
    assert i.on_control(False) is None
    assert i.on_cmd_vel(0.3, 0.1) == (0.3, 0.1)
    f = CmdVelInterceptor(faulty=True)
    assert f.on_control(True) is None
    assert f.on_cmd_vel(0.3, 0.1) == (0.3, 0.1)


def test_planner_paths(omap):
    pl = GlobalPlanner(omap)
    for goal in INSPECTION_POINTS:
        nav = pl.plan(goal)
        path = nav.path_from(-1.2, -0.8, max_length=100.0)
        assert np.hypot(*(path[-1] - np.array(goal))) < 1e-9
        # every path cell keeps the inflation radius from the static map's obstacles
        r, c = omap.cell_of(path[:-1, 0], path[:-1, 1])
        assert (pl.clearance[r, c] >= 0.30).all()
    with pytest.raises(ValueError):
        pl.plan((3.0, 1.1))  # inside a wall


def test_scenarios_registry():
    assert set(SCENARIOS) == {"nominal", "unmapped_obstacles", "dynamic_obstacle",
                              "sif_disabled", "interceptor_fault", "stop_delay",
                              "lidar_dropout"}
    assert get_scenario("stop_delay", 1.5).stop_delay == 1.5
    assert get_scenario("nominal", 1.5).stop_delay == 0.0
    with pytest.raises(KeyError):
        get_scenario("nope")
    with pytest.raises(ValueError):
        get_scenario("stop_delay", -1.0)


@pytest.mark.parametrize("ros1", [False, True])
def test_recorder_profiles(ros1):
    buf = io.BytesIO()
    rec = McapRecorder(buf, ros1=ros1, compression="lz4")
    f = rec.factory
    rec.write("/cmd_vel", 10, f.twist(0.1, 0.2))
    with pytest.raises(ValueError):
        rec.write("/cmd_vel", 5, f.twist(0.1, 0.2))
    with pytest.raises(ValueError):
        rec.write("/nope", 20, f.twist(0.1, 0.2))
    rec.finish()
    reader = make_reader(io.BytesIO(buf.getvalue()))
    assert reader.get_header().profile == ("ros1" if ros1 else "ros2")
    schemas = reader.get_summary().schemas
    twist = [s for s in schemas.values() if s.name.endswith("Twist")][0]
    assert twist.encoding == ("ros1msg" if ros1 else "ros2msg")
    assert b"MSG: geometry_msgs/Vector3" in twist.data
    with pytest.raises(ValueError):
        McapRecorder(io.BytesIO(), compression="gzip")
