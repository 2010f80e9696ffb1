"""The binding expression language: its tree and its static checks.

An expression (``"min(/scan.ranges) < 0.9"``) is parsed by :mod:`fretc.signals.bindings.parse`
into the frozen dataclasses below (:class:`Expr` and its subclasses; ``col`` is the 1-based
column in the expression text, for error messages).  The language itself (operators,
functions, values) is described in ``docs/bindings.md`` and in :mod:`fretc.signals.bindings`.

Errors are :class:`fretc.common.problems.BindingError` naming the binding file, line, column
and variable (:class:`ExprLocation` maps a column in the expression to one in the file).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass

from fretc.common.problems import BindingError
from fretc.common.streams import base_topic
from fretc.fretish.limits import MAX_EXPR_DEPTH, MAX_EXPR_NODES
from fretc.logs.schema import closest
from fretc.signals.bindings.paths import quote, topic_text

__all__ = ["Expr", "EntityParam", "const_value", "Const", "Named", "Slice", "Filter", "Field", "Ref", "UnaryOp", "BinOp",
           "FuncCall", "Span", "FUNCS", "GEOMETRY_CALLS", "GEOMETRY_VALUES", "geometry_tf", "MODIFIERS", "STATEFUL", "stateful_topics", "age_only_topics", "AGGREGATES", "check_aggregate", "written", "TF_COMPONENTS", "TF_TOPICS",
           "ExprLocation", "check", "check_size", "walk", "refs",
           "substitute", "unparse", "MAX_EXPR_CHARS"]

#: Characters of one binding expression (real ones have tens; the text is parsed whole)
MAX_EXPR_CHARS = 20_000


# ------------------------------------------------------------------------------------------------
# The expression tree
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Expr:
    """Base of expression nodes; ``col`` is the 1-based column in the expression text."""

    col: int


class EntityParam:
    """The value of an entity's variable (``$track``, docs/bindings.md "One verdict per
    entity") read when a binding is evaluated rather than when it is compiled: one compiled
    binding serves every entity of a log, the audit setting :attr:`value` to each entity's
    key before evaluating it (:mod:`fretc.audit.entities.read`). Written ``$name``."""

    __slots__ = ("name", "value", "time")

    def __init__(self, name: str) -> None:
        self.name = name
        self.value: object = None
        #: the time (ns, the bindings' time base) of the entity's newest message, for
        #: ``age($car)`` (set with :attr:`value` where entities are held on their own)
        self.time: int | None = None

    def __repr__(self) -> str:
        return f"${self.name}"


def const_value(v: object) -> object:
    """A constant's value as read now (an :class:`EntityParam`'s current value)."""
    return v.value if isinstance(v, EntityParam) else v


@dataclass(frozen=True)
class Const(Expr):
    """``1.5``, ``2e-3``, ``true``, ``false``, ``"charging"``: a float, a bool or a string;
    or an :class:`EntityParam` (an entity's key, set at evaluation)."""

    value: bool | float | str | EntityParam


@dataclass(frozen=True)
class Named(Expr):
    """A named constant of a message definition (``POWER_SUPPLY_STATUS_CHARGING``,
    DiagnosticStatus's ``ERROR``): a name in capitals that is not a variable of the binding
    file; its value is looked up in the log's schema of the field it is compared with
    (:mod:`fretc.signals.bindings.typecheck`)."""

    name: str


@dataclass(frozen=True)
class Slice:
    """``[lo:hi]`` of an array field (Python slice rules; None = open end)."""

    lo: int | None
    hi: int | None

    def text(self) -> str:
        """``[lo:hi]`` as written (open ends empty)."""
        return f"[{'' if self.lo is None else self.lo}:{'' if self.hi is None else self.hi}]"


@dataclass(frozen=True)
class Filter:
    """``{name=="battery"}`` (Foxglove's message path filter): keeps the items of an array
    of messages whose field ``path`` compares true (``op`` one of ``= != < <= > >=``) with
    ``value`` (a :class:`Const` or a :class:`Named` constant)."""

    path: tuple[str, ...]
    op: str
    value: Expr

    def text(self) -> str:
        """``{name=="battery"}`` as written (``=`` printed as ``==``)."""
        op = "==" if self.op == "=" else self.op
        return "{" + ".".join(self.path) + op + unparse(self.value) + "}"


@dataclass(frozen=True)
class Field(Expr):
    """``/topic.a.b[i]``: ``path`` holds attribute names (str), indexes (int), slices
    (:class:`Slice`) and filters (:class:`Filter`); after a slice or a filter the rest of
    the path applies to each item and the value is the array of the results."""

    topic: str
    path: tuple[str | int | Slice | Filter, ...]
    #: filters written right after the topic (``/track{id==3}.x``): ``topic`` is then the
    #: stream of the messages that pass them (``/track{id==3}``, :mod:`fretc.common.streams`)
    #: and ``path`` the rest of the path
    filters: tuple[Filter, ...] = ()

    def text(self) -> str:
        """``/topic.a[2].b`` (a topic that is not a plain ROS name quoted): the field as
        written in a binding."""
        out = topic_text(base_topic(self.topic) if self.filters else self.topic)
        for p in self.filters + self.path:
            out += (p.text() if isinstance(p, (Slice, Filter)) else f"[{p}]"
                    if isinstance(p, int) else f".{p}")
        return out

    @property
    def multi(self) -> bool:
        """Whether the path has a slice or a filter before its end, or a filter at the end
        (its value is then an array of items read from each)."""
        return any(isinstance(p, Filter) for p in self.path) or any(
            isinstance(p, Slice) for p in self.path[:-1])


@dataclass(frozen=True)
class Ref(Expr):
    """Another variable of the same binding file, by name (substituted before compiling)."""

    name: str


@dataclass(frozen=True)
class UnaryOp(Expr):
    """``-a`` (``op`` ``"-"``) or ``!a`` (``op`` ``"!"``)."""

    op: str
    arg: Expr


@dataclass(frozen=True)
class BinOp(Expr):
    """``left op right``; ``op`` one of ``+ - * / < <= > >= = != & | -> <->``."""

    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True)
