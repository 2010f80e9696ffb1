"""When a requirement takes the full build instead of its template (the opaque-safe rule).

A template (:mod:`fretc.compiler.template_table`) is its key's formulas built with placeholder
atoms: atoms that equal nothing but themselves. Filling in a requirement's atoms gives the
full build's texts exactly when every decision the simplifying constructors of
:mod:`fretc.compiler.ir` took on the placeholders they also take on the atoms (the argument in
:mod:`fretc.compiler.instantiate`'s docstring). They look at an argument's operator (constants
fold, ``!!a`` is ``a``, ``O FTP``, FRET's since identity ``a S (a & FTP) = H a``) and
compare arguments for equality (``a & a = a``, ``a | a = a``). So a requirement falls back
to the full build (:func:`fretc.compiler.semantics.formalize`) when

Design notes: ARCHITECTURE.md, `compiler/fallback.py`."""

from __future__ import annotations

from collections.abc import Sequence

from fretc.compiler.ir import Node
from fretc.compiler.template_table import ATOMS as _ATOMS
from fretc.compiler.template_table import Template

__all__ = ["inspected", "opaque_safe", "plain_compared_safe"]

#: operators a simplifying constructor of compiler.ir looks for in an argument
_INSPECTED_OPS = frozenset(("true", "false", "!", "FTP", "LAST"))


def inspected(atom: Node) -> bool:
    """Rule 1: would a simplifying constructor look inside ``atom`` (a constant, a
    negation, FTP or LAST at top level, or a conjunction with FTP as a side, FRET's since
    identity)?"""
    op = atom.op
    return op in _INSPECTED_OPS or (op == "&" and (atom.args[0].op == "FTP"
                                                   or atom.args[1].op == "FTP"))


def _matches(real: Node, t, atoms, n) -> bool:
    """Is the requirement's node ``real`` equal to template node ``t`` (a field number, or
    ``(op, name, lo, hi, args)`` with a bound ``n + k`` as ``(k,)``) instantiated with
    ``atoms`` and ``n``?"""
    if real is None:
        return False
    if type(t) is int:
        return real == atoms[t]
    op, name, lo, hi, args = t
    if (real.op != op or real.name != name or len(real.args) != len(args)
            or real.lo != _bound(lo, n) or real.hi != _bound(hi, n)):
        return False
    return all(_matches(a, b, atoms, n) for a, b in zip(real.args, args))


def _bound(b, n):
    if type(b) is tuple:
        return n + b[0]
    return b


def opaque_safe(tmpl: Template, atoms: Sequence[Node | None], n: int | None) -> bool:
    """Rules 1 and 2 of the module docstring: no atom is inspected by a constructor
    (:func:`inspected`), and every pair of formulas the template's construction compared
    and found different is still different with the requirement's atoms (``atoms``: the
    twelve atoms by field, None where absent; ``n`` the duration in ticks)."""
    for a in atoms:
        if a is not None and inspected(a):
            return False
    return _compared_safe(tmpl, atoms, n)


def _compared_safe(tmpl: Template, atoms, n: int | None) -> bool:
    """Rule 2 of :func:`opaque_safe` alone."""
    for conj in tmpl.compared:
        for kind, f, v in conj:
            if kind == 0:
                if atoms[f] != atoms[v]:
                    break
            elif kind == 1:
                if not _matches(atoms[f], v, atoms, n):
                    break
            elif n + f != v:
                break
        else:
            return False  # this pair of the template is equal with these atoms
    return True


def _plain_conditions(tmpl: Template) -> tuple:
    """``tmpl.compared`` for atoms that are the same in ft, ft_inf and pt (field ``f`` is
    field ``f % 4``): a condition "atom f equals atom g" of two fields of the same
    expression always holds and is dropped, equal conjunctions are kept once, and each
    conjunction checks the bounds, then atom equalities, then the structural matches
    (cheapest first; the order does not change the result)."""
    conds = tmpl.plain_compared
    if conds is None:
        out: dict = {}
        for conj in tmpl.compared:
            kept = []
            for kind, f, v in conj:
                if kind == 0:
                    f, v = f % _ATOMS, v % _ATOMS
                    if f == v:
                        continue
                elif kind == 1:
                    f %= _ATOMS
                kept.append((kind, f, v))
            kept.sort(key=lambda c: (2, 0, 1)[c[0]])
            out.setdefault(tuple(kept), None)
        conds = tmpl.plain_compared = tuple(out)
    return conds


def plain_compared_safe(tmpl: Template, one: Sequence[Node | None],
                        atoms: Sequence[Node | None], n: int | None) -> bool:
    """:func:`_compared_safe` for plain atoms: ``one`` the four atoms (mode, condition,
    stop, response), ``atoms`` them three times (ft, ft_inf, pt)."""
    for conj in _plain_conditions(tmpl):
        for kind, f, v in conj:
            if kind == 0:
                if one[f] != one[v]:
                    break
            elif kind == 1:
                a = one[f]
                if a is None or a.op != v[0] or not _matches(a, v, atoms, n):
                    break
            elif n + f != v:
                break
        else:
            return False  # this pair of the template is equal with these atoms
    return True

