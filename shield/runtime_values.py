"""The values of a shield's atoms, standard library only: an atom's truth for a variable's
value, the comparisons of several variables and their terms (:mod:`fretc.shield.predicates`),
the kinds of the variables atoms read, the number nearest a proposal that gives a
valuation of a variable's comparisons (the corrected numbers), the decided values of a
message group made one message (:func:`as_message`, :mod:`fretc.shield.message_model`), and
each value a step reads checked (:func:`read_value`).

Part of the shield's step (:mod:`fretc.shield.runtime`): ``fretc shield --emit python``
writes this module's source, then :mod:`fretc.shield.runtime_bounds`' and the runtime's,
into the generated module (:func:`fretc.shield.emit_python.render_python`), so it imports
nothing of fretc's.
"""

from __future__ import annotations

import itertools
import math
import numbers
from collections.abc import Callable
from typing import Any

__all__ = ["truth", "term_value", "term_variables", "kinds", "nearest", "message_value",
           "as_message", "MESSAGE_ORDERS", "Unreadable", "read_value"]

#: the most numbers of one message whose write orders are all tried (their permutations);
#: past it, only the first order (:func:`as_message`)
MESSAGE_ORDERS = 4

_OPS: dict[str, Callable[[float, float], bool]] = {
    "<": lambda x, c: x < c, "<=": lambda x, c: x <= c, ">": lambda x, c: x > c,
    ">=": lambda x, c: x >= c, "=": lambda x, c: x == c, "!=": lambda x, c: x != c}
_NOT = {"<": ">=", "<=": ">", ">": "<=", ">=": "<", "=": "!=", "!=": "="}


def truth(spec: tuple[str, str | None, float | None], value: Any) -> bool:
    """The truth of the atom ``spec`` ``(variable, op, constant)`` for the variable's
    ``value`` (op None: a boolean variable, which must be given a bool or an int).

    Raises:
        TypeError: a boolean variable given something else. ValueError: a NaN."""
    var, op, c = spec
    if op is None:
        if value is True or value is False:
            return bool(value)
        if not isinstance(value, int):
            raise TypeError(f"{var} must be a boolean, not {value!r}")
        return bool(value)
    x = float(value)
    if x != x:
        raise ValueError(f"{var} is NaN: its comparisons have no truth value")
    assert c is not None  # a comparison has its constant
    return _OPS[op](x, c)


def term_value(t: tuple[Any, ...], values: dict[str, Any]) -> Any:
    """A comparison of several variables, or one of its terms, at the variables' ``values``
    in double arithmetic (IEEE division, as C computes it): ``("cmp", op, a, b)`` gives a
    bool; ``("var", name)``, ``("num", x)``, ``("neg", a)``, ``(op, a, b)`` for ``+ - * /``,
    ``("fn", absReal|absInt|minReal|minInt|maxReal|maxInt, a[, b])`` a float.

    Raises ValueError: a variable's value is NaN."""
    op = t[0]
    if op == "cmp":
        return _OPS[t[1]](term_value(t[2], values), term_value(t[3], values))
    if op == "var":
        x = float(values[t[1]])
        if x != x:
            raise ValueError(f"{t[1]} is NaN: its comparisons have no truth value")
        return x
    if op == "num":
        return t[1]
    if op == "neg":
        return -term_value(t[1], values)
    if op == "fn":
        xs = [term_value(a, values) for a in t[2:]]
        f = t[1][:3]
        return abs(xs[0]) if f == "abs" else min(xs) if f == "min" else max(xs)
    a, b = term_value(t[1], values), term_value(t[2], values)
    if op in ("+", "-", "*"):
        return a + b if op == "+" else a - b if op == "-" else a * b
    if b == 0:
        return math.nan if a == 0 or a != a else math.copysign(math.inf, a) * math.copysign(1.0, b)
    return a / b


