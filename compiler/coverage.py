"""Coverage obligations of a requirement: what a set of traces must show for the requirement
to count as *exercised*, derived from the requirement's parsed fields (scope, condition,
timing, response) and read by the audit (``fretc audit --coverage``) and the test generator
(``fretc testgen``).

Every obligation but the threshold ones is a **verdict difference**: met on a trace when
FRET's finite-trace verdict of the requirement differs from that of a *variant* changing one
part and nothing else (unique-cause coverage, Whalen et al., ISSTA 2006; FRET's FLIP
coverage, Katis et al., NFM 2025). The obligations (``<field>:<atom>+``/``-``, ``trigger``,
``trigger-persists``, ``scope-entered``, ``scope-left``, ``deadline-reached``,
``deadline-missed``, ``timing:<kind>``, ``<field>:<comparison>:true``/``:false``) in full:
ARCHITECTURE.md ("Coverage obligations").
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from fretc.fretish import ast as A
from fretc.fretish.fret_since import SINCE

__all__ = ["Obligation", "obligations", "other_condition_kind", "atoms_of", "expr_text", "replace_atom",
           "with_ticks", "FIELDS", "TIMINGS"]

#: the fields whose atoms get obligations, in sentence order
FIELDS = ("scope", "condition", "stop", "response")

#: for each scope kind, the mode value that leaves the trace with no scope interval
_EMPTY_SCOPE = {"in": False, "notin": True, "after": False, "before": True,
                "onlyIn": True, "onlyAfter": True, "onlyBefore": False}
#: the scope that extends each kind past the end of its mode (``scope-left``)
_WIDER_SCOPE = {"in": "after", "before": "null", "notin": "null"}

#: each condition kind's other kind and a qualifier that writes it (``trigger-persists``)
_OTHER_CONDITION = {"regular": ("holding", "whenever"), "holding": ("regular", "upon")}

_DEADLINE_WORDS = {
    "within": ("a response comes at the last tick the deadline allows",
               "the response comes one tick past the deadline, or never"),
    "for": ("the response holds through exactly the window and fails right after it",
            "the response fails at the window's last tick"),
    "after": ("the response first comes exactly when the delay ends",
              "the response comes one tick after the delay ends, or early"),
}


@dataclass(frozen=True)
class Obligation:
    """One coverage obligation of one requirement.

    Attributes:
        requirement: the requirement's id.
        id: the obligation's id within the requirement (``response:stopped+``,
            ``trigger``, ``deadline-reached``, ``condition:distance < 0.9:true``).
        kind: ``atom``, ``trigger``, ``scope``, ``deadline``, ``timing`` or ``threshold``.
        description: the rule behind it, in plain English.
        variant: the requirement whose verdict must differ (None for ``threshold``).
        variant_ticks: the variant's duration in ticks (``within/for/after``), else None.
        atom: the comparison of a ``threshold`` obligation; ``side`` its wanted value.
    """

    requirement: str
    id: str
    kind: str
    description: str
    variant: A.Requirement | None = None
    variant_ticks: int | None = None
    atom: A.Expr | None = None
    side: bool | None = None


def expr_text(e: A.Expr) -> str:
    """FRETish text of an expression (fully bracketed below the top level; for names of
    obligations, not for parsing back)."""
    if isinstance(e, A.Var):
        return e.name
    if isinstance(e, A.BoolLit):
        return "true" if e.value else "false"
    if isinstance(e, A.NumLit):
        return e.text
    if isinstance(e, A.Unary):
        return f"{e.op}{_bracket(e.operand)}"
    if isinstance(e, A.Binary):
        return f"{_bracket(e.left)} {e.op} {_bracket(e.right)}"
    if e.name == SINCE and len(e.args) == 2:  # (a FRET latch: :mod:`fretc.fretish.fret_since`)
        return f"({expr_text(e.args[0])}) S ({expr_text(e.args[1])})"
    return f"{e.name}({', '.join(expr_text(a) for a in e.args)})"


def _bracket(e: A.Expr) -> str:
    t = expr_text(e)
    return f"({t})" if isinstance(e, A.Binary) else t


def atoms_of(e: A.Expr | None) -> list[A.Expr]:
    """The atomic propositions of a boolean expression, in order, without repeats (span
    ignored): the maximal sub-expressions under ``!`` and :data:`fretc.fretish.ast.BOOL_OPS`
    that are not themselves boolean connectives or literals (a variable, a comparison, a
    temporal function)."""
    out: list[A.Expr] = []
    seen: set[str] = set()

    def visit(x: A.Expr) -> None:
        if isinstance(x, A.Unary) and x.op == "!":
            visit(x.operand)
        elif isinstance(x, A.Binary) and x.op in A.BOOL_OPS:
            visit(x.left)
            visit(x.right)
        elif not isinstance(x, A.BoolLit):
            key = expr_text(x)
            if key not in seen:
                seen.add(key)
                out.append(x)

    if e is not None:
        visit(e)
    return out


def _replace_in(e: A.Expr | None, key: str, by: A.Expr) -> A.Expr | None:
    """:func:`_replace` in a field, which a requirement may not have (None stays None)."""
    return None if e is None else _replace(e, key, by)


def _replace(e: A.Expr, key: str, by: A.Expr) -> A.Expr:
    """``e`` with every boolean-position occurrence of the atom whose text is ``key``
    replaced by ``by``."""
    if isinstance(e, A.Unary) and e.op == "!":
        return dataclasses.replace(e, operand=_replace(e.operand, key, by))
    if isinstance(e, A.Binary) and e.op in A.BOOL_OPS:
        return dataclasses.replace(e, left=_replace(e.left, key, by),
                                   right=_replace(e.right, key, by))
    return by if expr_text(e) == key else e


def replace_atom(req: A.Requirement, field: str, atom: A.Expr, by: A.Expr) -> A.Requirement:
    """``req`` with ``atom`` replaced by ``by`` in one field (one of :data:`FIELDS`); the
    sentence's text is kept (the formulas are built from the fields)."""
    key = expr_text(atom)
    if field == "scope":
        return dataclasses.replace(req, scope=dataclasses.replace(
            req.scope, mode=_replace_in(req.scope.mode, key, by)))
    if field == "condition":
        c = req.condition
        parts = tuple(dataclasses.replace(p, expr=_replace(p.expr, key, by)) for p in c.parts)
        return dataclasses.replace(req, condition=dataclasses.replace(
            c, expr=_replace_in(c.expr, key, by), parts=parts))
    if field == "stop":
        return dataclasses.replace(req, timing=dataclasses.replace(
            req.timing, stop=_replace_in(req.timing.stop, key, by)))
    return dataclasses.replace(req, response=_replace_in(req.response, key, by))


