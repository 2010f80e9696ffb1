"""FRET's probabilistic form of a requirement: where FRET 3.1 puts the bounds, around fretc's
own (FRET-exact) infinite-trace formula.

Design notes: ARCHITECTURE.md, `compiler/pctl.py`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from fretc.compiler import ir
from fretc.compiler.ir import Node, name_of
from fretc.compiler.printers import mangle, to_smv
from fretc.compiler.semantics import marked_ft_inf

if TYPE_CHECKING:
    from fretc.fretish import ast as A
    from fractions import Fraction

__all__ = ["Pctl", "pctl_of", "pctl_key", "prism_text", "PrismUnsupported", "strip_bounds",
           "bound_structure",
           "prism_property", "ALMOST_SURE", "PROBABILITY_KEYS"]

#: the probability field of FRET's five-part keys
PROBABILITY_KEYS = ("bound", "null")
#: the bound of the ``null`` probability, and of the whole around the per-trigger bounds
ALMOST_SURE = ">=1"


def pctl_key(key: str, bounded: bool) -> str:
    """FRET's five-part key ``scope,condition,probability,timing,response`` of a four-part
    template key ``scope,condition,timing,response`` (``probability``: ``bound`` for a
    requirement with a probability bound, else ``null``)."""
    scope, cond, timing, response = key.split(",")
    return ",".join((scope, cond, "bound" if bounded else "null", timing, response))


@dataclass(frozen=True)
class Pctl:
    """The probabilistic form of one requirement.

    Attributes:
        key: FRET's five-part key (:func:`pctl_key`).
        tree: the formula with its bounds: ``P`` nodes (``name`` = the bound, e.g.
            ``">=0.9"``) around each occurrence of the timing's obligation, and around the
            whole (``>=1``) unless scope and condition are both ``null``.
        bound: the requirement's :class:`fretc.compiler.ir.ProbabilityBound`, or None (the
            ``null`` probability: every bound ``>=1``).
    """

    key: str
    tree: Node
    bound: object = None

    @property
    def text(self) -> str:
        """The formula in PRISM's syntax (:func:`prism_text`)."""
        return prism_text(self.tree)

    @property
    def path(self) -> Node:
        """The formula with its bounds removed: ft_inf (:func:`strip_bounds`)."""
        return strip_bounds(self.tree)

    @property
    def bounds(self) -> list[dict]:
        """Where the bounds sit (:func:`bound_structure`)."""
        return bound_structure(self.tree)


def pctl_of(req: A.Requirement, tick_period: Fraction | None = None) -> Pctl:
    """The :class:`Pctl` of a parsed requirement (not free-form) with the tick period
    ``tick_period`` (seconds, or None as :func:`fretc.compiler.semantics.formalize`).
    Raises :class:`fretc.compiler.expressions.SemanticsError` as ``formalize`` does."""
    b = ir.probability_bound(req.probability)
    name = ALMOST_SURE if b is None else f"{b.op}{b.text}"
    tree = marked_ft_inf(req, tick_period, lambda t: Node("P", (t,), name=name))
    if (req.scope.kind, req.condition.kind) != ("null", "null"):
        tree = Node("P", (tree,), name=ALMOST_SURE)
    assert req.key is not None  # (formalize refused a free-form requirement)
    return Pctl(pctl_key(req.key, b is not None), tree, b)


def strip_bounds(n: Node) -> Node:
    """``n`` without its ``P`` nodes, rebuilt by the IR's simplifying constructors
    (:func:`fretc.compiler.ir.rebuild`): for a :class:`Pctl` tree, exactly the ft_inf
    formula of the requirement."""
    memo: dict = {}

    def go(x: Node) -> Node:
        got = memo.get(id(x))
        if got is not None:
            return got
        if x.op == "P":
            out = go(x.args[0])
        elif not x.args or x.op in _ATOMS:
            out = x
        else:
            out = ir.rebuild(x, tuple(go(a) for a in x.args))
        memo[id(x)] = out
        return out

    return go(n)


#: IR nodes printed whole, never entered (terms and derived atoms)
_ATOMS = ("cmp", "call", "fn", "pre", "past", "future", "arith", "neg", "ite", "var", "num")
#: the temporal operators a bound's place is described by, as PRISM names them
_TEMPORAL = {"X": "X", "F": "F", "G": "G", "U": "U", "V": "R"}


def bound_structure(tree: Node) -> list[dict]:
    """The bounds of a :class:`Pctl` tree in pre-order: per bound ``{"bound": "P>=0.9",
    "parent": index of the enclosing bound or None, "under": [...]}``, ``under`` the
    temporal operators between the enclosing bound (or the root) and this one, outermost
    first (``X``, ``F``, ``G``; ``U.1``/``U.2``, ``R.1``/``R.2`` with the operand taken)."""
    out: list[dict] = []

    def go(x: Node, parent, under: tuple) -> None:
        if x.op == "P":
            out.append({"bound": f"P{x.name}", "parent": parent, "under": list(under)})
            here = len(out) - 1
            go(x.args[0], here, ())
            return
        if x.op in _ATOMS:
            return
        t = _TEMPORAL.get(x.op)
        for i, a in enumerate(x.args):
            if t is None:
                go(a, parent, under)
            else:
                go(a, parent, under + ((t if len(x.args) == 1 else f"{t}.{i + 1}"),))

    go(tree, None, ())
    return out


# --------------------------------------------------------------------------- PRISM's syntax
_PRISM_BIN = {"&": "&", "|": "|", "->": "=>", "<->": "<=>", "U": "U", "V": "R"}


