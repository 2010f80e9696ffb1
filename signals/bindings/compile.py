"""Compilation of an expression tree to nested Python closures (no ``eval`` of user text).

:func:`compile_node` gives, for one :class:`~fretc.signals.bindings.expression.Expr`, a function
of what the evaluation sees: an :class:`EvalState` (one tick: the held messages, their times
and the tick time) or, vectorized, a columns object (all ticks at once: ``n``,
``field(topic, path, node)`` and ``age(topic)``, see :mod:`fretc.signals.arrays`).  Both
evaluators apply the same :mod:`~fretc.signals.bindings.operations`, so they give the same values.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from fretc.common.units import NS_PER_S

from fretc.signals.bindings.expression import (GEOMETRY_CALLS, GEOMETRY_VALUES, BinOp, Const, EntityParam, Expr,
                                               Field, FuncCall, Named, UnaryOp, const_value,
                                               geometry_tf, walk)
from fretc.signals.bindings.extract import FieldAccessError, Valid, make_extractor
from fretc.signals.bindings.frames import LookupFailed, TfBuffer, pick_joint
from fretc.signals.bindings.geometry import compile_geometry
from fretc.signals.bindings.operations import (COMPARISONS, LOGICAL, NP_BINARY, PY_BINARY, PY_TYPES, Ops, max2, min2,
                         np_three_valued, num, py_three_valued, undeclared_inf)

__all__ = ["EvalState", "EvalError", "compile_node", "per_message_topic"]

Evaluator = Callable[[Any], Any]


class EvalState:
    """What a per-tick evaluation sees.

    Attributes:
        msgs: topic → data of the latest message at or before the tick (sample-and-hold).
        times: topic → time (ns, in the time base) of that message.
        now: the tick time (ns).
    """

    __slots__ = ("msgs", "times", "now", "values", "tf", "prev_msgs", "prev_times")

    def __init__(self) -> None:
        self.msgs: dict[str, Any] = {}
        self.times: dict[str, int] = {}
        self.now = 0
        #: (topic, field path) → (message data, extracted value): extraction memo.
        self.values: dict[tuple[str, Any], tuple[Any, Any]] = {}
        #: every transform of /tf and /tf_static so far, when a binding reads ``tf()``
        #: (the clock adds each message: :meth:`TfBuffer.add`); None otherwise.
        self.tf: TfBuffer | None = None
        #: topic -> the message before the held one and its time (``@delta``,
        #: ``@timedelta``, ``@derivative``), for the topics some binding reads so.
        self.prev_msgs: dict[str, Any] = {}
        self.prev_times: dict[str, int] = {}


class EvalError(Exception):
    """An evaluation that failed at ``node`` (its column goes into the error message)."""

    def __init__(self, node: Expr, message: str) -> None:
        super().__init__(message)
        self.node = node
        self.message = message


def compile_node(node: Expr, ops: Ops, extractors: dict[Field, Evaluator],
                 constants: dict[str, Any] | None = None) -> Evaluator:
    """Closure evaluating ``node``; its argument is an :class:`EvalState` (``ops`` per tick)
    or a columns object (``ops`` vectorized).  ``extractors`` (field -> extractor) is shared
    by the per-tick and the vectorized compilation of one binding; ``constants`` (name ->
    value: the :class:`Named` constants, filled in when the binding is checked against a
    log's schemas) is read when the closure runs.

    The closure raises :class:`EvalError` (a field missing from a message, an operation that
    does not apply to its values).
    """
    consts = constants if constants is not None else {}
    if isinstance(node, Const):
        v = node.value
        if isinstance(v, EntityParam):  # an entity's key, set before each evaluation
            return lambda st: v.value
        return lambda st: v
    if isinstance(node, Named):
        return _named(node, consts)
    if isinstance(node, Field):
        return _field(node, ops, extractors, consts)
    if isinstance(node, UnaryOp):
        return _unary(node, ops, extractors, consts)
    if isinstance(node, BinOp):
        return _binary(node, ops, extractors, consts)
    if isinstance(node, FuncCall):
        return _call(node, ops, extractors, consts)
    raise AssertionError(node)  # pragma: no cover


def _named(node: Named, consts: dict[str, Any]) -> Evaluator:
    name = node.name

    def named(st: Any) -> Any:
        try:
            return consts[name]
        except KeyError:
            raise EvalError(node, f"{name} is not a variable of this binding file, and its "
                            "value as a named constant was not read from the log's schemas "
                            "(fretc audit reads them before the audit; fretc watch does not: "
                            "write the number)") from None
    return named


def _field(node: Field, ops: Ops, extractors: dict[Field, Evaluator],
           consts: dict[str, Any]) -> Evaluator:
    if ops.vec:
        topic, path = node.topic, node.path
        if ops.inf_unread:
            return lambda cols: undeclared_inf(cols.field(topic, path, node), path)
        return lambda cols: cols.field(topic, path, node)
    if ops.inf_unread:
        plain = _field(node, Ops(False, ops.nan_unread, False), extractors, consts)
        fpath = node.path
        return lambda st: undeclared_inf(plain(st), fpath)
    ex = extractors.setdefault(node, make_extractor(node, consts))
    topic = node.topic
    key = (topic, node.text())  # not its path: the same field at another column is the same

    def field_value(st: EvalState) -> Any:
        msg = st.msgs[topic]
        memo = st.values.get(key)  # shared by bindings and ticks while the message is held
        if memo is not None and memo[0] is msg:
            return memo[1]
        try:
            v = ex(msg)
        except FieldAccessError as exc:
            raise EvalError(node, str(exc)) from None
        st.values[key] = (msg, v)
        return v

    return field_value


def _unary(node: UnaryOp, ops: Ops, extractors: dict[Field, Evaluator],
           consts: dict[str, Any]) -> Evaluator:
    arg = compile_node(node.arg, ops, extractors, consts)
    if node.op == "-":
        def neg(st: Any) -> Any:
            a = arg(st)
            if type(a) in PY_TYPES:
                return -a
            return ops.lift1(np.negative, a, True)
        return neg

    if ops.nan_unread:
        def not3(st: Any) -> Any:
            a = arg(st)
            if type(a) in PY_TYPES:
                return py_three_valued("!", a) if a != a else not a
            return ops.lift1(lambda x: np_three_valued("!", x), a, False)
        return not3

    def not_(st: Any) -> Any:
        a = arg(st)
        if type(a) in PY_TYPES:
            return not a
        return ops.lift1(np.logical_not, a, False)
    return not_


def _binary(node: BinOp, ops: Ops, extractors: dict[Field, Evaluator],
            consts: dict[str, Any]) -> Evaluator:
    left = compile_node(node.left, ops, extractors, consts)
    right = compile_node(node.right, ops, extractors, consts)
    npfn, numeric = NP_BINARY[node.op]
    pyfn = PY_BINARY[node.op]
    text_ok = node.op in ("=", "!=")
    if ops.nan_unread and node.op in COMPARISONS:
        npfn, pyfn = _nan_aware(npfn, pyfn)
    if ops.nan_unread and node.op in LOGICAL:
        return _logic3(node, left, right, ops)

    def binary(st: Any) -> Any:
        a = left(st)
        b = right(st)
        if type(a) in PY_TYPES and type(b) in PY_TYPES:
            return pyfn(a, b)
        if text_ok and (type(a) is str or type(b) is str):
            if isinstance(a, list) or isinstance(b, list):  # an array of strings, item-wise
                items, one = (a, b) if isinstance(a, list) else (b, a)
                return Valid(np.array([pyfn(x, one) for x in items], dtype=np.bool_), None)
            return pyfn(a, b)  # text equality (types checked: both are strings)
        try:
            return ops.lift2(npfn, a, b, numeric)
        except (ValueError, TypeError) as exc:
            raise EvalError(node, f"cannot apply {node.op!r}: {exc}") from None
    return binary


def _nan_aware(npfn, pyfn):
    """A comparison's numpy and Python functions under the policy "unread": NaN when an
    operand is NaN (per item for arrays), else the comparison
    (:mod:`fretc.signals.bindings.operations`)."""
    def py(a: Any, b: Any) -> Any:
        return math.nan if (a != a or b != b) else pyfn(a, b)

    def np_(da: Any, db: Any) -> Any:
        out = npfn(num(da), num(db))
        bad = None
        for d in (da, db):
            if isinstance(d, np.ndarray) and d.dtype.kind == "f":
                m = np.isnan(d)
                bad = m if bad is None else bad | m
        if bad is None or not bad.any():
            return out
        bad = np.broadcast_to(bad, np.shape(out))
        return np.where(bad, np.nan, np.asarray(out, dtype=np.float64))
    return np_, py


def _logic3(node: BinOp, left: Evaluator, right: Evaluator, ops: Ops) -> Evaluator:
    """``& | -> <->`` under the policy "unread": Kleene's three-valued logic, NaN unknown."""
    op = node.op
    pyfn = PY_BINARY[op]

    def logic(st: Any) -> Any:
        a = left(st)
        b = right(st)
        if type(a) in PY_TYPES and type(b) in PY_TYPES:
            if a != a or b != b:
                return py_three_valued(op, a, b)
            return pyfn(a, b)
        try:
            return ops.lift2(lambda x, y: np_three_valued(op, x, y), a, b, False)
        except (ValueError, TypeError) as exc:
            raise EvalError(node, f"cannot apply {op!r}: {exc}") from None
    return logic


def _call(node: FuncCall, ops: Ops, extractors: dict[Field, Evaluator],
          consts: dict[str, Any]) -> Evaluator:
    func = node.func
    if func == "age" and isinstance(node.args[0], Const):
        return _entity_age(node, node.args[0].value)
    if func == "age":
        topic = node.args[0].topic  # type: ignore[attr-defined]
        if ops.vec:
            return lambda cols: cols.age(topic)
        return lambda st: (st.now - st.times[topic]) / NS_PER_S
    if func == "tf":
        return _tf(node)
    if func in ("delta", "timedelta", "derivative", "unchanged"):
        return _stateful(node, ops, consts)
    if func == "sector":
        return _sector(node, ops, extractors, consts)
    if func in GEOMETRY_CALLS:
        return _geometry(node, ops, extractors, consts)
    args = [compile_node(a, ops, extractors, consts) for a in node.args]
    if func in _TRIG:
        return _trig(node, args, ops)
    if func == "sqrt":
        a0 = args[0]

        def sqrt_(st: Any) -> Any:
            a = a0(st)
            if type(a) in PY_TYPES:
                return math.sqrt(a) if a >= 0 else math.nan  # NaN compares as unread
            return ops.lift1(np.sqrt, a, True)
        return sqrt_
    if func == "joint":
        return _joint(node, args)
    if func == "abs":
        a0 = args[0]

        def abs_(st: Any) -> Any:
            a = a0(st)
            if type(a) in PY_TYPES:
                return abs(a)
            return ops.lift1(np.abs, a, True)
        return abs_
    if func in ("min", "max", "norm") and len(args) > 1:
        return _several(node, args)
    return _reduction(node, args[0], ops)


#: trigonometry (rad): numpy's in both evaluations, so that a tick's value and a block's are
#: one (libm's and numpy's sin may differ in the last bit)
_TRIG = {"sin": np.sin, "cos": np.cos, "tan": np.tan, "asin": np.arcsin, "acos": np.arccos,
         "atan": np.arctan, "atan2": np.arctan2}


def _trig(node: FuncCall, args: list[Evaluator], ops: Ops) -> Evaluator:
    """``sin(x)`` ... ``atan2(y, x)`` (rad; NaN outside ``asin``'s and ``acos``'s [-1, 1] and
    for an infinite ``sin``, ``cos``, ``tan``), item by item on arrays."""
    fn = _TRIG[node.func]
    if node.func == "atan2":
        a0, a1 = args

        def atan2_(st: Any) -> Any:
            y, x = a0(st), a1(st)
            with np.errstate(all="ignore"):
                if type(y) in PY_TYPES and type(x) in PY_TYPES:
                    return float(fn(float(y), float(x)))
                return ops.lift2(fn, y, x, True)
        return atan2_
    a0 = args[0]

    def trig(st: Any) -> Any:
        a = a0(st)
        with np.errstate(all="ignore"):
            if type(a) in PY_TYPES:
                return float(fn(float(a)))
            return ops.lift1(fn, a, True)
    return trig


def _geometry(node: FuncCall, ops: Ops, extractors: dict[Field, Evaluator],
              consts: dict[str, Any]) -> Evaluator:
    """A geometry call (:mod:`fretc.signals.bindings.geometry`). Vectorized, one of one
    topic's messages that reads no TF (``points_in(scan_points(/scan), polygon(...))``) is
    computed once per message over the block's messages and gathered per tick, as a
    reduction is."""
    def build(o: Ops) -> Evaluator:
        return compile_geometry(node, o.vec, lambda a: compile_node(a, o, extractors, consts),
                                EvalError)
    if not ops.vec or node.func in GEOMETRY_VALUES:
        return build(ops)
    topic = per_message_topic(node)
    vector = build(ops)
    if topic is None:
        return vector
    scalar = build(Ops(False, ops.nan_unread, ops.inf_unread))
    return lambda cols: cols.per_message(node, topic, vector, scalar)


def _entity_age(node: FuncCall, param: Any) -> Evaluator:
    """``age($car)``: the time (s) since the entity's newest message (its
    :class:`~fretc.signals.bindings.expression.EntityParam`'s ``time``, set where entities
    are held on their own); tick by tick only."""

    def age(st: Any) -> Any:
        if isinstance(st, EvalState):
            t = getattr(param, "time", None)
            if t is None:
                raise EvalError(node, f"age({param!r}) is the age of an entity held on its "
                                "own: its kind in [entities] says hold = \"entity\"")
            return (st.now - t) / NS_PER_S
        raise EvalError(node, f"age({param!r}) is evaluated tick by tick only")
    return age


def _tf(node: FuncCall) -> Evaluator:
    """``tf(parent, child).component`` from the transforms held at the tick."""
    parent, child, comp = (a.value for a in node.args)  # type: ignore[attr-defined]
    # (a frame may be an entity's key, $car: read at evaluation)

    def tf(st: Any) -> Any:
        buf = getattr(st, "tf", None)
        if buf is None:
            raise EvalError(node, "tf() is evaluated tick by tick only")
        p, c = const_value(parent), const_value(child)
        if not isinstance(p, str) or not isinstance(c, str):
            raise EvalError(node, f"tf(): a frame name is a string, not {p!r} ({c!r})")
        try:
            return buf.lookup(p, c, comp, st.now)
        except LookupFailed as exc:
            raise EvalError(node, str(exc)) from None
    return tf


def _stateful(node: FuncCall, ops: Ops, consts: dict[str, Any]) -> Evaluator:
    """``delta``/``timedelta``/``derivative`` of an expression of one topic's fields
    (Foxglove's ``@delta`` etc. on a field): its value on the held message of the topic
    against its value on the one before it (times on the time base, seconds);
    ``derivative`` is per second, NaN (unread) when both have one time. Tick by tick only:
    the vectorized evaluator raises, so the sampler evaluates it per tick."""
    arg = node.args[0]
    topic = next(n.topic for n in walk(arg) if isinstance(n, Field))
    func = node.func
    inner = compile_node(arg, Ops(False, ops.nan_unread, ops.inf_unread), {}, consts)
    before_state = EvalState()

    def stateful(st: Any) -> Any:
        if ops.vec or not isinstance(st, EvalState):
            raise EvalError(node, f"@{func} is evaluated tick by tick")
        prev = st.prev_msgs.get(topic)
        if prev is None:
            raise EvalError(node, f"@{func} needs the message before the held one of {topic}")
        dt = (st.times[topic] - st.prev_times[topic]) / NS_PER_S
        if func == "timedelta":
            return dt
        before_state.msgs[topic], before_state.times[topic] = prev, st.prev_times[topic]
        before_state.now = st.prev_times[topic]
        now, before = inner(st), inner(before_state)
        if func == "unchanged":
            return _same_value(now, before)
        try:
            d = float(now) - float(before)  # numbers (numpy scalars too), not arrays
        except (TypeError, ValueError):
            raise EvalError(node, f"@{func} takes a number, not an array") from None
        if func == "delta":
            return d
        return d / dt if dt != 0 else math.nan
    return stateful


def _sector(node: FuncCall, ops: Ops, extractors: dict[Field, Evaluator],
            consts: dict[str, Any]) -> Evaluator:
    """``sector(/scan.ranges, lo, hi)``: the LaserScan's ranges (REP 117's validity mask)
    with only the beams whose angle lies in ``[lo, hi]`` (radians, REP 103: 0 ahead,
    counter-clockwise) kept valid; a beam's angle is ``angle_min + i * angle_increment`` in
    the LiDAR's own frame, wrapped to ``[-pi, pi)``, and ``lo > hi`` is a sector through
    ``pi`` (behind: ``sector(/scan.ranges, 2.356, -2.356)``). So one binding means the same
    sector on a LiDAR of any beam count and field of view (a slice by beam index,
    ``[270:451]``, read nothing on a LiDAR of fewer beams: no valid return, a clear path).
    Tick by tick (message by message inside a reduction): the vectorized evaluator raises."""
    ranges_node = node.args[0]
    assert isinstance(ranges_node, Field)  # (expression's check)
    one = Ops(False, ops.nan_unread, ops.inf_unread)
    ranges = compile_node(ranges_node, one, extractors, consts)
    amin = compile_node(node.args[3], one, extractors, consts)
    ainc = compile_node(node.args[4], one, extractors, consts)
    lo_of = compile_node(node.args[1], one, extractors, consts)
    hi_of = compile_node(node.args[2], one, extractors, consts)

    def sector(st: Any) -> Any:
        if ops.vec or not isinstance(st, EvalState):
            raise EvalError(node, "sector() is evaluated message by message")
        r = ranges(st)
        if not isinstance(r, Valid):
            raise EvalError(node, "sector() takes a LaserScan's ranges")
        start, step = float(amin(st)), float(ainc(st))
        lo, hi = float(lo_of(st)), float(hi_of(st))
        n = r.data.shape[-1]
        angles = np.remainder(start + np.arange(n) * step + math.pi, 2 * math.pi) - math.pi
        lo_w = math.remainder(lo, 2 * math.pi)
        hi_w = math.remainder(hi, 2 * math.pi)
        inside = ((angles >= lo_w) & (angles <= hi_w)) if lo_w <= hi_w else (
            (angles >= lo_w) | (angles <= hi_w))
        mask = inside if r.mask is None else (r.mask & inside)
        # (beams outside the sector are neither valid nor invalid measurements: +inf, "no
        # return", so that invalid() and min() of the sector count only its own beams)
        data = np.where(inside, r.data, np.inf)
        return Valid(data, mask)
    return sector


def _same_value(a: Any, b: Any) -> bool:
    """``unchanged``: whether two values of one field (numbers, booleans, strings or arrays,
    a :class:`Valid`'s data) are the same, NaN equal to NaN (a frozen frame repeats its
    NaNs too)."""
    if isinstance(a, Valid):
        a = a.data
    if isinstance(b, Valid):
        b = b.data
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        x, y = np.asarray(a), np.asarray(b)
        if x.shape != y.shape:
            return False
        if x.dtype.kind == "f" and y.dtype.kind == "f":
            return bool(np.array_equal(x, y, equal_nan=True))
        return bool(np.array_equal(x, y))
    if isinstance(a, float) and isinstance(b, float) and a != a and b != b:
        return True
    return bool(a == b)


def _joint(node: FuncCall, args: list[Evaluator]) -> Evaluator:
    """``joint(/js.position, "name")``: the item of the array whose ``name`` is given."""
    values_of, names_of = args[0], args[2]
    joint_name = node.args[1].value  # type: ignore[attr-defined]
    text = node.args[0].text()  # type: ignore[attr-defined]

    def joint(st: Any) -> Any:
        try:
            return pick_joint(values_of(st), names_of(st), str(const_value(joint_name)), text)
        except LookupFailed as exc:
            raise EvalError(node, str(exc)) from None
    return joint


def _norm(vals: list[Any]) -> Any:
    """sqrt(a² + b² + ...) of Python numbers or of per-tick arrays."""
    if all(type(v) in PY_TYPES for v in vals):
        total = 0.0
        for v in vals:
            total = total + v * v
        return math.sqrt(total)
    total = 0.0
    for v in vals:
        v = num(v)
        total = total + v * v
    return np.sqrt(total)


def _several(node: FuncCall, args: list[Evaluator]) -> Evaluator:
    """``min``/``max``/``norm`` of several values (numbers, not arrays)."""
    func = node.func
    pair = {"min": min2, "max": max2}.get(func)
    npfn = {"min": np.minimum, "max": np.maximum}.get(func)

    def several(st: Any) -> Any:
        vals = [a(st) for a in args]
        for v in vals:
            if isinstance(v, Valid):
                raise EvalError(node, f"{func}() of several values takes numbers, not arrays")
        if func == "norm":
            return _norm(vals)
        acc = vals[0]
        for v in vals[1:]:
            if type(acc) in PY_TYPES and type(v) in PY_TYPES:
                acc = pair(acc, v)  # type: ignore[misc]  # set for min and max (norm returned)
            else:
                acc = npfn(num(acc), num(v))  # type: ignore[misc]  # as pair
        return acc
    return several


def _reduction(node: FuncCall, a0: Evaluator, ops: Ops) -> Evaluator:
    """A function of one value: a reduction of an array (or the value itself for a number)."""
    func = node.func

    def reduce_(st: Any) -> Any:
        a = a0(st)
        if not isinstance(a, Valid):
            if func == "len" and isinstance(a, (list, tuple, str)):
                return float(len(a))  # e.g. len(/tf.transforms): a sequence of messages
            if func in ("min", "max", "mean"):
                return a  # of one number: itself
            if func == "norm":
                return abs(a) if type(a) in PY_TYPES else np.abs(num(a))
            raise EvalError(node, f"{func}() takes an array")
        return ops.reduce(func, a)

    arg0 = node.args[0]
    if ops.vec:
        topic = per_message_topic(arg0)
        if topic is None:
            return reduce_
        # a reduction of one topic's fields (``min(/scan.ranges)``) depends only on the held
        # message: the columns compute it once per message and gather it per tick
        one = Ops(False, ops.nan_unread, ops.inf_unread)
        scalar = _reduction(node, compile_node(arg0, one, {}), one)
        return lambda cols: cols.per_message(node, topic, reduce_, scalar)
    if not isinstance(arg0, Field):
        return reduce_
    # a reduction of one field depends only on the held message: computed once per message,
    # shared by the bindings that use it (like the field memo)
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
    return reduce_memo


def per_message_topic(node: Expr) -> str | None:
    """The one topic whose message alone decides ``node`` (fields of that topic, constants,
    operators and reductions; no ``age``, no other topic), or None."""
    topics = set()
    for n in walk(node):
        if isinstance(n, FuncCall) and n.func in ("age", "delta", "timedelta", "derivative",
                                                  "unchanged"):
            return None
        if isinstance(n, FuncCall) and n.func in GEOMETRY_CALLS and geometry_tf(n):
            return None  # (TF: every message of /tf and /tf_static, not the held one)
        if isinstance(n, Field):
            topics.add(n.topic)
    return topics.pop() if len(topics) == 1 else None
