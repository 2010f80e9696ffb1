"""Comparisons of several variables in the shield (``x < y``, ``a + b > c``, ``state =
ap_standby_state``): predicates of the safety game, kept consistent by z3.

The shield takes these comparisons as propositions of its game (:mod:`fretc.shield.synthesis`:
each is a boolean atom of the game under a name of its own, :func:`substitute`). The shield
*chooses* them, so it must never choose truth values no numbers give: per cluster of linked
comparisons, z3 decides which valuations real numbers realize
(:mod:`fretc.check.predicates`, which ``fretc check``'s realizability uses too), and the
invariant joins the game's ``ctl_inv`` (outputs) or ``env_inv`` (inputs).

Design notes: ARCHITECTURE.md, `shield/predicates.py`."""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import Any

from fretc.check.bounds import classify
from fretc.check.predicates import (MAX_VALUATIONS, Cluster, NoWitness, PredicateBudget,
                                    is_predicate, undecidable)
from fretc.check import predicates as _check
from fretc.compiler import ir
from fretc.compiler.ir import Node
from fretc.compiler.printers import to_smv
from fretc.shield.runtime import term_value

__all__ = ["Cluster", "PredicateBudget", "MAX_VALUATIONS", "is_predicate", "refusal",
           "clusters", "substitute", "term", "PREFIX"]

#: the game's name of predicate ``k``: ``PREFIX + str(k)`` (no FRET variable starts so)
PREFIX = "__shield_predicate_"


def refusal(node: Node, inputs: Sequence[str]) -> str | None:
    """Why the predicate ``node`` cannot be a shield's atom (module docstring), or None."""
    for n in ir.walk(node):
        if n.op == "pre":
            return (f"{to_smv(node)} reads the previous value of a number ({to_smv(n)}): the "
                    "shield's game keeps no number from one tick to the next")
    why = undecidable(node)
    if why is not None:
        return why.replace("z3 is not given", "the shield does not evaluate")
    got = classify(node, inputs)
    return got if isinstance(got, str) else None


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


def clusters(pts: Sequence[Node], inputs: Sequence[str]) -> list[Cluster]:
    """The clusters of the atoms of ``pts`` (:func:`fretc.check.predicates.clusters`), each
    decided by z3, with the numbers of every realizable valuation as doubles; ``pts`` without
    bounds (the caller takes them out: :mod:`fretc.shield.plan`).

    Raises:
        PredicateBudget: a cluster past :data:`MAX_VALUATIONS`.
        ValueError: a predicate :func:`refusal` refuses (its message)."""
    for n in _check.comparisons(pts):
        if is_predicate(n) and (why := refusal(n, inputs)) is not None:
            raise ValueError(why)
    return _check.clusters(pts, inputs, _numbers)


def _numbers(c: Cluster, model: Any, reals: dict[str, Any],
             values: tuple[bool, ...]) -> dict[str, float]:
    """z3's numbers as doubles, checked to give the atoms ``values`` in double arithmetic
    (an output cluster's: the shield writes them; an input cluster's numbers are never
    written, and the environment may give the valuation whatever they are).

    Raises:
        NoWitness: rounding to doubles changes a truth value of an output cluster: the
            shield never chooses the valuation (never silently: the plan notes it)."""
    import z3

    out = {}
    for v in c.variables:
        x = model.eval(reals[v], model_completion=True)
        out[v] = float(Fraction(x.as_fraction())) if z3.is_rational_value(x) else float(
            x.approx(20).as_fraction())
    if c.is_input:
        return out
    for a, want in zip(c.atoms, values):
        if term_value(term(a), out) != want:
            raise NoWitness(f"z3's numbers {out} give {to_smv(a)} = {want} over the reals, "
                            "not in doubles")
    return out


def substitute(n: Node, names: dict[Node, Node]) -> Node:
    """``n`` with each predicate in ``names`` replaced by its game atom (a boolean ``ap``)."""
    got = names.get(n)
    if got is not None:
        return got
    if not n.args or n.op in ("cmp", "var", "num", "arith", "fn", "neg", "pre"):
        return n
    return ir.rebuild(n, tuple(substitute(a, names) for a in n.args))
