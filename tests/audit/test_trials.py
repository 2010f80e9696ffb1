"""The triggers of a probability requirement as trials (audit/trials.py): against FRET's
interval semantics on random traces (every violated trigger is a violated trial; the others
are satisfied trials or, only for a timing window the end of the log cut, cut), cut triggers
are exactly those a continuation of the run could still decide, and unknown ticks or a
damaged end make a trigger unknown, never a success."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.audit.trials import TIMED_WINDOWS, trigger_outcomes, trigger_trials
from fretc.fretish.parser import parse
from fretc.monitors.interval import evaluate_requirement
from fretc.monitors.unknowns import Unknowns

SCOPES = ["", "in mode m ", "unless in mode m ", "only in mode m ", "after m ", "before m ",
          "only after m ", "only before m "]
CONDITIONS = ["", "upon c ", "whenever c "]
TIMINGS = ["immediately", "at the next timepoint", "finally", "eventually", "", "always",
           "never", "within 2 ticks", "for 2 ticks", "after 2 ticks", "until s", "before s"]


def _req(scope: str, cond: str, timing: str):
    return parse(f"{scope}{cond}the robot shall with probability >= 0.9 {timing} "
                 "satisfy r".replace("  ", " "))


def _columns(bits: list[tuple[bool, ...]]) -> dict:
    arr = np.array(bits, dtype=np.bool_).reshape(len(bits), 4)
    return {name: arr[:, i].copy() for i, name in enumerate("mcrs")}


traces = st.lists(st.tuples(*[st.booleans()] * 4), min_size=1, max_size=14)


@settings(max_examples=300)
@given(st.sampled_from(SCOPES), st.sampled_from(CONDITIONS), st.sampled_from(TIMINGS),
       traces)
def test_trials_agree_with_fret_interval_semantics(scope, cond, timing, bits):
    req = _req(scope, cond, timing)
    cols, n = _columns(bits), len(bits)
    ev = evaluate_requirement(req, cols, n, 2)
    t = trigger_trials(req, cols, n, 2)
    assert t.satisfied + t.violated + t.cut == ev.triggers and t.unknown == 0
    assert t.violated == ev.violations  # a failed trigger is a violated trial
    if req.timing.kind not in TIMED_WINDOWS:
        assert t.cut == 0  # untimed obligations end with the run


@settings(max_examples=300)
@given(st.sampled_from(SCOPES[:3]), st.sampled_from(CONDITIONS),
       st.sampled_from(["at the next timepoint", "within 2 ticks", "for 2 ticks",
                        "after 2 ticks"]), traces, traces)
def test_cut_triggers_are_those_the_rest_of_the_run_decides(scope, cond, timing, bits, more):
    """Decided triggers keep their outcome whatever follows (the scope mode going on as
    at the last tick); some continuation decides each cut trigger either way."""
    req = _req(scope, cond, timing)
    n = len(bits)
    before = dict(trigger_outcomes(req, _columns(bits), n, 2))
    last_m = bits[-1][0]
    tails = {"given": [(last_m, x[1], x[2], x[3]) for x in more] + [(last_m, False, False,
                                                                       False)] * 4}
    for j in range(6):  # the response false for j ticks, then true
        tails[j] = [(last_m, False, i >= j, False) for i in range(5)]
    after = {name: dict(trigger_outcomes(req, _columns(bits + tail), n + len(tail), 2))
             for name, tail in tails.items()}
    for t, kind in before.items():
        if kind != "cut":
            assert all(a[t] == kind for a in after.values()), (t, kind, after)
        else:
            assert {after[j][t] for j in range(6)} == {"satisfied", "violated"}


def test_within_near_the_end_of_the_log_is_cut_not_satisfied():
    req = _req("", "upon c ", "within 2 ticks")
    cols = _columns([(0, 0, 0, 0), (0, 1, 0, 0), (0, 0, 0, 0), (0, 0, 1, 0), (0, 1, 0, 0),
                     (0, 0, 0, 0)])
    assert list(trigger_outcomes(req, cols, 6, 2)) == [(1, "satisfied"), (4, "cut")]
    # FRET's finite-trace semantics reads the cut trigger as met
    assert evaluate_requirement(req, cols, 6, 2).violations == 0
    # the interval's own end (not the log's) closes a window: FRET's vacuous pass stands
    inscope = _req("in mode m ", "upon c ", "within 2 ticks")
    cols = _columns([(1, 1, 0, 0), (1, 0, 0, 0), (0, 0, 0, 0), (0, 0, 0, 0)])
    assert list(trigger_outcomes(inscope, cols, 4, 2)) == [(0, "satisfied")]


def test_a_damaged_end_leaves_open_triggers_unknown():
    req = _req("", "upon c ", "eventually")
    cols = _columns([(0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 0), (0, 1, 0, 0), (0, 0, 0, 0)])
    assert list(trigger_outcomes(req, cols, 5, None)) == [(0, "satisfied"), (3, "violated")]
    assert list(trigger_outcomes(req, cols, 5, None, damaged=True)) == [
        (0, "satisfied"), (3, "unknown")]  # the run went on past the damage


def _unknowns(req, cols, n, unknown: dict) -> Unknowns:
    marks = {k: np.array(v, dtype=np.bool_) for k, v in unknown.items()}
    return Unknowns.of(req, marks, cols, n, nan_unknown=False)


def test_unknown_ticks_make_a_trigger_unknown_never_a_success():
    req = _req("", "upon c ", "within 2 ticks")
    cols = _columns([(0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 0), (0, 1, 0, 0), (0, 0, 0, 0),
                     (0, 0, 0, 0), (0, 1, 0, 0), (0, 0, 0, 0), (0, 0, 0, 0), (0, 0, 0, 0)])
    assert [k for _, k in trigger_outcomes(req, cols, 10, 2)] == [
        "satisfied", "violated", "violated"]
    # r unknown at tick 1 (where it met the first trigger) and at 4 (inside the second's
    # window): both unknown; the third trigger's window is known
    u = _unknowns(req, cols, 10, {"r": [0, 1, 0, 0, 1, 0, 0, 0, 0, 0]})
    assert [k for _, k in trigger_outcomes(req, cols, 10, 2, u)] == [
        "unknown", "unknown", "violated"]
    # the condition unknown where the third trigger rises: no trial, and maybe hidden
    u = _unknowns(req, cols, 10, {"c": [0, 0, 0, 0, 0, 0, 1, 0, 0, 0]})
    t = trigger_trials(req, cols, 10, 2, u)
    assert (t.satisfied, t.violated, t.unknown, t.hidden) == (1, 1, 1, True)


def test_one_tick_meets_eventually_whatever_the_unknown_ticks_after_it():
    req = _req("", "upon c ", "eventually")
    cols = _columns([(0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 0), (0, 0, 0, 0)])
    u = _unknowns(req, cols, 4, {"r": [0, 0, 1, 1]})
    assert list(trigger_outcomes(req, cols, 4, None, u)) == [(0, "satisfied")]
    u = _unknowns(req, cols, 4, {"r": [0, 1, 0, 0]})  # the tick that met it is unknown
    assert list(trigger_outcomes(req, cols, 4, None, u)) == [(0, "unknown")]