def with_ticks(req: A.Requirement, ticks: int) -> A.Requirement:
    """``req`` with its ``within/for/after`` duration set to ``ticks`` ticks."""
    return dataclasses.replace(req, timing=dataclasses.replace(
        req.timing, duration=A.Duration(str(ticks), "ticks")))


_FIELD_WORDS = {"scope": "the scope's mode", "condition": "the condition",
                "stop": "the stop condition", "response": "the response"}


def _atom_obligations(rid: str, req: A.Requirement, ticks: int | None) -> list[Obligation]:
    out = []
    for field in FIELDS:
        for atom in atoms_of(req.field_expr(field)):
            text = expr_text(atom)
            where = _FIELD_WORDS[field]
            for value, sign in ((True, "+"), (False, "-")):
                word, other = ("true", "false") if value else ("false", "true")
                out.append(Obligation(
                    rid, f"{field}:{text}{sign}", "atom",
                    f"{text}'s own effect in {where} when {word}: {text} is {word} at some "
                    f"tick and, everything else unchanged, the verdict would differ with "
                    f"{text} {other} throughout (unique cause)",
                    replace_atom(req, field, atom, A.BoolLit(not value)), ticks))
            out.extend(_threshold(rid, field, atom))
    return out


def _threshold(rid: str, field: str, atom: A.Expr) -> list[Obligation]:
    """The two sides of a numeric variable compared with a number (either order)."""
    if not (isinstance(atom, A.Binary) and atom.op in A.COMPARISON_OPS):
        return []
    pair = (atom.left, atom.right)
    if not any(isinstance(x, A.Var) for x in pair) or not any(
            isinstance(x, A.NumLit) for x in pair):
        return []
    text = expr_text(atom)
    return [Obligation(rid, f"{field}:{text}:{'true' if side else 'false'}", "threshold",
                       f"{text} seen {'true' if side else 'false'} at some tick (its "
                       "threshold approached from that side; the closest margin is reported)",
                       atom=atom, side=side)
            for side in (True, False)]


def other_condition_kind(req: A.Requirement) -> tuple[str, A.Requirement] | None:
    """``req`` with its condition read as the other of FRET's condition kinds (``regular``:
    ``upon``/``when``/``if``, a trigger at each rising edge; ``holding``: ``whenever``, at every
    tick the condition holds), with the qualifier that writes it; None without a condition."""
    if req.condition.kind not in _OTHER_CONDITION:
        return None
    other, word = _OTHER_CONDITION[req.condition.kind]
    parts = tuple(dataclasses.replace(p, qualifier=word) for p in req.condition.parts)
    return word, dataclasses.replace(req, condition=dataclasses.replace(
        req.condition, kind=other, parts=parts))


