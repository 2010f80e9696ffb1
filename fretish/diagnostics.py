"""Syntax errors of FRETish sentences: a Lark failure becomes a
:class:`~fretc.common.errors.FretishSyntaxError` at the right file position, with what the
parser expected in FRETish words ("a timing", "'satisfy'") and a hint for the common
mistakes ('and' in an expression, '==', 'globally', a reserved word as a name, a missing
'shall' or 'satisfy').

LALR parsers may reduce before they notice a bad token, so the expected set Lark reports can
be a later state's; :func:`accepted_before` replays the parse up to the bad token to get the
set at that point (Lark's interactive parser).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from lark import Lark
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from fretc.common.errors import FretishSyntaxError
from fretc.fretish.words import RESERVED_LETTERS, UNIT_TOKENS

__all__ = ["accepted_before", "expected_names", "failure_error", "make_error", "translate"]

# Terminal groups, for the "expected" list and for recognizing the parser's situation.
_OPERAND_START = {"BANG"}
_OPERATORS = {"AMP", "BAR", "XOR", "IMPLIES", "IFF", "PLUS", "STAR", "SLASH", "MOD", "CARET"}
_QUALIFIERS = {"UPON", "WHENEVER", "WHERE"}
_SCOPE_WORDS = {"ONLY", "EXCEPT", "DURING", "WHILE"}
_TIMING_WORDS = {"IMMEDIATELY", "INITIALLY", "FINALLY", "EVENTUALLY", "ALWAYS", "NEVER",
                 "WITHIN", "UNTIL"}
_UNIT_WORDS = set(UNIT_TOKENS)
_COMPARISONS = {"EQ", "NE", "LT", "LE", "GT", "GE"}
_KEYWORD_TYPES = {t.upper() for t in (
    "after always and at before during eventually except false finally first for hour if "
    "immediately in initially is last microsecond millisecond minute mod mode never next not "
    "occurrence of only or previous probability same satisfy second shall the then tick "
    "timepoint true unless until upon when whenever where while with within xor").split()}
_PUNCT = {"_COMMA": "','", "_DOT": "'.'", "RPAR": "')'", "LPAR": "'('", "$END":
          "the end of the sentence"}

_HINT_AND_OR = ("'and'/'or'/'not' are not expression operators in FRETish: write '&', '|' "
                "and '!' ('and'/'or' only chain conditions: 'upon p and when q')")
_HINT_SATISFY = ("the response must follow 'satisfy': "
                 "'... shall [timing] satisfy <condition>'")
_HINT_SHALL = ("a requirement needs 'shall' next to its component: "
               "'[the] component shall ...' or '... shall [the] component ...'")


def expected_names(exp: Iterable[str]) -> list[str]:
    """The terminals ``exp`` (Lark terminal names of ``grammar.lark``) as what a writer of
    FRETish would call them ("a scope", "an expression", "'shall'"), each once, in the
    order of a sentence."""
    exp = set(exp)
    out: list[str] = []

    def add(label):
        if label not in out:
            out.append(label)

    expr_start = "BANG" in exp
    if exp & {"IN", "ONLY", "EXCEPT", "DURING"}:
        add("a scope")
    if exp & _QUALIFIERS:
        add("a condition (upon/when/if/where/unless/whenever ...)")
    if "THE" in exp and not exp & {"NEXT", "PREVIOUS"} and "NAME" in exp:
        add("a component")
    if expr_start:
        add("an expression")
    elif "MODE" in exp and "NAME" in exp:
        add("a mode name")
    elif ("NAME" in exp or "STRING" in exp) and "a component" not in out:
        add("a name")
    if "SHALL" in exp:
        add("'shall'")
    if "WITH" in exp:
        add("a probability ('with probability >= 0.9')")
    if exp & _TIMING_WORDS:
        add("a timing (always, eventually, within N ticks, ...)")
    if "SATISFY" in exp:
        add("'satisfy'")
    if exp & _OPERATORS:
        add("an operator")
    elif exp & _COMPARISONS and "NUMBER" not in exp:
        add("a comparison (<, <=, >, >=, =)")
    if "IS" in exp:
        add("'is true'/'is false'")
    if exp & _UNIT_WORDS:
        add("a time unit (ticks, microseconds, milliseconds, seconds, minutes, hours)")
    if "NUMBER" in exp and not expr_start:
        add("a number")
    if exp == {"TRUE", "FALSE"}:
        add("'true' or 'false'")
    for t in ("THEN", "OF", "TIMEPOINT", "OCCURRENCE", "PROBABILITY", "IN", "MODE"):
        if t in exp and not (t == "IN" and "a scope" in out) and \
                not (t == "MODE" and "a mode name" in out):
            add(f"'{t.lower()}'")
    if exp & {"FIRST", "SAME", "LAST"}:
        add("'first', 'same', 'next' or 'last'")
    for t in ("RPAR", "_COMMA", "_DOT", "$END"):
        if t in exp:
            add(_PUNCT[t])
    return out


def _position(text: str, pos: int) -> tuple[int, int]:
    """1-based line and column of offset ``pos`` in ``text``."""
    line = text.count("\n", 0, pos) + 1
    col = pos - (text.rfind("\n", 0, pos) + 1) + 1
    return line, col


def make_error(text: str, source: str, line0: int, col0: int, pos: int, message: str,
               expected: Sequence[str], hint: str | None) -> FretishSyntaxError:
    """The error at offset ``pos`` of ``text``, which starts at line ``line0``, column
    ``col0`` (1-based) of ``source``: the position in file coordinates, the offending line
    of the text, the ``expected`` names and the ``hint``."""
    tline, tcol = _position(text, pos)
    lines = text.split("\n")
    text_line = lines[tline - 1] if tline - 1 < len(lines) else ""
    fline = tline + line0 - 1
    fcol = tcol + col0 - 1 if tline == 1 else tcol
    return FretishSyntaxError(message, source=source, line=fline, column=fcol,
                              text_line=text_line, expected=expected, hint=hint,
                              text_line_column=col0 if tline == 1 else 1, offset=pos)


_WORD = re.compile(r"[A-Za-z][A-Za-z0-9_.%]*")


def _previous_word(text: str, pos: int) -> str:
    """The word before offset ``pos`` (skipping what is not a word character), from its
    first letter, lower-cased; "" when there is none. Scans backwards from ``pos`` only:
    linear in the word's length (a regular-expression search over ``text[:pos]`` is
    quadratic on a long identifier)."""
    i = pos
    while i > 0 and not (text[i - 1].isalnum() or text[i - 1] == "_"):
        i -= 1
    end = i
    while i > 0 and (text[i - 1].isalnum() or text[i - 1] in "_%"):
        i -= 1
    word = text[i:end]
    m = re.search(r"[A-Za-z]", word)
    return word[m.start():].lower() if m else ""


def accepted_before(parser: Lark, text: str, start: str, pos: int) -> set[str] | None:
    """Terminals ``parser`` accepts just before offset ``pos``, found by replaying the
    parse up to there. (An LALR parser may perform reductions before it notices a bad
    token; the set it reports is then that of a later state, e.g. only "end of sentence"
    after "satisfy p" when it meets "and".) None if the replay fails."""
    try:
        ip = parser.parse_interactive(text, start=start)
        try:
            for tok in ip.iter_parse():
                if tok.start_pos >= pos:  # type: ignore[operator]  # lexer tokens have it
                    break
        except UnexpectedInput:
            pass          # the lexer stopped at pos: the parser state is the one before it
        return set(ip.accepts())
    except Exception:     # pragma: no cover - diagnostics must never fail
        return None


def translate(e: Exception, parser: Lark, text: str, source: str, line: int, column: int,
              start: str = "start") -> FretishSyntaxError:
    """Turn a Lark exception raised by ``parser`` (start symbol ``start``) on ``text``
    into a :class:`FretishSyntaxError` with a hint. Never raises; a Lark failure that is
    not about the input's position is reported at the start of the text."""
    located = _locate(e, text)
    if located is None:  # any other Lark failure: never leak Lark's exception
        return make_error(text, source, line, column, 0, f"cannot parse: {e}", [], None)
    pos, value, ttype, expected = located
    replayed = accepted_before(parser, text, start, pos if value is not None else len(text))
    if replayed:
        expected = replayed
    return failure_error(text, source, line, column, pos, value, ttype, expected)


