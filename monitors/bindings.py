"""Signal bindings: how each FRET variable is computed from recorded messages.

Bindings live apart from the requirement text (../shared/DESIGN.md, "Signals are declared, never
guessed"): one requirement set audits both the simulator and the real robot by swapping the
binding file.  A binding file is TOML (read with :mod:`tomllib`)::

    [tick]
    period = "100 ms"      # fixed period with sample-and-hold, or
    # topic = "/scan"      # one tick per message of this topic (exactly one of the two)
    # nominal_rate = "10 Hz" # topic only: converts durations in time units to ticks
    time = "log"           # time base: "log" (MCAP log time, default) or "header"
    # header_lag = "500 ms" # time="header" only: how late a message may arrive (default 1 s)

    [variables]
    too_close = "min(/scan.ranges) < 0.9"
    stopped = "abs(/cmd_vel.linear.x) < 1e-3 & abs(/cmd_vel.angular.z) < 1e-3"
    scan_stale = "age(/scan) > 0.3"

Durations are a number with a unit (:mod:`fretish.units`, the grammar of the requirement
files' ``tick_period`` too): ``ns``, ``us``, ``ms``, ``s``, ``min``, ``h`` (or their long
names, ``milliseconds``), or a frequency in ``Hz`` (period = 1/f); a bare TOML number is
seconds.

Expression language (grammar: ``bindings.lark``), loosest binding first:

=================  ==========================================================================
``a -> b``         implication (right-assoc.);  ``a <-> b`` equivalence
``a | b``          or;  ``a & b`` and;  ``! a`` not (looser than comparisons: ``!x < 3`` is
                   ``!(x < 3)``)
``< <= > >= = !=`` comparisons (``==`` also accepted); they do not chain
``+ - * /``        arithmetic; unary ``-``.  ``x / 0`` is ±inf (nan for 0/0), as IEEE 754
``/topic.a.b[i]``  a message field: topic name, then fields by ``.``, array items by ``[i]``
                   (negative counts from the end)
``1.5 2e-3 true``  numbers and booleans
``f(...)``         ``abs(x)``; ``norm(a, b, ...)`` = sqrt(a²+b²+...) or ``norm(array)``;
                   ``min``/``max`` of an array or of several values; ``mean``, ``any``,
                   ``all``, ``count`` (number of true/non-zero items), ``len`` of an array;
                   ``age(/topic)`` = seconds from the topic's latest message to the tick
=================  ==========================================================================

Values: booleans, float64 numbers (integer fields are read as floats), and arrays (numeric
arrays are read as float64).  Arithmetic and comparisons apply item by item to arrays
(numpy), so ``count(/scan.ranges < 0.9)`` counts close returns.  A variable must end as a
boolean or a number.  NaN compares false and counts as true in ``& | ! ->`` (numpy).
Reductions of an empty array: ``min`` → +inf, ``max`` → -inf, ``mean`` → nan, ``any`` →
false, ``all`` → true, ``count``/``len``/``norm`` → 0.  Outside LaserScans NaN propagates
through ``min``/``max``/``mean``.

LaserScan ranges (REP 117): a field path ending in ``ranges`` of a ``sensor_msgs/LaserScan``
(without an index) yields only the valid returns: values inside
``[range_min, range_max]``; NaN, +inf and out-of-range values are ignored by every
item-wise operation and reduction (``len`` counts valid returns).  So ``min(/scan.ranges)``
is +inf when no return is valid.  REP 117's -inf ("detected, too close to measure") is read
as ``range_min``, so a too-close object is never hidden from ``min``.
``/scan.ranges[i]`` is the raw value of beam i.

Each binding is parsed once (Lark, LALR) and compiled to nested Python closures (no eval of
user text): :meth:`Binding.evaluate` for one tick, :meth:`Binding.evaluate_columns` for all
ticks at once with numpy.  Errors name the binding file, line and column and the variable.
"""

from __future__ import annotations

import math
import operator
import re
import tomllib
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable, Iterable

import numpy as np
from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from fretish.units import NS_PER_S, parse_duration

from .problems import BindingError, SignalError

__all__ = [
    "Binding",
    "Bindings",
    "TickSpec",
    "EvalState",
    "Valid",
    "load_bindings",
    "parse_bindings",
    "parse_inline",
    "make_bindings",
    "parse_duration",
    "compile_expression",
    "LASER_SCAN",
    "check_types",
    "LogSelector",
]

LASER_SCAN = "sensor_msgs/msg/LaserScan"
DEFAULT_HEADER_LAG_NS = NS_PER_S
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
#: A FRET variable name as a binding key: an identifier, or the text of a quoted FRETish
#: variable (``"wind speed"``: a TOML quoted key ``"wind speed" = "..."``, or
#: ``--bind '"wind speed"=...'``): no quotes, no control characters, not blank at either end.
_VARNAME = re.compile(r"(?=\S)[^\"\x00-\x1f\x7f]*(?<=\S)\Z")


# ------------------------------------------------------------------------------------------------
# AST
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Node:
    """Base of expression nodes; ``col`` is the 1-based column in the expression text."""

    col: int


@dataclass(frozen=True)
class Const(Node):
    value: bool | float


@dataclass(frozen=True)
class Slice:
    """``[lo:hi]`` of an array field (Python slice rules; None = open end)."""

    lo: int | None
    hi: int | None

    def text(self) -> str:
        return f"[{'' if self.lo is None else self.lo}:{'' if self.hi is None else self.hi}]"


@dataclass(frozen=True)
class Field(Node):
    """``/topic.a.b[i]``: ``path`` holds attribute names (str), indexes (int) and, last,
    at most one :class:`Slice`."""

    topic: str
    path: tuple[str | int | Slice, ...]

    def text(self) -> str:
        out = self.topic
        for p in self.path:
            out += (p.text() if isinstance(p, Slice) else f"[{p}]" if isinstance(p, int)
                    else f".{p}")
        return out


@dataclass(frozen=True)
class Ref(Node):
    """Another variable of the same binding file, by name (substituted before compiling)."""

    name: str


@dataclass(frozen=True)
class Unary(Node):
    op: str  # "-" or "!"
    arg: Node


@dataclass(frozen=True)
class Binary(Node):
    op: str
    left: Node
    right: Node


@dataclass(frozen=True)
class Call(Node):
    func: str
    args: tuple[Node, ...]


# name: (min args, max args or None)
_FUNCS = {
    "abs": (1, 1), "norm": (1, None), "min": (1, None), "max": (1, None), "mean": (1, 1),
    "any": (1, 1), "all": (1, 1), "count": (1, 1), "len": (1, 1), "age": (1, 1),
}


@lru_cache(maxsize=1)
def _parser() -> Lark:
    return Lark.open("bindings.lark", rel_to=__file__, parser="lalr", lexer="contextual",
                     propagate_positions=True, maybe_placeholders=False)