class Span(Expr):
    """The window of a window function, its last argument (``mean(/battery.current, 2s)``):
    a duration (``ns``, from ``2s``, ``500 ms``, ``1 min``) or a count of messages
    (``messages``, from ``50 messages``); ``text`` as written
    (:mod:`fretc.signals.bindings.windowing`)."""

    text: str
    ns: int | None
    messages: int | None


@dataclass(frozen=True)
class FuncCall(Expr):
    """``func(args...)``, ``func`` a name of :data:`FUNCS`."""

    func: str
    args: tuple[Expr, ...]


#: The functions of the language: name -> (min args, max args or None). ``sector`` is
#: written with three (``sector(/scan.ranges, lo, hi)``; the scan's ``angle_min`` and
#: ``angle_increment`` are added as the fourth and fifth, so that they are read). ``joint`` is
#: written with two (``joint(/joint_states.position, "wheel")``; the ``name`` array beside
#: the first is added as a third), ``tf`` as ``tf("map", "base_link").x`` (the component
#: is its third).
FUNCS = {
    "abs": (1, 1), "norm": (1, None), "min": (1, None), "max": (1, None), "mean": (1, 1),
    "any": (1, 1), "all": (1, 1), "count": (1, 1), "len": (1, 1), "invalid": (1, 1), "age": (1, 1), "waiting": (1, 1), "goal_waiting": (1, 1),
    "joint": (3, 3), "tf": (3, 3),
    "any_of_messages": (1, 1), "all_of_messages": (1, 1), "count_of_messages": (1, 1),
    "min_of_messages": (1, 1), "max_of_messages": (1, 1),
    "sqrt": (1, 1), "delta": (1, 1), "timedelta": (1, 1), "derivative": (1, 1),
    "unchanged": (1, 1), "sector": (5, 5),
    # trigonometry (rad), item by item on arrays
    "sin": (1, 1), "cos": (1, 1), "tan": (1, 1), "asin": (1, 1), "acos": (1, 1),
    "atan": (1, 1), "atan2": (2, 2),
    # geometry (docs/bindings.md "Geometry"): the arities of the forms the parser expands
    # them into (fretc.signals.bindings.geometry_args)
    "scan_points": (4, 5), "cloud_points": (10, 11), "polygon": (3, None),
    "points_in": (2, 2), "collision_time": (6, 7),
}
#: The geometry calls; those whose value is points or a polygon, which only ``points_in`` and
#: ``collision_time`` take
GEOMETRY_CALLS = ("scan_points", "cloud_points", "polygon", "points_in", "collision_time")
GEOMETRY_VALUES = ("scan_points", "cloud_points", "polygon")
#: Foxglove's message path modifiers a field may end in (``/odom.x@derivative``).
MODIFIERS = ("derivative", "delta", "timedelta", "abs", "negative", "sqrt", "rad2deg",
             "deg2rad")
