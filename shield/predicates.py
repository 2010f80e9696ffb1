"""Comparisons of several variables in the shield (``x < y``, ``a + b > c``, ``state =
ap_standby_state``): predicates of the safety game, kept consistent by z3.

``fretc check`` reads such a comparison as an independent proposition
(:mod:`fretc.check.numeric_abstraction`: the controller's when it reads an output). The shield
takes the same atoms as propositions of its game (:mod:`fretc.shield.synthesis`: each is a
boolean atom of the game under a name of its own, :func:`substitute`), and adds what the
shield needs and ``check`` does not: the shield *chooses* them, so it must never choose truth
values no numbers give. Per **cluster** (the comparisons linked by the numeric variables they
share, comparisons of one variable with a constant included), z3 decides which valuations
of the cluster's atoms real numbers realize (the variables read as reals, as the numeric
abstraction reads them), by lazy enumeration with unsat cores (the lemmas of DPLL(T),
Nieuwenhuis, Oliveras, Tinelli, JACM 53, 2006): a propositional search proposes a valuation,
z3 decides it in linear real arithmetic; a realizable one is recorded with z3's numbers, an
unrealizable one is excluded with its unsat core. The invariant (conjunction of the cores'
negations) is exact: every valuation it allows was found realizable. It joins the game's
``ctl_inv`` (outputs) or ``env_inv`` (inputs).

An output cluster's recorded numbers are what the shield outputs for the cluster's
variables when it changes the truth of one of its atoms (the proposal's numbers give the
proposed truths, not the corrected ones). Refused (:class:`fretc.shield.plan.ShieldError`):
a comparison that reads both an input and an output (which truths the shield can give
depends on the input's number, which the game does not see), a past value of a number
(``preReal``: the game keeps no number from one tick to the next), a function other than
``absReal/absInt/minReal/minInt/maxReal/maxInt``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

from fretc.check.numeric_abstraction import simple_comparison
from fretc.compiler import ir
from fretc.compiler.ir import Node
from fretc.compiler.printers import to_smv
from fretc.shield.runtime import term_value

__all__ = ["Cluster", "PredicateBudget", "MAX_VALUATIONS", "is_predicate", "refusal",
           "clusters", "substitute", "term", "PREFIX"]

#: the most valuations (realizable plus excluded by a core) z3 is asked about per cluster
MAX_VALUATIONS = 4096
#: the game's name of predicate ``k``: ``PREFIX + str(k)`` (no FRET variable starts so)
PREFIX = "__shield_predicate_"
_FUNCS = {"absReal": 1, "absInt": 1, "minReal": 2, "minInt": 2, "maxReal": 2, "maxInt": 2}
_ARITH = ("+", "-", "*", "/")


class PredicateBudget(Exception):
    """A cluster with more valuations than :data:`MAX_VALUATIONS` to decide (no shield: an
    unknown answer, as a game past its budget)."""


def is_predicate(node: Node) -> bool:
    """Is ``node`` a comparison the game takes only as a predicate (not a boolean variable,
    not one variable against a constant)?"""
    return node.op == "cmp" and simple_comparison(node) is None


def refusal(node: Node, inputs: Sequence[str]) -> str | None:
    """Why the predicate ``node`` cannot be a shield's atom (module docstring), or None."""
    for n in ir.walk(node):
        if n.op == "pre":
            return (f"{to_smv(node)} reads the previous value of a number ({to_smv(n)}): the "
                    "shield's game keeps no number from one tick to the next")
        if n.op == "fn" and _FUNCS.get(ir.name_of(n)) != len(n.args):
            return f"{to_smv(node)} applies {to_smv(n)}, a function the shield does not evaluate"
        if n.op not in ("cmp", "var", "num", "neg", "arith", "fn"):
            return f"{to_smv(node)} has {to_smv(n)}, a term the shield does not evaluate"
        if n.op == "arith" and ir.name_of(n) not in _ARITH:
            return f"{to_smv(node)} has the operator {ir.name_of(n)}, which the shield does not evaluate"
    names = {ir.name_of(n) for n in ir.walk(node) if n.op == "var"}
    ins = sorted(v for v in names if v in inputs)
    if ins and len(ins) < len(names):
        return (f"{to_smv(node)} compares the input(s) {', '.join(ins)} with the output(s) "
                f"{', '.join(sorted(names - set(ins)))}: which truth values the shield can "
                "give it depends on the inputs' numbers, which its game does not see")
    return None


