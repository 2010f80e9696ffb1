"""Realizability with comparisons of several variables (:mod:`fretc.check.predicates`):
Spot's game takes each such comparison as a proposition, so a player could give ``x < y``
and ``y < x`` both true. The clusters' invariants make the per-tick ones exact; a
comparison z3 cannot decide tick by tick (``preReal``) or one of inputs and outputs that is
no bound makes the win of the player it favours ``unknown``, never
``realizable``/``unrealizable``; a bound of one output by the inputs is exact
(:mod:`fretc.check.bounds`)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.check.analysis import check_requirements
from fretc.check.solver import SpotWorker
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
from fretc.shield.build import build_shield
from fretc.shield.plan import ShieldError
from tests.check._roles import rest_as_outputs


def realizability_of(tmp_path: Path, text: str, inputs: list[str]) -> dict:
    """The realizability entry of the first component of the set ``text`` (queries in this
    process: the budgets are counted work, so the answers are the worker process's; the
    variables other than ``inputs`` outputs)."""
    p = tmp_path / "r.fret"
    p.write_text(text, encoding="utf-8")
    with SpotWorker(fork=False) as worker:
        compiled = compile_entries(load_requirements([p]))
        r = check_requirements(compiled, inputs=inputs,
                               outputs=rest_as_outputs(compiled, inputs),
                               vacuity=False, redundancy=False, worker=worker)
    return r.realizability["groups"][0]


def test_a_controller_cannot_make_x_below_y_and_y_below_x(tmp_path: Path) -> None:
    """Before the invariants, Spot's controller set both atoms true: realizable."""
    got = realizability_of(tmp_path, "A: the sw shall always satisfy x < y\n"
                                     "B: the sw shall always satisfy y < x\n", [])
    assert got["realizable"] is False


def test_per_tick_comparisons_of_outputs_stay_decided(tmp_path: Path) -> None:
    got = realizability_of(tmp_path, "A: the sw shall always satisfy x < y\n"
                                     "B: whenever i the sw shall immediately satisfy y < 3 & x > 1\n",
                           ["i"])
    assert got["realizable"] is True


def test_an_environment_cannot_make_a_below_b_and_b_below_a(tmp_path: Path) -> None:
    """The environment's spurious win: both atoms true forces o and !o."""
    got = realizability_of(tmp_path, "A: the sw shall always satisfy (a < b & b < a) -> o\n"
                                     "B: the sw shall always satisfy (a < b & b < a) -> !o\n",
                           ["a", "b"])
    assert got["realizable"] is True


def test_a_previous_value_of_an_output_makes_realizable_unknown(tmp_path: Path) -> None:
    """x starts at 10 and moves by at most 1 a tick: it cannot be at most 0 within 3 ticks.
    The abstraction's controller sets the rate atom true while x jumps: it said realizable."""
    got = realizability_of(tmp_path, (
        "A: the sw shall immediately satisfy x = 10.0\n"
        "B: the sw shall always satisfy FTP | absReal(preReal(0.0, x) - x) <= 1.0\n"
        "C: the sw shall within 3 ticks satisfy x <= 0.0\n"), [])
    assert got["realizable"] == "unknown"
    assert "previous value" in got["why"] and "preReal" in got["why"]


def test_an_output_above_an_input_is_realizable(tmp_path: Path) -> None:
    """For every input number a there is an x above it and below a + 1: realizable (the
    controller's choices hold whatever the input's number)."""
    got = realizability_of(tmp_path, "A: the sw shall always satisfy x > a\n"
                                     "B: the sw shall always satisfy x < a + 1.0\n", ["a"])
    assert got["realizable"] is True


def test_a_bound_whose_feasibility_the_environment_decides_is_exactly_unrealizable(
        tmp_path: Path) -> None:
    """x above a and below 3 fails for a >= 3 (truly unrealizable). It was unknown (the
    game's controller saw truth values, not numbers); ``x > a`` is a bound of x by the input
    (fretc.check.bounds): which of its truth values numbers give beside ``x < 3.0`` is the
    environment's move (the order comparison ``3.0 <= a``), so the answer is exact, and the
    input that defeats every controller is a number at or above 3."""
    got = realizability_of(tmp_path, "A: the sw shall always satisfy x > a\n"
                                     "B: the sw shall always satisfy x < 3.0\n", ["a"])
    assert got["realizable"] is False
    assert got["environment"]["prefix"] + got["environment"]["cycle"] == [{"a": 3.0}]


def test_a_bound_the_environment_keeps_feasible_is_realizable(tmp_path: Path) -> None:
    """Below 3 (the environment's condition, related by the numeric abstraction to the
    order comparison of the bounds) the controller can keep x above a and below 3."""
    got = realizability_of(tmp_path, "A: whenever a < 3.0 the sw shall immediately satisfy "
                                     "x > a\nB: the sw shall always satisfy x < 3.0\n", ["a"])
    assert got["realizable"] is True


def test_a_comparison_of_inputs_and_outputs_that_is_no_bound_leaves_a_loss_unknown(
        tmp_path: Path) -> None:
    """``x * a > 1`` reads x with a factor the input sets: no bound; the game's controller
    sees truth values, not numbers, so its loss is unknown, with why."""
    got = realizability_of(tmp_path, "A: the sw shall always satisfy x * a > 1.0\n"
                                     "B: the sw shall always satisfy x < 3.0\n", ["a"])
    assert got["realizable"] == "unknown"
    assert "compare the input(s) a with the output(s) x" in got["why"]


