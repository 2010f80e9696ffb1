"""Where FRET's reading of a nested ``if A then B`` differs from the grammar's.

In FRETish's grammar ``if A then B`` is a prefix operator whose ``B`` extends as far right as
possible (``a & if b then c | d`` is ``a & (b -> (c | d))``). FRET 3.x does not formalize
that parse: it rewrites the expression's text (`` then `` becomes ``=>``, ``if `` is
deleted) and parses the result again, which regroups an if-then that is an operand
(``(a & if b then c) | d`` becomes ``((a & b) -> c) | d``, ``!if a then b`` becomes
``(!a) -> b``), and in scope and stop conditions gives ``undefined(...)``
(../shared/fretish/README.md section 6b and section 7, defect 2).

fretc follows the grammar everywhere. :func:`regrouping_warnings` reproduces FRET's rewrite
on each expression of a requirement and returns a warning, showing both readings, for each
expression whose FRET reading means something else, so that a user porting requirements
from FRET sees where FRET's formulas and fretc's differ.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterable

from fretc.fretish import ast as A
from fretc.common.errors import FretishError
from fretc.fretish.parser import parse_expression

from fretc.compiler import ir
from fretc.compiler.expressions import Expander, SemanticsError
from fretc.compiler.ir import Node
from fretc.compiler.printers import expr_text

_THEN_WORD = re.compile(r"\bthen\b", re.IGNORECASE)
_IF = re.compile(r"\bif\s+", re.IGNORECASE)
_THEN = re.compile(r"\s*\bthen\s+", re.IGNORECASE)
_CONNECTIVES = ("&", "|", "!", "->", "<->", "xor", "true", "false")


def fret_rewrite(text: str) -> str:
    """FRET's text rewrite of an expression: ``then`` becomes ``=>`` and ``if`` is
    deleted."""
    return _THEN.sub(" => ", _IF.sub("", text))


def _fields(req: A.Requirement) -> Iterable[tuple[str, A.Expr]]:
    """(where, expression as written) for each expression of the requirement."""
    if req.scope.mode is not None:
        yield "scope condition", req.scope.mode
    for part in req.condition.parts:
        e = part.expr
        # "unless P" and "P is false" wrap the written expression in a negation that spans
        # the whole part
        if isinstance(e, A.Unary) and e.op == "!" and e.span == part.span:
            e = e.operand
        yield "condition", e
    if req.timing.stop is not None:
        yield "stop condition", req.timing.stop
    if req.response is not None:
        yield "response", req.response


def _atoms(node: Node, out: dict) -> None:
    if node.op in _CONNECTIVES:
        for a in node.args:
            _atoms(a, out)
    elif node not in out:
        out[node] = len(out)


def _value(node: Node, env: dict) -> bool:
    op = node.op
    if op == "true":
        return True
    if op == "false":
        return False
    if op == "!":
        return not _value(node.args[0], env)
    if op in ("&", "|", "->", "<->", "xor"):
        a, b = _value(node.args[0], env), _value(node.args[1], env)
        return {"&": a and b, "|": a or b, "->": (not a) or b, "<->": a == b,
                "xor": a != b}[op]
    return env[node]


def same_meaning(a: Node, b: Node, exhaustive_atoms: int = 14) -> tuple[bool, ...] | None:
    """None when the boolean combinations ``a`` and ``b`` agree on every valuation of their
    atoms (maximal sub-formulas that are not boolean connectives), otherwise a valuation
    (tuple of atom values, in order of appearance) where they differ. Up to
    ``exhaustive_atoms`` atoms every valuation is tried, beyond that 4096 random ones."""
    atoms: dict = {}
    _atoms(a, atoms)
    _atoms(b, atoms)
    keys = list(atoms)
    if len(keys) <= exhaustive_atoms:
        rows: Iterable[tuple[bool, ...]] = itertools.product((False, True), repeat=len(keys))
    else:
        import random  # lazy: only for many atoms (start-up time of fretc FILE)
        rnd = random.Random(0)
        rows = (tuple(rnd.random() < 0.5 for _ in keys) for _ in range(4096))
    for row in rows:
        env = dict(zip(keys, row))
        if _value(a, env) != _value(b, env):
            return row
    return None


def regrouping_warnings(req: A.Requirement) -> list[str]:
    """Warnings for the expressions of ``req`` that FRET's if-then rewrite reads with
    another meaning than the grammar (or cannot formalize). Empty when the sentence has no
    ``then``."""
    if not _THEN_WORD.search(req.text):
        return []
    out = []
    for where, e in _fields(req):
        written = req.text[e.span.start:e.span.end]
        if not _THEN_WORD.search(written):
            continue
        rewritten = fret_rewrite(written)
        try:
            fret_e = parse_expression(rewritten)
        except FretishError:
            out.append(f"if-then in the {where} '{written}': FRET rewrites it to "
                       f"'{rewritten}', which does not parse; fretc reads "
                       f"{expr_text(e)} (the grammar's grouping)")
            continue
        if where in ("scope condition", "stop condition"):
            out.append(f"if-then in the {where} '{written}': FRET cannot formalize it "
                       f"(prints undefined(...)); fretc reads {expr_text(e)} (the grammar's "
                       "grouping)")
            continue
        if fret_e == e:
            continue
        try:
            ours = Expander("pt", ir.FTP, ir.LAST, free=True).bool(e)
            theirs = Expander("pt", ir.FTP, ir.LAST, free=True).bool(fret_e)
        except SemanticsError:
            continue
        if same_meaning(ours, theirs) is None:
            continue
        out.append(f"if-then regrouped by FRET in the {where} '{written}': FRET reads "
                   f"{expr_text(fret_e)}, fretc reads {expr_text(e)} (the grammar's "
                   "grouping); they differ, so FRET's formulas for this requirement mean "
                   "something else than fretc's")
    return out
