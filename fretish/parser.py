"""FRETish sentence -> :class:`fretc.fretish.ast.Requirement`, by Lark.

The grammar is ``grammar.lark`` (Lark, LALR(1), contextual lexer); its header states the
phrasings and the expression precedence, one rule per level. :class:`_Builder` is Lark's
transformer, applied while parsing (no intermediate parse tree). Lark's tables are the sealed
cache entry ``lark/fretish-KEY.lark`` (:mod:`fretc.common.lark_tables`). The readings fixed
here follow FRET 3.x ``Requirement.g4`` and its semantic listener (``../shared/fretish/
README.md`` sections 1-5 and 7); spans are file coordinates (``line``/``column``) and 0-based
offsets (``start``/``end``). Each reading (scopes, conditions, FRET's defects fixed, minus
signs, errors, spans): ARCHITECTURE.md ("Reading a FRETish sentence").
"""

from __future__ import annotations

import dataclasses
import os
import re
import threading
from typing import Any, cast

import lark
from lark.exceptions import LarkError, UnexpectedInput

from fretc.common import lark_tables
from fretc.common.libraries import check_lark

from fretc.fretish import ast as A
from fretc.fretish.diagnostics import make_error, translate
from fretc.fretish.limits import LimitError, check_expression, check_requirement
from fretc.fretish.words import RESERVED_LETTERS, RESERVED_WORDS, UNIT_TOKENS

__all__ = ["parse", "parse_expression", "build_lark", "cached_lark", "RESERVED_WORDS",
           "RESERVED_LETTERS"]

_GRAMMAR_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "grammar.lark")
#: The parser's tables shipped with fretc (``python -m fretc.fretish.make_tables`` writes
#: them; :mod:`fretc.common.lark_tables`): a first run reads them instead of building them.
TABLES_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "grammar_tables.json")
_LARK_OPTIONS = dict(parser="lalr", lexer="contextual", start=["start", "expr"],
                     maybe_placeholders=False)

_BINOPS = {"AMP": "&", "BAR": "|", "XOR": "xor", "IMPLIES": "->", "IFF": "<->",
           "EQ": "=", "NE": "!=", "LT": "<", "LE": "<=", "GT": ">", "GE": ">=",
           "PLUS": "+", "MINUS": "-", "STAR": "*", "SLASH": "/", "MOD": "mod",
           "CARET": "^"}
_SIMPLE_TIMINGS = {"IMMEDIATELY": "immediately", "INITIALLY": "immediately",
                   "FINALLY": "finally", "EVENTUALLY": "eventually", "ALWAYS": "always",
                   "NEVER": "never", "WITHIN": "within", "FOR": "for", "AFTER": "after",
                   "UNTIL": "until", "BEFORE": "before"}
_AT_TIMINGS = {"FIRST": "immediately", "SAME": "immediately", "NEXT": "next",
               "LAST": "finally"}
_SCOPE_KINDS = {"in_scope": "in", "notin_scope": "notin", "onlyin_scope": "onlyIn",
                "after_scope": "after", "before_scope": "before",
                "onlyafter_scope": "onlyAfter", "onlybefore_scope": "onlyBefore"}
_DURATION_AMOUNT = re.compile(r"[0-9]+(?:\.[0-9]+)?\Z")


class _Fail(Exception):
    """A rule the grammar accepts but FRETish forbids, found while building the AST:
    ``span`` (an :class:`fretc.fretish.ast.Span`) where, ``message`` and ``hint``."""

    def __init__(self, span: A.Span, message: str, hint: str | None = None):
        super().__init__(message)
        self.span, self.message, self.hint = span, message, hint


class _Subject:
    """``[the] component shall`` / ``shall [the] component``: the name and its span."""

    def __init__(self, name: str, span: A.Span):
        self.name, self.span = name, span


class _ExplicitMode:
    """``mode M`` / ``M mode``: the mode variable and the phrase's span."""

    def __init__(self, var: A.Var, span: A.Span):
        self.var, self.span = var, span


def _unquote(tok) -> str:
    """A quoted name's text as FRET keeps it: only ``\\"`` is unescaped (to ``"``); every
    other backslash stays, so ``"back\\\\slash"`` keeps both (FRET prints
    ``_DQT_back_BSL__BSL_slash_DQT_``; ../shared/fretish/README.md section 6b, names)."""
    body = tok.value[1:-1]
    return body.replace('\\"', '"') if "\\" in body else body


