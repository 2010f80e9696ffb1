"""Types of a binding against a log's message types (:func:`check_types`), before the log is
read: a field the schema does not declare, a string in arithmetic or a boolean used as a
number is an error naming the binding file:line:col, the variable, the topic and the field.

Types are strings: ``"bool"``, ``"number"``, ``"array_bool"``, ``"array_number"``,
``"array_string"``, ``"array_other"`` (messages), ``"string"``, ``"message"``, and ``"any"`` when the
topic's schema is unknown (then nothing is checked).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from fretc.common.streams import base_topic
from fretc.common.problems import BindingError
from fretc.logs.schema import FieldPathError
from fretc.signals.bindings.binding import Binding
from fretc.logs.mcap.encodings import constant_name
from fretc.signals.bindings.expression import (GEOMETRY_CALLS, BinOp, Const, EntityParam, Expr, ExprLocation, Field, Filter, FuncCall, Named, Span,
                         UnaryOp, unparse)

__all__ = ["check_types"]

_BOOLS = ("bool", "array_bool")
_NUMS = ("number", "array_number")
_ARRAYS = ("array_bool", "array_number")
_WORDS = {"bool": "a boolean", "number": "a number", "array_bool": "an array of booleans",
          "array_number": "an array of numbers", "string": "a string", "message": "a message",
          "array_string": "an array of strings", "array_other": "an array of messages"}


def check_types(binding: Binding, schemas: Mapping[str, Any]) -> str:
    """Check ``binding`` against the message types of a log (:func:`fretc.logs.schema.log_schemas`)
    before it is evaluated: every field path must resolve through fields the
    schema declares (never Python attributes), strings cannot enter arithmetic or
    comparisons, a boolean is not a number and a number is not a boolean, and the value must
    end as a boolean or a number. Topics whose schema is unknown (None) are not checked.

    Args:
        schemas: topic -> its message schema (``resolve(path)`` -> field type), or None.

    Returns:
        the binding's type: ``"bool"``, ``"number"`` (or ``"any"`` when unknown).

    Named constants (``POWER_SUPPLY_STATUS_CHARGING``) are looked up in the message
    definition declaring the field they are compared with (or filter on) and their values
    stored in ``binding.constants``.

    Raises:
        BindingError: naming the binding file:line:col, the variable, and the topic and
            field at fault (with the fields that exist and the closest name); a named
            constant the message definition does not declare (with the ones it does).
    """
    checker = _TypeChecker(binding.location(), schemas, binding.constants)
    t = checker.type(binding.ast)
    if t not in ("bool", "number", "any"):
        raise checker.where.error(
            f"type error: a variable must be a boolean or a number, but "
            f"{_describe(binding.ast, t)}"
            + ("; reduce it with min/max/any/all/count" if "array" in t else ""))
    return t


def _compared_field(node: Expr) -> Field | None:
    """The field whose message definition declares a named constant compared with
    ``node``: ``node`` itself, or the field a function takes first (``max(/d.status[:].level)``,
    ``joint(/js.position, "w")``); None if neither ends in a field name."""
    if isinstance(node, FuncCall) and node.args and node.func != "tf":
        node = node.args[0]
    if isinstance(node, Field) and node.path and isinstance(node.path[-1], str):
        return node
    return None


def _kind(value) -> str:
    """The binding type of a constant's value."""
    return ("bool" if isinstance(value, bool) else "string" if isinstance(value, str)
            else "number")


def _describe(node: Expr, t: str) -> str:
    if isinstance(node, Field):
        path = node.text()[len(node.topic) + 1:]
        return (f"{node.text()} (topic {node.topic}, field {path}) is "
                f"{_WORDS.get(t, t)}")
    return f"{unparse(node).strip('()')} is {_WORDS.get(t, t)}"


