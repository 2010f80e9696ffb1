"""Past-time atoms inside future-time queries, by temporal testers
(:mod:`fretc.check.past_testers`): the finite traces ``fretc check``'s witnesses and ``fretc
testgen`` ask Spot for give a derived past atom (FRET's ``occurred``, ``persisted``, a latched
mode's since) the value of its expansion, so every trace found meets its query by FRET's
semantics (:func:`fretc.compiler.evaluate.ft_at`), and a query some short trace meets is
never answered "no trace". Before, Spot read the atom as a free proposition: on a latched
mode, testgen covered 3 of 41 obligations (now 39; the 2 left are unmeetable)."""

from __future__ import annotations

import itertools

from hypothesis import given, settings, strategies as st

from fretc.check.budget import Budget
from fretc.check.checker import Checker
from fretc.check.past_testers import MAX_WINDOW, with_testers
from fretc.check.solver import UNKNOWN, SpotWorker
from fretc.check.witness import finite_trace
from fretc.compiler import ir
from fretc.compiler.evaluate import ft_at
from fretc.compiler.ir import Node

_A, _B = ir.ap("a"), ir.ap("b")


def _pt(depth: int) -> st.SearchStrategy[Node]:
    """Random pt formulas over a and b: every past operator, bounded windows included, and
    a FRET stream by its state bit."""
    leaf = st.sampled_from([_A, _B, ir.FTP])
    if depth == 0:
        return leaf
    sub = _pt(depth - 1)
    bounds = st.tuples(st.integers(0, 2), st.integers(0, 2)).map(lambda x: (x[0], sum(x)))
    return st.one_of(
        leaf,
        sub.map(ir.not_),
        st.tuples(sub, sub).map(lambda x: ir.and_(*x)),
        st.tuples(sub, sub).map(lambda x: ir.or_(*x)),
        sub.map(ir.Y), sub.map(ir.Z), sub.map(ir.O), sub.map(ir.H),
        st.tuples(sub, sub).map(lambda x: ir.S(*x)),
        st.tuples(sub, sub).map(lambda x: Node("T", x)),
        st.tuples(sub, sub).map(lambda x: ir.stream("s", *x)),
        st.tuples(sub, bounds).map(lambda x: ir.O(x[0], *x[1])),
        st.tuples(sub, bounds).map(lambda x: ir.H(x[0], *x[1])))


def _shape(k: int, p: Node) -> Node:
    """An ft query around the past atom ``p`` (one of five shapes)."""
    return [ir.F(ir.and_(p, ir.not_(_A))), ir.G(ir.implies(_B, p)),
            ir.U(ir.not_(p), ir.and_(p, _B)), ir.F(ir.and_(ir.not_(p), ir.X(p))),
            ir.and_(ir.F(p), ir.F(ir.not_(p)))][k]


def _brute(query: Node, longest: int = 4) -> bool:
    """Whether some trace of 1 to ``longest`` ticks over a, b meets ``query``."""
    for n in range(1, longest + 1):
        for bits in itertools.product([False, True], repeat=2 * n):
            rows = [{"a": bits[2 * i], "b": bits[2 * i + 1]} for i in range(n)]
            if ft_at(query, rows):
                return True
    return False


@settings(max_examples=60, deadline=None)
@given(_pt(3), st.integers(0, 4))
def test_traces_found_meet_the_query_and_none_is_missed(expansion, shape):
    """A trace Spot finds for a query holding the past atom meets it when the atom is read
    as its expansion; when some trace of up to 4 ticks meets it, a trace is found."""
    p = Node("past", (expansion,), name=None)
    query = _shape(shape, p)
    with SpotWorker(Budget(), fork=False) as worker:
        got = finite_trace(Checker([], worker), [query], {"a": "bool", "b": "bool"})
    assert got != UNKNOWN
    if got:
        assert ft_at(query, got), (query, got)
    else:
        assert not _brute(query), query


def _at(k: int, f: Node) -> Node:
    for _ in range(k):
        f = ir.X(f)
    return f


@settings(max_examples=40, deadline=None)
@given(_pt(3), st.lists(st.tuples(st.booleans(), st.booleans()), min_size=1, max_size=4))
def test_the_testers_give_the_atom_its_value_at_every_tick(expansion, ticks):
    """On a trace pinned tick by tick (a, b and LAST at each position), the past atom takes
    at each tick exactly the value FRET's evaluator gives its expansion: the query asking
    the other value has no trace."""
    p = Node("past", (expansion,), name=None)
    rows = [{"a": a, "b": b} for a, b in ticks]
    pin = ir.TRUE
    for k, r in enumerate(rows):
        letter = ir.and_(_A if r["a"] else ir.not_(_A), _B if r["b"] else ir.not_(_B))
        pin = ir.and_(pin, _at(k, letter))
    pin = ir.and_(pin, _at(len(rows) - 1, ir.LAST))
    with SpotWorker(Budget(), fork=False) as worker:
        checker = Checker([], worker)
        for k in range(len(rows)):
            value = ft_at(p, rows, k)
            wrong = _at(k, ir.not_(p) if value else p)
            assert finite_trace(checker, [pin, wrong], {"a": "bool", "b": "bool"}) is None, \
                (expansion, rows, k, value)
            right = _at(k, p if value else ir.not_(p))
            assert finite_trace(checker, [pin, right], {"a": "bool", "b": "bool"}) == rows


def test_a_window_past_the_bound_stays_a_free_proposition():
    """``O[0, hi] a`` with a window wider than :data:`MAX_WINDOW` ticks: no testers, the
    atom unchanged (Spot reads it free, the judge confirms traces as before)."""
    p = Node("past", (ir.O(_A, 0, MAX_WINDOW + 5),), name="occurred")
    forms, axioms = with_testers([ir.F(p)])
    assert forms == [ir.F(p)] and axioms == []
    q = Node("past", (ir.Y(_A),), name="pre_a")
    forms, axioms = with_testers([ir.F(ir.and_(p, q))])
    assert len(axioms) == 1 and p in set(ir.walk(forms[0])) and q not in set(ir.walk(forms[0]))


def test_tester_names_do_not_take_a_formulas_atom():
    """A FRET variable named as a tester would be is not reused for one."""
    taken = ir.ap("fretc_tester_1")
    p = Node("past", (ir.Y(_A),), name="pre_a")
    forms, axioms = with_testers([ir.F(ir.and_(p, taken))])
    names = {ir.name_of(n) for f in forms + axioms for n in ir.walk(f) if n.op == "ap"}
    assert "fretc_tester_2" in names and taken in set(ir.walk(forms[0]))
