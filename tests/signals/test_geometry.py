"""Geometry in the bindings (docs/bindings.md, "Geometry"): the points of a LaserScan and of a
PointCloud2 in the robot's frame, counted in a polygon (fixed, or read from a PolygonStamped
through TF), the time before collision of the footprint moving along a commanded arc, and
trigonometry. Each against an independent computation (shapely's polygons and affine moves,
the points recomputed from the raw messages), the block evaluation against the tick-by-tick
one, on generated logs and on the shipped traces' real LaserScans."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from fretc.common.problems import BindingError
from fretc.logs import open_log
from fretc.signals.arrays import sample_arrays
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.extract import Valid
from fretc.signals.bindings.files import load_bindings, parse_bindings
from fretc.signals.bindings.geometry import Polygon, collision_time, count_inside, laser_points
from fretc.signals.clock import sample

from _logs import MS, ROS2, T, header, scan, twist, write_mcap

shapely = pytest.importorskip("shapely")
from shapely import affinity  # noqa: E402
from shapely.geometry import Point as SPoint  # noqa: E402
from shapely.geometry import Polygon as SPolygon  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
SCOUT = [(0.21, 0.165), (0.21, -0.165), (-0.21, -0.165), (-0.21, 0.165)]
SCOUT_TEXT = "polygon(" + ", ".join(f"{x}, {y}" for x, y in SCOUT) + ")"


def _star(draw: st.DrawFn) -> list[tuple[float, float]]:
    """A simple polygon: vertices at increasing angles around the origin (star-shaped)."""
    n = draw(st.integers(3, 9))
    angles = sorted(draw(st.lists(st.floats(0, 2 * math.pi, exclude_max=True),
                                  min_size=n, max_size=n, unique=True)))
    radii = draw(st.lists(st.floats(0.05, 3.0), min_size=n, max_size=n))
    pts = [(r * math.cos(a), r * math.sin(a)) for a, r in zip(angles, radii)]
    return pts if SPolygon(pts).is_valid and SPolygon(pts).area > 1e-6 else SCOUT


polygons = st.composite(_star)()
coords = st.floats(-4.0, 4.0, allow_nan=False)


def _shapely_count(xs, ys, poly) -> int:
    g = SPolygon(poly)
    return sum(g.covers(SPoint(x, y)) for x, y in zip(xs, ys))


@settings(max_examples=150, deadline=None)
@given(poly=polygons, pts=st.lists(st.tuples(coords, coords), min_size=0, max_size=40),
       on_vertex=st.booleans())
def test_points_in_a_polygon_are_shapelys_covered_points(poly, pts, on_vertex):
    """The count of points inside or on the boundary equals shapely's ``covers`` (a vertex
    itself counted)."""
    if on_vertex:
        pts = pts + [poly[0]]
    xs = np.array([p[0] for p in pts], dtype=float)
    ys = np.array([p[1] for p in pts], dtype=float)
    p = laser_points(Valid(np.zeros((1, len(xs))), np.ones((1, len(xs)), bool)), 0.0, 0.0)
    p.x, p.y = xs.reshape(1, -1), ys.reshape(1, -1)
    got = count_inside(p, Polygon(np.array([v[0] for v in poly]), np.array([v[1] for v in poly])))
    assert got[0] == _shapely_count(p.x[0], p.y[0], poly)


def _shapely_collision(xs, ys, poly, vx, wz, dt, horizon, least=1) -> float:
    """The first k * dt at which shapely's footprint, rotated by wz t about its origin and
    moved to the arc's point (by the unicycle's circle, written apart), covers ``least``
    points."""
    g = SPolygon(poly)
    k = 0
    while k * dt <= horizon * (1 + 1e-12):
        t = k * dt
        if abs(wz) < 1e-12:
            x, y, yaw = vx * t, 0.0, 0.0
        else:
            rad = vx / wz
            yaw = wz * t
            x, y = rad * math.sin(yaw), rad - rad * math.cos(yaw)
        moved = affinity.translate(affinity.rotate(g, yaw, origin=(0, 0), use_radians=True),
                                   x, y)
        if sum(moved.covers(SPoint(a, b)) for a, b in zip(xs, ys)) >= least:
            return t
        k += 1
    return math.inf


@settings(max_examples=100, deadline=None)
@given(pts=st.lists(st.tuples(st.floats(0.3, 2.0), st.floats(-math.pi, math.pi)).map(
           lambda p: (p[0] * math.cos(p[1]), p[0] * math.sin(p[1]))), min_size=1, max_size=25),
       vx=st.floats(-0.8, 0.8), wz=st.one_of(st.just(0.0), st.floats(-1.0, 1.0)),
       least=st.integers(1, 3))
@example(pts=[(0.6, 0.5), (1.2, -0.9)], vx=0.5, wz=0.6, least=1)  # (turning left into one)
@example(pts=[(1.0, 0.0), (0.9, 0.1)], vx=0.4, wz=0.0, least=2)
@example(pts=[(-0.8, 0.2)], vx=-0.3, wz=-0.5, least=1)  # (backing along a right turn)
def test_the_time_before_collision_is_shapelys_swept_footprint(pts, vx, wz, least):
    """The footprint moved along the commanded arc, every 0.1 s up to 3 s: the first time it
    covers ``least`` points is shapely's (the footprint rotated and moved by the arc's pose).
    Points within a micrometre of an edge at a step are left out (the two disagree on
    rounding there)."""
    xs = np.array([p[0] for p in pts])
    ys = np.array([p[1] for p in pts])
    p = laser_points(Valid(np.zeros((1, len(xs))), np.ones((1, len(xs)), bool)), 0.0, 0.0)
    p.x, p.y = xs.reshape(1, -1), ys.reshape(1, -1)
    fp = Polygon(np.array([v[0] for v in SCOUT]), np.array([v[1] for v in SCOUT]))
    got = collision_time(p, fp, vx, wz, 0.1, 3.0, least)[0]
    want = _shapely_collision(xs, ys, SCOUT, vx, wz, 0.1, 3.0, least)
    if got != want:  # (only a point on an edge within rounding may tell them apart)
        t = min(got, want)
        yaw = wz * t
        x, y = ((vx * t, 0.0) if abs(wz) < 1e-12 else
                (vx / wz * math.sin(yaw), vx / wz * (1 - math.cos(yaw))))
        moved = affinity.translate(affinity.rotate(SPolygon(SCOUT), yaw, origin=(0, 0),
                                                   use_radians=True), x, y)
        assert any(moved.exterior.distance(SPoint(a, b)) < 1e-6 for a, b in zip(xs, ys)), (
            got, want)


def test_collision_time_edges():
    """Inside the footprint now: 0; straight ahead at 1 m, 0.5 m/s: the front edge (0.21 m)
    covers it at 1.58 s, so the step of 1.6 s within a 3 s horizon and none within 1.5 s;
    a NaN twist or a blind LiDAR: NaN (unknown)."""
    fp = Polygon(np.array([v[0] for v in SCOUT]), np.array([v[1] for v in SCOUT]))
    p = laser_points(Valid(np.array([[0.1, 1.0]]), np.array([[True, True]])),
                     np.array([0.0]), np.array([0.0]))
    assert collision_time(p, fp, 0.0, 0.0, 0.1, 1.5)[0] == 0.0
    far = laser_points(Valid(np.array([[1.0]]), np.array([[True]])), 0.0, 0.1)
    assert collision_time(far, fp, 0.5, 0.0, 0.1, 3.0)[0] == pytest.approx(1.6)
    assert collision_time(far, fp, 0.5, 0.0, 0.1, 1.5)[0] == math.inf
    assert collision_time(far, fp, -0.5, 0.0, 0.1, 3.0)[0] == math.inf
    assert math.isnan(collision_time(far, fp, math.nan, 0.0, 0.1, 3.0)[0])
    blind = laser_points(Valid(np.array([[math.nan]]), np.array([[False]])), 0.0, 0.1)
    assert math.isnan(collision_time(blind, fp, 0.5, 0.0, 0.1, 3.0)[0])
    assert math.isnan(count_inside(blind, fp)[0])
    left = laser_points(Valid(np.array([[0.7]]), np.array([[True]])), 0.5, 0.0)
    right = laser_points(Valid(np.array([[0.7]]), np.array([[True]])), -0.5, 0.0)
    turning = collision_time(left, fp, 0.5, 0.6, 0.1, 3.0)[0]  # (counter-clockwise: left)
    assert turning < collision_time(right, fp, 0.5, 0.6, 0.1, 3.0)[0]
    assert turning == collision_time(right, fp, 0.5, -0.6, 0.1, 3.0)[0]  # (the mirror image)


def _scan_value(expr: str, msg, twist_msg=None) -> float:
    b = parse_bindings(f"[tick]\nperiod = \"100 ms\"\n[variables]\nv = '{expr}'\n")
    s = EvalState()
    s.msgs["/scan"], s.times["/scan"] = msg, 0
    if twist_msg is not None:
        s.msgs["/cmd_vel"], s.times["/cmd_vel"] = twist_msg, 0
    return b.variables["v"].evaluate(s)


def test_rep117_points():
    """REP 117: NaN, +inf and out-of-range returns are no point; -inf is a detection at
    range_min; every beam NaN is a blind LiDAR (unknown); every beam +inf a clear view (0
    points, no collision)."""
    box = "polygon(1.0, 1.0, -1.0, 1.0, -1.0, -1.0, 1.0, -1.0)"
    m = scan([0.5, math.nan, math.inf, 20.0, -math.inf], range_min=0.1, range_max=10.0)
    assert _scan_value(f"points_in(scan_points(/scan), {box})", m) == 2.0
    assert math.isnan(_scan_value(f"points_in(scan_points(/scan), {box})",
                                  scan([math.nan] * 5)))
    clear = scan([math.inf] * 5)
    assert _scan_value(f"points_in(scan_points(/scan), {box})", clear) == 0.0
    assert _scan_value(f"collision_time(scan_points(/scan), {SCOUT_TEXT}, /cmd_vel.linear.x, "
                       "/cmd_vel.angular.z, 0.1, 2.0)", clear, twist(0.5)) == math.inf


@settings(max_examples=100, deadline=None)
@given(x=st.one_of(st.floats(width=32, allow_infinity=False), st.floats(-10, 10, width=32)),
       y=st.floats(-10, 10, width=32))
def test_trigonometry_is_numpys_item_by_item(x, y):
    """``sin``, ``cos``, ``tan``, ``asin``, ``acos``, ``atan``, ``atan2`` of a field: numpy's
    value (NaN outside asin's and acos's domain), on one number and item by item on an
    array."""
    m = scan([1.0, 2.0, 3.0])
    m.angle_min, m.angle_increment = x, y
    with np.errstate(all="ignore"):
        for f, ref in (("sin", np.sin), ("cos", np.cos), ("tan", np.tan), ("asin", np.arcsin),
                       ("acos", np.arccos), ("atan", np.arctan)):
            got = _scan_value(f"{f}(/scan.angle_min)", m)
            want = float(ref(np.float64(m.angle_min)))
            assert got == want or (math.isnan(got) and math.isnan(want)), f
        got = _scan_value("atan2(/scan.angle_min, /scan.angle_increment)", m)
        want = float(np.arctan2(np.float64(m.angle_min), np.float64(m.angle_increment)))
        assert got == want or (math.isnan(got) and math.isnan(want))
        assert _scan_value("max(sin(/scan.ranges))", m) == float(np.sin(np.array([1.0, 2.0,
                                                                                  3.0])).max())


def _blocks_equal_ticks(log: Path, text: str) -> dict[str, np.ndarray]:
    """The block evaluation (the audit's) and the tick-by-tick one (the watch's clock) of the
    bindings ``text`` on ``log``: equal at every tick (NaN equal); the columns."""
    b = parse_bindings(text)
    _times, cols = sample_arrays(open_log(log), b)
    ticks = list(sample(open_log(log), b))
    for v in cols:
        x = np.asarray(cols[v], dtype=float)
        y = np.array([t.values[v] for t in ticks], dtype=float)
        assert len(x) == len(y) > 0 and np.array_equal(x, y, equal_nan=True), v
    return cols


@pytest.mark.parametrize("trace", ["sif_disabled", "lidar_dropout"])
def test_blocks_equal_ticks_on_the_shipped_traces(trace):
    """On the simulator's recordings (720 real beams a scan, silences in lidar_dropout): the
    count in a polygon, the time before collision along the recorded command and atan2 are
    the same by numpy over blocks as tick by tick."""
    cols = _blocks_equal_ticks(REPO / "traces" / f"{trace}.mcap", f"""[tick]
