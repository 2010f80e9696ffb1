"""Tests of FRETish syntax errors and their diagnostics (fretish.diagnostics, common.errors):
positions, carets, what was expected and the hints."""

from __future__ import annotations

import pytest

from fretc.fretish import FretishSyntaxError, parse
from fretc.fretish import ast as A



def error_of(text, **kw) -> FretishSyntaxError:
    with pytest.raises(FretishSyntaxError) as info:
        parse(text, **kw)
    return info.value


# --------------------------------------------------------------------------- diagnostics
@pytest.mark.tor("TOR-GRM-002")
def test_error_rendering_like_a_compiler():
    e = error_of("the sw shall always satisfy p and q", source="r1.fret", line=3, column=5)
    assert (e.source, e.line, e.column) == ("r1.fret", 3, 5 + 30)
    assert e.message == "unexpected 'and' in an expression"
    lines = str(e).split("\n")
    assert lines[0] == "r1.fret:3:35: error: unexpected 'and' in an expression"
    assert lines[1] == "the sw shall always satisfy p and q"
    assert lines[2] == " " * 30 + "^"
    assert lines[3].startswith("expected: ") and "an operator" in lines[3]
    assert lines[4].startswith("hint: ") and "'&'" in lines[4]


@pytest.mark.parametrize("text,col,needle", [
    ("globally the sw shall always satisfy p", 1, "globally"),
    ("Globally, upon p the sw shall always satisfy q", 1, "globally"),
    ("the sw shall globally satisfy p", 14, "globally"),
])
def test_hint_globally(text, col, needle):
    e = error_of(text)
    assert e.column == col and needle in e.message and "whole run" in e.hint


@pytest.mark.parametrize("text,word", [
    ("the sw shall always satisfy p and q", "and"),
    ("the sw shall always satisfy p or q", "or"),
    ("the sw shall always satisfy not p", "not"),
    ("upon p and q the sw shall always satisfy r", "and"),
    ("upon p or q the sw shall always satisfy r", "or"),
])
def test_hint_and_or_not(text, word):
    e = error_of(text)
    assert e.column == text.index(f" {word} ") + 2 + (len(word) + 1 if text.startswith("upon") else 0)
    assert e.hint and ("&" in e.hint or "|" in e.hint)
    assert word in e.message or word in e.hint


def test_hint_double_equals():
    e = error_of("the sw shall always satisfy x == 3")
    assert e.column == len("the sw shall always satisfy x ") + 1
    assert "'=='" in e.message and "'='" in e.hint


@pytest.mark.parametrize("text,word,col", [
    ("the sw shall always satisfy next", "next", 29),
    ("the sw shall always satisfy p & mode", "mode", 33),
    ("upon first the sw shall satisfy p", "first", 6),
    ("the mode shall satisfy p", "mode", 5),
    ("the sw shall always satisfy X | p", "X", 29),
    ("the sw shall always satisfy what", "what", 29),
])
def test_hint_reserved_word(text, word, col):
    e = error_of(text)
    assert e.column == col
    assert f'"{word}"' in e.hint and "rename" in e.hint


def test_hint_missing_satisfy():
    e = error_of("the sw shall always p")
    assert e.column == 21 and "'satisfy'" in e.expected and "satisfy" in e.hint
    e = error_of("the sw shall eventually")
    assert e.column == 24 and "end of the sentence" in e.message and "satisfy" in e.hint


def test_hint_missing_shall():
    e = error_of("the sw always satisfy p")
    assert e.column == 8 and e.expected == ["'shall'"] and "shall" in e.hint
    e = error_of("upon p the sw must always satisfy q")
    assert e.column == 15 and "shall" in e.hint


@pytest.mark.tor("TOR-GRM-002")
def test_hint_probability():
    e = error_of("the sw shall with probability >= 1.5 always satisfy q", line=2, column=4)
    assert (e.line, e.column) == (2, 4 + 33) and "outside [0, 1]" in e.message
    assert "[0, 1]" in e.hint


@pytest.mark.tor("TOR-GRM-002")
def test_errors_on_later_lines():
    e = error_of("the sw shall\n   always satisfy p\n   & & q", source="x.fret", line=10,
                 column=20)
    assert (e.line, e.column) == (12, 6) and e.text_line == "   & & q"
    assert str(e).split("\n")[2] == "     ^"


def test_unexpected_characters_and_strings():
    e = error_of("the sw shall always satisfy p @ q")
    assert e.column == 31 and "'@'" in e.message
    e = error_of('the sw shall always satisfy "open')
    assert e.column == 29 and "quote" in e.message
    e = error_of("")
    assert e.message == "empty requirement"


@pytest.mark.tor("TOR-GRM-002")
def test_no_lark_exception_escapes():
    import lark
    for text in ["", "(", ")", "shall", "the", '"', "upon", "in", "the sw shall satisfy (((",
                 "\x00", "the sw shall satisfy p\x00", "when in m is", "upon p,,", "é"]:
        try:
            parse(text)
        except FretishSyntaxError:
            pass
        except lark.exceptions.LarkError as e:  # pragma: no cover
            pytest.fail(f"raw Lark error for {text!r}: {e!r}")


def test_parse_rejects_non_strings():
    with pytest.raises(TypeError):
        parse(b"the sw shall satisfy p")  # type: ignore[arg-type]


# --------------------------------------------------------------------------- spans
def test_spans_in_file_coordinates():
    text = "upon p the sw shall always satisfy x + 1 > y"
    r = parse(text, source="f.fret", line=7, column=5)
    rel = r.response
    assert text[rel.span.start:rel.span.end] == "x + 1 > y"
    assert (rel.span.line, rel.span.column, rel.span.end_line, rel.span.end_column) == \
        (7, 5 + text.index("x + 1"), 7, 5 + len(text))
    p = r.condition.parts[0].expr
    assert (p.span.line, p.span.column, p.span.start, p.span.end) == (7, 10, 5, 6)


def test_spans_across_lines():
    text = "upon p the sw\n    shall always satisfy x &\n  y"
    r = parse(text, line=3, column=9)
    y = r.response.right
    assert (y.span.line, y.span.column, y.span.start) == (5, 3, text.rindex("y"))
    assert (r.response.span.line, r.response.span.column) == (4, 26)
    assert (r.component_span.line, r.component_span.column) == (3, 9 + len("upon p "))


def test_every_node_has_a_span():
    r = parse("in m upon p & f(x, -3) the sw shall within 3 seconds satisfy "
              "if a then !b | (at the next occurrence of c, d)")
    nodes = [r.scope, r.scope.mode, r.condition, *r.condition.parts, r.timing,
             r.timing.duration]
    for root in (r.condition.expr, r.response):
        nodes.extend(A.walk(root))
    for n in nodes:
        s = n.span
        assert s != A.NO_SPAN and s.start < s.end and s.line >= 1, n
        assert r.text[s.start:s.end].strip() == r.text[s.start:s.end]