class _TypeChecker:
    """The type of each node, bottom up; raises at the first node that does not fit."""

    def __init__(self, where: ExprLocation, schemas: Mapping[str, Any], constants: dict) -> None:
        self.where = where
        self.schemas = schemas
        self.constants = constants

    def need(self, node: Expr, t: str, ok: tuple, what: str, at: Expr) -> None:
        """Raise unless type ``t`` of ``node`` is one of ``ok`` (or unknown)."""
        if t != "any" and t not in ok:
            hint = ""
            if t in _NUMS and ok == _BOOLS:
                hint = "; compare it (e.g. x != 0) to make a boolean"
            elif t in _BOOLS and ok == _NUMS:
                hint = "; a boolean is not a number in a binding"
            raise self.where.error(f"type error: {what}, but {_describe(node, t)}{hint}", at.col)

    def type(self, node: Expr) -> str:
        if isinstance(node, Const):
            v = node.value
            if isinstance(v, EntityParam):  # an entity's key: any value of its field
                return "any"
            return "bool" if isinstance(v, bool) else "string" if isinstance(v, str) else "number"
        if isinstance(node, Named):
            if node.name in self.constants:
                return _kind(self.constants[node.name])
            raise self.where.error(f"{node.name} is not a variable of this binding file; a "
                                   "named constant must be compared with a field of the "
                                   "message that declares it (/battery.power_supply_status = "
                                   "POWER_SUPPLY_STATUS_CHARGING)", node.col)
        if isinstance(node, Field):
            return self.field(node)
        if isinstance(node, UnaryOp):
            return self.unary(node)
        if isinstance(node, BinOp):
            return self.binary(node)
        if isinstance(node, FuncCall):
            return self.call(node)
        return "any"  # pragma: no cover

    def field(self, node: Field) -> str:
        topic = base_topic(node.topic) if node.filters else node.topic
        sch = self.schemas.get(topic)
        if sch is None:
            return "any"
        try:
            for flt in node.filters:  # filters of whole messages (a stream's)
                sch.check_message_filter(flt)
                if isinstance(flt.value, Named):
                    self.resolve_named(flt.value, node, ())
            ft = sch.resolve(node.path)
        except FieldPathError as exc:
            raise self.where.error(f"{exc} (topic {topic}, {sch.typename})",
                                   node.col) from None
        for i, p in enumerate(node.path):
            if isinstance(p, Filter) and isinstance(p.value, Named):
                self.resolve_named(p.value, node, node.path[:i])
        if ft.kind == "array":
            return {"bool": "array_bool", "number": "array_number",
                    "string": "array_string"}.get(ft.item.kind, "array_other")
        return {"bool": "bool", "number": "number", "string": "string",
                "message": "message"}.get(ft.kind, "any")

    def unary(self, node: UnaryOp) -> str:
        t = self.type(node.arg)
        if node.op == "-":
            self.need(node.arg, t, _NUMS, "unary '-' takes a number", node)
        else:
            self.need(node.arg, t, _BOOLS, "'!' takes a boolean", node)
        return t

    def resolve_named(self, named: Named, field: Field, owner_path: tuple) -> None:
        """Store the value of ``named``, a constant of the message type at ``owner_path``
        of ``field``'s topic (the items' type for an array)."""
        sch = self.schemas.get(base_topic(field.topic) if field.filters else field.topic)
        if sch is None or not hasattr(sch, "constants"):
            return
        owner = sch.resolve(owner_path)
        while owner.kind == "array":
            owner = owner.item
        consts = sch.constants(owner.name) if owner.kind == "message" else {}
        name = named.name
        if name not in consts:  # a schema's enum title as written (any case): its constant
            folded = [c for c in consts if c.upper() == constant_name(name)]
            name = folded[0] if len(folded) == 1 else name
        if name not in consts:
            raise self.where.error(
                f"{named.name} is not a variable of this binding file nor a constant of "
                f"{owner.name} (its constants: {', '.join(consts) or 'none'})", named.col)
        self.constants[named.name] = consts[name]

    def binary(self, node: BinOp) -> str:
        for side, other in ((node.left, node.right), (node.right, node.left)):
            f = _compared_field(other)
            if isinstance(side, Named) and f is not None:
                self.type(f)  # the field exists
                self.resolve_named(side, f, f.path[:-1])
        a, b = self.type(node.left), self.type(node.right)
        if node.op in ("=", "!=") and {a, b} & {"string", "array_string"}:
            if {a, b} - {"string", "array_string", "any"} or a == b == "array_string":
                raise self.where.error(
                    f"type error: {node.op!r} compares a string with something else "
                    f"({_describe(node.left, a)}; {_describe(node.right, b)})", node.col)
            return "array_bool" if "array_string" in (a, b) else "bool"
        arr = "array" in a or "array" in b
        op = node.op
        if op in ("+", "-", "*", "/"):
            self.both(node, a, b, _NUMS, f"{op!r} takes numbers")
            return "array_number" if arr else ("any" if "any" in (a, b) else "number")
        if op in ("<", "<=", ">", ">="):
            self.both(node, a, b, _NUMS, f"{op!r} compares numbers")
        elif op in ("=", "!="):
            self.both(node, a, b, _NUMS + _BOOLS, f"{op!r} compares numbers or booleans")
            known = [x for x in (a, b) if x != "any"]
            if len(known) == 2 and (known[0] in _BOOLS) != (known[1] in _BOOLS) \
                    and not _zero_or_one(node):
                raise self.where.error(f"type error: {op!r} compares a boolean with a number "
                                       f"({_describe(node.left, a)}; "
                                       f"{_describe(node.right, b)})", node.col)
        else:
            self.both(node, a, b, _BOOLS, f"{op!r} takes booleans")
        return "array_bool" if arr else "bool"

    def geometry(self, node: FuncCall) -> str:
        """The type of a geometry call (:mod:`fretc.signals.bindings.geometry_args`'s
        canonical arguments): ``"points"``, ``"polygon"`` or ``"number"``; each field it
        reads checked against the message's type, named in the error."""
        f = node.func
        if f in _GEOMETRY_FIELDS:
            typename, wanted = _GEOMETRY_FIELDS[f]
            for a, want in zip(node.args[1:], wanted):
                try:
                    t = self.type(a)
                except BindingError as exc:
                    raise self.where.error(f"type error: {f}() reads a {typename}: {exc.message}",
                                           node.col) from None
                if t not in ("any", want) and not (want == "bool" and t == "number"):
                    raise self.where.error(f"type error: {f}() reads a {typename}, but "
                                           f"{_describe(a, t)}", node.col)
            return "points"
        if f == "polygon":
            kind = node.args[0].value  # type: ignore[attr-defined]
            if kind == "vertices":
                for a in node.args[1:]:
                    self.need(a, self.type(a), ("number",), "polygon() takes its vertices' "
                              "coordinates as numbers (m)", node)
                return "polygon"
            for a in node.args[1:3]:
                try:
                    t = self.type(a)
                except BindingError as exc:
                    raise self.where.error("type error: polygon() reads a geometry_msgs/"
                                           f"Polygon{'Stamped' if kind == 'stamped' else ''}: "
                                           f"{exc.message}", node.col) from None
                self.need(a, t, ("array_number",), "polygon() reads its vertices' x and y",
                          node)
            if kind == "stamped":
                self.type(node.args[3])
            return "polygon"
        p, g = self.type(node.args[0]), self.type(node.args[1])
        assert p == "points" and g == "polygon"  # (parse checked the calls)
        for a in node.args[2:]:
            self.need(a, self.type(a), ("number",), f"{f}() takes the twist (m/s, rad/s) and "
                      "its times (s) as numbers", node)
        return "number"

    def both(self, node: BinOp, a: str, b: str, ok: tuple, what: str) -> None:
        """Both operands of ``node`` (types ``a``, ``b``) must be one of ``ok``."""
        self.need(node.left, a, ok, what, node)
        self.need(node.right, b, ok, what, node)

    def call(self, node: FuncCall) -> str:
        f = node.func
        if node.args and isinstance(node.args[-1], Span):  # a window (windowing.py)
            arg = node.args[0]
            if isinstance(arg, Field) and not arg.path:  # rate(/scan, 1s), count(/estop, 1s)
                return "number"
            t = self.type(arg)
            if f in ("count", "count_ticks"):
                self.need(arg, t, ("bool",), f"{f}() over a window counts the "
                          f"{'ticks' if f == 'count_ticks' else 'messages'} on which a "
                          "condition held (count(/estop.data, 1min))", node)
            else:
                self.need(arg, t, ("number",), f"{f}() over a window takes numbers", node)
            return "number"
        if f in ("age", "tf", "timedelta", "waiting", "goal_waiting"):
            return "number"
        if f in GEOMETRY_CALLS:
            return self.geometry(node)
        if f in ("sin", "cos", "tan", "asin", "acos", "atan", "atan2"):
            ts = [self.type(a) for a in node.args]
            for a, t in zip(node.args, ts):
                self.need(a, t, _NUMS, f"{f}() takes numbers (rad for sin, cos, tan)", node)
            return ("array_number" if any("array" in t for t in ts)
                    else "any" if "any" in ts else "number")
        if f == "unchanged":
            self.type(node.args[0])
            return "bool"
        if f == "sector":
            ranges = node.args[0]
            if not (isinstance(ranges, Field) and ranges.path
                    and ranges.path[-1] == "ranges" and not ranges.multi):
                raise self.where.error("type error: sector() takes a LaserScan's ranges "
                                       "(sector(/scan.ranges, -0.785, 0.785)), not "
                                       f"{ranges.text() if isinstance(ranges, Field) else 'that'}",
                                       node.col)
            for a in node.args[1:3]:
                self.need(a, self.type(a), ("number",), "sector() takes its ends in radians",
                          node)
            return "array_number"
        if f in ("delta", "derivative", "sqrt"):
            t = self.type(node.args[0])
            self.need(node.args[0], t, ("number",), f"{f}() takes a number", node)
            return "number"
        if f == "joint":
            values, names = self.type(node.args[0]), self.type(node.args[2])
            self.need(node.args[0], values, _ARRAYS, "joint() picks from an array of numbers",
                      node)
            if names not in ("any", "array_string"):
                raise self.where.error(f"type error: joint() needs a name array of strings "
                                       f"beside its array, but {_describe(node.args[2], names)}",
                                       node.col)
            return {"array_bool": "bool", "array_number": "number"}.get(values, "any")
        ts = [self.type(a) for a in node.args]
        if f.endswith("_of_messages"):  # aggregations over messages (one value each)
            fold = f[:-len("_of_messages")]
            if fold in ("any", "all", "count"):
                self.need(node.args[0], ts[0], ("bool",), f"{f}() folds booleans", node)
                return "bool" if fold != "count" else "number"
            self.need(node.args[0], ts[0], ("number",), f"{f}() folds numbers", node)
            return "number"
        for a, t in zip(node.args, ts):
            if f in ("any", "all", "count"):
                self.need(a, t, _ARRAYS, f"{f}() takes an array", node)
            elif f in ("len", "invalid"):
                if t not in ("any", "array_bool", "array_number", "array_string",
                             "array_other"):
                    self.need(a, t, ("array_number",), f"{f}() takes an array", node)
            else:
                self.need(a, t, _NUMS, f"{f}() takes numbers", node)
        if f in ("any", "all"):
            return "bool"
        if f == "abs":
            return ts[0] if ts[0] != "any" else "any"
        if f in ("min", "max") and len(ts) > 1:
            for a, t in zip(node.args, ts):
                if "array" in t:
                    raise self.where.error(f"type error: {f}() of several values takes "
                                           f"numbers, but {_describe(a, t)}", node.col)
        return "number"


#: the fields each geometry value reads and what they must be (docs/bindings.md "Geometry"):
#: function -> (message type, per canonical argument after the frame: the type wanted or None)
_GEOMETRY_FIELDS = {
    "scan_points": ("sensor_msgs/LaserScan", ("array_number", "number", "number", "string")),
    "cloud_points": ("sensor_msgs/PointCloud2", ("number", "number", "array_number",
                                                 "array_other", "number", "number", "number",
                                                 "number", "bool", "string")),
}


def _zero_or_one(node: BinOp) -> bool:
    """``node`` (``=`` or ``!=``) compares with the number 0 or 1, as flight logs' users write
    a boolean (uORB's and DataFlash's ``bool`` fields are stored as 0/1 bytes: ``landed ==
    1``): read as false/true."""
    return any(isinstance(x, Const) and not isinstance(x.value, bool)
               and isinstance(x.value, (int, float)) and x.value in (0, 1)
               for x in (node.left, node.right))
