"""The obligations a damage leaves open (``IntervalStream.open_at_end``, what
:func:`fretc.audit.damage.open_obligations` and the streamed CSV judge at a ``cut`` row
read) against the rule applied trigger by trigger over the whole trace: every scope
interval and trigger (:func:`fretc.monitors.interval.every_trigger`), the first events after
each (:class:`fretc.monitors.obligations.FirstEvents`) and
:func:`fretc.monitors.obligations.open_reason`, for every FRET template key on random
traces, fed as one chunk and in random chunks."""

from __future__ import annotations

import random

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from fretc.audit.damage import open_obligations
from fretc.fretish import ast as A
from fretc.monitors.interval import IntervalStream, every_trigger
from fretc.monitors.obligations import FirstEvents, open_reason

from _monitor_helpers import KEYS, requirement


def _reference(req: A.Requirement, cols: dict, n: int, k: int) -> list[tuple]:
    """Every open trigger of the interval reaching the last tick, by the per-trigger rule."""
    got = every_trigger(req, cols, n, k)
    chk = FirstEvents(got.R, got.S)
    negate = req.scope.kind.startswith("only")
    out = []
    for (s, e), points in zip(got.intervals, got.triggers):
        if e != n - 1:
            continue
        for t in points:
            why = open_reason(req.timing.kind, negate, t, e, k, chk)
            if why is not None:
                out.append((t, (s, e), why))
    return out


def _trace(rnd: random.Random, n: int) -> dict:
    bias = rnd.choice((0.2, 0.5, 0.8))
    return {v: np.array([rnd.random() < bias for _ in range(n)], np.bool_)
            for v in ("m", "c", "r", "s")}


def _streamed(req: A.Requirement, cols: dict, n: int, k: int, rnd: random.Random,
              limit: int) -> list[tuple]:
    s = IntervalStream(req, k, limit=limit)
    at = 0
    while at < n:
        step = min(n - at, rnd.choice((1, 2, 3, 7)))
        s.feed({v: c[at:at + step] for v, c in cols.items()}, step,
               np.arange(at, at + step, dtype=np.int64))
        at += step
    s.finish()
    return [(o.trigger_tick, o.interval, o.what) for o in s.open_at_end(limit)]


@pytest.mark.tor("TOR-DMG-003")
@settings(max_examples=400, deadline=None)
@given(st.sampled_from(KEYS), st.sampled_from(("r", "!r", "r | s")), st.integers(0, 3),
       st.integers(1, 14), st.randoms(use_true_random=False))
def test_the_obligations_open_at_the_end_are_the_per_trigger_rule_s(key, response, k, n, rnd):
    """The first open obligation (trigger, interval, words) of the stream fed one chunk,
    and all of them fed in random chunks, are the per-trigger rule's."""
    req = requirement(*key, response=response, condition="!c", n=k)
    cols = _trace(rnd, n)
    ref = _reference(req, cols, n, k)
    got = [(o.trigger_tick, o.interval, o.what) for o in open_obligations(req, cols, n, k)]
    assert got == ref[:1], req.text
    assert _streamed(req, cols, n, k, rnd, limit=50) == ref[:50], req.text
