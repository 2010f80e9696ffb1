"""Propositional abstraction of the numbers in requirement formulas, for ``fretc check``.

Design notes: ARCHITECTURE.md, `check/numeric_abstraction.py`."""

from __future__ import annotations

from collections.abc import Iterable
import math
from fractions import Fraction

from fretc.compiler import ir
from fretc.compiler.ir import Node, name_of
from fretc.compiler.printers import to_smv

__all__ = ["NumericAbstraction", "simple_comparison"]

_FLIP = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "=": "=", "!=": "!="}
_TEST = {"<": lambda v, c: v < c, "<=": lambda v, c: v <= c, ">": lambda v, c: v > c,
         ">=": lambda v, c: v >= c, "=": lambda v, c: v == c, "!=": lambda v, c: v != c}


def _constant(n: Node) -> Fraction | float | None:
    """The value of a constant: exact (a Fraction), or +-inf for a literal past the largest
    float (``1e999`` is inf, as the judge and the monitors read it); None for another node."""
    if n.op == "num":
        try:
            name = name_of(n)
            if math.isinf(float(name)):
                return float(name)
            return Fraction(name)
        except (ValueError, ZeroDivisionError, OverflowError):
            return None
    if n.op == "neg":
        c = _constant(n.args[0])
        return None if c is None else -c
    return None


def simple_comparison(node: Node) -> tuple[str, str, Fraction | float] | None:
    """``(variable, op, constant)`` of a comparison of one variable with a constant, with the
    variable on the left (``3 < x`` gives ``("x", ">", 3)``); None for any other node."""
    if node.op != "cmp":
        return None
    a, b = node.args
    if a.op == "var" and (c := _constant(b)) is not None:
        return name_of(a), name_of(node), c
    if b.op == "var" and (c := _constant(a)) is not None:
        return name_of(b), _FLIP[name_of(node)], c
    return None


def _simple(node: Node) -> tuple[str, str, Fraction | float]:
    """:func:`simple_comparison` of an atom of the abstraction (one by construction)."""
    got = simple_comparison(node)
    assert got is not None
    return got


def _between(a: Fraction | float, b: Fraction | float) -> Fraction | float:
    """A value strictly between the constants ``a < b`` when there is one (either may be
    infinite: ``-inf`` and ``inf`` stand for "no constant below" and "none above"); ``a``
    when ``a == b`` (an infinite constant with nothing beyond it)."""
    if a == b:
        return a
    if math.isinf(a) and math.isinf(b):
        return Fraction(0)
    if math.isinf(b):
        return a + 1
    if math.isinf(a):
        return b - 1
    return (a + b) / 2


