"""Comparisons of several variables (``x < y``, ``a + b > c``, ``state = ap_standby_state``)
decided by z3: which truth values of linked comparisons real numbers realize.

Design notes: ARCHITECTURE.md, `check/predicates.py`."""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

from fretc.check.numeric_abstraction import simple_comparison
from fretc.compiler import ir
from fretc.compiler.ir import Node
from fretc.compiler.printers import to_smv

__all__ = ["Cluster", "PredicateBudget", "NoWitness", "MAX_VALUATIONS", "FUNCTIONS", "is_predicate",
           "undecidable", "comparisons", "clusters", "mixed_invariants"]

#: the most valuations (realizable plus excluded by a core) z3 is asked about per cluster
MAX_VALUATIONS = 4096
#: z3's deterministic resource limit per query (never seconds: same input, same answer); a
#: query past it makes the cluster undecided (:class:`PredicateBudget`)
RLIMIT = 5_000_000
#: the functions a comparison may apply, with their arity (FRET's names)
FUNCTIONS = {"absReal": 1, "absInt": 1, "minReal": 2, "minInt": 2, "maxReal": 2, "maxInt": 2}
_ARITH = ("+", "-", "*", "/")

#: called with (cluster, z3 model, z3 reals by variable, the valuation) for each realizable
#: valuation found; returns what :attr:`Cluster.witnesses` keeps for it
Witness = Callable[["Cluster", Any, dict[str, Any], tuple[bool, ...]], Any]


class NoWitness(Exception):
    """Raised by a :data:`Witness` whose caller cannot use z3's model of a realizable
    valuation (the shield: its numbers do not give the valuation in double arithmetic):
    the valuation is left out of the invariant as if no numbers realized it, and listed in
    :attr:`Cluster.unwitnessed` with the message."""


class PredicateBudget(Exception):
    """A cluster with more valuations than :data:`MAX_VALUATIONS` to decide, or a query z3
    did not answer within :data:`RLIMIT`."""


def _solver(ctx: Any) -> Any:
    import z3

    s = z3.Solver(ctx=ctx)
    s.set("rlimit", RLIMIT)
    return s


def _context() -> Any:
    """A new z3 context for one cluster's queries: its models and unsat cores (the numbers
    the shield writes, the lemmas of the invariant) depend on the cluster alone, not on what
    the process asked z3 before (z3's terms and caches live in their context)."""
    import z3

    return z3.Context()


def _undecided(c: Cluster, solver: Any) -> PredicateBudget:
    return PredicateBudget(f"z3 did not decide the comparisons "
                           f"{', '.join(to_smv(a) for a in c.atoms)} "
                           f"({solver.reason_unknown()})")


def is_predicate(node: Node) -> bool:
    """Is ``node`` a comparison the numeric abstraction leaves free (not a boolean variable,
    not one variable against a constant)?"""
    return node.op == "cmp" and simple_comparison(node) is None


def undecidable(node: Node, streams: Collection[str] = ()) -> str | None:
    """Why the truth values of the comparison ``node`` cannot be decided tick by tick from
    that tick's numbers, or None when they can. ``streams``: FRET's stream variables
    (:mod:`fretc.check.streams`), whose values come from earlier ticks as a previous
    value's do."""
    for n in ir.walk(node):
        if n.op == "var" and ir.name_of(n) in streams:
            return (f"{to_smv(node)} reads the stream variable {ir.name_of(n)} (FRET's "
                    "definition through pre): which truth values it can take depends on the "
                    "ticks before")
        if n.op == "pre":
            return (f"{to_smv(node)} reads the previous value of a number ({to_smv(n)}): "
                    "which truth values it can take depends on the tick before")
        if n.op == "fn" and FUNCTIONS.get(ir.name_of(n)) != len(n.args):
            return f"{to_smv(node)} applies {to_smv(n)}, a function z3 is not given"
        if n.op not in ("cmp", "var", "num", "neg", "arith", "fn"):
            return f"{to_smv(node)} has {to_smv(n)}, a term z3 is not given"
        if n.op == "arith" and ir.name_of(n) not in _ARITH:
            return f"{to_smv(node)} has the operator {ir.name_of(n)}, which z3 is not given"
    return None


