"""The three-valued judge against brute force: on random traces with unknown ticks, a
verdict it gives is the one every way of filling the unknown ticks gives (FRET's
finite-trace verdict by the pt formula, the LTL3 verdict by the monitor automata); with no
unknown tick it is the two-valued one; and the unknown ticks a gap leaves are the ticks at
which a lost message would be newer than the one held."""

from __future__ import annotations

import itertools

import pytest
import numpy as np
from hypothesis import given, settings, strategies as st

from fretc.audit.gaps import unknown_masks
from _monitor_helpers import compiled_of, pqmx_columns
from fretc.logs.base import Gap
from fretc.monitors.judge import ltl3_verdict as ltl3_two
from fretc.monitors.completions import decide
from fretc.monitors.three_valued import ltl3_verdict
from fretc.monitors.vectorized import node_series, pt_series

SENTENCES = [
    "the sw shall always satisfy p",
    "the sw shall never satisfy p & q",
    "upon p the sw shall within 2 ticks satisfy q",
    "whenever p the sw shall immediately satisfy q",
    "in m mode the sw shall always satisfy q",
    "the sw shall eventually satisfy p",
    "upon p the sw shall for 2 ticks satisfy q",
    "after m the sw shall always satisfy p",
    "only in m mode the sw shall eventually satisfy q",
    "upon p the sw shall until q satisfy m",
    "when x > 1 the sw shall within 1 ticks satisfy x + 1 < 3",
    "the sw shall always satisfy persisted(2, p) -> q",
]
_compiled_of, _columns = compiled_of, pqmx_columns


_row = st.tuples(st.booleans(), st.booleans(), st.booleans(), st.sampled_from([0.0, 1.0, 2.0]))


@settings(max_examples=300, deadline=None)
@given(text=st.sampled_from(SENTENCES), rows=st.lists(_row, min_size=1, max_size=7),
       holes=st.lists(st.tuples(st.integers(0, 6), st.sampled_from("pqmx")), max_size=3))
@pytest.mark.tor("TOR-VER-004")
def test_a_verdict_is_what_every_completion_gives(text, rows, holes):
    c, ms = _compiled_of(text)
    f = c.formalization
    names = set(f.variables)
    n = len(rows)
    cols = _columns(rows, names)
    unknown = {}
    cells = sorted({(i, v) for i, v in holes if i < n and v in cols})
    for i, v in cells:
        unknown.setdefault(v, np.zeros(n, np.bool_))[i] = True
    got, _reading, _why = decide(f.pt, cols, unknown, n)
    status, tick = ltl3_verdict(ms, cols, unknown, n)
    outcomes, ltl3s = set(), []
    values = {"p": (False, True), "q": (False, True), "m": (False, True),
              "x": (0.0, 1.0, 2.0)}
    for combo in itertools.product(*(values[v] for _i, v in cells)):
        filled = {k: a.copy() for k, a in cols.items()}
        for (i, v), val in zip(cells, combo):
            filled[v][i] = val
        outcomes.add(bool(pt_series(f.pt, filled, n)[-1]))
        ltl3s.append(ltl3_two(ms, filled, n))
    if got is not None:
        assert outcomes == {got}, (text, rows, cells)
    if len(outcomes) == 1 and all(v != "x" for _i, v in cells):
        # complete on boolean unknowns: the atoms are the variables, every letter a completion
        assert got == next(iter(outcomes)), (text, rows, cells, outcomes)
    if not cells:
        assert got is not None and (status, tick) == ltl3s[0]
    if status != "unknown":
        assert all(s == status and (t is not None and t <= tick) for s, t in ltl3s), \
            (text, rows, cells, status, tick, ltl3s)


@settings(max_examples=200, deadline=None)
@given(kept=st.lists(st.integers(0, 40), min_size=1, max_size=12, unique=True),
       lost=st.lists(st.integers(0, 40), max_size=4, unique=True),
       ticks=st.lists(st.integers(0, 45), min_size=1, max_size=10, unique=True))