class _Where:
    """Maps a column in the expression to file:line:col for error messages."""

    def __init__(self, source: str, variable: str | None, line: int | None, col: int | None,
                 exact: bool = True) -> None:
        self.source, self.variable, self.line, self.col, self.exact = source, variable, line, col, exact

    def error(self, message: str, expr_col: int | None = None) -> BindingError:
        line, col = self.line, self.col
        if expr_col is not None:
            if col is not None and self.exact:
                col = col + expr_col - 1
            else:
                message = f"{message} (column {expr_col} of the expression)"
        return BindingError(self.source, message, line=line, col=col, variable=self.variable)


def _to_ast(tree: Tree | Token, where: _Where) -> Node:
    if isinstance(tree, Token):  # pragma: no cover - grammar always wraps tokens
        raise where.error(f"unexpected {tree!r}", tree.column)
    data = tree.data
    kids = tree.children
    col = tree.meta.column if not tree.meta.empty else 1
    if data == "number":
        return Const(col, float(kids[0]))
    if data == "true":
        return Const(col, True)
    if data == "false":
        return Const(col, False)
    if data == "field":
        topic = str(kids[0])
        path: list[str | int] = []
        for sel in kids[1:]:
            if sel.data == "slice":
                lo, hi = (int(c.children[0]) if c.children else None for c in sel.children)
                path.append(Slice(lo, hi))
                continue
            tok = sel.children[0]
            path.append(int(tok) if sel.data == "index" else str(tok))
        for p in path[:-1]:
            if isinstance(p, Slice):
                raise where.error(f"{Field(0, topic, tuple(path)).text()}: a slice must be "
                                  "the last selector", kids[0].column)
        return Field(kids[0].column, topic, tuple(path))
    if data == "ref":
        return Ref(kids[0].column, str(kids[0]))
    if data == "neg":
        return Unary(col, "-", _to_ast(kids[0], where))
    if data == "not_":
        return Unary(col, "!", _to_ast(kids[0], where))
    if data in ("arith", "compare"):
        left, op, right = kids
        o = str(op)
        o = "=" if o == "==" else o
        return Binary(op.column, o, _to_ast(left, where), _to_ast(right, where))
    if data in ("and_", "or_", "implies", "iff"):
        op = {"and_": "&", "or_": "|", "implies": "->", "iff": "<->"}[data]
        return Binary(col, op, _to_ast(kids[0], where), _to_ast(kids[1], where))
    if data == "call":
        name_tok = kids[0]
        args = tuple(_to_ast(k, where) for k in kids[1:] if k is not None)
        return Call(name_tok.column, str(name_tok), args)
    raise where.error(f"unexpected construct {data!r}", col)  # pragma: no cover


def _check(node: Node, where: _Where, topics: set[str]) -> None:
    """Static checks: known functions and arities, age() of a topic, fields below topics."""
    if isinstance(node, Field):
        for p in node.path:
            if isinstance(p, str) and p.startswith("_"):
                raise where.error(f"{node.text()}: {p!r} is not a message field (ROS field "
                                  "names start with a letter; a binding reads only fields the "
                                  "message type declares)", node.col)
        if not node.path:
            raise where.error(f"{node.topic} is a topic, not a value: name a field "
                              f"(e.g. {node.topic}.data) or use age({node.topic})", node.col)
        topics.add(node.topic)
    elif isinstance(node, Ref):
        pass  # resolved against the other variables (_substitute)
    elif isinstance(node, Unary):
        _check(node.arg, where, topics)
    elif isinstance(node, Binary):
        _check(node.left, where, topics)
        _check(node.right, where, topics)
    elif isinstance(node, Call):
        if node.func not in _FUNCS:
            raise where.error(f"unknown function {node.func!r} (known: "
                              f"{', '.join(sorted(_FUNCS))})", node.col)
        lo, hi = _FUNCS[node.func]
        n = len(node.args)
        if n < lo or (hi is not None and n > hi):
            want = f"{lo}" if lo == hi else f"at least {lo}"
            raise where.error(f"{node.func}() takes {want} argument(s), got {n}", node.col)
        if node.func == "age":
            arg = node.args[0]
            if not isinstance(arg, Field) or arg.path:
                raise where.error("age() takes a topic name, e.g. age(/scan)", arg.col)
            topics.add(arg.topic)
            return
        for a in node.args:
            _check(a, where, topics)


def _parse(expr: str, where: _Where) -> tuple[Node, frozenset[str]]:
    if not expr.strip():
        raise where.error("empty expression")
    try:
        tree = _parser().parse(expr)
    except UnexpectedInput as exc:
        col = getattr(exc, "column", None)
        if isinstance(exc, UnexpectedCharacters):
            msg = f"unexpected character {expr[exc.pos_in_stream]!r}"
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
        raise where.error(f"syntax error: {msg}", col) from None
    node = _to_ast(tree, where)
    topics: set[str] = set()
    _check(node, where, topics)
    return node, frozenset(topics)


# ------------------------------------------------------------------------------------------------
# Values and field access
# ------------------------------------------------------------------------------------------------


class Valid:
    """An array value with an optional validity mask (REP 117-filtered LaserScan ranges).

    ``data`` is 1-D (one tick) or 2-D (ticks × items, vectorized path); ``mask`` is None
    (all items valid) or a bool array of the same shape.
    """

    __slots__ = ("data", "mask")

    def __init__(self, data: np.ndarray, mask: np.ndarray | None) -> None:
        self.data = data
        self.mask = mask


class _FieldError(Exception):
    pass


def _norm_scalar(v: Any) -> Any:
    t = type(v)
    if t is float or t is bool:
        return v
    if t is int:
        return float(v)
    if isinstance(v, np.generic):
        v = v.item()
        return v if type(v) is bool else float(v) if isinstance(v, (int, float)) else v
    return v


def _as_array(v: np.ndarray) -> np.ndarray:
    if v.dtype == np.bool_:
        return v
    if v.dtype.kind in "iuf":
        return v.astype(np.float64, copy=False)
    return v


def _identity(data: Any) -> Any:
    return data


