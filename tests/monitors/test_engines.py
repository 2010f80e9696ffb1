"""monitors: the pieces the split made public. The stepwise engine's replay equals
stepping the generated monitor by hand; the interval engine's trigger points follow FRET's
definition; the shared array conventions equal Python's scalar rules (compiler.evaluate, the
reference evaluator); the log's clock summary takes each figure from the right verdicts."""

from __future__ import annotations

import math
import random
from types import SimpleNamespace

import pytest
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.compiler import evaluate, ir
from fretc.audit.log import summarize_clocks
from fretc.monitors import arrays, stepwise
from fretc.monitors.interval import trigger_ticks

from _monitor_helpers import KEYS, compiled, load_module, random_trace, requirement, samples


@pytest.mark.tor("TOR-GEN-001")
def test_replay_equals_stepping_the_generated_monitor():
    responses = ["r", "x > 2", "r | s"]
    reqs = [compiled(requirement(s, c, t, response=responses[i % 3], condition="c & x <= 3",
                                 n=2), rid=f"K{i}") for i, (s, c, t) in enumerate(KEYS[::24])]
    mod = load_module(reqs, "engines_replay")
    rnd = random.Random(14)
    for c in reqs:
        cls = mod.MONITORS[c.id]
        cols = random_trace(rnd, 40)
        for n in (1, 17, 40):
            by_hand = cls()
            for s in samples(cols, n):
                by_hand.step(s)
            got = stepwise.verdict(stepwise.replay(cls, cols, n))
            assert got == (bool(by_hand.finish()), by_hand.status, by_hand.status_tick), c.id


@settings(max_examples=150, deadline=None)
@given(st.lists(st.booleans(), min_size=1, max_size=30), st.data())
@pytest.mark.tor("TOR-SEM-006")
def test_trigger_points_follow_fret_definition(values, data):
    C = np.array(values, dtype=np.bool_)
    n = len(C)
    s = data.draw(st.integers(0, n - 1))
    e = data.draw(st.integers(s, n - 1))
    inside = np.zeros(n, np.bool_)  # (the interval's membership, its start)
    inside[s:e + 1] = True
    starts = np.array([s])

    def trigger_points(cond, C):
        return trigger_ticks(cond, C, inside, starts, False).tolist()

    assert trigger_points("null", None) == [s]
    assert trigger_points("holding", C) == [t for t in range(s, e + 1) if C[t]]
    # regular: C becomes true, or holds at the interval's first point
    assert trigger_points("regular", C) == [
        t for t in range(s, e + 1) if C[t] and (t == s or not C[t - 1])]


FLOATS = st.floats(allow_nan=True, allow_infinity=False, width=64)


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(FLOATS, FLOATS), min_size=1, max_size=8),
       st.sampled_from(["+", "-", "*", "/", "mod"]))
def test_arith_equals_the_reference_evaluator(pairs, op):
    x = np.array([a for a, _b in pairs])
    y = np.array([b for _a, b in pairs])
    trace = [{"x": a, "y": b} for a, b in pairs]
    node = ir.Node("arith", (ir.Node("var", name="x"), ir.Node("var", name="y")), name=op)
    want = evaluate.series(node, trace)[:len(pairs)]
    got = arrays.arith(op, x, y)
    for g, w in zip(got.tolist(), want):
        assert (math.isnan(g) and math.isnan(w)) or g == w, (op, pairs)


@settings(max_examples=150, deadline=None)
@given(st.lists(FLOATS, min_size=1, max_size=4))
def test_py_min_max_keep_pythons_choice_with_nan(values):
    cols = [np.array([v]) for v in values]
    for ours, python in ((arrays.py_min, min), (arrays.py_max, max)):
        got, want = ours(cols)[0], python(values)
        assert (math.isnan(got) and math.isnan(want)) or got == want


def test_shifted_is_one_tick_later():
    x = np.array([True, False, True])
    assert arrays.shifted(x, False, np.bool_).tolist() == [False, True, False]
    assert arrays.shifted(np.array([1.5, 2.5]), 9.0, np.float64).tolist() == [9.0, 1.5]
    assert arrays.shifted(np.array([], dtype=np.float64), None, np.float64).tolist() == []


def _verdict(ticks, warmup, first, last, waiting):
    return SimpleNamespace(ticks_evaluated=ticks, warmup_ticks=warmup, first_tick_ns=first,
                           last_tick_ns=last, waiting_for=waiting)


def test_summarize_clocks_takes_each_figure_from_its_own_clock():
    la = SimpleNamespace(ticks_evaluated=0, warmup_ticks=0, first_time_ns=None, waiting_for=[],
                         ticks_after_damage=0, end_time_ns=99)
    vs = [_verdict(10, 3, 500, 900, ["/b"]), _verdict(12, 1, None, 950, ["/a", "/b"])]
    summarize_clocks(la, vs)
    assert (la.ticks_evaluated, la.warmup_ticks, la.first_time_ns) == (12, 3, 500)
    assert la.waiting_for == ["/a", "/b"]
    assert la.end_time_ns == 99  # no damage: the log's own end stands
    la.ticks_after_damage = 4
    summarize_clocks(la, vs)
    assert la.end_time_ns == 950  # the judged span ends at the last intact tick
    empty = SimpleNamespace(ticks_evaluated=7)
    summarize_clocks(empty, [])
    assert empty.ticks_evaluated == 7
