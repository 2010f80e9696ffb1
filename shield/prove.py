"""``fretc shield --prove``: the closed loop proved with Spot, independently of the game.

:func:`prove_shield` builds the shield composed with any environment and any controller as
an explicit Spot automaton over the atoms, from the emitted node tables, and for each
enforced requirement checks that its product with Spot's automaton of the negated ft_inf
formula is empty, and that the shield never blocks. Past :data:`MAX_STATES` states or
:data:`fretc.check.checker.SPOT_MAX_BOUND` ticks the answer is unknown, and says so. Under
assumptions (``--assume``) a requirement is proved under them, and a vacuous proof is "NOT
PROVED" (exit 1). The construction, past atoms, assumptions and bounded outputs in full:
ARCHITECTURE.md ("Proving the closed loop").
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from fretc.check.checker import SPOT_MAX_BOUND
from fretc.check.past_testers import with_testers
from fretc.check.smt import max_bound
from fretc.compiler import ir
from fretc.compiler.printers import to_smv, to_spot
from fretc.shield.build import Shield
from fretc.shield.machine import Machine

__all__ = ["Proof", "prove_shield", "closed_loop", "Loop", "MAX_STATES", "buddy_module"]

#: the most states of one machine's closed loop that are enumerated
MAX_STATES = 200_000


@dataclass
class Proof:
    """The result: ``results`` requirement id -> ``"holds"`` / ``"violated"`` /
    ``"vacuous"`` (module docstring) / ``"unknown"``, ``why`` id -> the reason of an unknown or a violating run (a lasso of
    letters), ``sizes`` per machine ``(states, edges, table nodes)``, ``blocking`` the
    states where the shield has no safe output (empty when it never blocks)."""

    results: dict[str, str] = field(default_factory=dict)
    why: dict[str, str] = field(default_factory=dict)
    sizes: list[tuple[str, int, int, int]] = field(default_factory=list)
    blocking: list[str] = field(default_factory=list)
    monitored: dict[str, str] = field(default_factory=dict)
    #: requirement id -> the assumptions it is proved under (none: any environment)
    under: dict[str, tuple[str, ...]] = field(default_factory=dict)
    #: what the proof assumes of the runtime's choice of numbers at each tick (outputs
    #: bounded by the inputs: :mod:`fretc.shield.runtime_bounds`), one line each
    choice: list[str] = field(default_factory=list)

    @property
    def holds(self) -> bool:
        """Every enforced requirement proved and no blocking state."""
        return not self.blocking and all(v == "holds" for v in self.results.values())

    def text(self) -> str:
        """The terminal report."""
        assumed = sorted({a for ids in self.under.values() for a in ids})
        lines = ["proof of the closed loop (" + ("any environment that keeps the assumptions "
                                                 + ", ".join(assumed) if assumed
                                                 else "any environment")
                 + ", any controller, Spot):"]
        for ids, states, edges, nodes in self.sizes:
            lines.append(f"  {ids}: {states} states, {edges} edges; {nodes} BDD nodes")
        for rid, res in self.results.items():
            under = (f" under {', '.join(self.under[rid])}"
                     if self.under.get(rid) and res == "holds" else "")
            lines.append(f"  {rid}: {res}{under}"
                         + (f" ({self.why[rid]})" if rid in self.why else ""))
        for b in self.blocking:
            lines.append(f"  BLOCKS: {b}")
        lines += [f"  assumes of the runtime's choice: {c}" for c in self.choice]
        for rid, why in self.monitored.items():
            lines.append(f"  {rid}: monitored only, not proved ({why})")
        lines.append(("the shield satisfies every enforced requirement"
                      + (" while the environment keeps its assumptions" if assumed else ""))
                     if self.holds else "NOT PROVED")
        return "\n".join(lines)


class Loop:
    """The reachable closed loop of a machine (:func:`closed_loop`): ``graph`` state ->
    next state -> the edge's label, a BDD (BuDDy's, in Spot's dictionary of ``owner``)
    over the atoms' variables ``var`` (input atoms, then output atoms); ``blocking`` the
    states with an input the environment may give and no safe output (described)."""

    def __init__(self, owner: Any, var: list[int], graph: dict[tuple[int, ...], dict[
            tuple[int, ...], Any]], blocking: list[str]):
        self.owner, self.var, self.graph, self.blocking = owner, var, graph, blocking


def buddy_module() -> Any:
    """BuDDy's Python module, as Spot loads it (``import buddy`` alone does not find it)."""
    import spot  # noqa: F401  (Spot puts BuDDy's binding where Python finds it)
    import buddy

    return buddy


