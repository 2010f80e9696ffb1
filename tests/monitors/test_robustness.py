"""monitors.robustness: the pt formula's space robustness equals a brute-force
evaluation of the quantitative semantics' definitions (windows and since as max/min over
every earlier tick, no recurrence, no numpy; comparisons' truth and terms from the reference
evaluator compiler.evaluate) on random traces, for every FRET template key; its sign is the
judge's verdict (interval semantics) and the pt verdict at every tick."""

from __future__ import annotations

import math
import random
from functools import lru_cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.compiler import evaluate, ir
from fretc.fretish import ast as A
from fretc.monitors.judge import judge
from fretc.monitors.robustness import (TINY, robustness, robustness_columns,
                                       robustness_series)
from fretc.monitors.vectorized import pt_series

from _monitor_helpers import KEYS, compiled, samples

INF = math.inf

# numeric responses and conditions (every comparison operator), and boolean ones
_X = A.Var("x")


def _cmp(op, value):
    return A.Binary(op, _X, A.NumLit(str(value)))


RESPONSES = [
    _cmp(">", 2),
    A.Binary("|", A.Var("r"), _cmp("<=", 1)),
    A.Unary("!", _cmp("<", 1)),
    A.Binary("&", _cmp("!=", 3), _cmp(">=", 0.5)),
    A.Binary("->", A.Var("r"), _cmp("=", 2)),
    A.Binary("xor", A.Var("r"), _cmp("<", 4)),
    A.Var("r"),
]
CONDITIONS = [_cmp(">=", 2), A.Binary("&", A.Var("c"), _cmp("<=", 3)), A.Var("c"),
              A.Binary("<->", A.Var("c"), _cmp(">", 1))]


def _requirement(scope, cond, timing, i):
    sc = A.Scope(scope, A.Binary("<", A.Var("y"), A.NumLit("2")) if scope != "null" else None)
    cd = A.Condition(cond, CONDITIONS[i % len(CONDITIONS)] if cond != "null" else None)
    n = i % 4
    tm = A.Timing(timing,
                  duration=A.Duration(str(n), "ticks") if timing in A.DURATION_TIMINGS else None,
                  stop=A.Var("s") if timing in A.STOP_TIMINGS else None)
    text = f"<{scope},{cond},{timing}> #{i}"
    return A.Requirement(text, scope=sc, condition=cd, component="sw", timing=tm,
                         response=RESPONSES[i % len(RESPONSES)])


@pytest.fixture(scope="module")
def all_keys():
    """One compiled requirement per template key whose pt formula is evaluable."""
    return [compiled(_requirement(s, c, t, i), rid=f"K{i}")
            for i, (s, c, t) in enumerate(KEYS)]


def _trace(rnd: random.Random, n: int) -> dict:
    values = [0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 2.25, -1.0, math.nan]
    cols = {v: np.array([rnd.random() < 0.5 for _ in range(n)], dtype=np.bool_)
            for v in ("m", "c", "r", "s")}
    for v in ("x", "y"):
        cols[v] = np.array([rnd.choice(values) for _ in range(n)])
    return cols


# ---------------------------------------------------------------- the brute-force reference
def _neg(v: float) -> float:
    return -TINY if v == 0 else -v


