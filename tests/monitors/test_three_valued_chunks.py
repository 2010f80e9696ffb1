"""monitors.three_valued and monitors.completions at every chunk boundary: Kleene's reading of a
pt formula (each node's values, the reading at the last tick, the last tick where it may hold,
the ticks its completions are followed over), the LTL3 verdict over every letter an unknown
tick may be (with its tick and time) and every completion of the unknown ticks, fed a chunk of
ticks at a time (any chunks, a boolean column's dtype changing from chunk to chunk, NaN
operands, unknown values and gap ticks anywhere), equal the same objects fed the whole trace
as one chunk. What the whole trace's readings must be is tested against every completion
(brute force: test_three_valued.py, test_gap_ticks.py)."""

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
from fretc.monitors.completions import CompletionsStream, TooManyStates, decide
from fretc.monitors.three_valued import (KleeneStream, Ltl3SetStream, kleene_unsupported,
                                         kleene_values, ltl3_verdict)
from fretc.monitors.vectorized import VectorizeError

from _monitor_helpers import KEYS, compiled, entry, keyed_monitors, requirement
from differential import random_requirement
from test_streams import _PAST, CONDITIONS, RESPONSES

BOOLS = ("m", "c", "r", "s")
X_VALUES = [0.0, 1.0, 2.0, 2.0, 3.0, 4.0, -0.0, 2.5, math.nan, math.nan]
_SEEDS = st.integers(0, 2**32 - 1).map(random.Random)


@pytest.fixture(scope="module")
def all_keys():
    return keyed_monitors(RESPONSES, CONDITIONS)


def _trace(rnd: random.Random, n: int, names=BOOLS, numbers=("x",)):
    """Columns (NaN among the numbers), unknown masks on some booleans, gap ticks (None
    without: their variables unknown) and times."""
    cols = {v: np.array([rnd.random() < 0.5 for _ in range(n)], np.bool_) for v in names}
    for v in numbers:
        cols[v] = np.array([rnd.choice(X_VALUES) for _ in range(n)])
    unknown = {v: np.array([rnd.random() < 0.1 for _ in range(n)], np.bool_)
               for v in names if rnd.random() < 0.5}
    stretch = None
    if rnd.random() < 0.5:
        stretch = np.array([rnd.random() < 0.08 for _ in range(n)], np.bool_)
        for v in cols:
            unknown[v] = unknown.get(v, np.zeros(n, np.bool_)) | stretch
    times = np.cumsum([rnd.randint(1, 10**6) for _ in range(n)]).astype(np.int64)
    return cols, unknown, stretch, times


def _chunks(rnd: random.Random, n: int, cols: dict, unknown: dict, stretch):
    a = 0
    while a < n:
        k = min(n - a, rnd.choice([0, 1, 1, 2, 3, 5, 8]))
        part = {}
        for name, col in cols.items():
            piece = col[a:a + k]
            if col.dtype == np.bool_:
                piece = piece.astype(rnd.choice([np.bool_, np.uint8, np.float64]))
            part[name] = piece
        yield (part, {v: m[a:a + k] for v, m in unknown.items()}, k, a,
               None if stretch is None else stretch[a:a + k])
        a += k


def _check_pt(pt, cols, unknown, stretch, n, rnd, what):
    try:
        stream = KleeneStream(pt)
    except VectorizeError:
        assert kleene_unsupported(pt) is not None
        return
    for part, unk, k, _a, gaps in _chunks(rnd, n, cols, unknown, stretch):
        stream.feed(part, unk, k, gaps)
    whole = KleeneStream(pt, whole=True)
    whole.feed(cols, unknown, n, stretch)
    assert stream.finish() == whole.finish(), what
    assert stream.free == whole.free, what


def _check_ltl3(ms, cols, unknown, stretch, times, n, rnd, what):
    try:
        stream = Ltl3SetStream(ms)
    except VectorizeError:
        return
    for part, unk, k, a, gaps in _chunks(rnd, n, cols, unknown, stretch):
        stream.feed(part, unk, k, times[a:a + k], gaps)
    status, tick, time = stream.finish()
    assert (status, tick) == ltl3_verdict(ms, cols, unknown, n, True, stretch), what
    assert time == (None if tick is None else int(times[tick])), what


@settings(max_examples=200, deadline=None)
@given(st.integers(0, len(KEYS) - 1), st.integers(1, 40), _SEEDS)
def test_kleene_streams_in_chunks_equal_one_chunk(all_keys, index, n, rnd):
    pt, ms = all_keys[index]
    cols, unknown, stretch, times = _trace(rnd, n)
    _check_pt(pt, cols, unknown, stretch, n, rnd, index)
    _check_ltl3(ms, cols, unknown, stretch, times, n, rnd, index)


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
    cols, unknown, stretch, times = _trace(rnd, n, sorted(bools), sorted(numbers))
    _check_pt(f.pt, cols, unknown, stretch, n, rnd, text)
    try:
        ms = monitor_source(comp, 0)
    except CodegenError:
        return
    _check_ltl3(ms, cols, unknown, stretch, times, n, rnd, text)