#: The modifiers (and functions) that read the message before the held one of the field's
#: topic: ``delta`` (value - previous value), ``timedelta`` (seconds between the two, on
#: the time base), ``derivative`` (delta / timedelta, per second), ``unchanged`` (true when
#: the value, a number or a whole array such as a LaserScan's ranges, is bit for bit the
#: previous message's: a driver republishing a frozen frame with fresh stamps; NaN items
#: equal). A tick is evaluated once the topic has two messages (warm-up until then).
STATEFUL = ("delta", "timedelta", "derivative", "unchanged")
#: Aggregations over the messages of one topic since the previous tick (docs/bindings.md, "events
#: between ticks"): function -> how the per-message values are folded. Only as the whole
#: binding; :func:`check_aggregate`.
AGGREGATES = {"any_of_messages": "any", "all_of_messages": "all",
              "count_of_messages": "count", "min_of_messages": "min",
              "max_of_messages": "max"}
#: The components of ``tf(parent, child)``: translation (m), yaw (rad) and age (s).
TF_COMPONENTS = ("x", "y", "z", "yaw", "age")
#: The topics ``tf()`` reads (REP 105 / tf2: dynamic and static transforms).
TF_TOPICS = ("/tf", "/tf_static")


def walk(node: Expr) -> Iterator[Expr]:
    """``node`` and every node below it, depth first, left to right (pre-order)."""
    yield node
    if isinstance(node, UnaryOp):
        yield from walk(node.arg)
    elif isinstance(node, BinOp):
        yield from walk(node.left)
        yield from walk(node.right)
    elif isinstance(node, FuncCall):
        for a in node.args:
            yield from walk(a)


def refs(node: Expr) -> list[str]:
    """Names of the variables ``node`` refers to, in order of appearance."""
    return [n.name for n in walk(node) if isinstance(n, Ref)]


def unparse(node: Expr) -> str:
    """Expression text of a node (fully parenthesized where it matters).

    Raises:
        TypeError: a :class:`Ref` (substitute references first).
    """
    if isinstance(node, Const):
        v = node.value
        if isinstance(v, EntityParam):
            return repr(v)
        if isinstance(v, str):
            return quote(v)
        return ("true" if v else "false") if isinstance(v, bool) else repr(float(v))
    if isinstance(node, Named):
        return node.name
    if isinstance(node, Field):
        return node.text()
    if isinstance(node, UnaryOp):
        arg = unparse(node.arg) if node.op == "!" else _operand(node.arg)
        return f"{node.op}{arg}"
    if isinstance(node, BinOp):
        return f"({_operand(node.left)} {node.op} {_operand(node.right)})"
    if isinstance(node, Span):
        return node.text
    if isinstance(node, FuncCall):
        if node.func in GEOMETRY_CALLS:
            return _geometry_text(node)
        if node.func == "tf":
            a = node.args
            return f"tf({unparse(a[0])}, {unparse(a[1])}).{a[2].value}"  # type: ignore
        args = (node.args[:2] if node.func == "joint" else node.args[:3]
                if node.func == "sector" else node.args)
        return f"{node.func}({', '.join(unparse(a) for a in args)})"
    raise TypeError(type(node).__name__)