def failure_error(text: str, source: str, line: int, column: int, pos: int,
                  value: str | None, ttype: str, expected: set) -> FretishSyntaxError:
    """The error of a parse that failed at offset ``pos`` of ``text`` (which starts at
    ``line``, ``column`` of ``source``) on ``value`` (None: the end of the sentence) of
    terminal ``ttype`` (``"CHAR"``: no terminal, ``"$END"``) with the terminals
    ``expected`` there: the message, expected names and hint of the common mistakes
    (:func:`_explain`). Used for Lark's exceptions (:func:`translate`)."""
    f = _Failure(text, pos, value, ttype, expected, expected_names(expected))
    pos, message, names, hint = _explain(f)
    return make_error(text, source, line, column, pos, message, names, hint)


def _locate(e: Exception, text: str) -> tuple[int, str | None, str, set] | None:
    """(offset, offending text or None at the end, terminal type, expected terminals) of
    a Lark failure; None for a failure that is not about a position."""
    if isinstance(e, UnexpectedToken):
        tok = e.token
        if tok.type == "$END":
            return len(text.rstrip()), None, tok.type, set(e.expected or ())
        return tok.start_pos, tok.value, tok.type, set(e.expected or ())
    if isinstance(e, UnexpectedCharacters):
        pos = e.pos_in_stream
        assert pos is not None  # UnexpectedCharacters is made with its position
        m = _WORD.match(text, pos)
        return pos, m.group(0) if m else text[pos], "CHAR", set(e.allowed or ())
    if isinstance(e, UnexpectedEOF):
        return len(text.rstrip()), None, "$END", set(e.expected or ())
    return None


