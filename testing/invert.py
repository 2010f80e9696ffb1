"""Inverting signal bindings: the message field values that make a binding expression
(:mod:`fretc.signals.bindings.expression`) evaluate to a given value, so that a generated
test's trace (FRET variable -> value per tick) can be written as messages of the bound topics
(:mod:`fretc.testing.mcap_log`).

Design notes: ARCHITECTURE.md, `testing/invert.py`."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from fretc.signals.bindings.expression import (BinOp, Const, EntityParam, Expr, Field,
                                               FuncCall, UnaryOp,
                                               unparse)

__all__ = ["NotWritable", "Range", "AGE", "MIN_MARGIN", "REL_MARGIN", "MAX_ALTERNATIVES", "margin",
           "point", "alternatives", "solve", "holds", "field_defaults"]

#: the relative margin of a value written for a comparison: 10 % of the constant's magnitude
REL_MARGIN = 0.1
#: the smallest margin (in the field's unit) of a value written for a comparison
MIN_MARGIN = 1e-3
#: the most assignments :func:`alternatives` keeps for one expression and value
MAX_ALTERNATIVES = 64
#: the key path of an ``age()`` constraint on a topic
AGE = "@age"

_CMP = ("<", "<=", ">", ">=", "=", "!=")
_FLIP = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "=": "=", "!=": "!="}
_NEGATE = {"<": ">=", "<=": ">", ">": "<=", ">=": "<", "=": "!=", "!=": "="}


class NotWritable(Exception):
    """A binding (or a value of it) no message can be derived for: the message says why,
    naming the part of the expression."""


#: an assignment of message fields: ``(topic, field path) -> value``
Assignment = dict[tuple[Any, ...], Any]

def margin(c: float) -> float:
    """The margin of a value written on one side of the threshold ``c``:
    ``max(REL_MARGIN * |c|, MIN_MARGIN)`` (same unit as ``c``)."""
    return max(REL_MARGIN * abs(c), MIN_MARGIN)


def holds(op: str, x: float, c: float) -> bool:
    """``x op c`` for a comparison operator of the binding language (``=`` is equality)."""
    return {"<": x < c, "<=": x <= c, ">": x > c, ">=": x >= c, "=": x == c,
            "!=": x != c}[op]


def point(op: str, c: float, target: bool, nonneg: bool = False) -> float | None:
    """A value ``x`` with ``(x op c) == target``: the constant itself for ``=`` (or ``!=``
    false), else ``c`` moved by :func:`margin` to the wanted side. ``nonneg``: the term is
    never negative (``abs``): a negative candidate is replaced by 0 when 0 is on the wanted
    side; None when no value >= 0 is."""
    if not target:
        op = _NEGATE[op]
    m = margin(c)
    x = {"<": c - m, "<=": c - m, ">": c + m, ">=": c + m, "=": c, "!=": c + m}[op]
    if nonneg and x < 0:
        return 0.0 if holds(op, 0.0, c) else None
    return float(x)


@dataclass(frozen=True)
class Range:
    """Any number between ``lo`` and ``hi`` (each end included when ``lo_in``/``hi_in``;
    +-inf for none), written as ``pref`` unless another constraint on the same field needs
    another value inside: what a comparison asks of its term (``abs(/cmd.linear.x) >= 1e-3``
    is any x >= 1e-3, preferably 0.002), so that another variable giving the field 1.5
    agrees with it."""

    lo: float
    hi: float
    lo_in: bool
    hi_in: bool
    pref: float

    def contains(self, x: float) -> bool:
        """Whether the number ``x`` lies in the range."""
        return ((self.lo < x or (self.lo_in and x == self.lo))
                and (x < self.hi or (self.hi_in and x == self.hi)))

    def meet(self, other: Range) -> Range | None:
        """The numbers in both ranges (None when none), preferring this one's ``pref``,
        then the other's, then a point inside by :func:`margin`."""
        lo, lo_in = max((self.lo, self.lo_in), (other.lo, other.lo_in),
                        key=lambda e: (e[0], not e[1]))
        hi, hi_in = min((self.hi, self.hi_in), (other.hi, other.hi_in),
                        key=lambda e: (e[0], e[1]))
        out = Range(lo, hi, lo_in, hi_in, self.pref)
        inside = [(lo + hi) / 2 if math.isfinite(lo) and math.isfinite(hi) else None,
                  lo + margin(lo) if math.isfinite(lo) else None,
                  hi - margin(hi) if math.isfinite(hi) else None, 0.0, lo, hi]
        for x in [self.pref, other.pref] + inside:
            if x is not None and math.isfinite(x) and out.contains(x):
                return Range(lo, hi, lo_in, hi_in, float(x))
        return None

    def neg(self) -> Range:
        """The range of ``-x``."""
        return Range(-self.hi, -self.lo, self.hi_in, self.lo_in, -self.pref)


