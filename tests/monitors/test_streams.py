"""monitors.robustness.RobustnessStream and monitors.judge.Ltl3Stream at every chunk boundary:
a trace fed a chunk of ticks at a time (any chunks: empty ones, single ticks, edges anywhere
across the blocks of ROBUSTNESS_CHUNK ticks, a boolean column's dtype changing from chunk to
chunk) gives the robustness value, tick and margin points and the LTL3 verdict and tick of
the whole trace fed as one chunk, the same bits, and the margin points are those of the
margin evaluated over the whole trace at once (robustness_series); margin_ticks equals a
brute-force reading of its definition; the stream's memory does not grow with the trace."""

from __future__ import annotations

import math
import random
import struct
import tracemalloc
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.compiler import ir
from fretc.compiler.build import compile_entry
from fretc.compiler.codegen import monitor_source
from fretc.compiler.pt_step import CodegenError
from fretc.monitors import robustness as rob_module
from fretc.monitors.judge import Ltl3Stream, ltl3_verdict
from fretc.monitors.robustness import (RobustnessStream, _MarginRuns, chunkable, margin_ticks,
                                       past_truth, robustness, robustness_series)
from fretc.monitors.vectorized import VectorizeError, node_series, supports

from _monitor_helpers import KEYS, entry, keyed_monitors
from differential import random_requirement

RESPONSES = ["r", "!r", "r | s", "r & c", "r xor m", "x > 2"]
CONDITIONS = ["c", "!c", "c & x <= 3"]
BOOLS = ("m", "c", "r", "s")
X_VALUES = [0.0, 1.0, 2.0, 2.0, 3.0, 4.0, -0.0, 2.5, math.nan]


@pytest.fixture(scope="module")
def all_keys():
    """Per template key: the pt formula and the monitor source (varied response,
    condition, duration)."""
    return keyed_monitors(RESPONSES, CONDITIONS)


def _bits(x: float) -> bytes:
    return struct.pack("<d", x)


def _trace(rnd: random.Random, n: int) -> tuple[dict, np.ndarray]:
    cols = {v: np.array([rnd.random() < 0.5 for _ in range(n)], dtype=np.bool_) for v in BOOLS}
    cols["x"] = np.array([rnd.choice(X_VALUES) for _ in range(n)])
    times = np.cumsum([rnd.randint(1, 10**6) for _ in range(n)]).astype(np.int64)
    return cols, times


def _chunks(rnd: random.Random, n: int, cols: dict, times: np.ndarray):
    """``(columns, k, times)`` of random chunks (empty ones and single ticks included), each
    boolean column as bool, uint8 0/1 or float64 0/1 at random; the chunks given as copies
    in arrays longer than ``k`` at times (only their first ``k`` values are the ticks)."""
    a = 0
    while a < n:
        k = min(n - a, rnd.choice([0, 1, 1, 2, 3, 5, 8, 13]))
        part = {}
        for name, col in cols.items():
            piece = col[a:a + k]
            if col.dtype == np.bool_:
                piece = piece.astype(rnd.choice([np.bool_, np.uint8, np.float64]))
            if rnd.random() < 0.3:  # (the reader's buffer, longer than the chunk)
                piece = np.concatenate((piece, piece[:1]))
            part[name] = piece
        yield part, k, times[a:a + k]
        a += k


def _fed_robustness(pt, points: int, chunk: int, rnd, n, cols, times):
    stream = RobustnessStream(pt, points, chunk=chunk)
    for part, k, t in _chunks(rnd, n, cols, times):
        stream.feed(part, k, t)
    return stream.finish()


def _expected_points(margin, times, points):
    return [(i, int(times[i]), float(margin[i])) for i in margin_ticks(margin, points)]