def term_variables(t: tuple[Any, ...]) -> set[str]:
    """The variables a comparison of several variables reads (:func:`term_value`'s shape)."""
    if t[0] == "var":
        return {t[1]}
    return set().union(*(term_variables(x) for x in t[1:] if isinstance(x, tuple)))


def kinds(specs: list[tuple[str, str | None, Any]]) -> dict[str, str]:
    """Each variable the atoms ``specs`` read -> ``"b"`` (a boolean) or ``"n"`` (a
    number), in first-seen order."""
    out: dict[str, str] = {}
    for var, op, c in specs:
        if op == "pred":
            for v in sorted(term_variables(c)):
                out.setdefault(v, "n")
        else:
            out.setdefault(var, "b" if op is None else "n")
    return out


def nearest(specs: list[tuple[str, str | None, float | None]], truths: list[int],
            x: float, integer: bool = False) -> float:
    """The number nearest ``x`` giving the comparisons ``specs`` (of one variable) the
    values ``truths``: ``x`` when it does, else the nearest end of their region (an open end
    one float inside). ``integer`` (a variable of whole numbers): ``x`` when it gives them
    and is whole or infinite, else the whole number nearest ``x`` that gives them (the
    smaller of two as near; for a NaN or infinite ``x``, nearest the region's end as above),
    so that a proposal of 4.4 under ``gear != 4`` is not left for an integer actuator to
    round to 4. Raises ValueError when no number gives them."""
    if not math.isnan(x) and all(truth(s, x) == bool(t) for s, t in zip(specs, truths)) \
            and (not integer or math.isinf(x) or x == math.floor(x)):
        return x
    if integer:
        return _nearest_whole(specs, truths, x)
    lo, hi = -math.inf, math.inf
    points: list[float] = []
    for (_v, spec_op, c), t in zip(specs, truths):
        assert spec_op is not None and c is not None  # numbers: comparisons only
        op = spec_op if t else _NOT[spec_op]
        if op in ("<", "<="):
            hi = min(hi, c)
        elif op in (">", ">="):
            lo = max(lo, c)
        elif op == "=":
            points.append(c)
    start = min(max(x, lo), hi) if not math.isnan(x) else (
        lo if math.isfinite(lo) else hi if math.isfinite(hi) else 0.0)
    for v in points + [start]:
        for w in (v, math.nextafter(v, math.inf), math.nextafter(v, -math.inf)):
            if all(truth(s, w) == bool(t) for s, t in zip(specs, truths)):
                return w
    raise ValueError("no number gives the comparisons of " + specs[0][0] + " those values")


def _nearest_whole(specs: list[tuple[str, str | None, float | None]], truths: list[int],
                   x: float) -> float:
    """:func:`nearest` for a variable of whole numbers: the truths change only at the
    constants, so the nearest whole number giving them is ``floor(x)``, ``ceil(x)``, or
    ``ceil(c) - 1``, ``floor(c)`` or ``floor(c) + 1`` of a constant ``c``
    (:meth:`fretc.check.numeric_abstraction.NumericAbstraction.region` keeps the same
    points); the candidates are compared in doubles, as the C shield does."""
    near = x
    if not math.isfinite(x):  # (NaN or infinite: the region's end, as for reals)
        near = nearest(specs, truths, x)
    cands = [math.floor(near), math.ceil(near)] if math.isfinite(near) else []
    for _v, _op, c in specs:
        assert c is not None  # numbers: comparisons only
        if math.isfinite(c):
            cands += [math.ceil(c) - 1, math.floor(c), math.floor(c) + 1]
    best = None
    for w in map(float, cands):
        if all(truth(s, w) == bool(t) for s, t in zip(specs, truths)) and (
                best is None or abs(w - near) < abs(best - near)
                or (abs(w - near) == abs(best - near) and w < best)):
            best = w
    if best is None:
        raise ValueError("no whole number gives the comparisons of " + specs[0][0]
                         + " those values")
    return best


