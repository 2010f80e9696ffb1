"""Typed abstract syntax of a FRETish requirement.

The shape follows FRET's sentence structure (FRET user manual, "FRETish"; Giannakopoulou et
al., REFSQ 2020)::

    [scope] [condition] [the] component shall [probability] [timing] satisfy response

Every node carries a :class:`Span` into the text it was parsed from; spans take no part in
equality, so two parses of differently spaced sentences compare equal.

The nodes are frozen dataclasses: immutable, hashable, compared and shown without their
spans.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from collections.abc import Iterator
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:  # fractions is imported lazily (start-up time)
    from fractions import Fraction

SCOPE_KINDS = ("null", "in", "notin", "onlyIn", "after", "before", "onlyAfter", "onlyBefore")
CONDITION_KINDS = ("null", "regular", "holding")
TIMING_KINDS = (
    "null", "immediately", "next", "finally", "eventually", "always", "never",
    "within", "for", "after", "until", "before",
)
#: Timings that take a duration (``within N unit``) and those that take a stop condition.
DURATION_TIMINGS = ("within", "for", "after")
STOP_TIMINGS = ("until", "before")
_UNIT_SECONDS: dict = {}


def __getattr__(name: str):
    """``UNIT_SECONDS`` (PEP 562): the canonical duration units and their length in seconds
    (exact :class:`fractions.Fraction`; ``ticks`` has none), made on first use: importing
    :mod:`fractions` (and :mod:`decimal`) costs every start-up that meets no time unit."""
    if name == "UNIT_SECONDS":
        if not _UNIT_SECONDS:
            from fractions import Fraction

            _UNIT_SECONDS.update({
                "microseconds": Fraction(1, 1_000_000),
                "milliseconds": Fraction(1, 1000),
                "seconds": Fraction(1),
                "minutes": Fraction(60),
                "hours": Fraction(3600),
            })
        return _UNIT_SECONDS
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class Span(NamedTuple):
    """Where a node sits in its source: 1-based ``line``/``column`` of its first character,
    ``end_line``/``end_column`` just past its last one, and 0-based character offsets
    ``start``/``end`` into the parsed text. (A named tuple: the parser makes one per node.)"""

    line: int
    column: int
    end_line: int
    end_column: int
    start: int
    end: int


NO_SPAN = Span(0, 0, 0, 0, 0, 0)


def _span() -> Span:
    return field(default=NO_SPAN, compare=False, repr=False)


# --------------------------------------------------------------------------- expressions
@dataclass(frozen=True)
class Var:
    """A FRET variable (boolean or numeric), by its source name (quotes removed)."""

    name: str
    span: Span = _span()


@dataclass(frozen=True)
class BoolLit:
    """``true``/``false`` in any letter case."""

    value: bool
    span: Span = _span()


@dataclass(frozen=True)
class NumLit:
    """A numeric literal, kept as written (``3``, ``-3.0e2``, ``0.5``) so printers can
    reproduce it; :attr:`value` gives it as ``int`` or ``float``."""

    text: str
    span: Span = _span()

    @property
    def value(self) -> int | float:
        """The literal's value: an ``int`` when the text is an integer, else a ``float``."""
        try:
            return int(self.text)
        except ValueError:
            return float(self.text)


@dataclass(frozen=True)
class Unary:
    """``op`` is ``"!"`` (logical not; FRETish ``!`` and ``~``) or ``"-"`` (arithmetic)."""

    op: str
    operand: Expr
    span: Span = _span()


#: Binary operators, in FRET's canonical spelling. ``=>`` is stored as ``->``, ``<=>`` as
#: ``<->`` and ``if A then B`` as ``A -> B``.
BOOL_OPS = ("&", "|", "xor", "->", "<->")
COMPARISON_OPS = ("=", "!=", "<", "<=", ">", ">=")
ARITH_OPS = ("+", "-", "*", "/", "mod", "^")


@dataclass(frozen=True)
class Binary:
    """A binary operation; ``op`` is one of :data:`BOOL_OPS`, :data:`COMPARISON_OPS` or
    :data:`ARITH_OPS`."""

    op: str
    left: Expr
    right: Expr
    span: Span = _span()


@dataclass(frozen=True)
class Call:
    """A function application ``name(args...)``. FRET's predefined temporal functions use
    this node too: ``persisted``, ``occurred``, ``preBool``/``preInt``/``preReal``,
    ``prevOcc``, ``persists``, ``occurs``, ``nextOcc`` (``at the previous occurrence of P, Q``
    is ``prevOcc(P, Q)``, ``at the next occurrence of P, Q`` is ``nextOcc(P, Q)``)."""

    name: str
    args: tuple[Expr, ...]
    span: Span = _span()



