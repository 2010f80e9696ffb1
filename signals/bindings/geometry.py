"""Geometry in the bindings: the points a LiDAR or a depth camera measured, in the robot's
frame, counted inside a polygon or swept by the footprint moving along a commanded arc, as
Nav2's collision monitor reads them (docs/bindings.md, "Geometry").

Values (only arguments of the functions that use them): points (:class:`Points`:
``scan_points``, REP 103 and REP 117; ``cloud_points``; moved through TF, REP 105) and
polygons (:class:`Polygon`, m, even-odd rule). Functions (numbers): ``points_in(P, POLY)``
and ``collision_time(P, POLY, vx, wz, dt, horizon[, min_points])`` (s; +inf when no collision
within the horizon); a blind sensor makes them NaN. Every function takes rows (one per tick
or per message of a block) and gives one number per row (:func:`compile_geometry`). Each
value and function in full: ARCHITECTURE.md ("Geometry in the bindings").
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from fretc.signals.bindings.expression import Const, Expr, FuncCall, const_value, geometry_tf
from fretc.signals.bindings.extract import Valid
from fretc.signals.bindings.frames import LookupFailed, Transform

__all__ = ["Points", "Polygon", "laser_points", "decode_cloud", "inside", "count_inside",
           "collision_time", "arc_pose", "compile_geometry", "POINT_FUNCS", "MAX_STEPS",
           "GeometryError"]

#: the functions whose value is points
POINT_FUNCS = ("scan_points", "cloud_points")
#: the most steps ``collision_time`` simulates (``horizon / dt``)
MAX_STEPS = 10_000
#: rows decided at once by ``collision_time`` and ``points_in`` (bounds their memory: rows x
#: points x vertices booleans)
_CHUNK = 256

Evaluator = Callable[[Any], Any]


class GeometryError(ValueError):
    """A value the geometry cannot take (a polygon of fewer than three vertices, a step that
    is not positive, an unknown point field type); the message says which."""


@dataclass
class Points:
    """Points per row (module docstring): ``x``, ``y``, ``z`` (m) of shape (rows, n),
    ``mask`` which are points (rows, n), ``blind`` (rows,) the rows of a sensor that measured
    no point and an invalid one, ``frame`` the frame they are in ("" the sensor's own)."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    mask: np.ndarray
    blind: np.ndarray
    frame: str = ""


@dataclass
class Polygon:
    """A polygon's vertices (m): ``xs``, ``ys`` of shape (m,) for every row, or a list of one
    (m_k,) array per row (a polygon read from messages); ``frames`` per row the frame of a
    stamped polygon (None: already in the points' frame)."""

    xs: Any
    ys: Any
    frames: list[str] | None = None


def laser_points(ranges: Valid, angle_min: Any, angle_increment: Any) -> Points:
    """The points of LaserScan ranges (REP 117's :class:`Valid`: data and mask of shape (n,)
    or (rows, n)) with each row's ``angle_min`` and ``angle_increment`` (rad): beam ``i`` at
    ``angle_min + i * angle_increment`` (REP 103) in the scan's frame, ``z`` 0."""
    data = np.atleast_2d(np.asarray(ranges.data, dtype=np.float64))
    rows, n = data.shape
    mask = (np.ones(data.shape, dtype=np.bool_) if ranges.mask is None
            else np.atleast_2d(ranges.mask))
    start = np.asarray(angle_min, dtype=np.float64).reshape(-1, 1)
    step = np.asarray(angle_increment, dtype=np.float64).reshape(-1, 1)
    angles = start + np.arange(n, dtype=np.float64) * step
    r = np.where(mask, data, 0.0)
    invalid = ~mask & ~np.isposinf(data)
    blind = np.asarray(~mask.any(axis=1) & invalid.any(axis=1), dtype=np.bool_)
    return Points(r * np.cos(angles), r * np.sin(angles), np.zeros((rows, n)), mask, blind)


#: PointField's datatypes (sensor_msgs/PointField: INT8 = 1 ... FLOAT64 = 8) as numpy's
_POINT_TYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}


