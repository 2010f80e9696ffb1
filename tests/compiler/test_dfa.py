"""compiler/dfa.py: our subset construction and minimization give Spot's minimal monitors.

Differential: for sentences of FRET's trace vectors (and both polarities, as the LTL3 monitor
uses), the table built by ``compiler.spot_monitors._table_monitor`` equals the one from Spot's
``tgba_powerset`` + ``minimize_monitor``, after the same breadth-first renaming."""

from __future__ import annotations

import random

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

spot = pytest.importorskip("spot")

from fretc.compiler import automata, dfa, spot_monitors  # noqa: E402
from fretc.compiler.printers import to_spot  # noqa: E402
from fretc.compiler.semantics import formalize  # noqa: E402
from fretc.fretish import parse  # noqa: E402
from _shared import jsonl, params  # noqa: E402


def _sentences() -> list[str]:
    """The sentences of FRET's trace vectors (none without ../shared)."""
    texts = set()
    for row in jsonl("fretish/fret_trace_verdicts.jsonl"):
        texts.update(c["sentence"] for c in row["cases"])
    return sorted(texts)


def _spot_table(aut, n_atoms: int):
    det = aut if aut.is_deterministic() else spot.tgba_powerset(aut)
    m = spot.minimize_monitor(det)
    names = [f"a{i}" for i in range(n_atoms)]
    var = {x: m.register_ap(x) for x in names}
    width = 1 << n_atoms
    rows = []
    for s in range(m.num_states()):
        row = [-1] * width
        for e in m.out(s):
            for letter in spot_monitors._letters(e.cond, var, names, width):
                row[letter] = e.dst
        rows.append(row)
    return spot_monitors._bfs_tables(m.get_init_state_number(), rows)[1], bool(m.is_empty())


SAMPLE = params(lambda: random.Random(7).sample(_sentences(), 60)) + [
    "only after mm whenever cc the sw shall after 7 ticks satisfy rr",
    "in mm whenever cc the sw shall within 5 ticks satisfy rr",
    # 8 atoms, few letter classes (found slow by bench/fuzz.py)
    "only after mm whenever cc the sw shall after 3 ticks satisfy rr | p0 | p1 | p2 | p6 | p7"]


@pytest.mark.parametrize("text", SAMPLE)
def test_same_minimal_monitor_as_spot(text):
    shape, atoms = automata.canonical_shape(formalize(parse(text)).ft_inf)
    for negate in (False, True):
        f = spot.formula(to_spot(shape))
        aut = spot.translate(spot.formula.Not(f) if negate else f, "monitor", "low")
        ours = spot_monitors._table_monitor(aut, len(atoms))
        if ours is None:
            pytest.skip(f"more than {dfa.SUBSET_MAX_CLASSES} letter classes: Spot's construction")
        table, empty = _spot_table(aut, len(atoms))
        assert (ours["table"], ours["empty"]) == (table, empty), (text, negate)


def test_minimize_merges_equivalent_states_and_drops_the_sink():
    # states 1 and 2 behave alike (letter 0 -> themselves, letter 1 -> reject); 0 differs
    rows = [[1, 2], [1, -1], [2, -1]]
    init, out = dfa.minimize(rows)
    init, out = spot_monitors._bfs_tables(init, out)
    assert out == [[1, 1], [1, -1]]


def test_determinize_unions_successors_and_gives_up_beyond_the_limit():
    # NFA over one atom (letter 0: a false, 1: a true): 0 -!a-> {0}, 0 -a-> {0,1};
    # 1 -!a-> {} (reject), 1 -a-> {1}
    succ = [[0b01, 0b11], [0b00, 0b10]]
    # {0}: !a -> {0}, a -> {0,1}; {0,1}: !a -> {0}, a -> {0,1}
    assert dfa.determinize(succ, 0, 2, prune_after=None) == [[0, 1], [0, 1]]
    # 1 is simulated by 0 (0 reads every word 1 reads): {0,1} is pruned to {0}
    assert dfa.simulation_dominated(succ) == [0b10, 0]
    assert dfa.determinize(succ, 0, 2, prune_after=0) == [[0, 0]]
    # pruning starts only when the plain construction exceeds prune_after sets
    assert dfa.determinize(succ, 0, 2, prune_after=5) == [[0, 1], [0, 1]]
    # from {1} alone: !a rejects
    assert dfa.determinize(succ, 1, 2, prune_after=0) == [[-1, 0]]
    assert dfa.determinize(succ, 0, 2, limit=1, prune_after=None) is None


def test_mutually_simulating_states_keep_the_lower_number():
    # 0 and 1 read the same words (each loops to both on every letter): 1 is dropped
    succ = [[0b11], [0b11]]
    assert dfa.simulation_dominated(succ) == [0b10, 0]


def _canonical(rows):
    init, rows = dfa.minimize(rows)
    return spot_monitors._bfs_tables(init, rows)[1]