def make_extractor(f: Field) -> Callable[[Any], Any]:
    """A function message-data → value of field ``f`` (normalized; see module docstring).

    Returns Python bool/float, :class:`Valid` for arrays (masked for LaserScan ranges), or the
    raw object for anything else (strings, nested messages).

    Raises (from the returned function):
        _FieldError: no such field, index out of range, or indexing a non-sequence.
    """
    if f.path and isinstance(f.path[-1], Slice):
        inner = make_extractor(Field(f.col, f.topic, f.path[:-1]))
        sl = slice(f.path[-1].lo, f.path[-1].hi)
        text = f.text()

        def sliced(data: Any) -> Any:
            v = inner(data)  # REP 117 validity of LaserScan ranges is kept for the slice
            if isinstance(v, Valid):
                return Valid(v.data[..., sl], None if v.mask is None else v.mask[..., sl])
            if isinstance(v, (list, tuple)):
                return list(v[sl])
            raise _FieldError(f"{text}: only arrays can be sliced")
        return sliced
    path = f.path
    laser = isinstance(path[-1], str) and path[-1] == "ranges"
    steps: list[Callable[[Any], Any]] = []
    attrs: list[str] = []
    for p in path[:-1] if laser else path:
        if isinstance(p, str):
            attrs.append(p)
            continue
        if attrs:
            steps.append(operator.attrgetter(".".join(attrs)))
            attrs = []
        steps.append(operator.itemgetter(p))
    if attrs:
        steps.append(operator.attrgetter(".".join(attrs)))
    text = f.text()

    def walk_steps(data: Any) -> Any:
        for s in steps:
            data = s(data)
        return data

    walk: Callable[[Any], Any]
    if len(steps) == 1:
        walk = steps[0]  # fast path: one attrgetter
    elif not steps:
        walk = _identity
    else:
        walk = walk_steps

    def extract(data: Any) -> Any:
        try:
            v = walk(data)
            if laser:
                parent = v
                v = parent.ranges
                if getattr(parent, "__msgtype__", None) == LASER_SCAN:
                    arr = np.asarray(v, dtype=np.float64)
                    # REP 117: -inf is a detection closer than range_min; count it as
                    # range_min so that a too-close object is never hidden
                    too_close = np.isneginf(arr)
                    if too_close.any():
                        arr = np.where(too_close, parent.range_min, arr)
                    return Valid(arr, (arr >= parent.range_min) & (arr <= parent.range_max))
        except AttributeError as exc:
            owner = data
            for p in path:  # find the object that lacks the field, for the message
                if isinstance(p, str) and not hasattr(owner, p):
                    break
                try:
                    owner = getattr(owner, p) if isinstance(p, str) else owner[p]
                except (IndexError, TypeError, KeyError):
                    break
            typename = getattr(owner, "__msgtype__", type(owner).__name__)
            raise _FieldError(f"{text}: a {typename} message has no field {exc.name!r}") from None
        except IndexError:
            raise _FieldError(f"{text}: index out of range") from None
        except (TypeError, KeyError) as exc:
            raise _FieldError(f"{text}: cannot index ({exc})") from None
        if isinstance(v, np.ndarray):
            return Valid(_as_array(v), None)
        if isinstance(v, (list, tuple)) and v and all(isinstance(x, (bool, int, float)) for x in v):
            return Valid(_as_array(np.asarray(v)), None)
        return _norm_scalar(v)

    return extract


# ------------------------------------------------------------------------------------------------
# Operations (shared by the per-tick and the vectorized evaluators)
# ------------------------------------------------------------------------------------------------

_PY = (float, bool, int)


def _num(x: Any) -> Any:
    """Booleans as numbers for arithmetic (numpy would treat bool + bool as logical or)."""
    if isinstance(x, np.ndarray) and x.dtype == np.bool_:
        return x.astype(np.float64)
    return x


class _Ops:
    """Array semantics; ``axis`` None evaluates one tick, 1 evaluates ticks × items."""

    def __init__(self, vectorized: bool) -> None:
        self.vec = vectorized
        self.axis = 1 if vectorized else None

    def _split(self, x: Any) -> tuple[Any, Any]:
        if isinstance(x, Valid):
            return x.data, x.mask
        if self.vec and isinstance(x, np.ndarray) and x.ndim == 1:
            return x[:, None], None
        return x, None

    def lift2(self, fn: Callable[[Any, Any], Any], a: Any, b: Any, numeric: bool) -> Any:
        if isinstance(a, Valid) or isinstance(b, Valid):
            da, ma = self._split(a)
            db, mb = self._split(b)
            if numeric:
                da, db = _num(da), _num(db)
            mask = ma if mb is None else mb if ma is None else ma & mb
            return Valid(fn(da, db), mask)
        if numeric:
            a, b = _num(a), _num(b)
        return fn(a, b)

    def lift1(self, fn: Callable[[Any], Any], a: Any, numeric: bool) -> Any:
        if isinstance(a, Valid):
            return Valid(fn(_num(a.data) if numeric else a.data), a.mask)
        return fn(_num(a) if numeric else a)

    # reductions of an array value ----------------------------------------------------------
    def _filled(self, a: Valid, fill: float) -> np.ndarray:
        data = _num(a.data)
        return data if a.mask is None else np.where(a.mask, data, fill)

    def _truthy(self, a: Valid) -> np.ndarray:
        t = a.data != 0
        return t if a.mask is None else t & a.mask

    def _count(self, a: Valid) -> Any:
        if a.mask is None:
            n = a.data.shape[-1]
            return np.full(a.data.shape[0], float(n)) if self.vec else float(n)
        return self._out(a.mask.sum(axis=self.axis))

    def _out(self, x: Any) -> Any:
        if self.vec:
            return np.asarray(x, dtype=np.float64) if np.asarray(x).dtype != np.bool_ else np.asarray(x)
        return x.item() if isinstance(x, np.generic) else x

    def reduce(self, func: str, a: Valid) -> Any:
        ax = self.axis
        # ndarray methods (not np.min etc.): same ufunc reductions, less Python overhead.
        if func == "min":  # where=: no filled copy; the same values
            return self._out(_num(a.data).min(axis=ax, initial=np.inf,
                                              where=True if a.mask is None else a.mask))
        if func == "max":
            return self._out(_num(a.data).max(axis=ax, initial=-np.inf,
                                              where=True if a.mask is None else a.mask))
        if func == "mean":
            total = self._filled(a, 0.0).sum(axis=ax)
            n = a.mask.sum(axis=ax) if a.mask is not None else a.data.shape[-1]
            return self._out(np.divide(total, n))
        if func == "norm":
            d = _num(a.data)
            sq = d * d
            if a.mask is not None:
                sq = np.where(a.mask, sq, 0.0)
            return self._out(np.sqrt(sq.sum(axis=ax)))
        if func == "any":
            return self._out(self._truthy(a).any(axis=ax))
        if func == "all":
            t = a.data != 0
            if a.mask is not None:
                t = t | ~a.mask
            return self._out(t.all(axis=ax))
        if func == "count":
            return self._out(self._truthy(a).sum(axis=ax).astype(np.float64))
        if func == "len":
            return self._count(a)
        raise AssertionError(func)  # pragma: no cover


def _min2(a: Any, b: Any) -> Any:
    if a != a or b != b:  # NaN propagates, as np.minimum
        return math.nan
    return a if a <= b else b


def _max2(a: Any, b: Any) -> Any:
    if a != a or b != b:
        return math.nan
    return a if a >= b else b


def _div(a: Any, b: Any) -> Any:
    if b == 0:
        return float(np.divide(np.float64(a), np.float64(b)))
    return a / b