def decode_cloud(data: Any, fields: Any, point_step: Any, row_step: Any, width: Any,
                 height: Any, big_endian: Any) -> Points:
    """The points of one ``sensor_msgs/PointCloud2`` (its fields as read): ``x``, ``y``,
    ``z`` of each of its ``width * height`` points at ``row * row_step + col * point_step``
    (the ``offset`` and ``datatype`` of its ``PointField`` named x, y, z); a point with a
    NaN or infinite coordinate is no point (a non-dense cloud's missing one, an invalid
    measurement). One row.

    Raises:
        GeometryError: no field x, y or z, an unknown datatype, or data shorter than the
            cloud's size."""
    by_name = {str(f.name): f for f in fields}
    missing = [c for c in "xyz" if c not in by_name]
    if missing:
        raise GeometryError(f"the cloud has no field {', '.join(missing)} (its fields: "
                            f"{', '.join(by_name) or 'none'})")
    raw = np.ascontiguousarray(np.asarray(getattr(data, "data", data)), dtype=np.uint8)
    w, h, step, rstep = int(width), int(height), int(point_step), int(row_step)
    order = ">" if bool(big_endian) else "<"
    cols = []
    for c in "xyz":
        f = by_name[c]
        kind = _POINT_TYPES.get(int(f.datatype))
        if kind is None:
            raise GeometryError(f"the cloud's field {c} has datatype {int(f.datatype)}, no "
                                "number type of sensor_msgs/PointField")
        off = int(f.offset)
        size = np.dtype(kind).itemsize
        if h and w and (h - 1) * rstep + (w - 1) * step + off + size > len(raw):
            raise GeometryError(f"the cloud's data holds {len(raw)} bytes, fewer than its "
                                f"{w} x {h} points of {step} bytes")
        vals = np.empty(w * h, dtype=np.float64)
        for r in range(h):
            row = np.ndarray((w,), dtype=np.dtype(order + kind), buffer=raw,
                             offset=r * rstep + off, strides=(step,))
            vals[r * w:(r + 1) * w] = row
        cols.append(vals)
    x, y, z = (c.reshape(1, -1) for c in cols)
    mask = np.isfinite(x) & np.isfinite(y) & np.isfinite(z)
    blind = np.array([not mask.any() and mask.size > 0])
    return Points(np.where(mask, x, 0.0), np.where(mask, y, 0.0), np.where(mask, z, 0.0),
                  mask, blind)


def _rotation(q: tuple[float, float, float, float]) -> np.ndarray:
    """The rotation matrix of a unit quaternion (x, y, z, w)."""
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def moved(p: Points, row: int, tr: Transform, frame: str) -> Points:
    """Row ``row`` of ``p`` moved by the transform ``tr`` (child -> parent: the points'
    frame into ``frame``), one row."""
    m = _rotation(tr[1])
    x, y, z = p.x[row], p.y[row], p.z[row]
    nx = m[0, 0] * x + m[0, 1] * y + m[0, 2] * z + tr[0][0]
    ny = m[1, 0] * x + m[1, 1] * y + m[1, 2] * z + tr[0][1]
    nz = m[2, 0] * x + m[2, 1] * y + m[2, 2] * z + tr[0][2]
    mask = p.mask[row:row + 1]
    return Points(np.where(mask, nx, 0.0), np.where(mask, ny, 0.0), np.where(mask, nz, 0.0),
                  mask, p.blind[row:row + 1], frame)


def heights(p: Points, low: float, high: float) -> Points:
    """``p`` with only the points whose ``z`` lies in ``[low, high]`` (Nav2's
    ``min_height``/``max_height`` of a point cloud source)."""
    keep = p.mask & (p.z >= low) & (p.z <= high)
    return Points(p.x, p.y, p.z, keep, p.blind, p.frame)


def inside(px: np.ndarray, py: np.ndarray, vx: np.ndarray, vy: np.ndarray) -> np.ndarray:
    """Whether each point (``px``, ``py``, any shape) lies inside the polygon of vertices
    ``vx``, ``vy`` (m,) or on its boundary: the even-odd rule (a ray to +x crosses its edges
    an odd number of times), or on an edge (collinear with it, within its bounding box)."""
    odd = np.zeros(np.broadcast(px, py).shape, dtype=np.bool_)
    edge = np.zeros_like(odd)
    m = len(vx)
    for k in range(m):
        ax, ay, bx, by = vx[k], vy[k], vx[(k + 1) % m], vy[(k + 1) % m]
        if ay != by:
            crosses = (ay > py) != (by > py)
            with np.errstate(all="ignore"):
                at = ax + (py - ay) * (bx - ax) / (by - ay)
            odd ^= crosses & (px < at)
        cross = (bx - ax) * (py - ay) - (by - ay) * (px - ax)
        edge |= ((cross == 0) & (px >= min(ax, bx)) & (px <= max(ax, bx))
                 & (py >= min(ay, by)) & (py <= max(ay, by)))
    return odd | edge


