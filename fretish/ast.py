"""Typed abstract syntax of a FRETish requirement.

The shape follows FRET's sentence structure (FRET user manual, "FRETish"; Giannakopoulou et
al., REFSQ 2020)::

    [scope] [condition] [the] component shall [probability] [timing] satisfy response

Every node carries a :class:`Span` into the text it was parsed from; spans take no part in
equality, so two parses of differently spaced sentences compare equal.

The nodes are dataclasses (``dataclasses.fields``/``replace`` work) that behave as
``@dataclass(frozen=True)`` ones: their methods are written out instead of generated
(:class:`_Node`, and an ``__init__`` per class). The generated ones cost start-up time
(compiled for every class at each start) and parse time (the frozen ``__init__`` sets each
field through ``object.__setattr__``). ``tests/fretish/test_parser.py`` compares
them with generated ones.
"""

from __future__ import annotations

from dataclasses import FrozenInstanceError, dataclass, field, fields
from typing import NamedTuple

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


class _Node:
    """What ``@dataclass(frozen=True)`` would generate for a node, written once for all
    (the generated methods are compiled anew for every class at each start-up):
    equality and hash over the fields that are not spans, ``repr`` without the spans,
    assignment and deletion refused. The subclasses are dataclasses (``fields``,
    ``replace``) with ``init=False, repr=False, eq=False`` and an ``__init__`` of their
    own; ``tests/fretish/test_parser.py`` compares them with generated ones."""

    __slots__ = ()

    def _key(self) -> tuple:
        d = self.__dict__
        return tuple([d[f] for f in self._COMPARED])

    def __eq__(self, other):
        if other.__class__ is self.__class__:
            return self._key() == other._key()
        return NotImplemented

    def __hash__(self):
        return hash(self._key())

    def __repr__(self):
        d = self.__dict__
        inner = ", ".join(f"{f}={d[f]!r}" for f in self._SHOWN)
        return f"{self.__class__.__qualname__}({inner})"

    def __setattr__(self, name, value):
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name):
        raise FrozenInstanceError(f"cannot delete field {name!r}")


def _node(cls):
    """Finish a node class (a dataclass): the fields compared and hashed, and those shown
    by ``repr``, as ``@dataclass`` would take them (every field but the spans)."""
    cls._COMPARED = tuple(f.name for f in fields(cls) if f.compare)
    cls._SHOWN = tuple(f.name for f in fields(cls) if f.repr)
    return cls


