"""Gap ticks against brute force: a gap tick (a CSV trace's ``gap`` row, a tick a gap of a tick
topic lost) stands for one tick or more, how many not known (docs/guide/ticks.md). On random
traces with unknown cells and gap ticks, a verdict the three-valued judge gives is the one
every completion gives, each gap filled with one, two or three ticks of any values and each
unknown cell with any value: FRET's finite-trace verdict (the pt formula, two-valued, over the
filled trace), the LTL3 verdict (the monitor automata), the definite triggers counted (the
interval semantics over the filled trace) and the trials a probability bound counts."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from fretc.audit.trials import trigger_outcomes
from _monitor_helpers import compiled_of, pqmx_columns
from fretc.compiler import ir
from fretc.monitors.completions import decide
from fretc.monitors.definite import definite_evidence
from fretc.monitors.interval import evaluate_requirement
from fretc.monitors.judge import ltl3_verdict as ltl3_two
from fretc.monitors.three_valued import kleene_values, ltl3_verdict, stretched_window
from fretc.monitors.unknowns import Unknowns
from fretc.monitors.vectorized import node_series, pt_series

#: scopes, conditions and timings: each counts ticks in its own way
SENTENCES = [
    "upon !p the sw shall at the next timepoint satisfy q | x > 1",
    "after p the sw shall always satisfy x > 1",
    "the sw shall always satisfy p",
    "upon p the sw shall within 2 ticks satisfy q",
    "upon p the sw shall for 2 ticks satisfy q",
    "whenever p the sw shall immediately satisfy q",
    "in m mode the sw shall always satisfy q",
    "before m the sw shall always satisfy p",
    "upon p the sw shall after 1 ticks satisfy q",
    "only after m the sw shall never satisfy p",
    "the sw shall eventually satisfy p",
    "upon p the sw shall until q satisfy m",
    "in m mode upon p the sw shall within 1 ticks satisfy q",
    "the sw shall always satisfy persisted(2, p) -> q",
    "when x > 1 the sw shall within 1 ticks satisfy x + 1 < 3",
]
VALUES = {"p": (False, True), "q": (False, True), "m": (False, True), "x": (0.0, 1.0, 2.0)}
_compiled_of, _columns = compiled_of, pqmx_columns


def _completions(cols, n, cells, gaps, counts=(1, 2, 3)):
    """Every filled trace: each unknown cell (tick, variable) any value, each gap tick one
    to three ticks of any values of the variables read; yields (columns, length)."""
    names = sorted(cols)
    letters = list(itertools.product(*(VALUES[v] for v in names)))
    free = [(i, v) for i, v in cells if i not in gaps]
    for combo in itertools.product(*(VALUES[v] for _i, v in free)):
        base = {k: a.copy() for k, a in cols.items()}
        for (i, v), val in zip(free, combo):
            base[v][i] = val
        for ks in itertools.product(counts, repeat=len(gaps)):
            spans = [list(itertools.product(letters, repeat=k)) for k in ks]
            for fills in itertools.product(*spans):
                filled = {k: [] for k in names}
                by_gap = dict(zip(gaps, fills))
                for i in range(n):
                    rows = by_gap.get(i)
                    if rows is None:
                        for k in names:
                            filled[k].append(base[k][i])
                        continue
                    for letter in rows:
                        for k, val in zip(names, letter):
                            filled[k].append(val)
                m = len(filled[names[0]]) if names else n + sum(ks) - len(ks)
                count = dict(zip(gaps, ks))
                at = np.cumsum([0] + [count.get(i, 1) for i in range(n)])[:-1]
                yield ({k: np.array(v, dtype=cols[k].dtype) for k, v in filled.items()}, m,
                       at)


_row = st.tuples(st.booleans(), st.booleans(), st.booleans(), st.sampled_from([0.0, 1.0, 2.0]))


def _check(text, rows, holes, gap_at):
    c, ms = _compiled_of(text)
    f = c.formalization
    req = c.entry.requirement
    n = len(rows)
    cols = _columns(rows, set(f.variables))
    gaps = sorted({i for i in gap_at if i < n})
    cells = sorted({(i, v) for i, v in holes if i < n and v in cols and i not in gaps})
    unknown: dict = {}
    for i, v in cells:
        unknown.setdefault(v, np.zeros(n, np.bool_))[i] = True
    stretch = np.zeros(n, np.bool_)
    stretch[gaps] = True
    for v in cols:  # a gap tick: every variable unknown
        unknown.setdefault(v, np.zeros(n, np.bool_))[gaps] = True
    got, _reading, _why = decide(f.pt, cols, unknown, n, True, stretch)
    status, _tick = ltl3_verdict(ms, cols, unknown, n, True, stretch)
    u = Unknowns.of(req, unknown, cols, n, True, stretch)
    counted, _possible = definite_evidence(req, cols, unknown, n, f.ticks, True, stretch)
    decided = {t: kind for t, kind in trigger_outcomes(req, cols, n, f.ticks, u)
               if kind in ("satisfied", "violated")}
    outcomes, statuses = set(), set()
    for filled, m, at in _completions(cols, n, cells, gaps):
        trials = dict(trigger_outcomes(req, filled, m, f.ticks))
        for t, kind in decided.items():  # (a decided trial is the same in every completion)
            assert trials.get(int(at[t])) == kind, (text, rows, cells, gaps, filled, t)
        outcomes.add(bool(pt_series(f.pt, filled, m)[-1]))
        statuses.add(ltl3_two(ms, filled, m)[0])
        two = evaluate_requirement(req, filled, m, f.ticks)
        assert two.triggers >= counted.triggers, (text, rows, cells, gaps, filled)
        if counted.violations:
            assert not two.holds, (text, rows, cells, gaps, filled)
    if got is not None:
        assert outcomes == {got}, (text, rows, cells, gaps)
    if status != "unknown":
        assert statuses == {status}, (text, rows, cells, gaps, status, statuses)
    return got, outcomes


@settings(max_examples=150, deadline=None)
@given(text=st.sampled_from(SENTENCES), rows=st.lists(_row, min_size=1, max_size=7),
       holes=st.lists(st.tuples(st.integers(0, 6), st.sampled_from("pqmx")), max_size=2),
       gap_at=st.lists(st.integers(0, 6), min_size=1, max_size=1))
@pytest.mark.tor("TOR-VER-004")
def test_a_verdict_across_a_gap_is_what_every_count_and_filling_gives(text, rows, holes,
                                                                       gap_at):
    _check(text, rows, holes, gap_at)


@pytest.mark.tor("TOR-VER-004")
def test_a_previous_value_at_a_gap_tick_whose_value_is_known_and_changed():
    """A gap tick stands for one tick or more: where a variable is known there (its topic not
    in the gap) and differs from the tick before, its previous value is the one before at
    the gap's first tick and its own at the later ones: one tick satisfies, two violate."""
    c, _ms = compiled_of("the sw shall always satisfy preReal(0, x) < 3")
    pt = c.formalization.pt
    known = {"x": np.zeros(2, np.bool_)}
    cols = {"x": np.array([0.0, 5.0])}
    assert decide(pt, cols, known, 2, True, np.array([False, True]))[0] is None
    assert decide(pt, cols, known, 2, True, None)[0] is True  # (no gap: one tick)
    cols = {"x": np.array([5.0, 5.0])}  # unchanged: violated at the gap's first tick
    assert decide(pt, cols, known, 2, True, np.array([False, True]))[0] is False


