"""A CSV trace's columns taken whole from its source (:func:`fretc.signals.csv_columns.
csv_columns`, the audit's read without bindings) equal the ticks :func:`fretc.signals.sample`
yields joined by :func:`fretc.signals.blocks_of_ticks`: times, values and their dtypes, the
sampling's figures and the source's pass (message count, partial, the cut), on random traces
with ``unknown`` cells, ``gap`` rows and a ``cut`` row, with and without a ``time`` column."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.logs import CSV_TOPIC, CsvSource
from fretc.signals import blocks_of_ticks, sample
from fretc.signals.csv_columns import csv_columns

NAMES = ["x", "p", "missing"]


def _pass(src: CsvSource) -> tuple:
    return (dict(src.counts), src.partial, src.damage_cut, src.cut_start, src.damage_time)


def _sampling(s) -> tuple:
    return (s.ticks, s.warmup_ticks, s.start_time, s.first_time, s.end_time)


@settings(max_examples=150, deadline=None)
@given(st.integers(0, 25), st.booleans(), st.sampled_from([0.0, 0.2]),
       st.sampled_from([0.0, 0.1]), st.booleans(), st.randoms(use_true_random=False))
def test_columns_equal_the_joined_ticks(tmp_path_factory, n, timed, unknown, gaps, cut, rnd):
    lines = ["time,x,p" if timed else "x,p"]
    for k in range(n):
        cells = [rnd.choice(["0.5", "-1", "nan", "2", "1"]), rnd.choice(["0", "1", "true"])]
        cells = [c if rnd.random() >= unknown else "unknown" for c in cells]
        if rnd.random() < gaps:
            cells = ["gap", "gap"]
        lines.append(",".join(([f"{k * 0.1:.1f}"] if timed else []) + cells))
    if cut:
        lines.append(",".join(([f"{n * 0.1:.1f}"] if timed else []) + ["cut", "cut"]))
    path = tmp_path_factory.mktemp("c") / "t.csv"
    path.write_text("\n".join(lines) + "\n")

    old = CsvSource(path, period_ns=7)
    s_old = sample(old, None)
    blocks = list(blocks_of_ticks(iter(s_old), NAMES, [CSV_TOPIC], size=4))
    new = CsvSource(path, period_ns=7)
    s_new, times, cols = csv_columns(new, NAMES)

    assert _pass(new) == _pass(old) and _sampling(s_new) == _sampling(s_old)
    want_t = (np.concatenate([b.times for b in blocks]) if blocks
              else np.zeros(0, np.int64))
    assert times.dtype == np.int64 and times.tolist() == want_t.tolist()
    for name in NAMES:
        parts = [b.values.get(name, np.zeros(len(b.times), np.bool_)) for b in blocks]
        want = np.concatenate(parts) if parts else np.zeros(0, np.bool_)
        assert cols[name].dtype == want.dtype, name
        assert np.array_equal(cols[name], want, equal_nan=want.dtype == np.float64), name