def _structural(rid: str, req: A.Requirement, ticks: int | None) -> list[Obligation]:
    out = []
    kind = req.scope.kind
    if kind in _EMPTY_SCOPE and req.scope.mode is not None:
        empty = A.BoolLit(_EMPTY_SCOPE[kind])
        out.append(Obligation(
            rid, "scope-entered", "scope",
            "the scope entered: the trace reaches a scope interval and what happens in it "
            "decides the verdict (with no scope interval the requirement would be vacuous)",
            dataclasses.replace(req, scope=dataclasses.replace(req.scope, mode=empty)), ticks))
    if kind in _WIDER_SCOPE:
        wider = _WIDER_SCOPE[kind]
        scope = (A.Scope() if wider == "null"
                 else dataclasses.replace(req.scope, kind=wider))
        out.append(Obligation(
            rid, "scope-left", "scope",
            f"the scope left: the trace leaves the scope and its end decides the verdict "
            f"(judged {'globally' if wider == 'null' else 'after the mode'} instead, the "
            "verdict would differ)", dataclasses.replace(req, scope=scope), ticks))
    if req.condition.kind != "null":
        out.append(Obligation(
            rid, "trigger", "trigger",
            "the trigger: the condition becomes true in scope and the requirement's "
            "obligation is judged (with the condition false throughout it would be vacuous)",
            dataclasses.replace(req, condition=dataclasses.replace(
                req.condition, expr=A.BoolLit(False), parts=())), ticks))
    swapped = other_condition_kind(req)
    if swapped is not None:
        word, variant = swapped
        out.append(Obligation(
            rid, "trigger-persists", "trigger",
            "the trigger persists: the condition holds past its first tick (or comes back) "
            f"and that decides the verdict (read as '{word}' the verdict would differ)",
            variant, ticks))
    if req.timing.kind in _DEADLINE_WORDS and ticks is not None:
        reached, missed = _DEADLINE_WORDS[req.timing.kind]
        if ticks >= 1:
            out.append(Obligation(
                rid, "deadline-reached", "deadline",
                f"the deadline reached: {reached} (with {ticks - 1} ticks instead of {ticks} "
                "the verdict would differ)", with_ticks(req, ticks - 1), ticks - 1))
        out.append(Obligation(
            rid, "deadline-missed", "deadline",
            f"the deadline missed by one tick: {missed} (with {ticks + 1} ticks instead of "
            f"{ticks} the verdict would differ)", with_ticks(req, ticks + 1), ticks + 1))
    return out


#: FRET's timings a requirement's timing is compared with (``timing:<kind>`` obligations)
TIMINGS = ("immediately", "next", "eventually", "always", "never", "within", "for", "after")


def _timing_effects(rid: str, req: A.Requirement, ticks: int | None) -> list[Obligation]:
    """The timing's own effect against each other timing of FRET (durations keep ``n``)."""
    if req.timing.kind in A.STOP_TIMINGS or req.response is None:
        return []
    own = req.timing.kind + (f" {ticks} ticks" if req.timing.kind in A.DURATION_TIMINGS
                             and ticks is not None else "")
    out = []
    for kind in TIMINGS:
        if kind == req.timing.kind:
            continue
        n = None
        if kind in A.DURATION_TIMINGS:
            n = ticks if ticks is not None else 1
        timing = A.Timing(kind, A.Duration(str(n), "ticks") if n is not None else None)
        word = f"{kind} {n} ticks" if n is not None else kind
        out.append(Obligation(
            rid, f"timing:{kind}", "timing",
            f"the timing's own effect: judged '{word}' instead of '{own}', the verdict "
            "would differ (the trace shows when the response must come)",
            dataclasses.replace(req, timing=timing), n))
    return out


def obligations(rid: str, req: A.Requirement, ticks: int | None) -> list[Obligation]:
    """The coverage obligations of requirement ``rid`` (module docstring), structural ones
    first. ``req``: the parsed, not free-form requirement; ``ticks``: its duration in ticks
    as the compiler converted it (``Formalization.ticks``), None without one. Free-form
    requirements have none (an empty list)."""
    if req is None or req.freeform:
        return []
    return (_structural(rid, req, ticks) + _timing_effects(rid, req, ticks)
            + _atom_obligations(rid, req, ticks))
