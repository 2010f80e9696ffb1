"""The binding expression parser: text -> :class:`~fretc.signals.bindings.expression.Expr`.

An expression (``"min(/scan.ranges) < 0.9"``) is parsed with Lark (LALR, contextual lexer)
from the grammar ``signals/bindings/grammar.lark``; :class:`_ToExpr`, a Lark
``Transformer`` whose callbacks are named after the grammar's rules, turns the parse tree
into the expression tree, which :func:`parse_expression` then checks (size, topics,
functions; :mod:`fretc.signals.bindings.expression`). Errors are
:class:`fretc.common.problems.BindingError` naming the binding file, line, column and variable.
"""

from __future__ import annotations

import math
import os
import re
from functools import lru_cache
from typing import cast

from lark import Lark, Transformer, __version__ as lark_version, v_args
from lark.exceptions import (UnexpectedCharacters, UnexpectedEOF, UnexpectedInput,
                             UnexpectedToken, VisitError)

from fretc.common import lark_tables
from fretc.common.libraries import check_lark
from fretc.common.problems import BindingError
from fretc.common.units import parse_duration
from fretc.fretish.limits import MAX_EXPR_DEPTH
from fretc.signals.bindings.expression import (MAX_EXPR_CHARS, MODIFIERS, STATEFUL, BinOp, Const, EntityParam, Expr,
                         ExprLocation, Field, Filter, FuncCall, Named, Ref, Slice, Span,
                         TF_COMPONENTS, UnaryOp, check, check_size)
from fretc.signals.bindings.geometry_args import GEOMETRY, expand
from fretc.signals.bindings.paths import unquote

__all__ = ["parse_expression"]


# ------------------------------------------------------------------------------------------------
# Parsing
# ------------------------------------------------------------------------------------------------


_LARK_OPTIONS = dict(parser="lalr", lexer="contextual", propagate_positions=True,
                     maybe_placeholders=False)


@lru_cache(maxsize=1)
def _parser() -> Lark:
    """The Lark parser of ``grammar.lark``, its tables kept in fretc's cache folder
    (:func:`fretc.common.lark_tables.cached_parser`: a sealed entry of plain data, never
    unpickled; built in memory when the cache is off)."""
    check_lark(lark_version)
    with open(os.path.join(os.path.dirname(__file__), "grammar.lark"), encoding="utf-8") as f:
        grammar = f.read()
    return cast(Lark, lark_tables.cached_parser(
        "bindings", grammar, _LARK_OPTIONS, {}, lambda: Lark(grammar, **_LARK_OPTIONS)))


def _col(meta: object) -> int:
    return meta.column if not meta.empty else 1  # type: ignore[attr-defined]


