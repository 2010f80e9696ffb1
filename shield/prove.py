"""``fretc shield --prove``: the closed loop proved with Spot, independently of the game.

The shield composed with *any* environment and *any* controller is a transition system:
from a state ``s`` (the monitors' bits), for every input letter ``i`` the environment may
give (``env_ok``: numbers consistent), the shield outputs some ``o`` with ``safe(s, i, o)``
(every safe ``o`` is possible: the controller may propose it; an unsafe proposal is mapped
to a safe one), and moves to ``next(s, i, o)``. :func:`prove_shield` builds that system
explicitly from the emitted node tables (the data every form runs), as a Spot automaton over
the atoms, and for each enforced requirement checks that its product with Spot's automaton
of the requirement's negated ft_inf formula (FRET's infinite-trace semantics, translated by
Spot, not by the game) is empty: no run of the closed loop violates it. It also checks that
the shield never blocks: every reachable state has a safe output for every consistent input.

The explicit system has at most :data:`MAX_STATES` states and each requirement's bounds at
most :data:`fretc.check.checker.SPOT_MAX_BOUND` ticks (Spot's translation grows
exponentially with them); past either the answer is unknown, and says so.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from fretc.check.checker import SPOT_MAX_BOUND
from fretc.check.smt import max_bound
from fretc.compiler import ir
from fretc.compiler.printers import to_spot
from fretc.shield.build import Shield
from fretc.shield.machine import Machine, evaluate

__all__ = ["Proof", "prove_shield", "closed_loop", "MAX_STATES", "MAX_LETTERS"]

#: the most states of one machine's closed loop that are enumerated
MAX_STATES = 200_000
#: the most letters (input and output atoms together: 2^n) enumerated per state
MAX_LETTERS = 1 << 14


@dataclass
class Proof:
    """The result: ``results`` requirement id -> ``"holds"`` / ``"violated"`` /
    ``"unknown"``, ``why`` id -> the reason of an unknown or a violating run (a lasso of
    letters), ``sizes`` per machine ``(states, edges, table nodes)``, ``blocking`` the
    states where the shield has no safe output (empty when it never blocks)."""

    results: dict[str, str] = field(default_factory=dict)
    why: dict[str, str] = field(default_factory=dict)
    sizes: list[tuple[str, int, int, int]] = field(default_factory=list)
    blocking: list[str] = field(default_factory=list)
    monitored: dict[str, str] = field(default_factory=dict)

    @property
    def holds(self) -> bool:
        """Every enforced requirement proved and no blocking state."""
        return not self.blocking and all(v == "holds" for v in self.results.values())

    def text(self) -> str:
        """The terminal report."""
        lines = ["proof of the closed loop (any environment, any controller, Spot):"]
        for ids, states, edges, nodes in self.sizes:
            lines.append(f"  {ids}: {states} states, {edges} edges; {nodes} BDD nodes")
        for rid, res in self.results.items():
            lines.append(f"  {rid}: {res}" + (f" ({self.why[rid]})" if rid in self.why else ""))
        for b in self.blocking:
            lines.append(f"  BLOCKS: {b}")
        for rid, why in self.monitored.items():
            lines.append(f"  {rid}: monitored only, not proved ({why})")
        lines.append("the shield satisfies every enforced requirement" if self.holds
                     else "NOT PROVED")
        return "\n".join(lines)


def closed_loop(m: Machine, limit: int = MAX_STATES
                ) -> tuple[dict[tuple[int, ...], dict[tuple[int, ...], list[tuple[int, ...]]]],
                           list[str]] | None:
    """The reachable closed loop of ``m``: state -> next state -> the letters (input atoms
    then output atoms, 0/1) of its edges; and the blocking states (described). None past
    ``limit`` states or :data:`MAX_LETTERS` letters."""
    n_in, n_out = len(m.inputs), len(m.outputs)
    if 1 << (n_in + n_out) > MAX_LETTERS:
        return None
    ins = list(itertools.product((0, 1), repeat=n_in))
    outs = list(itertools.product((0, 1), repeat=n_out))
    start = tuple(int(b) for b in m.init)
    graph: dict[tuple[int, ...], dict[tuple[int, ...], list[tuple[int, ...]]]] = {}
    todo, blocking = [start], []
    while todo:
        s = todo.pop()
        if s in graph:
            continue
        if len(graph) >= limit:
            return None
        edges: dict[tuple[int, ...], list[tuple[int, ...]]] = {}
        graph[s] = edges
        for i in ins:
            if not evaluate(m.nodes, m.env_ok, list(i) + [0] * n_out + list(s)):
                continue
            any_safe = False
            for o in outs:
                values = list(i + o + s)
                if evaluate(m.nodes, m.safe, values):
                    any_safe = True
                    nxt = tuple(int(evaluate(m.nodes, r, values)) for r in m.next)
                    edges.setdefault(nxt, []).append(i + o)
                    if nxt not in graph:
                        todo.append(nxt)
            if not any_safe:
                blocking.append(f"{', '.join(m.requirements)}: state {s}, inputs "
                                + ", ".join(f"{a.text}={v}" for a, v in zip(m.inputs, i)))
    return graph, blocking


def _automaton(m: Machine, graph: dict[tuple[int, ...], dict[tuple[int, ...],
                                                              list[tuple[int, ...]]]]) -> Any:
    """The closed loop as a Spot automaton (every run accepting) over the atoms' names."""
    import buddy
    import spot

    aut = spot.make_twa_graph(spot.make_bdd_dict())
    atoms = list(m.inputs) + list(m.outputs)
    var = [aut.register_ap(a.name) for a in atoms]
    aut.set_acceptance(0, spot.acc_code.t())
    aut.prop_state_acc(True)
    index = {s: k for k, s in enumerate(graph)}
    aut.new_states(len(index))
    aut.set_init_state(index[tuple(int(b) for b in m.init)])
    for s, edges in graph.items():
        for nxt, letters in edges.items():
            label = buddy.bddfalse
            for letter in letters:
                cube = buddy.bddtrue
                for v, bit in zip(var, letter):
                    cube = buddy.bdd_and(cube, buddy.bdd_ithvar(v) if bit
                                         else buddy.bdd_nithvar(v))
                label = buddy.bdd_or(label, cube)
            aut.new_edge(index[s], index[nxt], label)
    return aut


