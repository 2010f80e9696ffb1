"""Realizability of requirement sets with ``eventually`` responses by a symbolic Büchi game
(``fretc check``), beside the safety game of :mod:`fretc.check.safety_game`.

Design notes: ARCHITECTURE.md, `check/buchi_game.py`."""

from __future__ import annotations

from collections.abc import Sequence

from fretc.compiler.ir import Node
from fretc.compiler.printers import to_spot

from fretc.check.budget import Budget, Meter
from fretc.check.fixed_inputs import input_lasso, recurrence
from fretc.check.pt_monitor import Outside
from fretc.check.safety_game import MAX_LETTERS, Game, _varset, Witness, bdd_dict, letter_name

__all__ = ["solve_buchi_game"]


def _automaton(formula: Node, deterministic: bool = True):
    """Spot's complete, transition-based generalized Büchi automaton of an ft_inf formula,
    deterministic unless ``deterministic`` is False; raises :class:`Outside` when Spot gives
    no deterministic one."""
    import spot

    aut = spot.translate(to_spot(formula), "TGBA", "complete",
                         "deterministic" if deterministic else "small", dict=bdd_dict())
    if deterministic and not spot.is_deterministic(aut):
        # translate's "deterministic" is a preference: for some recurrence formulas it gives a
        # nondeterministic automaton although a deterministic Büchi one exists. Determinize
        # (a parity automaton) and let postprocess bring the acceptance down to Büchi.
        det = spot.postprocess(spot.tgba_determinize(aut), "TGBA", "deterministic",
                               "complete")
        if spot.is_deterministic(det):
            aut = det
    acc = aut.acc()
    if deterministic and not spot.is_deterministic(aut) or not (
            acc.is_t() or acc.is_generalized_buchi()):
        raise Outside(f"Spot gives no deterministic Büchi automaton for {to_spot(formula)} "
                      f"(acceptance {acc.get_acceptance()})")
    return aut


def _degree(aut) -> int:
    """Bits to choose among the edges leaving a state (0 for a deterministic automaton)."""
    import spot

    if spot.is_deterministic(aut):
        return 0
    most = max(sum(1 for _e in aut.out(s)) for s in range(aut.num_states()))
    return (most - 1).bit_length()


