"""The interval semantics' counts of many traces at once (monitors/interval_traces.py) equal
those of :func:`fretc.monitors.interval.evaluate_requirement` trace by trace: every scope
kind and condition kind, on random traces laid end to end (a trace of one tick among them),
with a mode and a condition over several variables; a temporal function or ``FTP`` is left
to the caller (None)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.fretish import parse
from fretc.monitors.interval import evaluate_requirement
from fretc.monitors.interval_traces import interval_counts

SCOPES = ["", "in m mode ", "when not in m mode ", "only in m mode ", "after m ",
          "before m ", "only after m ", "only before m "]
CONDITIONS = ["", "upon c ", "whenever c ", "upon c & x > 1 ", "when c | !m "]


@settings(max_examples=300, deadline=None)
@given(scope=st.sampled_from(SCOPES), cond=st.sampled_from(CONDITIONS),
       traces=st.lists(st.lists(st.tuples(st.booleans(), st.booleans(), st.booleans(),
                                          st.sampled_from([0.0, 2.0])),
                                min_size=1, max_size=9), min_size=1, max_size=6))
def test_counts_of_traces_equal_each_trace_alone(scope, cond, traces):
    req = parse(f"{scope}{cond}the sw shall always satisfy r")
    ticks = [t for tr in traces for t in tr]
    columns = {"m": np.array([t[0] for t in ticks]), "c": np.array([t[1] for t in ticks]),
               "r": np.array([t[2] for t in ticks]), "x": np.array([t[3] for t in ticks])}
    lengths = np.array([len(tr) for tr in traces], np.int64)
    firsts = np.concatenate(([0], np.cumsum(lengths)[:-1])).astype(np.int64)
    got = interval_counts(req, columns, firsts, lengths)
    assert got is not None
    for e, (a, n) in enumerate(zip(firsts.tolist(), lengths.tolist())):
        ev = evaluate_requirement(req, {k: c[a:a + n] for k, c in columns.items()}, n)
        assert (int(got[0][e]), int(got[1][e])) == (ev.intervals, ev.triggers), (scope, cond,
                                                                                   traces[e])


def test_a_temporal_function_or_ftp_is_left_to_the_caller():
    for text in ("upon persisted(2, c) the sw shall always satisfy r",
                 "in m mode upon FTP the sw shall always satisfy r",
                 "after occurred(1, m) the sw shall always satisfy r"):
        req = parse(text)
        cols = {k: np.array([True, False]) for k in ("m", "c", "r")}
        assert interval_counts(req, cols, np.array([0]), np.array([2])) is None, text