def prism_text(n: Node) -> str:
    """A formula of the IR (future time, with ``P`` bound nodes) in PRISM's property syntax,
    every binary operation and every bound inside the formula in parentheses as FRET
    prints them: ``! & | => <=>``, ``X F G U R``,
    bounded ``F<=k`` (``F[l,h]`` for a lower bound above 0), ``true``/``false``, names
    mangled as FRET does, ``P>=0.9 [ ... ]``. ``xor`` is written with ``&``, ``|`` and
    ``!``; ``mod`` and ``^`` as PRISM's ``mod(a, b)`` and ``pow(a, b)``; FRETish's
    ``absReal``/``absInt`` as ``max(x, -x)``, ``minReal``/``minInt`` and ``maxReal``/
    ``maxInt`` as PRISM's ``min`` and ``max`` (PRISM manual, "Expressions": its built-in
    functions).

    Raises:
        PrismUnsupported: something PRISM's properties cannot say: a past-time operator or
            function (``persisted``, ``occurred``, ``preBool``...: PCTL has no past), or a
            function PRISM has not (an uninterpreted one, ``det_3x3(a,b,c)``)."""
    memo: dict = {}

    def go(x: Node) -> str:
        s = memo.get(id(x))
        if s is None:
            s = memo[id(x)] = _prism(x, go)
        return s

    text = go(n)
    return text[1:-1] if n.op == "P" else text


def _bounds(x: Node) -> str:
    if x.hi is None:
        return ""
    return f"<={x.hi}" if not x.lo else f"[{x.lo},{x.hi}]"


def _prism(x: Node, go) -> str:
    op, a = x.op, x.args
    if op in ("true", "false"):
        return op
    if op in ("ap", "var"):
        return mangle(x.name)
    if op == "num":
        return name_of(x)
    if op == "P":  # parenthesized inside a formula, as FRET does (prism_text: not at the top)
        return f"(P{x.name} [ {go(a[0])} ])"
    if op == "!":
        return f"(! {go(a[0])})"
    if op in _PRISM_BIN:
        return f"({go(a[0])} {_PRISM_BIN[op]} {go(a[1])})"
    if op == "xor":
        p, q = go(a[0]), go(a[1])
        return f"(({p} & (! {q})) | ((! {p}) & {q}))"
    if op in ("X", "F", "G"):
        return f"({op}{_bounds(x)} {go(a[0])})"
    if op == "cmp":
        return f"({go(a[0])} {x.name} {go(a[1])})"
    if op == "arith":
        if x.name in ("mod", "^"):
            return f"{'mod' if x.name == 'mod' else 'pow'}({go(a[0])}, {go(a[1])})"
        return f"({go(a[0])} {x.name} {go(a[1])})"
    if op == "neg":
        return f"(- {go(a[0])})"
    fn = _PRISM_FN.get(x.name or "") if op == "fn" else None
    if fn is not None and len(a) == fn[1]:
        return fn[0].format(*(go(y) for y in a))
    what = (f"the past-time function {x.name}" if op == "past" and x.name else
            f"the comparison {to_smv(a[0])}, which reads a previous tick's value,"
            if op == "past" else
            f"the function {x.name}()" if op == "fn" else f"the past-time operator {op}"
            if op in _PAST else f"{to_smv(x)}")
    raise PrismUnsupported(f"{what} has no form in PRISM's properties (PCTL has no past, "
                           "and PRISM no functions but its built-in ones)")


#: FRETish functions PRISM's built-in functions give: name -> (PRISM text of the arguments'
#: texts, number of arguments)
_PRISM_FN = {"absReal": ("max({0}, (- {0}))", 1), "absInt": ("max({0}, (- {0}))", 1),
             "minReal": ("min({0}, {1})", 2), "minInt": ("min({0}, {1})", 2),
             "maxReal": ("max({0}, {1})", 2), "maxInt": ("max({0}, {1})", 2)}
_PAST = ("Y", "Z", "H", "O", "S", "T", "FTP", "past")


class PrismUnsupported(ValueError):
    """A formula PRISM's property syntax cannot express (:func:`prism_text`)."""


def prism_property(pctl: Pctl, name: str) -> str:
    """One property of a PRISM properties file: ``"name": formula;`` (PRISM's named
    properties), the formula :attr:`Pctl.text` with its ``=`` and ``!=`` bounds written
    in PRISM's bounds (``P=p [ f ]`` as ``(P>=p [ f ] & P<=p [ f ])``, ``P!=p [ f ]`` as
    ``(P<p [ f ] | P>p [ f ])``; at p = 0 or 1 the one bound that says it)."""
    return f'"{name}": {prism_text(_prism_bounds(pctl.tree))};'


def _prism_bounds(n: Node) -> Node:
    """``n`` with ``=``/``!=`` bounds written as PRISM's (:func:`prism_property`)."""
    args = tuple(_prism_bounds(a) for a in n.args)
    if n.op != "P" or not name_of(n).startswith(("=", "!=")):
        return n if args == n.args else Node(n.op, args, n.name, n.lo, n.hi)
    eq = name_of(n).startswith("=")
    text = name_of(n)[1:] if eq else name_of(n)[2:]
    p = float(text)

    def b(op: str) -> Node:
        return Node("P", args, name=op + text)

    if eq:
        return b(">=") if p == 1 else b("<=") if p == 0 else Node("&", (b(">="), b("<=")))
    return b("<") if p == 1 else b(">") if p == 0 else Node("|", (b("<"), b(">")))