@v_args(meta=True)
class _ToExpr(Transformer):
    """Parse tree -> :class:`Expr`; one callback per rule (alias) of ``grammar.lark``."""

    def __init__(self, where: ExprLocation, path_vars: dict | None = None) -> None:
        super().__init__(visit_tokens=False)
        self.where = where
        self.path_vars = path_vars or {}

    def _variable(self, tok) -> bool | float | str:
        """The value of FoxQL variable ``$name`` (the binding file's ``[path_variables]``).

        Raises:
            BindingError: a variable the file does not define, at its column.
        """
        name = str(tok)[1:]
        if name not in self.path_vars:
            known = ", ".join(f"${k}" for k in sorted(self.path_vars)) or "none"
            raise self.where.error(f"message path variable ${name} has no value: give it in "
                                   f"the binding file's [path_variables] table ({name} = 3) "
                                   f"(defined: {known})", tok.column)
        return self.path_vars[name]

    def path_variable(self, meta, kids):
        v = self._variable(kids[0])
        if isinstance(v, EntityParam):  # an entity's key, read at evaluation
            return Const(kids[0].column, v)
        return Const(kids[0].column, v if isinstance(v, (bool, str)) else float(v))

    def number(self, meta, kids):
        return Const(_col(meta), float(kids[0]))

    def span(self, meta, kids):
        """``2s``, ``500 ms``, ``50 messages``: a window's :class:`Span` (durations by
        :func:`fretc.common.units.parse_duration`)."""
        text = str(kids[0])
        m = re.match(r"([0-9.eE+-]+) ?([a-z]+)", text)
        assert m is not None
        number, unit = m.group(1), m.group(2)
        if unit.startswith("message"):
            if not number.isdigit() or int(number) < 1:
                raise self.where.error(f"{text}: a count of messages is a whole number of at "
                                       "least 1", _col(meta))
            return Span(_col(meta), text, None, int(number))
        try:
            return Span(_col(meta), text, parse_duration(f"{number} {unit}"), None)
        except ValueError as exc:
            raise self.where.error(f"window {text}: {exc}", _col(meta)) from None

    def neg_number(self, meta, kids):
        return Const(_col(meta), -float(kids[0]))

    def string(self, meta, kids):
        return Const(_col(meta), unquote(str(kids[0])))

    def named(self, meta, kids):
        return Named(kids[0].column, str(kids[0]))

    def true(self, meta, kids):
        return Const(_col(meta), True)

    def false(self, meta, kids):
        return Const(_col(meta), False)

    def attr(self, meta, kids):
        return str(kids[0])

    def index(self, meta, kids):
        return int(kids[0])

    def slice_lo(self, meta, kids):
        if kids and kids[0].type == "VARIABLE":
            v = self._variable(kids[0])
            if isinstance(v, bool) or not isinstance(v, int):
                raise self.where.error(f"{kids[0]} is {v!r}: a slice bound is an integer",
                                       kids[0].column)
            return v
        return int(kids[0]) if kids else None

    slice_hi = slice_lo

    def slice(self, meta, kids):
        return Slice(kids[0], kids[1])

    def filter_path(self, meta, kids):
        return tuple(str(k) for k in kids)

    def filter(self, meta, kids):
        path, op, value = kids
        return Filter(path, "=" if op == "==" else str(op), value)

    def modifier(self, meta, kids):
        return kids[0]  # the NAME token (its column for errors)

    def field(self, meta, kids):
        tok = kids[0]
        mods = [k for k in kids[1:] if getattr(k, "type", None) == "NAME"]
        path = tuple(k for k in kids[1:] if getattr(k, "type", None) != "NAME")
        topic = unquote(str(tok)) if tok.type == "STRING" else str(tok)
        lead = 0  # filters right after the topic select whole messages: a stream
        while lead < len(path) and isinstance(path[lead], Filter):
            lead += 1
        filters = path[:lead]
        if filters:
            topic += "".join(f.text() for f in filters)
        out: Expr = Field(tok.column, topic, path[lead:], filters)
        for i, m in enumerate(mods):
            out = apply_modifier(out, str(m), m.column, first=i == 0, where=self.where)
        return out

    def ref(self, meta, kids):
        return Ref(kids[0].column, str(kids[0]))

    def neg(self, meta, kids):
        return UnaryOp(_col(meta), "-", kids[0])

    def not_(self, meta, kids):
        return UnaryOp(_col(meta), "!", kids[0])

    def arith(self, meta, kids):
        left, op, right = kids
        return BinOp(op.column, "=" if op == "==" else str(op), left, right)

    compare = arith

    def member(self, meta, kids):
        """``x in [a, b]``: ``(x = a) | (x = b)``."""
        item, word, values = kids[0], kids[1], kids[2:]
        out: Expr = BinOp(word.column, "=", item, values[0])
        for v in values[1:]:
            out = BinOp(word.column, "|", out, BinOp(word.column, "=", item, v))
        return out

    def and_(self, meta, kids):
        return BinOp(_col(meta), "&", kids[0], kids[1])

    def or_(self, meta, kids):
        return BinOp(_col(meta), "|", kids[0], kids[1])

    def implies(self, meta, kids):
        return BinOp(_col(meta), "->", kids[0], kids[1])

    def iff(self, meta, kids):
        return BinOp(_col(meta), "<->", kids[0], kids[1])

    def call(self, meta, kids):
        name = kids[0]
        args = tuple(k for k in kids[1:] if k is not None)
        if name == "tf":
            raise self.where.error('tf() gives a transform: name one of its components, '
                                   'e.g. tf("map", "base_link").x (components: '
                                   f'{", ".join(TF_COMPONENTS)})', name.column)
        if ((name == "age" and len(args) == 1 or name == "rate" and len(args) == 2)
                and isinstance(args[0], (Const, Ref))):
            a = args[0]  # age("ORB-SLAM"), age(groundtruth), rate("ORB-SLAM", 1s): a topic
            topic = a.value if isinstance(a, Const) else a.name
            if isinstance(topic, str):
                args = (Field(a.col, topic, ()),) + args[1:]
        if name in ("called", "answered", "waiting", "goal_waiting"):
            return _service_call(str(name), args, self.where, name.column)
        if name == "joint":
            args = _joint_args(args, self.where, name.column)
        if name == "sector":
            args = _sector_args(args, self.where, name.column)
        if name in GEOMETRY:  # (docs/bindings.md "Geometry": the fields each reads)
            return expand(str(name), args, self.where, name.column)
        return FuncCall(name.column, str(name), args)

    def call_member(self, meta, kids):
        name, member = kids[0], kids[-1]
        args = tuple(k for k in kids[1:-1] if k is not None)
        if name != "tf":
            raise self.where.error(f"{name}(...).{member}: only tf() has components",
                                   member.column)
        if str(member) not in TF_COMPONENTS:
            raise self.where.error(f"tf(...) has no component {str(member)!r} (components: "
                                   f"{', '.join(TF_COMPONENTS)})", member.column)
        if len(args) != 2 or not all(isinstance(a, Const) and isinstance(a.value, (str,
                                                                                 EntityParam))
                                     for a in args):
            raise self.where.error('tf() takes two frame names, each in quotes or an entity '
                                   'of [entities]: tf("map", "base_link").x, tf("map", $car).x',
                                   name.column)
        return FuncCall(name.column, "tf", args + (Const(member.column, str(member)),))