def _geometry_text(node: FuncCall) -> str:
    """A geometry call (:mod:`fretc.signals.bindings.geometry_args`: its canonical arguments)
    as written."""
    a = node.args
    if node.func not in GEOMETRY_VALUES:
        return f"{node.func}({', '.join(unparse(x) for x in a)})"
    kind = a[0].value  # type: ignore[attr-defined]

    def base(f: Expr, drop: int) -> str:  # (the message a canonical field was read from)
        assert isinstance(f, Field)
        return Field(f.col, f.topic, f.path[:len(f.path) - drop]).text()

    if node.func in ("scan_points", "cloud_points"):
        rest = [quote(str(kind))] if kind else []
        low = a[1] if node.func == "cloud_points" else None
        if isinstance(low, (Const, UnaryOp)) and unparse(low) not in ("-inf", "(-inf)"):
            rest += [unparse(a[1]), unparse(a[2])]
        first = base(a[1] if node.func == "scan_points" else a[3], 1)
        return f"{node.func}({', '.join([first, *rest])})"
    if kind == "vertices":
        return f"polygon({', '.join(unparse(x) for x in a[1:])})"
    return f"polygon({base(a[1], 4 if kind == 'stamped' else 3)})"


def _operand(node: Expr) -> str:
    """``unparse`` of an operand: ``!`` binds looser than comparisons, arithmetic and unary
    minus (grammar.lark), so a negation inside them is parenthesized: ``(!a) = b``."""
    text = unparse(node)
    return f"({text})" if isinstance(node, UnaryOp) and node.op == "!" else text


# ------------------------------------------------------------------------------------------------
# Where an error is
# ------------------------------------------------------------------------------------------------


class ExprLocation:
    """Maps a column in the expression to file:line:col for error messages.

    ``line``/``col`` are where the expression text starts in ``source`` (1-based; None when
    unknown); ``exact`` is False when columns inside the expression do not map one to one
    onto the file (escapes, multi-line strings): the column in the expression is then said in
    words.
    """

    def __init__(self, source: str, variable: str | None, line: int | None, col: int | None,
                 exact: bool = True) -> None:
        self.source, self.variable, self.line, self.col, self.exact = (source, variable, line,
                                                                        col, exact)

    def error(self, message: str, expr_col: int | None = None) -> BindingError:
        """A :class:`BindingError` at column ``expr_col`` of the expression (None: at its
        start)."""
        line, col = self.line, self.col
        if expr_col is not None:
            if col is not None and self.exact:
                col = col + expr_col - 1
            else:
                message = f"{message} (column {expr_col} of the expression)"
        return BindingError(self.source, message, line=line, col=col, variable=self.variable)


# ------------------------------------------------------------------------------------------------
# Static checks and references
# ------------------------------------------------------------------------------------------------


def check_size(node: Expr, where: ExprLocation, what: str = "the expression") -> None:
    """The limits of requirements (:mod:`fretc.fretish.limits`) for a binding expression: at most
    :data:`~fretc.fretish.limits.MAX_EXPR_NODES` nodes counted as expanded (a variable referred to
    twice counts twice) and :data:`~fretc.fretish.limits.MAX_EXPR_DEPTH` levels. Shared subtrees
    (references substituted) are counted once per use without walking them again, so a
    chain of doubling references is refused in linear time.

    Raises:
        BindingError: over a limit, naming the limit.
    """
    size: dict[int, int] = {}
    depth: dict[int, int] = {}
    stack: list[tuple[Expr, bool]] = [(node, False)]
    while stack:
        n, done = stack.pop()
        if id(n) in size:
            continue
        kids = _children(n)
        if not done:
            stack.append((n, True))
            stack.extend((k, False) for k in kids if id(k) not in size)
            continue
        size[id(n)] = 1 + sum(size[id(k)] for k in kids)
        depth[id(n)] = 1 + max((depth[id(k)] for k in kids), default=0)
        if size[id(n)] > MAX_EXPR_NODES:
            raise where.error(f"{what} has more than {MAX_EXPR_NODES:,} names, numbers and "
                              "operators (counting each use of a referred variable)")
        if depth[id(n)] > MAX_EXPR_DEPTH:
            raise where.error(f"{what} is nested more than {MAX_EXPR_DEPTH} levels deep")


def _children(n: Expr) -> tuple[Expr, ...]:
    if isinstance(n, UnaryOp):
        return (n.arg,)
    if isinstance(n, BinOp):
        return (n.left, n.right)
    if isinstance(n, FuncCall):
        return tuple(n.args)
    return ()


