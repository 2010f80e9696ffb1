"""Types of a binding against a log's message types (:func:`check_types`), before the log is
read: a field the schema does not declare, a string in arithmetic or a boolean used as a
number is an error naming the binding file:line:col, the variable, the topic and the field.

Types are strings: ``"bool"``, ``"number"``, ``"array_bool"``, ``"array_number"``,
``"array_other"`` (messages or strings), ``"string"``, ``"message"``, and ``"any"`` when the
topic's schema is unknown (then nothing is checked).
"""

from __future__ import annotations

from ..sources.schema import FieldPathError
from .binding import Binding
from .expression import BinOp, Const, Expr, ExprLocation, Field, FuncCall, UnaryOp, unparse

__all__ = ["check_types"]

_BOOLS = ("bool", "array_bool")
_NUMS = ("number", "array_number")
_ARRAYS = ("array_bool", "array_number")
_WORDS = {"bool": "a boolean", "number": "a number", "array_bool": "an array of booleans",
          "array_number": "an array of numbers", "string": "a string", "message": "a message",
          "array_other": "an array of messages or strings"}


def check_types(binding: Binding, schemas: dict) -> str:
    """Check ``binding`` against the message types of a log (:func:`monitors.sources.schema.log_schemas`)
    before it is evaluated: every field path must resolve through fields the
    schema declares (never Python attributes), strings cannot enter arithmetic or
    comparisons, a boolean is not a number and a number is not a boolean, and the value must
    end as a boolean or a number. Topics whose schema is unknown (None) are not checked.

    Args:
        schemas: topic -> its message schema (``resolve(path)`` -> field type), or None.

    Returns:
        the binding's type: ``"bool"``, ``"number"`` (or ``"any"`` when unknown).

    Raises:
        BindingError: naming the binding file:line:col, the variable, and the topic and
            field at fault (with the fields that exist and the closest name).
    """
    checker = _TypeChecker(binding.location(), schemas)
    t = checker.type(binding.ast)
    if t not in ("bool", "number", "any"):
        raise checker.where.error(
            f"type error: a variable must be a boolean or a number, but "
            f"{_describe(binding.ast, t)}"
            + ("; reduce it with min/max/any/all/count" if "array" in t else ""))
    return t


def _describe(node: Expr, t: str) -> str:
    if isinstance(node, Field):
        path = node.text()[len(node.topic) + 1:]
        return (f"{node.text()} (topic {node.topic}, field {path}) is "
                f"{_WORDS.get(t, t)}")
    return f"{unparse(node).strip('()')} is {_WORDS.get(t, t)}"


class _TypeChecker:
    """The type of each node, bottom up; raises at the first node that does not fit."""

    def __init__(self, where: ExprLocation, schemas: dict) -> None:
        self.where = where
        self.schemas = schemas

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
            return "bool" if isinstance(node.value, bool) else "number"
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
        sch = self.schemas.get(node.topic)
        if sch is None:
            return "any"
        try:
            ft = sch.resolve(node.path)
        except FieldPathError as exc:
            raise self.where.error(f"{exc} (topic {node.topic}, {sch.typename})",
                                   node.col) from None
        if ft.kind == "array":
            return {"bool": "array_bool", "number": "array_number"}.get(ft.item.kind,
                                                                       "array_other")
        return {"bool": "bool", "number": "number", "string": "string",
                "message": "message"}.get(ft.kind, "any")

    def unary(self, node: UnaryOp) -> str:
        t = self.type(node.arg)
        if node.op == "-":
            self.need(node.arg, t, _NUMS, "unary '-' takes a number", node)
        else:
            self.need(node.arg, t, _BOOLS, "'!' takes a boolean", node)
        return t

    def binary(self, node: BinOp) -> str:
        a, b = self.type(node.left), self.type(node.right)
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
            if len(known) == 2 and (known[0] in _BOOLS) != (known[1] in _BOOLS):
                raise self.where.error(f"type error: {op!r} compares a boolean with a number "
                                       f"({_describe(node.left, a)}; "
                                       f"{_describe(node.right, b)})", node.col)
        else:
            self.both(node, a, b, _BOOLS, f"{op!r} takes booleans")
        return "array_bool" if arr else "bool"

    def both(self, node: BinOp, a: str, b: str, ok: tuple, what: str) -> None:
        """Both operands of ``node`` (types ``a``, ``b``) must be one of ``ok``."""
        self.need(node.left, a, ok, what, node)
        self.need(node.right, b, ok, what, node)

    def call(self, node: FuncCall) -> str:
        f = node.func
        if f == "age":
            return "number"
        ts = [self.type(a) for a in node.args]
        for a, t in zip(node.args, ts):
            if f in ("any", "all", "count"):
                self.need(a, t, _ARRAYS, f"{f}() takes an array", node)
            elif f == "len":
                if t not in ("any", "array_bool", "array_number", "array_other"):
                    self.need(a, t, ("array_number",), "len() takes an array", node)
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
