"""FRETish sentence -> :class:`fretish.ast.Requirement`.

The grammar is ``grammar.lark`` (Lark, LALR(1), contextual lexer); its header states the
phrasings and the expression precedence. The AST builder is applied while parsing (no
intermediate parse tree). Lark's LALR table, built from the grammar once and kept in fretc's
cache, is run by :class:`fretish.fastparse._FastParser` (a plain loop over the tokens of one
lexer regexp, applied chunk by chunk between spaces; a run of one-symbol reductions is one
dictionary lookup); a sentence it cannot parse goes to Lark itself, which is imported only
then and reports the error (``fretc FILE --emit ltl`` on valid sentences does not import
Lark). Both call the same AST builder (:class:`_Builder`) on tokens as plain tuples.

Readings fixed here (FRET 3.x ``Requirement.g4`` and its semantic listener, restated;
``../shared/fretish/README.md`` sections 1-5 and 7):

* Scope: ``in/during/when in/if in M`` and ``while C`` are ``in``; ``when not in/if not
  in/unless in/except in/except during/except when in/except if in M`` and ``except while
  C`` are ``notin``; ``only`` + an ``in`` phrase is ``onlyIn``; ``[only] after/before`` take
  a mode (``mode M``/``M mode``) or a condition (a bare name is a condition: ``Var`` either
  way). ``Scope.mode`` is the ``Var`` or the expression.
* Condition: parts ``[and|or] qualifier P [is true|is false]`` with optional commas; a
  part negates P when exactly one of "qualifier is unless" and "is false" holds (so
  ``unless P is false`` is P, as in FRET). A later part without ``and``/``or`` is a
  conjunction and records ``connective="and"``; the first part has ``connective=None``.
  Parts fold left (``and`` -> ``&``, ``or`` -> ``|``); ``holding`` iff every part is
  ``whenever``.
* ``is true``/``is false``, ``true``/``false`` in any letter case (FRET defect 4 fixed);
  ``~`` is negation (defect 1); ``if A then B`` is ``A -> B`` everywhere (defect 2);
  ``preBool`` with a numeric initial value is an error (defect 3).
* A minus sign written against a number literal, in operand position, is part of the
  literal, as in FRET's lexer: ``-3.0e2`` is ``NumLit("-3.0e2")`` and ``-3 ^ 2`` is
  ``(-3) ^ 2``; ``- 3``, ``-(3)`` and ``-x`` are ``Unary("-")``, which binds looser than
  ``^`` (``-x ^ 2`` is ``-(x ^ 2)``). After an operand, ``-`` is subtraction (``x -3`` is
  ``x - 3``; FRET's lexer would read a number ``-3`` there and reject the sentence).
* Spans: ``line``/``column`` in file coordinates (``parse(..., line=, column=)`` give where
  the text starts), ``start``/``end`` 0-based offsets into the text. A ``Scope``,
  ``Condition``, ``Timing`` or ``Probability`` span covers its words without the optional
  commas; ``Requirement.component_span`` covers ``[the] name`` and ``response_span``
  covers ``satisfy R`` (FRET's text ranges). A parenthesized expression's span includes
  its parentheses.
"""

from __future__ import annotations

import io
import os
import re
import sys
import threading

from . import ast as A
from common import cache
from .fastparse import _FastParser, fast_tables
from .limits import LimitError, check_expression, check_requirement
from .positions import _ctx, _Fail, _join, _mk, _new_span, _span_of
from .words import RESERVED_LETTERS, RESERVED_WORDS, UNIT_TOKENS

__all__ = ["parse", "parse_expression", "build_lark", "cached_lark", "RESERVED_WORDS",
           "RESERVED_LETTERS"]

_GRAMMAR_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "grammar.lark")

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
_DURATION_AMOUNT = re.compile(r"[0-9]+(?:\.[0-9]+)?\Z")


# --------------------------------------------------------------------------- positions
#: Held by :func:`_run` while a text is parsed (fast path or Lark): :data:`_ctx` is shared.
_parsing = threading.Lock()
_new = object.__new__


class _Subject:
    __slots__ = ("name", "span")

    def __init__(self, name: str, span: A.Span):
        self.name, self.span = name, span