def check(node: Expr, where: ExprLocation, topics: set[str]) -> None:
    """Static checks: known functions and arities, age() of a topic, fields below topics.
    Adds the topics ``node`` reads to ``topics``.

    Raises:
        BindingError: the first failed check, at ``where``.
    """
    if isinstance(node, Field):
        names = [p for p in node.path if isinstance(p, str)]
        names += [n for p in node.path if isinstance(p, Filter) for n in p.path]
        for p in names:
            if p.startswith("_"):
                raise where.error(f"{node.text()}: {p!r} is not a message field (ROS field "
                                  "names start with a letter; a binding reads only fields the "
                                  "message type declares)", node.col)
        if not node.path:
            raise where.error(f"{node.topic} is a topic, not a value: name a field "
                              f"(e.g. {node.topic}.data) or use age({node.topic})", node.col)
        topics.add(node.topic)
    elif isinstance(node, UnaryOp):
        check(node.arg, where, topics)
    elif isinstance(node, BinOp):
        check(node.left, where, topics)
        check(node.right, where, topics)
    elif isinstance(node, FuncCall):
        _check_call(node, where, topics)
    # a Ref is resolved against the other variables (substitute)


def geometry_tf(node: FuncCall) -> bool:
    """Whether the geometry call ``node`` reads TF (points moved into a named frame, or a
    polygon read in its header's frame), itself or through its arguments."""
    if node.func in ("scan_points", "cloud_points"):
        return bool(const_value(node.args[0].value))  # type: ignore[attr-defined]
    if node.func == "polygon":
        return const_value(node.args[0].value) == "stamped"  # type: ignore[attr-defined]
    return any(isinstance(a, FuncCall) and a.func in GEOMETRY_CALLS and geometry_tf(a)
               for a in node.args)


def _check_geometry(node: FuncCall, where: ExprLocation, topics: set[str]) -> None:
    """``points_in``/``collision_time``: their points and polygon (values only they take)
    read the topics of their fields; TF when they move points between frames."""
    for a in node.args[:2]:
        assert isinstance(a, FuncCall)  # (geometry_args.expand checked)
        for x in a.args:
            if isinstance(x, Field):
                topics.add(x.topic)
            elif not isinstance(x, Const):
                check(x, where, topics)
    if geometry_tf(node):
        topics.update(TF_TOPICS)
    for a in node.args[2:]:
        check(a, where, topics)


def _check_call(node: FuncCall, where: ExprLocation, topics: set[str]) -> None:
    if node.func in GEOMETRY_VALUES:
        raise where.error(f"{unparse(node)} gives {'a polygon' if node.func == 'polygon' else 'points'}, "
                          "which only points_in() and collision_time() take (a variable is a "
                          "boolean or a number)", node.col)
    if node.func in ("points_in", "collision_time"):
        _check_geometry(node, where, topics)
        return
    if node.args and isinstance(node.args[-1], Span):  # a window (windowing.check_window)
        for a in node.args[:-1]:
            if isinstance(a, Field) and not a.path:  # rate(/scan, 1s), count(/estop, 1min)
                topics.add(a.topic)
            else:
                check(a, where, topics)
        return
    last = node.args[-1] if node.args else None
    if isinstance(last, UnaryOp) and last.op == "-" and isinstance(last.arg, Span):
        raise where.error(f"{node.func}(): a window's span must be positive, not "
                          f"-{last.arg.text}", node.col)
    if node.func == "count_ticks":
        raise where.error("count_ticks() takes a condition and a duration, e.g. "
                          "count_ticks(too_close, 1min)", node.col)
    if node.func in ("sum", "median", "percentile", "variance", "rate"):
        q = ", 95" if node.func == "percentile" else ""
        arg = "/topic" if node.func == "rate" else "/topic.field"
        raise where.error(f"{node.func}() is a window function: its last argument is the "
                          f"window, e.g. {node.func}({arg}{q}, 2s)"
                          + ("" if node.func == "rate" else
                             f" or {node.func}({arg}{q}, 50 messages)"), node.col)
    if node.func not in FUNCS:
        raise where.error(f"unknown function {node.func!r} (known: "
                          f"{', '.join(sorted(FUNCS))})", node.col)
    lo, hi = FUNCS[node.func]
    n = len(node.args)
    if n < lo or (hi is not None and n > hi):
        want = f"{lo}" if lo == hi else f"at least {lo}"
        raise where.error(f"{node.func}() takes {want} argument(s), got {n}", node.col)
    if node.func == "tf":
        topics.update(TF_TOPICS)
        return
    if node.func in STATEFUL:
        stateful_arg = node.args[0]
        fields = {n.topic for n in walk(stateful_arg) if isinstance(n, Field)}
        other = [n for n in walk(stateful_arg) if isinstance(n, FuncCall)
                 and n.func in ("age", "tf") + STATEFUL + tuple(AGGREGATES)]
        if (isinstance(stateful_arg, Field) and not stateful_arg.path) or len(fields) != 1 or other:
            raise where.error(f"{node.func}() (the @{node.func} modifier) takes a field of a "
                              "message, or an expression of the fields of one topic, e.g. "
                              f"/odom.twist.twist.linear.x@{node.func} or "
                              f"{node.func}(joint(/joint_states.position, \"wheel\"))",
                              node.col)
    if node.func == "sector":
        ranges = node.args[0]
        if not (isinstance(ranges, Field) and ranges.path and ranges.path[-1] == "ranges"
                and not ranges.multi and not ranges.filters):
            raise where.error("sector() takes a LaserScan's ranges and the sector's ends in "
                              "radians (REP 103: 0 ahead, counter-clockwise), e.g. "
                              "min(sector(/scan.ranges, -0.785, 0.785))", node.col)
    if node.func in ("waiting", "goal_waiting"):  # a service's or an action's topic (parse.py)
        topics.add(node.args[0].topic)  # type: ignore[attr-defined]
        return
    if node.func == "age":
        age_arg = node.args[0]
        if isinstance(age_arg, Const) and isinstance(age_arg.value, EntityParam):
            return  # age($car): how old the entity's own newest message is (entities held)
        if not isinstance(age_arg, Field) or age_arg.path:
            raise where.error("age() takes a topic name, e.g. age(/scan), or an entity held "
                              "on its own, age($car)", age_arg.col)
        topics.add(age_arg.topic)
        return
    for a in node.args:
        check(a, where, topics)