_NP_BIN = {
    "+": (np.add, True), "-": (np.subtract, True), "*": (np.multiply, True),
    "/": (np.divide, True),
    "<": (np.less, False), "<=": (np.less_equal, False), ">": (np.greater, False),
    ">=": (np.greater_equal, False), "=": (np.equal, False), "!=": (np.not_equal, False),
    "&": (np.logical_and, False), "|": (np.logical_or, False),
    "->": (lambda a, b: np.logical_or(np.logical_not(a), b), False),
    "<->": (lambda a, b: np.logical_not(np.logical_xor(a, b)), False),
}
_PY_BIN: dict[str, Callable[[Any, Any], Any]] = {
    "+": operator.add, "-": operator.sub, "*": operator.mul, "/": _div,
    "<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge,
    "=": operator.eq, "!=": operator.ne,
    "&": lambda a, b: bool(a) and bool(b), "|": lambda a, b: bool(a) or bool(b),
    "->": lambda a, b: (not a) or bool(b), "<->": lambda a, b: bool(a) == bool(b),
}


class EvalState:
    """What a per-tick evaluation sees.

    Attributes:
        msgs: topic → data of the latest message at or before the tick (sample-and-hold).
        times: topic → time (ns, in the time base) of that message.
        now: the tick time (ns).
    """

    __slots__ = ("msgs", "times", "now", "values")

    def __init__(self) -> None:
        self.msgs: dict[str, Any] = {}
        self.times: dict[str, int] = {}
        self.now = 0
        #: (topic, field path) → (message data, extracted value): extraction memo.
        self.values: dict[tuple[str, tuple], tuple[Any, Any]] = {}


class _EvalError(Exception):
    def __init__(self, node: Node, message: str) -> None:
        super().__init__(message)
        self.node = node
        self.message = message


def _compile(node: Node, ops: _Ops, extractors: dict[Field, Callable[[Any], Any]]) -> Callable[[Any], Any]:
    """Closure evaluating ``node``; argument is an EvalState (per tick) or _Columns (vectorized)."""
    vec = ops.vec
    if isinstance(node, Const):
        v = node.value
        return lambda st: v
    if isinstance(node, Field):
        if vec:
            topic, path = node.topic, node.path
            return lambda cols: cols.field(topic, path, node)
        ex = extractors.setdefault(node, make_extractor(node))
        topic = node.topic
        key = (topic, node.path)

        def field_value(st: EvalState) -> Any:
            msg = st.msgs[topic]
            memo = st.values.get(key)  # shared by bindings and ticks while the message is held
            if memo is not None and memo[0] is msg:
                return memo[1]
            try:
                v = ex(msg)
            except _FieldError as exc:
                raise _EvalError(node, str(exc)) from None
            st.values[key] = (msg, v)
            return v

        return field_value
    if isinstance(node, Unary):
        arg = _compile(node.arg, ops, extractors)
        if node.op == "-":
            def neg(st: Any) -> Any:
                a = arg(st)
                if type(a) in _PY:
                    return -a
                return ops.lift1(np.negative, a, True)
            return neg

        def not_(st: Any) -> Any:
            a = arg(st)
            if type(a) in _PY:
                return not a
            return ops.lift1(np.logical_not, a, False)
        return not_
    if isinstance(node, Binary):
        left = _compile(node.left, ops, extractors)
        right = _compile(node.right, ops, extractors)
        npfn, numeric = _NP_BIN[node.op]
        pyfn = _PY_BIN[node.op]

        def binary(st: Any) -> Any:
            a = left(st)
            b = right(st)
            if type(a) in _PY and type(b) in _PY:
                return pyfn(a, b)
            try:
                return ops.lift2(npfn, a, b, numeric)
            except (ValueError, TypeError) as exc:
                raise _EvalError(node, f"cannot apply {node.op!r}: {exc}") from None
        return binary
    if isinstance(node, Call):
        func = node.func
        if func == "age":
            topic = node.args[0].topic  # type: ignore[attr-defined]
            if vec:
                return lambda cols: cols.age(topic)
            return lambda st: (st.now - st.times[topic]) / NS_PER_S
        args = [_compile(a, ops, extractors) for a in node.args]
        if func == "abs":
            a0 = args[0]

            def abs_(st: Any) -> Any:
                a = a0(st)
                if type(a) in _PY:
                    return abs(a)
                return ops.lift1(np.abs, a, True)
            return abs_
        if func in ("min", "max", "norm") and len(args) > 1:
            pair = {"min": _min2, "max": _max2}.get(func)
            npfn = {"min": np.minimum, "max": np.maximum}.get(func)

            def several(st: Any) -> Any:
                vals = [a(st) for a in args]
                for v in vals:
                    if isinstance(v, Valid):
                        raise _EvalError(node, f"{func}() of several values takes numbers, "
                                               "not arrays")
                if func == "norm":
                    if all(type(v) in _PY for v in vals):
                        total = 0.0
                        for v in vals:
                            total = total + v * v
                        return math.sqrt(total)
                    total = 0.0
                    for v in vals:
                        v = _num(v)
                        total = total + v * v
                    return np.sqrt(total)
                acc = vals[0]
                for v in vals[1:]:
                    if type(acc) in _PY and type(v) in _PY:
                        acc = pair(acc, v)
                    else:
                        acc = npfn(_num(acc), _num(v))
                return acc
            return several
        a0 = args[0]
        arg0 = node.args[0]
        if not vec and isinstance(arg0, Field):
            # a reduction of one field depends only on the held message: computed once per
            # message, shared by the bindings that use it (like the field memo)
            key = (func, arg0.topic, arg0.path)
            topic0 = arg0.topic

            def reduce_memo(st: Any) -> Any:
                msg = st.msgs[topic0]
                memo = st.values.get(key)
                if memo is not None and memo[0] is msg:
                    return memo[1]
                v = reduce_(st)
                st.values[key] = (msg, v)
                return v

        def reduce_(st: Any) -> Any:
            a = a0(st)
            if not isinstance(a, Valid):
                if func == "len" and isinstance(a, (list, tuple, str)):
                    return float(len(a))  # e.g. len(/tf.transforms): a sequence of messages
                if func in ("min", "max", "mean"):
                    return a  # of one number: itself
                if func == "norm":
                    return abs(a) if type(a) in _PY else np.abs(_num(a))
                raise _EvalError(node, f"{func}() takes an array")
            return ops.reduce(func, a)
        return reduce_memo if (not vec and isinstance(arg0, Field)) else reduce_
    raise AssertionError(node)  # pragma: no cover


# ------------------------------------------------------------------------------------------------
# Bindings
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TickSpec:
    """When the signals are sampled.

    Exactly one of:
        period_ns: fixed period (ns): ticks at start + k·period, sample-and-hold.
        topic: one tick per message of this topic, other topics held.
    """

    period_ns: int | None = None
    topic: str | None = None
    #: topic ticks only: the tick topic's nominal period (``[tick] nominal_rate``), with
    #: which durations in time units convert to ticks; the audit warns when the measured
    #: rate differs by more than 10 %.
    nominal_period_ns: int | None = None

    def __post_init__(self) -> None:
        if (self.period_ns is None) == (self.topic is None):
            raise ValueError("TickSpec needs exactly one of period_ns and topic")
        if self.period_ns is not None and self.period_ns <= 0:
            raise ValueError("TickSpec.period_ns must be positive")