def _assert_same_robustness(got, pt, cols, n, times, points, what, chunk=None):
    """``got`` (fed in chunks) against the whole trace fed as one chunk (blocks of
    ``chunk`` ticks), and its points against the margin over the whole trace at once."""
    want = robustness(pt, cols, n, chunk, times=times, points=points)
    assert _bits(got.value) == _bits(want.value), what
    assert (got.tick, got.tick_time) == (want.tick, int(times[want.tick])), what
    assert got.n == want.n == n, what
    body = pt.args[0] if pt.op == "H" and pt.hi is None else pt
    expected = _expected_points(robustness_series(body, cols, n), times, points)
    for kept in (got.points, want.points):
        assert [(t, tt, _bits(v)) for t, tt, v in kept] == \
            [(t, tt, _bits(v)) for t, tt, v in expected], what


# ---------------------------------------------------------------- margin_ticks
def _brute_margin_ticks(margin: list[float], points: int) -> list[int]:
    """margin_ticks' definition, tick by tick: runs of B (the least power of two with
    ceil(n / B) <= points) from tick 0; per run the least value, the first at ties, NaN
    least."""
    n, size = len(margin), 1
    while math.ceil(n / size) > points:
        size *= 2
    out = []
    for a in range(0, n, size):
        best = a
        for i in range(a, min(n, a + size)):
            if math.isnan(margin[best]):
                break
            if math.isnan(margin[i]) or margin[i] < margin[best]:
                best = i
        out.append(best)
    return out


#: seeds of the random draws of a case (a hypothesis ``randoms`` drawing every tick and chunk
#: makes its smallest example too large)
_SEEDS = st.integers(0, 2**32 - 1).map(random.Random)

_MARGINS = st.lists(st.sampled_from([0.0, -0.0, 1.0, -1.0, 0.5, math.inf, -math.inf,
                                     math.nan, 2.0]), max_size=300)


@settings(max_examples=300, deadline=None)
@given(_MARGINS, st.integers(1, 40))
def test_margin_ticks_by_its_definition(values, points):
    got = margin_ticks(np.array(values, dtype=np.float64), points)
    assert got == _brute_margin_ticks(values, points)
    assert len(got) <= points and got == sorted(set(got))
    assert all(isinstance(t, int) for t in got)


@settings(max_examples=300, deadline=None)
@given(_MARGINS, st.integers(1, 12), _SEEDS)
def test_margin_runs_fed_in_chunks_keep_margin_ticks(values, points, rnd):
    """The stream's margin points (runs merged two by two as the ticks outgrow ``points``
    runs) are margin_ticks' over the whole margin, with each tick's time and value."""
    margin = np.array(values, dtype=np.float64)
    times = np.arange(len(values), dtype=np.int64) * 7 + 3
    runs, a = _MarginRuns(points), 0
    while a < len(values):
        k = min(len(values) - a, rnd.choice([1, 1, 2, 3, 7, 16, 50]))
        runs.add(margin[a:a + k], a, times[a:a + k])
        a += k
    want = _expected_points(margin, times, points)
    assert [(t, tt, _bits(v)) for t, tt, v in runs.points_list()] == \
        [(t, tt, _bits(v)) for t, tt, v in want]


def test_margin_ticks_of_a_long_margin():
    """1000 ticks, 400 points: runs of 4 ticks (250 points); 400 ticks: every tick; 401:
    runs of 2 (the last of one tick)."""
    m = np.zeros(1000)
    m[[5, 998]] = -1.0
    ticks = margin_ticks(m, 400)
    assert len(ticks) == 250 and ticks[:3] == [0, 5, 8] and ticks[-1] == 998
    assert margin_ticks(m[:400], 400) == list(range(400))
    assert margin_ticks(np.zeros(401), 400) == list(range(0, 401, 2))
    with pytest.raises(ValueError):
        margin_ticks(m, 0)


# ---------------------------------------------------------------- RobustnessStream
@settings(max_examples=200, deadline=None)
@given(st.integers(0, len(KEYS) - 1), st.integers(1, 60), st.integers(1, 8),
       st.integers(1, 6), _SEEDS)