def _range(op: str, c: float, pref: float) -> Range | float:
    """The numbers ``x`` with ``x op c`` as a :class:`Range` (``=``/``!=``: the point)."""
    inf = math.inf
    return {"<": Range(-inf, c, False, False, pref), "<=": Range(-inf, c, False, True, pref),
            ">": Range(c, inf, False, False, pref), ">=": Range(c, inf, True, False, pref)
            }.get(op, pref)


def _meet(a: Any, b: Any) -> Any:
    """The value satisfying both ``a`` and ``b`` (numbers, strings, bools, :class:`Range`,
    one-element lists of them), or :data:`_NONE`."""
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b) == 1:
        m = _meet(a[0], b[0])
        return _NONE if m is _NONE else [m]
    if isinstance(a, Range) and isinstance(b, Range):
        m = a.meet(b)
        return _NONE if m is None else m
    if isinstance(a, Range) or isinstance(b, Range):
        r, x = (a, b) if isinstance(a, Range) else (b, a)
        ok = isinstance(x, float) and not isinstance(x, bool) and r.contains(x)
        return x if ok else _NONE
    return a if a == b and type(a) is type(b) else _NONE


_NONE = object()


def _resolved(v: Any) -> Any:
    if isinstance(v, Range):
        return v.pref
    if isinstance(v, list):
        return [_resolved(x) for x in v]
    return v


def _merge(a: Assignment, b: Assignment) -> Assignment | None:
    """The union of two assignments, None when they set one key to values no one value
    satisfies."""
    out = dict(a)
    for k, v in b.items():
        if k in out:
            v = _meet(out[k], v)
            if v is _NONE:
                return None
        out[k] = v
    return out


def _product(lists: list[list[Assignment]]) -> list[Assignment]:
    """Every consistent union of one assignment from each list (at most MAX_ALTERNATIVES)."""
    acc: list[Assignment] = [{}]
    for alts in lists:
        acc = [m for a in acc for b in alts if (m := _merge(a, b)) is not None]
        acc = acc[:MAX_ALTERNATIVES]
    return acc


def _field_key(f: Field) -> tuple[Any, ...]:
    if not f.path or not all(isinstance(p, str) for p in f.path):
        raise NotWritable(f"{f.text()}: only a field with a path of attribute names is "
                          "written (no index, slice, filter or whole message)")
    return (f.topic, tuple(f.path))


def _logical(e: BinOp, target: Any) -> list[Assignment]:
    if not isinstance(target, bool):
        raise NotWritable(f"{unparse(e)}: a boolean expression given a number")
    a, b = e.left, e.right
    if e.op == "->":  # a -> b is !a | b
        return _logical(BinOp(e.col, "|", UnaryOp(e.col, "!", a), b), target)
    if e.op == "<->":
        same = [[alternatives(a, v), alternatives(b, v)] for v in (True, False)]
        pairs = same if target else [[alternatives(a, v), alternatives(b, not v)]
                                     for v in (True, False)]
        return [m for p in pairs for m in _product(p)][:MAX_ALTERNATIVES]
    both = (e.op == "&") == target  # & true and | false: both operands give the target
    if both:
        return _product([alternatives(a, target), alternatives(b, target)])
    return (alternatives(a, target) + alternatives(b, target))[:MAX_ALTERNATIVES]