def _is_numeric_literal(e) -> bool:
    if isinstance(e, A.NumLit):
        return True
    if isinstance(e, A.Unary):
        return e.op == "-"
    return isinstance(e, A.Binary) and e.op in A.ARITH_OPS


def _join(a: A.Span, b: A.Span) -> A.Span:
    """The span from the start of ``a`` to the end of ``b``."""
    return A.Span(a.line, a.column, b.end_line, b.end_column, a.start, b.end)


class _Builder:
    """Lark's transformer for ``grammar.lark``: builds the AST, with spans in file
    coordinates. :meth:`begin` sets the text being parsed and where it starts in its file
    (:func:`_run` holds the parser's lock from then until the parse is over)."""

    def __init__(self):
        self.begin("", 1, 1)

    def begin(self, text: str, line: int, column: int, letters_as_names: bool = False) -> None:
        """Parse ``text``, whose first character is at file ``line``, ``column``;
        ``letters_as_names``: a reserved letter in an expression is a variable (:func:`parse`)."""
        self.text, self.dl, self.dc = text, line - 1, column - 1
        self.pending: list[_Fail] = []   # errors reported when their expression ends
        self.letters_as_names = letters_as_names
        self.letter_names: set[int] = set()  # (the offsets of the letters read as names)

    def span(self, x) -> A.Span:
        """The span of a token (file coordinates: the text's first line is shifted by its
        starting column) or of a node."""
        if not isinstance(x, lark.Token):
            return x.span
        dl, dc = self.dl, self.dc
        # Lark types a Token's position optional (a token made by hand has none); the
        # lexer's tokens, the only ones here, always have theirs
        return A.Span(x.line + dl, x.column + dc if x.line == 1 else x.column,  # type: ignore[operator, arg-type]
                      x.end_line + dl, x.end_column + dc if x.end_line == 1 else x.end_column,  # type: ignore[operator, arg-type]
                      x.start_pos, x.end_pos)  # type: ignore[arg-type]

    def join(self, a, b) -> A.Span:
        """The span from the start of ``a`` to the end of ``b`` (tokens or nodes)."""
        return _join(self.span(a), self.span(b))

    def name_of(self, tok) -> str:
        """A NAME's text, or a quoted name without its quotes (never empty)."""
        if tok.type != "STRING":
            return tok.value
        name = _unquote(tok)
        if not name.strip():
            raise _Fail(self.span(tok), "an empty quoted name", "write a name between the quotes")
        return name

    def not_here(self, span: A.Span) -> _Fail:
        """The error of a "!" (at ``span.start``) that is an operand of an arithmetic or
        comparison operator or of a unary minus."""
        bang = self.text[span.start]
        return _Fail(span, f"unexpected '{bang}' in an expression: a negation cannot be an "
                     "operand of an arithmetic or comparison operator",
                     f"put the negated part in parentheses: '({bang}p)'")

    # ---- expressions
    def expr(self, c):
        """A whole expression: the first error found inside it and not yet reported."""
        e = c[0]
        if self.pending:
            mine = [f for f in self.pending if f.span.start >= e.span.start]
            if mine:
                raise min(mine, key=lambda f: f.span.start)
        return e

    def number(self, c):
        return A.NumLit(c[0].value, self.span(c[0]))

    def var(self, c):
        return A.Var(self.name_of(c[0]), self.span(c[0]))

    def boolean(self, c):
        return A.BoolLit(c[0].type == "TRUE", self.span(c[0]))

    def reserved(self, c):
        t = c[0]
        w = t.value
        if self.letters_as_names and w in RESERVED_LETTERS:
            span = self.span(t)
            self.letter_names.add(span.start)
            return A.Var(w, span)
        if w.lower() == "what":
            raise _Fail(self.span(t), "'what' is a reserved word in FRETish (probability "
                        "queries)", f"quote it (\"{w}\") or rename the variable")
        raise _Fail(self.span(t), f"'{w}' is reserved: it is a temporal operator of FRET's "
                    "formulas", f"quote it (\"{w}\") or rename the variable")

    def paren(self, c):
        # the parentheses belong to the expression's span
        return dataclasses.replace(c[1], span=self.join(c[0], c[2]))

    def call(self, c):
        name, rpar = c[0], c[-1]
        args = tuple(c[2:-1])
        if name.value == "preBool" and args and _is_numeric_literal(args[0]):
            init = args[0]
            shown = self.text[init.span.start:init.span.end]
            raise _Fail(init.span, f"preBool's initial value must be true or false, not "
                        f"'{shown}'", "preBool(init, p) is init at the first step and p one "
                        "step earlier afterwards; write preBool(false, p) or preBool(true, p) "
                        "(FRET prints 'undefined' for a numeric initial value)")
        return A.Call(name.value, args, self.join(name, rpar))

    def binary(self, c):
        left, op, right = c
        return A.Binary(_BINOPS[op.type], left, right, _join(left.span, right.span))

    def cmp_chain(self, c):
        # a < b < c: reported at the second comparison operator (a longer chain keeps it)
        if len(c) == 5:
            op = c[3]
            self.pending.append(_Fail(
                self.span(op), f"comparisons do not chain: unexpected '{op.value}' after a "
                "comparison", "compare twice and join with '&': 'a < b & b < c'"))
        return A.Binary(_BINOPS[c[-2].type], c[0], c[-1], _join(c[0].span, c[-1].span))

    def negation(self, c):               # ! p, ~ p
        return A.Unary("!", c[1], self.join(c[0], c[1]))

    def bad_not(self, c):                # x = !y: reported when the expression ends
        self.pending.append(self.not_here(self.span(c[0])))
        return A.Unary("!", c[1], self.join(c[0], c[1]))

    def minus_bang(self, c):             # -!y
        raise self.not_here(self.span(c[1]))

    def negative(self, c):               # - x
        op, x = c
        text = self.text
        if op.end_pos < len(text) and text[op.end_pos] != "(":
            # a minus written against a number literal is part of it, as in FRET's
            # lexer: -3 ^ 2 is (-3) ^ 2, while - 3 ^ 2 and -x ^ 2 negate the power
            if type(x) is A.NumLit and x.span.start == op.end_pos \
                    and not x.text.startswith("-"):
                return A.NumLit("-" + x.text, self.join(op, x))
            if type(x) is A.Binary and x.op == "^" and type(x.left) is A.NumLit \
                    and x.left.span.start == op.end_pos and not x.left.text.startswith("-"):
                left = A.NumLit("-" + x.left.text, self.join(op, x.left))
                return A.Binary("^", left, x.right, _join(left.span, x.right.span))
        return A.Unary("-", x, self.join(op, x))

    def prefixed(self, c):               # an operand after "-!" (only to report it)
        op, x = c
        if op.type == "BANG":
            return A.Unary("!", x, self.join(op, x))
        if type(x) is A.Unary and x.op == "!" and self.text[x.span.start] != "(":
            raise self.not_here(x.span)
        return self.negative(c)

    def if_then(self, c):
        return A.Binary("->", c[1], c[3], self.join(c[0], c[3]))

    def occurrence(self, c):
        name = "prevOcc" if c[2].type == "PREVIOUS" else "nextOcc"
        return A.Call(name, (c[5], c[6]), self.join(c[0], c[6]))

    # ---- scope
    def mode_name(self, c):
        return A.Var(self.name_of(c[0]), self.span(c[0]))

    def explicit_mode(self, c):
        t = c[1] if c[0].type == "MODE" else c[0]
        return _ExplicitMode(A.Var(self.name_of(t), self.span(t)), self.join(c[0], c[1]))

    def _scope(self, kind, c):
        m = c[-1]
        if isinstance(m, _ExplicitMode):
            return A.Scope(kind, m.var, self.join(c[0], m))
        return A.Scope(kind, m, self.join(c[0], m))

    # ---- condition
    def _part(self, c, connective):
        i = 0
        if connective is not None and c[0].type in ("AND", "OR"):
            connective = c[0].type.lower()
            i = 1
        qualifier = c[i].value.lower()
        expr = c[i + 1]
        last = expr
        negate = qualifier == "unless"
        if len(c) > i + 2:                       # is true / is false
            last = c[i + 3]
            if last.type == "FALSE":
                negate = not negate
        span = self.join(c[0], last)
        if negate:
            expr = A.Unary("!", expr, span)
        return A.ConditionPart(qualifier, expr, connective, span)

    def cond_first(self, c):
        return self._part(c, None)

    def cond_next(self, c):
        return self._part(c, "and")

    def condition(self, c):
        first = c[0]
        parts = c[1:] if isinstance(first, lark.Token) else c
        expr = parts[0].expr
        for p in parts[1:]:
            expr = A.Binary("|" if p.connective == "or" else "&", expr, p.expr,
                            _join(expr.span, p.expr.span))
        kind = "holding" if all(p.qualifier == "whenever" for p in parts) else "regular"
        return A.Condition(kind, expr, tuple(parts), self.join(first, parts[-1]))

    # ---- component, probability, timing, response
    def subject(self, c):
        # [the] NAME shall | shall [the] NAME (NAME or STRING)
        if c[0].type == "SHALL":
            first, t = c[1], c[-1]
        else:
            first, t = c[0], c[-2]
        return _Subject(self.name_of(t), self.join(first, t))

    def probability(self, c):
        op, num = c[2], c[-1]
        value = ("-" if c[-2].type == "MINUS" else "") + num.value
        from fractions import Fraction

        v = Fraction(value)
        rounded = 0 < v < 1 and Fraction(float(v)) in (0, 1)  # '< 1e-400': 0 as a double,
        if rounded:  # what the monitors, the statistics and PRISM compute with
            v = Fraction(float(v))
        if not 0 <= v <= 1 or (op.type == "GT" and v == 1) or (op.type == "LT" and v == 0):
            what = (f"probability {value} is outside [0, 1]" if not 0 <= v <= 1 else
                    f"'{op.value} {value}' is no probability bound: "
                    + (f"{value} is {int(v)} as a double, and " if rounded else "")
                    + "a probability is never " + ("above 1" if v == 1 else "below 0"))
            raise _Fail(self.span(c[-1] if not value.startswith("-") else c[-2]), what,
                        "a probability bound is a number in [0, 1], e.g. "
                        "'with probability >= 0.99'")
        return A.Probability(_BINOPS[op.type], value, self.join(c[0], num))

    def duration(self, c):
        if len(c) == 1:  # a named duration, resolved by fretish.constants
            return A.Duration("", "", self.span(c[0]), name=c[0].value)
        num, unit = c
        if not _DURATION_AMOUNT.match(num.value):
            raise _Fail(self.span(num), f"a duration is a whole or decimal number, not "
                        f"'{num.value}'", "write e.g. 'within 3 seconds' or 'for 2.5 seconds'")
        return A.Duration(num.value, UNIT_TOKENS[unit.type], self.join(num, unit))

    def timing(self, c):
        head, last = c[0], c[-1]
        if head.type == "AT":
            return A.Timing(_AT_TIMINGS[c[2].type], None, None,
                            " ".join(t.value.lower() for t in c), self.join(head, last))
        kind = _SIMPLE_TIMINGS[head.type]
        phrase = head.value.lower()
        if len(c) == 1:
            return A.Timing(kind, None, None, phrase, self.span(head))
        if kind in A.DURATION_TIMINGS:     # a Duration
            return A.Timing(kind, last, None, phrase, self.join(head, last))
        return A.Timing(kind, None, last, phrase, self.join(head, last))

    def response(self, c):
        # (expression, span of "satisfy R"), read by position by sentence()
        return (c[1], self.join(c[0], c[1]))

    # ---- sentences
    def sentence(self, c):
        parts = {type(x): x for x in c[:-1]}
        response, response_span = c[-1]
        subject = parts[_Subject]
        return A.Requirement(self.text, parts.get(A.Scope, A.Scope()),
                             parts.get(A.Condition, A.Condition()), subject.name,
                             parts.get(A.Probability), parts.get(A.Timing, A.Timing()),
                             response, False, subject.span, response_span)

    def freeform(self, c):
        return A.Requirement(self.text, freeform=True)

    def start(self, c):
        return c[0]


