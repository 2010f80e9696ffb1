"""Depth and size limits on FRETish input.

A requirement beyond these limits is rejected with a positioned error (``file:line:col``)
instead of exhausting recursion, memory or time further down the tool chain (formalization,
printers, Spot, generated monitors). They are far above what requirements are written with:
the 197 NASA case-study requirements that parse (``shared/corpora/fret_casestudies.jsonl``)
reach an expression depth of 17 (calls counted as below), 227 expression nodes, numbers of 7
characters and durations of 200 ticks.

Design notes: ARCHITECTURE.md, `fretish/limits.py`."""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # fractions is imported lazily (start-up time)
    from fractions import Fraction

from fretc.fretish import ast as A
from fretc.common.errors import FretishError
from fretc.fretish.words import FRET_RESERVED

MAX_EXPR_DEPTH = 200
#: A function call counts for this many levels: FRET's past- and future-time functions
#: expand into up to four nested operators (``preBool(b, p)`` = ``(FTP & b) | (!FTP & Y p)``).
CALL_DEPTH = 4
MAX_EXPR_NODES = 5000
MAX_NUMBER_CHARS = 100
MAX_DURATION_TICKS = 1_000_000

__all__ = ["MAX_EXPR_DEPTH", "MAX_EXPR_NODES", "MAX_NUMBER_CHARS", "MAX_DURATION_TICKS",
           "LimitError", "check_requirement", "check_expression", "duration_too_long", "depth"]


class LimitError(FretishError):
    """A limit exceeded at ``span`` (a :class:`fretc.fretish.ast.Span`), with a hint."""

    def __init__(self, span, message: str, hint: str | None = None):
        super().__init__(message)
        self.span, self.message, self.hint = span, message, hint


def _expressions(req: A.Requirement) -> Iterator[A.Expr]:
    if req.scope.mode is not None:
        yield req.scope.mode
    if req.condition.expr is not None:
        yield req.condition.expr
    if req.timing.stop is not None:
        yield req.timing.stop
    if req.response is not None:
        yield req.response