class _ExplicitMode:
    """``mode M`` / ``M mode``: the mode variable and the phrase's span."""
    __slots__ = ("var", "span")

    def __init__(self, var: A.Var, span: A.Span):
        self.var, self.span = var, span


def _unquote(tok) -> str:
    body = tok[1][1:-1]
    if "\\" in body:
        body = body.replace('\\"', '"').replace("\\\\", "\\")
    return body


def _name_of(tok) -> str:
    if tok[0] == "STRING":
        name = _unquote(tok)
        if not name.strip():
            raise _Fail(tok, "an empty quoted name", "write a name between the quotes")
        return name
    return tok[1]


def _respan(node, span: A.Span):
    """``dataclasses.replace(node, span=span)`` for an AST node (whose ``__init__`` only
    stores its fields in its ``__dict__``), without the generic machinery."""
    new = object.__new__(node.__class__)
    d = new.__dict__
    d.update(node.__dict__)
    d["span"] = span
    return new


def _is_numeric_literal(e) -> bool:
    if isinstance(e, A.NumLit):
        return True
    if isinstance(e, A.Unary):
        return e.op == "-"
    return isinstance(e, A.Binary) and e.op in A.ARITH_OPS


# --------------------------------------------------------------------------- precedence
#: Binary operators: (precedence, right-associative); higher binds tighter (README
#: section 5, FRET's LTL grammar): <-> 1, -> 2 (right), xor 3, | 4, & 5, comparisons 7
#: (non-associative), + - 8, * / mod 9, ^ 11 (right). Prefix "!" takes an operand of
#: precedence >= 6 (a comparison or arithmetic), prefix "-" one of precedence >= 10 (^).
_PREC = {"IFF": (1, False), "IMPLIES": (2, True), "XOR": (3, False), "BAR": (4, False),
         "AMP": (5, False), "EQ": (7, False), "NE": (7, False), "LT": (7, False),
         "LE": (7, False), "GT": (7, False), "GE": (7, False), "PLUS": (8, False),
         "MINUS": (8, False), "STAR": (9, False), "SLASH": (9, False), "MOD": (9, False),
         "CARET": (11, True)}
_CMP = 7
_NOT_OPERAND = 6
_NEG_OPERAND = 10


def _climb(c: list, i: int, min_prec: int):
    """Precedence climbing over a flat chain ``c`` of operands and binary-operator tokens
    (grammar rule ``chain_ops``), from index ``i``, folding the operators of precedence
    >= ``min_prec``. Returns (node, next index). ``c`` is modified."""
    left, i = _operand(c, i, min_prec)
    n = len(c)
    while i < n:
        op = c[i]
        prec, right_assoc = _PREC[op[0]]
        if prec < min_prec:
            break
        right, i = _climb(c, i + 1, prec if right_assoc else prec + 1)
        left = A.Binary(_BINOPS[op[0]], left, right, _mk(left.span[4], right.span[5]))
        if prec == _CMP and i < n and _PREC[c[i][0]][0] == _CMP:
            raise _Fail(c[i], f"comparisons do not chain: unexpected '{c[i][1]}' after "
                        "a comparison",
                        "compare twice and join with '&': 'a < b & b < c'")
    return left, i


def _operand(c: list, i: int, min_prec: int):
    """The operand at ``c[i]``. A negation or unary minus written without parentheses
    (built by rule ``prefixed`` as if it stood alone) is re-attached here to everything
    it governs in the chain: "!" takes operators of precedence >= 6, "-" only "^"."""
    x = c[i]
    if type(x) is not A.Unary or _ctx.text[x.span.start] == "(":
        return x, i + 1
    if x.op == "!":
        if min_prec > _NOT_OPERAND:
            raise _not_here(x)
        c[i] = x.operand
        operand, i = _climb(c, i, _NOT_OPERAND)
    else:
        c[i] = x.operand
        operand, i = _climb(c, i, _NEG_OPERAND)
    return A.Unary(x.op, operand, _join(x, operand)), i