def age_only_topics(node: Expr) -> set[str]:
    """The topics ``node`` reads only through ``age(/topic)``: the time since their last
    message, never a value of one. Where such a topic had no publisher (nothing was sent),
    what the expression reads of it is known, unlike what a lost message held
    (:data:`fretc.logs.recorded_gaps.SILENT_CAUSES`)."""
    aged: set[str] = set()
    read: set[str] = set()

    def visit(n: Expr, in_age: bool) -> None:
        if isinstance(n, Field):
            (aged if in_age else read).add(n.topic)
        elif isinstance(n, UnaryOp):
            visit(n.arg, in_age)
        elif isinstance(n, BinOp):
            visit(n.left, in_age)
            visit(n.right, in_age)
        elif isinstance(n, FuncCall):
            if n.func == "tf":  # the transforms' values, whatever its arguments say
                read.update(TF_TOPICS)
            for a in n.args:
                visit(a, in_age or n.func == "age")

    visit(node, False)
    return aged - read


def stateful_topics(node: Expr) -> set[str]:
    """The topics whose previous message ``node`` reads (``@delta``, ``@timedelta``,
    ``@derivative``: :data:`STATEFUL`)."""
    return {f.topic for n in walk(node) if isinstance(n, FuncCall) and n.func in STATEFUL
            for f in walk(n.args[0]) if isinstance(f, Field)}


