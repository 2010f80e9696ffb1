"""A CSV trace's ``gap`` row stands for one tick or more, how many not known
(docs/guide/ticks.md): the audit's verdict over random traces with ``gap`` rows and ``unknown``
cells against brute force, FRET's interval semantics (:func:`fretc.monitors.interval.
verdict_of`, another evaluator than the audit's pt formula) over every completion, each gap
row filled with one or two ticks of any values and each unknown cell with any value. A
verdict the audit gives is the one every completion gives (satisfied or vacuous: every one
holds; violated: every one violates); where the completions differ it is unknown. Two traces
where one tick in the gap and two ticks disagree are unknown."""

from __future__ import annotations

import itertools
import json
import random
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from _logs import written_plan
from fretc.audit import audit_log
from fretc.audit.verdict import audit_json
from fretc.monitors.interval import verdict_of

REQUIREMENTS = """\
S1: after a the sw shall always satisfy x > 3
S2: the sw shall always satisfy x > 3 | b
S3: upon a the sw shall within 2 ticks satisfy b
S4: upon a the sw shall for 1 tick satisfy b
S5: in a mode the sw shall always satisfy b
S6: before a the sw shall never satisfy x > 3
S7: upon !a the sw shall at the next timepoint satisfy b | x > 3
S8: whenever a the sw shall immediately satisfy b
S9: only after b the sw shall never satisfy a
S10: upon a the sw shall after 1 tick satisfy b
S11: the sw shall eventually satisfy a & b
S12: upon a the sw shall until b satisfy x > 3
"""
XS = (0.0, 4.5)
VALUES = {"a": ("0", "1"), "b": ("0", "1"), "x": ("0", "4.5")}


@pytest.fixture(scope="module")
def plan(tmp_path_factory):
    return written_plan(str(tmp_path_factory.mktemp("gap_rows")), "gaps.fret", REQUIREMENTS)


def _verdicts(plan, path: Path) -> dict[str, str]:
    la = audit_log(plan, str(path))
    data = json.loads(audit_json([la], plan.requirements_json(), plan.bindings_json()))
    return {v["requirement"]: v["verdict"] for v in data["logs"][0]["verdicts"]}


def _completions(rows: list[list[str]], names: list[str]):
    """Every trace the rows may stand for: a ``gap`` row one or two rows of any values of
    ``names``, an ``unknown`` cell any value; yields columns (name -> array) and length."""
    holes = [(i, j) for i, r in enumerate(rows) if r[0] != "gap"
             for j, c in enumerate(r) if c == "unknown"]
    gaps = [i for i, r in enumerate(rows) if r[0] == "gap"]
    letters = list(itertools.product(*(VALUES[v] for v in names)))
    for combo in itertools.product(*(VALUES[names[j]] for _i, j in holes)):
        base = [list(r) for r in rows]
        for (i, j), val in zip(holes, combo):
            base[i][j] = val
        for ks in itertools.product((1, 2), repeat=len(gaps)):
            for fills in itertools.product(*(itertools.product(letters, repeat=k)
                                             for k in ks)):
                by_gap = dict(zip(gaps, fills))
                out: list[list[str]] = []
                for i, r in enumerate(base):
                    out.extend([list(x) for x in by_gap[i]] if i in by_gap else [r])
                yield ({v: np.array([float(r[j]) for r in out]) if v == "x" else
                        np.array([r[j] == "1" for r in out]) for j, v in enumerate(names)},
                       len(out))


def _check(plan, tmp: Path, rows: list[list[str]]) -> dict[str, tuple[str, set[str]]]:
    names = ["a", "b", "x"]
    path = tmp / "trace.csv"
    path.write_text("a,b,x\n" + "".join(",".join(r) + "\n" for r in rows), encoding="utf-8")
    got = _verdicts(plan, path)
    out = {}
    for r in plan.requirements:
        req, ticks = r.requirement, r.formalization.ticks
        seen = {verdict_of(req, cols, n, ticks) for cols, n in _completions(rows, names)}
        holds = {v != "violated" for v in seen}
        v = got[r.id]
        if v in ("satisfied", "vacuous"):
            assert holds == {True}, (r.id, rows, v, seen)
        elif v == "violated":
            assert holds == {False}, (r.id, rows, v, seen)
        else:
            assert v == "unknown", (r.id, rows, v)
        out[r.id] = (v, seen)
    return out