@dataclass
class _Failure:
    """Where and how a parse failed, as :func:`_explain` reads it."""

    text: str
    pos: int
    value: str | None  # the offending text; None at the end of the sentence
    ttype: str  # its terminal type ("CHAR": no terminal matched, "$END")
    expected: set
    names: list[str]

    @property
    def in_expr(self) -> bool:
        return bool(self.expected & (_OPERAND_START | _OPERATORS))

    @property
    def where(self) -> str:
        return " in an expression" if self.in_expr else ""

    @property
    def shown(self) -> str:
        return "end of the sentence" if self.value is None else f"'{self.value}'"


_HINT_GLOBALLY = ("drop it: a requirement without a scope already holds over the whole run "
                  "(the null scope)")
_HINT_UNITS = ("durations are '<number> <unit>' with unit tick(s), microsec(ond)(s), "
               "millisec(ond)(s), sec(ond)(s), minute(s) or hour(s)")


def _explain(f: _Failure) -> tuple[int, str, list[str], str | None]:
    """(offset, message, expected names, hint) of a failure: the common mistakes, most
    specific first, else "unexpected X"."""
    text, pos, value, ttype, expected = f.text, f.pos, f.value, f.ttype, f.expected
    message, names, where = f"unexpected {f.shown}{f.where}", f.names, f.where
    low = (value or "").lower()
    prev = _previous_word(text, pos)
    first = re.match(r"\s*([A-Za-z]+)", text)
    if not text.strip():
        return pos, "empty requirement", [], None
    if first and first.group(1).lower() == "globally" and (
            low == "globally" or prev == "globally"):
        return first.start(1), "'globally' is not FRETish", [], _HINT_GLOBALLY
    if low == "globally":
        return pos, "'globally' is not FRETish", names, _HINT_GLOBALLY
    if value == "=" and pos > 0 and text[pos - 1] == "=":
        return (pos - 1, f"unexpected '=='{where}", names,
                "FRETish equality is a single '=' ('==' is not FRETish)")
    if ttype in ("AND", "OR", "NOT") and (f.in_expr or "NAME" in expected):
        return pos, message, names, _HINT_AND_OR
    if prev in ("and", "or") and expected & {"UPON", "WHEN"} and "NAME" not in expected:
        return pos, f"unexpected {f.shown} after '{prev}'", names, (
            f"after '{prev}' a condition needs its own qualifier ('upon p {prev} when "
            f"q'); to combine expressions write 'p {'&' if prev == 'and' else '|'} q'")
    if prev == "shall" and "THE" in expected and ttype in _KEYWORD_TYPES:
        return (pos, f"unexpected '{value}': the component is missing after 'shall'", names,
                "name the component: '... shall [the] <component> [timing] satisfy ...'")
    if ttype == "IS" and not f.in_expr:
        return pos, message, names, ("'is true'/'is false' may follow a condition (when p "
                                     "is true), not a scope")
    if (ttype in _KEYWORD_TYPES or ttype == "RESERVED") and (
            "NAME" in expected or f.in_expr) and low not in ("shall", "satisfy"):
        kind = ("a temporal operator of FRET's formulas" if value in RESERVED_LETTERS
                else "a reserved word in FRETish")
        return pos, f"unexpected '{value}'{where}: '{value}' is {kind}", names, (
            f"a reserved word cannot name a variable or component: quote it "
            f"(\"{value}\") or rename it")
    if "SATISFY" in expected and ttype != "SATISFY":
        return pos, message, names, _HINT_SATISFY
    if "SHALL" in expected and ttype != "SHALL":
        return pos, message, names, _HINT_SHALL
    if expected & _UNIT_WORDS:
        return pos, message, names, _HINT_UNITS
    if ttype == "CHAR" and value and value[0] == '"':
        return pos, "unterminated quoted name", names, 'close the quote: "name"'
    if ttype == "CHAR" and value is not None:  # a CHAR failure has its character
        return pos, f"unexpected character '{value[0]}'{where}", names, None
    return pos, message, names, None