def _age(f: Expr, op: str, c: float, target: bool) -> list[Assignment]:
    if not isinstance(f, Field):
        raise NotWritable(f"age({unparse(f)}): only age of a topic is written")
    if not target:
        op = _NEGATE[op]
    if op in ("=", "!="):
        raise NotWritable(f"age({f.text()}) {op} {c}: only an order comparison of age() "
                          "is written")
    silent = op in (">", ">=")
    strict = op in (">", "<=")  # silent: age > c; fresh: age <= c, i.e. not (age > c)
    return [{(f.topic, AGE): (silent, int(round(c * 1e9)), strict)}]


def _comparison(e: BinOp, target: Any) -> list[Assignment]:
    if not isinstance(target, bool):
        raise NotWritable(f"{unparse(e)}: a comparison given a number")
    term, const, op = _folded(e.left), _folded(e.right), e.op
    if isinstance(term, Const) and not isinstance(const, Const):
        term, const, op = const, term, _FLIP[op]
    if not isinstance(const, Const) or isinstance(term, Const):
        raise NotWritable(f"{unparse(e)}: only a comparison of one term with a constant "
                          "is written")
    c = const.value
    if isinstance(c, EntityParam):
        raise NotWritable(f"{unparse(e)}: a comparison with an entity's key")
    if isinstance(c, str) or isinstance(c, bool):
        if op not in ("=", "!="):
            raise NotWritable(f"{unparse(e)}: an order comparison with {c!r}")
        want = (op == "=") == target
        if want:
            return alternatives(term, c)
        if isinstance(c, bool):
            return alternatives(term, not c)
        return alternatives(term, "" if c else "other")
    if isinstance(term, FuncCall) and term.func == "age":
        return _age(term.args[0], op, float(c), target)
    nonneg = isinstance(term, FuncCall) and term.func == "abs"
    if (op if target else _NEGATE[op]) == "!=":  # either side of c (one point, c + margin,
        # missed x != 4 & x < 3.5: the shield took such outputs for no message's)
        out: list[Assignment] = []
        for side in (">", "<"):
            x = point(side, float(c), True, nonneg)
            if x is not None:
                out += alternatives(term, _range(side, float(c), x))
        return out[:MAX_ALTERNATIVES]
    x = point(op, float(c), target, nonneg)
    if x is None:
        return []
    return alternatives(term, _range(op if target else _NEGATE[op], float(c), x))


def _folded(e: Expr) -> Expr:
    """``-c`` of a numeric constant as the constant ``-c`` (the parser reads ``-2.5`` so)."""
    if (isinstance(e, UnaryOp) and e.op == "-" and isinstance(e.arg, Const)
            and isinstance(e.arg.value, float) and not isinstance(e.arg.value, bool)):
        return Const(e.col, -e.arg.value)
    return e


def _function(e: FuncCall, target: Any) -> list[Assignment]:
    if isinstance(target, bool):
        raise NotWritable(f"{unparse(e)}: a number given a boolean")
    if e.func == "abs" and len(e.args) == 1:
        if isinstance(target, Range):  # the x >= 0 branch
            r = target.meet(Range(0.0, math.inf, True, False, max(target.pref, 0.0)))
            return [] if r is None else alternatives(e.args[0], r)
        return [] if target < 0 else alternatives(e.args[0], float(target))
    if e.func in ("min", "max") and len(e.args) == 1 and isinstance(e.args[0], Field):
        return [{_field_key(e.args[0]): [target if isinstance(target, Range)
                                         else float(target)]}]
    raise NotWritable(f"{unparse(e)}: {e.func}() is not inverted")