@pytest.mark.tor("TOR-DMG-002")
def test_a_gap_leaves_unknown_the_ticks_a_lost_message_could_hold(kept, lost, ticks):
    """Point gaps (one lost message each): a tick is unknown exactly when a lost message is
    at or before it and not older than the message it holds."""
    lost = [t for t in lost if t not in kept]
    kept, ticks = sorted(kept), np.array(sorted(ticks), np.int64)
    held = np.array([max([k for k in kept if k <= t], default=-1) for t in ticks], np.int64)
    got = unknown_masks(ticks, {"/a": held}, ["a"], None, [Gap(t, t, frozenset({"/a"}), "x")
                                                          for t in lost])
    want = np.array([any(h <= m <= t for m in lost) for t, h in zip(ticks, held)], np.bool_)
    assert np.array_equal(got.get("a", np.zeros(len(ticks), np.bool_)), want)


SCOPED = [
    "only after m the sw shall never satisfy p",
    "only before m the sw shall always satisfy p",
    "only in m mode the sw shall always satisfy p",
    "before m the sw shall always satisfy p",
    "after m the sw shall always satisfy p",
    "in m mode upon p the sw shall within 1 ticks satisfy q",
    "when not in m mode whenever p the sw shall immediately satisfy q",
    "after m upon p the sw shall eventually satisfy q",
]


def _definite_triggers(text, cols, unknown, n):
    from fretc.monitors.definite import definite_evidence

    c, _ms = _compiled_of(text)
    req, ticks = c.entry.requirement, c.formalization.ticks
    return definite_evidence(req, cols, unknown, n, ticks)[0].triggers, req, ticks


@settings(max_examples=200, deadline=None)
@given(text=st.sampled_from(SCOPED), rows=st.lists(_row, min_size=1, max_size=6),
       holes=st.lists(st.tuples(st.integers(0, 5), st.sampled_from("pqm")), max_size=2))
def test_the_triggers_counted_are_in_every_completion(text, rows, holes):
    """A trigger counted with unknown ticks (the one that makes a requirement satisfied
    rather than vacuous) fires in every way of filling them: at least as many triggers in
    each completion; with the ticks before it known and only the scope's end unknown it is
    counted (an ``only after`` whose mode is unknown at the last tick has its trigger at
    the first tick: fuzz_hostile crunner seed 67 input 1040)."""
    from fretc.monitors.interval import evaluate_requirement

    c, _ms = _compiled_of(text)
    n = len(rows)
    cols = _columns(rows, set(c.formalization.variables))
    cells = sorted({(i, v) for i, v in holes if i < n and v in cols})
    unknown: dict = {}
    for i, v in cells:
        unknown.setdefault(v, np.zeros(n, np.bool_))[i] = True
    counted, req, ticks = _definite_triggers(text, cols, unknown, n)
    for combo in itertools.product((False, True), repeat=len(cells)):
        filled = {k: a.copy() for k, a in cols.items()}
        for (i, v), val in zip(cells, combo):
            filled[v][i] = val
        assert evaluate_requirement(req, filled, n, ticks).triggers >= counted, \
            (text, rows, cells, combo, counted)


@pytest.mark.tor("TOR-VER-004")
def test_a_trigger_before_an_unknown_scope_end_is_counted():
    text = "only after m the sw shall never satisfy p"
    cols = {"m": np.array([True, True, True]), "p": np.array([False, False, False])}
    unknown = {"m": np.array([False, False, True])}
    assert _definite_triggers(text, cols, unknown, 3)[0] == 1


@settings(max_examples=200, deadline=None)
@given(text=st.sampled_from(SENTENCES + SCOPED), rows=st.lists(_row, min_size=1, max_size=12),
       start=st.integers(0, 11))
def test_the_stepped_pt_program_equals_the_vectorized_pt(text, rows, start):
    """The pt formula stepped tick by tick over its state (:mod:`fretc.monitors.completions`,
    the exact search's step), from the state read at any tick (the completions' reading of
    it, from the values kept before it), gives the vectorized evaluator's value at every
    tick after it."""
    from fretc.monitors.completions import CompletionsStream

    c, _ms = _compiled_of(text)
    f = c.formalization
    n = len(rows)
    start = min(start, n - 1)
    cols = _columns(rows, set(f.variables))
    want = pt_series(f.pt, cols, n)
    run = CompletionsStream(f.pt, start, start, n)
    run.feed(cols, {}, start)  # (the values before ``start`` kept)
    prog, state = run.prog, run._state_at_first()
    for i in range(start, n):
        leaves = {k: bool(node_series(prog.nodes[k], cols, n)[i]) for k in prog.leaves}
        got, state = prog.step(state, leaves, i)
        assert got == bool(want[i]), (text, rows, start, i)