def term(n: Node) -> tuple[Any, ...]:
    """The comparison or term ``n`` as a nested tuple the runtimes evaluate
    (:func:`fretc.shield.runtime.term_value`): ``("cmp", op, a, b)``, ``("var", name)``, ``("num", float)``,
    ``("neg", a)``, ``(op, a, b)`` for ``+ - * /``, ``("fn", name, a[, b])``."""
    if n.op == "cmp":
        return ("cmp", ir.name_of(n), term(n.args[0]), term(n.args[1]))
    if n.op == "var":
        return ("var", ir.name_of(n))
    if n.op == "num":
        return ("num", float(ir.name_of(n)))
    if n.op == "neg":
        return ("neg", term(n.args[0]))
    if n.op == "arith":
        return (ir.name_of(n), term(n.args[0]), term(n.args[1]))
    if n.op == "fn":
        return ("fn", ir.name_of(n), *(term(a) for a in n.args))
    raise ValueError(f"not a shield term: {to_smv(n)}")


@dataclass
class Cluster:
    """Numeric atoms linked by their variables, at least one a predicate: ``atoms`` (IR
    comparisons, first-seen order), ``variables`` the FRET variables they read, ``is_input``
    the environment's (every variable an input), ``invariant`` the valuations real numbers
    realize (propositional IR over ``atoms``), ``witnesses`` realizable valuation (a bool
    per atom) -> numbers of ``variables`` realizing it (doubles, checked)."""

    atoms: list[Node]
    variables: list[str]
    is_input: bool
    invariant: Node = ir.TRUE
    witnesses: dict[tuple[bool, ...], dict[str, float]] = field(default_factory=dict)


def clusters(pts: Sequence[Node], inputs: Sequence[str]) -> list[Cluster]:
    """The clusters of the atoms of ``pts`` (module docstring), each decided by z3.

    Raises:
        PredicateBudget: a cluster past :data:`MAX_VALUATIONS`.
        ValueError: a predicate :func:`refusal` refuses (its message)."""
    numeric: list[Node] = []
    for f in pts:
        for n in ir.walk(f):
            if n.op == "cmp" and n not in numeric:
                numeric.append(n)
    for n in numeric:
        if is_predicate(n) and (why := refusal(n, inputs)) is not None:
            raise ValueError(why)
    parent: dict[str, str] = {}

    def find(v: str) -> str:
        while parent.setdefault(v, v) != v:
            v = parent[v]
        return v

    for n in numeric:
        names = [ir.name_of(x) for x in ir.walk(n) if x.op == "var"]
        for v in names[1:]:
            a, b = find(names[0]), find(v)
            if a != b:
                parent[max(a, b)] = min(a, b)
    groups: dict[str, list[Node]] = {}
    for n in numeric:
        first = next(ir.name_of(x) for x in ir.walk(n) if x.op == "var")
        groups.setdefault(find(first), []).append(n)
    out = []
    for atoms in groups.values():
        if not any(is_predicate(a) for a in atoms):
            continue
        names = list(dict.fromkeys(ir.name_of(x) for a in atoms for x in ir.walk(a)
                                   if x.op == "var"))
        c = Cluster(atoms, names, all(v in inputs for v in names))
        _decide(c)
        out.append(c)
    return out


