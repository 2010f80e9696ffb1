"""Outputs bounded by functions of the inputs: comparisons of one output with a term over the
inputs (``linear_velocity <= 0.5 * (front_dist - 0.3)``, ``1.5 * linear_velocity <=
front_dist``, ``linear_velocity <= 0.3 * proposed_velocity``: Nav2's collision monitor's
slowdown, limit and approach written as requirements) as atoms of a game.

Design notes: ARCHITECTURE.md, `check/bounds.py`."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction

from fretc.check.numeric_abstraction import simple_comparison
from fretc.compiler import ir
from fretc.compiler.ir import Node
from fretc.compiler.printers import to_smv

__all__ = ["Bound", "classify", "bounds_of", "feasibility", "half_line"]

_FLIP = {"<": ">", "<=": ">=", ">": "<", ">=": "<="}
_NOT = {"<": ">=", "<=": ">", ">": "<=", ">=": "<"}


@dataclass(frozen=True)
class Bound:
    """A bound (module docstring): ``atom`` the comparison as written, ``output`` the output
    variable it reads, ``op`` and ``bound``: the atom holds exactly when ``output op bound``
    over the reals (``op`` in ``< <= > >=``; ``bound`` a term over the inputs and constants,
    IR)."""

    atom: Node
    output: str
    op: str
    bound: Node

    @property
    def down(self) -> bool:
        """Whether the atom's true values are a half-line downwards (``<``, ``<=``)."""
        return self.op in ("<", "<=")


def half_line(op: str) -> tuple[bool, bool]:
    """``(downwards, strict)`` of the half-line ``v op B`` (``op`` in ``< <= > >=``)."""
    return op in ("<", "<="), op in ("<", ">")


def _exact(n: Node) -> Fraction | None:
    """The exact value of a constant term (numbers, ``-``, ``+ - * /`` of them), or None."""
    if n.op == "num":
        try:
            return Fraction(ir.name_of(n))
        except (ValueError, ZeroDivisionError, OverflowError):
            return None
    if n.op == "neg":
        x = _exact(n.args[0])
        return None if x is None else -x
    if n.op == "arith" and ir.name_of(n) in ("+", "-", "*", "/"):
        a, b = _exact(n.args[0]), _exact(n.args[1])
        if a is None or b is None or (ir.name_of(n) == "/" and b == 0):
            return None
        op = ir.name_of(n)
        return a + b if op == "+" else a - b if op == "-" else a * b if op == "*" else a / b
    return None


def _reads(n: Node, v: str) -> bool:
    return any(x.op == "var" and ir.name_of(x) == v for x in ir.walk(n))


def classify(node: Node, inputs: Iterable[str]) -> Bound | str | None:
    """``node`` (a comparison) as a bound (module docstring): the :class:`Bound`; None when it
    reads no input or no output (not a comparison of the two); else why it is no bound (a
    sentence naming the comparison, for a refusal)."""
    if node.op != "cmp":
        return None
    names = list(dict.fromkeys(ir.name_of(x) for x in ir.walk(node) if x.op == "var"))
    given = set(inputs)
    ins = [v for v in names if v in given]
    outs = [v for v in names if v not in given]
    if not ins or not outs:
        return None
    text = to_smv(node)
    if len(outs) > 1:
        return (f"{text} compares the input(s) {', '.join(ins)} with the outputs "
                f"{', '.join(outs)}: a bound reads one output (the shield sets one number "
                "against the inputs' numbers); compare each output with the inputs alone")
    v, op = outs[0], ir.name_of(node)
    if op not in _FLIP:
        return (f"{text} compares the output {v} with the input(s) {', '.join(ins)} by {op}: "
                "the shield bounds an output by the inputs (<, <=, >, >=), whose truth values "
                "are half-lines of it; those of = and != are not")
    count = sum(1 for x in ir.walk(node) if x.op == "var" and ir.name_of(x) == v)
    if count > 1:
        return (f"{text} reads the output {v} {count} times: a bound reads it once, so that "
                "each truth value is a half-line of it")
    left, right = node.args
    side, other = (left, right) if _reads(left, v) else (right, left)
    if side is right:
        op = _FLIP[op]
    while side.op != "var":
        got = _step(side, other, op, v, text)
        if isinstance(got, str):
            return got
        side, other, op = got
    return Bound(node, v, op, other)