@dataclass(eq=False)
class Binding:
    """One FRET variable bound to an expression.

    Attributes:
        name: the FRET variable.
        expr: the expression text.
        source: binding file path, or ``"<--bind NAME>"``.
        line, col: where the expression text starts in ``source`` (1-based; None unknown).
        topics: topics the expression reads (fields and ``age``).
        fields: the field references, in order of appearance.
    """

    name: str
    expr: str
    source: str
    line: int | None
    col: int | None
    ast: Node
    topics: frozenset[str]
    fields: tuple[Field, ...]
    _exact: bool = True
    _scalar: Callable[[EvalState], Any] | None = field(default=None, repr=False)
    _vector: Callable[[Any], Any] | None = field(default=None, repr=False)

    def _where(self) -> _Where:
        return _Where(self.source, self.name, self.line, self.col, self._exact)

    def _fail(self, exc: _EvalError, context: str) -> SignalError:
        err = self._where().error(f"{exc.message}{context}", exc.node.col)
        return SignalError(str(err), variable=self.name)

    def evaluate(self, state: EvalState, context: str = "") -> bool | float:
        """Value at one tick: Python bool or float.

        Args:
            state: held messages, their times, and the tick time.
            context: appended to error messages (e.g. " at log time ...").

        Raises:
            SignalError: a missing field, index out of range, or a value that is an array;
                the message names the binding file:line:col and the variable.
        """
        try:
            v = self._scalar(state)  # type: ignore[misc]
        except _EvalError as exc:
            raise self._fail(exc, context) from None
        t = type(v)
        if t is bool or t is float:
            return v
        if t is int:
            return float(v)
        if isinstance(v, np.generic):
            v = v.item()
            return v if isinstance(v, bool) else float(v)
        if isinstance(v, Valid):
            raise self._fail(_EvalError(self.ast, f"value is an array of {v.data.shape[-1]} items; "
                                        "reduce it with min/max/any/all/count"), context)
        raise self._fail(_EvalError(self.ast, f"value {v!r} is not a boolean or a number"), context)

    def evaluate_columns(self, columns: Any) -> np.ndarray:
        """Values at all ticks (vectorized): 1-D bool or float64 array.

        Args:
            columns: an object with ``n`` (number of ticks), ``field(topic, path, node)`` →
                per-tick values (1-D array, or :class:`Valid` of 2-D) and ``age(topic)`` →
                seconds (1-D); see monitors.signals.

        Raises:
            SignalError: as :meth:`evaluate`.
        """
        try:
            v = self._vector(columns)  # type: ignore[misc]
        except _EvalError as exc:
            raise self._fail(exc, "") from None
        if isinstance(v, Valid):
            raise self._fail(_EvalError(self.ast, "value is an array; reduce it with "
                                        "min/max/any/all/count"), "")
        if not isinstance(v, np.ndarray):
            v = np.full(columns.n, v)
        if v.dtype == np.bool_:
            return v
        if v.dtype.kind in "iuf":
            return v.astype(np.float64, copy=False)
        raise self._fail(_EvalError(self.ast, f"values of type {v.dtype} are not booleans or "
                                    "numbers"), "")


def compile_expression(name: str, expr: str, *, source: str = "<expression>", line: int | None = None,
                       col: int | None = None, exact: bool = True,
                       refs: "dict[str, Binding] | None" = None) -> Binding:
    """Parse, check and compile one binding expression.

    Args:
        name: the FRET variable (an identifier).
        expr: the expression text.
        source, line, col: where ``expr`` starts, for error messages (``exact`` False when
            columns inside the expression cannot be mapped to the file, e.g. escapes).
        refs: the other variables a bare name in ``expr`` may refer to (already compiled);
            their expressions are substituted.

    Raises:
        BindingError: bad name, syntax error, unknown function, wrong arity, a bare topic
            used as a value; names source:line:col and the variable.
    """
    where = _Where(source, name, line, col, exact)
    if not _VARNAME.match(name):
        raise where.error(f"variable name {name!r} is not an identifier nor the text of a "
                          "quoted FRETish variable")
    node, topics = _parse(expr, where)
    if _refs(node):
        node = _substitute(node, refs or {}, where, name)
        found: set[str] = set()
        _check(node, where, found)
        topics = frozenset(found)
    fields: list[Field] = []

    def collect(n: Node) -> None:
        if isinstance(n, Field):
            if n.path:
                fields.append(n)
        elif isinstance(n, Unary):
            collect(n.arg)
        elif isinstance(n, Binary):
            collect(n.left)
            collect(n.right)
        elif isinstance(n, Call):
            for a in n.args:
                collect(a)

    collect(node)
    extractors: dict[Field, Callable[[Any], Any]] = {}
    scalar = _compile(node, _Ops(False), extractors)
    vector = _compile(node, _Ops(True), extractors)
    return Binding(name, expr, source, line, col, node, topics, tuple(fields), exact, scalar, vector)


def _refs(node: Node, deep: bool = False) -> list[str]:
    """Names of the variables ``node`` refers to, in order of appearance."""
    out: list[str] = []

    def walk(n: Node) -> None:
        if isinstance(n, Ref):
            out.append(n.name)
        elif isinstance(n, Unary):
            walk(n.arg)
        elif isinstance(n, Binary):
            walk(n.left)
            walk(n.right)
        elif isinstance(n, Call):
            for a in n.args:
                walk(a)
    walk(node)
    return out


def _substitute(node: Node, refs: dict, where: _Where, name: str) -> Node:
    """``node`` with every :class:`Ref` replaced by the referenced variable's expression."""
    if isinstance(node, Ref):
        if node.name == name:
            raise where.error(f"{name!r} refers to itself", node.col)
        b = refs.get(node.name)
        if b is None:
            from .schema import closest
            hint = closest(node.name, [n for n in refs if n != name] + list(_FUNCS))
            raise where.error(f"unknown name {node.name!r}: not a variable of this binding file"
                              + (f"; did you mean {hint!r}?" if hint else "")
                              + " (a field is /topic.field, a function call f(...))", node.col)
        return b.ast
    if isinstance(node, Unary):
        return Unary(node.col, node.op, _substitute(node.arg, refs, where, name))
    if isinstance(node, Binary):
        return Binary(node.col, node.op, _substitute(node.left, refs, where, name),
                      _substitute(node.right, refs, where, name))
    if isinstance(node, Call):
        return Call(node.col, node.func, tuple(_substitute(a, refs, where, name)
                                               for a in node.args))
    return node


