"""Differential test of the interval evidence (monitors/interval.py) on random sentences
that use every FRET temporal function (``persisted``, ``occurred``, ``persists``,
``occurs`` with 2 and 3 arguments, ``prevOcc``, ``nextOcc``, the occurrence phrases,
``preBool``) in conditions, responses, stop conditions and scope conditions, drawn by the
differential generator of tests/differential.py, on random traces.

On each trace the evidence must give

* the verdict (holds / violated) of the generated monitor's ``finish()`` (where the
  requirement has an online monitor: its pt needs no future-time function), of the audit's
  vectorized pt engine, and of FRET's ft and pt formulas under the reference evaluator;
* the vacuity, the number of scope intervals, triggers and violated triggers, and the
  first violation (trigger tick, scope interval) of tests/differential.py's independent
  interval-semantics oracle (written from section 6b's "meaning" column, per trigger).

A bounded sample runs by default; ``pytest -m slow`` runs a longer one.
"""

from __future__ import annotations

import json
import random

import numpy as np
import pytest

from fretc.compiler.evaluate import ft_at, pt_at
from fretc.compiler.ir import walk
from fretc.compiler.printers import to_smv
from fretc.compiler.semantics import formalize
from fretc.fretish import parse
from fretc.common.errors import FretishError
from fretc.monitors.interval import EvidenceUnsupported, evaluate_requirement
from fretc.monitors.vectorized import pt_series

from _monitor_helpers import compiled, load_module
from differential import (BOOL_VARS, MODE_VARS, NUM_VARS, _obligation, random_requirement,
                          random_trace, trigger_points, world_signals)

FUNCTIONS = ("persisted(", "occurred(", "persists(", "occurs(", "prevOcc(", "nextOcc(",
             "at the previous occurrence of", "at the next occurrence of", "preBool(")


def oracle_detail(meaning: dict, trace: list[dict]) -> dict:
    """Intervals, triggers, violated triggers and the first violation ``(t, (s, e))`` of
    a requirement on a finite trace, trigger by trigger, by tests/differential.py's oracle
    (its scope intervals, triggers and obligations; functions from section 6b's meaning)."""
    L = len(trace)
    w, R, S, C = world_signals(meaning, trace)
    negate = meaning["scope"].startswith("only")
    triggers = violations = 0
    first = None
    for s, e in w.intervals:
        for t in trigger_points(meaning, C, s, e):
            triggers += 1
            if not _obligation(meaning["timing"], negate, meaning["n"], t, e, R, S, L):
                violations += 1
                if first is None:
                    first = (t, (s, e))
    return {"intervals": len(w.intervals), "triggers": triggers, "violations": violations,
            "first": first}


def _columns(trace: list[dict]) -> dict[str, np.ndarray]:
    return {v: np.array([r[v] for r in trace]) for v in BOOL_VARS + MODE_VARS + NUM_VARS}


def check_sentences(rnd: random.Random, sentences: int, traces: int,
                    monitors: bool = True) -> tuple[int, int]:
    """Check ``sentences`` random sentences (each using a temporal function) on ``traces``
    random traces each; returns the numbers of (sentence, trace) pairs checked and of those
    checked against a generated monitor too. Fails with the sentence and trace of the first
    disagreement."""
    drawn = []
    while len(drawn) < sentences:
        text, meaning = random_requirement(rnd)
        if any(f in text for f in FUNCTIONS):
            drawn.append((text, meaning))
    comps = [compiled(parse(text), rid=f"D{i}") for i, (text, _) in enumerate(drawn)]
    classes = {}
    if monitors:
        classes = load_module(comps, "evidence_functions").MONITORS
    pairs = with_monitor = 0
    for _i, ((text, meaning), comp) in enumerate(zip(drawn, comps)):
        req, f = comp.requirement, comp.formalization
        cls = classes.get(comp.id)
        for _ in range(traces):
            L = rnd.randint(1, 9)
            trace = random_trace(rnd, L)
            cols = _columns(trace)
            where = f"{text}\n    trace {trace}"
            ev = evaluate_requirement(req, cols, L, f.ticks)
            holds = ft_at(f.ft, trace)
            assert ev.holds == holds, f"evidence {ev.holds}, ft {holds}: {where}"
            assert ev.holds == pt_at(f.pt, trace), f"evidence {ev.holds}, pt: {where}"
            if cls is not None:
                mon = cls()
                for row in trace:
                    mon.step(row)
                assert ev.holds == mon.finish(), f"monitor {mon.finish()}: {where}"
                assert ev.holds == bool(pt_series(f.pt, cols, L)[-1]), f"vectorized: {where}"
                with_monitor += 1
            want = oracle_detail(meaning, trace)
            got = {"intervals": ev.intervals, "triggers": ev.triggers,
                   "violations": ev.violations,
                   "first": (ev.violation.trigger_tick, ev.violation.interval)
                   if ev.violation else None}
            assert got == want, f"evidence {got}, oracle {want}: {where}"
            assert ev.vacuous == (ev.holds and (ev.intervals == 0 or ev.triggers == 0))
            if ev.violation is not None:
                v = ev.violation
                assert v.window[0] <= v.violation_tick and v.trigger_tick <= v.window[0]
            pairs += 1
    return pairs, with_monitor