def _vertices(poly: Polygon, row: int) -> tuple[np.ndarray, np.ndarray]:
    """The vertices of ``poly`` at ``row`` (m,), checked.

    Raises:
        GeometryError: fewer than three, or one not a finite number."""
    if isinstance(poly.xs, list):
        xs, ys = poly.xs[row], poly.ys[row]
    else:
        xs, ys = poly.xs, poly.ys
    xs, ys = np.asarray(xs, dtype=np.float64), np.asarray(ys, dtype=np.float64)
    if len(xs) < 3 or len(xs) != len(ys):
        raise GeometryError(f"a polygon has at least three vertices; this one has {len(xs)}")
    if not (np.isfinite(xs).all() and np.isfinite(ys).all()):
        raise GeometryError("a polygon's vertices are finite numbers; this one has "
                            f"{list(zip(xs.tolist(), ys.tolist()))}")
    return xs, ys


def count_inside(p: Points, poly: Polygon) -> np.ndarray:
    """Per row, how many points of ``p`` lie in ``poly`` (:func:`inside`); NaN for a blind
    row (module docstring). float64 (rows,)."""
    rows = p.x.shape[0]
    out = np.empty(rows, dtype=np.float64)
    shared = not isinstance(poly.xs, list)
    for lo in range(0, rows, _CHUNK):
        hi = min(lo + _CHUNK, rows)
        if shared:
            vx, vy = _vertices(poly, 0)
            got = inside(p.x[lo:hi], p.y[lo:hi], vx, vy) & p.mask[lo:hi]
            out[lo:hi] = got.sum(axis=1)
        else:
            for r in range(lo, hi):
                vx, vy = _vertices(poly, r)
                out[r] = (inside(p.x[r], p.y[r], vx, vy) & p.mask[r]).sum()
    return np.where(p.blind, np.nan, out)


def arc_pose(vx: np.ndarray, wz: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray,
                                                                  np.ndarray]:
    """The pose ``(x, y, yaw)`` (m, m, rad) at time ``t`` (s) of a base starting at the origin
    with the constant twist ``vx`` (m/s), ``wz`` (rad/s), arrays of one shape: the arc
    ``x = vx sin(wz t) / wz``, ``y = vx (1 - cos(wz t)) / wz`` (a straight line for ``wz t``
    near 0, written with its series so that the two agree there)."""
    a = wz * t
    small = np.abs(a) < 1e-6
    safe = np.where(small, 1.0, a)
    s = np.where(small, 1.0 - a * a / 6.0, np.sin(safe) / safe)
    c = np.where(small, a / 2.0, (1.0 - np.cos(safe)) / safe)
    return vx * t * s, vx * t * c, a


