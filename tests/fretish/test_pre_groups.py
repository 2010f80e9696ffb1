"""FRET definitions nested through ``pre`` past the depth of one expression (LMCPS's NN
defines ``xt``, ``yt``, ``zt`` as 199-deep ``c0 -> pre(c1 -> pre(...))`` tables of values over
time) are read as one equation per ``pre`` group (:func:`fretc.fretish.lustre.pre_groups`) and
computed tick by tick as the streams they are: the column the audit computes equals a Lustre
reading written here (value at tick t of each operator), for random definitions read whole and
nested 210 groups deep; ``fretc check`` reads them as the environment's; a project whose
component cannot be checked exits with the worst result of the others, not 2."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from fretc.compiler.stream_code import stream_columns
from fretc.fretish.fret_definitions import GROUPED, definitions
from fretc.fretish.fret_streams import StreamSystem, stream_system
from fretc.fretish.fret_variables import FretVariable
from fretc.fretish.lustre import pre_groups

SHARED = Path(__file__).resolve().parents[3] / "shared"
LMCPS = SHARED / "corpora" / "fret_projects" / "LMCPS" / "LM_requirements.json"

# a Lustre expression as a tree: ("c", k) | ("x",) | ("y",) | (op, a, b) | ("->", a, b)
# | ("pre", a)
_leaf = st.one_of(st.integers(-3, 3).map(lambda k: ("c", k)), st.just(("x",)),
                  st.just(("y",)))
_tree = st.recursive(_leaf, lambda t: st.one_of(
    st.tuples(st.sampled_from("+-*"), t, t), st.tuples(st.just("->"), t, t),
    st.tuples(st.just("pre"), t)), max_leaves=8)


def _text(e) -> str:
    if e[0] == "c":
        return f"{e[1]}.0" if e[1] >= 0 else f"(- {-e[1]}.0)"
    if e[0] in ("x", "y"):
        return e[0]
    if e[0] == "pre":
        return f"pre({_text(e[1])})"
    return f"({_text(e[1])} {e[0]} {_text(e[2])})"


def _value(e, t: int, cols) -> float:
    """Lustre's value of ``e`` at tick ``t`` (``pre`` at the first tick: FRET's 0)."""
    op = e[0]
    if op == "c":
        return float(e[1])
    if op in ("x", "y"):
        return float(cols[op][t])
    if op == "pre":
        return _value(e[1], t - 1, cols) if t > 0 else 0.0
    if op == "->":
        return _value(e[1], t, cols) if t == 0 else _value(e[2], t, cols)
    a, b = _value(e[1], t, cols), _value(e[2], t, cols)
    return a + b if op == "+" else a - b if op == "-" else a * b


def _column(text: str, n: int, cols) -> np.ndarray:
    """The audit's column of ``v``, FRET's Internal variable defined as ``text`` (numeric,
    inputs ``x``, ``y``), computed as the stream it is."""
    variables = (FretVariable("C", "x", "Input", "double"),
                 FretVariable("C", "y", "Input", "double"),
                 FretVariable("C", "v", "Internal", "double", text))
    system = stream_system(variables, ["v"])
    assert system is not None
    return stream_columns(system, cols, n)["v"]


@settings(max_examples=150, deadline=None)
@given(tree=_tree, table=st.lists(st.integers(-9, 9), min_size=1, max_size=4),
       xs=st.lists(st.integers(-3, 3), min_size=8, max_size=8))
def test_a_definition_nested_past_the_depth_is_the_lustre_stream_it_writes(tree, table, xs):
    """``c0 -> pre(c1 -> pre(... E))`` 210 groups deep around a random ``E``: the audit's
    column is Lustre's value at each tick (the table's constants, then ``E`` delayed)."""
    deep = 210
    consts = [table[i % len(table)] for i in range(deep)]
    text = _text(tree)
    for c in reversed(consts):
        text = f"{c}.0 -> pre({text})"
    n = deep + 8
    cols = {"x": np.array(xs * (n // 8 + 1), np.float64)[:n],
            "y": np.array(list(reversed(xs)) * (n // 8 + 1), np.float64)[:n]}
    got = _column(text, n, cols)
    assert got is not None
    want = [float(consts[t]) if t < deep else _value(tree, t - deep, cols) for t in range(n)]
    assert np.array_equal(got, np.array(want)), (text[:200],)


@settings(max_examples=150, deadline=None)
@given(tree=_tree, xs=st.lists(st.integers(-3, 3), min_size=6, max_size=6))
def test_pre_groups_of_a_shallow_definition_give_its_values(tree, xs):
    """The equations of :func:`pre_groups` of any definition with a ``pre (...)`` group,
    computed as a stream system, give Lustre's value of the definition at every tick."""
    text = "0.0 -> pre(" + _text(tree) + ")"
    eqs = pre_groups(text, "v", lambda n: n in ("x", "y", "v"), lambda n: False)
    assert eqs is not None and eqs[-1][0] == "v"
    system = StreamSystem(tuple(e[0] for e in eqs), tuple(e[1] for e in eqs),
                          tuple(e[2] for e in eqs), ("x", "y"), (False, False),
                          tuple(e[3] for e in eqs))
    n = 6
    cols = {"x": np.array(xs, np.float64), "y": np.array(xs[::-1], np.float64)}
    got = stream_columns(system, cols, n)["v"]
    want = np.array([_value(("->", ("c", 0), ("pre", tree)), t, cols) for t in range(n)])
    assert np.array_equal(got, want), (text,)


def test_a_table_of_constants_is_a_stream_reading_no_variable():
    """A 250-deep table: a stream (computed tick by tick), the reason said, no variable
    read: the environment's to ``fretc check``."""
    text = "0.0"
    for k in range(250, 0, -1):
        text = f"{k}.0 -> pre({text})"
    variables = (FretVariable("C", "t", "Internal", "double", text),)
    defs = definitions(variables)
    assert "t" in defs.streams and defs.free["t"] == GROUPED
    system = stream_system(variables, ["t"])
    assert system is not None and system.inputs == ()
    col = stream_columns(system, {}, 260)["t"]
    assert col.tolist() == [float(k) for k in range(1, 251)] + [0.0] * 10


def test_a_definition_too_deep_outside_pre_stays_free():
    """400 nested ``not``: no ``pre`` group to read apart; a free variable, the reason
    given (hostile glossaries still end there)."""
    variables = (FretVariable("C", "b", "Input", "boolean"),
                 FretVariable("C", "d", "Internal", "boolean", "not " * 400 + "b"))
    defs = definitions(variables)
    assert "d" not in defs.values and "d" not in defs.streams
    assert "nested" in defs.free["d"]


@pytest.mark.skipif(not LMCPS.exists(), reason="../shared is absent")
def test_lmcps_nn_is_checked_and_the_project_exits_1(tmp_path):
    """``fretc check LM_requirements.json``: NN's ``xt``, ``yt``, ``zt`` are streams the
    environment sets (were 'declared neither Input nor Output'), NN is checked, and the
    project exits 1 (its unrealizable components), not 2."""
    out = tmp_path / "check.json"
    run = subprocess.run([sys.executable, "-m", "fretc", "check", str(LMCPS),
                          "--tick-period", "1s", "-o", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 1, run.stderr[-2000:]
    doc = json.loads(out.read_text())
    rows = {r["component"]: r for r in doc["fret_components"]}
    assert rows["NN"]["realizability"] != "not checked", rows["NN"]
    assert "declared neither" not in rows["NN"]["reason"]
    assert {r["realizability"] for r in rows.values()} >= {"unrealizable"}
    assert doc["exit_code"] == 1
