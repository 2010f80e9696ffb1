"""Fixed input sequences that defeat every controller of a lost game (``fretc check``'s
realizability), and the nested fixed point the games and the monitors share.

A game lost by the controller (:mod:`fretc.check.safety_game`, :mod:`fretc.check.buchi_game`) may be
lost only because the environment reacts to the outputs; when a *fixed* input sequence
defeats every controller, ``fretc check`` shows it: an input lasso (a prefix, then a cycle
repeated forever) along which no output sequence meets the set. For one lasso that is the
games' own fixed point with the inputs fixed and the outputs alone to choose
(:func:`defeats`). Two searches use it:

Design notes: ARCHITECTURE.md, `check/fixed_inputs.py`."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from typing import Any, Protocol

from fretc.check.budget import BudgetSpent, Meter

__all__ = ["recurrence", "keep_forever", "defeats", "post", "input_lasso", "prefix_search",
           "MAX_LASSO", "SEARCH_SETS"]

class Game(Protocol):
    """What the searches read of a game (:class:`fretc.check.safety_game.Game`, or
    :class:`fretc.check.buchi_game._BuchiGame` with its acceptance sets): BuDDy ``b``, the
    BDDs of the initial states ``init`` and the transition relation ``step`` (over the
    current state, the inputs, the outputs and the next state), the variable sets of the
    current state, inputs, outputs and of a tick's letter, the acceptance sets ``acc``
    (empty for a safety game), and the renamings between next and current state bits."""

    b: Any
    init: Any
    cur_set: Any
    in_set: Any
    out_set: Any
    letter_vars: Any
    acc: list

    @property
    def step(self) -> Any:
        """The BDD of the moves that keep every requirement (state, letter, next state)."""

    def _primed(self, bdd: Any) -> Any: ...

    def _unprimed(self, bdd: Any) -> Any: ...


#: the longest input lasso (prefix and cycle, in ticks) enumerated
MAX_LASSO = 4
#: sets of states a breadth-first prefix search visits at most
SEARCH_SETS = 4000


def recurrence(b: Any, z: Any, accs: Sequence, prepare: Callable[[Any, Any], Any],
               step: Callable[[Any, Any], Any], tick: Callable[[Any], Any],
               lost: Callable[[Any], Any] | None = None) -> Any:  # b: buddy; BDDs
    """The states of ``z`` (a BDD of states) from which each acceptance set of ``accs``
    can be met infinitely often: ``nu Z. AND_j mu Y. Z & step(prepare(acc_j, Z), Y)``
    (Emerson & Lei, LICS 1986; ``z`` itself when ``accs`` is empty). ``prepare(acc, Z)``:
    what one round of ``acc``'s least fixed point reads of ``Z`` (computed once per round);
    ``step(part, Y)``: the states that take an ``acc`` edge into ``Z`` or move into ``Y``,
    one step (the game's controllable or the monitors' existential predecessor);
    ``tick(iterate)``: called each iteration with the set it computed (raises
    :class:`fretc.check.budget.BudgetSpent` past the budget); ``lost(W)``: stop early with ``W``
    when true (the first state is out)."""
    while accs:
        new = z
        for acc in accs:
            part = prepare(acc, z)
            y = b.bddfalse
            while True:
                y_new = b.bdd_and(z, step(part, y))
                tick(y_new)
                if y_new == y:
                    break
                y = y_new
            new = b.bdd_and(new, y)
            if lost is not None and lost(new):
                return new
        if new == z:
            return z
        z = new
    return z


def defeats(game: Game, cubes: list, start: int, meter: Meter) -> bool:
    """Does the input lasso ``cubes[:start]`` then ``cubes[start:]`` forever (BDD cubes of
    the input atoms) defeat every controller of ``game`` (a :class:`fretc.check.safety_game.
    Game` or :class:`fretc.check.buchi_game._BuchiGame`): is there no output sequence along it
    that keeps every requirement with each acceptance set met infinitely often? The games'
    nested fixed point with the outputs alone to choose, one set of states per position."""
    return game.b.bdd_and(game.init, _keep(game, cubes, start, meter)[0]) == game.b.bddfalse


def keep_forever(game: Game, cube: Any, meter: Meter) -> Any:  # BDDs
    """The states from which, with the inputs ``cube`` at every tick, some output sequence
    keeps every requirement of ``game`` (and meets each acceptance set infinitely often)."""
    return _keep(game, [cube], 0, meter)[0]


def _keep(game, cubes: list, start: int, meter: Meter) -> list:
    b, n = game.b, len(cubes)
    succ = [i + 1 if i + 1 < n else start for i in range(n)]
    steps = [b.bdd_and(game.step, c) for c in cubes]

    def ex(i, target):
        return b.bdd_appex(steps[i], target, b.bddop_and, game.letter_vars)

    z = [b.bddtrue] * n
    while True:
        primed = [game._primed(x) for x in z]
        new = [b.bddtrue] * n
        for acc in game.acc or [b.bddtrue]:
            y = [b.bddfalse] * n
            while True:
                y_new = [ex(i, b.bdd_or(b.bdd_and(acc, primed[succ[i]]),
                                        game._primed(y[succ[i]]))) for i in range(n)]
                meter.nodes(b, *y_new)
                if y_new == y:
                    break
                y = y_new
            new = [b.bdd_and(x, v) for x, v in zip(new, y)]
        if new == z:
            return z
        z = new


def post(game: Game, states: Any, cube: Any) -> Any:  # BDDs
    """The states ``game``'s monitors can be in one tick after ``states`` with the inputs
    ``cube``, over every output that keeps every requirement."""
    b = game.b
    every = b.bdd_and(b.bdd_and(game.cur_set, game.in_set), game.out_set)
    return game._unprimed(b.bdd_appex(b.bdd_and(states, cube), game.step, b.bddop_and,
                                      every))


def input_lasso(game: Game, letters: list, meter: Meter) -> tuple[tuple | None, str]:
    """The shortest input lasso that defeats every controller (module docstring), as
    ``(prefix, cycle)`` of indices into ``letters`` (``(values, cube)`` pairs, the input
    letters the environment may set), up to :data:`MAX_LASSO` ticks, then longer prefixes
    with a one-letter cycle (:func:`prefix_search`); or None and why."""
    meter.relation(game.b, game.step)
    try:
        keeps = [keep_forever(game, c, meter) for _v, c in letters]
        for length in range(1, MAX_LASSO + 1):
            for start in range(length):
                for seq in itertools.product(range(len(letters)), repeat=length):
                    if start == length - 1:  # a one-letter cycle: keep() answers
                        states = game.init
                        for k in seq[:-1]:
                            states = post(game, states, letters[k][1])
                            meter.nodes(game.b, states)
                        win = game.b.bdd_and(states, keeps[seq[-1]]) != game.b.bddfalse
                    else:
                        win = not defeats(game, [letters[k][1] for k in seq], start, meter)
                    if not win:
                        return (list(seq[:start]), list(seq[start:])), ""
        found = prefix_search(game, letters, keeps, meter)
    except BudgetSpent:
        return None, ("no fixed input sequence found within the search budget: the "
                      "environment may have to react to the outputs")
    if found is not None:
        return found, ""
    return None, (f"no input lasso of up to {MAX_LASSO} ticks, and no longer prefix with a "
                  "one-tick cycle, defeats every controller: the environment may have to "
                  "react to the outputs")


def prefix_search(game: Game, letters: list, keeps: list, meter: Meter) -> tuple | None:
    """Breadth first over input prefixes: the first prefix after which every state the
    monitors can be in (:func:`post`) is outside ``keeps[c]`` (:func:`keep_forever` of
    letter ``c``) for some ``c``, as ``(prefix indices, [c])``; None when every set of
    states was visited. Raises :class:`fretc.check.budget.BudgetSpent` past the meter's budget
    or past :data:`SEARCH_SETS` sets."""
    b = game.b
    frontier: list[tuple[Any, tuple[int, ...]]] = [(game.init, ())]  # (states BDD, letters)
    seen = {game.init.id()}
    while frontier:
        if len(seen) > SEARCH_SETS:
            raise BudgetSpent(f"{SEARCH_SETS} sets of states searched")
        nxt_frontier: list[tuple[Any, tuple[int, ...]]] = []
        for states, seq in frontier:
            for c, keep in enumerate(keeps):
                if b.bdd_and(states, keep) == b.bddfalse:
                    return list(seq), [c]
            for k, (_values, cube) in enumerate(letters):
                nxt = post(game, states, cube)
                meter.nodes(b, nxt)
                if nxt.id() not in seen:
                    seen.add(nxt.id())
                    nxt_frontier.append((nxt, seq + (k,)))
        frontier = nxt_frontier
    return None
