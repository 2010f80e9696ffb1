"""The C form decides a tick whose input number is NaN as the Python form does: that input
is any value, each machine keeping a belief (the states it may be in, in arrays of fixed
capacity in C), and a machine that no longer knows its state gives the fallback's outputs
(none without one: the step returns -1, the runner's cells are empty) until reset.

Random requirement sets over the inputs ``a`` (a boolean), ``d`` and ``e`` (numbers,
compared with constants and with each other) and the outputs ``x``, ``y`` (booleans) and
``v`` (a number); random runs in which ``d`` and ``e`` are often NaN, on several ticks in a
row and at once (the belief grows and meets again); the C runner's row equals the Python
form's decision at every tick: outputs, override, reasons and fault.
"""

from __future__ import annotations

import csv
import io
import math
import random
import subprocess
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.shield.build import build_shield
from fretc.shield.emit_c import C_FREE_LIMIT, render_c
from fretc.shield.emit_python import tables
from fretc.shield.runtime import BELIEF_LIMIT, ShieldRuntime

from _c_monitors import build, needs_cc, write
from _gen import compile_text, csv_cell, fault_kind, shield_or_assume, unscoped_sets

INPUTS = ["a", "d", "e"]
OUTPUTS = ["x", "y", "v"]
CONDITIONS = ["", "whenever a ", "upon a ", "whenever d > 1 ", "upon d <= 0 ", "whenever e > 2 ",
              "upon d < e ", "whenever d + e > 3 ", "upon a & e <= 1 "]
RESPONSES = ["x", "!x", "x & y", "x | y", "v <= 1", "v > 2", "!y -> x", "y", "v = 2"]
TIMINGS = ["immediately ", "at the next timepoint ", "within 2 ticks ", "within 3 ticks ",
           "for 2 ticks ", "always ", "never ", "until a "]


@st.composite
def requirement_sets(draw) -> str:
    return draw(unscoped_sets(CONDITIONS, TIMINGS, RESPONSES))


NUMBERS = [-1.0, 0.0, 0.5, 1.0, 2.0, 3.0, math.inf]


@st.composite
def runs(draw, length: int = 60) -> list[tuple[dict, dict]]:
    """Ticks of inputs (``d``, ``e`` NaN about a third of the time each) and proposals
    (``v`` now and then NaN or infinite)."""
    out = []
    for _ in range(draw(st.integers(1, length))):
        ins = {"a": draw(st.booleans()),
               "d": draw(st.sampled_from([math.nan, math.nan, math.nan, *NUMBERS])),
               "e": draw(st.sampled_from([math.nan, math.nan, math.nan, *NUMBERS]))}
        prop = {"x": draw(st.booleans()), "y": draw(st.booleans()),
                "v": draw(st.sampled_from([0.0, 0.5, 1.0, 2.0, 2.5, 3.0, math.nan, math.inf]))}
        out.append((ins, prop))
    return out


def run_c(shield, rows: list[tuple[dict, dict]]) -> list[dict]:
    """The C runner's rows for ``rows`` (inputs, proposal: the variables of the first)."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write(render_c(shield, "t"), folder)
        exe = build(folder, ["t_shield.c", "t_shield_run.c"], "run")
        ins_vars, outs_vars = list(rows[0][0]), list(rows[0][1])
        text = io.StringIO()
        w = csv.writer(text, lineterminator="\n")
        w.writerow(ins_vars + outs_vars)
        for ins, prop in rows:
            w.writerow([csv_cell(ins[v]) for v in ins_vars] + [csv_cell(prop[v]) for v in outs_vars])
        got = subprocess.run([str(exe)], input=text.getvalue(), capture_output=True,
                             text=True, timeout=60)
    assert got.returncode == 0 and not got.stderr, got.stderr
    return list(csv.DictReader(io.StringIO(got.stdout)))


def assert_alike(shield, rows: list[tuple[dict, dict]]) -> list:
    """The Python form's decisions on ``rows``, each equal to the C runner's row."""
    rt = ShieldRuntime(tables(shield))
    decisions = []
    for (ins, prop), c in zip(rows, run_c(shield, rows), strict=True):
        d = rt.step(ins, prop)
        decisions.append(d)
        assert c["fault"] == fault_kind(d), (ins, prop, d, c)
        assert c["overridden"] == str(int(d.overridden)), (ins, prop, d, c)
        assert set(filter(None, c["reasons"].split("|"))) == set(d.reasons), (d, c)
        for v, x in prop.items():
            if v not in shield.read:
                continue
            if v not in d.outputs:
                assert c[v] == "", (v, d, c)
            elif isinstance(x, bool):
                assert c[v] == str(int(d.outputs[v])), (v, ins, prop, d, c)
            else:
                assert float(c[v]) == d.outputs[v], (v, ins, prop, d, c)
    return decisions


@settings(max_examples=6, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(text=requirement_sets(), rows=runs())
@pytest.mark.tor("TOR-SHD-004")
def test_c_and_python_decide_alike_on_nan_inputs(text, rows):
    needs_cc()
    _compiled, shield = shield_or_assume(text, INPUTS, OUTPUTS)
    assert_alike(shield, rows)


def test_a_machine_with_no_outputs_safe_for_every_value_is_lost_in_both_forms(tmp_path):
    """``o`` must be ``x > 1``: a NaN ``x`` leaves no ``o`` safe in every case, and the
    shield has no fallback: from that tick on the machine of F3 and F4 gives no outputs (C:
    -1, empty cells) while F1's machine still decides (its reason at tick 2 is given)."""
    needs_cc()
    compiled = compile_text("F1: upon a ctrl shall within 2 ticks satisfy p\n"
                            "F3: whenever x > 1 ctrl shall immediately satisfy o\n"
                            "F4: whenever x <= 1 ctrl shall immediately satisfy !o\n", tmp_path)
    shield = build_shield(compiled, ["a", "x"], ["o", "p"], fork=False)
    assert shield.fallback is None
    rows = [({"a": k == 0, "x": math.nan if k in (2, 5) else 0.0},
             {"o": False, "p": False}) for k in range(7)]
    decisions = assert_alike(shield, rows)
    assert [d.outputs for d in decisions[:2]] == [{"o": False, "p": False}] * 2
    assert all(d.outputs == {} and d.lost == ("F3", "F4") for d in decisions[2:])
    assert decisions[2].reasons == ("F1",)


