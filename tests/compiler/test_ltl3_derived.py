"""LTL3 monitors of safety and guarantee shapes built from one cheap translation.

``compiler.spot_monitors.spot_automata`` builds the bad-prefix monitor of a syntactic safety
formula from Spot's terminal automaton of its (guarantee) negation
(``compiler.dfa.guarantee_bad_prefixes``), translates it for a formula that is safety only
after Spot's basic rewriting, and derives the other monitor from it
(``compiler.dfa.safety_complement``). Differential:
each derived table equals the table of Spot's monitor translated directly
(``spot_monitors._spot_monitor``), on the 288 template keys, on FRET's trace-vector sentences and
on random formulas (hypothesis); plus hand-checked small cases of both rules.
"""

from __future__ import annotations

import random
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

spot = pytest.importorskip("spot")

from fretc.compiler import automata, dfa, spot_monitors  # noqa: E402
from fretc.compiler.printers import to_spot  # noqa: E402
from fretc.compiler.semantics import formalize  # noqa: E402
from fretc.fretish import parse  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "tests" / "compiler"))

from bench_codegen import template_sentences  # noqa: E402
from test_ltl3_exact import _verdict_sentences  # noqa: E402
from _shared import PRESENT  # noqa: E402

MAX, APS = automata.MAX_AUTOMATON_STATES, automata.TABLE_MAX_APS


def _translated(text: str, n_atoms: int) -> dict:
    return {"bad": spot_monitors._spot_monitor(text, False, n_atoms, MAX, APS),
            "good": spot_monitors._spot_monitor(text, True, n_atoms, MAX, APS)}


def _check(text: str, n_atoms: int) -> str:
    """Assert that each derivation that applies to ``text`` gives the translated table;
    return the shape's class: "safety" or "guarantee" (syntactically), "rewritten" (after
    Spot's basic rewriting) or "neither"."""
    f = spot.formula(text)
    side, cls = spot_monitors._safety_side(f), None
    if side is None:
        g = spot.tl_simplifier(spot.tl_simplifier_options(True, False, False)).simplify(f)
        side = spot_monitors._safety_side(g)
        cls = "rewritten" if side is not None else "neither"
    want = _translated(text, n_atoms)
    if side is not None:
        other = "good" if side == "bad" else "bad"
        if cls is None:
            cls = "safety" if side == "bad" else "guarantee"
            terminal = spot_monitors._terminal_monitor(
                f if side == "good" else spot.formula.Not(f), n_atoms, MAX)
            assert terminal == want[side], (text, side)
        assert spot_monitors._safety_complement_data(want[side], MAX) == want[other], \
            (text, other)
    assert spot_monitors.spot_automata(text, n_atoms, MAX, APS) == want, text
    return cls


def _shape(sentence: str) -> tuple[str, int]:
    shape, atoms = automata.canonical_shape(formalize(parse(sentence)).ft_inf)
    return to_spot(shape), len(atoms)


#: (FRET's trace-vector sentences only with ../shared)
SENTENCES = template_sentences(3) + (
    random.Random(5).sample(_verdict_sentences(), 40) if PRESENT else []) + [
    # the slowest safety shape of the trace vectors: bounds 7 to 9 under an 'only after'
    "only after m upon c the sw shall within 9 ticks satisfy r"]


def test_derived_tables_equal_translated_ones():
    seen, classes = set(), {"safety": 0, "guarantee": 0, "rewritten": 0, "neither": 0}
    for sentence in SENTENCES:
        shape = _shape(sentence)
        if shape not in seen:
            seen.add(shape)
            classes[_check(*shape)] += 1
    for text in ("G(a0 -> F a1)", "G F a0", "F G a0", "(a0 U G a1) & X a2"):  # liveness
        classes[_check(text, 3)] += 1
    # the sample exercises both derivations (and the fallback) many times
    assert classes["safety"] > 100 and classes["guarantee"] >= 2, classes
    assert classes["rewritten"] >= 5 and classes["neither"] >= 4, classes


_ATOMS = st.sampled_from(["a0", "a1", "a2", "true", "false"])


def _formulas(depth: int):
    if depth == 0:
        return _ATOMS
    sub = _formulas(depth - 1)
    n = st.integers(1, 3)
    return st.one_of(
        _ATOMS,
        sub.map(lambda a: f"!({a})"),
        sub.map(lambda a: f"X({a})"),
        sub.map(lambda a: f"G({a})"),
        sub.map(lambda a: f"F({a})"),
        st.tuples(n, sub).map(lambda t: f"F[0..{t[0]}]({t[1]})"),
        st.tuples(n, sub).map(lambda t: f"G[0..{t[0]}]({t[1]})"),
        st.tuples(st.sampled_from(["&", "|", "->", "U", "R", "W", "M"]), sub, sub).map(
            lambda t: f"({t[1]}) {t[0]} ({t[2]})"))


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_formulas(3))
def test_derived_tables_equal_translated_ones_on_random_formulas(text):
    _check(text, 3)


def test_safety_complement_of_a_hand_checked_monitor():
    # g = a0 (bit 0 of the letter): no run on a first letter without a0, then anything
    bad = [[-1, 1], [1, 1]]
    raw = dfa.safety_complement(bad)
    # not g: runs on the prefixes starting without a0 (and the empty one); the monitor of g's
    # state 1 (every continuation satisfies g) has no run, "no run" became a looping state
    assert raw == [[2, -1], [-1, -1], [2, 2]]
    assert spot_monitors._bfs_tables(*dfa.minimize(raw))[1] == [[1, -1], [1, 1]]
    # g = G a0: every prefix can still be extended to violate it; the derived automaton has
    # two equivalent states that only the minimization merges
    raw = dfa.safety_complement([[-1, 0]])
    assert len(raw) == 2
    assert spot_monitors._bfs_tables(*dfa.minimize(raw))[1] == [[0, 0]]
    # g valid: not g has no run at all
    assert dfa.safety_complement([[0, 0]]) == [[-1, -1]]


def test_guarantee_bad_prefixes_of_hand_checked_automata():
    # h = F a (letter 1: a): 0 loops, 0 -a-> 1, 1 (target) loops; the monitor of G !a
    succ = [[0b01, 0b11], [0b10, 0b10]]
    assert dfa.guarantee_bad_prefixes(succ, 0, 2, 0b10, 100) == [[0, -1]]
    # h = X a | X !a (as an automaton: 0 -> {1, 3}, 1 -a-> 2, 3 -!a-> 2, 2 target): every
    # word satisfies h although the first set {1, 3} is not accepting: the empty prefix is
    # already good for h, so not h's monitor has no run
    succ = [[0b1010, 0b1010], [0, 0b100], [0b100, 0b100], [0b100, 0]]
    assert dfa.guarantee_bad_prefixes(succ, 0, 2, 0b100, 100) == [[-1, -1]]
    # h = a U b (bit 0: a, bit 1: b; 0 -a&!b-> 0, 0 -b-> 1, 1 target): not h's monitor has
    # no run once b held with a before
    succ = [[0, 0b01, 0b10, 0b10], [0b10] * 4]
    rows = dfa.guarantee_bad_prefixes(succ, 0, 4, 0b10, 100)
    # {0} on letter 0 (!a & !b) -> the empty set (a run that satisfies not h forever)
    assert rows[0][1] == 0 and rows[0][2] == -1 and rows[0][3] == -1
    assert rows[rows[0][0]] == [rows[0][0]] * 4
    # the limit on subsets
    assert dfa.guarantee_bad_prefixes(succ, 0, 4, 0b10, 1) is None