class _BuchiGame(Game):
    """The game of :func:`solve_buchi_game`: a :class:`fretc.check.safety_game.Game` over the pt
    formulas ``pts`` (and ``extra``, monitored beside) with the automata of the ``liveness``
    formulas in its state (``self.acc``: one BDD over (state, inputs, outputs) per
    acceptance set: this tick's edge is in it). Also the product of
    :mod:`fretc.check.monitor_sat` when a query has a requirement that is not safety."""

    def __init__(self, pts: Sequence[Node], liveness: Sequence[Node], inputs: Sequence[str],
                 env_inv: Node, ctl_inv: Node, extra: Sequence[Node] = (),
                 deterministic: bool = True, meter: Meter | None = None):
        self.automata = [_automaton(f, deterministic) for f in liveness]
        widths = [max(1, (a.num_states() - 1).bit_length()) for a in self.automata]
        choices = [_degree(a) for a in self.automata]
        super().__init__(pts, inputs, env_inv, ctl_inv, extra=extra, atoms_of=liveness,
                         reserve=sum(widths) + sum(choices), meter=meter)
        self.acc: list = []
        self.iterations = 0
        try:
            for aut, width, choice in zip(self.automata, widths, choices):
                self._encode(aut, width, choice)
        except BaseException:
            self.close()
            raise
        self.relations()
        self.out_set = _varset(self.b, self.m.out_vars)
        self._step = None
        self.step_vars = self.b.bdd_and(self.nxt_set, self.out_set)
        self.letter_vars = self.b.bdd_and(self.step_vars, self.in_set)

    def _encode(self, aut, width: int, choice: int) -> None:
        """Add the automaton's state bits (its state number in binary), their next-value
        functions, its edges' existence to ``ok`` and its acceptance sets to ``acc``. A
        nondeterministic automaton's edge is picked each tick by ``choice`` more variables
        set like outputs (the k-th edge leaving a state when they read k): exact for
        satisfiability, where every variable is existential."""
        b, m = self.b, self.m
        by_name = {letter_name(a): m.atom_var[a] for a in self.atoms}
        dct = bdd_dict()
        rename = [(dct.varnum(ap), by_name[ap.ap_name()]) for ap in aut.ap()]
        start = aut.get_init_state_number()
        bits = [m.add_bit(bool(start >> k & 1)) for k in range(width)]
        cubes = []
        for s in range(aut.num_states()):
            cube = b.bddtrue
            for k, (var, _bit) in enumerate(bits):
                cube = b.bdd_and(cube, var if s >> k & 1 else b.bdd_not(var))
            cubes.append(cube)
        nexts = [b.bddfalse] * width
        some = b.bddfalse
        accs = [b.bddfalse] * aut.num_sets()
        picks = [m.add_choice() for _k in range(choice)]
        rank: dict[int, int] = {}
        for e in aut.edges():
            cond = e.cond
            for ap_var, var in rename:
                cond = b.bdd_compose(cond, b.bdd_ithvar(var), ap_var)
            edge = b.bdd_and(cubes[e.src], cond)
            k = rank[e.src] = rank.get(e.src, -1) + 1
            for j, var in enumerate(picks):
                edge = b.bdd_and(edge, b.bdd_ithvar(var) if k >> j & 1 else b.bdd_nithvar(var))
            some = b.bdd_or(some, edge)
            for k in range(width):
                if e.dst >> k & 1:
                    nexts[k] = b.bdd_or(nexts[k], edge)
            for j in e.acc.sets():
                accs[j] = b.bdd_or(accs[j], edge)
        for (_var, bit), fn in zip(bits, nexts):
            bit[3] = fn
        self.ok = b.bdd_and(self.ok, some)
        self.acc += accs

    def _tick(self, *iterates) -> None:
        """Pay one iteration: the nodes of the sets it computed (:mod:`fretc.check.budget`)."""
        self.iterations += 1
        self.meter.nodes(self.b, *iterates)

    def cpre(self, target):
        """States where, whatever inputs the environment sets, the controller has outputs
        keeping every requirement with this tick's edge in ``target`` (a BDD over the state,
        the letter and the next state's bits, primed)."""
        b = self.b
        some_out = b.bdd_appex(self.step, target, b.bddop_and, self.step_vars)
        return b.bdd_forall(b.bdd_imp(self.env_ok, some_out), self.in_set)

    def winning(self):
        """``W`` of the module docstring; stops early once the first state is out of it.
        Raises :class:`fretc.check.budget.BudgetSpent` past the meter's budget."""
        b = self.b
        self.meter.relation(b, self.step)
        z = b.bddtrue
        while True:  # first the states where the controller keeps every requirement
            new = b.bdd_and(z, self.cpre(self._primed(z)))
            self._tick(new)
            z, stable = new, new == z
            if stable or b.bdd_and(self.init, z) == b.bddfalse:
                break
        # then the acceptance, from those states on (from every state, each outer round
        # would remove one tick's worth of the states that lose later: quadratic)
        if b.bdd_and(self.init, z) == b.bddfalse:
            return z
        return recurrence(
            b, z, self.acc, lambda acc, z: b.bdd_and(acc, self._primed(z)),
            lambda base, y: self.cpre(b.bdd_or(base, self._primed(y))), self._tick,
            lambda w: b.bdd_and(self.init, w) == b.bddfalse)


# --------------------------------------------------------------------------- the environment
def _lasso(game: _BuchiGame, meter: Meter) -> tuple[tuple | None, str]:
    """The shortest input lasso that defeats every controller
    (:func:`fretc.check.fixed_inputs.input_lasso`), as ``(prefix, cycle)`` of ``(letter, cube)``
    (letters ``{atom name: bool}``, cubes their BDDs); or None and why."""
    w = Witness(game)
    letters = w._cubes(w.in_atoms, game.env_ok, MAX_LETTERS)
    if letters is None:
        return None, (f"no fixed input sequence searched: {len(w.in_atoms)} input atoms are "
                      "too many letters")
    found, note = input_lasso(game, letters, meter)
    if found is None:
        return None, note
    named = [({letter_name(a): v for a, v in zip(w.in_atoms, letters[k][0])}, letters[k][1])
             for k in found[0] + found[1]]
    return (named[:len(found[0])], named[len(found[0]):]), ""


