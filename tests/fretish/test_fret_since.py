"""A FRET boolean stream monotone in its own previous value is the past-time formula
``P S psi`` (fretish/fret_since.py): for random monotone definitions and random traces, the
analyses' expansion (pt, ft's derived past atom, the interval semantics' columns) equals the
stream the audit and the monitors compute tick by tick (compiler/stream_code.py, Lustre's
semantics); a stream not monotone in its previous value stays a stream."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.common.errors import FretishError
from fretc.compiler.coverage import expr_text as coverage_text
from fretc.compiler.evaluate import series
from fretc.compiler.expressions import Expander
from fretc.compiler.ir import TRUE
from fretc.compiler.printers import expr_text
from fretc.compiler.stream_code import stream_columns
from fretc.fretish import ast as A
from fretc.fretish.fret_definitions import definitions
from fretc.fretish.fret_since import SINCE
from fretc.fretish.fret_streams import stream_system
from fretc.fretish.fret_variables import FretVariable
from fretc.fretish.lustre import LustreError, parse_definition
from fretc.fretish.parser import parse_expression
from fretc.monitors.expressions import ColumnExpressions

INPUTS = ("a", "b", "c")


def _vars(definition: str = "", mode: str = "", **more: str) -> tuple[FretVariable, ...]:
    """The inputs, ``s`` (Internal ``definition``, or a Mode with requirement ``mode``), and
    more Internal boolean variables."""
    out = [FretVariable("c", n, "Input", "boolean") for n in INPUTS]
    if mode:
        out.append(FretVariable("c", "s", "Mode", "boolean", "", mode))
    else:
        out.append(FretVariable("c", "s", "Internal", "boolean", definition))
    out += [FretVariable("c", n, "Internal", "boolean", d) for n, d in more.items()]
    return tuple(out)


# -------------------------------------------------------------- random monotone definitions
# A tree is a tuple: ("var", x), ("lit", bool), ("pre", x) (an input's previous value),
# ("self", b) (s's previous value, first value b), ("not", t), ("and"|"or", t, u),
# ("ite", c, t, u), ("arrow", t, u) (Lustre's ->), ("implies", t, u).
_leaf = st.one_of(st.tuples(st.just("var"), st.sampled_from(INPUTS)),
                  st.tuples(st.just("lit"), st.booleans()),
                  st.tuples(st.just("pre"), st.sampled_from(INPUTS)))
_free = st.recursive(_leaf, lambda t: st.one_of(
    st.tuples(st.just("not"), t), st.tuples(st.sampled_from(["and", "or"]), t, t),
    st.tuples(st.just("ite"), t, t, t), st.tuples(st.just("arrow"), t, t)), max_leaves=4)


def _monotone(first: st.SearchStrategy) -> st.SearchStrategy:
    """Trees positive in ``("self", b)`` (``b`` from ``first``)."""
    return st.recursive(st.one_of(st.tuples(st.just("self"), first), _free), lambda t: st.one_of(
        st.tuples(st.sampled_from(["and", "or"]), t, t),
        st.tuples(st.just("not"), st.tuples(st.just("not"), t)),
        st.tuples(st.just("ite"), _free, t, t), st.tuples(st.just("arrow"), t, t),
        st.tuples(st.just("implies"), _free, t)), max_leaves=8)


def _printer(forms: dict) -> Callable[[tuple], str]:
    """A printer of trees: ``forms[kind]`` takes the node's fields, subtrees printed."""
    def show(t: tuple) -> str:
        return forms[t[0]](*(show(x) if isinstance(x, tuple) else x for x in t[1:]))
    return show


def _lit(b: bool) -> str:
    return "true" if b else "false"


def _infix(op: str) -> Callable[[str, str], str]:
    return lambda a, b: f"({a} {op} {b})"


_lustre = _printer({
    "var": str, "lit": _lit, "pre": lambda x: f"(pre {x})", "pre of": lambda a: f"(pre {a})",
    "self": lambda b: "(true -> pre s)" if b else "(pre s)", "not": lambda a: f"(not {a})",
    "and": _infix("and"), "or": _infix("or"), "xor": _infix("xor"), "=": _infix("="),
    "arrow": _infix("->"), "implies": _infix("=>"),
    "ite": lambda c, a, b: f"(if {c} then {a} else {b})"})
# the tree in FRETish (a Mode's requirement): ``preBool(b, s)`` as written
_fretish = _printer({
    "var": str, "lit": _lit, "pre": lambda x: f"preBool(false, {x})",
    "self": lambda b: f"preBool({_lit(b)}, s)", "not": lambda a: f"(! {a})",
    "and": _infix("&"), "or": _infix("|"), "implies": _infix("=>"),
    "arrow": lambda a, b: f"ite(FTP, {a}, {b})", "ite": lambda c, a, b: f"ite({c}, {a}, {b})"})


def _has_self(t: tuple) -> bool:
    return t[0] == "self" or any(_has_self(x) for x in t[1:] if isinstance(x, tuple))


_traces = st.integers(1, 12).flatmap(lambda n: st.lists(
    st.fixed_dictionaries({x: st.booleans() for x in INPUTS}), min_size=n, max_size=n))


