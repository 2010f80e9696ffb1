"""Mutants of a requirement, for measuring how well a test set detects faults in it (the
mutation score of ``bench/bench_mutation.py``): the classic specification mutation operators
(Black, Okun, Yesha, "Mutation operators for specifications", ASE 2000; Fraser, Wotawa,
"Using model-checkers for mutation-based test-case generation", 2007) on FRET's fields:

Design notes: ARCHITECTURE.md, `compiler/mutants.py`."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

from fretc.compiler.coverage import (FIELDS, atoms_of, expr_text, other_condition_kind,
                                     replace_atom, with_ticks)
from fretc.fretish import ast as A

__all__ = ["mutants"]

_SCOPES = ("in", "notin", "before", "after", "onlyIn", "onlyAfter", "onlyBefore")
_TIMINGS = ("immediately", "next", "eventually", "always", "never", "within", "for", "after")


def _swaps(e: A.Expr) -> Iterator[A.Expr]:
    """``e`` with one ``&``/``|`` (boolean positions) swapped, each occurrence in turn."""
    if isinstance(e, A.Unary) and e.op == "!":
        for x in _swaps(e.operand):
            yield dataclasses.replace(e, operand=x)
    elif isinstance(e, A.Binary) and e.op in A.BOOL_OPS:
        if e.op in ("&", "|"):
            yield dataclasses.replace(e, op="|" if e.op == "&" else "&")
        for x in _swaps(e.left):
            yield dataclasses.replace(e, left=x)
        for x in _swaps(e.right):
            yield dataclasses.replace(e, right=x)


def _set(req: A.Requirement, field: str, e: A.Expr) -> A.Requirement:
    if field == "scope":
        return dataclasses.replace(req, scope=dataclasses.replace(req.scope, mode=e))
    if field == "condition":
        return dataclasses.replace(req, condition=dataclasses.replace(
            req.condition, expr=e, parts=()))
    if field == "stop":
        return dataclasses.replace(req, timing=dataclasses.replace(req.timing, stop=e))
    return dataclasses.replace(req, response=e)


def _expression_mutants(req: A.Requirement) -> Iterator[tuple[str, A.Requirement]]:
    every = [a for f in FIELDS for a in atoms_of(req.field_expr(f))]
    for field in FIELDS:
        e = req.field_expr(field)
        for atom in atoms_of(e):
            text = expr_text(atom)
            yield (f"{field}: negate {text}",
                   replace_atom(req, field, atom, A.Unary("!", atom)))
            for other in every:
                if expr_text(other) != text:
                    yield (f"{field}: {text} -> {expr_text(other)}",
                           replace_atom(req, field, atom, other))
        if e is not None:
            for k, swapped in enumerate(_swaps(e), 1):
                yield f"{field}: and/or swap #{k}", _set(req, field, swapped)


def _structure_mutants(req: A.Requirement, ticks: int | None
                       ) -> Iterator[tuple[str, A.Requirement]]:
    if ticks is not None and req.timing.kind in A.DURATION_TIMINGS:
        if ticks >= 1:
            yield "timing n-1", with_ticks(req, ticks - 1)
        yield "timing n+1", with_ticks(req, ticks + 1)
    if req.scope.kind != "null" and req.scope.mode is not None:
        for kind in _SCOPES:
            if kind != req.scope.kind:
                yield f"scope {kind}", dataclasses.replace(
                    req, scope=dataclasses.replace(req.scope, kind=kind))
    swapped = other_condition_kind(req)
    if swapped is not None:
        yield f"condition {swapped[0]}", swapped[1]
    if req.timing.kind not in A.STOP_TIMINGS:
        for kind in _TIMINGS:
            if kind == req.timing.kind:
                continue
            duration = (A.Duration(str(ticks if ticks is not None else 1), "ticks")
                        if kind in A.DURATION_TIMINGS else None)
            yield f"timing {kind}", dataclasses.replace(
                req, timing=A.Timing(kind, duration))


def mutants(req: A.Requirement, ticks: int | None) -> list[tuple[str, A.Requirement]]:
    """``(operator, mutant)`` pairs of a parsed, not free-form requirement (module
    docstring); ``ticks``: its duration in ticks (``Formalization.ticks``) or None."""
    out, seen = [], {repr(req)}
    for name, m in list(_structure_mutants(req, ticks)) + list(_expression_mutants(req)):
        key = repr(m)
        if key not in seen:
            seen.add(key)
            out.append((name, m))
    return out