def prove_shield(shield: Shield, compiled: Sequence[Any]) -> Proof:
    """Prove each enforced requirement of ``shield`` on its closed loop (module docstring);
    ``compiled`` the requirements it was built from (their ft_inf formulas)."""
    import spot

    by_id = {c.id: c for c in compiled}
    proof = Proof(monitored=dict(shield.monitored))
    for m in shield.machines:
        ids = ", ".join(m.requirements)
        loop = closed_loop(m)
        if loop is None:
            for rid in m.requirements:
                proof.results[rid] = "unknown"
                proof.why[rid] = (f"the closed loop has more than {MAX_STATES} states or "
                                  f"2^{len(m.inputs) + len(m.outputs)} letters a state")
            continue
        graph, blocking = loop
        proof.blocking += blocking
        aut = _automaton(m, graph)
        proof.sizes.append((ids, aut.num_states(), aut.num_edges(), len(m.nodes)))
        for rid in m.requirements:
            phi = ir.fold_constants(by_id[rid].formalization.ft_inf)  # (as the game read it)
            if max_bound([phi]) > SPOT_MAX_BOUND:
                proof.results[rid] = "unknown"
                proof.why[rid] = (f"a bound of {max_bound([phi])} ticks; Spot is given up "
                                  f"to {SPOT_MAX_BOUND}")
                continue
            neg = spot.translate(spot.formula.Not(spot.formula(to_spot(phi))),
                                 dict=aut.get_dict())
            run = spot.product(aut, neg).accepting_word()
            if run is None:
                proof.results[rid] = "holds"
            else:
                proof.results[rid] = "violated"
                run.simplify()
                proof.why[rid] = f"a run of the closed loop violates it: {run}"
    return proof
