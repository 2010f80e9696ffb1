"""``fretc shield``'s synthesis end to end: requirements -> :class:`Shield` (one
:class:`fretc.shield.machine.Machine` per component), or the reason no shield exists.

Each component's game runs in ``fretc check``'s query worker with ``fretc check``'s budgets
(:class:`fretc.check.solver.SpotWorker`): a game past its budget makes no shield (exit 1,
as ``fretc check``'s unknown answers); an unrealizable component is an input error naming
the inputs that defeat every controller (found as ``fretc check`` finds them).
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

from fretc.check.budget import Budget
from fretc.check.numeric_abstraction import NumericAbstraction, simple_comparison
from fretc.check.safety_game import letter_name
from fretc.check.solver import UNKNOWN, SpotWorker
from fretc.common.units import format_period_ms
from fretc.compiler import ir
from fretc.compiler.ir import Node
from fretc.compiler.printers import mangle, to_smv
from fretc.shield.lookback import lookback
from fretc.shield.machine import Atom, Machine
from fretc.shield.plan import Component, Plan, ShieldError, enforced_pts, plan
from fretc.fretish.fret_variables import INTEGER_TYPES, FretVariable
from fretc.shield.predicates import PredicateBudget, term
from fretc.shield.synthesis import synthesize
from fretc.signals.bindings.spec import Bindings

__all__ = ["Requirement", "Shield", "ShieldUnknown", "build_shield", "parse_preferences",
           "with_margin"]


class ShieldUnknown(Exception):
    """A component's game ran past its budget (or Spot/BuDDy could not take it): no shield;
    the message says which and why."""


@dataclass(frozen=True)
class Requirement:
    """An enforced requirement as the shield carries it: ``id``, ``text`` (FRETish),
    ``source`` (``file:line``), ``pt`` (FRET's pt formula, FRET/SMV text), ``component``
    (index of its machine)."""

    id: str
    text: str
    source: str
    pt: str
    component: int


@dataclass(frozen=True)
class Shield:
    """The synthesized shield: ``machines`` one per component; ``inputs``/``outputs`` the
    FRET variables (outputs no requirement reads pass through unchanged); ``requirements``
    the enforced ones; ``monitored`` id -> why not enforced; ``preferences`` ``(output atom
    text, wanted value)`` in the user's order; ``period`` the requirements' tick (seconds,
    None when they declare none); ``messages`` the output variables corrected together (bound
    to one topic); ``numbers`` the variables that are numbers (compared in a formula; the
    others are booleans); ``read`` the variables some requirement reads; ``digest`` a hash
    of the requirements and choices (traceability); ``integers`` the outputs of whole
    numbers."""

    name: str
    machines: tuple[Machine, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    requirements: tuple[Requirement, ...]
    monitored: dict[str, str]
    preferences: tuple[tuple[str, bool], ...]
    period: Fraction | None
    messages: tuple[tuple[str, ...], ...] = ()
    numbers: frozenset[str] = frozenset()
    read: frozenset[str] = frozenset()
    notes: tuple[str, ...] = ()
    digest: str = ""
    #: the outputs that take whole numbers only (FRET's export declares them integers):
    #: corrected to the whole number nearest the proposal (:func:`fretc.shield.runtime.nearest`)
    integers: tuple[str, ...] = ()
    stats: dict[str, Any] = field(default_factory=dict, compare=False)
    #: the outputs of a tick whose inputs cannot be read, as the runtimes' tables hold
    #: them (:func:`fretc.shield.fallback.fallback_of`); None when no outputs are safe
    #: from every state whatever the inputs
    fallback: dict[str, Any] | None = None
    #: the assumptions of the environment the games took (:mod:`fretc.shield.plan`), as
    #: the requirements are carried
    assumptions: tuple[Requirement, ...] = ()
    #: the outputs scaled together, each a twist (``[shield] twists``,
    #: :mod:`fretc.shield.twists`)
    twists: tuple[tuple[str, ...], ...] = ()

    def weights(self, k: int) -> dict[int, tuple[bool, int]]:
        """Machine ``k``'s preferences as :func:`fretc.shield.machine.correct` takes them:
        output atom index -> (wanted value, weight), weights ``2**(P-1) .. 1`` in order."""
        m, p = self.machines[k], len(self.preferences)
        out = {}
        for rank, (text, want) in enumerate(self.preferences):
            for j, a in enumerate(m.outputs):
                if a.text == text:
                    out[j] = (want, 1 << (p - 1 - rank))
        return out


def parse_preferences(text: str | None) -> list[tuple[str, bool]]:
    """``"stopped, !moving"`` -> ``[("stopped", True), ("moving", False)]``: output atoms
    (a boolean variable or a comparison's FRET text) and the value to prefer among equally
    few changes.

    Raises:
        ShieldError: an atom named twice (``o,!o``: the first would hide the second)."""
    out: list[tuple[str, bool]] = []
    for part in (text or "").split(","):
        part = part.strip()
        if part:
            neg = part.startswith("!")
            atom = part[1:].strip() if neg else part
            if any(a == atom for a, _v in out):
                raise ShieldError(f"--prefer names {atom} twice: an atom has one preferred "
                                  "value, and the first would hide the second")
            out.append((atom, not neg))
    return out


def with_margin(compiled: Sequence[Any], margin: int) -> list[Any]:
    """``compiled`` with every ``within N`` deadline shortened by ``margin`` ticks (each
    recompiled from its entry; the text says so): a shield that meets a deadline ``margin``
    ticks early still meets it in the view of a sampler whose ticks lag its own (a recorder
    on the same bus, the audit's grid at another phase), the shield's answers being at most
    that late there.

    Raises:
        ShieldError: a deadline shorter than the margin."""
    from dataclasses import replace

    from fretc.compiler.build import compile_entry
    from fretc.compiler.coverage import with_ticks
    from fretc.compiler.semantics import duration_ticks

    if margin <= 0:
        return list(compiled)
    out = []
    for c in compiled:
        req = c.entry.requirement
        if c.formalization is None or req is None or req.timing.kind != "within":
            out.append(c)
            continue
        assert req.timing.duration is not None  # a within timing has its duration
        ticks = duration_ticks(req.timing.duration, c.entry.tick_period, [])
        if ticks - margin < 0:
            raise ShieldError(f"{c.entry.source}:{c.entry.line}: {c.id}: its deadline of "
                              f"{ticks} ticks is shorter than the margin of {margin}")
        entry = replace(c.entry, requirement=with_ticks(req, ticks - margin),
                        text=f"{c.entry.text} [a deadline {margin} tick(s) early: "
                             f"{ticks - margin} ticks]")
        out.append(compile_entry(entry))
    return out


def _one_period(compiled: Sequence[Any]) -> dict[Any, list[str]]:
    """The tick periods of ``compiled`` (:class:`fretc.compiler.build.Compiled`; the files'
    ``@tick_period``) -> the requirements of each, checked before anything reads their
    formulas.

    Raises:
        ShieldError: a free-form requirement (no formula), or requirements of different tick
            periods (the shield steps on one tick: a duration of the other period would count
            ticks of the wrong length)."""
    for c in compiled:
        if c.formalization is None:
            where = f"{c.entry.source}:{c.entry.line}: {c.id}"
            raise ShieldError(f"{where} has no formula ({c.error})" if c.error is not None
                              else f"{where} is free-form text: it has no formula a shield "
                              "could enforce or monitor; leave it out of the shield's files")
    periods: dict[Any, list[str]] = {}
    for c in compiled:
        if c.entry.tick_period is not None:
            periods.setdefault(c.entry.tick_period, []).append(
                f"{c.id} ({c.entry.source}:{c.entry.line})")
    if len(periods) > 1:
        raise ShieldError("requirements of different tick periods: " + "; ".join(
            f"{format_period_ms(t)}: {', '.join(ids)}" for t, ids in sorted(periods.items()))
            + ". The shield steps on one tick, and each duration counts ticks of its own "
            "file's period; give the files one @tick_period")
    return periods


def build_shield(compiled: Sequence[Any], inputs: Sequence[str], outputs: Sequence[str], *,
                 bindings: Bindings | None = None, prefer: Sequence[tuple[str, bool]] = (),
                 budget: Budget | None = None, name: str = "shield",
                 fork: bool = True, fallback: dict[str, Any] | None = None,
                 assumptions: Sequence[Any] = (),
                 twists: Sequence[Sequence[str]] = (),
                 twists_where: str = "[shield] twists") -> Shield:
    """Synthesize the shield of ``compiled`` (:class:`fretc.compiler.build.Compiled`) for the
    FRET variables ``inputs`` (the environment's) and ``outputs`` (the controller's), with
    ``bindings`` relating outputs of one message, ``prefer`` the tie-breaking preferences,
    ``budget`` each game's (``fretc check``'s defaults), ``fork`` the games in a worker
    process (False: in this one, for tests), ``fallback`` the declared outputs of a tick
    whose inputs cannot be read (:mod:`fretc.shield.fallback`; None: the shield's own),
    ``assumptions`` the environment's (compiled; the games take them, :mod:`fretc.shield.plan`),
    ``twists`` the outputs scaled together (``[shield] twists``, :mod:`fretc.shield.twists`;
    ``twists_where`` where they are written, for a refusal).

    Raises:
        ShieldError: a free-form requirement (no formula), a requirement that cannot be
            enforced, an unrealizable component (with
            the inputs that defeat every controller), an unknown preference, requirements
            of different tick periods (the shield steps on one tick: a duration of the other
            period would count ticks of the wrong length), outputs a FRET export declares
            whole numbers that a requirement compares (:func:`_integer_outputs`), a twist
            that is not one of outputs of numbers (:func:`fretc.shield.twists.check_twists`).
        ShieldUnknown: a component's game past its budget, or comparisons of several
            variables with too many valuations to decide
            (:data:`fretc.shield.predicates.MAX_VALUATIONS`)."""
    periods = _one_period([*compiled, *assumptions])
    integers = _integer_outputs(compiled, outputs)
    from fretc.shield.twists import check_twists

    twists = check_twists(twists, outputs, _numbers([*compiled, *assumptions]), integers,
                          _booleans([*compiled, *assumptions]), twists_where)
    try:
        p = plan(compiled, inputs, outputs, bindings, integers, assumptions, twists)
    except PredicateBudget as exc:
        raise ShieldUnknown(f"no shield: {exc}") from None
    machines = []
    with SpotWorker(budget, fork=fork) as worker:
        for comp in p.components:
            machines.append(_machine(worker, comp, p))
    reqs = tuple(Requirement(x.id, x.compiled.entry.text, x.location, to_smv(pt), k)
                 for k, comp in enumerate(p.components)
                 for x, pt in zip(comp.items, enforced_pts(comp.items)))
    assumed = tuple(Requirement(x.id, x.compiled.entry.text, x.location, to_smv(pt), k)
                    for k, comp in enumerate(p.components)
                    for x, pt in zip(comp.assumptions, enforced_pts(comp.assumptions)))
    texts = {a.text for m in machines for a in m.outputs}
    unknown = [t for t, _v in prefer if t not in texts]
    if unknown:
        raise ShieldError("--prefer names " + ", ".join(unknown) + ", not an output atom of "
                          "an enforced requirement (" + ", ".join(sorted(texts)) + ")")
    read = frozenset(v for c in [*compiled, *assumptions] for v in c.formalization.variables)
    unread = _unread_notes(p, read)
    assert len(periods) <= 1  # (mixed periods were refused above)
    from fretc.shield.fallback import fallback_of

    fb, fb_notes = fallback_of(machines, fallback, p.outputs,
                               _numbers(compiled) | {v for t in twists for v in t},
                               p.integers, prefer)
    digest = hashlib.sha256("\n".join(
        [f"{r.id}:{r.text}" for r in reqs] + [f"in:{','.join(p.inputs)}",
                                              f"out:{','.join(p.outputs)}",
                                              f"prefer:{list(prefer)}"]
        + ([f"integers:{','.join(p.integers)}"] if p.integers else [])
        + [str(m.nodes) for m in machines]
        + [str(m.clusters) for m in machines if m.clusters]
        + [f"fallback:{fb}"]
        + [f"assumes {a.id}:{a.text}" for a in assumed]
        + [f"twist:{','.join(t)}" for t in twists]).encode()).hexdigest()
    return Shield(name, tuple(machines), tuple(p.inputs), tuple(p.outputs), reqs,
                  dict(p.monitored), tuple(prefer), next(iter(periods), None),
                  tuple(tuple(g.variables) for c in p.components for g in c.messages
                        if len(g.variables) > 1),
                  _numbers([*compiled, *assumptions]),
                  read, tuple(p.notes) + tuple(unread) + tuple(fb_notes), digest,
                  integers=tuple(p.integers), fallback=fb, assumptions=assumed,
                  twists=tuple(tuple(t) for t in twists))


def _unread_notes(p: Any, read: frozenset[str]) -> list[str]:
    """The notes of the declared inputs and outputs of the plan ``p`` that no requirement
    reads (``read``): an input not used; an output passed through unchanged (scaled with
    its twist, kept in its message's field)."""
    unread = [f"{v}: declared an input, read by no requirement (not used)" for v in p.inputs
              if v not in read]
    in_message = {v for c in p.components for g in c.messages if g.model is not None
                  for v in g.model["passed"]}
    twisted = {v for c in p.components for t in c.twists for v in t}
    unread += [f"{v}: declared an output, read by no requirement (passed through unchanged"
               + (", scaled with its twist" if v in twisted else "")
               + (", where the decided message of its topic keeps its field"
                  + ("" if v in twisted else "; the C form has no field for it")
                  if v in in_message else "") + ")"
               for v in p.outputs if v not in read]
    return unread


def _declared(compiled: Sequence[Any]) -> list[FretVariable]:
    """The FRET variables a FRET export declares for the requirements' components."""
    return list({(v.component, v.name): v for c in compiled
                 for v in getattr(c.entry, "variables", ())}.values())


def _integer_outputs(compiled: Sequence[Any], outputs: Sequence[str]) -> list[str]:
    """The outputs a FRET export declares whole numbers that a requirement compares with
    constants (sorted): the shield corrects them to whole numbers (``gear > 2`` from a
    proposal of 1 gives 3, not the real 2.0000000000000004, which an integer actuator takes
    as 2).

    Raises:
        ShieldError: such an output read otherwise (compared with another variable, in
            arithmetic or a function): the shield's numbers for those are reals
            (:mod:`fretc.shield.predicates`); or declared ``unsigned integer`` (its sign is
            not kept); named with their declared type."""
    numbers = _numbers(compiled)
    ints = {v.name: v.data_type for v in _declared(compiled)
            if v.data_type in INTEGER_TYPES and v.name in outputs and v.name in numbers}
    unsigned = sorted(f"{v} ({t})" for v, t in ints.items() if t != "integer")
    if unsigned:
        raise ShieldError("outputs declared unsigned whole numbers in the FRET export and "
                          f"compared with numbers: {', '.join(unsigned)}. The shield keeps "
                          "whole numbers but not their sign (it could correct one to -1); "
                          "not supported (declare them integer and require >= 0)")
    other: set[str] = set()
    for c in compiled:
        for n in ir.walk(c.formalization.ft_inf):
            if n.op in ("cmp", "arith") and simple_comparison(n) is None:
                other.update(ir.name_of(x) for x in ir.walk(n) if x.op == "var")
    bad = sorted(f"{v} ({t})" for v, t in ints.items() if v in other)
    if bad:
        raise ShieldError("outputs declared whole numbers in the FRET export and compared "
                          f"with other variables or in arithmetic: {', '.join(bad)}. The "
                          "shield gives such comparisons real numbers and could give one "
                          "that is no whole number; not supported (compare them with "
                          "constants only)")
    return sorted(ints)


def _booleans(compiled: Sequence[Any]) -> frozenset[str]:
    """The FRET variables read as booleans (outside every comparison and arithmetic) in any
    formula."""
    out: set[str] = set()
    for c in compiled:
        out.update(ir.name_of(n) for n in ir.walk(c.formalization.ft_inf) if n.op == "ap")
    return frozenset(out)


def _numbers(compiled: Sequence[Any]) -> frozenset[str]:
    """The FRET variables read as numbers (under a comparison or arithmetic) in any formula."""
    out: set[str] = set()
    for c in compiled:
        for n in ir.walk(c.formalization.ft_inf):
            if n.op in ("cmp", "arith"):
                out.update(ir.name_of(x) for x in ir.walk(n) if x.op == "var")
    return frozenset(out)


def _machine(worker: SpotWorker, comp: Component, p: Plan) -> Machine:
    """The machine of one component (module docstring)."""
    ans = worker.ask(("call", synthesize, (comp.game_pts, comp.game_inputs, comp.env_inv,
                                           comp.ctl_inv, comp.watch, comp.raw_pts)))
    if ans == UNKNOWN:
        why = worker.failures[-1] if worker.failures else "no reason given"
        if why.startswith("RuntimeError:"):  # a defect of the synthesis, not a budget
            raise RuntimeError(why[len("RuntimeError:"):].strip())
        raise ShieldUnknown(f"the shield of {', '.join(comp.ids)} could not be synthesized: "
                            f"{why} (raise --budget or --memory-budget)")
    if not ans["realizable"]:
        raise ShieldError(_unrealizable(comp, p, ans))
    back = {ap: pred for pred, ap in comp.names.items()}
    atoms = [(_atom(back.get(a, a), comp.bounds), is_in) for a, is_in in ans["atoms"]]
    outs = [a for a, i in atoms if not i]
    bounds = tuple({"atom": j, "variable": a.variable, "down": int(b.down),
                    "estimate": term(b.bound)}
                   for j, a in enumerate(outs) for b in comp.bounds.values()
                   if a.text == to_smv(b.atom))
    clusters = []
    for cl in comp.clusters:
        if cl.is_input:
            continue
        index = [next(j for j, a in enumerate(outs) if a.text == to_smv(x)) for x in cl.atoms]
        clusters.append({"atoms": index, "variables": list(cl.variables),
                         "numbers": {sum(int(b) << k for k, b in enumerate(key)): nums
                                     for key, nums in sorted(cl.witnesses.items())}})
    # (the ticks after which a machine that lost its state knows it again: shield.lookback)
    stats = {**ans["stats"], "lookback": lookback(comp.game_pts)}
    return Machine(tuple(comp.ids), tuple(a for a, i in atoms if i), tuple(outs),
                   tuple(ans["init"]), tuple(tuple(n) for n in ans["nodes"]), ans["safe"],
                   tuple(ans["next"]), tuple(ans["keep"]), ans["env_ok"], ans["ctl_ok"],
                   tuple(comp.messages), tuple(clusters), stats, ans["robust"],
                   tuple(a.id for a in comp.assumptions), tuple(ans["watch"]), bounds,
                   tuple(tuple(t) for t in comp.twists))


def _atom(node: Node, bounds: dict[Node, Any] | None = None) -> Atom:
    """An IR atom (a boolean variable, a comparison with a constant, a comparison of
    several variables, a bound of ``bounds``: its ``variable`` the output it bounds) as an
    :class:`Atom`."""
    if node.op == "cmp" and simple_comparison(node) is None:
        bound = (bounds or {}).get(node)
        first = bound.output if bound is not None else next(
            ir.name_of(x) for x in ir.walk(node) if x.op == "var")
        return Atom(to_smv(node), first, "pred", None, letter_name(node), term(node))
    if node.op == "ap":
        return Atom(to_smv(node), ir.name_of(node), name=letter_name(node))
    sc = simple_comparison(node)
    assert sc is not None  # the game takes no other atom
    var, op, c = sc
    return Atom(to_smv(node), var, op, float(c), letter_name(node))


def _cluster_numbers(comp: Component, letter: dict[str, bool]) -> dict[str, float]:
    """Numbers of the inputs compared together (an input cluster, the order comparisons of
    bounds among them) that give their atoms the truths of ``letter`` (a game letter: atom
    name -> value), from z3's witness of that valuation; none for a cluster the letter does
    not value whole."""
    out: dict[str, float] = {}
    for cl in comp.clusters:
        if not cl.is_input:
            continue
        names = [letter_name(comp.names.get(a, a)) for a in cl.atoms]
        if not all(n in letter for n in names):
            continue
        got = cl.witnesses.get(tuple(bool(letter[n]) for n in names))
        if isinstance(got, dict):
            out.update({v: x for v, x in got.items() if v not in out})
    return out


def _unrealizable(comp: Component, p: Plan, ans: dict[str, Any]) -> str:
    """The refusal of an unrealizable component, with the inputs that defeat every
    controller when the search found them."""
    head = (f"no shield exists for {', '.join(comp.ids)} ({', '.join(x.location for x in comp.items)}): "
            "the requirements are unrealizable (no controller meets them whatever the inputs "
            f"{', '.join(p.inputs)} do)")
    numeric = NumericAbstraction.of(enforced_pts(comp.items))
    whole = [v for v in sorted(numeric.atoms) if v in p.integers
             and numeric.region(v) != numeric.region(v, True, True)]
    gaps = [v for v in sorted(numeric.atoms) if v not in whole
            and numeric.region(v) != numeric.region(v, True)]
    if gaps:  # (check decides over the reals, the shield in doubles)
        head += (f", in doubles as the shield decides: the comparisons of {', '.join(gaps)} "
                 "have values between their constants that no double takes (two literals "
                 "that are one double, or no double between them), which fretc check, over "
                 "the reals, counts")
    if whole:
        head += (f", in whole numbers as FRET's export declares {', '.join(whole)}: their "
                 "comparisons have values between their constants that no whole number "
                 "takes, which fretc check, over the reals, counts")
    unused = [(cl, v) for cl in comp.clusters for v in cl.unwitnessed]
    if unused:
        head += (", in doubles as the shield decides: " + "; ".join(
            " & ".join(to_smv(a) if t else f"!{to_smv(a)}" for a, t in zip(cl.atoms, v))
            + f" ({cl.unwitnessed[v]})" for cl, v in unused)
            + ": never chosen, where fretc check, over the reals, counts it")
    restricted = [g for g in comp.messages if g.valuations
                  and len(g.valuations) < 2 ** len(g.valuations[0][0])]
    if restricted:  # (check reads no bindings)
        head += (", with the outputs as messages give them: valuations of " + "; ".join(
            f"{', '.join(g.variables)} that no message of {', '.join(g.topics)} gives"
            for g in restricted) + " are never chosen (the bindings), which fretc check "
            "does not read")
    if not ans.get("inputs"):
        return head + "; " + (ans.get("note") or "the environment must react to the outputs")
    atoms = {to_smv(a): a for name in numeric.atoms for a in numeric.atoms[name]}
    rows = []
    for letter in ans["inputs"]:
        truth = {atoms[k]: v for k, v in letter.items() if k in atoms}
        numbers = numeric.values(truth)
        row: dict[str, Any] = {}
        clustered = _cluster_numbers(comp, letter)
        for v in p.inputs:
            if v in clustered:  # (compared with other inputs: the cluster's numbers)
                row[v] = clustered[v]
            elif v in numeric.atoms:
                row[v] = numbers[v]
            elif mangle(v) in letter:  # (a letter names a variable as Spot's words do)
                row[v] = letter[mangle(v)]
        rows.append("{" + ", ".join(f"{k}={str(x).lower() if isinstance(x, bool) else x}"
                                    for k, x in row.items()) + "}")
    return (head + "; these inputs, tick by tick, defeat every controller: "
            + " ".join(rows) + ("" if gaps or whole or unused or restricted
                                else " (fretc check gives the same finding)"))
