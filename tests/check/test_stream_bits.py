"""A FRET boolean stream reading booleans only, not monotone in its previous value (a toggle
``false -> (a xor pre s)``), is read by ``fretc check`` and ``fretc shield`` by its state bit
(fretish/fret_since.py ``stream_expansion``, IR ``stream``): the reference evaluator's pt
and ft series, the BDD monitor of check/pt_monitor.py stepped tick by tick and the interval
semantics' column all equal the stream as the audit computes it (compiler/stream_code.py),
on random definitions (``xor``, ``=``, negations, ``pre s`` in an ``ite``'s condition, either
first value) and traces; and ``fretc check`` answers realizability exactly on a toggle."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.cli import main
from test_monitor_sat import _monitor_series as stepped
from fretc.compiler import ir
from fretc.compiler.evaluate import series
from fretc.compiler.expressions import Expander
from fretc.compiler.ir import TRUE
from fretc.compiler.printers import expr_text, to_smv
from fretc.compiler.stream_code import stream_columns
from fretc.fretish.fret_definitions import definitions
from fretc.fretish.fret_since import stream_name
from fretc.fretish.fret_streams import stream_system
from fretc.monitors.expressions import ColumnExpressions
from tests.fretish.test_fret_since import INPUTS, _free, _has_self, _lustre, _traces, _vars

#: any boolean definition reading ``pre s`` (first value false: ``pre s``; true: ``true ->
#: pre s``) non-monotonically as well: under ``xor``, ``=``, a negation, an ``ite``'s
#: condition, the left of ``=>``
_bits = st.recursive(st.one_of(st.tuples(st.just("self"), st.booleans()), _free), lambda t: (
    st.one_of(st.tuples(st.sampled_from(["and", "or", "xor", "=", "arrow", "implies"]), t, t),
              st.tuples(st.just("not"), t), st.tuples(st.just("ite"), t, t, t))),
    max_leaves=8)


def _monitor_series(pt: ir.Node, trace: list[dict]) -> list[bool]:
    """The BDD monitor of ``pt`` (check/pt_monitor.py, through the safety game) stepped
    over ``trace``: its value at each tick (tests/check/test_monitor_sat.py's stepper)."""
    return stepped(pt, trace)[0]


def _agree(variables, trace: list[dict]) -> None:
    """The analyses' expansion of ``s`` by its state bit equals its column computed tick by
    tick: pt series, ft derived past atom, BDD monitor, interval columns."""
    defs = definitions(variables, bits=True)
    assert "s" in defs.bits and "s" not in defs.free and "s" not in defs.streams
    e = defs.values["s"]
    assert stream_name(e) == "s" and expr_text(e) == "s"
    system = stream_system(variables, ["s"])
    assert system is not None and system.names == ("s",)
    n = len(trace)
    columns = {x: np.array([r[x] for r in trace], np.bool_) for x in INPUTS}
    want = stream_columns(system, columns, n)["s"].tolist()
    pt = Expander("pt", TRUE, TRUE).bool(e)
    ft = Expander("ft", TRUE, TRUE).bool(e)
    assert ft.op == "past" and ft.name == "s"
    assert series(pt, trace) == want, (to_smv(pt.args[0]), to_smv(pt.args[1]), trace)
    assert series(ft, trace) == want
    if pt.op == "stream":  # (a definition folding to a constant is no stream)
        assert to_smv(pt) == "s"
    assert _monitor_series(pt, trace) == want
    got = ColumnExpressions({x: np.append(c, False) for x, c in columns.items()}, n).bool(e)
    assert got[:n].tolist() == want and not got[n]


@settings(max_examples=300, deadline=None)
@given(_bits.filter(_has_self), _traces)
def test_every_boolean_stream_of_booleans_is_its_state_bit(tree, trace):
    """A monotone one stays a since (``pasts``); every other is its one-bit machine."""
    variables = _vars(_lustre(tree))
    if "s" in definitions(variables, bits=True).pasts:
        assert "s" not in definitions(variables, bits=True).bits
        return
    _agree(variables, trace)


@pytest.mark.parametrize("definition", [
    "false -> not pre s",            # a toggle: s counts modulo 2
    "false -> (pre s xor a)",
    "true -> (a = pre s)",
    "if pre s then a else b",        # in an ite's condition
    "(pre s) => a",                  # on the left of =>
    "a or not pre s",
    "(true -> pre s) xor (pre s) xor b",  # two first values
])
def test_the_streams_that_were_left_free_are_exact(definition):
    trace = [{"a": k % 3 == 0, "b": k % 2 == 1, "c": k % 5 == 2} for k in range(13)]
    _agree(_vars(definition), trace)
    # (without bits, the reading of testgen and fretc compile, it stays a stream)
    assert "s" in definitions(_vars(definition)).streams


def test_a_stream_reading_a_previous_number_or_itself_otherwise_is_still_a_stream():
    """``pre x`` of a number (a comparison of two ticks' values), or ``s`` read two ticks
    back or inside another ``pre``: no state bit computes it. A comparison of the tick's
    values is an atom: ``(x > 1.0) xor pre s`` is one bit."""
    from fretc.fretish.fret_variables import FretVariable

    variables = (*_vars("false -> ((x > 1.0) xor pre s)"),
                 FretVariable("c", "x", "Input", "double"))
    assert "s" in definitions(variables, bits=True).bits
    for definition in ("false -> ((x > pre x) xor pre s)", "a or pre (pre s)",
                       "a or (pre (s and b))"):
        variables = (*_vars(definition), FretVariable("c", "x", "Input", "double"))
        defs = definitions(variables, bits=True)
        assert "s" not in defs.values and "s" in defs.streams, definition
        assert "s" not in defs.bits


# ----------------------------------------------------------------------------- fretc check
def _var(name: str, kind: str, assignment: str = "", data_type: str = "boolean") -> dict:
    return {"project": "P", "component_name": "ctrl", "variable_name": name, "idType": kind,
            "dataType": data_type, "assignment": assignment}


def _check(tmp_path: Path, texts: list[str]) -> tuple[int, dict]:
    path = tmp_path / "p.json"
    path.write_text(json.dumps({"requirements": [
        {"reqid": f"R{k + 1}", "project": "P", "fulltext": t} for k, t in enumerate(texts)],
        "variables": [_var("a", "Input"), _var("o", "Output"),
                      _var("t", "Internal", "false -> (a xor pre t)")]}), encoding="utf-8")
    got = CliRunner().invoke(main, ["check", str(path), "--no-progress", "--json"])
    return got.exit_code, json.loads(got.output)


def _no_stream(doc: dict) -> None:
    assert "streams" not in doc["realizability"], doc["realizability"]
    assert not [a for a in doc["abstractions"] if "stream variable" in a["why"]]
    assert any(n.startswith("t: FRET defines it (Internal) as false -> (a xor pre t); that "
                            "definition is a boolean stream with state reading booleans "
                            "and this tick's comparisons only: exactly a machine with one "
                            "state bit")
               for n in doc["notes"]), doc["notes"]


def test_check_answers_a_toggle_exactly(tmp_path):
    """``o <-> t``: the controller reads ``a`` and its own bit of the toggle, realizable.
    ``always t``: the toggle is false at the first tick, unrealizable (as a free
    proposition of the environment's it would have been the environment's to give)."""
    code, doc = _check(tmp_path, ["ctrl shall always satisfy o <-> t"])
    assert code == 0 and [g["realizable"] for g in doc["realizability"]["groups"]] \
        == [True], doc
    assert doc["realizability"]["groups"][0]["method"] == "safety game"
    _no_stream(doc)
    (tmp_path / "u").mkdir()
    code, doc = _check(tmp_path / "u", ["ctrl shall always satisfy t"])
    [group] = doc["realizability"]["groups"]
    assert code == 1 and group["realizable"] is False, doc
    _no_stream(doc)


def test_check_finds_the_conflict_the_toggle_makes(tmp_path):
    """``a`` at the second tick makes the toggle true: o must be true and false."""
    code, doc = _check(tmp_path, ["whenever t ctrl shall immediately satisfy o",
                                  "whenever a ctrl shall immediately satisfy !o"])
    [group] = doc["realizability"]["groups"]
    assert code == 1 and group["realizable"] is False, doc
    _no_stream(doc)
    (tmp_path / "ok").mkdir()
    code, doc = _check(tmp_path / "ok", ["whenever t ctrl shall immediately satisfy o",
                                         "whenever !t ctrl shall immediately satisfy !o"])
    assert code == 0 and [g["realizable"] for g in doc["realizability"]["groups"]] \
        == [True], doc