class BruteForce:
    """rho(node, i) straight from the definitions (module docstring of
    monitors.robustness), one tick at a time."""

    def __init__(self, cols: dict, n: int):
        self.trace = samples(cols, n)
        self.n = n
        self.rho = lru_cache(maxsize=None)(self._rho)

    def _truth(self, node, i):
        return bool(evaluate.series(node, self.trace)[i])

    def _rho(self, node, i):  # noqa: C901 - one case per operator, as the definition
        op, a = node.op, node.args
        if op == "cmp":
            x = float(evaluate.series(a[0], self.trace)[i])
            y = float(evaluate.series(a[1], self.trace)[i])
            d = {"<": y - x, "<=": y - x, ">": x - y, ">=": x - y,
                 "=": -abs(x - y), "!=": abs(x - y)}[node.name]
            truth = self._truth(node, i)
            if truth and not d >= 0:
                return 0.0
            if not truth and not d < 0:
                return -TINY
            return d
        if op == "!":
            return _neg(self.rho(a[0], i))
        if op in ("&", "|"):
            f = min if op == "&" else max
            return f(self.rho(a[0], i), self.rho(a[1], i))
        if op == "->":
            return max(_neg(self.rho(a[0], i)), self.rho(a[1], i))
        if op in ("<->", "xor"):
            p, q = self.rho(a[0], i), self.rho(a[1], i)
            iff = min(max(_neg(p), q), max(p, _neg(q)))
            return iff if op == "<->" else _neg(iff)
        if op in ("Y", "Z"):
            if i == 0:
                return -INF if op == "Y" else INF
            return self.rho(a[0], i - 1)
        if op in ("O", "H"):
            lo, hi = (node.lo or 0, node.hi) if node.hi is not None else (0, i)
            window = [self.rho(a[0], j) for j in range(max(0, i - hi), i - lo + 1)]
            if op == "O":
                return max(window, default=-INF)
            return min(window, default=INF)
        if op == "S":  # max over j of min(b[j], a over (j, i])
            return max(min([self.rho(a[1], j)] + [self.rho(a[0], k) for k in range(j + 1, i + 1)])
                       for j in range(i + 1))
        if op == "T":  # min over j of max(b[j], a over (j, i])
            return min(max([self.rho(a[1], j)] + [self.rho(a[0], k) for k in range(j + 1, i + 1)])
                       for j in range(i + 1))
        if op == "ite":
            c = self.rho(a[0], i)
            return max(min(c, self.rho(a[1], i)), min(_neg(c), self.rho(a[2], i)))
        return INF if self._truth(node, i) else -INF


def _check(comp, cols, n):
    f = comp.formalization
    rob = robustness(f.pt, cols, n)
    ref = BruteForce(cols, n).rho(f.pt, n - 1)
    assert rob.value == ref, comp.text
    _check_tick(f.pt, rob, cols, n)
    # the sign is the verdict: of the judge (interval semantics), and of pt at every tick
    j = judge(comp.requirement, f, cols, n)
    assert (rob.value >= 0) == j.holds, comp.text
    assert j.robustness is not None and j.robustness.value == rob.value
    signs = (robustness_series(f.pt, cols, n) >= 0).tolist()
    assert signs == pt_series(f.pt, cols, n).tolist(), comp.text


def _margin(pt, cols, n):
    """The margin at every tick: the robustness of a top ``H``'s body, else of ``pt``."""
    return robustness_series(pt.args[0] if pt.op == "H" and pt.hi is None else pt, cols, n)


def _check_tick(pt, rob, cols, n):
    """:attr:`RobustnessSummary.tick` by its definition: the first tick at the least margin
    for a top ``H``, else the first tick of the last run of ticks at the last tick's
    margin."""
    m, t = _margin(pt, cols, n), rob.tick
    assert m[t] == rob.value
    if pt.op == "H" and pt.hi is None:
        assert rob.value == m.min() and not (m[:t] == rob.value).any()
    else:
        assert rob.value == m[-1] and (m[t:] == rob.value).all()
        assert t == 0 or m[t - 1] != rob.value


@pytest.mark.tor("TOR-VER-007")
def test_every_template_key_against_brute_force(all_keys):
    rnd = random.Random(29)
    for comp in all_keys:
        for _ in range(3):
            n = rnd.randint(1, 9)
            _check(comp, _trace(rnd, n), n)


@settings(max_examples=120, deadline=None)
@given(st.integers(0, len(KEYS) - 1), st.integers(1, 12), st.randoms(use_true_random=False))
def test_random_keys_and_traces_against_brute_force(all_keys, index, n, rnd):
    _check(all_keys[index], _trace(rnd, n), n)


