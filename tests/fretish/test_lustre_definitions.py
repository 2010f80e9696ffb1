"""FRET's glossary definitions (Lustre) read as FRETish expressions
(:mod:`fretc.fretish.lustre`) and expanded for the analyses
(:mod:`fretc.fretish.fret_definitions`).

The reading is checked against a reference stream evaluator of Lustre written here (a
definition's value at each tick of random traces, ``pre`` at the first tick taken as the
reading's false / 0, which Lustre leaves undefined), through fretc's own pt expansion and
reference evaluator of the IR; the expansion of definitions through each other, the
recursive ones kept free with the reason, and ``fretc check`` on an export whose Internal
variable is defined by its glossary."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from _monitor_helpers import fret_export
from fretc.cli import main
from fretc.compiler import ir
from fretc.compiler.evaluate import series
from fretc.compiler.expressions import Expander
from fretc.fretish.fret_definitions import definitions
from fretc.fretish.fret_variables import FretVariable
from fretc.fretish.lustre import LustreError, parse_definition

BOOLS, NUMS = ("p", "q"), ("x", "y")


def _is_bool(name: str) -> bool:
    return name in BOOLS


# ------------------------------------------------------------------ a reference evaluator
def _ref(e, trace: list[dict], t: int):
    """The value at tick ``t`` of the Lustre term ``e`` (a tuple tree made by the strategy
    below), on ``trace``."""
    op = e[0]
    if op == "var":
        return trace[t][e[1]]
    if op == "lit":
        return e[1]
    if op == "not":
        return not _ref(e[1], trace, t)
    if op == "neg":
        return -_ref(e[1], trace, t)
    if op == "pre":
        if t == 0:
            return False if _bool_term(e[1]) else 0.0
        return _ref(e[1], trace, t - 1)
    if op == "->":
        return _ref(e[1], trace, t) if t == 0 else _ref(e[2], trace, t)
    if op == "if":
        return _ref(e[2], trace, t) if _ref(e[1], trace, t) else _ref(e[3], trace, t)
    a, b = _ref(e[1], trace, t), _ref(e[2], trace, t)
    return {"and": lambda: a and b, "or": lambda: a or b, "xor": lambda: a != b,
            "=>": lambda: (not a) or b, "=": lambda: a == b, "<>": lambda: a != b,
            "<": lambda: a < b, "<=": lambda: a <= b, "+": lambda: a + b,
            "-": lambda: a - b, "*": lambda: a * b}[op]()


def _bool_term(e) -> bool:
    op = e[0]
    if op == "var":
        return e[1] in BOOLS
    if op == "lit":
        return isinstance(e[1], bool)
    if op in ("pre", "neg"):
        return _bool_term(e[1]) if op == "pre" else False
    if op in ("->", "if"):
        return _bool_term(e[-1])
    return op in ("not", "and", "or", "xor", "=>", "=", "<>", "<", "<=")


def _text(e) -> str:
    """The Lustre text of ``e``, fully parenthesized where precedence could matter."""
    op = e[0]
    if op == "var":
        return e[1]
    if op == "lit":
        return str(e[1]).lower() if isinstance(e[1], bool) else repr(e[1])
    if op in ("not", "pre"):
        return f"{op} ({_text(e[1])})"
    if op == "neg":
        return f"- ({_text(e[1])})"
    if op == "if":
        return f"(if {_text(e[1])} then {_text(e[2])} else {_text(e[3])})"
    return f"({_text(e[1])} {op} {_text(e[2])})"


def _terms():
    num_leaf = st.one_of(st.sampled_from(NUMS).map(lambda n: ("var", n)),
                         st.sampled_from([0.0, 1.0, 2.5]).map(lambda v: ("lit", v)))
    bool_leaf = st.one_of(st.sampled_from(BOOLS).map(lambda n: ("var", n)),
                          st.booleans().map(lambda v: ("lit", v)))

    def num_ext(num):
        return st.one_of(
            st.tuples(st.sampled_from(["+", "-", "*"]), num, num),
            st.tuples(st.just("neg"), num), st.tuples(st.just("pre"), num),
            st.tuples(st.just("->"), num, num))
    nums = st.recursive(num_leaf, num_ext, max_leaves=6)

    def bool_ext(b):
        return st.one_of(
            st.tuples(st.sampled_from(["and", "or", "xor", "=>", "=", "<>"]), b, b),
            st.tuples(st.just("not"), b), st.tuples(st.just("pre"), b),
            st.tuples(st.just("->"), b, b),
            st.tuples(st.sampled_from(["<", "<=", "=", "<>"]), nums, nums),
            st.tuples(st.just("if"), b, b, b))
    return st.recursive(bool_leaf, bool_ext, max_leaves=8)


def _traces():
    row = st.fixed_dictionaries({"p": st.booleans(), "q": st.booleans(),
                                 "x": st.sampled_from([-1.0, 0.0, 1.0, 2.5]),
                                 "y": st.sampled_from([0.0, 2.0, 3.0])})
    return st.lists(row, min_size=1, max_size=6)


@settings(max_examples=150, deadline=None)
@given(_terms(), _traces())
def test_a_boolean_definition_means_what_lustre_says_at_every_tick(term, trace):
    e = parse_definition(_text(term), _is_bool)
    node = Expander("pt", ir.FTP, ir.LAST, free=True).bool(e)
    got = series(node, trace)
    assert got == [bool(_ref(term, trace, t)) for t in range(len(trace))], _text(term)


@pytest.mark.parametrize("text, why", [
    ("x div 2", "div"), ("a +", "at the end"), ("current x", "outside"), ("a $ b", "'$'"),
    ("if a then b", "else")])
def test_what_is_outside_the_subset_is_refused_with_where(text, why):
    with pytest.raises(LustreError) as err:
        parse_definition(text, _is_bool)
    assert why in str(err.value)


@pytest.mark.parametrize("text", ["x --y", "x -- y", "x - (* y *) 1", "x /* y */", "x // y"])
def test_a_lustre_comment_is_refused_not_read_as_operators(text):
    """Lustre reads ``x --y`` as ``x`` (``--`` opens a comment to the end of the line); the
    subset read it as ``x - (-y)``, another value than FRET's. A comment in a definition is
    refused, so the variable stays free with the reason (the analyses, the audit and the
    monitors read it so), and so is a number longer than a FRETish number may be."""
    with pytest.raises(LustreError, match="comment"):
        parse_definition(text, _is_bool)
    defs = definitions((_var("x", kind="Input", data_type="double"),
                        _var("y", kind="Input", data_type="double"),
                        _var("d", text, data_type="double")))
    assert "d" not in defs.values and "a Lustre comment" in defs.free["d"]
    assert parse_definition("x - -y", _is_bool) == parse_definition("x - (- y)", _is_bool)
    with pytest.raises(LustreError, match="a number of 101 characters"):
        parse_definition("x + 1" + "0" * 100, _is_bool)


def _var(name: str, assignment: str = "", kind: str = "Internal",
         data_type: str = "boolean") -> FretVariable:
    return FretVariable("c", name, kind, data_type, assignment)


_STAGE = (_var("a", kind="Input"), _var("b", kind="Input"),
          _var("hold", "a and not b"), _var("held", "hold or pre held"),
          _var("twice", "hold and not pre hold"), _var("k", "3.0", data_type="double"),
          _var("uses", "held and a"), _var("bad", "a div b"))


def test_definitions_expand_through_each_other_and_recursive_ones_stay_free():
    defs = definitions(_STAGE)
    assert str(defs.values["twice"]) == str(parse_definition(
        "(a and not b) and not pre (a and not b)", lambda n: True))
    # (held, monotone in its previous value, is a since for the analyses, and uses with it:
    # fretish.fret_since; the audit's reading keeps both streams, as before)
    assert set(defs.values) == {"hold", "twice", "k", "held", "uses"}
    assert defs.pasts == {"held"} and "held" not in defs.free and not defs.streams
    ticked = definitions(_STAGE, since=False)
    assert set(ticked.values) == {"hold", "twice", "k"}
    assert "reads itself" in ticked.free["held"]
    assert "reads held" in ticked.free["uses"]
    assert list(ticked.streams) == ["held", "uses"]
    assert "outside FRET's Lustre subset" in defs.free["bad"]


def test_a_cycle_without_pre_and_a_definition_too_deep_stay_free_with_the_reason():
    """A cycle without ``pre`` defines no value (not a stream with state); a chain of 3,000
    ``and`` (built by the reader's loop, no recursion) or an expansion nested past FRETish's
    200 levels stays free: no RecursionError later, in the substitution or the compiler."""
    chain = " and ".join(["a"] * 3000)
    half = " and ".join(["a"] * 150)
    defs = definitions((
        _var("a", kind="Input"), _var("p", "q"), _var("q", "not p"),
        _var("long", chain), _var("half", half), _var("twice", "not (half or half)"),
        _var("deeper", " or ".join(["twice"] * 2) + " or " + "not " * 60 + "twice")))
    assert "without pre (a cycle" in defs.free["p"] and "without pre" in defs.free["q"]
    assert "nested more than 200 levels deep" in defs.free["long"]
    assert set(defs.values) == {"half", "twice"}
    assert "nested more than 200 levels deep" in defs.free["deeper"]


def _check(path, doc: dict, *options: str):
    """``fretc check`` of ``doc`` written to ``path`` (the click result)."""
    path.write_text(json.dumps(doc), encoding="utf-8")
    return CliRunner().invoke(main, ["check", str(path), "--no-progress", *options])


def test_a_deep_definition_is_no_internal_error_in_monitors_or_check(tmp_path):
    """A FRET export whose definition is a chain of 3,000 ``and``: ``--emit monitor`` and
    ``check`` read the variable as free (a note says why), exit 0/2, never 4."""
    doc = fret_export({"R1": "whenever d ctrl shall immediately satisfy o"},
                  ("a", "Input", "boolean"), ("o", "Output", "boolean"),
                  ("d", "Internal", "boolean", {"assignment": " and ".join(["a"] * 3000)}))
    path = tmp_path / "p.json"
    got = _check(path, doc)
    assert got.exit_code == 2 and "nested more than 200 levels deep" in got.output, got.output
    got = CliRunner().invoke(main, [str(path), "--emit", "monitor", "-o",
                                    str(tmp_path / "m.py")])
    assert got.exit_code == 0, got.output
    assert "nested more than 200 levels deep" in got.stderr


def test_check_reads_an_internal_variable_as_its_definition(tmp_path):
    """``hold`` is Internal, ``a and not b``: realizability is decided over the Inputs a, b
    (before, ``hold`` was a free variable declared neither input nor output: exit 2), and
    the note says the definition is used."""
    doc = fret_export({"R1": "whenever hold ctrl shall immediately satisfy o",
                   "R2": "whenever b ctrl shall immediately satisfy !o"},
                  ("a", "Input", "boolean"), ("b", "Input", "boolean"),
                  ("o", "Output", "boolean"),
                  ("hold", "Internal", "boolean", {"assignment": "a and not b"}))
    got = _check(tmp_path / "p.json", doc, "--json")
    assert got.exit_code == 0, got.output
    res = json.loads(got.output)
    assert res["realizability"]["undeclared"] == []
    assert all(g["realizable"] is True for g in res["realizability"]["groups"])
    assert any(n.startswith("hold: FRET defines it (Internal) as a and not b; that "
                            "definition in the analysis") for n in res["notes"])
    # with hold "a or b" the two requirements conflict whenever b: unrealizable
    doc["variables"][3]["assignment"] = "a or b"
    got = _check(tmp_path / "p.json", doc, "--json")
    assert got.exit_code == 1 and "unrealizable" in got.output, got.output


def test_a_mode_is_its_mode_requirement(tmp_path):
    """A Mode with FRET's mode requirement (a FRETish condition) is that condition: ``in
    cruise mode`` holds where ``speed > 10``; without a requirement it stays a free variable,
    declared neither input nor output (exit 2)."""
    doc = fret_export({"M1": "in cruise mode ctrl shall always satisfy o",
                   "M2": "whenever speed <= 10 ctrl shall immediately satisfy !o"},
                  ("speed", "Input", "double"), ("o", "Output", "boolean"),
                  ("cruise", "Mode", "boolean", {"modeRequirement": "speed > 10"}))
    path = tmp_path / "p.json"
    got = _check(path, doc, "--json")
    assert got.exit_code == 0, got.output
    res = json.loads(got.output)
    assert all(g["realizable"] is True for g in res["realizability"]["groups"])
    assert any(n.startswith("cruise: FRET defines the mode as speed > 10; that definition")
               for n in res["notes"])
    # the mode overlapping M2's trigger: o and !o both owed where 8 < speed <= 10
    doc["variables"][2]["modeRequirement"] = "speed > 8"
    got = _check(path, doc, "--json")
    assert got.exit_code == 1 and "unrealizable" in got.output, got.output
    doc["variables"][2]["modeRequirement"] = ""
    got = _check(path, doc, "--json")
    assert got.exit_code == 2 and "cruise a Mode of ctrl" in got.output, got.output