for _rule, _kind in _SCOPE_KINDS.items():
    setattr(_Builder, _rule, lambda self, c, _kind=_kind: self._scope(_kind, c))
del _rule, _kind


# --------------------------------------------------------------------------- the parser
def _read_grammar() -> str:
    """The text of ``grammar.lark`` (the only source of the parser tables)."""
    with open(_GRAMMAR_FILE, encoding="utf-8") as f:
        return f.read()


def build_lark(**options: Any) -> lark.Lark:
    """A new Lark parser for ``grammar.lark`` (start symbols ``start`` and ``expr``), LALR
    with the contextual lexer and a new :class:`_Builder` applied while parsing. ``options``
    go to :class:`lark.Lark` (the tests pass ``debug=True`` to see conflicts, :func:`cached_lark`
    ``cache=``). Without ``cache`` it builds the LALR tables from the grammar (about a
    second). Raises :class:`fretc.common.libraries.LibraryError` when the ``lark`` imported
    is not Lark 1.x (ROS 2's lark-parser 0.12 in its place)."""
    check_lark(lark.__version__)
    return lark.Lark(_read_grammar(), transformer=_Builder(), **_LARK_OPTIONS, **options)


def cached_lark() -> lark.Lark:
    """The parser of :func:`build_lark`, its tables kept in fretc's cache folder at
    ``lark/fretish-KEY.lark`` (:func:`fretc.common.lark_tables.cached_parser`: a sealed entry
    of plain data, never unpickled): loaded when there is one for the same grammar, options,
    Lark and Python versions (KEY is a hash of them, so editing the grammar or upgrading Lark
    or Python gives a new entry, never a stale one), else read from the tables shipped with
    fretc (:data:`TABLES_FILE`) when they were made from the same grammar and Lark version,
    else built, and written. An entry that cannot be read or loaded is a miss; when the
    folder cannot be written, or the cache is off (``FRETC_CACHE_DIR=""``), the tables are
    read from the shipped ones or built in memory. Raises
    :class:`fretc.common.libraries.LibraryError` when the ``lark`` imported is not Lark 1.x."""
    check_lark(lark.__version__)
    return cast(lark.Lark, lark_tables.cached_parser(
        "fretish", _read_grammar(), _LARK_OPTIONS, {"transformer": _Builder()}, build_lark,
        shipped=TABLES_FILE))