def _shunt(c: list):
    """:func:`_climb`'s tree for chain ``c`` built without recursion (operator precedence by
    a stack of pending operators: a shunting-yard), when it is a plain precedence chain:
    at most one comparison, and every prefix operand written without parentheses ("!p",
    "-x") is followed by no operator it would take (precedence >= 6 for "!", >= 10 for
    "-") and, for "!", stands where a negation may (after no operator of precedence >= 6
    and no "^"): :func:`_operand` then returns a node equal to it, spans included.
    None otherwise (:func:`_climb` decides, errors included)."""
    text = _ctx.text
    n = len(c)
    min_prec = 1
    comparisons = 0
    for i in range(0, n, 2):
        x = c[i]
        if i + 1 < n:
            prec, right_assoc = _PREC[c[i + 1][0]]
        else:
            prec, right_assoc = 0, False
        if type(x) is A.Unary and text[x.span[4]] != "(":
            if x.op == "!":
                if min_prec > _NOT_OPERAND or prec >= _NOT_OPERAND:
                    return None
            elif prec >= _NEG_OPERAND:
                return None
        if prec == _CMP:
            comparisons += 1
            if comparisons > 1:
                return None
        min_prec = prec if right_assoc else prec + 1
    out = [c[0]]
    pending: list = []         # (precedence, operator token), precedences increasing
    for i in range(1, n, 2):
        op = c[i]
        prec, right_assoc = _PREC[op[0]]
        while pending and (pending[-1][0] > prec or (pending[-1][0] == prec
                                                     and not right_assoc)):
            right = out.pop()
            left = out[-1]
            out[-1] = A.Binary(_BINOPS[pending.pop()[1][0]], left, right,
                               _mk(left.span[4], right.span[5]))
        pending.append((prec, op))
        out.append(c[i + 1])
    while pending:
        right = out.pop()
        left = out[-1]
        out[-1] = A.Binary(_BINOPS[pending.pop()[1][0]], left, right,
                           _mk(left.span[4], right.span[5]))
    return out[0]


def _not_here(x) -> "_Fail":
    bang = _ctx.text[x.span.start]
    return _Fail(x, f"unexpected '{bang}' in an expression: a negation cannot be an operand "
                 "of an arithmetic or comparison operator",
                 f"put the negated part in parentheses: '({bang}p)'")