class NumericAbstraction:
    """The comparisons of a set of IR formulas and the invariants relating them.

    Build with :meth:`of` (all formulas of the requirement set, so every query sees the same
    atoms). ``atoms[x]`` lists the comparison nodes of variable ``x`` with constants.
    """

    def __init__(self) -> None:
        self.atoms: dict[str, list[Node]] = {}
        self._uninterpreted: dict[str, str] = {}

    @classmethod
    def of(cls, formulas: Iterable[Node]) -> NumericAbstraction:
        """Collect the atoms of ``formulas`` (IR nodes)."""
        self = cls()
        seen = set()
        for f in formulas:
            for n in ir.walk(f):
                if n in seen:
                    continue
                seen.add(n)
                if n.op == "cmp":
                    sc = simple_comparison(n)
                    if sc is not None:
                        lst = self.atoms.setdefault(sc[0], [])
                        if n not in lst:
                            lst.append(n)
                    else:
                        self._uninterpreted.setdefault(
                            to_smv(n), "comparison that is not one variable against a "
                            "constant: an independent proposition")
                elif n.op == "call":
                    self._uninterpreted.setdefault(
                        to_smv(n), "boolean function: an independent proposition")
                elif n.op in ("past", "future"):
                    self._uninterpreted.setdefault(
                        to_smv(n), "temporal function of the other time direction: an "
                        "independent proposition at each tick")
        return self

    def uninterpreted(self) -> list[tuple[str, str]]:
        """``(atom text, why)`` of every atom left uninterpreted, sorted by text."""
        return sorted(self._uninterpreted.items())

    def _regions(self, name: str, doubles: bool = False, integer: bool = False
                 ) -> list[tuple[Fraction | float, tuple[bool, ...]]]:
        """``(representative value, truth of each atom)`` per region, distinct truths only.
        ``doubles``: the values are IEEE doubles and each constant the double nearest it, as
        the monitors and the shield compute (``y > 0.1 & y < 0.10000000000000001`` has a
        real between its constants, no double: the two literals are one double); a region
        is kept when a double lies in it (each constant, the double just above it when it
        is below the next constant, the double just below the first). ``integer``: the
        variable takes whole numbers only, and a region is kept when one lies in it
        (``x > 1 & x < 2`` has none): the truths of the comparisons change only at the
        constants, so ``ceil(c) - 1``, ``floor(c)`` and ``floor(c) + 1`` of each constant
        ``c`` (the whole numbers just below it, at or below it, just above it) meet every
        region a whole number can be in."""
        atoms = self.atoms[name]
        points: list[Fraction | float]
        if integer:
            ends = sorted({float(_simple(a)[2]) if doubles else _simple(a)[2] for a in atoms})
            whole = sorted({w for c in ends if not math.isinf(c)
                            for w in (math.ceil(c) - 1, math.floor(c), math.floor(c) + 1)
                            }) or [0]
            points = [float(w) if doubles else Fraction(w) for w in whole]
        elif doubles:
            fc = sorted({float(_simple(a)[2]) for a in atoms})
            points = [math.nextafter(fc[0], -math.inf)] if fc[0] > -math.inf else []
            for i, d in enumerate(fc):
                points.append(d)
                up = math.nextafter(d, math.inf)
                if d < math.inf and (i + 1 == len(fc) or up < fc[i + 1]):
                    points.append(up)
        else:
            consts = sorted({_simple(a)[2] for a in atoms})
            points = [_between(-math.inf, consts[0])]
            for i, c in enumerate(consts):
                points.append(c)
                points.append(_between(c, consts[i + 1] if i + 1 < len(consts) else math.inf))
        out, seen = [], set()
        for v in points:
            truth = tuple(_TEST[_simple(a)[1]](v, float(_simple(a)[2]) if doubles
                                               else _simple(a)[2])
                          for a in atoms)
            if truth not in seen:
                seen.add(truth)
                out.append((v, truth))
        return out

    def invariant(self, formulas: Iterable[Node]) -> Node:
        """``G`` of the region disjunction for every variable compared with a constant in
        ``formulas`` (TRUE when none or when its comparisons are independent anyway)."""
        names = []
        for f in formulas:
            for n in ir.walk(f):
                if n.op == "cmp":
                    sc = simple_comparison(n)
                    if sc is not None and sc[0] not in names and sc[0] in self.atoms:
                        names.append(sc[0])
        out = ir.TRUE
        for name in sorted(names):
            out = ir.and_(out, self.variable_invariant(name))
        return out

    def variable_invariant(self, name: str) -> Node:
        """The invariant of one variable (TRUE when it has a single comparison): ``G`` of
        :meth:`region`."""
        disj = self.region(name)
        return disj if disj.op == "true" else ir.G(disj)

    def region(self, name: str, doubles: bool = False, integer: bool = False) -> Node:
        """The truth values of one variable's comparisons that one real value (``doubles``:
        one double; ``integer``: one whole number; :meth:`_regions`) gives, as a
        propositional disjunction over them (TRUE when every combination is possible)."""
        atoms = self.atoms.get(name, [])
        if not atoms or (len(atoms) < 2 and not doubles and not integer):
            return ir.TRUE
        regions = self._regions(name, doubles, integer)
        if len(regions) == 2 ** len(atoms):
            return ir.TRUE
        disj = ir.FALSE
        for _v, truth in regions:
            disj = ir.or_(disj, ir.and_all(*(a if t else ir.not_(a)
                                             for a, t in zip(atoms, truth))))
        return disj

    def regions(self, names: Iterable[str], doubles: bool = False,
                integers: Iterable[str] = ()) -> Node:
        """The conjunction of :meth:`region` over ``names`` (a propositional formula that
        holds at every tick: the game's and the monitors' consistency of numbers), those in
        ``integers`` taking whole numbers only."""
        whole = frozenset(integers)
        return ir.and_all(*(self.region(v, doubles, v in whole) for v in names))

    def values(self, truth: dict[Node, bool]) -> dict[str, float]:
        """A value per compared variable giving the comparisons the truth values ``truth``
        (atom node -> bool; atoms missing from ``truth`` are free). A combination no real
        value gives (impossible under the invariant) takes the first region."""
        out: dict[str, float] = {}
        for name in self.atoms:
            atoms = self.atoms[name]
            regions = self._regions(name)
            pick = regions[0][0]
            for v, t in regions:
                if all(truth.get(a, tv) == tv for a, tv in zip(atoms, t)):
                    pick = v
                    break
            out[name] = float(pick)
        return out