@pytest.mark.tor("TOR-VER-004")
def test_arithmetic_negation_over_an_unknown_tick():
    """Kleene's reading of a negated number: known where its operand is, unknown at the tick
    whose value is unknown, and a violation on a known tick stands."""
    c, _ms = compiled_of("the sw shall always satisfy -x < 0")
    pt = c.formalization.pt
    none, one = np.zeros(3, np.bool_), np.array([False, True, False])
    assert decide(pt, {"x": np.array([1.0, 2.0, 3.0])}, {"x": none}, 3)[0] is True
    assert decide(pt, {"x": np.array([1.0, 2.0, 3.0])}, {"x": one}, 3)[0] is None
    assert decide(pt, {"x": np.array([1.0, 2.0, -3.0])}, {"x": one}, 3)[0] is False


@pytest.mark.slow
@settings(max_examples=3000, deadline=None)
@given(text=st.sampled_from(SENTENCES), rows=st.lists(_row, min_size=1, max_size=8),
       holes=st.lists(st.tuples(st.integers(0, 7), st.sampled_from("pqmx")), max_size=2),
       gap_at=st.lists(st.integers(0, 7), min_size=1, max_size=2))
def test_a_verdict_across_gaps_is_what_every_count_and_filling_gives_sweep(text, rows, holes,
                                                                           gap_at):
    _check(text, rows, holes, gap_at)


@pytest.mark.tor("TOR-VER-004")
@pytest.mark.parametrize("text, rows, gap", [
    # one tick in the gap meets the obligation, two ticks break it
    ("upon !p the sw shall at the next timepoint satisfy q | x > 1",
     [(False, True, False, 1.0), (False, True, False, 0.0), (True, False, False, 1.0),
      (False, False, False, 0.0), (False, True, False, 4.5)], 3),
    # the mode's first interval can end inside the gap, x broken at its second tick
    ("after p the sw shall always satisfy x > 1",
     [(False, True, False, 4.5), (False, False, False, 0.0), (True, True, False, 6.0),
      (True, True, False, 1.0), (True, True, False, 6.0)], 1),
    # q false two rows after the trigger: inside the duration with one gap tick, past it
    # with three (no definite failed trigger to show)
    ("upon p the sw shall for 2 ticks satisfy q",
     [(True, True, False, 0.0), (False, False, False, 0.0), (False, False, False, 0.0),
      (False, True, False, 0.0)], 1),
])
def test_a_verdict_one_gap_tick_gives_but_two_do_not_is_unknown(text, rows, gap):
    got, outcomes = _check(text, rows, [], [gap])
    assert got is None and outcomes == {False, True}