# --------------------------------------------------------------------------- AST builder
class _Builder:
    """Lark callbacks, one per grammar rule or alias; each gets the rule's children (AST
    nodes, helper objects and the named keyword tokens)."""

    # ---- expressions
    # number and var, the most frequent nodes, are made as A.NumLit / A.Var and _mk would
    # make them, written out (no Python-level __init__ or _mk call)
    def number(self, c):
        t = c[0]
        node = _new(A.NumLit)
        d = node.__dict__
        d["text"] = t[1]
        flat = _ctx.flat
        if flat is None:
            d["span"] = _mk(t[2], t[3])
        else:
            line, col = flat
            d["span"] = _new_span((line, t[2] + col, line, t[3] + col, t[2], t[3]))
        return node

    def var(self, c):
        t = c[0]
        node = _new(A.Var)
        d = node.__dict__
        d["name"] = t[1] if t[0] == "NAME" else _name_of(t)
        flat = _ctx.flat
        if flat is None:
            d["span"] = _mk(t[2], t[3])
        else:
            line, col = flat
            d["span"] = _new_span((line, t[2] + col, line, t[3] + col, t[2], t[3]))
        return node

    def boolean(self, c):
        t = c[0]
        return A.BoolLit(t[0] == "TRUE", _mk(t[2], t[3]))

    def reserved(self, c):
        t = c[0]
        w = t[1]
        if w.lower() == "what":
            raise _Fail(t, "'what' is a reserved word in FRETish (probability queries)",
                        f"quote it (\"{w}\") or rename the variable")
        raise _Fail(t, f"'{w}' is reserved: it is a temporal operator of FRET's formulas",
                    f"quote it (\"{w}\") or rename the variable")

    def paren(self, c):
        # the parentheses belong to the expression's span
        return _respan(c[1], _mk(c[0][2], c[2][3]))

    def call(self, c):
        name, rpar = c[0], c[-1]
        args = tuple(c[2:-1])
        if name[1] == "preBool" and args and _is_numeric_literal(args[0]):
            init = args[0]
            shown = _ctx.text[init.span.start:init.span.end]
            raise _Fail(init, f"preBool's initial value must be true or false, not '{shown}'",
                        "preBool(init, p) is init at the first step and p one step earlier "
                        "afterwards; write preBool(false, p) or preBool(true, p) (FRET "
                        "prints 'undefined' for a numeric initial value)")
        return A.Call(name[1], args, _join(name, rpar))

    def prefixed(self, c):               # ! p, ~ p, - x (as if standing alone)
        op, x = c
        if op[0] == "BANG":
            return A.Unary("!", x, _join(op, x))
        if type(x) is A.Unary and x.op == "!" and _ctx.text[x.span.start] != "(":
            raise _not_here(x)
        if type(x) is A.NumLit and x.span.start == op[3] \
                and _ctx.text[op[3]] != "(" and not x.text.startswith("-"):
            # a minus written against a number literal is part of it, as in FRET's
            # lexer: -3 ^ 2 is (-3) ^ 2, while - 3 ^ 2 and -x ^ 2 negate the power
            return A.NumLit("-" + x.text, _join(op, x))
        return A.Unary("-", x, _join(op, x))

    def chain_ops(self, c):              # operands and operators, collected left to right
        first = c[0]
        if type(first) is list:
            first.extend(c[1:])
            return first
        return c

    open_ops = chain_ops                 # a chain ending in a prefix form (if-then ...)

    def climb(self, c):
        c = c[0]
        left = c[0]
        n = len(c)
        if type(left) is not A.Unary:
            # one operator, or several of one left-associative precedence that is not the
            # comparisons', and no prefix operand: _climb's result is a left fold
            prec = _PREC[c[1][0]]
            if n == 3 or not (prec[1] or prec[0] == _CMP):
                for i in range(2, n, 2):
                    if type(c[i]) is A.Unary or (i + 1 < n and _PREC[c[i + 1][0]] != prec):
                        break
                else:
                    start = left.span[4]
                    for i in range(1, n, 2):
                        right = c[i + 1]
                        left = A.Binary(_BINOPS[c[i][0]], left, right,
                                        _mk(start, right.span[5]))
                    return left
        node = _shunt(c)
        if node is None:
            node, _ = _climb(c, 0, 1)
        return node

    def if_then(self, c):
        return A.Binary("->", c[1], c[3], _join(c[0], c[3]))

    def occurrence(self, c):
        name = "prevOcc" if c[2][0] == "PREVIOUS" else "nextOcc"
        return A.Call(name, (c[5], c[6]), _join(c[0], c[6]))

    # ---- scope
    def mode_name(self, c):
        t = c[0]
        return A.Var(_name_of(t), _mk(t[2], t[3]))

    def explicit_mode(self, c):
        t = c[1] if c[0][0] == "MODE" else c[0]
        return _ExplicitMode(A.Var(_name_of(t), _span_of(t)), _join(c[0], c[1]))

    def _scope(self, kind, c):
        m = c[-1]
        if isinstance(m, _ExplicitMode):
            return A.Scope(kind, m.var, _mk(c[0][2], m.span[5]))
        return A.Scope(kind, m, _mk(c[0][2], m.span[5]))

    # one Lark callback per scope rule, all through _scope (kept: Lark wants a method per rule)
    def in_scope(self, c):
        return self._scope("in", c)

    def notin_scope(self, c):
        return self._scope("notin", c)

    def onlyin_scope(self, c):
        return self._scope("onlyIn", c)

    def after_scope(self, c):
        return self._scope("after", c)

    def before_scope(self, c):
        return self._scope("before", c)

    def onlyafter_scope(self, c):
        return self._scope("onlyAfter", c)

    def onlybefore_scope(self, c):
        return self._scope("onlyBefore", c)

    # ---- condition
    @staticmethod
    def _part(c, connective):
        i = 0
        if connective is not None and c[0][0] in ("AND", "OR"):
            connective = c[0][0].lower()
            i = 1
        q = c[i]
        qualifier = q[1].lower()
        expr = c[i + 1]
        last = expr
        negate = qualifier == "unless"
        if len(c) > i + 2:                       # is true / is false
            last = c[i + 3]
            if last[0] == "FALSE":
                negate = not negate
        span = _join(c[0], last)
        if negate:
            expr = A.Unary("!", expr, span)
        return A.ConditionPart(qualifier, expr, connective, span)

    def cond_first(self, c):
        return self._part(c, None)

    def cond_next(self, c):
        return self._part(c, "and")

    def condition(self, c):
        first = c[0]
        parts = c[1:] if type(first) is tuple else c
        if len(parts) == 1:      # one part (most conditions): the loops below, unrolled
            p = parts[0]
            return A.Condition("holding" if p.qualifier == "whenever" else "regular", p.expr,
                               (p,), _mk(first[2] if type(first) is tuple else p.span[4],
                                         p.span[5]))
        expr = parts[0].expr
        for p in parts[1:]:
            expr = A.Binary("|" if p.connective == "or" else "&", expr, p.expr,
                            _join(expr, p.expr))
        kind = "holding" if all(p.qualifier == "whenever" for p in parts) else "regular"
        return A.Condition(kind, expr, tuple(parts), _join(first, parts[-1]))

    # ---- component, probability, timing, response
    def subject(self, c):
        # [the] NAME shall | shall [the] NAME (NAME or STRING)
        if c[0][0] == "SHALL":
            first, t = c[1], c[-1]
        else:
            first, t = c[0], c[-2]
        return _Subject(t[1] if t[0] == "NAME" else _name_of(t), _mk(first[2], t[3]))

    def probability(self, c):
        op, num = c[2], c[-1]
        value = ("-" if c[-2][0] == "MINUS" else "") + num[1]
        if op[0] == "NE":
            raise _Fail(op, "a probability bound uses <, <=, >, >= or =, not '!='",
                        "write e.g. 'with probability >= 0.99'")
        from fractions import Fraction  # lazy: probabilities are rare (start-up time)

        v = Fraction(value)
        if not 0 <= v <= 1 or (op[0] == "GT" and v == 1) or (op[0] == "LT" and v == 0):
            what = (f"probability {value} is outside [0, 1]" if not 0 <= v <= 1 else
                    f"'{op[1]} {value}' is no probability bound: a probability is never "
                    + ("above 1" if v == 1 else "below 0"))
            raise _Fail(c[-1] if not value.startswith("-") else c[-2], what,
                        "a probability bound is a number in [0, 1], e.g. "
                        "'with probability >= 0.99'")
        return A.Probability(_BINOPS[op[0]], value, _join(c[0], num))

    def duration(self, c):
        num, unit = c
        amount = num[1]
        # (a NUMBER token is ASCII: isdigit() is [0-9]+, the common case, without the regexp)
        if not amount.isdigit() and not _DURATION_AMOUNT.match(amount):
            raise _Fail(num, f"a duration is a whole or decimal number, not '{num[1]}'",
                        "write e.g. 'within 3 seconds' or 'for 2.5 seconds'")
        return A.Duration(num[1], UNIT_TOKENS[unit[0]], _mk(num[2], unit[3]))

    def timing(self, c):
        head = c[0]
        last = c[-1]
        if head[0] == "AT":
            return A.Timing(_AT_TIMINGS[c[2][0]], None, None,
                            " ".join(t[1].lower() for t in c), _mk(head[2], last[3]))
        kind = _SIMPLE_TIMINGS[head[0]]
        phrase = head[1].lower()
        if len(c) == 1:
            return A.Timing(kind, None, None, phrase, _mk(head[2], head[3]))
        if kind in A.DURATION_TIMINGS:     # a Duration
            return A.Timing(kind, last, None, phrase, _mk(head[2], last.span[5]))
        return A.Timing(kind, None, last, phrase, _join(head, last))

    def response(self, c):
        # (expression, span of "satisfy R"): always the sentence's last part, so a plain
        # pair (sentence reads it by position)
        return (c[1], _mk(c[0][2], c[1].span[5]))

    # ---- sentences
    def sentence(self, c):
        # the fields by the class of each part (an absent part: the null one, which is
        # never modified, so one is shared as Requirement's own defaults are)
        parts = [_NULL_SCOPE, _NULL_CONDITION, None, None, _NULL_TIMING]
        for x in c:
            i = _SENTENCE_PARTS.get(type(x))
            if i is not None:
                parts[i] = x
        scope, condition, subject, probability, timing = parts
        response, response_span = c[-1]
        return A.Requirement(_ctx.text, scope, condition, subject.name, probability, timing,
                             response, False, subject.span, response_span)

    def freeform(self, c):
        return A.Requirement(_ctx.text, freeform=True)

    def start(self, c):
        return c[0]