@dataclass
class Cluster:
    """Numeric atoms linked by their variables, at least one a predicate: ``atoms`` (IR
    comparisons, first-seen order), ``variables`` the FRET variables they read, ``is_input``
    the environment's (every variable an input), ``invariant`` the valuations real numbers
    realize (propositional IR over ``atoms``), ``witnesses`` realizable valuation (a bool
    per atom) -> what the caller's :data:`Witness` made of z3's model (None without one)."""

    atoms: list[Node]
    variables: list[str]
    is_input: bool
    invariant: Node = ir.TRUE
    witnesses: dict[tuple[bool, ...], Any] = field(default_factory=dict)
    #: realizable valuations the witness could not use (:class:`NoWitness`) -> why
    unwitnessed: dict[tuple[bool, ...], str] = field(default_factory=dict)


def comparisons(formulas: Sequence[Node]) -> list[Node]:
    """Every comparison node of ``formulas``, first-seen order, without repeats."""
    out: list[Node] = []
    seen: set[Node] = set()
    for f in formulas:
        for n in ir.walk(f):
            if n.op == "cmp" and n not in seen:
                seen.add(n)
                out.append(n)
    return out


def clusters(formulas: Sequence[Node], inputs: Sequence[str],
             witness: Witness | None = None,
             undecided: list[tuple[Cluster, str]] | None = None,
             streams: Collection[str] = ()) -> list[Cluster]:
    """The clusters of the comparisons of ``formulas`` (module docstring), each decided by
    z3; ``witness`` turns the model of each realizable valuation into what the cluster keeps.
    With ``undecided`` (a list), a cluster holding a predicate :func:`undecidable` refuses is
    appended to it with the reason, undecided (its invariant TRUE), instead of raising.
    ``streams`` as :func:`undecidable` takes them.

    Raises:
        PredicateBudget: a cluster past :data:`MAX_VALUATIONS`.
        ValueError: without ``undecided``, a predicate :func:`undecidable` refuses (its
            message)."""
    numeric = comparisons(formulas)
    if undecided is None:
        for n in numeric:
            if is_predicate(n) and (why := undecidable(n, streams)) is not None:
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
        first = next((ir.name_of(x) for x in ir.walk(n) if x.op == "var"), None)
        if first is not None:
            groups.setdefault(find(first), []).append(n)
    out = []
    for atoms in groups.values():
        if not any(is_predicate(a) for a in atoms):
            continue
        names = list(dict.fromkeys(ir.name_of(x) for a in atoms for x in ir.walk(a)
                                   if x.op == "var"))
        c = Cluster(atoms, names, all(v in inputs for v in names))
        why = next((w for a in atoms if is_predicate(a) and (w := undecidable(a, streams))),
                   None)
        if why is not None and undecided is not None:
            undecided.append((c, why))
            continue
        _decide(c, witness)
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
        ctx = next(iter(reals.values())).ctx  # (a cluster reads at least one variable)
        return z3.RealVal(str(Fraction(ir.name_of(n))), ctx)
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