def test_a_visible_input_comparison_lets_the_controller_choose(tmp_path: Path) -> None:
    """Below 3 the controller keeps x above a and below 3; at or above 3 it may leave x
    anywhere: it sees the truth of a < 3 and chooses accordingly."""
    got = realizability_of(tmp_path, "A: whenever a < 3.0 the sw shall immediately satisfy "
                                     "x > a & x < 3.0\n", ["a"])
    assert got["realizable"] is True


def test_an_unrealizable_answer_stands_against_a_freer_controller(tmp_path: Path) -> None:
    """A preReal atom the controller sets freely cannot make it lose: unrealizable stands."""
    got = realizability_of(tmp_path, (
        "A: the sw shall always satisfy o\n"
        "B: whenever i the sw shall immediately satisfy !o\n"
        "C: the sw shall always satisfy FTP | absReal(preReal(0.0, x) - x) <= 1.0\n"), ["i"])
    assert got["realizable"] is False


_ATOMS = ["x < y", "y < x", "x + y > 3.0", "x > 2.0", "i", "o"]
_FORMS = ["the sw shall always satisfy {a} -> {b}",
          "whenever {a} the sw shall immediately satisfy {b}",
          "upon {a} the sw shall at the next timepoint satisfy {b}",
          "the sw shall always satisfy {a} | {b}",
          "the sw shall always satisfy {a} & {b}"]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.sampled_from(_FORMS), st.sampled_from(_ATOMS),
                          st.sampled_from(_ATOMS + ["!o"])),
                min_size=1, max_size=3))
def test_check_agrees_with_the_shield_on_comparisons_of_outputs(tmp_path: Path, parts) -> None:
    """Differential: ``fretc check`` (Spot's game with the clusters' invariants) and the
    shield (the safety game with the same clusters, :mod:`fretc.shield.plan`) decide
    realizability of the same safety sets alike."""
    text = "".join(f"R{k}: " + form.format(a=a, b=b) + "\n"
                   for k, (form, a, b) in enumerate(parts))
    got = realizability_of(tmp_path, text, ["i"])
    if got["realizable"] == "unknown":
        pytest.skip("the game ran past its budget")
    p = tmp_path / "r.fret"
    compiled = compile_entries(load_requirements([p]))
    if any(set(c.formalization.variables) <= {"i"} for c in compiled):
        return  # over inputs only: the shield monitors it, check finds it unrealizable
    variables = sorted({v for c in compiled for v in c.formalization.variables})
    try:
        build_shield(compiled, ["i"], [v for v in variables if v != "i"], fork=False)
        shield = True
    except ShieldError as exc:
        if "not a safety" in str(exc) or "over inputs only" in str(exc):
            return
        shield = False
    assert got["realizable"] is shield, text


_MIXED = ["x > a", "x < a + 1.0", "x < 3.0", "a < 2.0", "x > 1.0", "a > x + 2.0", "a >= 5.0"]


def _truth(parts: list[tuple[str, str, str]]) -> bool:
    """Ground truth for invariants of one tick: realizable iff for every a some x meets
    them all (z3, quantified linear real arithmetic)."""
    import z3

    a, x = z3.Reals("a x")
    env = {"a": a, "x": x}

    def atom(text: str):
        return eval(text.replace("&", " and "), {}, env)  # noqa: S307 - the fixed atoms above

    def form(op: str, p: str, q: str):
        return {"&": z3.And, "|": z3.Or, "->": z3.Implies}[op](atom(p), atom(q))

    s = z3.Solver()
    s.add(z3.Not(z3.ForAll([a], z3.Exists([x], z3.And(*[form(o, p, q) for o, p, q in parts])))))
    return s.check() == z3.unsat


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.sampled_from(["&", "|", "->"]), st.sampled_from(_MIXED),
                          st.sampled_from(_MIXED)), min_size=1, max_size=3))
def test_realizability_of_an_input_and_an_output_never_contradicts_the_numbers(
        tmp_path: Path, parts) -> None:
    """Invariants of one tick over an input a and an output x are realizable exactly when
    every a has an x: ``fretc check`` answers that, or unknown - never the other."""
    text = "".join(f"R{k}: the sw shall always satisfy ({p}) {op} ({q})\n"
                   for k, (op, p, q) in enumerate(parts))
    got = realizability_of(tmp_path, text, ["a"])
    if got["realizable"] != "unknown":
        assert got["realizable"] is _truth(parts), text


def test_a_comparison_z3_does_not_decide_in_its_limit_is_unknown(tmp_path: Path,
                                                                 monkeypatch) -> None:
    """A query past z3's resource limit leaves the cluster undecided: the realizability is
    unknown and says so (before the limit, an unknown answer raised from z3's unsat core)."""
    from fretc.check import predicates

    monkeypatch.setattr(predicates, "RLIMIT", 1)
    got = realizability_of(tmp_path, "A: the sw shall always satisfy x * y > 2.0\n"
                                     "B: the sw shall always satisfy x * x < y - 3.0\n", [])
    assert got["realizable"] == "unknown"
    assert "z3 did not decide" in got["why"]