def check_aggregate(node: Expr, where: ExprLocation) -> str | None:
    """The aggregation of a binding (``"any"``, ``"all"``, ``"count"``, ``"min"``,
    ``"max"``: :data:`AGGREGATES`) when ``node``, the whole binding, is one, else None.

    Raises:
        BindingError: an aggregation that is not the whole binding, or whose argument reads
            other than the fields of one topic (``age()``, ``tf()``, two topics), at its
            column.
    """
    agg = None
    if (isinstance(node, FuncCall) and node.func == "count_ticks" and node.args
            and isinstance(node.args[0], FuncCall) and node.args[0].func in AGGREGATES):
        # count_ticks(called(/arm), 1min): the ticks whose messages since the previous tick
        # the aggregation folds true (signals/tick_windows.py counts them)
        return check_aggregate(node.args[0], where)
    if isinstance(node, FuncCall) and node.func in AGGREGATES:
        agg = AGGREGATES[node.func]
        inner = node.args[0]
        topics = set()
        for n in walk(inner):
            if isinstance(n, FuncCall) and n.func in ("age", "tf"):
                raise where.error(f"{node.func}() folds the fields of one topic's messages; "
                                  f"{n.func}() is not a field of a message", n.col)
            if isinstance(n, FuncCall) and n.func in AGGREGATES:
                raise where.error(f"{n.func}() inside {node.func}(): aggregations over "
                                  "messages do not nest", n.col)
            if isinstance(n, Field):
                topics.add(n.topic)
        if len(topics) != 1:
            raise where.error(f"{node.func}() folds the messages of one topic, but its "
                              f"argument reads {len(topics)} ({', '.join(sorted(topics))})"
                              if topics else f"{node.func}() needs a field of a topic",
                              node.col)
        return agg
    for n in walk(node):
        if isinstance(n, FuncCall) and n.func in AGGREGATES:
            said = written(n)
            raise where.error(f"{said} is the whole binding (e.g. error_logged = "
                              f"\"{n.func}(/log.level >= 8)\", busy = \"count_ticks({said}, "
                              "1min)\"), not a part of one: bind it to its own variable and "
                              "combine the variables in the requirement", n.col)
    return None


def written(n: FuncCall) -> str:
    """How the user wrote an aggregation: ``called(/arm)`` / ``answered(/arm)`` for the
    service events' folds that parse.py makes of them, else ``any_of_messages()`` ..."""
    arg = n.args[0] if n.args else None
    if (n.func == "any_of_messages" and isinstance(arg, BinOp) and isinstance(arg.left, Field)
            and arg.left.path == ("info", "event_type")
            and arg.left.topic.endswith("/_service_event")):
        service = arg.left.topic[:-len("/_service_event")]
        return f"{'called' if arg.op == '<=' else 'answered'}({service})"
    return f"{n.func}()"


#: A name that may be a constant of a message definition (ROS writes them in capitals).
_CONSTANT = re.compile(r"[A-Z][A-Z0-9_]*\Z")


def _enum_name(side: Expr, other: Expr, trees: dict[str, Expr]) -> Expr:
    """``side`` as a :class:`Named` constant when it is a name that is no variable and
    ``other`` is a field (``/v.kind == Video``), else ``side``."""
    if isinstance(side, Ref) and side.name not in trees and isinstance(other, Field):
        return Named(side.col, side.name)
    return side


def substitute(node: Expr, trees: dict[str, Expr], where: ExprLocation, name: str) -> Expr:
    """``node`` with every :class:`Ref` replaced by the tree of the variable it names.

    Args:
        trees: variable -> its (already substituted) tree.
        name: the variable ``node`` belongs to (it may not refer to itself).

    Raises:
        BindingError: a reference to ``name`` itself or to an unknown variable (a name in
            capitals that is no variable becomes a :class:`Named` constant).
    """
    if isinstance(node, Ref):
        if node.name == name:
            raise where.error(f"{name!r} refers to itself", node.col)
        tree = trees.get(node.name)
        if tree is None and _CONSTANT.match(node.name):
            return Named(node.col, node.name)  # resolved against the log's schemas
        if tree is None:
            hint = closest(node.name, [n for n in trees if n != name] + list(FUNCS))
            raise where.error(f"unknown name {node.name!r}: not a variable of this binding file"
                              + (f"; did you mean {hint!r}?" if hint else "")
                              + " (a field is /topic.field, a function call f(...))", node.col)
        return tree
    if isinstance(node, UnaryOp):
        return UnaryOp(node.col, node.op, substitute(node.arg, trees, where, name))
    if isinstance(node, BinOp):
        left, right = node.left, node.right
        if node.op in ("=", "!="):  # compared with a field: an enum's name as its schema
            # writes it ("Video"), resolved against the log's schemas like a capital one
            left, right = _enum_name(left, right, trees), _enum_name(right, left, trees)
        return BinOp(node.col, node.op, substitute(left, trees, where, name),
                     substitute(right, trees, where, name))
    if isinstance(node, FuncCall):
        return FuncCall(node.col, node.func, tuple(substitute(a, trees, where, name)
                                                   for a in node.args))
    return node