@settings(max_examples=300, deadline=None)
@given(lo=st.integers(0, 3), span=st.integers(0, 3), once=st.booleans(),
       values=st.lists(st.sampled_from((None, False, True)), min_size=1, max_size=7),
       gaps=st.lists(st.booleans(), min_size=7, max_size=7))
def test_a_window_over_gap_ticks_is_what_every_count_gives(lo, span, once, values, gaps):
    """``O[lo,hi]`` / ``H[lo,hi]`` over gap ticks (each one to three ticks) against the window
    over every expanded trace: true where every expansion is, false where none is."""
    hi = lo + span
    n = len(values)
    g = np.array(gaps[:n], np.bool_)
    x_lo = np.array([v is True for v in values])
    x_hi = np.array([v is not False for v in values])
    got_lo, got_hi = stretched_window((x_lo, x_hi), lo, hi, once, g)
    free = [i for i in range(n) if values[i] is None]  # (a known value: at each of its ticks)
    seen = [set() for _ in range(n)]
    for ks in itertools.product((1, 2, 3), repeat=int(g.sum())):
        count = dict(zip(np.flatnonzero(g).tolist(), ks))
        owner = [i for i in range(n) for _ in range(count.get(i, 1))]
        slots = [j for j, i in enumerate(owner) if i in free]
        for bits in itertools.product((False, True), repeat=len(slots)):
            x = [bool(values[i]) for i in owner]
            for j, b in zip(slots, bits):
                x[j] = b
            for j, i in enumerate(owner):
                window = [x[j - d] for d in range(lo, hi + 1) if j - d >= 0]
                seen[i].add(any(window) if once else all(window))
    for i in range(n):
        assert not got_lo[i] or seen[i] == {True}, (i, values, gaps, lo, hi, once)
        assert got_hi[i] or seen[i] == {False}, (i, values, gaps, lo, hi, once)


_ATOMS = st.one_of(st.sampled_from("pqm").map(ir.ap), st.just(ir.Node("FTP")),
                   st.sampled_from(["<", ">="]).map(lambda op: ir.cmp(op, ir.var("x"),
                                                                         ir.num("1"))))
_PAST = st.recursive(_ATOMS, lambda sub: st.one_of(
    sub.map(ir.Y), sub.map(ir.Z), sub.map(ir.not_), sub.map(ir.O), sub.map(ir.H),
    st.tuples(sub, st.integers(0, 2), st.integers(0, 2)).map(
        lambda a: ir.O(a[0], a[1], a[1] + a[2])),
    st.tuples(sub, st.integers(0, 2), st.integers(0, 2)).map(
        lambda a: ir.H(a[0], a[1], a[1] + a[2])),
    st.tuples(sub, sub).map(lambda a: ir.S(*a)), st.tuples(sub, sub).map(lambda a: ir.T(*a)),
    st.tuples(sub, sub).map(lambda a: ir.and_(*a))), max_leaves=4)


@settings(max_examples=200, deadline=None)
@given(node=_PAST, rows=st.lists(_row, min_size=1, max_size=5),
       holes=st.lists(st.tuples(st.integers(0, 4), st.sampled_from("pqmx")), max_size=2),
       gap_at=st.lists(st.integers(0, 4), max_size=1))
@pytest.mark.tor("TOR-VER-004")
def test_kleene_values_at_every_tick_are_what_every_count_and_filling_gives(node, rows, holes,
                                                                           gap_at):
    """Kleene's reading of any past-time formula at every tick (a gap tick at each of the
    ticks it stands for): true where every completion is, false where none is (the
    two-valued engine over the filled trace)."""
    n = len(rows)
    cols = _columns(rows, set("pqmx"))
    gaps = sorted({i for i in gap_at if i < n})
    cells = sorted({(i, v) for i, v in holes if i < n and i not in gaps})
    unknown: dict = {v: np.zeros(n, np.bool_) for v in cols}
    for i, v in cells:
        unknown[v][i] = True
    stretch = np.zeros(n, np.bool_)
    stretch[gaps] = True
    for v in cols:
        unknown[v][gaps] = True
    values = kleene_values(node, cols, unknown, n, 0, {}, stretch=stretch)
    for filled, m, at in _completions(cols, n, cells, gaps, counts=(1, 2)):
        truth = node_series(node, filled, m)
        for i in range(n):
            span = truth[at[i]:(at[i + 1] if i + 1 < n else m)]
            if values[i] > 0:
                assert span.all(), (node, rows, cells, gaps, i)
            elif values[i] < 0:
                assert not span.any(), (node, rows, cells, gaps, i)
