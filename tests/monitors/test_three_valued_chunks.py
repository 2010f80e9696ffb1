"""monitors.kleene_stream: Kleene's three-valued reading of a pt formula and the LTL3 verdict
over every letter an unknown tick may be, fed a chunk of ticks at a time (any chunks, a
boolean column's dtype changing from chunk to chunk, NaN operands and unknown ticks
anywhere), equal to ThreeValued over the whole trace: the pair at the last tick, the last
tick where the formula may hold, and the LTL3 verdict with its tick and time."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.compiler import ir
from fretc.compiler.build import compile_entry
from fretc.compiler.codegen import monitor_source
from fretc.compiler.pt_step import CodegenError
from fretc.monitors.kleene_stream import (KleeneStream, Ltl3SetStream, kleene_unsupported,
                                          kleene_values)
from fretc.monitors.three_valued import ThreeValued, ltl3_verdict
from fretc.monitors.vectorized import VectorizeError

from _monitor_helpers import KEYS, compiled, entry, requirement
from differential import random_requirement
from test_streams import _PAST, CONDITIONS, RESPONSES

BOOLS = ("m", "c", "r", "s")
X_VALUES = [0.0, 1.0, 2.0, 2.0, 3.0, 4.0, -0.0, 2.5, math.nan, math.nan]
_SEEDS = st.integers(0, 2**32 - 1).map(random.Random)


@pytest.fixture(scope="module")
def all_keys():
    out = []
    for i, (s, c, t) in enumerate(KEYS):
        comp = compiled(requirement(s, c, t, response=RESPONSES[i % 6],
                                    condition=CONDITIONS[i % 3], n=i % 4), rid=f"K{i}")
        out.append((comp.formalization.pt, monitor_source(comp, i)))
    return out


def _trace(rnd: random.Random, n: int, names=BOOLS, numbers=("x",)):
    """Columns (NaN among the numbers), unknown masks on some booleans, and times."""
    cols = {v: np.array([rnd.random() < 0.5 for _ in range(n)], np.bool_) for v in names}
    for v in numbers:
        cols[v] = np.array([rnd.choice(X_VALUES) for _ in range(n)])
    unknown = {v: np.array([rnd.random() < 0.1 for _ in range(n)], np.bool_)
               for v in names if rnd.random() < 0.5}
    times = np.cumsum([rnd.randint(1, 10**6) for _ in range(n)]).astype(np.int64)
    return cols, unknown, times


def _chunks(rnd: random.Random, n: int, cols: dict, unknown: dict):
    a = 0
    while a < n:
        k = min(n - a, rnd.choice([0, 1, 1, 2, 3, 5, 8]))
        part = {}
        for name, col in cols.items():
            piece = col[a:a + k]
            if col.dtype == np.bool_:
                piece = piece.astype(rnd.choice([np.bool_, np.uint8, np.float64]))
            part[name] = piece
        yield part, {v: m[a:a + k] for v, m in unknown.items()}, k, a
        a += k


def _check_pt(pt, cols, unknown, times, n, rnd, what):
    try:
        stream = KleeneStream(pt)
    except VectorizeError:
        assert kleene_unsupported(pt) is not None
        return
    for part, unk, k, _a in _chunks(rnd, n, cols, unknown):
        stream.feed(part, unk, k)
    lo, hi = ThreeValued(cols, unknown, n).pair(pt)
    still = np.flatnonzero(hi)
    assert stream.finish() == (bool(lo[-1]), bool(hi[-1]),
                               int(still[-1]) if len(still) else None), what


def _check_ltl3(ms, cols, unknown, times, n, rnd, what):
    try:
        stream = Ltl3SetStream(ms)
    except VectorizeError:
        return
    for part, unk, k, a in _chunks(rnd, n, cols, unknown):
        stream.feed(part, unk, k, times[a:a + k])
    status, tick, time = stream.finish()
    assert (status, tick) == ltl3_verdict(ms, ThreeValued(cols, unknown, n)), what
    assert time == (None if tick is None else int(times[tick])), what


@settings(max_examples=200, deadline=None)
@given(st.integers(0, len(KEYS) - 1), st.integers(1, 40), _SEEDS)
def test_kleene_streams_equal_the_three_valued_judge(all_keys, index, n, rnd):
    pt, ms = all_keys[index]
    cols, unknown, times = _trace(rnd, n)
    _check_pt(pt, cols, unknown, times, n, rnd, index)
    _check_ltl3(ms, cols, unknown, times, n, rnd, index)


@settings(max_examples=150, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 40), _SEEDS)
def test_kleene_streams_of_random_requirements(seed, n, rnd):
    """Random requirements over the whole grammar (past-time functions in atoms, nested
    conditions, every scope and timing)."""
    text, _ = random_requirement(random.Random(seed))
    comp = compile_entry(entry("R", text))
    f = comp.formalization
    bools, numbers = set(), set()
    for node in list(ir.walk(f.pt)) + list(ir.walk(f.ft_inf)):
        if node.op == "ap":
            bools.add(ir.name_of(node))
        elif node.op == "var":
            numbers.add(ir.name_of(node))
    cols, unknown, times = _trace(rnd, n, sorted(bools), sorted(numbers))
    _check_pt(f.pt, cols, unknown, times, n, rnd, text)
    try:
        ms = monitor_source(comp, 0)
    except CodegenError:
        return
    _check_ltl3(ms, cols, unknown, times, n, rnd, text)


@settings(max_examples=200, deadline=None)
@given(_PAST, st.integers(1, 30), _SEEDS)
def test_kleene_values_are_the_pair_of_every_node(node, n, rnd):
    """Every past-time formula: the value fed in chunks thresholded at > 0 and >= 0 is
    ThreeValued's (lo, hi) at every tick."""
    cols, unknown, _times = _trace(rnd, n)
    carry: dict = {}
    got: list[float] = []
    for part, unk, k, a in _chunks(rnd, n, cols, unknown):
        if k:
            got += kleene_values(node, part, unk, k, a, carry).tolist()
    lo, hi = ThreeValued(cols, unknown, n).pair(node)
    assert [v > 0 for v in got] == lo.tolist(), node
    assert [v >= 0 for v in got] == hi.tolist(), node


