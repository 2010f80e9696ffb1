"""The first rejection of many traces at once (:func:`fretc.monitors.judge.first_rejections`,
the per-entity batch's LTL3 verdicts) equals each trace's own, whether the traces are stepped
together by numpy or one tick at a time (the monitors of every template key:
tests/monitors/test_vectorized.py)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.monitors import judge as J


@st.composite
def automata_and_traces(draw):
    """A random complete table over ``2**atoms`` letters (-1: rejected) and traces of
    letters laid end to end."""
    atoms = draw(st.integers(0, 2))
    states = draw(st.integers(1, 4))
    table = [[draw(st.integers(-1, states - 1)) for _ in range(2 ** atoms)]
             for _ in range(states)]
    lengths = draw(st.lists(st.integers(0, 9), min_size=0, max_size=40))
    letters = draw(st.lists(st.integers(0, 2 ** atoms - 1), min_size=sum(lengths),
                            max_size=sum(lengths)))
    return table, draw(st.integers(0, states - 1)), lengths, letters


@settings(max_examples=300, deadline=None)
@given(case=automata_and_traces(), together=st.sampled_from([0, 1, 3, 32]))
@pytest.mark.tor("TOR-VER-009", "TOR-GEN-002")
def test_the_first_rejection_of_each_trace_is_its_own(case, together, monkeypatch_session):
    table, initial, lengths, letters = case
    monkeypatch_session.setattr(J, "STEP_TOGETHER", together)
    lens = np.asarray(lengths, np.int64)
    firsts = (np.cumsum(lens) - lens).astype(np.int64)
    arr = np.asarray(letters, np.uint16)
    got = J.first_rejections(table, initial, arr, firsts, lens).tolist()
    want = [J._first_rejection(table, initial, arr[a:a + m]) for a, m in zip(firsts, lengths)]
    assert got == [-1 if w is None else w for w in want]


@pytest.fixture(scope="module")
def monkeypatch_session():
    with pytest.MonkeyPatch.context() as m:
        yield m


def test_a_table_of_unequal_rows_is_stepped_one_tick_at_a_time(monkeypatch_session):
    """A table numpy cannot take as an array (rows of unequal length) gives each trace's own
    first rejection all the same."""
    monkeypatch_session.setattr(J, "STEP_TOGETHER", 1)
    table = [[0, -1], [1]]
    letters = np.array([0, 1, 0, 0, 1, 0], np.uint16)
    got = J.first_rejections(table, 0, letters, np.array([0, 2, 5]), np.array([2, 3, 1]))
    assert got.tolist() == [1, 2, -1]


@pytest.mark.tor("TOR-VER-009", "TOR-GEN-002")
def test_a_rejection_past_the_first_chunk_of_letters_is_found_at_its_tick():
    """The letters are read into Python a chunk at a time (``_LETTERS_CHUNK``): a rejection
    in any chunk, at a chunk's edge included, is found at its own tick, and a trace with no
    rejecting letter is never rejected."""
    table = [[0, -1]]  # letter 1 rejects
    chunk = J._LETTERS_CHUNK
    n = 3 * chunk
    for at in (5, chunk - 1, chunk, chunk + 7, 2 * chunk + 1, n - 1):
        letters = np.zeros(n, np.uint16)
        letters[at] = 1
        assert J.first_rejections(table, 0, letters, np.array([0]), np.array([n])).tolist() \
            == [at], at
        assert J._first_rejection(table, 0, letters) == at
    assert J.first_rejections(table, 0, np.zeros(n, np.uint16), np.array([0]),
                              np.array([n])).tolist() == [-1]