#: The events of a service on its rosbag2 topic ``<service>/_service_event`` (ROS 2 Jazzy's
#: service introspection, service_msgs/msg/ServiceEventInfo's ``event_type``): a request
#: (REQUEST_SENT 0, REQUEST_RECEIVED 1) and a response (RESPONSE_SENT 2, RESPONSE_RECEIVED 3).
SERVICE_EVENT_TOPIC = "/_service_event"


def _service_call(name: str, args: tuple, where: ExprLocation, col: int) -> Expr:
    """``called(/arm)`` -> ``any_of_messages(/arm/_service_event.info.event_type <= 1)`` (a
    request since the previous tick), ``answered(/arm)`` the same with ``>= 2`` (a response),
    ``waiting(/arm)`` -> the call to ``waiting`` of the event topic (the oldest unanswered
    call's wait, :mod:`fretc.signals.windows`); ``goal_waiting(/navigate)`` -> the call of
    the action's status topic ``/navigate/_action/status`` (the oldest active goal's wait).

    Raises:
        BindingError: the argument is not a service name (``/arm``, ``"arm"``).
    """
    a = args[0] if len(args) == 1 else None
    if isinstance(a, Const) and isinstance(a.value, str):
        a = Field(a.col, a.value, ())
    if not isinstance(a, Field) or a.path:
        raise where.error(f"{name}() takes a service's name, e.g. {name}(/arm): its events are "
                          f"the topic /arm{SERVICE_EVENT_TOPIC}", col)
    if name == "goal_waiting":  # an action's goals: its status topic (ROS 2 actions)
        return FuncCall(col, "goal_waiting", (Field(a.col, a.topic.rstrip("/")
                                                    + "/_action/status", ()),))
    topic = a.topic.rstrip("/") + SERVICE_EVENT_TOPIC
    if name == "waiting":
        return FuncCall(col, "waiting", (Field(a.col, topic, ()),))
    etype = Field(a.col, topic, ("info", "event_type"))
    test = BinOp(col, "<=", etype, Const(col, 1.0)) if name == "called" else BinOp(
        col, ">=", etype, Const(col, 2.0))
    return FuncCall(col, "any_of_messages", (test,))


def apply_modifier(e: Expr, name: str, col: int, first: bool, where: ExprLocation) -> Expr:
    """``e@name`` (Foxglove's message path modifiers, as its plot panel has them) as an
    expression of the language: ``@abs`` -> ``abs(e)``, ``@negative`` -> ``-e``, ``@sqrt`` ->
    ``sqrt(e)``, ``@rad2deg``/``@deg2rad`` -> ``e * 180/pi`` / ``e * pi/180``; ``@delta``,
    ``@timedelta``, ``@derivative`` -> ``delta(e)`` etc. (between the held message of the
    field's topic and the one before it; only right after the field).

    Raises:
        BindingError: an unknown modifier, or a message-to-message one after another
            modifier, at ``col``.
    """
    if name == "abs" or name == "sqrt":
        return FuncCall(col, name, (e,))
    if name == "negative":
        return UnaryOp(col, "-", e)
    if name in ("rad2deg", "deg2rad"):
        k = 180.0 / math.pi if name == "rad2deg" else math.pi / 180.0
        return BinOp(col, "*", e, Const(col, k))
    if name in STATEFUL:
        if not first:
            raise where.error(f"@{name} compares a field's value with the previous message's: "
                              "write it right after the field (e.g. /odom.twist.twist.linear.x"
                              f"@{name}@abs)", col)
        return FuncCall(col, name, (e,))
    raise where.error(f"unknown modifier @{name} (known: {', '.join(MODIFIERS)})", col)