@pytest.mark.parametrize("chunk", range(3))
def test_evidence_equals_monitor_and_oracle_on_temporal_functions(chunk):
    pairs, with_monitor = check_sentences(random.Random(500 + chunk), sentences=40, traces=15)
    assert pairs == 40 * 15 and with_monitor >= 150


@pytest.mark.slow
@pytest.mark.parametrize("chunk", range(10))
def test_evidence_differential_long(chunk):
    check_sentences(random.Random(9000 + chunk), sentences=150, traces=30)


def test_the_sample_uses_every_function():
    rnd = random.Random(500)
    texts = []
    while len(texts) < 90:
        text, _ = random_requirement(rnd)
        if any(f in text for f in FUNCTIONS):
            texts.append(text)
    joined = "\n".join(texts)
    for needle in FUNCTIONS:
        assert needle in joined, needle
    # the 3-argument forms and functions inside scope conditions
    assert any(t.count(",") >= 2 and ("occurs(" in t or "persists(" in t) for t in texts)
    assert any(t.startswith(("while (", "after (", "before (", "only", "except while ("))
               and any(f in t.split(" the sw shall")[0] for f in FUNCTIONS) for t in texts)


@pytest.mark.parametrize("sentence, trace, holds, first", [
    # prevOcc is true at the first position of the scope interval (FRET's prevOcc)
    ("the sw shall always satisfy at the previous occurrence of p, q",
     {"p": "1100", "q": "1100"}, True, None),
    ("the sw shall always satisfy at the previous occurrence of p, q",
     {"p": "1010", "q": "0000"}, False, (0, (0, 3))),
    # nextOcc is true at the last position of the interval (family 2)
    ("in m the sw shall always satisfy nextOcc(p, q)",
     {"m": "1101", "p": "0101", "q": "0100"}, True, None),
    ("in m the sw shall always satisfy nextOcc(p, q)",
     {"m": "1111", "p": "0001", "q": "0000"}, False, (0, (0, 3))),
    # occurs(m,n,p): p in [t+m, min(t+n, e)]; persists(m,n,p) needs e >= t+n
    ("in m upon q the sw shall immediately satisfy occurs(1, 2, p)",
     {"m": "1110", "q": "1000", "p": "1001"}, False, (0, (0, 2))),
    ("the sw shall immediately satisfy persists(1, 3, p)",
     {"p": "0111"}, True, None),
    ("the sw shall immediately satisfy persists(1, 4, p)",
     {"p": "0111"}, False, (0, (0, 3))),
    # an interval of `when not in m` reaching the end has no Right (no LAST in FRET's):
    # occurs looks into the absorbing state, where !p holds
    ("when not in m the sw shall immediately satisfy occurs(1, 2, !p)",
     {"m": "0000", "p": "0000"}, True, None),
    ("when not in m upon q the sw shall immediately satisfy occurs(1, 2, !p)",
     {"m": "0000", "q": "0001", "p": "1111"}, True, None),
    ("when not in m upon q the sw shall immediately satisfy occurs(2, !p)",
     {"m": "0000", "q": "0001", "p": "1111"}, True, None),
    ("in m upon q the sw shall immediately satisfy occurs(1, 2, !p)",
     {"m": "1111", "q": "0001", "p": "1111"}, False, (3, (0, 3))),
    # a scope condition uses the endpoint-free form: false with no earlier p
    ("while prevOcc(p, q) the sw shall always satisfy r",
     {"p": "1000", "q": "1000", "r": "0111"}, True, None),
    ("while prevOcc(p, q) the sw shall always satisfy r",
     {"p": "1000", "q": "1000", "r": "0101"}, False, (1, (1, 3))),
])
def test_hand_checked_functions(sentence, trace, holds, first):
    n = len(next(iter(trace.values())))
    cols = {k: np.array([c == "1" for c in v]) for k, v in trace.items()}
    for name in ("m", "p", "q", "r"):
        cols.setdefault(name, np.zeros(n, bool))
    req = parse(sentence)
    ev = evaluate_requirement(req, cols, n)
    rows = [{k: bool(v[i]) for k, v in cols.items()} for i in range(n)]
    assert ev.holds == holds == ft_at(formalize(req).ft, rows)
    got = (ev.violation.trigger_tick, ev.violation.interval) if ev.violation else None
    assert got == first


