"""The geometry calls of a binding as written and in the canonical form the evaluators take
(:mod:`fretc.signals.bindings.geometry`): the parser expands each into the fields it reads, so
that the decoders decode them and the type checker checks them against the log's schemas.

Design notes: ARCHITECTURE.md, `signals/bindings/geometry_args.py`."""

from __future__ import annotations

import math

from fretc.signals.bindings.expression import (Const, Expr, ExprLocation, Field, FuncCall,
                                               Slice, UnaryOp)

__all__ = ["expand", "POINTS", "GEOMETRY", "TRIG"]

#: the calls whose value is points, and every geometry call
POINTS = ("scan_points", "cloud_points")
GEOMETRY = POINTS + ("polygon", "points_in", "collision_time")
#: trigonometric functions (rad), item by item on arrays, and their arities
TRIG = {"sin": 1, "cos": 1, "tan": 1, "asin": 1, "acos": 1, "atan": 1, "atan2": 2}


def _message(a: Expr | None, what: str, where: ExprLocation, col: int) -> Field:
    """The message a geometry call reads: a topic (``/scan``) or a field of one holding the
    message (``/robot.scan``), as a :class:`Field` without filters or slices.

    Raises:
        BindingError: anything else."""
    if isinstance(a, Const) and isinstance(a.value, str):
        a = Field(a.col, a.value, ())
    if not isinstance(a, Field) or a.filters or any(not isinstance(p, str) for p in a.path):
        raise where.error(f"{what} takes a topic (or a field of names holding the message), "
                          "e.g. " + ("scan_points(/scan)" if what.startswith("scan")
                                     else "cloud_points(/points)" if what.startswith("cloud")
                                     else "polygon(/local_costmap/published_footprint)"), col)
    return a


def _frame(a: Expr | None, where: ExprLocation, col: int) -> str:
    """A frame argument: a TF frame name in quotes, ``""`` the sensor's own frame.

    Raises:
        BindingError: anything else."""
    if not (isinstance(a, Const) and isinstance(a.value, str) and a.value == a.value.strip()):
        raise where.error('a frame is a TF frame name in quotes, e.g. "base_link" ("": the '
                          "sensor's own)", col)
    return a.value


def _number(a: Expr) -> float | None:
    """A constant number (``1.5``, ``-0.2``), else None."""
    if isinstance(a, Const) and isinstance(a.value, float) and not isinstance(a.value, bool):
        return a.value
    if isinstance(a, UnaryOp) and a.op == "-":
        x = _number(a.arg)
        return None if x is None else -x
    return None


def _sub(f: Field, *names: object) -> Field:
    return Field(f.col, f.topic, f.path + tuple(names))  # type: ignore[arg-type]


def expand(name: str, args: tuple[Expr, ...], where: ExprLocation, col: int) -> FuncCall:
    """The call ``name(args)`` as written, in its canonical form (module docstring).

    Raises:
        BindingError: arguments a geometry call does not take, at ``col``."""
    if name == "scan_points":
        if len(args) not in (1, 2):
            raise where.error("scan_points() takes a LaserScan topic and optionally a frame: "
                              'scan_points(/scan) or scan_points(/scan, "base_link")', col)
        m = _message(args[0], "scan_points()", where, col)
        frame = _frame(args[1], where, col) if len(args) > 1 else ""
        out: tuple[Expr, ...] = (Const(col, frame), _sub(m, "ranges"), _sub(m, "angle_min"),
                                 _sub(m, "angle_increment"))
        return FuncCall(col, name, out + ((_sub(m, "header", "frame_id"),) if frame else ()))
    if name == "cloud_points":
        if len(args) not in (1, 2, 4):
            raise where.error("cloud_points() takes a PointCloud2 topic, optionally a frame and "
                              'the heights kept: cloud_points(/points, "base_link", 0.05, 1.0)',
                              col)
        m = _message(args[0], "cloud_points()", where, col)
        frame = _frame(args[1], where, col) if len(args) > 1 else ""
        low, high = ((args[2], args[3]) if len(args) == 4
                     else (Const(col, -math.inf), Const(col, math.inf)))
        for h in (low, high):
            if _number(h) is None:
                raise where.error("cloud_points(): the heights kept are numbers (m)", h.col)
        out = (Const(col, frame), low, high) + tuple(
            _sub(m, f) for f in ("data", "fields", "point_step", "row_step", "width",
                                 "height", "is_bigendian"))
        return FuncCall(col, name, out + ((_sub(m, "header", "frame_id"),) if frame else ()))
    if name == "polygon":
        return _polygon(args, where, col)
    if name == "points_in":
        if len(args) != 2:
            raise where.error("points_in() takes points and a polygon: points_in(scan_points"
                              "(/scan), polygon(0.3, 0.2, 0.3, -0.2, -0.3, -0.2, -0.3, 0.2))",
                              col)
    elif len(args) not in (6, 7):
        raise where.error("collision_time() takes points, the footprint, the twist's linear x "
                          "and angular z, the simulation time step and the time horizon (s), "
                          "and optionally the least number of points: collision_time(scan_"
                          "points(/scan), polygon(...), /cmd_vel.linear.x, /cmd_vel.angular.z, "
                          "0.1, 2.0)", col)
    _geometry_operands(name, args, where, col)
    return FuncCall(col, name, args)