def test_robustness_stream_equals_robustness(all_keys, index, n, chunk, points, rnd):
    """Every template key: fed in random chunks with blocks of ``chunk`` ticks, the value,
    tick, its time and the margin points are robustness()'s over the whole trace (in blocks
    of ``chunk`` ticks, and at once), bit for bit; a window longer than a block refused."""
    pt = all_keys[index][0]
    cols, times = _trace(rnd, n)
    try:
        got = _fed_robustness(pt, points, chunk, rnd, n, cols, times)
    except VectorizeError:  # (a window longer than a block: the whole trace at once)
        assert not rob_module._chunkable(pt, chunk), index
        return
    _assert_same_robustness(got, pt, cols, n, times, points, index, chunk)
    _assert_same_robustness(got, pt, cols, n, times, points, index, n)


def test_robustness_stream_with_a_small_robustness_chunk(all_keys, monkeypatch):
    """ROBUSTNESS_CHUNK itself set to 8 (both paths read it): long traces over many blocks,
    fed in chunks whose edges fall anywhere in them."""
    monkeypatch.setattr(rob_module, "ROBUSTNESS_CHUNK", 8)
    rnd = random.Random(41)
    for pt, _ in all_keys[::5]:
        n = rnd.randint(1, 90)
        cols, times = _trace(rnd, n)
        stream = RobustnessStream(pt, 7)
        assert stream.chunk == 8
        for part, k, t in _chunks(rnd, n, cols, times):
            stream.feed(part, k, t)
        _assert_same_robustness(stream.finish(), pt, cols, n, times, 7, pt)


def _random_compiled(seed: int):
    """A random requirement over the whole grammar (tests/differential.py), compiled, and
    columns for every variable its pt formula and ft_inf read."""
    text, _ = random_requirement(random.Random(seed))
    comp = compile_entry(entry("R", text))
    assert comp.error is None, comp.error
    return text, comp


def _columns_for(comp, rnd: random.Random, n: int) -> tuple[dict, np.ndarray]:
    f = comp.formalization
    cols = {}
    for node in list(ir.walk(f.pt)) + list(ir.walk(f.ft_inf)):
        if node.op == "ap":
            cols[ir.name_of(node)] = np.array([rnd.random() < 0.5 for _ in range(n)], np.bool_)
        elif node.op == "var":
            cols[ir.name_of(node)] = np.array([float(rnd.randint(-1, 3)) for _ in range(n)])
    times = np.cumsum([rnd.randint(1, 1000) for _ in range(n)]).astype(np.int64)
    return cols, times


@settings(max_examples=150, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 40), st.integers(1, 8), st.integers(1, 5),
       _SEEDS)
def test_robustness_stream_of_random_requirements(seed, n, chunk, points, rnd):
    """Random requirements (past-time functions, nested conditions, every scope and
    timing): the stream equals robustness(), or refuses a formula that cannot be evaluated a
    chunk at a time (a future-time function; a comparison over a past-time value; a window
    longer than a block)."""
    text, comp = _random_compiled(seed)
    pt = comp.formalization.pt
    top = pt.op == "H" and pt.hi is None
    body = pt.args[0] if top else pt
    cols, times = _columns_for(comp, rnd, n)
    try:
        got = _fed_robustness(pt, points, chunk, rnd, n, cols, times)
    except VectorizeError:
        assert not supports(pt) or not rob_module._chunkable(body, chunk), text
        return
    _assert_same_robustness(got, pt, cols, n, times, points, text, chunk)