def collision_time(p: Points, poly: Polygon, vx: Any, wz: Any, dt: float, horizon: float,
                   min_points: float = 1.0) -> np.ndarray:
    """Per row, the first time ``k * dt`` (s, ``k = 0, 1, ...`` while ``k * dt <= horizon``)
    at which at least ``min_points`` points of ``p`` lie in ``poly`` moved along the arc of
    the row's twist ``vx``, ``wz`` (:func:`arc_pose`): a point ``q`` is in the moved polygon
    when ``R(-yaw) (q - (x, y))`` is in ``poly`` (:func:`inside`). +inf when none within the
    horizon; NaN for a blind row or a twist that is no finite number. float64 (rows,).

    Raises:
        GeometryError: ``dt`` not positive, ``horizon`` negative or not finite, more than
            :data:`MAX_STEPS` steps, or a polygon of fewer than three vertices."""
    if not dt > 0 or not math.isfinite(dt):
        raise GeometryError(f"collision_time(): the simulation time step is a positive "
                            f"number of seconds, not {dt!r}")
    if not horizon >= 0 or not math.isfinite(horizon):
        raise GeometryError(f"collision_time(): the time horizon is a number of seconds, "
                            f"not {horizon!r}")
    steps = int(math.floor(horizon / dt * (1 + 1e-12))) + 1
    if steps > MAX_STEPS:
        raise GeometryError(f"collision_time(): {horizon!r} s in steps of {dt!r} s is "
                            f"{steps} steps, more than {MAX_STEPS}")
    rows = p.x.shape[0]
    v = np.broadcast_to(np.asarray(vx, dtype=np.float64).reshape(-1), (rows,))
    w = np.broadcast_to(np.asarray(wz, dtype=np.float64).reshape(-1), (rows,))
    out = np.full(rows, np.inf)
    for lo in range(0, rows, _CHUNK):
        hi = min(lo + _CHUNK, rows)
        for r0 in (range(lo, hi) if isinstance(poly.xs, list) else [lo]):
            r1 = r0 + 1 if isinstance(poly.xs, list) else hi
            vxs, vys = _vertices(poly, r0)
            _sweep(p, slice(r0, r1), vxs, vys, v[r0:r1], w[r0:r1], dt, steps, min_points,
                   out)
    bad = p.blind | ~np.isfinite(v) | ~np.isfinite(w)
    return np.where(bad, np.nan, out)


def _sweep(p: Points, rows: slice, vxs: np.ndarray, vys: np.ndarray, v: np.ndarray,
           w: np.ndarray, dt: float, steps: int, min_points: float, out: np.ndarray) -> None:
    """:func:`collision_time` for the rows ``rows`` of ``p`` (the twists ``v``, ``w`` of those
    rows), written into ``out``."""
    x, y, mask = p.x[rows], p.y[rows], p.mask[rows]
    left = np.ones(x.shape[0], dtype=np.bool_)
    with np.errstate(all="ignore"):
        for k in range(steps):
            t = k * dt
            ox, oy, yaw = arc_pose(v, w, t)
            c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
            dx, dy = x - ox[:, None], y - oy[:, None]
            hit = inside(c * dx + s * dy, -s * dx + c * dy, vxs, vys) & mask
            now = left & (hit.sum(axis=1) >= min_points)
            if now.any():
                idx = np.nonzero(now)[0] + rows.start
                out[idx] = t
                left &= ~now
            if not left.any():
                return


# --- evaluation ----------------------------------------------------------------------------


def compile_geometry(node: FuncCall, vectorized: bool, compile_arg: Callable[[Expr], Evaluator],
                     fail: Callable[[Expr, str], Exception]) -> Evaluator:
    """The evaluator of a geometry call ``node`` (its arguments in the canonical form the
    parser gives, :mod:`fretc.signals.bindings.parse`): ``compile_arg`` compiles an argument
    (one tick, or ``vectorized`` over rows), ``fail(node, why)`` the error an evaluation
    raises (:class:`fretc.signals.bindings.compile.EvalError`). ``points_in`` and
    ``collision_time`` give a float per tick (a float64 array over rows, vectorized); the
    others their :class:`Points` / :class:`Polygon`. A call reading TF needs the tick's
    transforms (``st.tf``): vectorized it raises, so that the binding is evaluated tick by
    tick, as ``tf()`` is."""
    func = node.func
    if func in POINT_FUNCS:
        return _points_eval(node, vectorized, compile_arg, fail)
    if func == "polygon":
        return _polygon_eval(node, vectorized, compile_arg, fail)
    pts, poly = compile_arg(node.args[0]), compile_arg(node.args[1])
    rest = [compile_arg(a) for a in node.args[2:]]
    tf = geometry_tf(node)

    def run(st: Any) -> Any:
        if tf and (vectorized or getattr(st, "tf", None) is None):
            raise fail(node, f"{func}() reads TF: it is evaluated tick by tick")
        p, g = pts(st), poly(st)
        try:
            g = _in_frame(g, p, st)
            if func == "points_in":
                got = count_inside(p, g)
            else:
                nums = [r(st) for r in rest]
                got = collision_time(p, g, nums[0], nums[1], _scalar(nums[2]),
                                     _scalar(nums[3]),
                                     _scalar(nums[4]) if len(nums) > 4 else 1.0)
        except (GeometryError, LookupFailed) as exc:
            raise fail(node, f"{func}(): {exc}") from None
        return got if vectorized else float(got[0])
    return run