def _play(game: _BuchiGame, prefix: list, cycle: list, length: int) -> list[dict]:
    """A controller's best effort along the input lasso (cubes) unrolled to at least
    ``length`` ticks: each tick outputs that keep every requirement to the end of the
    unrolled run when any do, taking the automata's accepting edges when it can. Rows
    ``{atom name: bool}`` (inputs and outputs)."""
    b = game.b
    reps = max(2, -(-(length - len(prefix)) // len(cycle)))
    cubes = prefix + cycle * reps
    keep = [b.bddtrue]  # keep[k]: the states from which the last k ticks can be kept
    for cube in reversed(cubes):
        keep.append(b.bdd_appex(b.bdd_and(game.step, cube), game._primed(keep[-1]),
                                b.bddop_and, game.letter_vars))
    keep.reverse()
    accept = b.bddtrue
    for acc in game.acc:
        accept = b.bdd_and(accept, acc)
    state, rows, every = game.init, [], b.bdd_and(game.in_set, game.out_set)
    for t, cube in enumerate(cubes):
        here = b.bdd_and(state, cube)
        moves = b.bdd_appex(b.bdd_and(game.step, here), game._primed(keep[t + 1]),
                            b.bddop_and, game.nxt_set)
        if moves == b.bddfalse:  # none keeps the requirements: any the outputs allow
            moves = b.bdd_and(here, game.ctl_ok)
        best = b.bdd_and(moves, accept)
        letter = b.bdd_satoneset(b.bdd_exist(best if best != b.bddfalse else moves,
                                             game.cur_set), every, b.bddfalse)
        rows.append({letter_name(a): b.bdd_and(letter, b.bdd_ithvar(game.m.atom_var[a]))
                     != b.bddfalse for a in game.atoms})
        state = game.next_state(b.bdd_and(here, letter))
    return rows


def _longest_bound(formulas: Sequence[Node]) -> int:
    from fretc.compiler import ir

    return max([n.hi for f in formulas for n in ir.walk(f) if n.hi is not None] or [0])


def solve_buchi_game(pts: Sequence[Node], liveness: Sequence[Node], inputs: Sequence[str],
                     env_inv: Node, ctl_inv: Node, budget: Budget | None = None,
                     search: bool = False) -> dict:
    """Decide the generalized Büchi game of the safety requirements' pt formulas ``pts``
    and the ft_inf formulas ``liveness`` of the others (module docstring).

    ``inputs``: the environment's FRET variables; ``env_inv``/``ctl_inv``: propositional
    IR formulas over the comparisons (numeric consistency of inputs / outputs); ``budget``:
    the query's :class:`fretc.check.budget.Budget` (past it :class:`fretc.check.budget.BudgetSpent` is
    raised); ``search``: when the game is lost, search an input lasso that defeats every
    controller, within a quarter of the work budget more (:mod:`fretc.check.fixed_inputs`).
    Returns ``{"realizable": True, "strategy": {...}}`` (the strategy's size),
    ``{"realizable": False, "inputs": (prefix, cycle) | None, "note": why none}``, or
    ``{"outside": why}`` for formulas the game does not handle.
    """
    budget = budget or Budget()
    meter = Meter(budget)
    try:
        game = _BuchiGame(pts, liveness, inputs, env_inv, ctl_inv, meter=meter)
    except Outside as exc:
        return {"outside": str(exc)}
    try:
        win = game.winning()
        realizable = game.b.bdd_and(game.init, win) != game.b.bddfalse
        out: dict = {"realizable": realizable}
        if realizable:
            out["strategy"] = {"method": "Büchi game", "state_bits": len(game.m.bits),
                               "automaton_states": [a.num_states() for a in game.automata],
                               "winning_region_bdd_nodes": game.b.bdd_nodecount(win),
                               "iterations": game.iterations}
        elif search:
            lasso, out["note"] = _lasso(game, Meter(budget, 0.25))
            out["inputs"], out["run"] = None, []
            if lasso is not None:
                out["inputs"] = tuple([letter for letter, _c in part] for part in lasso)
                prefix, cycle = ([c for _l, c in part] for part in lasso)
                out["run"] = _play(game, prefix, cycle, 2 * _longest_bound([*pts, *liveness]) + 4)
        return out
    finally:
        game.automata, game.acc, game._step = [], [], None
        game.close()