@settings(max_examples=200, deadline=None)
@given(_PAST, st.integers(1, 30), _SEEDS)
@pytest.mark.tor("TOR-LOG-003")
def test_kleene_values_in_chunks_are_those_of_one_chunk(node, n, rnd):
    """Every past-time formula (bounded windows across gap ticks and chunk edges): the
    values fed in chunks, each temporal operator's state carried, are those of the whole
    trace at once, as read at > 0 and >= 0."""
    cols, unknown, stretch, _times = _trace(rnd, n)
    carry: dict = {}
    got: list[float] = []
    for part, unk, k, a, gaps in _chunks(rnd, n, cols, unknown, stretch):
        if k:
            got += kleene_values(node, part, unk, k, a, carry, stretch=gaps).tolist()
    want = kleene_values(node, cols, unknown, n, 0, {}, stretch=stretch)
    assert [v > 0 for v in got] == (want > 0).tolist(), node
    assert [v >= 0 for v in got] == (want >= 0).tolist(), node


def test_what_the_kleene_stream_refuses_a_chunk_at_a_time():
    comp = compile_entry(entry("R", "the sw shall always satisfy persists(2, p)"))
    assert kleene_unsupported(comp.formalization.pt) is not None
    with pytest.raises(VectorizeError):
        KleeneStream(comp.formalization.pt, whole=True)
    compared = ir.H(ir.cmp(">", ir.Node("pre", (ir.num("0"), ir.var("x"))), ir.num("1")))
    assert "past-time" in (kleene_unsupported(compared) or "")
    with pytest.raises(VectorizeError):
        KleeneStream(compared)
    whole = KleeneStream(compared, whole=True)  # (the whole trace as one chunk)
    whole.feed({"x": np.array([0.0, 2.0, 3.0])}, {}, 3)
    with pytest.raises(ValueError, match="one chunk"):
        whole.feed({"x": np.array([0.0])}, {}, 1)
    assert whole.finish() == (False, False, None)
    with pytest.raises(ValueError):
        KleeneStream(ir.H(ir.ap("p"))).finish()


# ---------------------------------------------------------------- CompletionsStream
def _completions_case(pt, cols, unknown, stretch, n, rnd):
    """Every completion followed a chunk at a time against the whole trace fed as one chunk
    (:func:`decide`, where Kleene's reading is open at the last tick)."""
    if kleene_unsupported(pt):
        return None
    holds, (lo, hi, _last), why = decide(pt, cols, unknown, n, True, stretch)
    if lo or not hi:
        return holds
    kleene = KleeneStream(pt)
    for part, unk, k, _a, gaps in _chunks(rnd, n, cols, unknown, stretch):
        kleene.feed(part, unk, k, gaps)
    if kleene.free is None:
        assert holds is False
        return holds
    stream = CompletionsStream(pt, *kleene.free, n)
    try:
        for part, unk, k, _a, gaps in _chunks(rnd, n, cols, unknown, stretch):
            stream.feed(part, unk, k, gaps)
        got: object = stream.finish()
    except TooManyStates as exc:
        got = str(exc)
    assert got == (why or holds), pt
    return why or holds


@settings(max_examples=300, deadline=None)
@given(st.integers(0, len(KEYS) - 1), st.integers(1, 40), _SEEDS)
def test_the_completions_in_chunks_are_those_of_one_chunk(all_keys, index, n, rnd):
    """Every completion followed a chunk at a time (the state before the first unknown
    tick carried, the states stepped over the unknown ticks and the gaps' further ticks,
    each completion evaluated from its state over the rest) gives the whole trace's
    answer."""
    pt, _ms = all_keys[index]
    cols, unknown, stretch, _times = _trace(rnd, n)
    _completions_case(pt, cols, unknown, stretch, n, rnd)


@settings(max_examples=200, deadline=None)
@given(_PAST, st.integers(1, 30), _SEEDS)
def test_the_completions_of_past_time_formulas_in_chunks(node, n, rnd):
    cols, unknown, stretch, _times = _trace(rnd, n)
    _completions_case(node, cols, unknown, stretch, n, rnd)


def test_the_completions_outgrow_at_the_same_tick_in_chunks(monkeypatch):
    """Past the bound on the work, the chunks stop at the tick the whole trace stops."""
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
    got = _completions_case(pt, cols, unknown, None, n, random.Random(1))
    assert isinstance(got, str) and "node evaluations by tick" in got