Expr = Var | BoolLit | NumLit | Unary | Binary | Call


# --------------------------------------------------------------------------- fields
@dataclass(frozen=True)
class Scope:
    """``kind`` in :data:`SCOPE_KINDS`; ``mode`` is the mode variable or, for ``while C``
    and ``after/before C``, a boolean expression (``None`` for the null scope)."""

    kind: str = "null"
    mode: Expr | None = None
    span: Span = _span()


@dataclass(frozen=True)
class ConditionPart:
    """One qualified condition as written: ``qualifier`` is ``upon``, ``when``, ``if``,
    ``where``, ``unless`` or ``whenever``; ``expr`` is the expression with ``is true``/
    ``is false`` and ``unless`` already applied."""

    qualifier: str
    expr: Expr
    connective: str | None = None  # "and"/"or" joining it to the previous part
    span: Span = _span()


@dataclass(frozen=True)
class Condition:
    """The trigger. ``kind`` in :data:`CONDITION_KINDS`: ``holding`` when every part is
    ``whenever``, otherwise ``regular``; ``expr`` folds the parts left to right with their
    connectives (FRET: ``upon p, or when r`` is ``p | r``)."""

    kind: str = "null"
    expr: Expr | None = None
    parts: tuple[ConditionPart, ...] = ()
    span: Span = _span()


@dataclass(frozen=True)
class Duration:
    """``amount`` as written (``"10"``, ``"2.5"``) and ``unit`` canonical: ``ticks`` or a key
    of :data:`UNIT_SECONDS`. A named duration (``within T_stop``) has its ``name``; its
    ``amount`` and ``unit`` are those of the constant's declaration once resolved
    (:mod:`fretc.fretish.constants`), empty before."""

    amount: str
    unit: str
    span: Span = _span()
    name: str | None = None

    @property
    def value(self) -> Fraction:
        """The amount as an exact ``Fraction`` (``"2.5"`` is 5/2), in :attr:`unit`."""
        from fractions import Fraction  # lazy (start-up time)

        return Fraction(self.amount)

    @property
    def resolved(self) -> bool:
        """Whether the duration has a value (a number, or a declared constant's)."""
        return bool(self.amount)


@dataclass(frozen=True)
class Timing:
    """``kind`` in :data:`TIMING_KINDS`; ``duration`` for ``within/for/after``, ``stop`` (the
    stop condition) for ``until/before``; ``phrase`` is the phrasing used."""

    kind: str = "null"
    duration: Duration | None = None
    stop: Expr | None = None
    phrase: str = ""
    span: Span = _span()


@dataclass(frozen=True)
class Probability:
    """``with probability OP value``; ``op`` one of ``< <= > >= = !=`` (``!=`` accepted as FRET
    accepts it), value in [0, 1]."""

    op: str
    value: str
    span: Span = _span()


@dataclass(frozen=True)
class Requirement:
    """A parsed FRETish sentence.

    ``freeform`` sentences (one double-quoted string) carry only ``text``; they are kept,
    never formalized. ``key`` is FRET's template key ``scope,condition,timing,satisfaction``.
    """

    text: str
    scope: Scope = Scope()
    condition: Condition = Condition()
    component: str = ""
    probability: Probability | None = None
    timing: Timing = Timing()
    response: Expr | None = None
    freeform: bool = False
    component_span: Span = _span()
    response_span: Span = _span()

    def field_expr(self, field: str) -> Expr | None:
        """The expression of ``field`` (``scope``: the mode, ``condition``, ``stop``: the
        timing's stop condition, else the response), None where the sentence has none."""
        if field == "scope":
            return self.scope.mode if self.scope.kind != "null" else None
        if field == "condition":
            return self.condition.expr if self.condition.kind != "null" else None
        if field == "stop":
            return self.timing.stop if self.timing.kind in STOP_TIMINGS else None
        return self.response

    @property
    def key(self) -> str | None:
        """FRET's template key ``scope,condition,timing,satisfaction`` (FRET's ``semantics.json``
        keys; duration classes aside), or None for a free-form requirement."""
        if self.freeform:
            return None
        return f"{self.scope.kind},{self.condition.kind},{self.timing.kind},satisfaction"


def walk(expr: Expr) -> Iterator[Expr]:
    """Yield ``expr`` and all its sub-expressions, pre-order."""
    stack = [expr]
    while stack:
        node = stack.pop()
        yield node
        if isinstance(node, Unary):
            stack.append(node.operand)
        elif isinstance(node, Binary):
            stack.extend((node.right, node.left))
        elif isinstance(node, Call):
            stack.extend(reversed(node.args))