def _decide(c: Cluster, witness: Witness | None) -> None:
    """Fill ``c.invariant`` and ``c.witnesses`` (module docstring)."""
    import z3

    ctx = _context()
    reals = {v: z3.Real(v, ctx) for v in c.variables}
    bs = [z3.Bool(f"p{k}", ctx) for k in range(len(c.atoms))]
    theory = _solver(ctx)
    for b, a in zip(bs, c.atoms):
        theory.add(b == _z3(a, reals))
    search = z3.Solver(ctx=ctx)  # (propositional: no limit needed)
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
        answer = theory.check(*lits)
        if answer == z3.unknown:
            raise _undecided(c, theory)
        if answer == z3.sat:
            search.add(z3.Not(z3.And(*lits)))
            try:
                c.witnesses[values] = (witness(c, theory.model(), reals, values)
                                       if witness is not None else None)
            except NoWitness as exc:
                c.unwitnessed[values] = str(exc)
                lemmas.append(ir.not_(ir.and_all(*(a if v else ir.not_(a)
                                                   for a, v in zip(c.atoms, values)))))
            continue
        core = {str(x) for x in theory.unsat_core()}
        picked = [(k, v) for k, (lit, v) in enumerate(zip(lits, values)) if str(lit) in core]
        search.add(z3.Not(z3.And(*(lits[k] for k, _v in picked))))
        lemmas.append(ir.not_(ir.and_all(*(c.atoms[k] if v else ir.not_(c.atoms[k])
                                             for k, v in picked))))
    c.invariant = ir.and_all(*lemmas)


def mixed_invariants(c: Cluster, inputs: Sequence[str]) -> tuple[Node, Node]:
    """A cluster of inputs and outputs (``x > a``, ``a`` an input) for a game whose
    controller sees only the truth values of the comparisons: ``(environment's invariant,
    controller's invariant)``, propositional over ``c.atoms``.

    The environment gives its comparisons (those reading inputs only) the valuations input
    numbers realize. Given those truth values, the controller may give its comparisons (the
    others) a valuation only when *every* input numbers with those truth values leave output
    numbers that realize it (z3: ``forall inputs. in-valuation -> exists outputs.
    valuation``; an answer z3 does not give counts as no). A controller winning with that
    invariant has numbers for its choices whatever the inputs' numbers: its realizable
    answer is sound; an unrealizable one is not (the real controller sees the numbers).

    Raises:
        PredicateBudget: more than :data:`MAX_VALUATIONS` valuations to ask about."""
    import itertools

    import z3

    ins = [a for a in c.atoms if all(ir.name_of(x) in inputs for x in ir.walk(a)
                                     if x.op == "var")]
    outs = [a for a in c.atoms if a not in ins]
    if 2 ** (len(ins) + len(outs)) > MAX_VALUATIONS:
        raise PredicateBudget(
            f"the comparisons {', '.join(to_smv(a) for a in c.atoms)} have more than "
            f"{MAX_VALUATIONS} valuations to decide")
    out_vars = [v for v in c.variables if v not in inputs]
    ctx = _context()
    reals = {v: z3.Real(v, ctx) for v in c.variables}
    in_z3 = [_z3(a, reals) for a in ins]
    out_z3 = [_z3(a, reals) for a in outs]
    env: list[Node] = []
    ctl: list[Node] = []
    for iv in itertools.product((False, True), repeat=len(ins)):
        given = z3.And(*[x if v else z3.Not(x) for x, v in zip(in_z3, iv)],
                       z3.BoolVal(True, ctx))
        iota = ir.and_all(*(a if v else ir.not_(a) for a, v in zip(ins, iv)))
        s = _solver(ctx)
        s.add(given)
        answer = s.check()
        if answer == z3.unknown:
            raise _undecided(c, s)
        if answer == z3.unsat:  # (no input numbers give it: the environment's lemma)
            env.append(ir.not_(iota))
            continue
        allowed = []
        for ov in itertools.product((False, True), repeat=len(outs)):
            want = z3.And(*[x if v else z3.Not(x) for x, v in zip(out_z3, ov)],
                          z3.BoolVal(True, ctx))
            bad = _solver(ctx)
            body = z3.Exists([reals[v] for v in out_vars], want) if out_vars else want
            bad.add(given, z3.Not(body))
            if bad.check() == z3.unsat:
                allowed.append(ir.and_all(*(a if v else ir.not_(a) for a, v in zip(outs, ov))))
        ctl.append(ir.implies(iota, ir.or_all(*allowed) if allowed else ir.FALSE))
    return ir.and_all(*env), ir.and_all(*ctl)