def _scalar(x: Any) -> float:
    """A parameter (a time step, a horizon, a count) as one number: a column's values must
    be one (they are constants or read from one configuration)."""
    a = np.asarray(x, dtype=np.float64).reshape(-1)
    if a.size and not (a == a[0]).all():
        raise GeometryError("its time step, horizon and point count are one number at every "
                            f"tick, not {a[:3].tolist()}...")
    return float(a[0]) if a.size else math.nan


def _in_frame(poly: Polygon, p: Points, st: Any) -> Polygon:
    """``poly`` in the frame of the points ``p`` (a stamped polygon moved through TF at the
    tick: one row)."""
    if poly.frames is None:
        return poly
    frame = poly.frames[0]
    xs, ys = _vertices(poly, 0)
    if frame.lstrip("/") == p.frame.lstrip("/"):
        return Polygon(xs, ys)
    tr = st.tf.transform(p.frame, frame)
    m = _rotation(tr[1])
    return Polygon(m[0, 0] * xs + m[0, 1] * ys + tr[0][0], m[1, 0] * xs + m[1, 1] * ys + tr[0][1])


def _points_eval(node: FuncCall, vectorized: bool, compile_arg: Callable[[Expr], Evaluator],
                 fail: Callable[[Expr, str], Exception]) -> Evaluator:
    """``scan_points``: (frame, ranges, angle_min, angle_increment[, header.frame_id]);
    ``cloud_points``: (frame, low, high, data, fields, point_step, row_step, width, height,
    is_bigendian[, header.frame_id])."""
    frame = str(const_value(node.args[0].value))  # type: ignore[attr-defined]
    args = [compile_arg(a) for a in node.args[1:]]
    scan = node.func == "scan_points"
    n_data = 3 if scan else 9

    def run(st: Any) -> Points:
        if frame and (vectorized or getattr(st, "tf", None) is None):
            raise fail(node, f"{node.func}() reads TF: it is evaluated tick by tick")
        vals = [a(st) for a in args[:n_data]]
        try:
            if scan:
                if not isinstance(vals[0], Valid):
                    raise GeometryError("scan_points() takes a LaserScan")
                p = laser_points(vals[0], vals[1], vals[2])
            else:
                if vectorized:
                    raise GeometryError("cloud_points() is evaluated message by message")
                p = heights(decode_cloud(*vals[2:9]), float(vals[0]), float(vals[1]))
            if frame:
                source = str(args[n_data](st))
                tr = st.tf.transform(frame, source)
                p = moved(p, 0, tr, frame)
        except (GeometryError, LookupFailed) as exc:
            raise fail(node, f"{node.func}(): {exc}") from None
        return p
    return run


def _polygon_eval(node: FuncCall, vectorized: bool, compile_arg: Callable[[Expr], Evaluator],
                  fail: Callable[[Expr, str], Exception]) -> Evaluator:
    """``polygon``: ("vertices", x1, y1, ...), ("field", xs, ys) or ("stamped", xs, ys,
    header.frame_id)."""
    kind = node.args[0].value  # type: ignore[attr-defined]
    args = [compile_arg(a) for a in node.args[1:]]

    if kind == "vertices":
        consts = [a.value for a in node.args[1:] if isinstance(a, Const)]
        if len(consts) == len(node.args) - 1:
            fixed = Polygon(np.array(consts[0::2], dtype=np.float64),
                            np.array(consts[1::2], dtype=np.float64))
            return lambda st: fixed

        def vertices(st: Any) -> Polygon:
            vals = [_scalar(a(st)) for a in args]
            return Polygon(np.array(vals[0::2]), np.array(vals[1::2]))
        return vertices

    def read(st: Any) -> Polygon:
        if vectorized:
            raise fail(node, "polygon() of a topic is evaluated tick by tick")
        xs, ys = (np.asarray(getattr(a(st), "data", a(st)), dtype=np.float64)
                  for a in args[:2])
        frames = [str(args[2](st))] if kind == "stamped" else None
        return Polygon([xs], [ys], frames)
    return read
