"""Tests of FRETish expressions (fretish.parser.parse_expression): the precedence levels of
``grammar.lark``, the expressions FRETish rejects and where their errors are reported, and
round trips of random expression trees through their text.

Reference: ../shared/fretish/README.md section 5 (precedence), FRET's printed formulas.
"""

from __future__ import annotations

import re

import pytest
from hypothesis import given, settings, strategies as st

from fretc.compiler.printers import expr_text as fret_text
from fretc.fretish import FretishSyntaxError, parse
from fretc.fretish import ast as A
from fretc.fretish.parser import RESERVED_LETTERS, RESERVED_WORDS, parse_expression
from fretc.fretish.words import FRET_RESERVED


@pytest.mark.parametrize("text,expected", [
    ("a xor b | c", "(a xor (b | c))"),
    ("a & b xor c", "((a & b) xor c)"),
    ("a | b xor c & d", "((a | b) xor (c & d))"),
    ("a -> b -> c", "(a -> (b -> c))"),
    ("a => b -> c", "(a -> (b -> c))"),
    ("a <-> b <-> c", "((a <-> b) <-> c)"),
    ("a -> b <-> c -> d", "((a -> b) <-> (c -> d))"),
    ("a xor b -> c", "((a xor b) -> c)"),
    ("!a & b", "((! a) & b)"),
    ("!x > 3", "(! (x > 3))"),
    ("!!a", "(! (! a))"),
    ("~a | b", "((! a) | b)"),
    ("x - y - z", "((x - y) - z)"),
    ("x / y * z", "((x / y) * z)"),
    ("x ^ y ^ z", "(x ^ (y ^ z))"),
    ("-x ^ 2", "(- (x ^ 2))"),
    ("-x^2", "(- (x ^ 2))"),
    ("2 ^ -x", "(2 ^ (- x))"),
    ("-x * y", "((- x) * y)"),
    ("x mod 2 + 1 = 0", "(((x mod 2) + 1) = 0)"),
    ("x + 2 * y ^ 2 <= z mod 3", "((x + (2 * (y ^ 2))) <= (z mod 3))"),
    ("if a then b & c", "(a -> (b & c))"),
    ("if a then if b then c", "(a -> (b -> c))"),
    ("if if a then b then c", "((a -> b) -> c)"),
    ("(if a then b) & c", "((a -> b) & c)"),
    # a nested if-then as the last operand, with the grammar's grouping (FRET regroups
    # these by a text rewrite: ../shared/fretish/README.md section 6b, defect 2)
    ("a & if b then c", "(a & (b -> c))"),
    ("a & if b then c | d", "(a & (b -> (c | d)))"),
    ("(speed <= alt) & if landed then q", "((speed <= alt) & (landed -> q))"),
    ("q <=> if a then b", "(q <-> (a -> b))"),
    ("!if a then b", "(! (a -> b))"),
    ("a | !if b then c", "(a | (! (b -> c)))"),
    ("a xor b & if c then d", "(a xor (b & (c -> d)))"),
    ("r & at the next occurrence of p, q | s", "(r & nextOcc(p,(q | s)))"),
    ("a & (b | c)", "(a & (b | c))"),
    ("x>-3.0e2", "(x > -3.0e2)"),
    ("x-3", "(x - 3)"),
    ("- 3", "(- 3)"),
    ("-3 ^ 2", "(-3 ^ 2)"),
    ("- 3 ^ 2", "(- (3 ^ 2))"),
    ("2 ^ -3", "(2 ^ -3)"),
    ("x - -3", "(x - -3)"),
    ("-(3)", "(- 3)"),
    ("- -3", "(- -3)"),
])
@pytest.mark.tor("TOR-GRM-003")
def test_precedence_table(text, expected):
    assert fret_text(parse_expression(text)) == expected


@pytest.mark.parametrize("text", [
    "a < b < c", "a = b = c", "x = !y", "x + !y", "x ^ !y", "-!y", "x = !if a then b",
    "(if a then b", "a & if b", "if a then b & if c",
    "p and q", "p or q", "not p", "x == 3", ".5", "f(a,)", "(a", "a)", "a &", "3x",
    "x = y z", "at the next occurrence of p", "X", "next", "the",
])
@pytest.mark.tor("TOR-GRM-002")
def test_bad_expressions(text):
    with pytest.raises(FretishSyntaxError):
        parse_expression(text)


@pytest.mark.parametrize("text,column,message", [
    # "!" as an arithmetic operand or a comparison side, and chained comparisons, are
    # reported when the expression holding them ends, the leftmost first
    ("x = !y & (a)", 5, "unexpected '!' in an expression"),
    ("(x = !y) garbage", 6, "unexpected '!' in an expression"),
    ("a < b + !c < d", 9, "unexpected '!' in an expression"),
    ("a < b < !c", 7, "comparisons do not chain: unexpected '<'"),
    ("(a < b < c) garbage", 8, "comparisons do not chain"),
    # an error found while the expression is read comes first
    ("x = !y & T", 10, "'T' is reserved"),
    # "-!" at once
    ("-!y ^ 2", 2, "unexpected '!' in an expression"),
    ("- -!y", 4, "unexpected '!' in an expression"),
])
@pytest.mark.tor("TOR-GRM-002")
def test_where_expression_errors_are_reported(text, column, message):
    with pytest.raises(FretishSyntaxError) as info:
        parse_expression(text)
    assert (info.value.column, info.value.message[:len(message)]) == (column, message)


def test_negative_number_literals_keep_their_spans():
    e = parse_expression("-3 ^ 2")
    assert e.left == A.NumLit("-3") and (e.left.span.start, e.left.span.end) == (0, 2)
    assert (e.span.start, e.span.end) == (0, 6)
    assert parse_expression("-(3) ^ 2") == A.Unary("-", A.Binary("^", A.NumLit("3"),
                                                                  A.NumLit("2")))