@settings(max_examples=200, deadline=None)
@given(st.integers(0, len(KEYS) - 1), st.integers(2, 30), st.integers(1, 7),
       st.randoms(use_true_random=False))
def test_chunks_give_the_margin_of_the_whole_trace(all_keys, index, n, chunk, rnd):
    """Evaluated ``chunk`` ticks at a time (every temporal operator's state carried over,
    bounded windows their last ticks), the margin, value and tick are the whole trace's,
    bit for bit, wherever the chunks' edges fall."""
    pt = all_keys[index].formalization.pt
    cols = _trace(rnd, n)
    whole = robustness(pt, cols, n, chunk=n, points=n)
    parts = robustness(pt, cols, n, chunk=chunk, points=n)
    assert (parts.value, parts.tick) == (whole.value, whole.tick), all_keys[index].text
    for got in (parts, whole):  # (every tick: n points)
        assert [t for t, _tt, _v in got.points] == list(range(n)), all_keys[index].text
        margin = np.array([v for _t, _tt, v in got.points])
        assert margin.tobytes() == _margin(pt, cols, n).tobytes(), all_keys[index].text


@settings(max_examples=60, deadline=None)
@given(st.integers(0, len(KEYS) - 1), st.lists(st.integers(1, 9), min_size=1, max_size=6),
       st.randoms(use_true_random=False))
def test_traces_end_to_end_give_each_traces_own_robustness(all_keys, index, lengths, rnd):
    """Traces laid end to end and evaluated at once (every temporal operator restarting at
    each trace's first tick: the per-entity audit's violated entities) give each trace the
    value, tick and margin of :func:`robustness` over that trace alone, bit for bit."""
    pt = all_keys[index].formalization.pt
    traces = [_trace(rnd, m) for m in lengths]
    cols = {k: np.concatenate([t[k] for t in traces]) for k in traces[0]}
    counts = np.array(lengths, dtype=np.int64)
    firsts = np.cumsum(counts) - counts
    got = robustness_columns(pt, cols, firsts, counts)
    assert got is not None, all_keys[index].text  # (no template compares a past-time operand)
    margin, values, ticks = got
    for t, a, m, value, tick in zip(traces, firsts, lengths, values, ticks):
        alone = robustness(pt, t, m)
        assert (value, tick) == (alone.value, alone.tick) or (
            math.isnan(value) and math.isnan(alone.value)), all_keys[index].text
        assert margin[a:a + m].tobytes() == _margin(pt, t, m).tobytes(), all_keys[index].text


_ATOMS = st.sampled_from(["m", "c", "r", "s"]).map(ir.ap)
_PAST = st.recursive(_ATOMS, lambda sub: st.one_of(
    sub.map(ir.Y), sub.map(ir.Z), sub.map(ir.not_),
    st.tuples(sub, st.integers(0, 2), st.integers(0, 3)).map(
        lambda a: ir.O(a[0], a[1], a[1] + a[2])),
    st.tuples(sub, st.integers(0, 2), st.integers(0, 3)).map(
        lambda a: ir.H(a[0], a[1], a[1] + a[2])),
    sub.map(ir.O), sub.map(ir.H),
    st.tuples(sub, sub).map(lambda a: ir.S(*a)), st.tuples(sub, sub).map(lambda a: ir.T(*a)),
    st.tuples(sub, sub).map(lambda a: ir.and_(*a))), max_leaves=6)


@settings(max_examples=60, deadline=None)
@given(_PAST, st.lists(st.integers(1, 7), min_size=1, max_size=5),
       st.randoms(use_true_random=False))
