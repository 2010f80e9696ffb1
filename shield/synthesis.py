"""The shield of one component of requirements, synthesized from ``fretc check``'s safety game.

Runs in ``fretc check``'s query worker (:class:`fretc.check.solver.SpotWorker`, the query
``("call", synthesize, args)``), so the game has the same BDD engine (BuDDy), work and memory
budgets and unknown answers as ``fretc check``'s realizability (:mod:`fretc.check.safety_game`).

Design notes: ARCHITECTURE.md, `shield/synthesis.py`."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from fretc.check.budget import Budget, Meter
from fretc.check.safety_game import Game, Witness, letter_name
from fretc.compiler.ir import Node

__all__ = ["synthesize"]


def synthesize(pts: Sequence[Node], inputs: Sequence[str], env_inv: Node, ctl_inv: Node,
               watch: Sequence[Node] = (), raw: Sequence[Node] = (), *,
               budget: Budget | None = None) -> dict[str, Any]:
    """The shield of the pt formulas ``pts`` (one per enforced requirement, in order):
    ``inputs`` the environment's FRET variables, ``env_inv``/``ctl_inv`` the propositional
    consistency of the input / output atoms (numbers, messages); ``watch`` sub-formulas of
    ``pts`` whose values are exported too (the assumptions' ``H A``,
    :mod:`fretc.shield.plan`); ``raw`` (with assumptions) the requirements' pt formulas
    without them, sub-formulas of ``pts``, which ``robust`` keeps too (module docstring).

    Returns ``{"realizable": True, "atoms": [(IR atom, is input)], "init": [bool],
    "nodes": [(var, lo, hi)], "safe": int, "next": [int], "keep": [int], "env_ok": int,
    "ctl_ok": int, "robust": int, "watch": [int], "stats": {...}}`` (variables numbered as :mod:`fretc.shield.machine` says) or
    ``{"realizable": False, "inputs": [letters] | None, "run": [rows], "note": str}``
    (letters and rows: ``{atom name: bool}``, as :func:`fretc.check.safety_game.solve_game`).

    Raises:
        fretc.check.budget.BudgetSpent: past the work or memory budget.
        fretc.check.pt_monitor.Outside: a formula the game does not take."""
    budget = budget or Budget()
    meter = Meter(budget)
    game = Game(pts, inputs, env_inv, ctl_inv, meter=meter)
    try:
        if not game.solve():
            w = Witness(game)
            seq, note = w.search(budget)
            if seq is None:
                return {"realizable": False, "inputs": None, "run": [], "note": note}
            letters = [{letter_name(a): v for a, v in zip(w.in_atoms, values)}
                       for values in seq]
            return {"realizable": False, "inputs": letters, "run": w.play(seq), "note": ""}
        b, m = game.b, game.m
        lose = game.layers[-1] if game.layers else b.bddfalse
        safe = _keep(game, game.ok, lose)
        keeps = []
        for f in pts:
            ok_j = m.value(f)
            keeps.append(_stay(game, ok_j, _attractor(game, ok_j, meter)))
        nexts = [bit[3] for bit in m.bits]
        ins = [a for a in game.atoms if m.atom_var[a] in m.in_vars]
        outs = [a for a in game.atoms if m.atom_var[a] in m.out_vars]
        varmap = {m.atom_var[a]: k for k, a in enumerate(ins + outs)}
        for k, bit in enumerate(m.bits):
            varmap[bit[0]] = len(ins) + len(outs) + k
        table = _Table(b, varmap)
        # safe first: its nodes are the table's first (the correction's shortest path reads
        # only them, :mod:`fretc.shield.runtime`)
        # the fallback's outputs: safe from every state of the winning region whatever
        # the (consistent) inputs (the outputs of a tick whose inputs cannot be read)
        robust = b.bdd_forall(b.bdd_imp(b.bdd_and(b.bdd_not(lose), game.env_ok), safe),
                              b.bdd_and(game.cur_set, game.in_set))
        for f in raw:  # (not relying on the assumptions: module docstring)
            ok_raw = m.value(f)
            lose_raw = _attractor(game, ok_raw, meter)
            robust = b.bdd_and(robust, b.bdd_forall(
                b.bdd_imp(b.bdd_and(b.bdd_not(lose_raw), game.env_ok),
                          _stay(game, ok_raw, lose_raw)),
                b.bdd_and(game.cur_set, game.in_set)))
        watched = [m.value(w) for w in watch]  # (planned: sub-formulas of the game's pts)
        bdds = [safe, *nexts, *keeps, game.env_ok, game.ctl_ok, robust, *watched]
        roots = [table.add(f) for f in bdds]
        _self_check(b, varmap, table, bdds, roots)
        roots, watch_roots = roots[:len(roots) - len(watched)], roots[len(roots) - len(watched):]
        return {"realizable": True,
                "atoms": [(a, True) for a in ins] + [(a, False) for a in outs],
                "init": [bool(bit[2]) for bit in m.bits], "nodes": table.nodes,
                "safe": roots[0], "next": roots[1:1 + len(nexts)],
                "keep": roots[1 + len(nexts):1 + len(nexts) + len(keeps)],
                "env_ok": roots[-3], "ctl_ok": roots[-2], "robust": roots[-1],
                "watch": watch_roots,
                "stats": {"state_bits": len(m.bits),
                          "winning_region_bdd_nodes": b.bdd_nodecount(b.bdd_not(lose)),
                          "iterations": len(game.layers),
                          "table_nodes": len(table.nodes)}}
    finally:
        game.close()


#: random full assignments at which every exported root is compared with BuDDy's BDD
SELF_CHECKS = 256


def _self_check(b: Any, varmap: dict[int, int], table: _Table, bdds: list[Any],
                roots: list[int]) -> None:
    """Compare each exported root with its BuDDy BDD at :data:`SELF_CHECKS` random full
    assignments (a fixed seed): the table every form runs is the BDD the game computed, or
    RuntimeError (a defect of fretc, never a shield that differs silently)."""
    import random

    from fretc.shield.machine import evaluate

    rnd = random.Random(0)
    order = sorted(varmap)
    for _ in range(SELF_CHECKS):
        bits = {v: rnd.random() < 0.5 for v in order}
        cube = b.bddtrue
        values = [0] * len(order)
        for v, on in bits.items():
            cube = b.bdd_and(cube, b.bdd_ithvar(v) if on else b.bdd_nithvar(v))
            values[varmap[v]] = int(on)
        for f, root in zip(bdds, roots):
            want = b.bdd_restrict(f, cube) == b.bddtrue
            if evaluate(table.nodes, root, values) != want:
                raise RuntimeError("the exported node table differs from the game's BDD")


def _attractor(game: Game, ok: Any, meter: Meter) -> Any:
    """``Lose`` of the game with ``ok`` as the requirements' truth (the least fixed point
    of :meth:`fretc.check.safety_game.Game.pre` with ``ok`` in place of the game's)."""
    b = game.b
    lose = b.bddfalse
    while True:
        bad = b.bdd_or(b.bdd_not(ok), game.successors_in(lose))
        every_out = b.bdd_forall(b.bdd_imp(game.ctl_ok, bad), game.out_set)
        nxt = b.bdd_or(lose, b.bdd_exist(b.bdd_and(game.env_ok, every_out), game.in_set))
        meter.nodes(b, nxt)
        if nxt == lose:
            return lose
        lose = nxt