# --------------------------------------------------------------------------- round trips
_KW = {w.lower() for w in RESERVED_WORDS}
names = st.from_regex(r"[A-Za-z][A-Za-z0-9_%]{0,6}(\.[A-Za-z0-9_%]{1,4})?", fullmatch=True).filter(
    lambda s: s.lower() not in _KW and s not in RESERVED_LETTERS and s not in FRET_RESERVED
    and s.split(".")[0].lower() not in _KW | {"true", "false"})
# FRET unescapes only \" in a quoted name: a name ending in a backslash, or with one before a
# quote, cannot be written
quoted = st.text(st.characters(blacklist_categories=("Cs", "Cc"), blacklist_characters='\n'),
                 min_size=1, max_size=8).filter(
    lambda s: s.strip() != "" and not s.endswith("\\") and '\\"' not in s)
numbers = st.from_regex(r"-?[0-9]{1,4}(\.[0-9]{1,3})?([eE][+-]?[0-9]{1,2})?", fullmatch=True)
atoms = st.one_of(names.map(A.Var), quoted.map(A.Var), st.booleans().map(A.BoolLit),
                  numbers.map(A.NumLit))
OPS = A.BOOL_OPS + A.COMPARISON_OPS + A.ARITH_OPS


def _extend(children):
    return st.one_of(
        st.tuples(st.sampled_from(OPS), children, children).map(lambda t: A.Binary(*t)),
        st.tuples(st.sampled_from("!-"), children).map(lambda t: A.Unary(*t)),
        st.tuples(names, st.lists(children, max_size=3)).map(
            lambda t: A.Call(t[0], tuple(t[1]))),
    )


exprs = st.recursive(atoms, _extend, max_leaves=12)


def _name(v: A.Var, quote_all=False) -> str:
    if quote_all or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_%.]*", v.name) or \
            v.name.lower() in _KW or v.name in RESERVED_LETTERS or v.name in FRET_RESERVED or \
            v.name.endswith(".") or \
            ".." in v.name or v.name.split(".")[0].lower() in _KW:
        return '"' + v.name.replace('"', '\\"') + '"'
    return v.name


def show_full(e: A.Expr, rnd=0) -> str:
    """Fully parenthesized FRETish text of ``e``."""
    if isinstance(e, A.Var):
        return _name(e)
    if isinstance(e, A.BoolLit):
        return ("TRUE", "true", "True", "fALSE")[rnd % 3] if e.value else ("false", "FALSE", "False")[rnd % 3]
    if isinstance(e, A.NumLit):
        return e.text
    if isinstance(e, A.Unary):
        inner = show_full(e.operand, rnd + 1)
        return f"(~{inner})" if e.op == "!" and rnd % 2 else f"({e.op}({inner}))"
    if isinstance(e, A.Binary):
        op = {"->": ("->", "=>"), "<->": ("<->", "<=>")}.get(e.op, (e.op,))[rnd % 2 if e.op in ("->", "<->") else 0]
        if e.op == "->" and rnd % 3 == 2:
            return f"(if {show_full(e.left, rnd + 1)} then {show_full(e.right, rnd + 2)})"
        return f"({show_full(e.left, rnd + 1)} {op} {show_full(e.right, rnd + 2)})"
    return f"{e.name}({', '.join(show_full(a, rnd + i) for i, a in enumerate(e.args))})"


# Minimal-parentheses printer, from the precedence table alone (../shared/fretish/README.md section 5).
_PREC = {"<->": 1, "->": 2, "xor": 3, "|": 4, "&": 5, "=": 7, "!=": 7, "<": 7, "<=": 7,
         ">": 7, ">=": 7, "+": 8, "-": 8, "*": 9, "/": 9, "mod": 9, "^": 11}
_RIGHT = {"->", "^"}


def _prec(e) -> int:
    if isinstance(e, A.Binary):
        return _PREC[e.op]
    if isinstance(e, A.Unary):
        return 6 if e.op == "!" else 10
    return 12


def show_min(e: A.Expr) -> str:
    def sub(x, need):
        s = show_min(x)
        return f"({s})" if _prec(x) < need else s

    if isinstance(e, A.Unary):
        if e.op == "!":
            return "!" + sub(e.operand, 6)
        if isinstance(e.operand, A.NumLit):
            return f"-({e.operand.text})"
        return "- " + sub(e.operand, 10)
    if isinstance(e, A.Binary):
        p = _PREC[e.op]
        left_need = p + 1 if e.op in _RIGHT or p == 7 else p
        right_need = p if e.op in _RIGHT else p + 1
        return f"{sub(e.left, left_need)} {e.op} {sub(e.right, right_need)}"
    if isinstance(e, A.Call):
        return f"{e.name}({', '.join(show_min(a) for a in e.args)})"
    return show_full(e)


@settings(max_examples=400, deadline=None)
@given(exprs, st.integers(0, 5))
def test_round_trip_fully_parenthesized(e, rnd):
    assert parse_expression(show_full(e, rnd)) == e


@settings(max_examples=400, deadline=None)
@given(exprs)
def test_round_trip_minimal_parentheses(e):
    text = show_min(e)
    assert parse_expression(text) == e, text


@settings(max_examples=200, deadline=None)
@given(exprs)
def test_round_trip_in_sentences(e):
    text = show_full(e)
    r = parse(f"upon {text} the sw shall before {text} satisfy {text}.")
    assert r.condition.expr == r.timing.stop == r.response == e
    s = r.response_span
    assert r.text[s.start:s.end] == f"satisfy {text}"