def _agree(variables: tuple[FretVariable, ...], trace: list[dict]) -> None:
    """The analyses' expansion of ``s`` (a since) equals its column computed tick by tick,
    in pt, in ft (a derived past atom) and in the interval semantics' columns."""
    defs = definitions(variables)
    assert "s" in defs.pasts and "s" not in defs.free and "s" not in defs.streams
    e = defs.values["s"]
    assert isinstance(e, A.Call) and e.name == SINCE
    system = stream_system(variables, ["s"])  # (the audit's and the monitors' reading)
    assert system is not None and system.names == ("s",)
    n = len(trace)
    columns = {x: np.array([r[x] for r in trace], np.bool_) for x in INPUTS}
    want = stream_columns(system, columns, n)["s"].tolist()
    pt = Expander("pt", TRUE, TRUE).bool(e)
    ft = Expander("ft", TRUE, TRUE).bool(e)
    assert ft.op == "past" and "S" in ft.name
    assert series(pt, trace) == want, (expr_text(e), trace)
    assert series(ft, trace) == want
    got = ColumnExpressions({x: np.append(c, False) for x, c in columns.items()}, n).bool(e)
    assert got[:n].tolist() == want and not got[n]


@settings(max_examples=250, deadline=None)
@given(_monotone(st.just(False)).filter(_has_self), _traces)
def test_a_monotone_lustre_stream_is_its_since(tree, trace):
    """Lustre definitions (``pre s``, ``true -> pre s``, ``->``, ``=>``, ``if``, the
    previous values of inputs) positive in ``pre s``."""
    _agree(_vars(_lustre(tree)), trace)


@settings(max_examples=250, deadline=None)
@given(_monotone(st.booleans()).filter(_has_self), _traces)
def test_a_monotone_mode_with_either_first_value_is_its_since(tree, trace):
    """A Mode's FRETish requirement reading ``preBool(true, s)`` and ``preBool(false, s)``
    (first values true and false, mixed)."""
    _agree(_vars(mode=_fretish(tree)), trace)


#: any boolean definition reading ``pre s`` (``xor``, ``=``, ``pre`` of a formula reading s,
#: s in a condition, under a negation)
_any = st.recursive(st.one_of(st.tuples(st.just("self"), st.just(False)), _free), lambda t: (
    st.one_of(st.tuples(st.sampled_from(["and", "or", "xor", "=", "arrow", "implies"]), t, t),
              st.tuples(st.just("not"), t), st.tuples(st.just("ite"), t, t, t),
              st.tuples(st.just("pre of"), t))), max_leaves=8)


@settings(max_examples=300, deadline=None)
@given(_any.filter(_has_self), _traces)
def test_whatever_is_read_as_a_since_is_the_stream(tree, trace):
    """Soundness over any definition: when the analyses read ``s`` as a since, it is the
    stream; otherwise it stays one."""
    variables = _vars(_lustre(tree))
    if "s" in definitions(variables).pasts:
        _agree(variables, trace)
    else:
        assert "s" in definitions(variables).streams


@pytest.mark.parametrize("definition", [
    "false -> not pre s",            # a toggle: s counts modulo 2
    "false -> (pre s xor a)",
    "a -> (pre s = b)",
    "if pre s then a else b",        # in an ite's condition
    "(pre s) => a",                  # on the left of =>
    "a or pre (pre s)",              # under another pre
    "a or not pre s",
    "a or (pre (s and b))",
])
def test_a_stream_not_monotone_in_its_previous_value_stays_a_stream(definition):
    defs = definitions(_vars(definition))
    assert "s" not in defs.values and "s" not in defs.pasts
    assert "reads itself" in defs.free["s"] and "s" in defs.streams
    assert "s" in definitions(_vars(definition), since=False).streams


def test_the_latch_and_what_reads_it():
    """FRET's mode latch is ``(!FTP & (a | !b)) S (!FTP & a)``; a definition reading it is
    expanded with it for the analyses; a non-monotone stream reading it stays a stream,
    computed with the latch tick by tick; the audit's reading keeps all three streams."""
    variables = _vars("false -> (a or (pre s and not b))", uses="s and c",
                      parity="false -> (pre parity xor s)")
    defs = definitions(variables)
    assert expr_text(defs.values["s"]) == "(((! FTP) & (a | (! b))) S ((! FTP) & a))"
    assert coverage_text(defs.values["s"]) == "(!FTP & (a | !b)) S (!FTP & a)"
    assert expr_text(defs.values["uses"]) == f"({expr_text(defs.values['s'])} & c)"
    assert defs.pasts == {"s"} and list(defs.streams) == ["parity"]
    assert list(definitions(variables, since=False).streams) == ["s", "parity", "uses"]
    system = stream_system(variables, ["parity"])
    assert system is not None and system.names == ("s", "parity") and system.inputs == ("a", "b")


def test_no_text_writes_the_since():
    """The call name is no FRETish or Lustre name: neither reader produces it."""
    with pytest.raises(LustreError):
        parse_definition(f"{SINCE}(a, b)", lambda n: True)
    with pytest.raises(FretishError):
        parse_expression(f"{SINCE}(a, b)")
    with pytest.raises(FretishError):
        parse_expression(f'"{SINCE}"(a, b)')  # (a quoted name is a variable, never a call)
    assert not any(isinstance(x, A.Call) for x in A.walk(parse_expression(f'"{SINCE}" | a')))
