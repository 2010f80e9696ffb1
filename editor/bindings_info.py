"""What the language server says of a variable from its binding (``*.bindings.toml`` beside
the requirements, docs/bindings.md): where it is bound, its expression, its type and its
unit.

Design notes: ARCHITECTURE.md, `editor/bindings_info.py`."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING
from dataclasses import dataclass, field
from pathlib import Path

if TYPE_CHECKING:
    from fretc.signals.bindings.expression import Expr

__all__ = ["VariableInfo", "BindingsFile", "bindings_beside", "read_bindings", "FIELD_UNITS"]

#: REP 103 units of standard message fields: (message type, field path with ``*`` for any
#: one name) -> unit
FIELD_UNITS = {
    ("geometry_msgs/msg/Twist", ("linear", "*")): "m/s",
    ("geometry_msgs/msg/Twist", ("angular", "*")): "rad/s",
    ("geometry_msgs/msg/TwistStamped", ("twist", "linear", "*")): "m/s",
    ("geometry_msgs/msg/TwistStamped", ("twist", "angular", "*")): "rad/s",
    ("geometry_msgs/msg/Pose", ("position", "*")): "m",
    ("geometry_msgs/msg/PoseStamped", ("pose", "position", "*")): "m",
    ("geometry_msgs/msg/Point", ("*",)): "m",
    ("nav_msgs/msg/Odometry", ("pose", "pose", "position", "*")): "m",
    ("nav_msgs/msg/Odometry", ("twist", "twist", "linear", "*")): "m/s",
    ("nav_msgs/msg/Odometry", ("twist", "twist", "angular", "*")): "rad/s",
    ("sensor_msgs/msg/LaserScan", ("ranges",)): "m",
    ("sensor_msgs/msg/LaserScan", ("range_min",)): "m",
    ("sensor_msgs/msg/LaserScan", ("range_max",)): "m",
    ("sensor_msgs/msg/LaserScan", ("angle_min",)): "rad",
    ("sensor_msgs/msg/LaserScan", ("angle_max",)): "rad",
    ("sensor_msgs/msg/LaserScan", ("angle_increment",)): "rad",
    ("sensor_msgs/msg/LaserScan", ("time_increment",)): "s",
    ("sensor_msgs/msg/LaserScan", ("scan_time",)): "s",
    ("sensor_msgs/msg/Range", ("range",)): "m",
    ("sensor_msgs/msg/Range", ("min_range",)): "m",
    ("sensor_msgs/msg/Range", ("max_range",)): "m",
    ("sensor_msgs/msg/Range", ("field_of_view",)): "rad",
    ("sensor_msgs/msg/Imu", ("angular_velocity", "*")): "rad/s",
    ("sensor_msgs/msg/Imu", ("linear_acceleration", "*")): "m/s^2",
    ("sensor_msgs/msg/BatteryState", ("voltage",)): "V",
    ("sensor_msgs/msg/BatteryState", ("current",)): "A",
    ("sensor_msgs/msg/BatteryState", ("charge",)): "Ah",
    ("sensor_msgs/msg/BatteryState", ("capacity",)): "Ah",
    ("sensor_msgs/msg/BatteryState", ("percentage",)): "fraction (0..1)",
    ("sensor_msgs/msg/BatteryState", ("temperature",)): "degC",
    ("sensor_msgs/msg/Temperature", ("temperature",)): "degC",
    ("sensor_msgs/msg/FluidPressure", ("fluid_pressure",)): "Pa",
    ("sensor_msgs/msg/NavSatFix", ("latitude",)): "deg",
    ("sensor_msgs/msg/NavSatFix", ("longitude",)): "deg",
    ("sensor_msgs/msg/NavSatFix", ("altitude",)): "m",
}
_SAME_UNIT = ("abs", "min", "max", "mean", "norm", "min_of_messages", "max_of_messages",
              "sum", "median", "percentile")
_NUMBER_FUNCS = ("abs", "norm", "min", "max", "mean", "count", "len", "age", "joint",
                 "sqrt", "delta", "timedelta", "derivative", "count_of_messages",
                 "min_of_messages", "max_of_messages", "sum", "median", "percentile",
                 "variance", "rate", "waiting", "goal_waiting")
_BOOL_OPS = ("<", "<=", ">", ">=", "=", "!=", "&", "|", "->", "<->")


@dataclass(frozen=True)
class VariableInfo:
    """One bound variable: its ``name``, bindings ``file``, 0-based ``line`` and ``col`` of its
    key and ``end_col`` just past it, the ``expr`` text, its ``type`` (``boolean``,
    ``number`` or ``unknown``), its ``unit`` (None: not known) and ``how`` the type was found."""

    name: str
    file: str
    line: int
    col: int
    end_col: int
    expr: str
    type: str = "unknown"
    unit: str | None = None
    how: str = ""

    def detail(self) -> str:
        """``number (m/s)``, ``boolean``, ``unknown type``: completion's one-line detail."""
        if self.type == "unknown":
            return "unknown type"
        return f"{self.type} ({self.unit})" if self.unit else self.type


