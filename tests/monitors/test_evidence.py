"""monitors.interval: FRET's interval semantics computed directly is a second opinion that
agrees with the generated monitors' finish() on random traces for all 288 template keys and
with every FRET interval verdict of fret_trace_verdicts.jsonl; its evidence (intervals,
triggers, first violation) is right on hand-made traces."""

from __future__ import annotations

import random

import numpy as np
import pytest

from fretc.compiler.evaluate import ft_at
from fretc.compiler.semantics import formalize
from fretc.fretish import parse
from fretc.monitors.interval import (EvidenceUnsupported, evaluate_requirement, scope_intervals)

from _monitor_helpers import KEYS, compiled, load_module, random_trace, requirement, samples

from _shared import jsonl, needs_shared

VERDICTS = jsonl("fretish/fret_trace_verdicts.jsonl")

RESPONSES = ["r", "!r", "r | s", "r & c", "r xor m", "x > 2"]
CONDITIONS = ["c", "!c", "c & x <= 3"]


@pytest.fixture(scope="module")
def all_keys():
    reqs = []
    for i, (s, c, t) in enumerate(KEYS):
        req = requirement(s, c, t, response=RESPONSES[(i + 3) % 6],
                          condition=CONDITIONS[(i + 1) % 3], n=(i + 2) % 5)
        reqs.append((req, compiled(req, rid=f"K{i}")))
    mod = load_module([c for _, c in reqs], "evidence_keys")
    return [(req, c, mod.MONITORS[c.id]) for req, c in reqs]


def test_interval_semantics_equals_monitor_for_all_288_keys(all_keys):
    rnd = random.Random(99)
    vacuous = violated = 0
    for req, comp, cls in all_keys:
        for _ in range(15):
            n = rnd.randint(1, 14)
            cols = random_trace(rnd, n)
            mon = cls()
            for s in samples(cols, n):
                mon.step(s)
            ev = evaluate_requirement(req, cols, n, comp.formalization.ticks)
            assert ev.holds == mon.finish(), (req.text, {k: v.tolist() for k, v in cols.items()})
            # and with the reference evaluator of the ft formula (FRET's trace model)
            assert ev.holds == ft_at(comp.formalization.ft, samples(cols, n))
            vacuous += ev.vacuous
            violated += not ev.holds
            if not ev.holds:
                v = ev.violation
                s, e = v.interval
                assert s <= v.trigger_tick <= e and v.window[0] >= v.trigger_tick
                assert ev.violations >= 1 and ev.triggers >= ev.violations
    assert vacuous > 100 and violated > 500  # both outcomes well exercised


@needs_shared
def test_every_fret_trace_verdict():
    checked = 0
    for case in VERDICTS:
        L = case["length"]
        cols = {v: np.array([any(a <= i <= b for a, b in iv) for i in range(L)])
                for v, iv in case["intervals"].items()}
        for c in case["cases"]:
            req = parse(c["sentence"])
            ev = evaluate_requirement(req, cols, L, formalize(req).ticks)
            assert ev.holds == c["expected"], (case["trace"], c)
            checked += 1
    assert checked == 2640


def _cols(**kw):
    return {k: np.array([ch == "1" for ch in v]) for k, v in kw.items()}


def test_scope_intervals():
    m = np.array([c == "1" for c in "0110011100"])
    assert scope_intervals("null", None, 10) == [(0, 9)]
    assert scope_intervals("in", m, 10) == [(1, 2), (5, 7)]
    assert scope_intervals("notin", m, 10) == [(0, 0), (3, 4), (8, 9)]
    assert scope_intervals("onlyIn", m, 10) == [(0, 0), (3, 4), (8, 9)]
    assert scope_intervals("before", m, 10) == [(0, 0)]
    assert scope_intervals("after", m, 10) == [(3, 9)]
    assert scope_intervals("onlyBefore", m, 10) == [(1, 9)]
    assert scope_intervals("onlyAfter", m, 10) == [(0, 2)]
    first = np.array([c == "1" for c in "1100000000"])
    assert scope_intervals("before", first, 10) == []
    assert scope_intervals("onlyBefore", first, 10) == [(0, 9)]
    tail = np.array([c == "1" for c in "0000000111"])
    assert scope_intervals("after", tail, 10) == []  # the first M run reaches the end
    assert scope_intervals("onlyAfter", np.zeros(10, bool), 10) == [(0, 9)]