def _step(side: Node, other: Node, op: str, v: str, text: str
          ) -> tuple[Node, Node, str] | str:
    """One step of solving ``side op other`` for ``v`` (read once in ``side``): the part of
    ``side`` reading ``v``, ``other`` with the rest moved over, the comparison (flipped by a
    negative factor); or why ``v`` is not read linearly with a constant factor."""
    kind = side.op
    if kind == "neg":
        return side.args[0], ir.Node("neg", (other,)), _FLIP[op]
    if kind == "arith":
        a, b = side.args
        name = ir.name_of(side)
        first = _reads(a, v)
        if name == "+":
            return (a, ir.arith("-", other, b), op) if first else (b, ir.arith("-", other, a), op)
        if name == "-":
            return (a, ir.arith("+", other, b), op) if first else (b, ir.arith("-", a, other),
                                                                    _FLIP[op])
        k_node = b if first else a
        k = _exact(k_node)
        if name == "*":
            if k is None:
                return (f"{text} multiplies the output {v} by {to_smv(k_node)}, which is no "
                        "constant: the sign of its factor would be the inputs', and a bound "
                        "reads the output with a constant factor")
            if k == 0:
                return f"{text} multiplies the output {v} by 0: it does not bound {v}"
            return (a if first else b), ir.arith("/", other, k_node), (op if k > 0 else _FLIP[op])
        if name == "/" and first:
            if k is None or k == 0:
                return (f"{text} divides the output {v} by {to_smv(k_node)}, which is no "
                        "constant other than 0: a bound reads the output with a constant "
                        "factor")
            return a, ir.arith("*", other, k_node), (op if k > 0 else _FLIP[op])
        if name == "/":
            return (f"{text} divides by the output {v}: a bound reads the output with a "
                    "constant factor, never as a divisor")
        return (f"{text} applies {name} to the output {v}: a bound reads the output through "
                "+, -, and products and quotients by constants")
    return (f"{text} reads the output {v} inside {to_smv(side)}: a bound reads the output "
            "through +, -, and products and quotients by constants, so that each of its "
            "truth values is a half-line of it")


def bounds_of(formulas: Iterable[Node], inputs: Iterable[str]) -> dict[Node, Bound]:
    """Every bound in ``formulas`` (IR), first-seen order (comparisons that are no bound are
    left out: :func:`classify` says why)."""
    given = frozenset(inputs)
    out: dict[Node, Bound] = {}
    for f in formulas:
        for n in ir.walk(f):
            if n.op == "cmp" and n not in out:
                got = classify(n, given)
                if isinstance(got, Bound):
                    out[n] = got
    return out


def _literals(bounds: Sequence[Bound], constants: Sequence[Node], v: str
              ) -> list[tuple[Node, str, Node, bool]]:
    """The comparisons of ``v``: ``(atom, op, end, is a bound)``, the atom holding exactly
    when ``v op end``."""
    out = [(b.atom, b.op, b.bound, True) for b in bounds if b.output == v]
    for a in constants:
        sc = simple_comparison(a)
        if sc is None or sc[0] != v or sc[1] not in _FLIP:
            continue
        left, right = a.args
        end = right if left.op == "var" else left
        out.append((a, sc[1], end, False))
    return out


def feasibility(bounds: Sequence[Bound], constants: Sequence[Node]) -> tuple[list[Node], Node]:
    """The order comparisons and the controller's invariant of ``bounds`` (module docstring):
    ``constants`` the comparisons of the bounded outputs with constants (``v <= 0.5``; ``=``
    and ``!=`` left out, which a bounded output may not have). Returns ``(order comparisons,
    invariant)``: IR comparisons over the inputs and constants (first-seen order, none
    twice), and a propositional IR formula over the atoms and them."""
    orders: list[Node] = []
    clauses: list[Node] = []
    for v in dict.fromkeys(b.output for b in bounds):
        lits = _literals(bounds, constants, v)
        for i, (a, op_a, end_a, bound_a) in enumerate(lits):
            for b, op_b, end_b, bound_b in lits[i + 1:]:
                if not (bound_a or bound_b):
                    continue  # (two constants: the numeric abstraction's regions)
                for ta in (True, False):
                    for tb in (True, False):
                        oa, ob = (op_a if ta else _NOT[op_a]), (op_b if tb else _NOT[op_b])
                        (down_a, strict_a), (down_b, strict_b) = half_line(oa), half_line(ob)
                        if down_a == down_b:
                            continue  # (two half-lines of one direction always meet)
                        hi, lo = (end_a, end_b) if down_a else (end_b, end_a)
                        cond = _order(lo, hi, strict_a or strict_b)
                        if cond.op == "true":
                            continue
                        for c in ir.walk(cond):
                            if c.op == "cmp" and c not in orders:
                                orders.append(c)
                        pair = ir.and_(a if ta else ir.not_(a), b if tb else ir.not_(b))
                        clauses.append(ir.or_(ir.not_(pair), cond))
    return orders, ir.and_all(*clauses)


def _order(lo: Node, hi: Node, strict: bool) -> Node:
    """``lo < hi`` (``strict``) or ``lo <= hi``, folded to TRUE/FALSE when the two ends are
    one term or both constants (exactly, as the reals read them); ``lo < hi`` is written
    ``!(hi <= lo)``, so that a pair's two orders are one comparison of the game."""
    if lo == hi:
        return ir.FALSE if strict else ir.TRUE
    x, y = _exact(lo), _exact(hi)
    if x is not None and y is not None:
        return ir.const(x < y if strict else x <= y)
    return ir.not_(ir.cmp("<=", hi, lo)) if strict else ir.cmp("<=", lo, hi)