def _z3(n: Node, reals: dict[str, Any]) -> Any:
    import z3

    if n.op == "cmp":
        a, b = _z3(n.args[0], reals), _z3(n.args[1], reals)
        op = ir.name_of(n)
        return {"<": a < b, "<=": a <= b, ">": a > b, ">=": a >= b, "=": a == b,
                "!=": a != b}[op]
    if n.op == "var":
        return reals[ir.name_of(n)]
    if n.op == "num":
        return z3.RealVal(str(Fraction(ir.name_of(n))))
    if n.op == "neg":
        return -_z3(n.args[0], reals)
    if n.op == "fn":
        xs = [_z3(a, reals) for a in n.args]
        name = ir.name_of(n)
        if name.startswith("abs"):
            return z3.If(xs[0] >= 0, xs[0], -xs[0])
        if name.startswith("min"):
            return z3.If(xs[0] <= xs[1], xs[0], xs[1])
        return z3.If(xs[0] >= xs[1], xs[0], xs[1])
    a, b = _z3(n.args[0], reals), _z3(n.args[1], reals)
    op = ir.name_of(n)
    return a + b if op == "+" else a - b if op == "-" else a * b if op == "*" else a / b


def _decide(c: Cluster) -> None:
    """Fill ``c.invariant`` and ``c.witnesses`` (module docstring)."""
    import z3

    reals = {v: z3.Real(v) for v in c.variables}
    bs = [z3.Bool(f"p{k}") for k in range(len(c.atoms))]
    theory = z3.Solver()
    for b, a in zip(bs, c.atoms):
        theory.add(b == _z3(a, reals))
    search = z3.Solver()
    lemmas: list[Node] = []
    asked = 0
    while search.check() == z3.sat:
        asked += 1
        if asked > MAX_VALUATIONS:
            raise PredicateBudget(
                f"the comparisons {', '.join(to_smv(a) for a in c.atoms)} have more than "
                f"{MAX_VALUATIONS} valuations to decide")
        model = search.model()
        values = tuple(z3.is_true(model.eval(b, model_completion=True)) for b in bs)
        lits = [b if v else z3.Not(b) for b, v in zip(bs, values)]
        if theory.check(*lits) == z3.sat:
            c.witnesses[values] = _numbers(c, theory.model(), reals, values)
            search.add(z3.Not(z3.And(*lits)))
            continue
        core = {str(x) for x in theory.unsat_core()}
        picked = [(k, v) for k, (lit, v) in enumerate(zip(lits, values)) if str(lit) in core]
        search.add(z3.Not(z3.And(*(lits[k] for k, _v in picked))))
        lemmas.append(ir.not_(ir.and_all(*(c.atoms[k] if v else ir.not_(c.atoms[k])
                                             for k, v in picked))))
    c.invariant = ir.and_all(*lemmas)


def _numbers(c: Cluster, model: Any, reals: dict[str, Any],
             values: tuple[bool, ...]) -> dict[str, float]:
    """z3's numbers as doubles, checked to give the atoms ``values`` in double arithmetic.

    Raises RuntimeError when rounding to doubles changes a truth value (never silently)."""
    import z3

    out = {}
    for v in c.variables:
        x = model.eval(reals[v], model_completion=True)
        out[v] = float(Fraction(x.as_fraction())) if z3.is_rational_value(x) else float(
            x.approx(20).as_fraction())
    for a, want in zip(c.atoms, values):
        if term_value(term(a), out) != want:
            raise RuntimeError(f"z3's numbers {out} for {to_smv(a)} = {want} do not hold "
                               "in doubles")
    return out


def substitute(n: Node, names: dict[Node, Node]) -> Node:
    """``n`` with each predicate in ``names`` replaced by its game atom (a boolean ``ap``)."""
    got = names.get(n)
    if got is not None:
        return got
    if not n.args or n.op in ("cmp", "var", "num", "arith", "fn", "neg", "pre"):
        return n
    return ir.rebuild(n, tuple(substitute(a, names) for a in n.args))