@pytest.mark.parametrize("sentence", [
    "the sw shall always satisfy f(p)",                  # uninterpreted function
    "whenever p the sw shall immediately satisfy g(p, q) | q",
])
def test_only_uninterpreted_functions_are_unsupported(sentence):
    cols = {"p": np.array([True, False]), "q": np.array([True, True])}
    with pytest.raises(EvidenceUnsupported):
        evaluate_requirement(parse(sentence), cols, 2)


@pytest.mark.parametrize("sentence", [
    "the sw shall always satisfy f(p)",
    "whenever p the sw shall immediately satisfy g(p, q) | q",
    "whenever q the sw shall within 2 ticks satisfy x = 1.5 * sqrt(w) + 10",
    "when in m the sw shall always satisfy det_3x3(a, w * 2, -a) > 0",
])
def test_uninterpreted_functions_read_their_column(sentence):
    """With a column under the printed call (as the generated monitors and FRET's ft read
    it), the evidence agrees with FRET's ft formula under the reference evaluator on random
    traces; the column's values, not the arguments', decide."""
    rnd = random.Random(7)
    req = parse(sentence)
    ft = formalize(req).ft
    calls = sorted({to_smv(n) for n in walk(ft) if n.op in ("fn", "call")})
    assert calls
    for _ in range(60):
        n = rnd.randint(1, 6)
        rows = [{"p": rnd.random() < 0.5, "q": rnd.random() < 0.5, "m": rnd.random() < 0.7,
                 "x": rnd.choice([0.0, 11.5, 13.0]), "w": rnd.choice([0.0, 1.0, 4.0]),
                 "a": rnd.choice([-1.0, 0.0, 2.0])} for _ in range(n)]
        for r in rows:
            r.update({c: (rnd.random() < 0.5 if c.startswith(("f(", "g("))
                          else rnd.choice([-1.0, 0.0, 1.0, 2.0])) for c in calls})
        cols = {k: np.array([r[k] for r in rows]) for k in rows[0]}
        assert evaluate_requirement(req, cols, n).holds == ft_at(ft, rows), (sentence, rows)


def test_fret_function_vectors(shared):
    """The 152 sentences FRET formalized around its temporal functions
    (fret_vectors_functions.jsonl): the evidence gives the ft verdict on random traces."""
    path = shared / "fretish/fret_vectors_functions.jsonl"
    rnd = random.Random(21)
    checked = 0
    for line in path.open(encoding="utf-8"):
        row = json.loads(line)
        try:
            req = parse(row["text"])
            f = formalize(req)
        except FretishError:  # a sentence FRET rejects too
            continue
        names = sorted(f.variables)
        for _ in range(25):
            n = rnd.randint(1, 9)
            rows = [{v: rnd.random() < 0.5 for v in names} for _ in range(n)]
            cols = {v: np.array([r[v] for r in rows]) for v in names}
            ev = evaluate_requirement(req, cols, n, f.ticks)
            assert ev.holds == ft_at(f.ft, rows), (row["text"], rows)
        checked += 1
    assert checked >= 140