def _polygon(args: tuple[Expr, ...], where: ExprLocation, col: int) -> FuncCall:
    if len(args) == 1:
        m = _message(args[0], "polygon()", where, col)
        pts = (_sub(m, "points", Slice(None, None), "x"), _sub(m, "points", Slice(None, None),
                                                               "y"))
        if m.path:  # a geometry_msgs/Polygon field: in the points' frame
            return FuncCall(col, "polygon", (Const(col, "field"),) + pts)
        stamped = Field(m.col, m.topic, ("polygon",))
        return FuncCall(col, "polygon", (
            Const(col, "stamped"), _sub(stamped, "points", Slice(None, None), "x"),
            _sub(stamped, "points", Slice(None, None), "y"), _sub(m, "header", "frame_id")))
    if len(args) < 6 or len(args) % 2:
        raise where.error("polygon() takes its vertices as x1, y1, x2, y2, x3, y3, ... (m, at "
                          f"least three; {len(args)} number(s) given), or a PolygonStamped "
                          "topic: polygon(/local_costmap/published_footprint)", col)
    return FuncCall(col, "polygon", (Const(col, "vertices"),) + args)


def _geometry_operands(name: str, args: tuple[Expr, ...], where: ExprLocation,
                       col: int) -> None:
    """Check the points, the polygon and the constants of ``points_in``/``collision_time``.

    Raises:
        BindingError: naming the argument."""
    p, poly = args[0], args[1]
    if not (isinstance(p, FuncCall) and p.func in POINTS):
        raise where.error(f"{name}() takes points first: scan_points(/scan) or "
                          "cloud_points(/points)", p.col)
    if not (isinstance(poly, FuncCall) and poly.func == "polygon"):
        raise where.error(f"{name}() takes a polygon second: polygon(x1, y1, ...) or "
                          "polygon(/footprint)", poly.col)
    if poly.args[0].value == "stamped" and not p.args[0].value:  # type: ignore[attr-defined]
        raise where.error(f"{name}(): a polygon read with its header's frame is moved into the "
                          "points' frame: name it, e.g. scan_points(/scan, \"base_link\")",
                          poly.col)
    if name != "collision_time":
        return
    for a, what in zip(args[4:], ("the simulation time step", "the time horizon",
                                  "the least number of points")):
        x = _number(a)
        if x is None:
            raise where.error(f"collision_time(): {what} is a number", a.col)
        if what.endswith("step") and not (x > 0 and math.isfinite(x)):
            raise where.error(f"collision_time(): {what} is a positive number of seconds, "
                              f"not {x!r}", a.col)
        if what.endswith("horizon") and not (x >= 0 and math.isfinite(x)):
            raise where.error(f"collision_time(): {what} is a number of seconds, not {x!r}",
                              a.col)
        if what.endswith("points") and not (x >= 1 and x == math.floor(x)):
            raise where.error(f"collision_time(): {what} is a whole number from 1, not {x!r}",
                              a.col)