def alternatives(e: Expr, target: Any) -> list[Assignment]:
    """The assignments (module docstring) that make ``e`` evaluate to ``target`` (a bool, a
    float or a string), at most :data:`MAX_ALTERNATIVES`, the simplest first; an empty list
    when none does (``abs(x) = -1``).

    Raises:
        NotWritable: ``e`` holds a part that is not inverted (module docstring)."""
    if isinstance(e, Field):
        return [{_field_key(e): target}]
    if isinstance(e, Const):
        if isinstance(target, Range):
            ok = isinstance(e.value, float) and target.contains(e.value)
            return [{}] if ok else []
        return [{}] if e.value == target else []
    if isinstance(e, UnaryOp):
        if e.op == "!":
            if not isinstance(target, bool):
                raise NotWritable(f"{unparse(e)}: a boolean expression given a number")
            return alternatives(e.arg, not target)
        if isinstance(target, (bool, str)):
            raise NotWritable(f"{unparse(e)}: a number given {target!r}")
        return alternatives(e.arg, target.neg() if isinstance(target, Range)
                            else -float(target))
    if isinstance(e, BinOp) and e.op in ("&", "|", "->", "<->"):
        return _logical(e, target)
    if isinstance(e, BinOp) and e.op in _CMP:
        return _comparison(e, target)
    if isinstance(e, FuncCall):
        return _function(e, target)
    raise NotWritable(f"{unparse(e)}: not inverted (arithmetic and other operators are "
                      "not written)")


def solve(wanted: list[tuple[str, Expr, Any]]) -> tuple[Assignment | None, str, str]:
    """One assignment making every ``(variable, expression, value)`` of ``wanted`` give its
    value together (backtracking over each one's :func:`alternatives`), ``""`` and ``""``;
    or None, the variable that cannot be given its value with those before it, and the
    words naming them (those before it reading a field it reads).

    Raises:
        NotWritable: an expression is not inverted."""
    options = [(name, alternatives(expr, value), value) for name, expr, value in wanted]
    options.sort(key=lambda o: len(o[1]))

    def search(i: int, acc: Assignment, depth: list[int]) -> Assignment | None:
        depth[0] = max(depth[0], i)
        if i == len(options):
            return acc
        for alt in options[i][1]:
            m = _merge(acc, alt)
            if m is not None and (got := search(i + 1, m, depth)) is not None:
                return got
        return None

    depth = [0]
    got = search(0, {}, depth)
    if got is not None:
        return {k: _resolved(v) for k, v in got.items()}, "", ""
    name, alts, value = options[depth[0]]
    if not alts:
        return None, name, f"{name}={_show(value)} is not a value its binding can give"
    keys = {k for a in alts for k in a}
    others = [f"{n}={_show(v)}" for n, al, v in options[:depth[0]]
              if keys & {k for a in al for k in a}]
    return None, name, (f"{name}={_show(value)} conflicts with " + ", ".join(others)
                  if others else f"{name}={_show(value)} conflicts with the other variables")


def _show(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v)


def field_defaults(e: Expr, ctx: str = "bool") -> dict[tuple[Any, ...], Any]:
    """Every field of ``e`` that :func:`alternatives` may set, with the value a message holds
    when no variable sets it: ``[0.0]`` under ``min``/``max``, ``""`` when compared with a
    string, ``false`` where a boolean is read, else 0.0. ``ctx``: what ``e`` itself gives
    (``"bool"``, ``"num"``, ``"str"``). Fields that are not inverted are left out."""
    if isinstance(e, Field):
        if not e.path or not all(isinstance(p, str) for p in e.path):
            return {}
        return {(e.topic, tuple(e.path)): {"bool": False, "str": ""}.get(ctx, 0.0)}
    if isinstance(e, UnaryOp):
        return field_defaults(e.arg, "bool" if e.op == "!" else "num")
    if isinstance(e, BinOp):
        if e.op in _CMP:
            strs = any(isinstance(x, Const) and isinstance(x.value, str)
                       for x in (e.left, e.right))
            bools = any(isinstance(x, Const) and isinstance(x.value, bool)
                        for x in (e.left, e.right))
            sub = "str" if strs else "bool" if bools else "num"
            return {**field_defaults(e.left, sub), **field_defaults(e.right, sub)}
        sub = "bool" if e.op in ("&", "|", "->", "<->") else "num"
        return {**field_defaults(e.left, sub), **field_defaults(e.right, sub)}
    if isinstance(e, FuncCall):
        if e.func in ("min", "max") and len(e.args) == 1 and isinstance(e.args[0], Field):
            return {k: [0.0] for k in field_defaults(e.args[0], "num")}
        if e.func == "abs" and len(e.args) == 1:
            return field_defaults(e.args[0], "num")
    return {}