def _lark_callback(f):
    def callback(self, c):
        # a lark.Token is a str; nothing the builder returns is
        return f(self, [(x.type, str(x), x.start_pos, x.end_pos) if isinstance(x, str) else x
                        for x in c])
    callback.__name__ = f.__name__
    return callback


class _LarkBuilder(_Builder):
    """The :class:`_Builder` as Lark's transformer: each callback first turns Lark's tokens
    into the builder's token tuples (``lark.Token`` ``type``, text, ``start_pos``,
    ``end_pos``), so Lark and the fast path run the same code on the same values (Lark is
    the reference the fast path is tested against, and reports every error)."""


for _name, _f in list(vars(_Builder).items()):
    if not _name.startswith("_") and callable(_f):
        setattr(_LarkBuilder, _name, _lark_callback(_f))
del _name, _f


_SENTENCE_PARTS = {A.Scope: 0, A.Condition: 1, _Subject: 2, A.Probability: 3, A.Timing: 4}
_NULL_SCOPE, _NULL_CONDITION, _NULL_TIMING = A.Scope(), A.Condition(), A.Timing()


# --------------------------------------------------------------------------- the parser
_lock = threading.RLock()
_lark = None          # the lark.Lark parser (loaded on first need: errors, no fast path)
_fast = None          # the _FastParser, False when it cannot be used