@st.composite
def _nfas(draw):
    n = draw(st.integers(1, 9))
    width = draw(st.sampled_from([1, 2, 4]))
    succ = [[draw(st.integers(0, (1 << n) - 1)) for _ in range(width)] for _ in range(n)]
    return succ, draw(st.integers(0, n - 1)), width


@settings(max_examples=300, deadline=None)
@given(_nfas())
def test_pruning_by_simulation_keeps_the_minimal_dfa(nfa):
    """Differential: the subset construction with and without simulation pruning gives the
    same minimal DFA on random NFAs (every state accepting, as in a monitor)."""
    succ, init, width = nfa
    assert _canonical(dfa.determinize(succ, init, width, prune_after=0)) == \
        _canonical(dfa.determinize(succ, init, width, prune_after=None))


@settings(max_examples=200, deadline=None)
@given(_nfas())
def test_simulation_is_sound_on_words(nfa):
    """s dominated by t: every word (up to length 4) with a run from s has one from t."""
    succ, _, width = nfa
    n = len(succ)

    def words_from(s):
        out, frontier = {()}, {((), 1 << s)}
        for _ in range(4):
            nxt = set()
            for w, states in frontier:
                for a in range(width):
                    r = 0
                    for q in range(n):
                        if states >> q & 1:
                            r |= succ[q][a]
                    if r:
                        nxt.add((w + (a,), r))
            out |= {w for w, _ in nxt}
            frontier = nxt
        return out

    dom = dfa.simulation_dominated(succ)
    for t in range(n):
        for s in range(n):
            if dom[t] >> s & 1:
                assert words_from(s) <= words_from(t), (s, t)


@st.composite
def _dfas(draw):
    n = draw(st.integers(1, 12))
    width = draw(st.sampled_from([1, 2, 3, 4]))
    return [[draw(st.integers(-1, n - 1)) for _ in range(width)] for _ in range(n)]


@settings(max_examples=300, deadline=None)
@given(_dfas())
def test_small_minimization_equals_the_numpy_one(rows):
    """Differential: the plain-Python refinement used on small tables gives the same
    quotient as the numpy one (same initial class, same rows in the same order)."""
    small = dfa._minimize_small(rows)
    saved = dfa.PYTHON_MINIMIZE_MAX
    dfa.PYTHON_MINIMIZE_MAX = -1  # force numpy
    try:
        big = dfa.minimize(rows)
    finally:
        dfa.PYTHON_MINIMIZE_MAX = saved
    assert spot_monitors._bfs_tables(*small) == spot_monitors._bfs_tables(*big)
    assert len(small[1]) == len(big[1])


_BOOL_ATOMS = st.sampled_from(["a0", "a1", "a2", "a3", "b", "true", "false"])
_BOOLS = st.recursive(_BOOL_ATOMS, lambda sub: st.one_of(
    sub.map(lambda a: f"!({a})"),
    st.tuples(st.sampled_from(["&", "|", "^", "->", "<->"]), sub, sub).map(
        lambda t: f"({t[1]}) {t[0]} ({t[2]})")), max_leaves=8)


@settings(max_examples=200, deadline=None)
@given(_BOOLS, st.integers(1, 4))
def test_letters_of_a_bdd_are_its_satisfying_letters(text, n_atoms):
    """Differential: spot_monitors._letters (depth-first restriction) against evaluating the
    Boolean formula on every letter; a condition that depends on an atom outside the letter
    (``b``) is satisfied by no letter unless it is true whatever ``b`` is."""
    d = spot.make_bdd_dict()
    aut = spot.make_twa_graph(d)
    names = [f"a{i}" for i in range(n_atoms)]
    var = {x: aut.register_ap(x) for x in names}
    aut.register_ap("b")
    f = spot.formula(text)
    cond = spot.formula_to_bdd(f, d, aut)
    width = 1 << n_atoms
    got = spot_monitors._letters(cond, var, names, width)
    assert got == sorted(got)
    assert got == _brute_letters(text, n_atoms)


def _brute_letters(text: str, n_atoms: int) -> list[int]:
    """The letters over a0..a{n_atoms-1} on which ``text`` is true whatever a{n_atoms}..a3
    and b are (Python evaluation of the formula)."""
    expr = (text.replace("!", " not ").replace("&", " and ").replace("|", " or ")
            .replace("<->", " == ").replace("->", " <= ").replace("^", " != ")
            .replace("true", "True").replace("false", "False"))
    out = []
    for letter in range(1 << n_atoms):
        ok = True
        for rest in range(1 << (5 - n_atoms)):
            env = {f"a{i}": bool(letter >> i & 1) for i in range(n_atoms)}
            extra = [f"a{i}" for i in range(n_atoms, 4)] + ["b"]
            env.update({x: bool(rest >> j & 1) for j, x in enumerate(extra)})
            if not eval(expr, {}, env):  # noqa: S307 - generated Boolean text
                ok = False
                break
        if ok:
            out.append(letter)
    return out