@dataclass
class Bindings:
    """A set of variable bindings with a tick and a time base.

    Attributes:
        variables: FRET variable → Binding, in declaration order.
        tick: the tick clock.
        time_base: ``"log"`` (MCAP log time / bag timestamp) or ``"header"``
            (``header.stamp`` of each message).
        header_lag_ns: time_base "header" only: how far (ns, header clock) a message may
            arrive behind the newest stamp seen and still be placed in stamp order.
        source: the binding file, or None.
    """

    variables: dict[str, Binding]
    tick: TickSpec
    time_base: str = "log"
    header_lag_ns: int = DEFAULT_HEADER_LAG_NS
    source: str | None = None
    #: ``[logs]``: the logs this binding file applies to (None: every log).
    logs: "LogSelector | None" = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if self.time_base not in ("log", "header"):
            raise ValueError(f"time_base must be 'log' or 'header', not {self.time_base!r}")

    @property
    def topics(self) -> frozenset[str]:
        """All topics the variables reference (fields and age())."""
        out: set[str] = set()
        for b in self.variables.values():
            out |= b.topics
        return frozenset(out)

    def with_inline(self, specs: Iterable[str]) -> "Bindings":
        """A copy with ``NAME=EXPR`` bindings (CLI ``--bind``) added or replacing same-named ones.

        Raises:
            BindingError: as :func:`parse_inline`.
        """
        variables = dict(self.variables)
        for spec in specs:
            b = parse_inline(spec, refs=variables)
            variables[b.name] = b
        return Bindings(variables, self.tick, self.time_base, self.header_lag_ns, self.source)


def unparse(node: Node) -> str:
    """Expression text of a binding AST node (fully parenthesized where it matters)."""
    if isinstance(node, Const):
        v = node.value
        return ("true" if v else "false") if isinstance(v, bool) else repr(float(v))
    if isinstance(node, Field):
        return node.text()
    if isinstance(node, Unary):
        return f"{node.op}{unparse(node.arg)}"
    if isinstance(node, Binary):
        return f"({unparse(node.left)} {node.op} {unparse(node.right)})"
    if isinstance(node, Call):
        return f"{node.func}({', '.join(unparse(a) for a in node.args)})"
    raise TypeError(type(node).__name__)


_COMPARISONS = ("<", "<=", ">", ">=", "=", "!=")


def operand_signals(binding: Binding, limit: int = 4) -> list[tuple[str, Binding]]:
    """The numbers behind a boolean binding: the non-constant operands of the comparisons it
    is made of (through ``& | -> !``), as ``(label, Binding)`` pairs; e.g. ``too_close =
    "min(/scan.ranges) < 0.9"`` gives ``("too_close: min(/scan.ranges)", ...)``. At most
    ``limit`` of them; evidence shows them next to the boolean."""
    found: list[Node] = []

    def walk(n: Node) -> None:
        if isinstance(n, Unary) and n.op == "!":
            walk(n.arg)
        elif isinstance(n, Binary) and n.op in ("&", "|", "->"):
            walk(n.left)
            walk(n.right)
        elif isinstance(n, Binary) and n.op in _COMPARISONS:
            for side in (n.left, n.right):
                if not isinstance(side, Const):
                    found.append(side)

    walk(binding.ast)
    out: list[tuple[str, Binding]] = []
    seen: set[str] = set()
    for i, side in enumerate(found):
        text = unparse(side)
        if text.startswith("(") and text.endswith(")"):
            text = text[1:-1]
        if text in seen or len(out) >= limit:
            continue
        seen.add(text)
        aux = compile_expression(f"{binding.name}__operand{i}", text, source=binding.source,
                                 line=binding.line, col=binding.col, exact=False)
        out.append((f"{binding.name}: {text}", aux))
    return out


def parse_inline(spec: str, refs: "dict[str, Binding] | None" = None) -> Binding:
    """One inline binding ``NAME=EXPR`` (CLI ``--bind``); source is ``"<--bind NAME>"``.

    Raises:
        BindingError: no ``=``, bad name, or a bad expression (column counted in ``spec``).
    """
    name, sep, expr = spec.partition("=")
    name = name.strip()
    if len(name) >= 2 and name[0] == name[-1] == '"':
        name = name[1:-1]  # a quoted FRETish variable: --bind '"wind speed"=...'
    if not sep or not name:
        raise BindingError(f"<--bind {spec}>", "expected NAME=EXPRESSION")
    col = spec.index("=") + 2
    return compile_expression(name, expr, source=f"<--bind {name}>", line=1, col=col,
                              refs=refs)


def make_bindings(variables: dict[str, str], tick: TickSpec, *, time_base: str = "log",
                  header_lag_ns: int = DEFAULT_HEADER_LAG_NS) -> Bindings:
    """Bindings from a mapping of variable → expression text (source ``"<inline>"``).

    Raises:
        BindingError: a bad name or expression.
    """
    out = {name: compile_expression(name, expr, source=f"<--bind {name}>", line=1, col=len(name) + 2)
           for name, expr in variables.items()}
    return Bindings(out, tick, time_base, header_lag_ns, None)


# -- TOML --------------------------------------------------------------------------------------

_TABLE = re.compile(r"\s*\[\s*([A-Za-z0-9_.\"' -]+?)\s*\]\s*(#.*)?\Z")
_KEY = re.compile(r"""\s*(?:"((?:[^"\\]|\\.)*)"|'([^']*)'|([A-Za-z0-9_-]+))\s*=\s*""")


def _locate(text: str) -> dict[tuple[str, str], tuple[int, int, str]]:
    """(table, key) → (line, col of the value's first char, value text rest of line)."""
    out: dict[tuple[str, str], tuple[int, int, str]] = {}
    table = ""
    for i, raw in enumerate(text.splitlines(), start=1):
        m = _TABLE.match(raw)
        if m and not raw.lstrip().startswith("[["):
            table = m.group(1).strip().strip("\"'")
            out.setdefault(("[table]", table), (i, raw.index("[") + 1, ""))
            continue
        m = _KEY.match(raw)
        if m:
            key = m.group(1) if m.group(1) is not None else m.group(2) if m.group(2) is not None else m.group(3)
            out.setdefault((table, key), (i, m.end() + 1, raw[m.end():]))
            out.setdefault(("[key]", table + "." + key), (i, len(raw) - len(raw.lstrip()) + 1, ""))
    return out


def _value_start(rest: str, value: str) -> tuple[int, bool]:
    """Offset from the value token to the string's first char, and whether columns map exactly."""
    for q in ('"""', "'''", '"', "'"):
        if rest.startswith(q):
            body = rest[len(q):]
            if q.startswith('"') and "\\" in body.split(q)[0]:
                return len(q), False
            if q in ('"""', "'''"):
                return len(q), False
            return len(q), body.startswith(value)
    return 0, False


