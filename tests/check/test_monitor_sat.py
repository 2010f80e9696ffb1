"""fretc check on the requirements' pt monitors (check/monitor_sat.py, check/pt_monitor.py):

* the premise: for every template key whose ft_inf is safety, ft_inf holds on a lasso iff the
  pt formula holds at every tick (random lassos), and `finally` is rightly left out;
* the BDD monitor, with its one-counter deadlines, gives the pt formula's value at every tick
  of random traces for every template key (against compiler.evaluate);
* the same answers as Spot on random sets with bounds up to 12;
* deadlines of 250 ticks decided, with a witness fretc audit replays;
* the fixed points' step through the transition relation in parts (one relational product
  per counter) gives the same sets as BuDDy's substitution of every next-value function and
  as the monolithic relational product, on random sets and sets of states; the counters'
  interleaved bits keep the states of a 1000-tick set a small BDD.
"""

from __future__ import annotations

import random
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from fretc.check.analysis import check_requirements
from fretc.check.items import make_item, monitored_forms
from fretc.check.budget import Budget, Meter
from fretc.check.monitor_sat import _Search
from fretc.check.numeric_abstraction import NumericAbstraction
from fretc.check.safety_game import Game, pt_monitors_ft_inf
from fretc.check.solver import UNKNOWN, SpotWorker
from fretc.check.witness import read_expected
from fretc.compiler import ir
from fretc.compiler.build import compile_entries
from fretc.compiler.evaluate import series
from fretc.compiler.semantics import formalize
from fretc.fretish import parse
from fretc.fretish.files import load_requirements
from fretc.monitors.interval import verdict_of
from tests.check._replay import audit_verdicts
from tests.check.test_smt import _FORMULA, _SET, _file, _spot_sat, assert_same_answers
from tests.lasso import lasso_at
from tests.compiler.test_semantics import (CONDITION_PHRASES, KEYS, SCOPE_PHRASES,
                                           TIMING_PHRASES)


def _sentences(bound: int, rnd: random.Random):
    """One sentence per template key and response (r, false, true), phrases drawn."""
    for scope, cond, timing in KEYS:
        for resp in ("r", "false", "true"):
            parts = (rnd.choice(SCOPE_PHRASES[scope]), rnd.choice(CONDITION_PHRASES[cond]),
                     "the sw shall", rnd.choice(TIMING_PHRASES[timing]).format(n=bound),
                     "satisfy", resp)
            yield (scope, cond, timing), " ".join(x for x in parts if x)


def _letters(rnd: random.Random, n: int) -> list[dict]:
    return [{v: rnd.random() < 0.5 for v in "mcrs"} for _ in range(n)]


def test_pt_monitors_ft_inf_on_random_lassos():
    """ft_inf on a lasso u v^w equals "pt at every tick" (pt read on u v^12: its state is
    periodic by then for bounds up to 4) for every key the monitors take; the `finally`
    timing, left out, disagrees."""
    rnd = random.Random(7)
    taken, finally_disagrees = 0, False
    for (_s, _c, timing), sentence in _sentences(rnd.randint(2, 4), rnd):
        f = formalize(parse(sentence))
        for _ in range(25):
            u, v = _letters(rnd, rnd.randint(0, 6)), _letters(rnd, rnd.randint(1, 3))
            same = lasso_at(f.ft_inf, u, v) == all(series(f.pt, u + v * 12))
            if pt_monitors_ft_inf(f):
                assert same, (sentence, u, v)
            elif timing == "finally" and not same:
                finally_disagrees = True
        taken += pt_monitors_ft_inf(f)
    assert taken > 400 and finally_disagrees


def _monitor_series(pt, trace: list[dict]) -> tuple[list[bool], int]:
    """The BDD monitor of ``pt`` run on ``trace``: its value at each tick, and how many
    deadlines it monitors by a counter."""
    g = Game([pt], [], ir.TRUE, ir.TRUE)
    try:
        b, m = g.b, g.m
        state, out = g.init, []
        for letter in trace:
            here = state
            for atom, var in m.atom_var.items():
                here = b.bdd_and(here, b.bdd_ithvar(var) if letter[atom.name]
                                 else b.bdd_nithvar(var))
            out.append(b.bdd_and(here, g.ok) != b.bddfalse)
            state = b.bddtrue
            for cur, _nxt, _init, fn in m.bits:
                on = b.bdd_and(here, fn) != b.bddfalse
                state = b.bdd_and(state, b.bdd_ithvar(cur) if on else b.bdd_nithvar(cur))
        return out, len(m.deadlines)
    finally:
        g.close()