def test_robustness_stream_refusals_and_errors():
    comp = compile_entry(entry("R", "the sw shall always satisfy persists(2, p)"))
    with pytest.raises(VectorizeError):
        RobustnessStream(comp.formalization.pt, 10)
    window = compile_entry(entry("R", "the sw shall always satisfy persisted(9, p) -> q"))
    RobustnessStream(window.formalization.pt, 10)  # (a window of 9 ticks in a block of 8:)
    with pytest.raises(VectorizeError):
        RobustnessStream(window.formalization.pt, 10, chunk=8)
    compared = ir.cmp(">", ir.Node("pre", (ir.num("0"), ir.var("x"))), ir.num("1"))
    assert not chunkable(compared)
    with pytest.raises(VectorizeError):
        RobustnessStream(ir.H(compared), 10)
    at_once = RobustnessStream(ir.H(compared), 10, whole=True)  # (the whole trace, one chunk)
    at_once.feed({"x": np.array([0.0, 2.0, 3.0])}, 3, np.arange(3))
    with pytest.raises(ValueError, match="one chunk"):
        at_once.feed({"x": np.array([0.0])}, 1, np.arange(1))
    assert at_once.finish() == robustness(ir.H(compared), {"x": np.array([0.0, 2.0, 3.0])}, 3,
                                          points=10)
    stream = RobustnessStream(window.formalization.pt, 10)
    with pytest.raises(VectorizeError, match="'q'"):
        stream.feed({"p": np.ones(3, np.bool_)}, 3, np.arange(3))
    with pytest.raises(ValueError):
        stream.finish()  # (no tick)
    with pytest.raises(ValueError):
        RobustnessStream(window.formalization.pt, 0)


def test_robustness_stream_memory_does_not_grow_with_the_trace():
    """The peak of the allocations while a trace is fed (tracemalloc counts numpy's) is the
    same for 4 and for 16 blocks of ticks: the blocks, a chunk's arrays and the margin
    points, not the ticks."""
    c = compile_entry(entry("R", "in m mode upon p the sw shall within 3 ticks satisfy x > 1"))
    pt = c.formalization.pt

    def peak(n: int) -> int:
        rng = np.random.default_rng(5)
        stream = RobustnessStream(pt, 400, chunk=4096)
        tracemalloc.start()
        try:
            base = tracemalloc.get_traced_memory()[0]
            for a in range(0, n, 1000):
                k = min(1000, n - a)
                cols = {"m": rng.random(k) < 0.9, "p": rng.random(k) < 0.3,
                        "x": rng.random(k) * 3}
                stream.feed(cols, k, np.arange(a, a + k, dtype=np.int64))
            stream.finish()
            return tracemalloc.get_traced_memory()[1] - base
        finally:
            tracemalloc.stop()

    short, long = peak(4 * 4096), peak(16 * 4096)
    assert long < short * 1.25 + 50_000, (short, long)


# ---------------------------------------------------------------- Ltl3Stream
_ATOMS = st.one_of(st.sampled_from(BOOLS).map(ir.ap), st.just(ir.Node("FTP")),
                   st.sampled_from(["<", "<=", "=", "!=", ">=", ">"]).map(
                       lambda op: ir.cmp(op, ir.var("x"), ir.num("2"))))
_PAST = st.recursive(_ATOMS, lambda sub: st.one_of(
    sub.map(ir.Y), sub.map(ir.Z), sub.map(ir.not_), sub.map(ir.O), sub.map(ir.H),
    st.tuples(sub, st.integers(0, 2), st.integers(0, 3)).map(
        lambda a: ir.O(a[0], a[1], a[1] + a[2])),
    st.tuples(sub, st.integers(0, 2), st.integers(0, 3)).map(
        lambda a: ir.H(a[0], a[1], a[1] + a[2])),
    st.tuples(sub, sub).map(lambda a: ir.S(*a)), st.tuples(sub, sub).map(lambda a: ir.T(*a)),
    st.tuples(sub, sub).map(lambda a: ir.and_(*a)),
    st.tuples(sub, sub).map(lambda a: ir.xor(*a))), max_leaves=6)


@settings(max_examples=200, deadline=None)
@given(_PAST, st.integers(1, 30), _SEEDS)
def test_past_truth_fed_in_chunks_is_the_truth_over_the_whole_trace(node, n, rnd):
    """The truth of a past-time formula as the sign of its robustness, chunk by chunk with
    its operators' state carried (how Ltl3Stream reads an atom holding a past-time
    function), is node_series' over the whole trace."""
    cols, _ = _trace(rnd, n)
    carry: dict = {}
    got, a = [], 0
    while a < n:
        k = min(n - a, rnd.choice([1, 1, 2, 3, 5]))
        got += past_truth(node, {v: c[a:a + k] for v, c in cols.items()}, k, a, carry).tolist()
        a += k
    assert got == node_series(node, cols, n).tolist(), node


