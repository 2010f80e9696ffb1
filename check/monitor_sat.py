"""Satisfiability of safety requirements by symbolic model checking of their pt monitors
(``fretc check`` at deadlines of hundreds of ticks).

The queries of :mod:`fretc.check.analysis` are conjunctions of three kinds of formulas:
a requirement (it holds), a requirement's trigger (it fires in scope: non-vacuity) and a
negated requirement (it is violated: redundancy, witnesses). When every requirement's ft_inf
is monitored by its FRET pt formula (:func:`fretc.check.safety_game.pt_monitors_ft_inf`: ft_inf
holds on an infinite run iff pt holds at every tick), each kind is a property of the product
of the pt monitors (:class:`fretc.check.pt_monitor.Monitor`: one bit per ``Y``/``O``/``H``/``S``,
a counter of ``log2 w`` bits per ``O[0,w]``, one per deadline), so no bound is unrolled into states:

Design notes: ARCHITECTURE.md, `check/monitor_sat.py`."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from fretc.compiler import ir
from fretc.compiler.ir import Node

from fretc.check.budget import Budget, Meter
from fretc.check.buchi_game import _BuchiGame
from fretc.check.fixed_inputs import recurrence
from fretc.check.pt_monitor import Outside
from fretc.check.safety_game import Game, _varset, letter_name

__all__ = ["decide"]


def decide(safe: Sequence[Node], goals: Sequence[Node], invariant: Node,
           finite: bool, length: int | None = None, budget: Budget | None = None,
           liveness: Sequence[Node] = (), last: Sequence[Node] = ()) -> tuple[Any, Any]:
    """Is there a run on which every pt formula of ``safe`` holds at every tick and every
    pt formula of ``goals`` holds at some tick (module docstring)?

    ``invariant``: a propositional IR formula over the atoms, true at every tick (the
    numeric regions); ``finite``: a finite trace (FRET's ft) rather than an infinite run
    (ft_inf); ``length``: exactly that many ticks (finite only); ``budget``: the query's
    :class:`fretc.check.budget.Budget` (default: the defaults), past which
    :class:`fretc.check.budget.BudgetSpent` is raised. Returns ``(False, None)``, ``(True, None)`` (infinite)
    or ``(True, (letters, []))`` (finite: the trace's letters ``{atom name: bool}``, as
    :class:`fretc.check.solver.SpotWorker` gives words). ``liveness``: ft_inf formulas that hold
    too (infinite runs only), each by Spot's Büchi automaton in the product, its
    nondeterminism chosen like a letter (:mod:`fretc.check.buchi_game`); ``("outside", why)`` when
    Spot gives no generalized Büchi automaton. ``last``: pt formulas that hold at the last
    tick (finite only: FRET's pt formula at the last tick is its ft formula). Raises
    :class:`fretc.check.safety_game.Outside` for an atom the monitors cannot take.
    """
    meter = Meter(budget or Budget())
    if last and not finite:
        raise ValueError("last-tick formulas are read on finite traces only")
    # the first layer of the search: the goals have held, the last-tick formulas hold
    marks = [ir.O(g) for g in goals] + list(last)
    game: Game
    if liveness:
        if finite:
            raise ValueError("liveness formulas are read on infinite runs only")
        try:
            game = _BuchiGame(list(safe), list(liveness), [], ir.TRUE, invariant, extra=marks,
                              deterministic=False, meter=meter)
        except Outside as exc:
            return ("outside", str(exc))
    else:
        game = Game(list(safe), [], ir.TRUE, invariant, extra=marks, meter=meter)
    try:
        return _Search(game, meter).run(finite, length)
    finally:
        game.close()


class _Search:
    """The fixed points of :func:`decide` on one product monitor (``game``: a
    :class:`fretc.check.safety_game.Game` whose atoms are all the controller's)."""

    def __init__(self, game: Game, meter: Meter):
        self.g, self.b, self.meter = game, game.b, meter
        b = self.b
        self.ok = b.bdd_and(game.ok, game.ctl_ok)
        self.done = b.bddtrue
        for mark in game.extra:
            self.done = b.bdd_and(self.done, mark)
        self.letter_set = b.bdd_and(game.in_set, game.out_set)
        self.parts = _clusters(b, game.m.parts())
        meter.relation(b, self.ok, *(relation for relation, _nxt in self.parts))

    def _tick(self, *iterates) -> None:
        """Pay one iteration: the nodes of the sets it computed (:mod:`fretc.check.budget`)."""
        self.meter.nodes(self.b, *iterates)

    def successors_in(self, target, state=None):
        """BDD over (state, letter): the next state is in ``target``, by one relational
        product per part of the transition relation, each quantifying the next variables
        of its part (early quantification: Burch, Clarke, Long, "Symbolic model checking
        with partitioned transition relations", 1991). ``state``: a cube of every state
        bit, the parts restricted to it first (right only at that state; the witness
        traces, measured twice as fast)."""
        b = self.b
        f = self.g._primed(target)
        for relation, nxt in self.parts:
            if state is not None:
                relation = b.bdd_restrict(relation, state)
            f = b.bdd_appex(relation, f, b.bddop_and, nxt)
        return f

    def pre(self, target, now=None):
        """States with a letter keeping every safe formula (and ``now``) whose next state
        is in ``target``."""
        b = self.b
        ok = self.ok if now is None else b.bdd_and(self.ok, now)
        return b.bdd_appex(ok, self.successors_in(target), b.bddop_and, self.letter_set)

    def live(self):
        """``Live``: the states from which the safe formulas can hold forever (and each
        acceptance set of the liveness formulas' automata be met infinitely often: the
        nested fixed point of Emerson and Lei, 1986)."""
        b = self.b
        z = b.bddtrue
        while True:
            nxt = b.bdd_and(z, self.pre(z))
            self._tick(nxt)
            if nxt == z:
                break
            z = nxt
        # from the safe states on (else each outer round removes one tick's worth of the
        # states that die later: measured quadratic in the bound)
        return recurrence(b, z, getattr(self.g, "acc", []), lambda acc, z: self.pre(z, acc),
                          lambda base, y: b.bdd_or(base, self.pre(y)), self._tick)

    def run(self, finite: bool, length: int | None):
        """The answer of :func:`decide`."""
        b, init = self.b, self.g.init
        live = b.bddtrue if finite else self.live()
        if b.bdd_and(init, live) == b.bddfalse:
            return (False, None)
        layers = [self.pre(live, self.done)]
        if length is not None:  # exactly ``length`` ticks: the layers are not merged
            for _ in range(length - 1):
                layers.append(self.pre(layers[-1]))
                self._tick(layers[-1])
            if b.bdd_and(init, layers[-1]) == b.bddfalse:
                return (False, None)
            return (True, (self._trace(layers, live, exact=True), []))
        reach = front = layers[0]
        while b.bdd_and(init, reach) == b.bddfalse:
            # the states first found at this step (a state whose successor was found
            # earlier was found then): measured 5 times faster than the pre of all of reach
            front = b.bdd_and(b.bdd_and(live, self.pre(front)), b.bdd_not(reach))
            self._tick(front)
            if front == b.bddfalse:
                return (False, None)
            reach = b.bdd_or(reach, front)
            layers.append(reach)
        return (True, (self._trace(layers, live, exact=False), []) if finite else None)

    def _trace(self, layers: list, live, exact: bool) -> list[dict]:
        """The letters of a run from the first state down the layers: each tick a letter
        whose next state is in the layer below (the last tick's: the goals all reached)."""
        b, g = self.b, self.g
        state, letters = g.init, []
        top = len(layers) - 1
        if not exact:  # the first layer holding the first state: a shortest trace
            top = next(k for k, layer in enumerate(layers)
                       if b.bdd_and(state, layer) != b.bddfalse)
        for k in range(top, -1, -1):
            want = self.done if k == 0 else b.bddtrue
            target = live if k == 0 else layers[k - 1]
            f = b.bdd_and(self.successors_in(target, state),
                          b.bdd_and(state, b.bdd_and(self.ok, want)))
            letter = b.bdd_satoneset(b.bdd_exist(f, g.cur_set), self.letter_set, b.bddfalse)
            letters.append(self._letter(letter))
            state = g.next_state(b.bdd_and(state, letter))
        return letters

    def _letter(self, cube) -> dict:
        b, g = self.b, self.g
        return {letter_name(a): b.bdd_and(cube, b.bdd_ithvar(g.m.atom_var[a])) != b.bddfalse
                for a in g.atoms}


#: a part of the transition relation grows by the next one-bit state's relation while its
#: BDD stays under this many nodes (measured on bench/bench_check.py's 1000-tick sets)
PART_NODES = 3000


def _clusters(b, groups: list[list]) -> list[tuple]:
    """The transition relation in parts ``(relation, its next variables)``: one per
    counter, the one-bit states' merged in order while under :data:`PART_NODES` nodes
    (``groups``: :meth:`fretc.check.pt_monitor.Monitor.parts`)."""
    out: list[list] = []
    for group in groups:
        relation = b.bddtrue
        for _cur, nxt, _init, fn in group:
            relation = b.bdd_and(relation, b.bdd_biimp(b.bdd_ithvar(nxt), fn))
        nxt = [bit[1] for bit in group]
        if len(group) == 1 and out and out[-1][2]:
            merged = b.bdd_and(out[-1][0], relation)
            if b.bdd_nodecount(merged) <= PART_NODES:
                out[-1] = [merged, out[-1][1] + nxt, True]
                continue
        out.append([relation, nxt, len(group) == 1])
    return [(relation, _varset(b, nxt)) for relation, nxt, _single in out]
