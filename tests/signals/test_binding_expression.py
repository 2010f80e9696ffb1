"""The binding expression language's tree (signals/bindings/expression.py): the Lark
Transformer and the printer agree, and walking the tree follows the text."""

from __future__ import annotations


from fretc.signals.bindings import EvalState
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.signals.bindings.binding import compile_expression
from fretc.signals.bindings.expression import (BinOp, Const, ExprLocation, Field, FuncCall, Ref,
                                          UnaryOp, refs, unparse, walk)
from fretc.signals.bindings.parse import parse_expression

FIELDS = ["/scan.ranges", "/odom.pose.x", "/odom.v[2]", "/a.b[-1]", "/scan.ranges[1:3]",
          "/imu.q[:2]"]
NAMES = ["p", "q", "speed"]


def _expressions() -> st.SearchStrategy[str]:
    leaf = st.one_of(st.sampled_from(FIELDS), st.sampled_from(["1", "0.5", "2e-3", "true",
                                                               "false"]),
                     st.sampled_from(NAMES), st.just("age(/scan)"))

    def grow(inner: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
        binop = st.sampled_from(["+", "-", "*", "/", "<", "<=", ">", ">=", "=", "!=", "&", "|",
                                 "->", "<->"])
        return st.one_of(
            st.builds(lambda a, o, b: f"({a} {o} {b})", inner, binop, inner),
            st.builds(lambda a: f"-{a}", inner),
            st.builds(lambda a: f"(!{a})", inner),
            st.builds(lambda f, a: f"{f}({a})", st.sampled_from(["abs", "min", "mean", "any"]),
                      inner),
            st.builds(lambda a, b: f"max({a}, {b})", inner, inner))
    return st.recursive(leaf, grow, max_leaves=8)


def _where() -> ExprLocation:
    return ExprLocation("<test>", "v", 1, 1)


@settings(max_examples=100, deadline=None)
@given(_expressions())
def test_printing_a_parsed_tree_and_parsing_it_again_gives_the_same_tree(text):
    tree, _topics = parse_expression(text, _where())
    if any(isinstance(n, Ref) for n in walk(tree)):
        return  # unparse prints substituted trees only
    printed = unparse(tree)
    again, _ = parse_expression(printed, _where())
    assert unparse(again) == printed


def test_a_negation_inside_a_comparison_keeps_its_parentheses():
    tree, _ = parse_expression("(!/a.b) = /c.d", _where())
    assert unparse(tree) == "((!/a.b) = /c.d)"
    again, _ = parse_expression(unparse(tree), _where())
    assert isinstance(again, BinOp) and again.op == "="
    neg, _ = parse_expression("-(!/a.b)", _where())
    assert unparse(neg) == "-(!/a.b)"
    assert unparse(parse_expression("!(/a.b = 1)", _where())[0]) == "!(/a.b = 1.0)"


@settings(max_examples=100, deadline=None)
@given(_expressions())
def test_walk_meets_the_leaves_in_the_order_of_the_text(text):
    tree, _topics = parse_expression(text, _where())
    leaves = [n for n in walk(tree) if isinstance(n, (Field, Const, Ref))]
    cols = [n.col for n in leaves]
    assert cols == sorted(cols) and len(set(cols)) == len(cols)
    assert refs(tree) == [n.name for n in leaves if isinstance(n, Ref)]


def test_the_transformer_builds_one_node_per_rule():
    tree, topics = parse_expression("!(/a.b[1] + 2 < 3) -> min(/s.r[0:2]) == x", _where())
    assert topics == {"/a", "/s"}
    assert isinstance(tree, BinOp) and tree.op == "->"
    neg = tree.left
    assert isinstance(neg, UnaryOp) and neg.op == "!" and neg.col == 1
    cmp_ = neg.arg
    assert isinstance(cmp_, BinOp) and cmp_.op == "<" and cmp_.col == 15
    assert cmp_.left == BinOp(11, "+", Field(3, "/a", ("b", 1)), Const(13, 2.0))
    right = tree.right
    assert isinstance(right, BinOp) and right.op == "=" and right.col == 38  # '==' reads as '='
    call = right.left
    assert isinstance(call, FuncCall) and call.func == "min" and call.col == 23
    assert unparse(call.args[0]) == "/s.r[0:2]"
    assert right.right == Ref(41, "x")


def test_a_slice_before_a_field_reads_the_field_of_each_item():
    """Foxglove's message path syntax: after a slice the rest of the path applies to each
    item (a slice had to be last before)."""
    from types import SimpleNamespace as NS
    b = compile_expression("v", "1 + min(/a.b[0:2].c)", source="f.toml", line=4, col=5)
    st = EvalState()
    st.msgs["/a"] = NS(b=[NS(c=5), NS(c=3), NS(c=-9)])
    assert b.evaluate(st) == 4.0
    assert unparse(b.ast.right.args[0]) == "/a.b[0:2].c"


def test_fields_of_a_binding_follow_the_text_through_substitution():
    q = compile_expression("q", "/b.y > 0 | /c.z")
    p = compile_expression("p", "/a.x < 1 & q & /d.w", refs={"q": q})
    assert [f.topic for f in p.fields] == ["/a", "/b", "/c", "/d"]