_LARK_OPTIONS = dict(parser="lalr", lexer="contextual", start=["start", "expr"],
                     maybe_placeholders=False)


def _import_lark():
    """Import Lark (on first need: ``fretc FILE --emit ltl`` on valid sentences runs without
    it)."""
    import lark
    return lark


def _lark_version() -> str:
    """The installed Lark's version, read from its ``__init__.py`` without importing Lark
    (importing it costs more than parsing a hundred sentences); imports it when that fails.

    The file is found as the import system finds it: Lark's own module when it is imported
    already, else ``sys.path``'s finder (:class:`importlib.machinery.PathFinder`, loaded
    with Python's start-up), else :func:`importlib.util.find_spec` (any other finder; that
    module costs about 0.3 ms to import)."""
    try:
        spec = getattr(sys.modules.get("lark"), "__spec__", None)
        if spec is None:
            from importlib.machinery import PathFinder

            spec = PathFinder.find_spec("lark")
        if spec is None:
            import importlib.util

            spec = importlib.util.find_spec("lark")
        with open(spec.origin, encoding="utf-8") as f:
            text = f.read()
        m = re.search(r"^__version__\s*(?::\s*str\s*)?=\s*[\"']([^\"']+)[\"']", text, re.M)
        if m:
            return m.group(1)
    except (AttributeError, OSError, TypeError, ValueError, ImportError):
        pass
    return _import_lark().__version__


def _read_grammar() -> str:
    """The text of ``grammar.lark`` (the only source of the parser tables)."""
    with open(_GRAMMAR_FILE, encoding="utf-8") as f:
        return f.read()


def _cache_key(grammar: str) -> str:
    return cache.key_of("fretish-lark-2", grammar, _lark_version(),
                        "%d.%d" % sys.version_info[:2], repr(sorted(_LARK_OPTIONS.items())))


def build_lark(**options):
    """A new Lark parser for ``grammar.lark`` (start symbols ``start`` and ``expr``), LALR
    with the contextual lexer and the AST builder applied while parsing. ``options`` go
    to :class:`lark.Lark` (the tests pass ``debug=True`` to see conflicts). Builds the LALR
    tables from the grammar (about a second); :func:`cached_lark` loads them instead."""
    lark = _import_lark()
    return lark.Lark(_read_grammar(), transformer=_LarkBuilder(),
                     **_LARK_OPTIONS, **options)


