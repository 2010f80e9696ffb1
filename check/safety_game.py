"""Realizability of safety requirements by a symbolic safety game (``fretc check``).

Design notes: ARCHITECTURE.md, `check/safety_game.py`."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Any, TYPE_CHECKING

from fretc.compiler import ir
from fretc.compiler.ir import Node
from fretc.compiler.printers import mangle, to_smv

from fretc.check.budget import Budget, BudgetSpent, Meter
from fretc.check.fixed_inputs import keep_forever, post, prefix_search
from fretc.check.numeric_abstraction import simple_comparison
from fretc.check.pt_monitor import Monitor, NoRoom, Outside, deadline_uses, state_bits

if TYPE_CHECKING:
    from fretc.compiler.semantics import Formalization

__all__ = ["is_safety", "pt_monitors_ft_inf", "Outside", "solve_game", "game_atoms", "letter_name",
           "Game", "Witness", "bdd_dict", "new_bdd_dict"]

#: fixed-input-sequence search: sets of states visited before giving up
SEARCH_BUDGET = 4000
#: more input letters than this (2^10) and no fixed sequence is searched for
MAX_LETTERS = 1024


# --------------------------------------------------------------------------- fragment
def is_safety(n: Node, positive: bool = True) -> bool:
    """Is ``n`` (an ft_inf IR formula, read with polarity ``positive``) in the syntactic
    safety fragment (Sistla, "Safety, liveness and fairness in temporal logic", 1994):
    negation normal form with only ``X``, ``G``, ``V`` (release), the weak until ``(p U q) |
    G p`` and bounded ``F``/``G`` over atoms? ``F`` and ``U`` are allowed under negation
    only."""
    op = n.op
    if not n.args or op in ("cmp", "call", "past", "future"):
        return True
    if op == "!":
        return is_safety(n.args[0], not positive)
    if op == "|" and positive and (weak := _weak_until(n)) is not None:
        p, q = weak
        return is_safety(p, positive) and is_safety(q, positive)
    if op in ("&", "|"):
        return all(is_safety(a, positive) for a in n.args)
    if op == "->":
        return is_safety(n.args[0], not positive) and is_safety(n.args[1], positive)
    if op in ("<->", "xor"):
        return all(is_safety(a, p) for a in n.args for p in (True, False))
    if op == "X" or (op in ("F", "G") and n.hi is not None):
        return is_safety(n.args[0], positive)
    if op in ("G", "V"):
        return positive and all(is_safety(a, positive) for a in n.args)
    if op in ("F", "U"):
        return (not positive) and all(is_safety(a, positive) for a in n.args)
    return False


def _weak_until(n: Node) -> tuple[Node, Node] | None:
    """``(p, q)`` of ``(p U q) | G p`` (either order): the weak until ``p W q``, a safety
    property when ``p`` and ``q`` are (FRET writes its ``after`` scopes so); else None."""
    if len(n.args) != 2:
        return None
    for u, g in (n.args, n.args[::-1]):
        if u.op == "U" and g.op == "G" and g.hi is None and g.args[0] == u.args[0]:
            return u.args[0], u.args[1]
    return None


def pt_monitors_ft_inf(formalization: Formalization) -> bool:
    """Does FRET's pt formula of ``formalization`` (a :class:`fretc.compiler.semantics.
    Formalization`) monitor its ft_inf formula: ft_inf holds on an infinite run iff pt holds
    at every tick? True when ft_inf is syntactically safe (:func:`is_safety`), except for the
    ``finally`` timing ("at the last timepoint"): its pt formula reads the last tick of a
    finite trace while its ft_inf formula, with no last tick, holds on every infinite run.
    Checked on random lassos for every template key (tests/check/test_monitor_sat.py)."""
    f = formalization
    return (f.pt is not None and f.key.split(",")[2:3] != ["finally"]
            and is_safety(f.ft_inf))


def game_atoms(pts: Sequence[Node]) -> list[Node]:
    """The atoms of pt formulas, in first-seen order; raises :class:`Outside` for an atom
    the game cannot give a player (a function, a comparison of two variables, ``LAST``)."""
    out: list[Node] = []
    for f in pts:
        for n in ir.walk(f):
            if n.op == "ap" or (n.op == "cmp" and simple_comparison(n) is not None):
                if n not in out:
                    out.append(n)
            elif n.op in ("cmp", "call", "past", "future", "LAST"):
                raise Outside(f"the atom {to_smv(n)} is neither a boolean variable nor a "
                              "comparison of one variable with a constant")
    return out


def letter_name(atom: Node) -> str:
    """An atom's key in a letter, as Spot's words name it (:mod:`fretc.check.solver`) and every
    solver of ``fretc check`` gives it: the mangled name of a boolean variable, the
    FRET/SMV text of any other atom."""
    return mangle(atom.name) if atom.op == "ap" else to_smv(atom)


def _buddy():
    import spot  # noqa: F401  lazy: Spot initializes BuDDy
    import buddy

    return buddy


# --------------------------------------------------------------------------- the game
_DICT: list = []


def bdd_dict() -> Any:  # a spot.bdd_dict
    """The Spot BDD dictionary of the games and the automata they read (so their BDD
    variables live in one BuDDy space), the same until :func:`new_bdd_dict`."""
    import spot  # lazy: Spot (and its BuDDy) in the query worker process only

    if not _DICT:
        _DICT.append(spot.make_bdd_dict())
    return _DICT[0]


def new_bdd_dict() -> None:
    """Make the games from here on in a new BDD dictionary (:func:`bdd_dict`), numbered from
    nothing: :mod:`fretc.check.solver` calls it before each game query, so no variable an
    earlier query or other work of the process left registered changes the numbering (the
    answer). A game made before keeps its own."""
    _DICT.clear()


class Game:
    """The safety game of a set of pt formulas (module docstring). ``inputs``: FRET
    variable names of the environment; ``env_inv``/``ctl_inv``: propositional IR formulas
    over the atoms (the numeric consistency of inputs / outputs); ``extra``: more pt
    formulas monitored beside (their values in ``self.extra``), not required to hold;
    ``atoms_of``: more formulas whose atoms the players set (not monitored here);
    ``reserve``: state bits kept free for more monitors (:mod:`fretc.check.buchi_game`), whose
    bits are added with ``self.m`` and made part of the relations by :meth:`relations`;
    ``meter``: the query's work (:mod:`fretc.check.budget`; default budgets when None): the state
    variables are checked against its memory budget before they are made
    (:class:`fretc.check.budget.BudgetSpent`), and each iteration of :meth:`solve` is paid."""

    def __init__(self, pts: Sequence[Node], inputs: Sequence[str], env_inv: Node,
                 ctl_inv: Node, extra: Sequence[Node] = (), atoms_of: Sequence[Node] = (),
                 reserve: int = 0, meter: Meter | None = None):
        import spot  # lazy: Spot (and its BuDDy) in the query worker process only

        self.meter = meter if meter is not None else Meter(Budget())
        self.atoms = game_atoms(list(pts) + list(extra) + [env_inv, ctl_inv, *atoms_of])
        b = self.b = _buddy()
        # the deadlines as counters first (a few bits each); a deadline that must be its
        # delay line after all (NoRoom) gets every bit it may need, in a second build
        for counted in (frozenset(deadline_uses([*pts, *extra])), frozenset()):
            seen: set = set()
            counts = [state_bits(f, seen, counted) for f in [*pts, *extra]]
            other = sum(o for _d, o in counts) + 1 + reserve
            delay = sum(d for d, _o in counts)
            nvars = len(self.atoms) + 2 * (other + delay) + 2
            self.meter.variables(nvars, "the monitors' state, atoms and delay lines")
            self.dict = bdd_dict()
            self.owner = spot.make_twa_graph(self.dict)
            first = self.dict.register_anonymous_variables(nvars, self.owner)
            m = self.m = Monitor(b, first, self.atoms, set(inputs), other,
                                 delay if counted else None)
            try:
                m.plan([*pts, *extra])
                self.ok = b.bddtrue
                for f in pts:
                    self.ok = b.bdd_and(self.ok, m.value(f))
                self.env_ok, self.ctl_ok = m.value(env_inv), m.value(ctl_inv)
                self.extra = [m.value(f) for f in extra]  # encoded with their state bits
                break
            except NoRoom:
                self.m = self.ok = None  # type: ignore[assignment]  # planned again below
                self.dict.unregister_all_my_variables(self.owner)
        self.in_set = _varset(b, m.in_vars)
        self.out_set = _varset(b, m.out_vars)
        self.layers: list = []
        self.acc: list = []  # no acceptance sets: a safety game (check.fixed_inputs)
        self._step = None
        self.relations()
        self.letter_vars = b.bdd_and(b.bdd_and(self.nxt_set, self.out_set), self.in_set)

    def relations(self) -> None:
        """The first state and the state-variable sets of ``self.m``'s bits, the transition
        relation dropped (again after bits are added)."""
        b, m = self.b, self.m
        self._trans, self.init = None, b.bddtrue
        for cur, _nxt, init, _fn in m.bits:
            self.init = b.bdd_and(self.init, b.bdd_ithvar(cur) if init
                                  else b.bdd_nithvar(cur))
        self.cur_set = _varset(b, [x[0] for x in m.bits])
        self.same = b.bddtrue
        for cur, nxt, _init, _fn in reversed(m.bits):
            self.same = b.bdd_and(self.same, b.bdd_biimp(b.bdd_ithvar(cur), b.bdd_ithvar(nxt)))
        self.nxt_set = _varset(b, [x[1] for x in m.bits])

    def close(self) -> None:
        """Drop the BDDs and give their variables back to Spot's allocator."""
        self.layers = []
        self.m = self.ok = self.env_ok = self.ctl_ok = self._trans = self.init = None  # type: ignore[assignment]  # closed
        self.extra, self.same, self._step = [], None, None
        self.dict.unregister_all_my_variables(self.owner)

    @property
    def trans(self) -> Any:  # a BDD
        """The transition relation, ``next <-> next-value`` for every state bit, built
        when first asked (:mod:`fretc.check.monitor_sat` steps through it in parts instead)."""
        if self._trans is None:
            b, self._trans = self.b, self.b.bddtrue
            for _cur, nxt, _init, fn in self.m.bits:
                self._trans = b.bdd_and(self._trans, b.bdd_biimp(b.bdd_ithvar(nxt), fn))
        return self._trans

    @property
    def step(self) -> Any:  # a BDD
        """The moves that keep every requirement: ``ok & ctl_ok & trans`` over (state,
        letter, next state), built when first asked (the satisfiability fixed points of
        :mod:`fretc.check.monitor_sat` step through the relation in parts instead)."""
        if self._step is None:
            b = self.b
            self._step = b.bdd_and(b.bdd_and(self.ok, self.ctl_ok), self.trans)
        return self._step

    def _primed(self, f):
        """``f`` over the state bits' next variables: a relational product with ``cur ==
        next`` (BuDDy's Python binding has no variable pairs for ``bdd_replace``; measured
        over a hundred times faster than composing bit by bit)."""
        return self.b.bdd_appex(self.same, f, self.b.bddop_and, self.cur_set)

    def _unprimed(self, f):
        """``f`` over the state bits' current variables (:meth:`_primed` the other way)."""
        return self.b.bdd_appex(self.same, f, self.b.bddop_and, self.nxt_set)

    def successors_in(self, target: Any) -> Any:  # BDDs
        """BDD over (state, inputs, outputs): the next state is in ``target``
        (``target`` with each state bit replaced by its next-value function: renamed to
        its next variable first, so the substitution is simultaneous)."""
        b = self.b
        used = _support(b, target)
        bits = [x for x in self.m.bits if x[0] in used]
        f = target
        for cur, nxt, _init, _fn in bits:
            f = b.bdd_compose(f, b.bdd_ithvar(nxt), cur)
        for _cur, nxt, _init, fn in bits:
            f = b.bdd_compose(f, fn, nxt)
        return f

    def pre(self, lose: Any) -> Any:  # BDDs
        """States from which the environment forces a loss now or a move into ``lose``."""
        b = self.b
        bad = b.bdd_or(b.bdd_not(self.ok), self.successors_in(lose))
        every_out = b.bdd_forall(b.bdd_imp(self.ctl_ok, bad), self.out_set)
        return b.bdd_exist(b.bdd_and(self.env_ok, every_out), self.in_set)

    def solve(self) -> bool:
        """Compute the layers of ``Lose`` (stopping once the initial state is in it);
        True when the controller wins (realizable). Raises
        :class:`fretc.check.budget.BudgetSpent` past the meter's work budget."""
        b = self.b
        self.meter.relation(b, self.ok, *(fn for _c, _n, _i, fn in self.m.bits))
        lose = b.bddfalse
        while True:
            nxt = b.bdd_or(lose, self.pre(lose))
            self.meter.nodes(b, nxt)
            if nxt == lose:
                return True
            lose = nxt
            self.layers.append(lose)
            if b.bdd_and(self.init, lose) != b.bddfalse:
                return False

    def next_state(self, here: Any) -> Any:  # BDDs
        """The state after ``here`` (a cube of every state bit and atom), as a cube of the
        state bits."""
        b, out = self.b, self.b.bddtrue
        for cur, _nxt, _init, fn in self.m.bits:
            on = b.bdd_and(here, fn) != b.bddfalse
            out = b.bdd_and(out, b.bdd_ithvar(cur) if on else b.bdd_nithvar(cur))
        return out

    def strategy_size(self) -> dict:
        """The controller the game gives: memory = the monitors' state bits; each tick it
        picks outputs that keep the requirements and the next state in the winning region
        (the complement of ``Lose``, a BDD of ``winning_region_bdd_nodes`` nodes)."""
        b = self.b
        win = b.bdd_not(self.layers[-1]) if self.layers else b.bddtrue
        return {"method": "safety game", "state_bits": len(self.m.bits),
                "winning_region_bdd_nodes": b.bdd_nodecount(win),
                "iterations": len(self.layers)}


def _support(b, f) -> set[int]:
    """The variables ``f`` depends on."""
    cube, out = b.bdd_support(f), set()
    while cube != b.bddtrue:
        out.add(b.bdd_var(cube))
        cube = b.bdd_high(cube)
    return out


def _varset(b, variables: Sequence[int]):
    out = b.bddtrue
    for v in variables:
        out = b.bdd_and(out, b.bdd_ithvar(v))
    return out


# --------------------------------------------------------------------------- the environment
class Witness:
    """A fixed input sequence that defeats every controller, and a controller's best
    effort along it (module docstring)."""

    def __init__(self, game: Game):
        self.g, self.b = game, game.b
        m = game.m
        self.in_atoms = [a for a in game.atoms if m.atom_var[a] in m.in_vars]
        self.out_atoms = [a for a in game.atoms if m.atom_var[a] in m.out_vars]
        self.all_set = game.b.bdd_and(game.b.bdd_and(game.cur_set, game.in_set),
                                      game.out_set)

    def _cubes(self, atoms: list[Node], allowed, limit: int) -> list[tuple] | None:
        """Assignments of ``atoms`` allowed by ``allowed`` (a BDD over them), as
        ``(values, cube)``, at most ``limit`` (None when there are more)."""
        b, var = self.b, self.g.m.atom_var
        if 2 ** len(atoms) > limit:
            return None
        out = []
        for values in itertools.product((False, True), repeat=len(atoms)):
            cube = b.bddtrue
            for a, v in zip(atoms, values):
                cube = b.bdd_and(cube, b.bdd_ithvar(var[a]) if v else b.bdd_nithvar(var[a]))
            if b.bdd_and(cube, allowed) != b.bddfalse:
                out.append((values, cube))
        return out

    def rank(self, states: Any) -> int:  # a BDD
        """Fewest ticks in which the environment forces a loss from every state of
        ``states`` (``len(layers)`` when some state is not known to lose)."""
        b, layers = self.b, self.g.layers
        lo, hi = 0, len(layers)
        while lo < hi:
            mid = (lo + hi) // 2
            if b.bdd_and(states, b.bdd_not(layers[mid])) == b.bddfalse:
                hi = mid
            else:
                lo = mid + 1
        return lo

    def post(self, states: Any, cube: Any) -> Any:  # BDDs
        """The states the monitors can be in after one tick with inputs ``cube``, over
        every output that keeps every requirement."""
        b, g = self.b, self.g
        now = b.bdd_and(b.bdd_and(states, cube), b.bdd_and(g.ctl_ok, g.ok))
        return g._unprimed(b.bdd_appex(now, g.trans, b.bddop_and, self.all_set))

    def search(self, budget: Budget) -> tuple[list | None, str]:
        """Best-first search (by rank) over the sets of states: the input letters of a
        prefix after which no output sequence keeps the requirements, or None and why.
        Within :data:`SEARCH_BUDGET` sets and a quarter of the work ``budget``; past them, a
        prefix then one input letter repeated (:mod:`fretc.check.fixed_inputs`), within another
        quarter."""
        import heapq

        letters = self._cubes(self.in_atoms, self.g.env_ok, MAX_LETTERS)
        if letters is None:
            return None, (f"no fixed input sequence searched: {len(self.in_atoms)} input "
                          "atoms are too many letters")
        meter = Meter(budget, 0.25)
        meter.relation(self.b, self.g.trans)
        start = self.g.init
        # (rank, length, count, states BDD, letters)
        heap: list[tuple[Any, int, int, Any, tuple[int, ...]]] = [(self.rank(start), 0, 0, start, ())]
        seen = {start.id()}
        count = 0
        try:
            while heap:
                if count >= SEARCH_BUDGET:
                    break
                _r, _n, _c, states, seq = heapq.heappop(heap)
                for k, (_values, cube) in enumerate(letters):
                    nxt = self.post(states, cube)
                    meter.nodes(self.b, nxt)
                    if nxt == self.b.bddfalse:
                        return [letters[i][0] for i in seq + (k,)], ""
                    if nxt.id() not in seen:
                        seen.add(nxt.id())
                        count += 1
                        heapq.heappush(heap, (self.rank(nxt), len(seq) + 1, count, nxt,
                                              seq + (k,)))
            else:
                return None, ("no fixed input sequence defeats every controller (every one "
                              "has a matching output sequence): the environment must react "
                              "to the outputs")
        except BudgetSpent:
            pass
        found = self._one_letter_cycle(letters, Meter(budget, 0.25))
        if found is not None:
            return found, ""
        return None, ("no fixed input sequence found within the search budget "
                      f"({count} sets of monitor states, then a prefix and one input "
                      "repeated): the environment may have to react to the outputs")

    def _one_letter_cycle(self, letters: list, meter: Meter) -> list | None:
        """A prefix, then one input letter repeated until no output sequence keeps the
        requirements (:func:`fretc.check.fixed_inputs.prefix_search`), as input letters; None
        when none is found within ``meter``'s budget."""
        meter.relation(self.b, self.g.step)
        try:
            keeps = [keep_forever(self.g, c, meter) for _v, c in letters]
            found = prefix_search(self.g, letters, keeps, meter)
            if found is None:
                return None
            seq, (c,) = found
            states = self.g.init
            for k in seq:
                states = post(self.g, states, letters[k][1])
            while states != self.b.bddfalse:  # outside keep(c): empty after finitely many
                states = post(self.g, states, letters[c][1])
                meter.nodes(self.b, states)
                seq = seq + [c]
        except BudgetSpent:
            return None
        return [letters[i][0] for i in seq]

    def play(self, inputs: list[tuple]) -> list[dict]:
        """A controller's best effort along ``inputs`` (letters of :meth:`search`): each
        tick the outputs that keep every requirement and reach the state of highest rank
        (any allowed outputs once none keeps them). Rows ``{atom name: bool}``."""
        b, g = self.b, self.g
        var = g.m.atom_var
        state, rows = g.init, []
        for values in inputs:
            cube = b.bddtrue
            for a, v in zip(self.in_atoms, values):
                cube = b.bdd_and(cube, b.bdd_ithvar(var[a]) if v else b.bdd_nithvar(var[a]))
            here = b.bdd_and(state, cube)
            keep = b.bdd_exist(b.bdd_and(here, b.bdd_and(g.ctl_ok, g.ok)), g.cur_set)
            keep = b.bdd_exist(keep, g.in_set)
            if keep == b.bddfalse:
                keep = g.ctl_ok
            best = None
            for values_o, cube_o in self._cubes(self.out_atoms, keep, 256) or []:
                nxt = self.g.next_state(b.bdd_and(here, cube_o))
                r = self.rank(nxt)
                if best is None or r > best[0]:
                    best = (r, values_o, nxt)
            if best is None:  # too many output letters: any that keeps the requirements
                one = b.bdd_satoneset(keep, g.out_set, b.bddfalse)
                values_o = tuple(b.bdd_and(one, b.bdd_ithvar(var[a])) != b.bddfalse
                                 for a in self.out_atoms)
                best = (0, values_o, self.g.next_state(b.bdd_and(here, one)))
            row = {letter_name(a): v for a, v in zip(self.in_atoms, values)}
            row.update({letter_name(a): v for a, v in zip(self.out_atoms, best[1])})
            rows.append(row)
            state = best[2]
        return rows


def solve_game(pts: Sequence[Node], inputs: Sequence[str], env_inv: Node, ctl_inv: Node,
               budget: Budget | None = None) -> dict:
    """Decide the safety game of the pt formulas ``pts`` (module docstring).

    ``inputs``: the environment's FRET variables (every other variable is the
    controller's); ``env_inv``/``ctl_inv``: propositional IR formulas over the comparisons
    (numeric consistency of inputs / outputs); ``budget``: the query's
    :class:`fretc.check.budget.Budget` (the game, then the search of a fixed input sequence
    within half of it more). Returns ``{"realizable": True, "strategy": {...}}`` or
    ``{"realizable": False, "inputs": [letters] | None, "run": [rows], "note": str}``
    (letters and rows: ``{atom name: bool}``). Raises :class:`Outside` for formulas the game
    does not handle, :class:`fretc.check.budget.BudgetSpent` past the budget.
    """
    budget = budget or Budget()
    game = Game(pts, inputs, env_inv, ctl_inv, meter=Meter(budget))
    try:
        if game.solve():
            return {"realizable": True, "strategy": game.strategy_size()}
        w = Witness(game)
        seq, note = w.search(budget)
        if seq is None:
            return {"realizable": False, "inputs": None, "run": [], "note": note,
                    "iterations": len(game.layers)}
        letters = [{letter_name(a): v for a, v in zip(w.in_atoms, values)}
                   for values in seq]
        return {"realizable": False, "inputs": letters, "run": w.play(seq), "note": "",
                "iterations": len(game.layers)}
    finally:
        game.close()
