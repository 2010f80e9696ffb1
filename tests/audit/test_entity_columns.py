"""The per-entity columns gathered by numpy (audit/entities/columns.py) against the loop they
replace: the absent value at each tick (typed over all ticks), the entity's row where it is
present, the column bool exactly when every value in it is a bool."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.audit.entities.columns import EntityColumns, HeldRows, RowBlock, column, floats

E = "\x00entities"
VALUE = st.sampled_from([True, False, 0.5, 2.0, math.nan, math.inf])


class _Tick:
    def __init__(self, absent, rows):
        self.values = {E: (absent, rows)}


def _naive(ticks, j, i, i0, i1):
    vals = column([t.values[E][0][j] for t in ticks])[i0:i1 + 1].tolist()
    for k in range(i0, i1 + 1):
        for e, got in ticks[k].values[E][1]:
            if e == i:
                vals[k - i0] = got[j]
    return column(vals)


def _as_blocks(ticks, split):
    """The same ticks with their rows in two :class:`RowBlock` s (messages before ``split``
    in the first), each tick's rows a :class:`HeldRows`; a tick without rows keeps []."""
    out, blocks = [], []
    for part in (ticks[:split], ticks[split:]):
        rows = [t.values[E][1] for t in part]
        flat = [r for rs in rows for r in rs]
        blk = RowBlock(np.array([r[0] for r in flat], np.int64),
                       np.cumsum([0] + [len(rs) for rs in rows], dtype=np.int64),
                       {n: floats([r[1][j] for r in flat]) for j, n in enumerate(["x", "y"])})
        blocks.append(blk)
        for q, t in enumerate(part):
            h = HeldRows()
            h.block, h.at = blk, q
            out.append(_Tick(t.values[E][0], h if t.values[E][1] else []))
    return out


def _same(a, b):
    return a.dtype == b.dtype and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


@settings(max_examples=200, deadline=None)
@given(data=st.lists(st.tuples(st.tuples(VALUE, VALUE),
                               st.dictionaries(st.integers(0, 3), st.tuples(VALUE, VALUE),
                                               max_size=4)), min_size=1, max_size=12),
       span=st.tuples(st.integers(0, 11), st.integers(0, 11)))
def test_columns_equal_the_loop(data, span):
    ticks = [_Tick(a, sorted(rows.items())) for a, rows in data]
    cols = EntityColumns(ticks, ["x", "y"], E, 4)
    blocks = EntityColumns(_as_blocks(ticks, span[0] % (len(ticks) + 1)), ["x", "y"], E, 4)
    i0, i1 = sorted(min(s, len(ticks) - 1) for s in span)
    for i in range(4):
        got = cols.trace(i, i0, i1)
        also = blocks.trace(i, i0, i1)
        for j, n in enumerate(["x", "y"]):
            assert _same(got[n], _naive(ticks, j, i, i0, i1)), (i, n)
            assert _same(also[n], got[n]), (i, n)
    # every entity end to end (entity 3 first, entity 1 left out)
    judged = [3, 0, 2]
    i0s = np.array([i0, 0, i1], np.int64)
    lengths = np.array([i1 - i0 + 1, i1 + 1, 1], np.int64)
    firsts = np.concatenate(([0], np.cumsum(lengths)[:-1])).astype(np.int64)
    idx = np.arange(int(lengths.sum())) - np.repeat(firsts - i0s, lengths)
    got = cols.end_to_end(judged, i0s, firsts, lengths, idx)
    also = blocks.end_to_end(judged, i0s, firsts, lengths, idx)
    for j, n in enumerate(["x", "y"]):
        assert _same(also[n], got[n])
        want = column(sum((_naive(ticks, j, i, int(a), int(a + m - 1)).tolist()
                           for i, a, m in zip(judged, i0s, lengths)), []))
        assert _same(got[n], want)


@settings(max_examples=100, deadline=None)
@given(absent=st.tuples(VALUE, VALUE),
       runs=st.lists(st.tuples(st.integers(1, 4),
                               st.dictionaries(st.integers(0, 3), st.tuples(VALUE, VALUE),
                                               max_size=4)), min_size=1, max_size=6),
       span=st.tuples(st.integers(0, 23), st.integers(0, 23)))
def test_columns_of_runs_equal_those_of_their_ticks(absent, runs, span):
    """Runs of ticks holding the same rows (audit/entities/runs.py), the rows as lists or as
    :class:`HeldRows` of a block, give the columns of their ticks one by one."""
    ticks = [_Tick(absent, sorted(rows.items())) for m, rows in runs for _ in range(m)]
    blocks = _as_blocks([_Tick(absent, sorted(rows.items())) for _m, rows in runs],
                        span[1] % (len(runs) + 1))  # (the runs' rows in one or two blocks)
    spans, k = [], 0
    for (m, _r), t in zip(runs, blocks):
        spans.append((k, m, t.values[E][1]))
        k += m
    cols = EntityColumns(ticks, ["x", "y"], E, 4)
    firsts, counts, rows = (list(x) for x in zip(*spans))
    lists = EntityColumns.of_runs(["x", "y"], absent, firsts, counts,
                                  [sorted(r.items()) for _m, r in runs], len(ticks), 4)
    held = EntityColumns.of_runs(["x", "y"], absent, firsts, counts, rows, len(ticks), 4)
    i0, i1 = sorted(min(s, len(ticks) - 1) for s in span)
    for i in range(4):
        want = cols.trace(i, i0, i1)
        for got in (lists.trace(i, i0, i1), held.trace(i, i0, i1)):
            for n in ["x", "y"]:
                assert _same(got[n], want[n]), (i, n)