@dataclass
class BindingsFile:
    """The variables of one bindings file (name -> :class:`VariableInfo`, in file order) and
    the file's ``error`` (its first line), None when it parses."""

    path: str
    variables: dict[str, VariableInfo] = field(default_factory=dict)
    error: str | None = None


_CACHE: dict[str, tuple[tuple, BindingsFile]] = {}


def bindings_beside(path: str) -> list[BindingsFile]:
    """The ``*.bindings.toml`` files in the folder of ``path``, read (and kept while their
    size and modification time stay the same), in name order."""
    folder = Path(path).parent
    if not folder.is_dir():
        return []
    out = []
    for f in sorted(folder.glob("*.bindings.toml")):
        try:
            st = f.stat()
        except OSError:
            continue
        stamp = (st.st_size, st.st_mtime_ns)
        got = _CACHE.get(str(f))
        if got is None or got[0] != stamp:
            try:
                text = f.read_text(encoding="utf-8") if st.st_size <= 4 << 20 else ""
            except (OSError, UnicodeDecodeError):
                continue
            got = _CACHE[str(f)] = (stamp, read_bindings(text, str(f)))
        out.append(got[1])
    return out


def _key_places(text: str) -> dict[str, tuple[int, int, int]]:
    """Variable -> (0-based line, col, end col) of its key in ``[variables]`` (a scan)."""
    out: dict[str, tuple[int, int, int]] = {}
    table = None
    for i, raw in enumerate(text.splitlines()):
        s = raw.strip()
        if s.startswith("["):
            table = s.strip("[] ")
            continue
        m = re.match(r'\s*("?)([^"=]+?)\1\s*=', raw)
        if table == "variables" and m:
            name = m.group(2).strip()
            col = raw.index(name, m.start(2))
            out.setdefault(name, (i, col, col + len(name)))
    return out


def read_bindings(text: str, source: str) -> BindingsFile:
    """The :class:`BindingsFile` of the bindings ``text`` (the file ``source``)."""
    from fretc.common.errors import FretcError
    from fretc.signals.bindings.files import parse_bindings

    places = _key_places(text)
    out = BindingsFile(source)
    try:
        b = parse_bindings(text, source)
    except FretcError as exc:
        out.error = str(exc).splitlines()[0]
        for name, (ln, col, end) in places.items():
            out.variables[name] = VariableInfo(name, source, ln, col, end, "")
        return out
    schemas = _schemas(b.types)
    for name, binding in b.variables.items():
        ln, col, end = places.get(name, (max((binding.line or 1) - 1, 0), 0, 0))
        t, how = _type(binding, schemas)
        out.variables[name] = VariableInfo(name, source, ln, col, end, binding.expr, t,
                                           unit_of(binding.ast, schemas) if t == "number"
                                           else None, how)
    return out


