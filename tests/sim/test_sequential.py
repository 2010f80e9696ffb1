"""Sequential tests (sim/sequential.py) on synthetic Bernoulli streams with known p: Wald's
error bounds hold, and the decisions come where they should."""

from __future__ import annotations

import numpy as np
import pytest

from fretc.sim.sequential import SPRT, SequentialCP, effective_delta, make_test


def _decide(test, rng, p, cap=20000):
    while test.decision is None and test.n < cap:
        test.update(bool(rng.random() < p))
    return test.decision


@pytest.mark.parametrize("op", [">=", "<="])
def test_sprt_error_rates_are_bounded_at_the_edges_of_the_indifference_region(op):
    rng = np.random.default_rng(2024)
    p, d, a, b, reps = 0.9, 0.03, 0.05, 0.05, 400
    bad_p = p - d if op == ">=" else p + d    # the bound is false by delta
    good_p = p + d if op == ">=" else p - d   # true by delta
    wrong_holds = sum(_decide(SPRT(op, p, d, a, b), rng, bad_p) == "holds" for _ in range(reps))
    wrong_fails = sum(_decide(SPRT(op, p, d, a, b), rng, good_p) == "fails" for _ in range(reps))
    # Wald: at most about alpha (beta); 3 binomial standard deviations of slack
    assert wrong_holds / reps <= a + 3 * (a * (1 - a) / reps) ** 0.5
    assert wrong_fails / reps <= b + 3 * (b * (1 - b) / reps) ** 0.5


def test_sprt_decides_clear_cases_quickly_and_right():
    rng = np.random.default_rng(7)
    outcomes = [_decide(SPRT(">=", 0.9, 0.05), rng, 0.99) for _ in range(50)]
    assert outcomes.count("holds") >= 48
    t = SPRT(">=", 0.9, 0.05)
    _decide(t, rng, 0.5)
    assert t.decision == "fails" and t.at < 20
    assert len(t.path) == t.n and t.to_json()["decision"] == "fails"


def test_sprt_equality_never_decides_and_says_why():
    t = SPRT("=", 0.5, 0.05)
    for _ in range(100):
        t.update(True)
    assert t.decision is None and "equality" in t.why_undecided()


def test_effective_delta_keeps_the_region_inside_0_1():
    assert effective_delta(0.99, 0.05) == pytest.approx(0.005)
    t = SPRT(">=", 0.99, 0.05)
    assert t.p_holds <= 1 and t.p_fails >= 0
    t1 = SPRT(">=", 1.0, 0.05)  # one violation refutes P = 1
    t1.update(False)
    assert t1.decision == "fails"
    assert t1.to_json()["path"] == ["-inf"]


def test_sequential_clopper_pearson_is_sound_and_decides():
    rng = np.random.default_rng(11)
    wrong = sum(_decide(SequentialCP(">=", 0.9, 0.05), rng, 0.88, cap=3000) == "holds"
                for _ in range(200))
    assert wrong <= 10 + 3 * (200 * 0.05 * 0.95) ** 0.5
    t = SequentialCP(">=", 0.5, 0.05)
    _decide(t, rng, 0.95)
    assert t.decision == "holds" and t.path[-1][1] >= 0.5


def test_bad_parameters_are_refused():
    with pytest.raises(ValueError):
        make_test("sprt", ">=", 0.9, 0.0, 0.05, 0.05)
    with pytest.raises(ValueError):
        make_test("wald", ">=", 0.9, 0.05, 0.05, 0.05)