def test_what_the_kleene_stream_refuses():
    comp = compile_entry(entry("R", "the sw shall always satisfy persists(2, p)"))
    assert kleene_unsupported(comp.formalization.pt) is not None
    with pytest.raises(VectorizeError):
        KleeneStream(comp.formalization.pt)
    compared = ir.cmp(">", ir.Node("pre", (ir.num("0"), ir.var("x"))), ir.num("1"))
    assert "past-time" in (kleene_unsupported(ir.H(compared)) or "")
    with pytest.raises(ValueError):
        KleeneStream(ir.H(ir.ap("p"))).finish()


# ---------------------------------------------------------------- CompletionsStream
def _completions_case(pt, cols, unknown, n, rnd):
    """completed_verdict over the whole trace against the stream given its free ticks."""
    from fretc.monitors.completions import TooManyStates, completed_verdict
    from fretc.monitors.completions_stream import CompletionsStream, completions_unsupported

    if kleene_unsupported(pt) or completions_unsupported(pt):
        return None
    ev = ThreeValued(cols, unknown, n)
    try:
        want: object = completed_verdict(pt, ev)
    except TooManyStates as exc:
        want = str(exc)
    kleene = KleeneStream(pt)
    for part, unk, k, _a in _chunks(rnd, n, cols, unknown):
        kleene.feed(part, unk, k)
    if kleene.free is None:
        assert want == bool(ev.pair(pt)[0][-1])
        return want
    stream = CompletionsStream(pt, *kleene.free, n)
    try:
        for part, unk, k, _a in _chunks(rnd, n, cols, unknown):
            stream.feed(part, unk, k)
        got: object = stream.finish()
    except TooManyStates as exc:
        got = str(exc)
    assert got == want, pt
    return want


@settings(max_examples=300, deadline=None)
@given(st.integers(0, len(KEYS) - 1), st.integers(1, 40), _SEEDS)
def test_the_completions_stream_is_completed_verdict(all_keys, index, n, rnd):
    """Every completion followed a chunk at a time (the state before the first unknown
    tick carried, the states stepped over the unknown ticks, each completion evaluated
    from its state over the rest) gives completed_verdict's answer."""
    pt, _ms = all_keys[index]
    cols, unknown, _times = _trace(rnd, n)
    _completions_case(pt, cols, unknown, n, rnd)


@settings(max_examples=200, deadline=None)
@given(_PAST, st.integers(1, 30), _SEEDS)
def test_the_completions_stream_of_past_time_formulas(node, n, rnd):
    cols, unknown, _times = _trace(rnd, n)
    _completions_case(node, cols, unknown, n, rnd)


def test_the_completions_stream_outgrows_where_the_search_does(monkeypatch):
    """Past the bound on the work, the stream stops at the tick the whole search stops."""
    import fretc.monitors.completions as completions

    monkeypatch.setattr(completions, "MAX_STEPS", 300)
    comp = compiled(requirement("in", "regular", "always", response="r"), rid="C")
    pt = comp.formalization.pt
    n = 60
    cols = {v: np.ones(n, np.bool_) for v in BOOLS}
    cols["x"] = np.zeros(n)
    unknown = {"m": np.zeros(n, np.bool_), "r": np.zeros(n, np.bool_)}
    unknown["m"][[3, 50]] = True
    unknown["r"][[4, 40]] = True
    got = _completions_case(pt, cols, unknown, n, random.Random(1))
    assert isinstance(got, str) and "node evaluations by tick" in got