period = "100 ms"
[variables]
near = "points_in(scan_points(/scan), polygon(0.8, 0.4, 0.8, -0.4, -0.5, -0.4, -0.5, 0.4))"
near_tf = 'points_in(scan_points(/scan, "base_link"), {SCOUT_TEXT})'
ttc = "collision_time(scan_points(/scan), {SCOUT_TEXT}, /cmd_vel.linear.x, /cmd_vel.angular.z, 0.1, 1.5)"
heading = "atan2(/cmd_vel.angular.z, /cmd_vel.linear.x)"
""")
    if trace == "sif_disabled":  # (it drives into a drum: a finite time before collision)
        assert np.isfinite(cols["ttc"]).any() and (cols["near"] > 0).any()


def _raw_scans(log: Path, topic: str = "/scan") -> list[tuple[int, object]]:
    """Every message of ``topic`` (log time, decoded by rosbags from the MCAP's bytes: an
    independent reading)."""
    from mcap.reader import make_reader

    out = []
    with open(log, "rb") as f:
        for _schema, _channel, message in make_reader(f).iter_messages(topics=[topic]):
            out.append((message.log_time, ROS2.deserialize_cdr(message.data,
                                                               "sensor_msgs/msg/LaserScan")))
    return out


def test_a_real_laserscan_counted_against_shapely():
    """Each scan of the shipped ``sif_disabled`` recording (a tick per scan): the points in
    the Scout Mini's footprint grown by 0.3 m, as the binding counts them, are those shapely
    covers among the beams recomputed from the raw message (REP 117's valid returns)."""
    grown = [(0.51, 0.465), (0.51, -0.465), (-0.51, -0.465), (-0.51, 0.465)]
    text = ", ".join(f"{x}, {y}" for x, y in grown)
    log = REPO / "traces" / "sif_disabled.mcap"
    b = parse_bindings(f'[tick]\ntopic = "/scan"\nnominal_rate = "10 Hz"\n[variables]\n'
                       f'n = "points_in(scan_points(/scan), polygon({text}))"\n')
    _times, cols = sample_arrays(open_log(log), b)
    scans = _raw_scans(log)
    assert len(cols["n"]) == len(scans)
    g = SPolygon(grown)
    some = 0
    for got, (_t, m) in zip(cols["n"], scans):
        r = np.asarray(m.ranges, dtype=np.float64)
        a = m.angle_min + np.arange(len(r)) * np.float64(m.angle_increment)
        ok = (r >= m.range_min) & (r <= m.range_max)
        want = sum(g.covers(SPoint(x, y)) for x, y in zip((r * np.cos(a))[ok],
                                                           (r * np.sin(a))[ok]))
        assert got == want
        some += want > 0
    assert some > 0


def _quat(yaw: float):
    return T(ROS2, "geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=math.sin(yaw / 2),
                                                   w=math.cos(yaw / 2))


def _tf(ns: int, parent: str, child: str, x: float, y: float, yaw: float):
    tr = T(ROS2, "geometry_msgs/msg/Transform")(
        translation=T(ROS2, "geometry_msgs/msg/Vector3")(x=x, y=y, z=0.0), rotation=_quat(yaw))
    return T(ROS2, "tf2_msgs/msg/TFMessage")(transforms=[T(ROS2, "geometry_msgs/msg/TransformStamped")(
        header=header(ns, frame=parent), child_frame_id=child, transform=tr)])


def _footprint(ns: int, frame: str, pts):
    P = T(ROS2, "geometry_msgs/msg/Point32")
    return T(ROS2, "geometry_msgs/msg/PolygonStamped")(
        header=header(ns, frame=frame),
        polygon=T(ROS2, "geometry_msgs/msg/Polygon")(points=[P(x=x, y=y, z=0.0) for x, y in pts]))


def _laser(ns: int, ranges, frame="laser"):
    m = scan(ranges, ns=ns, range_min=0.05, range_max=8.0)
    m.header.frame_id = frame
    m.angle_min, m.angle_increment = -math.pi, 2 * math.pi / len(ranges)
    return m


@pytest.fixture(scope="module")
def tf_log(tmp_path_factory) -> tuple[Path, list]:
    """A LiDAR mounted 0.2 m ahead of base_link turned by 90 degrees (/tf_static), a base
    moving in odom (/tf), Nav2's published footprint in odom (a PolygonStamped, the
    footprint's pose changing), a command."""
    rng = np.random.default_rng(7)
    msgs = [("/tf_static", "tf2_msgs/msg/TFMessage", 0, _tf(0, "base_link", "laser", 0.2, 0.0,
                                                            math.pi / 2))]
    truth = []
    for k in range(30):
        t = k * 100 * MS + 1
        bx, byaw = 0.05 * k, 0.02 * k
        msgs.append(("/tf", "tf2_msgs/msg/TFMessage", t, _tf(t, "odom", "base_link", bx, 0.0,
                                                             byaw)))
        fp_odom = [(bx + math.cos(byaw) * x - math.sin(byaw) * y,
                    math.sin(byaw) * x + math.cos(byaw) * y) for x, y in SCOUT]
        msgs.append(("/footprint", "geometry_msgs/msg/PolygonStamped", t + 1,
                     _footprint(t, "odom", fp_odom)))
        ranges = rng.uniform(0.1, 1.0, 64)
        ranges[rng.integers(0, 64, 4)] = math.nan
        msgs.append(("/scan", "sensor_msgs/msg/LaserScan", t + 2, _laser(t, ranges)))
        msgs.append(("/cmd_vel", "geometry_msgs/msg/Twist", t + 3, twist(0.3, 0.2)))
        truth.append((ranges, bx, byaw))
    path = tmp_path_factory.mktemp("tf") / "tf.mcap"
    write_mcap(path, msgs)
    return path, truth


def test_points_through_tf_and_a_footprint_from_a_topic(tf_log):
    """Points of a LiDAR whose frame is not the base's, moved into base_link through
    /tf_static; the footprint read from a PolygonStamped in odom, moved into base_link through
    /tf: the count equals shapely's over the points moved by the mounting (written apart), in
    both evaluations; the time before collision too."""
    log, truth = tf_log
    cols = _blocks_equal_ticks(log, f"""[tick]
topic = "/scan"
nominal_rate = "10 Hz"
[variables]
n = 'points_in(scan_points(/scan, "base_link"), polygon(/footprint))'
n_fixed = 'points_in(scan_points(/scan, "base_link"), {SCOUT_TEXT})'
ttc = 'collision_time(scan_points(/scan, "base_link"), polygon(/footprint), /cmd_vel.linear.x, /cmd_vel.angular.z, 0.1, 1.0)'
""")
    g = SPolygon(SCOUT)
    for k, (ranges, _bx, _byaw) in enumerate(truth[1:], start=1):  # (a tick per scan)
        r = np.asarray(ranges, dtype=np.float32).astype(np.float64)
        a = -math.pi + np.arange(64) * np.float64(np.float32(2 * math.pi / 64))
        ok = np.isfinite(r)
        lx, ly = r * np.cos(a), r * np.sin(a)
        bxs, bys = 0.2 - ly, lx  # (the laser turned by 90 degrees, 0.2 m ahead)
        want = sum(g.covers(SPoint(x, y)) for x, y in zip(bxs[ok], bys[ok]))
        assert cols["n_fixed"][k - 1] == want
        assert abs(cols["n"][k - 1] - want) <= 1  # (the footprint's float32 vertices)
    assert np.isfinite(cols["ttc"]).all()


def _cloud(ns: int, pts: np.ndarray) -> object:
    F = T(ROS2, "sensor_msgs/msg/PointField")
    fields = [F(name="x", offset=0, datatype=7, count=1), F(name="y", offset=4, datatype=7,
                                                          count=1),
              F(name="z", offset=8, datatype=7, count=1),
              F(name="intensity", offset=12, datatype=7, count=1)]
    data = np.zeros((len(pts), 5), dtype=np.float32)  # (a pad of 4 bytes a point)
    data[:, :3] = pts
    return T(ROS2, "sensor_msgs/msg/PointCloud2")(
        header=header(ns, frame="base_link"), height=1, width=len(pts), fields=fields,
        is_bigendian=False, point_step=20, row_step=20 * len(pts),
        data=data.view(np.uint8).reshape(-1), is_dense=False)


def test_a_point_cloud_counted_between_heights(tmp_path):
    """A PointCloud2 (float32 x, y, z among other fields, a pad, NaN points of a non-dense
    cloud) in its own frame (""): the points between the heights kept, counted in the polygon,
    equal the count over the generated points; a cloud of NaN only is a blind sensor
    (unknown)."""
    rng = np.random.default_rng(3)
    msgs, want = [], []
    for k in range(12):
        pts = rng.uniform(-1.0, 1.0, (50, 3)).astype(np.float32)
        pts[rng.integers(0, 50, 5)] = np.nan
        if k == 11:
            pts[:] = np.nan
        t = k * 100 * MS + 1
        msgs.append(("/points", "sensor_msgs/msg/PointCloud2", t, _cloud(t, pts)))
        p = pts.astype(np.float64)
        keep = np.isfinite(p).all(axis=1) & (p[:, 2] >= 0.05) & (p[:, 2] <= 0.8)
        n = sum(SPolygon(SCOUT).covers(SPoint(x, y)) for x, y, _z in p[keep])
        want.append(math.nan if k == 11 else n)
    log = write_mcap(tmp_path / "cloud.mcap", msgs)
    cols = _blocks_equal_ticks(log, f"""[tick]
topic = "/points"
nominal_rate = "10 Hz"
[variables]
n = 'points_in(cloud_points(/points, "", 0.05, 0.8), {SCOUT_TEXT})'
""")
    assert np.array_equal(cols["n"], np.array(want), equal_nan=True)


@pytest.mark.parametrize("expr, says", [
    ("points_in(scan_points(/cmd_vel), polygon(1, 1, -1, 1, 0, -1))", "reads a sensor_msgs/LaserScan"),
    ("points_in(scan_points(/scan), polygon(1, 1, -1, 1))", "at least three"),
    ("scan_points(/scan) > 0", "only points_in() and collision_time() take"),
    ("collision_time(scan_points(/scan), polygon(1, 1, -1, 1, 0, -1), 0.1, 0.0, 0, 1)",
     "positive number of seconds"),
    ("points_in(scan_points(/scan), polygon(/footprint))", "name it"),
    ("points_in(polygon(1, 1, -1, 1, 0, -1), scan_points(/scan))", "points first"),
    ("sin(/scan.header.frame_id)", "takes numbers"),
])
def test_bad_geometry_is_an_error_naming_the_file_line_and_column(tmp_path, expr, says):
    """A geometry call a binding cannot make is an input error naming the binding file, its
    line and the column, with the reason (checked against the log's schemas where a type is
    at fault)."""
    f = tmp_path / "g.bindings.toml"
    f.write_text(f"[tick]\nperiod = \"100 ms\"\n[variables]\nv = '{expr}'\n")
    log = write_mcap(tmp_path / "g.mcap", [
        ("/scan", "sensor_msgs/msg/LaserScan", 1, scan([1.0])),
        ("/cmd_vel", "geometry_msgs/msg/Twist", 2, twist(0.1))])
    with pytest.raises(BindingError) as exc:
        from fretc.logs.schema import log_schemas
        from fretc.signals.bindings.typecheck import check_types
        b = load_bindings(f)
        check_types(b.variables["v"], log_schemas(open_log(log)))
    assert says in str(exc.value) and f"{f}:4:" in str(exc.value), str(exc.value)