def test_a_belief_past_its_bound_is_lost_at_the_same_tick_in_both_forms(tmp_path):
    """Four deadlines on comparisons of ``d`` and ``e``, both NaN at most ticks and the
    proposals never meeting a deadline: the belief grows past 256 states (the Python form's
    BELIEF_LIMIT, the C form's capacity), and both forms lose the machine at the same tick,
    giving the fallback's outputs from then on."""
    needs_cc()
    compiled = compile_text(
        "R1: upon d > 1 sw shall within 5 ticks satisfy x\n"
        "R2: upon d > 2 sw shall within 4 ticks satisfy y\n"
        "R3: upon d > 3 sw shall within 6 ticks satisfy v > 2\n"
        "R4: upon e > 2 sw shall within 5 ticks satisfy x & y\n", tmp_path)
    shield = build_shield(compiled, INPUTS, OUTPUTS, fork=False)
    assert shield.fallback is not None
    rnd = random.Random(0)
    rows = [({"a": False, "d": math.nan if rnd.random() < 0.8 else rnd.choice([0.0, 2.5, 3.5]),
              "e": math.nan if rnd.random() < 0.8 else rnd.choice([0.0, 3.0])},
             {"x": False, "y": False, "v": 0.0}) for _ in range(40)]
    decisions = assert_alike(shield, rows)
    lost = [k for k, d in enumerate(decisions) if d.lost]
    assert lost and lost == list(range(lost[0], len(rows))), lost
    assert f"more than {BELIEF_LIMIT} states" in decisions[lost[0]].fault
    fb = shield.fallback["outputs"]
    assert all({v: d.outputs[v] for v in fb} == fb for d in decisions[lost[0]:])


@pytest.mark.tor("TOR-SHD-004")
def test_more_free_comparisons_than_the_c_bound_lose_the_machine_in_c(tmp_path):
    """The one place the forms differ, by design: the C form tries the 2^k valuations of the
    k input atoms a tick's NaN inputs leave free, k at most C_FREE_LIMIT; a machine with more
    (here 18 comparisons of ``d``) is lost in C at such a tick (the fallback from then on,
    column ``fault`` = ``input``, then ``lost``), where the Python form decides it."""
    needs_cc()
    assert C_FREE_LIMIT < 18
    cond = " | ".join(f"d > {k}" for k in range(1, 19))
    compiled = compile_text(f"R1: whenever {cond} sw shall immediately satisfy x\n", tmp_path)
    shield = build_shield(compiled, INPUTS, OUTPUTS, fork=False)
    assert shield.fallback is not None and shield.fallback["outputs"]["x"] is True
    rows = [({"a": False, "d": x, "e": 0.0}, {"x": False, "y": False, "v": 0.0})
            for x in (0.0, math.nan, 0.0, 0.0)]
    c = run_c(shield, rows)
    assert [(r["x"], r["overridden"], r["fault"]) for r in c] == [
        ("0", "0", ""), ("1", "1", "input"), ("1", "1", "lost"), ("1", "1", "lost")], c
    rt = ShieldRuntime(tables(shield))
    d = [rt.step(i, p) for i, p in rows]
    assert not any(x.lost for x in d) and d[1].outputs["x"] and not d[2].outputs["x"], d
