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


#: the timings whose obligation a cut can leave open (``always`` and ``never`` are left to the
#: LTL3 verdict: an invariant held so far is not an open obligation of one trigger)
_CUT_TIMINGS = ("immediately", "next", "finally", "eventually", "within", "for", "after",
                "until", "before")


def _tails(length: int) -> list[list[tuple[bool, bool]]]:
    """Continuations (r, s per tick): r and s each constant, switching once, or pulsing."""
    out = []
    for j in range(length + 1):
        for r_first, s_at in ((False, None), (True, None), (False, j), (True, j)):
            out.append([(r_first != (i >= j), s_at is not None and i >= s_at)
                        for i in range(length)])
    out.append([(i % 2 == 0, False) for i in range(length)])
    return out


@pytest.mark.tor("TOR-DMG-003")
@settings(max_examples=300, deadline=None)
@given(st.sampled_from(("null", "regular")), st.sampled_from(_CUT_TIMINGS),
       st.lists(st.tuples(st.booleans(), st.booleans()), min_size=1, max_size=8),
       st.integers(0, 7))
def test_an_obligation_is_open_at_a_cut_exactly_when_the_rest_of_the_run_decides_it(
        cond, timing, rs, pulse):
    """Independent of the rule: one trigger (``upon c`` with c true at one tick, or the
    first tick), a run cut after the prefix; the reference evaluator
    (:mod:`fretc.qualification.reference`) judges the prefix followed by each continuation.
    The obligation is open at the cut exactly when some continuations satisfy the
    requirement and others violate it."""
    from fretc.fretish import parse
    from fretc.qualification import reference as ref

    key = f"null,{cond},{timing}"
    text = dict(ref.key_sentences())[key]
    n = len(rs)
    at = pulse % n
    prefix = [{"m": False, "c": cond == "regular" and i == at, "r": r, "s": s}
              for i, (r, s) in enumerate(rs)]
    cols = {v: np.array([t[v] for t in prefix], np.bool_) for v in ref.VARIABLES}
    opened = open_obligations(parse(text), cols, n, ref.DURATION)
    length = 2 * ref.DURATION + 3
    verdicts = {ref.verdict(key, prefix + [{"m": False, "c": False, "r": r, "s": s}
                                          for r, s in tail])
                for tail in _tails(length)}
    decided_by_rest = {"satisfied", "violated"} <= verdicts
    assert bool(opened) == decided_by_rest, (text, rs, at, opened, verdicts)


@pytest.mark.tor("TOR-DMG-003")
def test_the_reason_names_the_ticks_past_the_cut():
    """The words of an open obligation (the audit's ``unknown_reason``) name the tick or the
    window the cut hides: ``next`` its tick t+1, ``for`` its window [t, t+k]."""
    from fretc.fretish import parse

    def cols(c: list[int], r: list[int]) -> dict:
        return {"m": np.zeros(len(c), np.bool_), "c": np.array(c, np.bool_),
                "r": np.array(r, np.bool_), "s": np.zeros(len(c), np.bool_)}

    nxt = open_obligations(parse("upon c the sw shall at the next timepoint satisfy r"),
                           cols([0, 0, 1], [0, 0, 0]), 3, 0)
    assert [(o.trigger_tick, o.what) for o in nxt] == [(2, "R at t+1=3, past the damage")]
    held = open_obligations(parse("upon c the sw shall for 2 ticks satisfy r"),
                            cols([0, 1, 0], [0, 1, 1]), 3, 2)
    assert [(o.trigger_tick, o.what) for o in held] == [
        (1, "R must hold on [1, 3], whose end lies past the damage")]