def _fed_ltl3(ms, rnd, n, cols, times):
    stream = Ltl3Stream(ms)
    for part, k, t in _chunks(rnd, n, cols, times):
        stream.feed(part, k, t)
    return stream.finish()


@pytest.mark.tor("TOR-VER-009", "TOR-LOG-003")
@settings(max_examples=200, deadline=None)
@given(st.integers(0, len(KEYS) - 1), st.integers(1, 40), _SEEDS)
def test_ltl3_stream_equals_ltl3_verdict(all_keys, index, n, rnd):
    ms = all_keys[index][1]
    cols, times = _trace(rnd, n)
    status, tick, time = _fed_ltl3(ms, rnd, n, cols, times)
    assert (status, tick) == ltl3_verdict(ms, cols, n), index
    assert time == (None if tick is None else int(times[tick])), index


@pytest.mark.tor("TOR-VER-009", "TOR-LOG-003")
@settings(max_examples=150, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 40), _SEEDS)
def test_ltl3_stream_of_random_requirements(seed, n, rnd):
    """Random requirements: atoms that read earlier ticks (past-time functions inside
    ft_inf) carried from chunk to chunk."""
    text, comp = _random_compiled(seed)
    try:
        ms = monitor_source(comp, 0)
    except CodegenError:  # (a future-time function: no online monitor)
        return
    cols, times = _columns_for(comp, rnd, n)
    status, tick, time = _fed_ltl3(ms, rnd, n, cols, times)
    assert (status, tick) == ltl3_verdict(ms, cols, n), text
    assert time == (None if tick is None else int(times[tick])), text


def test_ltl3_stream_takes_an_atom_over_pre_in_one_chunk():
    """An atom comparing a past-time value is evaluated over the whole trace fed as one
    chunk (``whole``), and refused in chunks."""
    comp = compile_entry(entry("R", "the sw shall always satisfy preReal(0, x) <= x + 1"))
    ms = monitor_source(comp, 0)
    with pytest.raises(VectorizeError):
        Ltl3Stream(ms)
    stream = Ltl3Stream(ms, whole=True)
    stream.feed({"x": np.array([0.0, 2.0, 0.5])}, 3, np.arange(3))
    with pytest.raises(ValueError, match="one chunk"):
        stream.feed({"x": np.array([0.0])}, 1, np.arange(1))
    assert stream.finish()[:2] == ("violated", 2)


@pytest.mark.tor("TOR-VER-009", "TOR-LOG-003")
def test_ltl3_stream_carries_past_atoms_and_refuses_chains():
    """An atom holding a past-time function is evaluated with its state carried (a 3-tick
    window across 1-tick chunks); an automaton without a table is refused as ltl3_verdict
    refuses it."""
    comp = compile_entry(entry("R", "upon persisted(3, p) the sw shall immediately satisfy q"))
    ms = monitor_source(comp, 0)
    stream = Ltl3Stream(ms)
    assert stream.carry  # (the persisted atom)
    p = [True, True, True, True, False]
    q = [False, False, False, False, False]
    for i in range(5):
        stream.feed({"p": np.array(p[i:i + 1]), "q": np.array(q[i:i + 1])}, 1,
                    np.array([100 * i]))
    cols = {"p": np.array(p), "q": np.array(q)}
    assert stream.finish() == (*ltl3_verdict(ms, cols, 5), 300)
    chains = SimpleNamespace(empty=False, complete=False, table=None, atoms=(), initial=0)
    fake = SimpleNamespace(bad=chains, good=None)
    with pytest.raises(VectorizeError):
        ltl3_verdict(fake, {}, 1)
    with pytest.raises(VectorizeError):
        Ltl3Stream(fake)
    empty = SimpleNamespace(bad=SimpleNamespace(empty=True), good=None)
    decided = Ltl3Stream(empty)
    decided.feed({}, 3, np.arange(3))
    assert decided.finish() == ("violated", None, None)