def message_value(t: tuple[Any, ...], msg: list[Any]) -> Any:
    """A message term (:mod:`fretc.shield.message_model`) on the message ``msg`` (one value
    per slot, doubles; a boolean field 0/1): a bool for ``not and or iff cmp``, else a
    number."""
    op = t[0]
    if op == "slot":
        return msg[t[1]]
    if op == "num":
        return t[1]
    if op == "not":
        return not message_value(t[1], msg)
    if op == "and":
        return bool(message_value(t[1], msg)) and bool(message_value(t[2], msg))
    if op == "or":
        return bool(message_value(t[1], msg)) or bool(message_value(t[2], msg))
    if op == "iff":
        return bool(message_value(t[1], msg)) == bool(message_value(t[2], msg))
    if op == "cmp":
        return _OPS[t[1]](message_value(t[2], msg), message_value(t[3], msg))
    if op == "neg":
        return -message_value(t[1], msg)
    return abs(message_value(t[2], msg))  # ("fn", "abs", a)


def _message_write(t: tuple[Any, ...], msg: list[Any], x: float) -> bool:
    """Set the slot the number's term ``t`` reads so that ``t`` gives ``x`` (a field; ``-a``;
    ``abs(a)``, ``a``'s sign kept, + when it is not negative); False when it cannot."""
    while t[0] != "slot":
        if t[0] == "neg":
            x, t = -x, t[1]
        elif t[0] == "fn" and t[1] == "abs":
            if x < 0:
                return False
            x, t = (-x if message_value(t[2], msg) < 0 else x), t[2]
        else:
            return False
    msg[t[1]] = x
    return True


def _read_as(kind: str, t: tuple[Any, ...], msg: list[Any]) -> Any:
    x = message_value(t, msg)
    return bool(x) if kind == "b" else float(x)


def _same(a: Any, b: Any) -> bool:
    if a is None or b is None:
        return False
    if isinstance(a, bool) or isinstance(b, bool):
        return bool(a) == bool(b)
    return bool(a == b)


def as_message(model: dict[str, Any], bits: tuple[int, ...], specs: list[Any],
               decided: dict[str, Any], proposed: dict[str, Any], fresh: bool = False,
               twisted: dict[str, Any] | None = None) -> dict[str, Any]:
    """The values of one message group as one message gives them (KP-124,
    :mod:`fretc.shield.message_model`): ``model`` the group's table, ``bits`` the machine's
    decided output atoms (``specs`` theirs), ``decided`` the decided value of each of the
    group's variables the requirements read, ``proposed`` the proposal (the raw values of
    the ``passed`` ones; ``fresh``: the proposal's message could not be read, so none of its
    values is written; ``twisted``: the values the shield decided of ``passed`` ones a twist
    scales, written in their proposals' place, fresh or not). Returns the values to use
    (empty: the decided ones are the proposal's message, or no message was found, which the
    tables exclude).

    The message: the witness of the decided valuation with each number of ``writes``
    written through its binding, those the decision kept first (so the corrected ones decide
    a field two numbers read), then in every other order (all when at most
    :data:`MESSAGE_ORDERS`), then the witness alone; the first whose values give ``bits``
    (and whole numbers for ``integers``) is read back through the terms. A ``passed``
    variable's proposal is then written where that changes no other value."""
    own = [(v, k, t) for v, k, t in model["reads"] if v not in model["passed"]]
    if any(decided.get(v) is None for v, _k, _t in own):
        return {}
    kept = all(_same(decided.get(v), proposed.get(v)) for v, _k, _t in own)
    if kept and not (fresh and model["passed"]):
        return {}
    base = model["witness"].get(sum(bits[j] << i for i, j in enumerate(model["atoms"])))
    if base is None:
        return {}
    terms = {v: t for v, _k, t in model["reads"]}
    writes = model["writes"]
    first = tuple(sorted(writes, key=lambda v: not _same(decided[v], proposed.get(v))))
    orders: list[tuple[str, ...]] = [first]
    if len(writes) <= MESSAGE_ORDERS:
        orders += [o for o in itertools.permutations(writes) if o != first]
    for order in [*orders, ()]:
        msg = list(base)
        if not all(_message_write(terms[v], msg, float(decided[v])) for v in order):
            continue
        got = {v: _read_as(k, t, msg) for v, k, t in own}
        if all(truth(specs[j], got[specs[j][0]]) == bool(bits[j]) for j in model["check"]) \
                and all(math.isinf(got[v]) or got[v] == math.floor(got[v])
                        for v in model["integers"]):
            break
    else:
        return {}
    for v in model["passed"]:
        x = proposed.get(v)
        if twisted and v in twisted:
            x = twisted[v]
        elif fresh:
            continue
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
            continue
        trial = list(msg)
        if _message_write(terms[v], trial, float(x)) and all(
                _same(_read_as(k, t, trial), got[w]) for w, k, t in own):
            msg = trial
    got.update({v: _read_as(k, terms[v], msg) for v, k, _t in model["reads"]
                if v in model["passed"]})
    return {v: got[v] for v in model["passed"]} if kept else got