def tables_text() -> str:
    """The text of :data:`TABLES_FILE`: the tables of a parser built from ``grammar.lark``
    now (:func:`fretc.common.lark_tables.tables_text`)."""
    check_lark(lark.__version__)
    return lark_tables.tables_text("fretish", _read_grammar(), _LARK_OPTIONS, build_lark())


_lock = threading.Lock()
_parser: lark.Lark | None = None


def _run(start: str, text: str, source: str, line: int, column: int,
         letters_as_names: bool = False):
    global _parser
    if not isinstance(text, str):
        raise TypeError(f"parse() wants a str, got {type(text).__name__}")
    with _lock:
        if _parser is None:
            _parser = cached_lark()
        builder = cast(_Builder, _parser.options.transformer)
        builder.begin(text, line, column, letters_as_names)
        try:
            # the transformer (_Builder) makes the tree the AST: a Requirement or an Expr
            result = cast(Any, _parser.parse(text, start=start))
            if start == "start":
                check_requirement(result, frozenset(builder.letter_names))
            else:
                check_expression(result)
            return result
        except (LimitError, _Fail) as f:
            raise make_error(text, source, line, column, f.span.start, f.message, (),
                             f.hint) from None
        except (UnexpectedInput, LarkError) as e:
            builder.begin(text, line, column)  # translate() parses the text again
            raise translate(e, _parser, text, source, line, column, start) from None
        except RecursionError:
            raise make_error(text, source, line, column, 0, "expression nested too deeply",
                             [], "split the requirement or add parentheses") from None
        finally:
            builder.begin("", 1, 1)