#: A sentence this short cannot exceed the expression limits, so its expressions are not
#: walked: a number literal beyond :data:`MAX_NUMBER_CHARS` is longer; every node takes at
#: least one character of the text (a name, a number, an operator, ``!``, ``-``), and a
#: call, which counts :data:`CALL_DEPTH` levels, at least three (``f()``), so the depth is
#: at most ``1 + CALL_DEPTH / 3`` per character and the node count at most one per character.
SHORT_TEXT = min(MAX_NUMBER_CHARS, MAX_EXPR_NODES, (MAX_EXPR_DEPTH - 1) * 3 // CALL_DEPTH)

#: Up to this length, only a long number literal can exceed a limit (the depth and node
#: bounds of :data:`SHORT_TEXT`), and a text with no run of :data:`MAX_NUMBER_CHARS` - 1
#: number characters (a literal, or ``-`` and one, is at most that run and its sign) has
#: none: such a text is not walked either.
SHORT_TEXT_NO_NUMBER = min(MAX_EXPR_NODES, (MAX_EXPR_DEPTH - 1) * 3 // CALL_DEPTH)
_NUMBER_RUN = re.compile(f"[0-9][0-9.eE+-]{{{MAX_NUMBER_CHARS - 2}}}")


def check_requirement(req: A.Requirement, letter_names: frozenset[int] = frozenset()) -> None:
    """Check a parsed requirement against the limits (iteratively: any depth is safe) and
    FRET's reserved names (:func:`check_reserved`; ``letter_names`` as there). Raises
    :class:`LimitError` at the first node beyond a limit or reserved."""
    check_reserved(req, letter_names)
    n = len(req.text)
    if n > SHORT_TEXT and (n > SHORT_TEXT_NO_NUMBER or _NUMBER_RUN.search(req.text)):
        count = [0]
        for e in _expressions(req):
            _check(e, count)
    d = req.timing.duration
    if d is not None and len(d.amount) > MAX_NUMBER_CHARS:
        raise _long_number(d.span, d.amount)
    if d is not None and d.unit == "ticks" and (
            int(d.amount) if d.amount.isascii() and d.amount.isdigit() else d.value
    ) > MAX_DURATION_TICKS:
        raise LimitError(d.span, duration_too_long(d.value), _DURATION_HINT)


_RESERVED_WORD = re.compile(r"(?<![A-Za-z0-9_])(" + "|".join(sorted(FRET_RESERVED, key=len,
                                                                   reverse=True))
                            + r")(?![A-Za-z0-9_])")


def check_reserved(req: A.Requirement, letter_names: frozenset[int] = frozenset()) -> None:
    """FRET's rule on names (../shared/fretish/README.md section 5): a variable or function
    named by one of NuSMV's or R2U2's reserved words (:data:`fretc.fretish.words.FRET_RESERVED`,
    case sensitive: ``count``, ``abs``, ``min``, ``init``, ``E``, ``R``, ...) is refused with
    FRET's message; a quoted one (``"count"``) is not (FRET prints it ``_DQT_count_DQT_``,
    and so does :func:`fretc.compiler.printers.mangle`); nor is a letter read as a name from a
    FRET export (``letter_names``: the offsets of those names in the text, which FRET
    formalized and fretc prints quoted). Raises :class:`LimitError` at the first such name."""
    if not _RESERVED_WORD.search(req.text):
        return
    for root in _expressions(req):
        stack = [root]
        while stack:
            e = stack.pop()
            name = getattr(e, "name", None)
            if (type(e) in (A.Var, A.Call) and name in FRET_RESERVED
                    and e.span.start not in letter_names
                    and not req.text[e.span.start:e.span.end].lstrip("( \t").startswith('"')):
                raise LimitError(e.span, "These reserved letter combinations cannot be used: "
                                 f"{name}", _reserved_hint(name, type(e) is A.Call))
            stack.extend(_children(e))


def _reserved_hint(name: str, call: bool) -> str:
    """What to write instead of a reserved word: FRET's own function for ``abs``, ``min``,
    ``max`` (the binding language's spellings), else another name."""
    fret = {"abs": "absReal(...) or absInt(...)", "min": "minReal(...) or minInt(...)",
            "max": "maxReal(...) or maxInt(...)"}.get(name)
    if fret is None:
        return "rename it"
    return (f"FRET spells it {fret}" + ("; or compute it in a binding file (x = "
                                        f"\"{name}(/topic.field)\") and use x here"
                                        if call else "; or rename it"))


def _children(e: A.Expr) -> list:
    if isinstance(e, A.Unary):
        return [e.operand]
    if isinstance(e, A.Binary):
        return [e.left, e.right]
    if isinstance(e, A.Call):
        return list(e.args)
    return []


def check_expression(e: A.Expr) -> None:
    """:func:`check_requirement` for one expression."""
    _check(e, [0])


_DURATION_HINT = ("use a coarser tick period or a shorter duration; monitors keep up to one "
                  "bit per tick of a bounded duration")


def depth(e: A.Expr) -> int:
    """The nesting depth of the expression ``e`` as :func:`check_expression` counts it (an
    operator one level, a call :data:`CALL_DEPTH`), without recursion."""
    out, stack = 0, [(e, 1)]
    while stack:
        x, d = stack.pop()
        out = max(out, d)
        if isinstance(x, A.Unary):
            stack.append((x.operand, d + 1))
        elif isinstance(x, A.Binary):
            stack += [(x.left, d + 1), (x.right, d + 1)]
        elif isinstance(x, A.Call):
            stack += [(a, d + CALL_DEPTH) for a in x.args]
    return out


def duration_too_long(ticks: Fraction | float) -> str:
    """The message for a duration of ``ticks`` ticks above :data:`MAX_DURATION_TICKS`."""
    shown = f"{int(ticks):,}" if ticks == int(ticks) else f"{float(ticks):,.1f}"
    return (f"a duration of {shown} ticks is beyond the limit of {MAX_DURATION_TICKS:,} "
            "ticks")


def _long_number(span, text: str) -> LimitError:
    return LimitError(span, f"a number of {len(text):,} characters is beyond the limit of "
                      f"{MAX_NUMBER_CHARS} characters", "write it with an exponent (1e400)")


def _check(root: A.Expr, count: list) -> None:
    stack: list = [(root, 1)]
    while stack:
        e, depth = stack.pop()
        count[0] += 1
        if count[0] > MAX_EXPR_NODES:
            raise LimitError(e.span, f"the requirement has more than {MAX_EXPR_NODES:,} names, "
                             "numbers and operators", "split it into several requirements")
        if depth > MAX_EXPR_DEPTH:
            raise LimitError(e.span, f"expression nested more than {MAX_EXPR_DEPTH} levels "
                             "deep (operators, negations and function calls inside one "
                             "another)", "split it into several requirements or introduce a "
                             "variable for a part of it")
        t = type(e)
        if t is A.NumLit:
            if len(e.text) > MAX_NUMBER_CHARS:
                raise _long_number(e.span, e.text)
        elif t is A.Unary:
            stack.append((e.operand, depth + 1))
        elif t is A.Binary:
            stack.append((e.right, depth + 1))
            stack.append((e.left, depth + 1))
        elif t is A.Call:
            stack.extend((a, depth + CALL_DEPTH) for a in reversed(e.args))