@pytest.mark.parametrize("bound", [2, 3, 5])
def test_bdd_monitor_gives_the_pt_value_at_every_tick(bound):
    """The one-counter deadlines keep the value of the whole pt formula exact at every tick
    (FRET's within and after timings, in every scope), against the reference evaluator."""
    rnd = random.Random(bound)
    counted = 0
    for _key, sentence in _sentences(bound, rnd):
        f = formalize(parse(sentence))
        if not pt_monitors_ft_inf(f):
            continue
        for _ in range(6):
            trace = _letters(rnd, rnd.randint(1, 3 * bound + 6))
            got, deadlines = _monitor_series(f.pt, trace)
            assert got == [bool(x) for x in series(f.pt, trace)], (sentence, trace)
        counted += deadlines > 0
    assert counted >= 20  # the counters were exercised, not only delay lines


def test_a_deadline_is_a_counter_not_a_delay_line():
    f = formalize(parse("whenever p the sw shall within 250 ticks satisfy q"))
    g = Game([f.pt], [], ir.TRUE, ir.TRUE)
    try:
        assert len(g.m.deadlines) == 1 and len(g.m.bits) < 32
    finally:
        g.close()


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                HealthCheck.function_scoped_fixture])
@given(_SET)
def test_monitors_and_spot_agree_on_random_sets(tmp_path_factory, parts):
    """Every check answers alike by the pt monitors (engine bdd, z3 for what they do not
    take) and by Spot, on bounds up to 12, where neither is unknown."""
    path = _file(tmp_path_factory.mktemp("mon"), parts)
    assert_same_answers(*(check_requirements(compile_entries(load_requirements([path])),
                                             engine=e) for e in ("spot", "bdd")),
                        path)


@settings(max_examples=40, deadline=None)
@given(st.one_of(st.lists(_FORMULA, min_size=1, max_size=3),
                 st.builds(lambda f, g: [ir.or_(f, g), ir.not_(f)], _FORMULA, _FORMULA)))
@example([ir.F(ir.ap("p")), ir.G(ir.not_(ir.ap("p")))])
@example([ir.G(ir.F(ir.ap("p"))), ir.F(ir.G(ir.ap("q"))), ir.G(ir.implies(ir.ap("q"),
                                                                         ir.not_(ir.ap("p"))))])
def test_buchi_product_agrees_with_spot_on_random_formulas(formulas):
    """Random LTL formulas (``F``, ``G``, ``U``, ``V``, bounds up to 15) as liveness formulas
    of the monitor query (their Büchi automata in the product, nondeterminism chosen like a
    letter): satisfiable on infinite runs exactly when Spot says so. Half the sets are
    ``f | g`` with ``!f``: satisfiable exactly when ``g & !f`` is, which an acceptance
    condition left out gets wrong."""
    from fretc.check.numeric_abstraction import NumericAbstraction

    inv = NumericAbstraction.of(formulas).regions(
        sorted({v for f in formulas for v in ir.variables(f)}))
    with SpotWorker(fork=False) as w:
        got = w.ask(("monitor_sat", [], [], inv, False, None, list(formulas), []))
        assert got != UNKNOWN, w.failures
        ref = _spot_sat(w, ir.and_all(*formulas))
    assert got[0] == ref[0], [str(f) for f in formulas]


def test_finally_is_not_taken_for_its_pt_formula(tmp_path):
    """`at the last timepoint` holds on every infinite run (ft_inf); with `always !r` the set
    is realizable. Its pt formula (r at the last tick) once made the safety game say no."""
    p = tmp_path / "f.fret"
    p.write_text("A: the sw shall at the last timepoint satisfy r\n"
                 "B: the sw shall always satisfy !r\n", encoding="utf-8")
    r = check_requirements(compile_entries(load_requirements([p])), inputs=["p"],
                           outputs=["r"])
    assert r.realizability["groups"][0]["realizable"] is True


