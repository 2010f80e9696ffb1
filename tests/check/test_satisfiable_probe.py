"""The worker's ``satisfiable`` query (:meth:`fretc.check.solver._Session.satisfiable`, the
redundancy stage's) against its ``sat`` query on random conjunctions: the same answer on
every one, whatever the probe's bound, and each of its ways to answer taken (an empty
product, a whole product, a word of the product tested on the conjuncts left, ``sat``)."""

from __future__ import annotations

import pytest

spot = pytest.importorskip("spot")

from fretc.check import solver  # noqa: E402
from fretc.check.solver import _Session, run_query  # noqa: E402


def _conjunctions(count: int, seed: int) -> list[tuple[list[str], list[str]]]:
    """``count`` queries: 2-6 random LTL formulas over 3 atoms (Spot's randltl, a fixed
    seed) as the base, one negated formula as the extra conjunct (as the redundancy of a
    requirement asks: the others and not it)."""
    gen = spot.randltl(["a", "b", "c"], seed=seed, tree_size=(4, 12), simplify=0)
    formulas = [str(next(gen)) for _ in range(count * 7)]
    out, k = [], 0
    for q in range(count):
        n = 2 + q % 5
        base = formulas[k:k + n]
        out.append((base, [f"!({formulas[k + n]})"]))
        k += n + 1
    return out


def test_satisfiable_answers_as_sat_does_whatever_the_probe(monkeypatch):
    ways = {"empty": 0, "whole": 0, "word": 0, "sat": 0}
    calls = {"sat": 0, "word": 0}
    real_sat, real_lasso = _Session.sat, spot.twa_word.as_automaton

    def counted_sat(self, base, extra):
        calls["sat"] += 1
        return real_sat(self, base, extra)

    def counted_lasso(self, *args):
        calls["word"] += 1
        return real_lasso(self, *args)

    monkeypatch.setattr(_Session, "sat", counted_sat)
    monkeypatch.setattr(spot.twa_word, "as_automaton", counted_lasso)
    queries = _conjunctions(60, seed=7)
    # (a redundant requirement: its negation with the others is empty)
    queries += [(["G(a -> X b)", "G(b -> c)", "GF a"], ["!G(a -> X c)"]),
                (["G(a -> b)", "G(b -> c)"], ["!G(a -> c)"])]
    for probe in (0, 1, 3, 8, 40, 10**6):
        for base, extra in queries:
            want = real_sat(_Session(), base, extra)[0]
            before = dict(calls)
            got = _Session().satisfiable(base, extra, probe=probe)
            assert got is want, (probe, base, extra)
            if calls["sat"] > before["sat"]:
                ways["sat"] += 1
            elif calls["word"] > before["word"]:
                ways["word"] += 1
                assert got is True
            else:
                ways["empty" if got is False else "whole"] += 1
    assert all(v >= 10 for v in ways.values()), ways


def test_satisfiable_is_a_query_of_the_worker_with_a_bool_answer():
    assert run_query(("satisfiable", ["G(a -> b)", "G(b -> c)"], ["!G(a -> c)"])) is False
    assert run_query(("satisfiable", ["G(a -> b)"], ["!G(b -> a)"])) is True
    assert solver.SPOT_PROBE_STATES > 0