def test_any_past_formula_end_to_end_gives_each_traces_own_robustness(pt, lengths, rnd):
    """As above for any past-time formula of boolean atoms (bounded windows that reach back
    before a trace's first tick, since and trigger restarting at each trace)."""
    traces = [_trace(rnd, m) for m in lengths]
    cols = {k: np.concatenate([t[k] for t in traces]) for k in traces[0]}
    counts = np.array(lengths, dtype=np.int64)
    firsts = np.cumsum(counts) - counts
    got = robustness_columns(pt, cols, firsts, counts)
    assert got is not None
    margin, values, ticks = got
    for t, a, m, value, tick in zip(traces, firsts, lengths, values, ticks):
        alone = robustness(pt, t, m)
        assert (value, tick) == (alone.value, alone.tick), pt
        assert margin[a:a + m].tobytes() == _margin(pt, t, m).tobytes(), pt


@pytest.mark.tor("TOR-VER-007")
def test_numeric_margin_is_the_distance_to_the_threshold():
    """``always x <= 0.5``: the least margin, where it first occurs; a strict comparison at
    its threshold is violated at distance 0 (-TINY), a non-strict one satisfied (0.0)."""
    from _monitor_helpers import entry
    from fretc.compiler.build import compile_entry

    def value(text, xs):
        c = compile_entry(entry("R", text))
        cols = {"x": np.array(xs, dtype=float)}
        r = robustness(c.formalization.pt, cols, len(xs))
        return r.value, r.tick

    assert value("the sw shall always satisfy x <= 0.5", [0.125, 0.25, 0.375, 0.375]) == (0.125, 2)
    assert value("the sw shall always satisfy x <= 0.5", [0.1, 0.75, 0.2]) == (-0.25, 1)
    assert value("the sw shall always satisfy x <= 0.5", [0.5, 0.1]) == (0.0, 0)
    assert value("the sw shall always satisfy x < 0.5", [0.1, 0.5]) == (-TINY, 1)
    # a vacuous requirement: the margin by which the condition never held
    assert value("whenever x > 3 the sw shall immediately satisfy x > 10",
                 [1.0, 2.5, 2.0])[0] == pytest.approx(0.5)


def test_the_tick_of_a_last_value_is_where_its_last_run_began():
    """A pt formula without a top ``H`` (a scope): the value is the last tick's margin and
    the tick the first of the last run of ticks at it (the margin 0.5 at ticks 0-1 came
    from the first mode interval; the second's eventually met at tick 3 decides)."""
    from _monitor_helpers import entry
    from fretc.compiler.build import compile_entry

    c = compile_entry(entry("R", "in m mode the sw shall eventually satisfy x > 1"))
    cols = {"x": np.array([1.5, 0.0, 0.5, 1.5]), "m": np.array([True, False, True, True])}
    r = robustness(c.formalization.pt, cols, 4)
    assert [v for _t, _tt, v in r.points] == [0.5, 0.5, -0.5, 0.5]
    assert (r.value, r.tick) == (0.5, 3)


def test_memory_is_a_few_arrays_of_the_ticks_not_objects_per_tick():
    """A 10^7-row CSV audit took 1.27 GB, most of it here: the since recurrence as Python
    lists of every tick (about 100 bytes a tick) and an array kept for every node of the
    formula. Measured by the allocations the computation makes (tracemalloc counts numpy's),
    not by time: at most 16 float arrays of the ticks at the peak, for a requirement whose pt
    formula has more than 20 nodes (the values: the brute-force tests above)."""
    import tracemalloc

    from _monitor_helpers import entry
    from fretc.compiler import ir
    from fretc.compiler.build import compile_entry

    c = compile_entry(entry("R", "in m mode upon p the sw shall within 3 ticks satisfy x > 1"))
    pt = c.formalization.pt
    assert len(set(ir.walk(pt))) > 20
    n = 200_000
    rng = np.random.default_rng(3)
    cols = {"m": rng.random(n) < 0.9, "p": rng.random(n) < 0.3, "x": rng.random(n) * 3}
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        robustness(pt, cols, n)
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    assert peak < 16 * 8 * n, f"{peak / n:.0f} bytes a tick"