def test_deadlines_of_250_ticks_are_decided_with_a_replayed_witness(tmp_path):
    """Four interacting 250-tick requirements: every answer known; B4's trigger cannot fire
    beside B5 (a vacuity with the minimal set {B4, B5}); the witness replays through the
    audit with the verdicts its header promises."""
    _deadlines_decided(tmp_path, 250)


@pytest.mark.slow
def test_deadlines_of_1000_ticks_are_decided_with_a_replayed_witness(tmp_path):
    """The same set with 1000-tick deadlines (bench/bench_check.py times it)."""
    _deadlines_decided(tmp_path, 1000)


def _deadlines_decided(tmp_path: Path, n: int) -> None:
    p = tmp_path / "d.fret"
    p.write_text(f"B1: whenever p the sw shall within {n} ticks satisfy q\n"
                 f"B2: upon p the sw shall for {n - 3} ticks satisfy !q\n"
                 f"B4: in m mode upon p the sw shall within {n} ticks satisfy speed > 0.6\n"
                 "B5: in m mode the sw shall always satisfy speed <= 0.5\n", encoding="utf-8")
    r = check_requirements(compile_entries(load_requirements([p])),
                           witness_dir=str(tmp_path / "w"), witness_judge=verdict_of)
    status = {s["id"]: s for s in r.requirements}
    assert r.unknown_queries == 0 and r.monitor_queries > 0 and r.smt_queries == 0
    assert [status[i]["non_vacuous"] for i in ("B1", "B2", "B4", "B5")] == [
        True, True, False, True]
    assert all(s["satisfiable"] is True and s["redundant"] is False
               for s in r.requirements)
    (vac,) = [f for f in r.findings if f.kind == "vacuous"]
    assert vac.subsets == [["B4", "B5"]] and vac.details["witness_shows_finding"] is True
    promised = read_expected(vac.witness)
    assert audit_verdicts(p, Path(vac.witness), tmp_path) == promised
    assert promised["B4"] == "satisfied" and promised["B5"] == "violated"


def _random_states(b, game, rnd: random.Random):
    """A random set of monitor states: a union of up to four cubes over the state bits."""
    out = b.bddfalse
    for _ in range(rnd.randint(1, 4)):
        cube = b.bddtrue
        for cur, _nxt, _init, _fn in rnd.sample(game.m.bits, min(4, len(game.m.bits))):
            cube = b.bdd_and(cube, b.bdd_ithvar(cur) if rnd.random() < 0.5
                             else b.bdd_nithvar(cur))
        out = b.bdd_or(out, cube)
    return out