class Unreadable(ValueError):
    """A value the shield cannot read (:mod:`fretc.shield.runtime`, "a step is all or
    nothing"); the message says which and why."""


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def read_value(var: str, kind: str, values: dict[str, Any], proposal: bool = False) -> Any:
    """``values[var]`` checked for a variable read as ``kind`` (``"b"`` a boolean, ``"n"``
    a number; :mod:`fretc.shield.runtime`, "a step is all or nothing"): a bool, or a
    float.

    Raises:
        Unreadable: missing, of the wrong type, NaN, too large for a double, (a
            ``proposal``) infinite, or an exception (a host's reading that failed, e.g. an
            :class:`Unreadable`: its message is the reason)."""
    try:
        value = values[var]
    except KeyError:
        raise Unreadable(f"{var} is missing") from None
    if isinstance(value, Exception):  # (a host's reading that failed, with its reason; an
        # Unreadable of another copy of this module, e.g. a generated shield's, is one too)
        raise Unreadable(str(value))
    t = type(value)
    if t is float and kind == "n":  # (the common cases first: a step reads many values)
        if value != value:
            raise Unreadable(f"{var} is NaN")
        if proposal and (value == math.inf or value == -math.inf):
            raise Unreadable(f"{var} is {value}: no actuator takes an infinite value")
        return value
    if t is bool and kind == "b":
        return value
    if kind == "b":
        if value is True or value is False:
            return value
        if type(value).__name__ == "bool_":  # (numpy's, from a message's array)
            return bool(value)
        if isinstance(value, numbers.Integral) and value in (0, 1):
            return bool(value)
        raise Unreadable(f"{var} must be a boolean, not {_shown(value)}")
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or type(value).__name__ == "bool_":
        raise Unreadable(f"{var} must be a number, not {_shown(value)}")
    try:
        x = float(value)
    except (OverflowError, ValueError, TypeError):
        raise Unreadable(f"{var} is {_shown(value)}, which no double holds") from None
    if x != x:
        raise Unreadable(f"{var} is NaN")
    if proposal and math.isinf(x):
        raise Unreadable(f"{var} is {x}: no actuator takes an infinite value")
    return x


def _checked(kinds_of: dict[str, str], values: dict[str, Any], proposal: bool
             ) -> dict[str, Any]:
    """Every variable of ``kinds_of`` (variable -> kind) read from ``values`` as
    :func:`read_value` reads it (a bool, or a finite float: taken as they are; anything
    else through :func:`read_value`).

    Raises:
        Unreadable: as :func:`read_value`."""
    out = {}
    for v, k in kinds_of.items():
        x = values.get(v, values)  # (``values`` itself: no variable's value)
        t = type(x)
        if (t is bool and k == "b") or (t is float and k == "n" and x - x == 0.0):
            out[v] = x
        else:
            out[v] = read_value(v, k, values, proposal)
    return out