def test_evidence_of_a_late_stop():
    """R1 on a run where the robot stops too late for one trigger and never for another."""
    req = parse("whenever too_close agilex_agent shall eventually satisfy stopped")
    cols = _cols(too_close="0011000011100", stopped="0000010000000")
    ev = evaluate_requirement(req, cols, 13)
    assert not ev.holds and ev.triggers == 5 and ev.violations == 3
    v = ev.violation
    assert v.trigger_tick == 8 and v.interval == (0, 12) and v.violation_tick == 12
    assert v.window == (8, 12)


def test_evidence_of_within_and_vacuity():
    req = parse("upon p the sw shall within 2 ticks satisfy q")
    ev = evaluate_requirement(req, _cols(p="0100000100", q="0001000000"), 10)
    assert not ev.holds
    assert ev.violation.trigger_tick == 7 and ev.violation.violation_tick == 9
    # the same trigger one tick later: the run ends before the deadline, so no obligation
    ev = evaluate_requirement(req, _cols(p="0100000010", q="0001000000"), 10)
    assert ev.holds and not ev.vacuous and ev.triggers == 2
    ev = evaluate_requirement(req, _cols(p="0000000000", q="0000000000"), 10)
    assert ev.holds and ev.vacuous and ev.triggers == 0
    req = parse("in m the sw shall always satisfy q")
    ev = evaluate_requirement(req, _cols(m="0000", q="0000"), 4)
    assert ev.holds and ev.vacuous and ev.intervals == 0


def test_only_scope_negates():
    # q must not hold at the start of an interval outside m
    req = parse("only in m the sw shall immediately satisfy q")
    ev = evaluate_requirement(req, _cols(m="1100", q="1110"), 4)
    assert not ev.holds and ev.violation.trigger_tick == 2
    assert ev.violation.interval == (2, 3)
    assert evaluate_requirement(req, _cols(m="1100", q="1101"), 4).holds
    # FRET: "only in m ... eventually q" means q never holds outside m
    req = parse("only in m the sw shall eventually satisfy q")
    ev = evaluate_requirement(req, _cols(m="1100", q="1101"), 4)
    assert not ev.holds and ev.violation.violation_tick == 3


def test_interval_relative_functions_agree_with_monitor():
    """FRET's functions relative to the scope interval ($Left$/$Right$): against the monitor
    where there is one (past-time functions) and the reference ft evaluator always (a
    future-time function has no online monitor)."""
    sentences = [
        "in m the sw shall always satisfy persisted(2, p) -> q",
        "in m upon occurred(1, 2, p) the sw shall immediately satisfy q",
        "after m the sw shall always satisfy persists(1, p) | !q",
        "before m whenever occurs(2, p) the sw shall eventually satisfy q",
        "the sw shall always satisfy preBool(false, p) | q",
    ]
    rnd = random.Random(5)
    for s in sentences:
        req = parse(s)
        comp = compiled(req, rid="F")
        cls = load_module([comp], "fn_ev").MONITORS.get("F")
        for _ in range(200):
            n = rnd.randint(1, 12)
            cols = random_trace(rnd, n, variables=("m", "p", "q"), numeric=())
            ev = evaluate_requirement(req, cols, n, comp.formalization.ticks)
            where = (s, {k: v.tolist() for k, v in cols.items()})
            assert ev.holds == ft_at(comp.formalization.ft, samples(cols, n)), where
            if cls is not None:
                mon = cls()
                for smp in samples(cols, n):
                    mon.step(smp)
                assert ev.holds == mon.finish(), where


def test_unsupported_functions_are_reported():
    # every FRET temporal function is evaluated (tests/monitors/test_evidence_functions.py);
    # an uninterpreted function is not
    req = parse("whenever p the sw shall immediately satisfy prevOcc(p, q)")
    assert evaluate_requirement(req, _cols(p="01", q="11"), 2).holds
    req = parse("whenever p the sw shall immediately satisfy h(p, q)")
    with pytest.raises(EvidenceUnsupported):
        evaluate_requirement(req, _cols(p="01", q="11"), 2)