# --------------------------------------------------------------------------- expressions
@_node
@dataclass(init=False, repr=False, eq=False)
class Var(_Node):
    """A FRET variable (boolean or numeric), by its source name (quotes removed)."""

    name: str
    span: Span = _span()

    def __init__(self, name, span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["name"] = name
        d["span"] = span


@_node
@dataclass(init=False, repr=False, eq=False)
class BoolLit(_Node):
    """``true``/``false`` in any letter case."""

    value: bool
    span: Span = _span()

    def __init__(self, value, span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["value"] = value
        d["span"] = span


@_node
@dataclass(init=False, repr=False, eq=False)
class NumLit(_Node):
    """A numeric literal, kept as written (``3``, ``-3.0e2``, ``0.5``) so printers can
    reproduce it; :attr:`value` gives it as ``int`` or ``float``."""

    text: str
    span: Span = _span()

    def __init__(self, text, span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["text"] = text
        d["span"] = span

    @property
    def value(self) -> int | float:
        try:
            return int(self.text)
        except ValueError:
            return float(self.text)


@_node
@dataclass(init=False, repr=False, eq=False)
class Unary(_Node):
    """``op`` is ``"!"`` (logical not; FRETish ``!`` and ``~``) or ``"-"`` (arithmetic)."""

    op: str
    operand: "Expr"
    span: Span = _span()

    def __init__(self, op, operand, span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["op"] = op
        d["operand"] = operand
        d["span"] = span


#: Binary operators, in FRET's canonical spelling. ``=>`` is stored as ``->``, ``<=>`` as
#: ``<->`` and ``if A then B`` as ``A -> B``.
BOOL_OPS = ("&", "|", "xor", "->", "<->")
COMPARISON_OPS = ("=", "!=", "<", "<=", ">", ">=")
ARITH_OPS = ("+", "-", "*", "/", "mod", "^")


@_node
@dataclass(init=False, repr=False, eq=False)
class Binary(_Node):
    """A binary operation; ``op`` is one of :data:`BOOL_OPS`, :data:`COMPARISON_OPS` or
    :data:`ARITH_OPS`."""

    op: str
    left: "Expr"
    right: "Expr"
    span: Span = _span()

    def __init__(self, op, left, right, span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["op"] = op
        d["left"] = left
        d["right"] = right
        d["span"] = span


@_node
@dataclass(init=False, repr=False, eq=False)
class Call(_Node):
    """A function application ``name(args...)``. FRET's predefined temporal functions use
    this node too: ``persisted``, ``occurred``, ``preBool``/``preInt``/``preReal``,
    ``prevOcc``, ``persists``, ``occurs``, ``nextOcc`` (``at the previous occurrence of P, Q``
    is ``prevOcc(P, Q)``, ``at the next occurrence of P, Q`` is ``nextOcc(P, Q)``)."""

    name: str
    args: tuple["Expr", ...]
    span: Span = _span()

    def __init__(self, name, args, span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["name"] = name
        d["args"] = args
        d["span"] = span


Expr = Var | BoolLit | NumLit | Unary | Binary | Call


# --------------------------------------------------------------------------- fields
@_node
@dataclass(init=False, repr=False, eq=False)
class Scope(_Node):
    """``kind`` in :data:`SCOPE_KINDS`; ``mode`` is the mode variable or, for ``while C``
    and ``after/before C``, a boolean expression (``None`` for the null scope)."""

    kind: str = "null"
    mode: Expr | None = None
    span: Span = _span()

    def __init__(self, kind="null", mode=None, span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["kind"] = kind
        d["mode"] = mode
        d["span"] = span


@_node
@dataclass(init=False, repr=False, eq=False)
class ConditionPart(_Node):
    """One qualified condition as written: ``qualifier`` is ``upon``, ``when``, ``if``,
    ``where``, ``unless`` or ``whenever``; ``expr`` is the expression with ``is true``/
    ``is false`` and ``unless`` already applied."""

    qualifier: str
    expr: Expr
    connective: str | None = None  # "and"/"or" joining it to the previous part
    span: Span = _span()

    def __init__(self, qualifier, expr, connective=None, span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["qualifier"] = qualifier
        d["expr"] = expr
        d["connective"] = connective
        d["span"] = span


@_node
@dataclass(init=False, repr=False, eq=False)
class Condition(_Node):
    """The trigger. ``kind`` in :data:`CONDITION_KINDS`: ``holding`` when every part is
    ``whenever``, otherwise ``regular``; ``expr`` folds the parts left to right with their
    connectives (FRET: ``upon p, or when r`` is ``p | r``)."""

    kind: str = "null"
    expr: Expr | None = None
    parts: tuple[ConditionPart, ...] = ()
    span: Span = _span()

    def __init__(self, kind="null", expr=None, parts=(), span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["kind"] = kind
        d["expr"] = expr
        d["parts"] = parts
        d["span"] = span


@_node
@dataclass(init=False, repr=False, eq=False)
class Duration(_Node):
    """``amount`` as written (``"10"``, ``"2.5"``) and ``unit`` canonical: ``ticks`` or a key
    of :data:`UNIT_SECONDS`."""

    amount: str
    unit: str
    span: Span = _span()

    def __init__(self, amount, unit, span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["amount"] = amount
        d["unit"] = unit
        d["span"] = span

    @property
    def value(self) -> Fraction:
        from fractions import Fraction  # lazy (start-up time)

        return Fraction(self.amount)


@_node
@dataclass(init=False, repr=False, eq=False)
class Timing(_Node):
    """``kind`` in :data:`TIMING_KINDS`; ``duration`` for ``within/for/after``, ``stop`` (the
    stop condition) for ``until/before``; ``phrase`` is the phrasing used."""

    kind: str = "null"
    duration: Duration | None = None
    stop: Expr | None = None
    phrase: str = ""
    span: Span = _span()

    def __init__(self, kind="null", duration=None, stop=None, phrase="", span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["kind"] = kind
        d["duration"] = duration
        d["stop"] = stop
        d["phrase"] = phrase
        d["span"] = span


@_node
@dataclass(init=False, repr=False, eq=False)
class Probability(_Node):
    """``with probability OP value``; ``op`` one of ``< <= > >= =``, value in [0, 1]."""

    op: str
    value: str
    span: Span = _span()

    def __init__(self, op, value, span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["op"] = op
        d["value"] = value
        d["span"] = span


@_node
@dataclass(init=False, repr=False, eq=False)
class Requirement(_Node):
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

    def __init__(self, text, scope=Scope(), condition=Condition(), component="",
                 probability=None, timing=Timing(), response=None, freeform=False,
                 component_span=NO_SPAN, response_span=NO_SPAN):
        d = self.__dict__  # frozen: the fields are set once, here
        d["text"] = text
        d["scope"] = scope
        d["condition"] = condition
        d["component"] = component
        d["probability"] = probability
        d["timing"] = timing
        d["response"] = response
        d["freeform"] = freeform
        d["component_span"] = component_span
        d["response_span"] = response_span

    @property
    def key(self) -> str | None:
        if self.freeform:
            return None
        return f"{self.scope.kind},{self.condition.kind},{self.timing.kind},satisfaction"


def walk(expr: Expr):
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