@settings(max_examples=12, deadline=None, suppress_health_check=[
    HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(_SET, st.integers(0, 2**16))
def test_the_step_in_parts_gives_the_sets_of_the_whole_relation(tmp_path_factory, parts, seed):
    """On random sets (bounds up to 12, the requirements safe and one negated as a goal):
    the successors in a set of states by one relational product per part of the
    transition relation (check/monitor_sat.py) equal BuDDy's simultaneous substitution of
    the next-value functions (``Game.successors_in``), and the predecessors equal those of
    the monolithic relational product, for Live's iterates and random sets of states; so
    do the successors from one state with the parts restricted to it."""
    path = _file(tmp_path_factory.mktemp("parts"), parts)
    items = [make_item(k, c) for k, c in
             enumerate(compile_entries(load_requirements([path]))) if c.error is None]
    forms = monitored_forms(items)[False]
    safe = [v[1] for k, v in forms.items() if v[0] == "safe"]
    goals = [v[1] for k, v in forms.items() if v[0] == "goal"][:1]
    if not safe:
        return
    inv = NumericAbstraction.of(list(forms)).regions(["s"])
    game = Game(safe, [], ir.TRUE, inv, extra=[ir.O(g) for g in goals])
    try:
        search, b, rnd = _Search(game, Meter(Budget())), game.b, random.Random(seed)
        whole = b.bdd_and(search.ok, game.trans)
        step_vars = b.bdd_and(game.nxt_set, search.letter_set)
        targets, z = [], b.bddtrue
        for _ in range(6):  # the first iterates of Live
            z = b.bdd_and(z, search.pre(z))
            targets.append(z)
        targets += [_random_states(b, game, rnd) for _ in range(4)]
        for target in targets:
            succ = game.successors_in(target)
            assert search.successors_in(target) == succ
            assert search.pre(target) == b.bdd_appex(whole, game._primed(target),
                                                     b.bddop_and, step_vars)
            state = b.bddtrue  # one state: the parts restricted to it first (witnesses)
            for cur, _nxt, _init, _fn in game.m.bits:
                state = b.bdd_and(state, b.bdd_ithvar(cur) if rnd.random() < 0.5
                                  else b.bdd_nithvar(cur))
            assert b.bdd_and(search.successors_in(target, state), state) == b.bdd_and(
                succ, state)
    finally:
        game.close()


def test_the_states_of_a_1000_tick_set_are_a_small_bdd():
    """With the counters' bits interleaved by significance (check/pt_monitor.py), the states
    that keep two 1000-tick deadlines and a 997-tick hold ("the hold ends before the
    deadline": a difference of counters) are a BDD of about a hundred nodes; with each
    counter's bits together they took about 3000."""
    pts = [formalize(parse(s)).pt for s in (
        "whenever p the sw shall within 1000 ticks satisfy q",
        "upon p the sw shall for 997 ticks satisfy !q",
        "in m mode upon p the sw shall within 1000 ticks satisfy r")]
    game = Game(pts, [], ir.TRUE, ir.TRUE)
    try:
        live = _Search(game, Meter(Budget())).live()
        assert live != game.b.bddfalse and game.b.bdd_nodecount(live) < 400
    finally:
        game.close()


@pytest.mark.parametrize("text, kinds", [
    ("B1: whenever p the sw shall within 250 ticks satisfy q\n"
     "B2: upon p the sw shall for 253 ticks satisfy !q\n"
     "B3: the sw shall eventually satisfy p\n", ["conflict"]),
    ("B1: whenever p the sw shall within 250 ticks satisfy q\n"
     "B2: upon p the sw shall for 247 ticks satisfy !q\n"
     "B3: the sw shall eventually satisfy p\n"
     "B6: whenever q the sw shall eventually satisfy r\n", []),
])
def test_eventually_beside_250_tick_deadlines(tmp_path, text, kinds):
    """``eventually`` requirements beside 250-tick deadlines: every query decided by the
    monitors with the Büchi automata in the product (no z3), the finite witnesses by the
    last-tick pt formulas; each witness replays through fretc audit as its header says."""
    req = tmp_path / "set.fret"
    req.write_text(text, encoding="utf-8")
    r = check_requirements(compile_entries(load_requirements([req])),
                           witness_dir=str(tmp_path / "w"), witness_judge=verdict_of)
    assert [f.kind for f in r.findings] == kinds, [f.message for f in r.findings]
    assert r.smt_queries == 0 and r.unknown_queries == 0 and r.monitor_queries > 0
    assert r.witnesses
    for w in r.witnesses:
        promised = read_expected(w["path"])
        assert promised and audit_verdicts(req, Path(w["path"]), tmp_path) == promised
    if kinds:
        assert r.findings[0].details["witness_shows_finding"] is True


def test_a_deadline_under_a_root_conjunction_is_not_counted():
    # a deadline O[N,N] a -> O[0,N-1] b that is a conjunct of a formula's root conjunction
    # (no parent above it) is kept as its delay line, not one counter; it raised
    # AttributeError (the root's missing parent read as None.op) before
    from fretc.check.pt_monitor import deadline_uses

    a, b, x = (ir.Node("ap", name=v) for v in "abx")
    phi = ir.implies(ir.O(a, 2, 2), ir.O(b, 0, 1))
    assert deadline_uses([ir.and_(phi, x)]) == {}
    # under a since formula's left, as the counter wants it, it is counted
    assert deadline_uses([ir.S(ir.and_(phi, x), x)]) == {}
    since = ir.S(phi, ir.and_(x, phi))
    assert deadline_uses([since]) == {phi: [x]}