def cached_lark():
    """The parser of :func:`build_lark`, with its LALR tables loaded from fretc's disk
    cache (:mod:`common.cache`, sub-folder ``lark``) when an entry for this grammar text,
    Lark version, Python version and these options is there, else built and stored
    (``Lark.save`` / ``Lark.load``, Lark's documented serialization; loading takes a few
    milliseconds where building the tables takes about a second).

    ``grammar.lark`` stays the only source: the entry's name is a hash of everything the
    tables depend on, so editing the grammar or upgrading Lark or Python gives a new entry,
    never a stale one. Entries are written atomically (:func:`common.cache.write_bytes`);
    an entry that cannot be read or loaded is ignored and rebuilt, and when the cache
    folder cannot be written the tables are built in memory as :func:`build_lark` does."""
    lark = _import_lark()
    grammar = _read_grammar()
    name = f"grammar-{_cache_key(grammar)[:40]}.pickle"
    data = cache.read_bytes("lark", name)
    if data is not None:
        try:
            parser = lark.Lark.load(io.BytesIO(data))
            if type(parser.options.transformer) is _LarkBuilder:
                return parser
        except Exception:  # a damaged or foreign entry: rebuild it  # noqa: BLE001
            pass
    parser = build_lark()
    buf = io.BytesIO()
    try:
        parser.save(buf)
    except Exception:  # noqa: BLE001 - not serializable here: keep the built parser
        return parser
    cache.write_bytes("lark", name, buf.getvalue())
    return parser


def _get_parser():
    global _lark
    if _lark is None:
        with _lock:
            if _lark is None:
                _lark = cached_lark()
    return _lark


#: The format of :func:`fast_tables`'s data (part of its cache entry's name).
_FAST_FORMAT = "v5"


#: Where the fast path's tables are kept first: beside the package, as Python keeps its
#: ``.pyc`` files (so emptying fretc's cache folder, as a "cold" run does, does not mean
#: building the LALR tables again, about a second). None: only fretc's cache folder.
_PACKAGE_CACHE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "__pycache__")


def _load_fast():
    """The :class:`_FastParser` from its cache entry (built from Lark's tables, and stored,
    when missing), or False when it cannot be used.

    The entry (plain data, :func:`fast_tables`, marshalled) holds the grammar text, Lark's
    and Python's versions and the data format it was built from (its name is a CRC of
    them), and is used only when they are this run's, so it is never stale; a CRC-32 of the entry's
    bytes precedes them, so an altered entry is rebuilt, not used.
    It is read from :data:`_PACKAGE_CACHE`, else from fretc's cache folder
    (:mod:`common.cache`, sub-folder ``lark``); a new entry is written beside the package
    unless that folder cannot be written or Python writes no bytecode
    (``PYTHONDONTWRITEBYTECODE``), and then to fretc's cache folder. An entry that cannot be
    loaded is ignored and written again."""
    import marshal  # plain data only; the identity names the Python version (its format)
    import zlib
    grammar = _read_grammar()
    # Everything the tables depend on, stored in the entry and compared on loading (exact,
    # and no SHA-256 at start-up: loading OpenSSL costs more than reading the entry)
    identity = "\n".join((_FAST_FORMAT, _lark_version(), "%d.%d" % sys.version_info[:2],
                          repr(sorted(_LARK_OPTIONS.items())), grammar))
    name = f"grammar-{zlib.crc32(identity.encode('utf-8')):08x}-{_FAST_FORMAT}.fast.marshal"
    beside = None if _PACKAGE_CACHE is None else os.path.join(_PACKAGE_CACHE, name)
    for data in (None if beside is None else cache.read_file(beside),
                 cache.read_bytes("lark", name)):
        # the first 4 bytes are a CRC-32 of the rest: an altered table that still
        # unmarshals would parse sentences wrongly, so it is rebuilt, never used
        if data is not None and len(data) > 4 and zlib.crc32(data[4:]) == int.from_bytes(
                data[:4], "big"):
            try:
                tables = marshal.loads(data[4:])
                if tables["identity"] == identity:
                    return _FastParser(tables, _Builder())
            except Exception:  # a damaged entry: rebuild it  # noqa: BLE001
                pass
    tables = fast_tables(_get_parser(), _Builder())
    if tables is None:
        return False
    tables["identity"] = identity
    body = marshal.dumps(tables)
    data = zlib.crc32(body).to_bytes(4, "big") + body
    if beside is None or sys.dont_write_bytecode or not cache.write_file(beside, data):
        cache.write_bytes("lark", name, data)
    return _FastParser(tables, _Builder())