def parse_bindings(text: str, source: str = "<bindings>") -> Bindings:
    """Bindings from binding-file text (see the module docstring for the format).

    Raises:
        BindingError: TOML syntax error; unknown table or key; [tick] without exactly one of
            period/topic, a bad duration, time not "log"/"header"; a variable that is not a
            string, a bad name, or a bad expression.  Names source:line:col.
    """
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        msg = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        raise BindingError(source, f"TOML syntax error: {msg}",
                           line=int(m.group(1)) if m else None,
                           col=int(m.group(2)) if m else None) from None
    where = _locate(text)

    def at(table: str, key: str | None = None) -> tuple[int | None, int | None]:
        loc = where.get((table, key) if key is not None else ("[table]", table))
        return (loc[0], loc[1]) if loc else (None, None)

    for key in doc:
        if key not in ("tick", "variables", "logs"):
            line, col = at(key) if isinstance(doc[key], dict) else at("", key)
            raise BindingError(source, f"unknown {'table [' + key + ']' if isinstance(doc[key], dict) else 'key ' + repr(key)} "
                               "(expected [tick], [variables] and optionally [logs])", line=line, col=col)
    tick_t = doc.get("tick")
    if not isinstance(tick_t, dict):
        raise BindingError(source, "missing [tick] table: say period = \"100 ms\" or topic = \"/scan\" "
                           "(signals are declared, never guessed)", line=1)
    for key in tick_t:
        if key not in ("period", "topic", "time", "header_lag", "nominal_rate"):
            line, col = at("tick", key)
            raise BindingError(source, f"unknown key {key!r} in [tick] (period, topic, "
                               "nominal_rate, time, header_lag)", line=line, col=col)
    has_p, has_t = "period" in tick_t, "topic" in tick_t
    if has_p == has_t:
        line, col = at("tick")
        raise BindingError(source, "[tick] needs exactly one of period = \"...\" and topic = \"/...\"",
                           line=line, col=col)
    if has_p:
        try:
            tick = TickSpec(period_ns=parse_duration(tick_t["period"]))
        except ValueError as exc:
            line, col = at("tick", "period")
            raise BindingError(source, f"[tick] period: {exc}", line=line, col=col) from None
    else:
        topic = tick_t["topic"]
        if not isinstance(topic, str) or not re.fullmatch(r"(/[A-Za-z0-9_]+)+", topic):
            line, col = at("tick", "topic")
            raise BindingError(source, f"[tick] topic {topic!r} is not a topic name like \"/scan\"",
                               line=line, col=col)
        nominal = None
        if "nominal_rate" in tick_t:
            try:
                nominal = parse_duration(tick_t["nominal_rate"])
            except ValueError as exc:
                line, col = at("tick", "nominal_rate")
                raise BindingError(source, f"[tick] nominal_rate: {exc}", line=line,
                                   col=col) from None
        tick = TickSpec(topic=topic, nominal_period_ns=nominal)
    if has_p and "nominal_rate" in tick_t:
        line, col = at("tick", "nominal_rate")
        raise BindingError(source, "[tick] nominal_rate goes with topic = \"/...\" (a fixed "
                           "period is its own rate)", line=line, col=col)
    time_base = tick_t.get("time", "log")
    if time_base not in ("log", "header"):
        line, col = at("tick", "time")
        raise BindingError(source, f"[tick] time must be \"log\" or \"header\", not {time_base!r}",
                           line=line, col=col)
    lag = DEFAULT_HEADER_LAG_NS
    if "header_lag" in tick_t:
        try:
            lag = parse_duration(tick_t["header_lag"])
        except ValueError as exc:
            line, col = at("tick", "header_lag")
            raise BindingError(source, f"[tick] header_lag: {exc}", line=line, col=col) from None
    var_t = doc.get("variables", {})
    if not isinstance(var_t, dict):
        line, col = at("", "variables")
        raise BindingError(source, "variables must be a table [variables]", line=line, col=col)
    pending: dict[str, tuple] = {}
    for name, expr in var_t.items():
        loc = where.get(("variables", name))
        line, col, rest = loc if loc else (None, None, "")
        if not isinstance(expr, str):
            raise BindingError(source, "the binding must be a string expression",
                               line=line, col=col, variable=name)
        if not _VARNAME.match(name):
            kline, kcol, _ = where.get(("[key]", "variables." + name), (line, None, ""))
            raise BindingError(source, f"variable name {name!r} is not an identifier nor the "
                               "text of a quoted FRETish variable",
                               line=kline, col=kcol, variable=name)
        exact = False
        if col is not None:
            off, exact = _value_start(rest, expr)
            col = col + off
        pending[name] = (expr, line, col, exact)
    # references to other variables: compile in dependency order, cycles are errors
    deps: dict[str, list[str]] = {}
    for name, (expr, line, col, exact) in pending.items():
        node, _t = _parse(expr, _Where(source, name, line, col, exact))
        deps[name] = [r for r in _refs(node) if r in pending]
    state: dict[str, int] = {}

    def visit(name: str, chain: list[str]) -> None:
        if state.get(name) == 2:
            return
        if state.get(name) == 1:
            cyc = chain[chain.index(name):] + [name]
            expr, line, col, _e = pending[name]
            raise BindingError(source, "variables refer to each other in a cycle: "
                               + " -> ".join(cyc), line=line, col=col, variable=name)
        state[name] = 1
        for d in deps[name]:
            visit(d, chain + [name])
        expr, line, col, exact = pending[name]
        compiled[name] = compile_expression(name, expr, source=source, line=line, col=col,
                                            exact=exact, refs=compiled)
        state[name] = 2

    compiled: dict[str, Binding] = {}
    for name in pending:
        visit(name, [])
    variables = {name: compiled[name] for name in pending}
    out = Bindings(variables, tick, time_base, lag, source)
    out.logs = _parse_logs(doc.get("logs"), source, at)
    return out


@dataclass(frozen=True)
class LogSelector:
    """``[logs]`` of a binding file: which logs it applies to. ``glob``: patterns matched
    against the log's path from the right (:meth:`pathlib.PurePath.match`: ``"*.bag"``,
    ``"stage_*"``, ``"real/*.mcap"``); ``topics``: topics the log must have. A log is
    selected when it matches some pattern (if any are given) and has every topic (if any
    are given)."""

    glob: tuple[str, ...] = ()
    topics: tuple[str, ...] = ()

    def matches(self, path: str, log_topics: Iterable[str] | None) -> bool:
        from pathlib import PurePath
        p = PurePath(path)
        if self.glob and not any(p.match(g) or p.name == g for g in self.glob):
            return False
        if self.topics and (log_topics is None or not set(self.topics) <= set(log_topics)):
            return False
        return True

    def text(self) -> str:
        parts = []
        if self.glob:
            parts.append("glob " + ", ".join(self.glob))
        if self.topics:
            parts.append("topics " + ", ".join(self.topics))
        return "; ".join(parts)