def closed_loop(m: Machine, limit: int = MAX_STATES, assumed: bool = False) -> Loop | None:
    """The reachable closed loop of ``m`` (:class:`Loop`), computed symbolically: each
    state's edges are the node table's ``safe`` and ``env_ok`` with the state's bits fixed,
    as a BDD over the atoms, split by the next state's bits (no letter is enumerated).
    ``assumed``: only the moves with which the machine's assumptions of the environment
    still hold (the runs the guarantee is about: a run that breaks an assumption's pt
    formula breaks its ft_inf, :mod:`fretc.shield.plan`); the blocking states are then
    those with an input that keeps the assumptions and no safe output. None past
    ``limit`` states."""
    import spot

    buddy = buddy_module()
    owner = spot.make_twa_graph(spot.make_bdd_dict())
    atoms = list(m.inputs) + list(m.outputs)
    var = [owner.register_ap(a.name) for a in atoms]
    n_atoms = len(atoms)
    outs = buddy.bddtrue
    for v in var[len(m.inputs):]:
        outs = buddy.bdd_and(outs, buddy.bdd_ithvar(v))
    start = tuple(int(b) for b in m.init)
    graph: dict[tuple[int, ...], dict[tuple[int, ...], Any]] = {}
    todo, blocking = [start], []
    while todo:
        st = todo.pop()
        if st in graph:
            continue
        if len(graph) >= limit:
            return None
        memo: dict[int, Any] = {}

        def fixed(root: int, st: tuple[int, ...] = st, memo: dict[int, Any] = memo) -> Any:
            return _restricted(m, root, st, var, n_atoms, memo)

        env = fixed(m.env_ok)
        held = buddy.bddtrue
        for r in (m.assumed if assumed else ()):
            held = buddy.bdd_and(held, fixed(r))
        label = buddy.bdd_and(buddy.bdd_and(fixed(m.safe), env), held)
        # (an input with which the assumptions hold and no safe output: the shield blocks)
        stuck = buddy.bdd_and(buddy.bdd_and(env, buddy.bdd_exist(held, outs)),
                              buddy.bdd_not(buddy.bdd_exist(label, outs)))
        if stuck != buddy.bddfalse:
            one = buddy.bdd_satone(stuck)
            blocking.append(f"{', '.join(m.requirements)}: state {st}, inputs "
                            + ", ".join(f"{a.text}="
                                        f"{int(buddy.bdd_and(one, buddy.bdd_ithvar(v)) != buddy.bddfalse)}"
                                        for a, v in zip(m.inputs, var)))
        edges: dict[tuple[int, ...], Any] = {}
        _split(label, [fixed(r) for r in m.next], (), edges)
        graph[st] = edges
        todo.extend(nxt for nxt in edges if nxt not in graph)
    return Loop(owner, var, graph, blocking)


def _restricted(m: Machine, root: int, st: tuple[int, ...], var: list[int], n_atoms: int,
                memo: dict[int, Any]) -> Any:
    """The node table's BDD ``root`` with the state bits ``st`` fixed, as a BuDDy BDD over
    the atoms' variables ``var`` (``memo``: the table's nodes already converted, for this
    state)."""
    buddy = buddy_module()

    def rec(n: int) -> Any:
        if n < 2:
            return buddy.bddtrue if n == 1 else buddy.bddfalse
        got = memo.get(n)
        if got is None:
            v, lo, hi = m.nodes[n]
            if v >= n_atoms:
                got = rec(hi) if st[v - n_atoms] else rec(lo)
            else:
                got = buddy.bdd_ite(buddy.bdd_ithvar(var[v]), rec(hi), rec(lo))
            memo[n] = got
        return got

    return rec(root)


def _split(label: Any, nexts: list[Any], bits: tuple[int, ...],
           out: dict[tuple[int, ...], Any]) -> None:
    """The moves ``label`` split by the next state (``nexts``: each bit's BDD): next state
    -> its moves, into ``out``."""
    buddy = buddy_module()

    if label == buddy.bddfalse:
        return
    if len(bits) == len(nexts):
        out[bits] = label
        return
    f = nexts[len(bits)]
    _split(buddy.bdd_and(label, buddy.bdd_not(f)), nexts, bits + (0,), out)
    _split(buddy.bdd_and(label, f), nexts, bits + (1,), out)


def _automaton(m: Machine, loop: Loop) -> Any:
    """The closed loop as a Spot automaton (every run accepting) over the atoms' names."""
    import spot

    aut = spot.make_twa_graph(loop.owner.get_dict())
    aut.copy_ap_of(loop.owner)
    aut.set_acceptance(0, spot.acc_code.t())
    aut.prop_state_acc(True)
    index = {s: k for k, s in enumerate(loop.graph)}
    aut.new_states(len(index))
    aut.set_init_state(index[tuple(int(b) for b in m.init)])
    for s, edges in loop.graph.items():
        for nxt, label in edges.items():
            aut.new_edge(index[s], index[nxt], label)
    return aut