def _joint_args(args: tuple, where: ExprLocation, col: int) -> tuple:
    """``joint(/js.position, "wheel")`` -> (the values field, the name, the ``name`` array
    beside the values field)."""
    if (len(args) != 2 or not isinstance(args[0], Field) or not args[0].path
            or not isinstance(args[0].path[-1], str) or not isinstance(args[1], Const)
            or not isinstance(args[1].value, (str, EntityParam))):
        raise where.error('joint() takes an array field and a joint name in quotes: '
                          'joint(/joint_states.position, "wheel_left_joint")', col)
    f = args[0]
    return (f, args[1], Field(f.col, f.topic, f.path[:-1] + ("name",)))


def _sector_args(args: tuple, where: ExprLocation, col: int) -> tuple:
    """``sector(/scan.ranges, lo, hi)`` -> (the ranges field, lo, hi, the scan's
    ``angle_min``, its ``angle_increment``: read with the ranges).

    Raises:
        BindingError: not a LaserScan's ``ranges`` field and two ends, at ``col``."""
    f = args[0] if args else None
    if (len(args) != 3 or not isinstance(f, Field) or not f.path or f.path[-1] != "ranges"
            or f.multi or f.filters):
        raise where.error("sector() takes a LaserScan's ranges and the sector's ends in "
                          "radians (REP 103: 0 ahead, counter-clockwise), e.g. "
                          "min(sector(/scan.ranges, -0.785, 0.785))", col)
    base = f.path[:-1]
    return (f, args[1], args[2], Field(f.col, f.topic, base + ("angle_min",)),
            Field(f.col, f.topic, base + ("angle_increment",)))


def _syntax_error(expr: str, exc: UnexpectedInput, where: ExprLocation) -> BindingError:
    col = getattr(exc, "column", None)
    if isinstance(exc, UnexpectedCharacters):
        msg = f"unexpected character {expr[exc.pos_in_stream]!r}"  # type: ignore[index]  # set by UnexpectedCharacters
    elif isinstance(exc, UnexpectedEOF) or (isinstance(exc, UnexpectedToken)
                                            and exc.token.type == "$END"):
        msg = "expression ends too early"
        col = len(expr) + 1
    elif isinstance(exc, UnexpectedToken):
        msg = f"unexpected {str(exc.token)!r}"
    else:  # pragma: no cover
        msg = "syntax error"
    if not isinstance(col, int) or col < 1:
        col = None
    return where.error(f"syntax error: {msg}", col)


def parse_expression(expr: str, where: ExprLocation, path_vars: dict | None = None
                     ) -> tuple[Expr, frozenset[str]]:
    """Parse and check (:func:`check`) one expression; ``path_vars`` the values of FoxQL's
    message path variables (``$track``: name -> bool, number or string).

    Returns:
        the tree and the topics it reads (fields and ``age``); references (:class:`Ref`)
        are left in the tree.

    Raises:
        BindingError: empty text, a syntax error, or a failed static check, at ``where``.
    """
    if not expr.strip():
        raise where.error("empty expression")
    if len(expr) > MAX_EXPR_CHARS:
        raise where.error(f"the expression has {len(expr):,} characters; the limit is "
                          f"{MAX_EXPR_CHARS:,}")
    try:
        tree = _parser().parse(expr)
    except UnexpectedInput as exc:
        raise _syntax_error(expr, exc, where) from None
    try:
        node = _ToExpr(where, path_vars).transform(tree)
    except VisitError as exc:
        raise exc.orig_exc from None
    except RecursionError:
        raise where.error(f"the expression is nested more than {MAX_EXPR_DEPTH} levels deep "
                          "(operators, signs, calls)") from None
    check_size(node, where)
    topics: set[str] = set()
    check(node, where, topics)
    return node, frozenset(topics)