def _parse_logs(table: Any, source: str, at: Callable) -> "LogSelector | None":
    if table is None:
        return None
    line, col = at("logs")
    if not isinstance(table, dict):
        raise BindingError(source, "logs must be a table [logs]", line=line, col=col)
    for key in table:
        if key not in ("glob", "topics"):
            kl, kc = at("logs", key)
            raise BindingError(source, f"unknown key {key!r} in [logs] (glob, topics)",
                               line=kl, col=kc)

    def strings(key: str) -> tuple[str, ...]:
        v = table.get(key, [])
        v = [v] if isinstance(v, str) else v
        if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
            kl, kc = at("logs", key)
            raise BindingError(source, f"[logs] {key} must be a string or a list of strings",
                               line=kl, col=kc)
        return tuple(v)

    sel = LogSelector(strings("glob"), strings("topics"))
    if not sel.glob and not sel.topics:
        raise BindingError(source, "[logs] needs glob = \"...\" and/or topics = [...]",
                           line=line, col=col)
    return sel


def load_bindings(path: str | Path, inline: Iterable[str] = ()) -> Bindings:
    """Read a binding file (TOML), then apply ``inline`` ``NAME=EXPR`` overrides.

    Raises:
        BindingError: unreadable file, or see :func:`parse_bindings` / :func:`parse_inline`.
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise BindingError(str(path), f"cannot read binding file: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise BindingError(str(path), f"binding file is not UTF-8: {exc}") from None
    b = parse_bindings(text, str(path))
    return b.with_inline(inline) if inline else b


# -- types against a log's schemas -------------------------------------------------------------

_BOOLS = ("bool", "array_bool")
_NUMS = ("number", "array_number")
_WORDS = {"bool": "a boolean", "number": "a number", "array_bool": "an array of booleans",
          "array_number": "an array of numbers", "string": "a string", "message": "a message",
          "array_other": "an array of messages or strings"}


def check_types(binding: Binding, schemas: dict) -> str:
    """Check ``binding`` against the message types of a log (:func:`monitors.schema.log_schemas`)
    before it is evaluated (issue 15): every field path must resolve through fields the
    schema declares (never Python attributes), strings cannot enter arithmetic or
    comparisons, a boolean is not a number and a number is not a boolean, and the value must
    end as a boolean or a number. Topics whose schema is unknown (None) are not checked.

    Returns:
        the binding's type: ``"bool"``, ``"number"`` (or ``"any"`` when unknown).

    Raises:
        BindingError: naming the binding file:line:col, the variable, and the topic and
            field at fault (with the fields that exist and the closest name).
    """
    from .schema import FieldPathError

    where = binding._where()

    def describe(node: Node, t: str) -> str:
        if isinstance(node, Field):
            path = node.text()[len(node.topic) + 1:]
            return (f"{node.text()} (topic {node.topic}, field {path}) is "
                    f"{_WORDS.get(t, t)}")
        return f"{unparse(node).strip('()')} is {_WORDS.get(t, t)}"

    def need(node: Node, t: str, ok: tuple, what: str, at: Node) -> None:
        if t != "any" and t not in ok:
            hint = ""
            if t in _NUMS and ok == _BOOLS:
                hint = "; compare it (e.g. x != 0) to make a boolean"
            elif t in _BOOLS and ok == _NUMS:
                hint = "; a boolean is not a number in a binding"
            raise where.error(f"type error: {what}, but {describe(node, t)}{hint}", at.col)

    def typ(node: Node) -> str:
        if isinstance(node, Const):
            return "bool" if isinstance(node.value, bool) else "number"
        if isinstance(node, Field):
            sch = schemas.get(node.topic)
            if sch is None:
                return "any"
            try:
                ft = sch.resolve(node.path)
            except FieldPathError as exc:
                raise where.error(f"{exc} (topic {node.topic}, {sch.typename})", node.col) from None
            if ft.kind == "array":
                k = ft.item.kind
                return {"bool": "array_bool", "number": "array_number"}.get(k, "array_other")
            return {"bool": "bool", "number": "number", "string": "string",
                    "message": "message"}.get(ft.kind, "any")
        if isinstance(node, Unary):
            t = typ(node.arg)
            if node.op == "-":
                need(node.arg, t, _NUMS, "unary '-' takes a number", node)
                return t
            need(node.arg, t, _BOOLS, "'!' takes a boolean", node)
            return t
        if isinstance(node, Binary):
            a, b = typ(node.left), typ(node.right)
            arr = "array" in a or "array" in b
            if node.op in ("+", "-", "*", "/"):
                need(node.left, a, _NUMS, f"{node.op!r} takes numbers", node)
                need(node.right, b, _NUMS, f"{node.op!r} takes numbers", node)
                return "array_number" if arr else ("any" if "any" in (a, b) else "number")
            if node.op in ("<", "<=", ">", ">="):
                need(node.left, a, _NUMS, f"{node.op!r} compares numbers", node)
                need(node.right, b, _NUMS, f"{node.op!r} compares numbers", node)
                return "array_bool" if arr else "bool"
            if node.op in ("=", "!="):
                known = [x for x in (a, b) if x != "any"]
                for n, x in ((node.left, a), (node.right, b)):
                    need(n, x, _NUMS + _BOOLS, f"{node.op!r} compares numbers or booleans", node)
                if len(known) == 2 and (known[0] in _BOOLS) != (known[1] in _BOOLS):
                    raise where.error(f"type error: {node.op!r} compares a boolean with a number "
                                      f"({describe(node.left, a)}; {describe(node.right, b)})",
                                      node.col)
                return "array_bool" if arr else "bool"
            need(node.left, a, _BOOLS, f"{node.op!r} takes booleans", node)
            need(node.right, b, _BOOLS, f"{node.op!r} takes booleans", node)
            return "array_bool" if arr else "bool"
        if isinstance(node, Call):
            f = node.func
            if f == "age":
                return "number"
            ts = [typ(a) for a in node.args]
            for a, t in zip(node.args, ts):
                if f in ("any", "all", "count"):
                    need(a, t, ("array_bool", "array_number"), f"{f}() takes an array", node)
                elif f == "len":
                    if t not in ("any", "array_bool", "array_number", "array_other"):
                        need(a, t, ("array_number",), "len() takes an array", node)
                else:
                    need(a, t, _NUMS, f"{f}() takes numbers", node)
            if f in ("any", "all"):
                return "bool"
            if f == "abs":
                return ts[0] if ts[0] != "any" else "any"
            if f in ("min", "max") and len(ts) > 1:
                for a, t in zip(node.args, ts):
                    if "array" in t:
                        raise where.error(f"type error: {f}() of several values takes numbers, "
                                          f"but {describe(a, t)}", node.col)
            return "number"
        return "any"  # pragma: no cover

    t = typ(binding.ast)
    if t not in ("bool", "number", "any"):
        raise where.error(f"type error: a variable must be a boolean or a number, but "
                          f"{describe(binding.ast, t)}"
                          + ("; reduce it with min/max/any/all/count" if "array" in t else ""))
    return t