def prove_shield(shield: Shield, compiled: Sequence[Any]) -> Proof:
    """Prove each enforced requirement of ``shield`` on its closed loop (module docstring);
    ``compiled`` the requirements it was built from (their ft_inf formulas)."""
    import spot

    by_id = {c.id: c for c in compiled}
    proof = Proof(monitored=dict(shield.monitored))
    for m in shield.machines:
        for v in dict.fromkeys(b["variable"] for b in m.bounds):
            mine = [m.outputs[j].text for j, a in enumerate(m.outputs) if a.variable == v]
            proof.choice.append(
                f"each tick {v} takes a number that gives every comparison the machine "
                f"decided of {', '.join(mine)} (the machine chooses only truth values whose "
                "half-lines meet, by the order of their bounds at that tick, the "
                "environment's move); the forms clamp the proposal between the comparisons' "
                "thresholds in doubles, and a tick where no finite number gives them (a "
                "bound of -inf or NaN, an input a bound reads that cannot be read) is a "
                "fault they report (Decision.fault, the C state's fault 4), the proof's "
                "assumption broken there")
        ids = ", ".join(m.requirements)
        loop = closed_loop(m, assumed=bool(m.assumed))  # (the runs A & !R can have)
        if loop is None:
            for rid in m.requirements:
                proof.results[rid] = "unknown"
                proof.why[rid] = f"the closed loop has more than {MAX_STATES} states"
            continue
        proof.blocking += loop.blocking
        aut = _automaton(m, loop)
        proof.sizes.append((ids, aut.num_states(), aut.num_edges(), len(m.nodes)))
        assumed = [ir.fold_constants(by_id[a].formalization.ft_inf) for a in m.assumptions]
        if assumed and max_bound(assumed) <= SPOT_MAX_BOUND:
            forms, axioms = with_testers(assumed)  # (past atoms: their expansions)
            keeps = spot.translate(spot.formula.And(
                [spot.formula(to_spot(a)) for a in forms + axioms]), dict=aut.get_dict())
            if spot.product(aut, keeps).accepting_word() is None:
                for rid in m.requirements:
                    proof.under[rid] = tuple(m.assumptions)
                    proof.results[rid] = "vacuous"
                    proof.why[rid] = ("no run of the closed loop keeps the assumptions "
                                      f"{', '.join(m.assumptions)}: nothing is proved")
                continue
        for rid in m.requirements:
            phi = ir.fold_constants(by_id[rid].formalization.ft_inf)  # (as the game read it)
            proof.under[rid] = tuple(m.assumptions)
            # (a derived past atom over testers: Spot reads it as its expansion)
            forms, axioms = with_testers([*assumed, phi])
            free = _free_pasts(forms)
            if free:
                proof.results[rid] = "unknown"
                proof.why[rid] = (f"it reads {free}, which Spot's formula reads as a free "
                                  "proposition (a derived past atom no tester writes)")
                continue
            if max_bound([phi, *assumed]) > SPOT_MAX_BOUND:
                proof.results[rid] = "unknown"
                proof.why[rid] = (f"a bound of {max_bound([phi, *assumed])} ticks; Spot is "
                                  f"given up to {SPOT_MAX_BOUND}")
                continue
            neg = spot.translate(spot.formula.And(
                [spot.formula(to_spot(a)) for a in forms[:-1] + axioms]
                + [spot.formula.Not(spot.formula(to_spot(forms[-1])))]), dict=aut.get_dict())
            run = spot.product(aut, neg).accepting_word()
            if run is None:
                proof.results[rid] = "holds"
                if assumed:
                    _vacuity(proof, rid, by_id[rid], assumed, aut, m.assumptions)
            else:
                proof.results[rid] = "violated"
                run.simplify()
                proof.why[rid] = f"a run of the closed loop violates it: {run}"
    return proof


def _free_pasts(formulas: list[Any]) -> str:
    """The derived past atoms left in ``formulas`` (those :func:`fretc.check.past_testers.
    with_testers` could not write: a bounded window past its bound, a comparison reading a
    previous value), by their printed text, comma-separated ("" for none)."""
    names = {to_smv(n) for f in formulas for n in ir.walk(f) if n.op == "past"}
    return ", ".join(sorted(names))


def _vacuity(proof: Proof, rid: str, compiled: Any, assumed: list[Any], aut: Any,
             names: Sequence[str]) -> None:
    """A requirement proved under assumptions: ``"vacuous"`` instead of ``"holds"`` when no
    run of the closed loop ``aut`` keeping the assumptions ``assumed`` (ft_inf) fires its
    trigger (module docstring)."""
    import spot

    from fretc.check.items import make_item

    trigger = make_item(0, compiled).trigger
    if trigger is None or max_bound([trigger, *assumed]) > SPOT_MAX_BOUND:
        return
    forms, axioms = with_testers([*assumed, trigger])  # (past atoms: their expansions)
    fires = spot.translate(spot.formula.And(
        [spot.formula(to_spot(a)) for a in forms + axioms]), dict=aut.get_dict())
    if spot.product(aut, fires).accepting_word() is None:
        proof.results[rid] = "vacuous"
        proof.why[rid] = (f"under {', '.join(names)} no run of the closed loop fires its "
                          "trigger (enters its scope and meets its condition): it holds only "
                          "vacuously")