def parse(text: str, *, source: str = "<string>", line: int = 1,
          column: int = 1, letters_as_names: bool = False) -> A.Requirement:
    """Parse one FRETish requirement sentence.

    ``text`` is the sentence (a trailing ``.`` is allowed); ``source``, ``line`` and
    ``column`` say where ``text`` starts in its file, so every :class:`~fretc.fretish.ast.Span`
    and error position is in file coordinates (1-based), while ``Span.start``/``end`` are
    0-based offsets into ``text``. A sentence that is one double-quoted string is free
    form: ``Requirement(text, freeform=True)``.

    Returns a :class:`fretc.fretish.ast.Requirement`. Raises :class:`FretishSyntaxError` for any
    text that is not FRETish (FRET 3.x grammar, with the fixes of
    ../shared/fretish/README.md section 7),
    including a probability outside [0, 1], a reserved word used as a name and
    ``preBool`` with a numeric initial value.

    ``letters_as_names``: the letters fretc reserves for the operators of FRET's printed
    formulas (``X F G U V Y Z H O S T``, :data:`fretc.fretish.words.RESERVED_LETTERS`) are
    variables where an expression names them, as in FRET's own grammar, which has no such
    operator (a FRET export: FRET formalized ``T * mag(Vt + Vv)`` in its case studies). The
    name is the letter; the printers quote it (``T`` prints ``_DQT_T_DQT_``), so no printed
    formula reads it as an operator.
    """
    return _run("start", text, source, line, column, letters_as_names)


def parse_expression(text: str, *, source: str = "<string>", line: int = 1,
                     column: int = 1) -> A.Expr:
    """Parse one FRETish expression (../shared/fretish/README.md section 5), e.g.
    ``"x + 1 > y & !p"``; same positions and errors as :func:`parse`."""
    return _run("expr", text, source, line, column)
