"""monitors.definite.DefiniteStream at every chunk boundary: on random sentences of
tests/differential.py's generator (every scope, condition and timing), random traces with NaN
operands, unknown values and gap ticks anywhere, split into random chunks, the evidence
(definite triggers and first trigger, the definite failed triggers listed), the times of the
ticks it names and whether a trigger may have fired in unknown ticks are those of the whole
trace fed as one chunk (definite_evidence). What the whole trace's must be is tested against
every completion (test_three_valued.py, test_gap_ticks.py)."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.fretish import parse
from fretc.monitors.definite import DefiniteStream, _RunMask, _Runs, definite_evidence
from fretc.monitors.interval import stream_unsupported

from differential import BOOL_VARS, MODE_VARS, NUM_VARS, random_requirement
from test_interval_stream import named_ticks, random_chunks, time_of


def _columns(rnd: random.Random, n: int) -> tuple[dict, dict, np.ndarray | None]:
    """Columns (runs of booleans, NaN among the numbers), unknown masks and gap ticks (None
    without; every variable unknown there)."""
    cols: dict = {}
    for v in BOOL_VARS + MODE_VARS:
        flips = np.array([rnd.random() < rnd.choice([0.1, 0.5]) for _ in range(n)])
        cols[v] = (np.cumsum(flips) % 2).astype(np.bool_)
    for v in NUM_VARS:
        cols[v] = np.array([math.nan if rnd.random() < 0.08 else float(rnd.randint(-1, 3))
                            for _ in range(n)])
    unknown = {v: np.array([rnd.random() < 0.08 for _ in range(n)], np.bool_)
               for v in BOOL_VARS + MODE_VARS if rnd.random() < 0.3}
    stretch = None
    if rnd.random() < 0.4:
        stretch = np.array([rnd.random() < 0.05 for _ in range(n)], np.bool_)
        for v in cols:
            unknown[v] = unknown.get(v, np.zeros(n, np.bool_)) | stretch
    return cols, unknown, stretch


def _check(text: str, rnd: random.Random, n: int) -> None:
    req = parse(text)
    if stream_unsupported(req) is not None:
        return
    cols, unknown, stretch = _columns(rnd, n)
    want, possible = definite_evidence(req, cols, unknown, n, None, True, stretch)
    s = DefiniteStream(req, None)
    times = time_of(np.arange(n, dtype=np.int64))
    for i, k, chunk in random_chunks(cols, n, rnd):
        s.feed(chunk, {v: m[i:i + k] for v, m in unknown.items()}, k, times[i:i + k],
               None if stretch is None else stretch[i:i + k])
    got, got_times = s.finish()
    assert got == want, f"{text}\n stream {got}\n whole  {want}"
    assert {t: got_times[t] for t in named_ticks(want)} == \
        {t: time_of(t) for t in named_ticks(want)}, text
    assert s.possible_trigger == possible, text


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 60))
@pytest.mark.tor("TOR-LOG-003")
def test_the_definite_evidence_in_chunks_is_that_of_one_chunk(seed, n):
    rnd = random.Random(seed)
    text, _ = random_requirement(rnd, depth=1)
    _check(text, rnd, n)


@pytest.mark.parametrize("seed", range(6))
def test_long_traces_and_listed_violations(seed):
    """Longer traces (more chunks, more failed triggers than are listed)."""
    rnd = random.Random(seed)
    for _ in range(8):
        text, _ = random_requirement(rnd, depth=1)
        _check(text, rnd, rnd.randint(200, 600))


@settings(max_examples=200, deadline=None)
@given(st.lists(st.booleans(), min_size=1, max_size=40), st.integers(1, 7),
       st.integers(-2, 45), st.integers(-2, 45))
def test_runs_answer_as_the_mask(bits, step, lo, hi):
    """The runs of a mask fed in chunks answer a tick and a range as the bool array."""
    mask = np.array(bits, np.bool_)
    runs = _Runs()
    for a in range(0, len(mask), step):
        runs.add(mask[a:a + step], a)
    got: _RunMask = runs.mask()
    lo, hi = max(lo, 0), max(hi, 0)
    assert got[lo:hi].any() == bool(mask[lo:hi].any())
    if lo < len(mask):
        assert bool(got[lo]) == bool(mask[lo])
    assert runs.count == int(np.sum(np.diff(mask.astype(np.int8), prepend=0) == 1))