def _rows(rnd: random.Random, n: int, gaps: int, unknowns: int) -> list[list[str]]:
    rows = [[rnd.choice("01"), rnd.choice("01"), rnd.choice(("0", "4.5", "3"))]
            for _ in range(n)]
    for _ in range(unknowns):
        rows[rnd.randrange(n)][rnd.randrange(3)] = "unknown"
    for _ in range(gaps):
        rows.insert(rnd.randrange(n + 1), ["gap"] * 3)
    return rows


@settings(max_examples=120, deadline=None)
@given(n=st.integers(1, 6), unknowns=st.integers(0, 2), rnd=st.randoms(use_true_random=False))
@pytest.mark.tor("TOR-DMG-002")
def test_a_gap_row_verdict_is_what_every_count_and_filling_gives(plan, tmp_path_factory, n,
                                                                 unknowns, rnd):
    _check(plan, tmp_path_factory.mktemp("g"), _rows(rnd, n, 1, unknowns))


@pytest.mark.slow
@settings(max_examples=2500, deadline=None)
@given(n=st.integers(1, 7), gaps=st.integers(1, 2), unknowns=st.integers(0, 2),
       rnd=st.randoms(use_true_random=False))
def test_a_gap_row_verdict_is_what_every_count_and_filling_gives_sweep(
        plan, tmp_path_factory, n, gaps, unknowns, rnd):
    _check(plan, tmp_path_factory.mktemp("g"), _rows(rnd, n, gaps, unknowns))


@pytest.mark.tor("TOR-DMG-002")
def test_traces_one_gap_tick_and_two_disagree_on_are_unknown(plan, tmp_path):
    """S7 on ``0,1,3 / unknown,1,0 / 1,0,1 / gap / 0,1,4.5`` was satisfied, S1 on ``0,1,4.5 /
    gap / 1,1,6 / 1,1,3 / 1,1,unknown`` vacuous: one tick in the gap meets them, two ticks
    (``0,0,0`` twice; ``1,0,0`` then ``0,0,0``) break them."""
    s7 = [["0", "1", "3"], ["unknown", "1", "0"], ["1", "0", "1"], ["gap"] * 3,
          ["0", "1", "4.5"]]
    got = _check(plan, tmp_path, s7)
    assert got["S7"][0] == "unknown" and got["S7"][1] >= {"satisfied", "violated"}
    s1 = [["0", "1", "4.5"], ["gap"] * 3, ["1", "1", "6"], ["1", "1", "3"],
          ["1", "1", "unknown"]]
    got = _check(plan, tmp_path, s1)
    assert got["S1"][0] == "unknown" and got["S1"][1] >= {"vacuous", "violated"}


@pytest.mark.tor("TOR-DMG-002")
def test_a_previous_value_across_a_gap_row_is_what_every_count_and_filling_gives(tmp_path):
    """A requirement reading the previous tick's value (``preReal``) across a gap row: the
    tick after the gap reads a value of the gap's, any value; the verdict is the one every
    count and filling gives, else unknown (against brute force)."""
    pre = written_plan(str(tmp_path), "pre.fret",
                       "P1: the sw shall always satisfy preReal(0, x) <= x | b\n"
                       "P2: whenever a the sw shall immediately satisfy preReal(0, x) < 3\n")
    rows = [["0", "1", "0"], ["gap"] * 3, ["0", "0", "4.5"], ["1", "1", "4.5"]]
    got = _check(pre, tmp_path, rows)
    assert got["P1"][0] == "unknown" and got["P2"][0] == "violated", got  # (a = 1 at 4.5)
    rows = [["1", "0", "4.5"], ["gap"] * 3, ["1", "0", "0"], ["0", "1", "0"]]
    got = _check(pre, tmp_path, rows)
    assert got["P1"][0] == got["P2"][0] == "unknown", got  # (a = 1 after the gap)


def test_a_violation_after_a_gap_row_stays_violated(plan, tmp_path):
    """A requirement that counts ticks is judged across a gap row (it was judged up to it,
    the violation after it hidden as unknown)."""
    rows = [["0", "0", "4.5"], ["gap"] * 3, ["0", "0", "4.5"], ["1", "0", "4.5"],
            ["0", "0", "4.5"], ["0", "0", "4.5"], ["0", "0", "4.5"]]
    got = _check(plan, tmp_path, rows)
    assert got["S3"][0] == "violated" and got["S4"][0] == "violated"