def _keep(game: Game, ok: Any, lose: Any) -> Any:
    """The moves that keep ``ok`` now and the next state out of ``lose``, with consistent
    outputs."""
    return game.b.bdd_and(_stay(game, ok, lose), game.ctl_ok)


def _stay(game: Game, ok: Any, lose: Any) -> Any:
    """The moves that keep ``ok`` now and the next state out of ``lose``, whatever the
    outputs' consistency (``keep_j``: a requirement is a reason of an override only when
    the proposal breaks it, not when the proposal is no valuation the outputs can take)."""
    b = game.b
    return b.bdd_and(ok, b.bdd_not(game.successors_in(lose)))


class _Table:
    """BuDDy BDDs copied into one node table (:mod:`fretc.shield.machine`): children
    first, low before high, shared nodes once; ``varmap`` BuDDy variable -> table
    variable."""

    def __init__(self, b: Any, varmap: dict[int, int]):
        self.b, self.varmap = b, varmap
        self.nodes: list[tuple[int, int, int]] = [(-1, 0, 0), (-1, 1, 1)]
        self.index: dict[int, int] = {}

    def add(self, f: Any) -> int:
        """The table index of ``f`` (added with its children when new)."""
        b = self.b
        if f == b.bddfalse:
            return 0
        if f == b.bddtrue:
            return 1
        key = f.id()
        got = self.index.get(key)
        if got is not None:
            return got
        lo, hi = self.add(b.bdd_low(f)), self.add(b.bdd_high(f))
        var = b.bdd_var(f)
        if var not in self.varmap:
            raise RuntimeError(f"BDD variable {var} is neither an atom nor a state bit")
        self.nodes.append((self.varmap[var], lo, hi))
        self.index[key] = len(self.nodes) - 1
        return len(self.nodes) - 1