def _schemas(types: dict[str, str]) -> dict:
    """Topic -> :class:`fretc.logs.schema.TopicSchema` for the ``[types]`` table (ROS 2's
    definitions); a type rosbags does not know is left out."""
    if not types:
        return {}
    from fretc.logs.ros.known_types import _store
    from fretc.logs.schema import TopicSchema

    store = _store("ros2_humble")
    out = {}
    for topic, name in types.items():
        full = name if "/msg/" in name else name.replace("/", "/msg/", 1)
        if full in store.fielddefs:
            out[topic] = TopicSchema(topic, full, store)
    return out


def _type(binding, schemas: dict) -> tuple[str, str]:
    """(``boolean``/``number``/``unknown``, how it was found) of a binding."""
    from fretc.common.errors import FretcError
    from fretc.signals.bindings.typecheck import check_types

    if schemas and binding.topics & set(schemas):
        try:
            t = check_types(binding, {t: schemas.get(t) for t in binding.topics})
        except FretcError as exc:
            return "unknown", f"type error: {str(exc).splitlines()[0]}"
        if t != "any":
            return ("boolean" if t == "bool" else "number"), "by the message types of [types]"
    t = _static(binding.ast)
    if t == "unknown":
        return t, "a field of a topic whose type the file's [types] table does not name"
    return t, "from its expression"


def _static(node) -> str:
    """The type of an expression from its form alone (module docstring)."""
    from fretc.signals.bindings.expression import BinOp, Const, FuncCall, UnaryOp

    if isinstance(node, Const):
        return ("boolean" if isinstance(node.value, bool) else "unknown"
                if isinstance(node.value, str) else "number")
    if isinstance(node, UnaryOp):
        return "boolean" if node.op == "!" else "number"
    if isinstance(node, BinOp):
        return "boolean" if node.op in _BOOL_OPS else "number"
    if isinstance(node, FuncCall):
        if node.func in ("any", "all", "any_of_messages", "all_of_messages"):
            return "boolean"
        if node.func in _NUMBER_FUNCS:
            return "number"
        if node.func == "tf":
            return "number"
    return "unknown"


def unit_of(node: Expr, schemas: dict) -> str | None:
    """The unit of a numeric expression (module docstring), or None."""
    from fretc.signals.bindings.expression import BinOp, Const, Field, FuncCall, UnaryOp

    if isinstance(node, Field):
        return _field_unit(node, schemas)
    if isinstance(node, UnaryOp) and node.op == "-":
        return unit_of(node.arg, schemas)
    if isinstance(node, FuncCall):
        f = node.func
        if f in ("count", "len", "count_of_messages"):
            return "count"
        if f in ("age", "timedelta", "waiting", "goal_waiting"):
            return "s"
        if f == "rate":
            return "Hz"
        if f == "tf":
            comp = node.args[-1].value if isinstance(node.args[-1], Const) else None
            return {"x": "m", "y": "m", "z": "m", "yaw": "rad", "age": "s"}.get(str(comp))
        if f in _SAME_UNIT or f == "delta":
            args = node.args[:1] if type(node.args[-1]).__name__ == "Span" else node.args
            units = {unit_of(a, schemas) for a in args}
            return units.pop() if len(units) == 1 else None
        if f == "derivative":
            u = unit_of(node.args[0], schemas)
            return f"{u}/s" if u else None
        return None
    if isinstance(node, BinOp) and node.op in ("+", "-", "*", "/"):
        a, b = unit_of(node.left, schemas), unit_of(node.right, schemas)
        if node.op in ("+", "-"):
            return a if a == b or isinstance(node.right, Const) else (
                b if isinstance(node.left, Const) else None)
        if isinstance(node.right, Const):
            return a
        if isinstance(node.left, Const) and node.op == "*":
            return b
    return None


def _field_unit(node, schemas: dict) -> str | None:
    sch = schemas.get(node.topic)
    if sch is None:
        return None
    names = tuple(p for p in node.path if isinstance(p, str))
    for (typename, pattern), unit in FIELD_UNITS.items():
        if typename == sch.typename and len(pattern) == len(names) and all(
                p in ("*", n) for p, n in zip(pattern, names)):
            return unit
    return None