def _get_fast():
    global _fast
    if _fast is None:
        with _lock:
            if _fast is None:
                _fast = _load_fast()
    return _fast


def _run(start: str, text: str, source: str, line: int, column: int):
    if not isinstance(text, str):
        raise TypeError(f"parse() wants a str, got {type(text).__name__}")
    fast = _fast if _fast is not None else _get_fast()
    with _parsing:
        if fast:
            _ctx.set(text, line - 1, column - 1)
            try:
                result = fast.parse(text, start)
                if start == "start":
                    check_requirement(result)
                else:
                    check_expression(result)
                return result
            except Exception:  # noqa: BLE001 - Lark decides, with its exact error
                pass
            finally:
                _ctx.text = ""
        return _run_slow(start, text, source, line, column)


def _run_slow(start: str, text: str, source: str, line: int, column: int):
    """A text the fast path did not parse: its syntax error as Lark gives it, replayed on
    the fast path's tables without Lark where that is exact
    (:func:`fretish.fasterrors.lark_failure`: no Lark import, table load or lexer scanners,
    about 0.2 s of CPU per run with a typo); else Lark itself (:func:`_run_lark`)."""
    fast = _fast
    if fast:
        from .diagnostics import failure_error, make_error
        from .fasterrors import lark_failure

        _ctx.set(text, line - 1, column - 1)
        try:
            failure = lark_failure(fast, text, start, own=(_Fail,))
        except _Fail as f:  # as _run_lark reports it
            s = f.span
            raise make_error(text, source, line, column, s.start, f.message, (),
                             f.hint) from None
        finally:
            _ctx.text = ""
        if failure is not None:
            pos, value, ttype, expected = failure
            raise failure_error(text, source, line, column, pos, value, ttype,
                                expected) from None
    return _run_lark(start, text, source, line, column)


def _run_lark(start: str, text: str, source: str, line: int, column: int):
    """Parse with Lark itself (the reference; every error is reported from here)."""
    from lark.exceptions import LarkError, UnexpectedInput

    from .diagnostics import make_error, translate
    lark = _get_parser()
    _ctx.set(text, line - 1, column - 1)
    try:
        result = lark.parse(text, start=start)
        if start == "start":
            check_requirement(result)
        else:
            check_expression(result)
        return result
    except LimitError as f:
        raise make_error(text, source, line, column, f.span.start, f.message, (),
                         f.hint) from None
    except _Fail as f:
        s = f.span
        raise make_error(text, source, line, column, s.start, f.message, (), f.hint) from None
    except (UnexpectedInput, LarkError) as e:
        raise translate(e, lark, text, source, line, column, start) from None
    except RecursionError:
        raise make_error(text, source, line, column, 0,
                          "expression nested too deeply", [],
                          "split the requirement or add parentheses") from None
    finally:
        _ctx.text = ""


def parse(text: str, *, source: str = "<string>", line: int = 1,
          column: int = 1) -> A.Requirement:
    """Parse one FRETish requirement sentence.

    ``text`` is the sentence (a trailing ``.`` is allowed); ``source``, ``line`` and
    ``column`` say where ``text`` starts in its file, so every :class:`~fretish.ast.Span`
    and error position is in file coordinates (1-based), while ``Span.start``/``end`` are
    0-based offsets into ``text``. A sentence that is one double-quoted string is free
    form: ``Requirement(text, freeform=True)``.

    Returns a :class:`fretish.ast.Requirement`. Raises :class:`FretishSyntaxError` for any
    text that is not FRETish (FRET 3.x grammar, with the fixes of
    ../shared/fretish/README.md section 7),
    including a probability outside [0, 1], a reserved word used as a name and
    ``preBool`` with a numeric initial value.
    """
    return _run("start", text, source, line, column)


def parse_expression(text: str, *, source: str = "<string>", line: int = 1,
                     column: int = 1) -> A.Expr:
    """Parse one FRETish expression (../shared/fretish/README.md section 5), e.g.
    ``"x + 1 > y & !p"``; same positions and errors as :func:`parse`."""
    return _run("expr", text, source, line, column)
