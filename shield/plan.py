"""What ``fretc shield`` enforces: the requirements sorted into enforced, monitored and refused,
the enforced ones into components, and the consistency of the outputs' atoms.

Enforced: a safety requirement reading an output whose atoms the game takes; monitored
only: one over inputs only; refused (input errors, exit 2, :class:`ShieldError`): not a
safety property, an atom the game cannot take, a variable declared neither input nor output.
Assumptions of the environment (``--assume``, Alshiekh et al., AAAI 2018) join the components
whose variables they share. Outputs bounded by the inputs (:mod:`fretc.check.bounds`) are
atoms of the controller. Components are joined further by shared topics and twists, and
valuations no single message gives are excluded (:func:`fretc.testing.invert.solve`). Each
rule in full: ARCHITECTURE.md ("What the shield enforces").
"""

from __future__ import annotations

import itertools
from collections.abc import Collection, Sequence
from dataclasses import dataclass, field
from typing import Any

from fretc.check.bounds import Bound, bounds_of, feasibility
from fretc.common.grouping import connected_groups
from fretc.check.items import CheckItem, make_item
from fretc.check.numeric_abstraction import NumericAbstraction, simple_comparison
from fretc.check.pt_monitor import Outside
from fretc.check.safety_game import game_atoms
from fretc.common.errors import FretcError
from fretc.compiler import ir
from fretc.shield import predicates as preds
from fretc.shield.message_model import model_of
from fretc.compiler.ir import Node
from fretc.compiler.printers import to_smv
from fretc.signals.bindings.expression import BinOp, Const, Expr, Field, FuncCall, UnaryOp
from fretc.signals.bindings.spec import Bindings
from fretc.testing.invert import AGE, NotWritable, solve

__all__ = ["ShieldError", "MessageGroup", "Component", "Plan", "plan", "MAX_GROUP_ATOMS",
           "enforced_pts"]

#: the most output atoms of one message whose valuations are enumerated (2^12 inversions)
MAX_GROUP_ATOMS = 12


class ShieldError(FretcError, ValueError):
    """Requirements ``fretc shield`` cannot enforce, or inputs it cannot use; the message says
    why (and, for an unrealizable set, gives the inputs that defeat every controller)."""


@dataclass
class MessageGroup:
    """Output variables bound to one topic (``variables``) and the valuations of their atoms
    some message gives: ``valuations`` ``(atom text -> value, the message's fields
    ((topic, path) -> value), numeric variable -> its value on that message)``, the
    numbers of a variable whose binding is not evaluated here left out. Empty when the
    bindings are not inverted (any valuation allowed, noted). ``topics``: the topics their
    bindings read."""

    variables: list[str]
    valuations: list[tuple[dict[str, bool], dict[tuple[str, tuple[str, ...]], Any],
                           dict[str, float]]] = field(default_factory=list)
    topics: list[str] = field(default_factory=list)
    #: the outputs bound to its topics that no requirement reads (passed through)
    passed: list[str] = field(default_factory=list)
    #: its bindings as terms over the message's fields, so that every form decides values
    #: one message gives (:mod:`fretc.shield.message_model`); None when they are no such
    #: terms (noted)
    model: dict[str, Any] | None = None


@dataclass
class Component:
    """Enforced requirements sharing variables or messages: ``items`` (check's view of each),
    ``env_inv``/``ctl_inv`` the consistency of the input / output atoms (propositional IR
    over the game's atoms: numeric regions, the clusters' invariants, and for outputs the
    message constraints), ``messages`` the groups of output variables bound to one topic
    (the shield corrects each group together), ``clusters`` the comparisons of several
    variables (:mod:`fretc.shield.predicates`), ``names`` each such comparison -> its game
    atom (a boolean ``ap``), ``game_pts`` the pt formulas with them substituted,
    ``game_inputs`` the inputs and the game atoms of input clusters."""

    items: list[CheckItem]
    env_inv: Node = ir.TRUE
    ctl_inv: Node = ir.TRUE
    messages: list[MessageGroup] = field(default_factory=list)
    clusters: list[preds.Cluster] = field(default_factory=list)
    names: dict[Node, Node] = field(default_factory=dict)
    game_pts: list[Node] = field(default_factory=list)
    game_inputs: list[str] = field(default_factory=list)
    #: the assumptions of the environment this component's game takes (module docstring)
    assumptions: list[CheckItem] = field(default_factory=list)
    #: per assumption its "held at every tick so far" (``H A``, with the game's atom names),
    #: whose values the forms report (:mod:`fretc.shield.runtime`)
    watch: list[Node] = field(default_factory=list)
    #: with assumptions, the requirements' pt formulas without them (the game's atom
    #: names): the fallback keeps these whatever the environment does, so that it never
    #: relies on an assumption that broke (:mod:`fretc.shield.synthesis`)
    raw_pts: list[Node] = field(default_factory=list)
    #: the comparisons of one output with a term over the inputs (module docstring), by
    #: atom
    bounds: dict[Node, Bound] = field(default_factory=dict)
    #: the twists whose outputs this component corrects (``[shield] twists``)
    twists: list[list[str]] = field(default_factory=list)

    @property
    def ids(self) -> list[str]:
        """The requirement ids, in input order."""
        return [x.id for x in self.items]


@dataclass
class Plan:
    """The requirements as the shield sees them (module docstring): ``components`` of the
    enforced ones, ``monitored`` id -> why not enforced, ``notes`` what the plan could not
    relate (a binding that is not inverted)."""

    inputs: list[str]
    outputs: list[str]
    components: list[Component]
    monitored: dict[str, str]
    notes: list[str]
    #: the outputs that take whole numbers only (FRET's export declares them so)
    integers: list[str] = field(default_factory=list)


def plan(compiled: Sequence[Any], inputs: Sequence[str], outputs: Sequence[str],
         bindings: Bindings | None = None, integers: Sequence[str] = (),
         assumptions: Sequence[Any] = (), twists: Sequence[Sequence[str]] = ()) -> Plan:
    """Sort ``compiled`` (:class:`fretc.compiler.build.Compiled`) into the plan of the module
    docstring, ``inputs``/``outputs`` the FRET variables of the environment / controller,
    ``integers`` the outputs that take whole numbers only (their comparisons' regions those
    a whole number lies in, :meth:`fretc.check.numeric_abstraction.NumericAbstraction.region`),
    ``assumptions`` the environment's (compiled, module docstring), ``twists`` the outputs
    of each twist (checked by :func:`fretc.shield.twists.twists_of`).

    Raises:
        ShieldError: a requirement that cannot be enforced, a variable both input and
            output or neither, a requirement that did not formalize, an assumption that
            is not a safety property or reads an output at the tick it is judged, an
            output bounded by the inputs that is also compared with ``=``/``!=``, with
            another output or takes whole numbers."""
    inputs, outputs = list(dict.fromkeys(inputs)), list(dict.fromkeys(outputs))
    both = sorted(set(inputs) & set(outputs))
    if both:
        raise ShieldError("declared both input and output: " + ", ".join(both))
    enforced: list[CheckItem] = []
    monitored: dict[str, str] = {}
    notes: list[str] = []
    assumed = [_assumption(len(compiled) + k, c, inputs, outputs)
               for k, c in enumerate(assumptions)]
    # (the inputs an assumption relates to an output: a requirement over them is enforced)
    linked = {v for a in assumed if set(a.variables) & set(outputs) for v in a.variables}
    for k, c in enumerate(compiled):
        if c.formalization is None:
            raise ShieldError(f"{_where(c)}: {c.id} has no formalization"
                              + (f" ({c.error})" if c.error else " (free-form text)"))
        bound = _probability_bound(c)
        if bound is not None:
            notes.append(bound)
        item = make_item(k, c)
        undeclared = [v for v in item.variables if v not in inputs and v not in outputs]
        _refuse_streams(c, undeclared)
        _refuse_undeclared(c, undeclared)
        if all(v in inputs for v in item.variables) and not set(item.variables) & linked:
            monitored[c.id] = ("over inputs only (" + ", ".join(item.variables) + "): the "
                               "environment's, no output can keep it; monitored, not enforced"
                               + ("" if not assumed else " (no assumption relates "
                                  + ", ".join(item.variables) + " to an output)"))
            continue
        if item.pt is None:
            raise ShieldError(f"{_where(c)}: {c.id} is not a safety property: "
                              + _not_safety(c.formalization.key))
        for n in ir.walk(item.pt):
            if preds.is_predicate(n) and (why := preds.refusal(n, inputs)) is not None:
                raise ShieldError(f"{_where(c)}: {c.id}: {why}")
        try:
            game_atoms([preds.substitute(item.pt, {n: ir.ap(preds.PREFIX) for n in
                                                   ir.walk(item.pt) if preds.is_predicate(n)})])
        except Outside as exc:
            raise ShieldError(f"{_where(c)}: {c.id}: {exc}") from None
        enforced.append(item)
    groups = _message_groups(outputs, bindings)
    whole = sorted(set(integers) & set(outputs))
    ids = {a.id for a in assumed}
    turns = [list(t) for t in twists]
    _refuse_shared_fields(turns, outputs, bindings)
    components = []
    for items in _components(enforced + assumed, groups + turns):
        reqs = [x for x in items if x.id not in ids]
        assume = [x for x in items if x.id in ids]
        if not reqs:
            notes.extend(f"assumption {a.id} shares no variable with an enforced requirement: "
                         "not used" for a in assume)
            continue
        comp = _component(reqs, inputs, groups, bindings, notes, whole, assume, turns)
        components.append(comp)
    _twists_read(turns, components, notes)
    return Plan(inputs, outputs, components, monitored, notes, whole)


def _refuse_undeclared(c: Any, undeclared: Sequence[str]) -> None:
    """Raise :class:`ShieldError` when requirement ``c`` reads variables declared neither
    input nor output (``undeclared``), naming their kind in a FRET export."""
    if not undeclared:
        return
    fret = {v.name: v for v in getattr(c.entry, "variables", ())}
    kinds = [f"{v} is {'an' if fret[v].kind[0] in 'IO' else 'a'} {fret[v].kind} "
             "variable" + (f" of {fret[v].component}" if fret[v].component else "")
             + " in FRET's export" for v in undeclared if v in fret and fret[v].kind]
    raise ShieldError(f"{_where(c)}: {c.id} reads {', '.join(undeclared)}, declared "
                      "neither input nor output (--inputs/--outputs, or @inputs/"
                      "@outputs in the file): the shield must know who sets each"
                      + (f" ({'; '.join(kinds)})" if kinds else ""))


def _fields(e: Expr) -> set[tuple[str, tuple[str, ...]]]:
    """The message fields a binding reads (topic, path of attribute names)."""
    out: set[tuple[str, tuple[str, ...]]] = set()
    stack = [e]
    while stack:
        x = stack.pop()
        if isinstance(x, Field):
            out.add((x.topic, tuple(str(p) for p in x.path)))
        stack.extend(c for c in vars(x).values() if isinstance(c, Expr))
        stack.extend(c for v in vars(x).values() if isinstance(v, (list, tuple))
                     for c in v if isinstance(c, Expr))
    return out


def _at(bindings: Bindings, v: str) -> str:
    """``file:line`` of the binding of ``v``."""
    b = bindings.variables[v]
    return f"{b.source}:{b.line}" if b.line is not None else str(b.source)


def _refuse_shared_fields(twists: list[list[str]], outputs: list[str],
                          bindings: Bindings | None) -> None:
    """Refuse a twist whose output's field another output outside the twist reads
    (``angular_speed = abs(angular.z)`` or ``stopped`` beside ``angular_velocity =
    angular.z``): scaling the twist would change that output too, which the shield decides by
    its own comparisons (so the forms scale a twist's fields and nothing else).

    Raises:
        ShieldError: naming the twist's output, the other output and the field."""
    if bindings is None:
        return
    for t in twists:
        for v in t:
            if v not in bindings.variables:
                continue
            mine = _fields(bindings.variables[v].ast)
            for u in outputs:
                if u in t or u not in bindings.variables:
                    continue
                shared = mine & _fields(bindings.variables[u].ast)
                if shared:
                    topic, path = sorted(shared)[0]
                    raise ShieldError(
                        f"[shield] twists: {v} reads {topic}.{'.'.join(path)}, which the "
                        f"output {u} reads too ({_at(bindings, u)}): scaling the twist "
                        f"would change {u}, which the shield decides by its own comparisons; "
                        "a twist's outputs must be the only outputs of their fields (write "
                        f"{u}'s comparisons over {v}: -0.5 <= {v} & {v} <= 0.5 for "
                        "abs(...) <= 0.5)")


def _twists_read(twists: list[list[str]], components: list[Component], notes: list[str]
                 ) -> None:
    """Note each twist no enforced requirement reads (its outputs pass through unchanged)."""
    for t in twists:
        if not any(t in c.twists for c in components):
            notes.append(f"the twist {', '.join(t)}: no enforced requirement reads its "
                         "outputs (passed through unchanged)")


def _refuse_streams(c: Any, undeclared: Sequence[str]) -> None:
    """Refuse the requirement ``c`` (:class:`fretc.compiler.build.Compiled`) when it reads
    a FRET stream variable among ``undeclared`` (an Internal variable whose Lustre
    definition reads itself through ``pre``: :mod:`fretc.check.streams`), naming it, the
    variables its definition reads and why: the shield's game and runtime step the
    requirements' monitors over the inputs and outputs of one tick, and hold no state of a
    stream (``fretc check`` reads such a comparison as an independent proposition, which
    a shield cannot enforce). The reason names the kind: a numeric stream is a stored real
    number; a boolean one that reads a previous number (``pre`` of a number, or a numeric
    stream) is not a machine of boolean state bits over the tick's atoms. A boolean stream
    of booleans and of the tick's comparisons is none of these (a latch is its
    formula ``P S psi``, another its one-bit machine, IR ``stream``, and both are enforced:
    :mod:`fretc.fretish.fret_since`).

    Raises:
        ShieldError: it reads one."""
    from fretc.check.streams import streams_of_entry

    found = streams_of_entry(c.entry, undeclared)
    if not found:
        return
    said = "; ".join(f"{n} (its definition {s.text} reads "
                     + (", ".join(s.reads) or "no variable") + " now and through pre; "
                     + (_NOT_PAST if s.boolean else _NUMERIC) + ")"
                     for n, s in found.items())
    raise ShieldError(f"{_where(c)}: {c.id} reads the FRET stream variable"
                      f"{'s' * (len(found) > 1)} {said}: the shield does not compute stream "
                      "variables (its machines step over one tick's inputs and outputs); "
                      "leave the requirement out (--exclude), or declare the variable an "
                      "input (--inputs) for the shield to read it from the system")


#: why the shield cannot hold a numeric stream (:func:`_refuse_streams`)
_NUMERIC = ("a numeric stream is a stored real number, a memory of a past value: no finite "
            "game holds it")
#: why the shield cannot hold a boolean stream it is given (one reading booleans and the
#: tick's comparisons only is a machine of state bits, which the shield reads:
#: :mod:`fretc.fretish.fret_since`)
_NOT_PAST = ("a boolean stream reading a previous number (pre of a number, or a numeric "
             "stream) holds what a real number decides, not a machine of boolean state "
             "bits over the tick's atoms")


def _assumption(index: int, c: Any, inputs: Sequence[str], outputs: Sequence[str]
                ) -> CheckItem:
    """An assumption of the environment as the game takes it (module docstring).

    Raises:
        ShieldError: free-form text, not a safety property, a variable neither input nor
            output, an atom the game cannot take, or an output read at the tick the
            assumption is judged (the controller could break it)."""
    if c.formalization is None:
        raise ShieldError(f"{_where(c)}: assumption {c.id} has no formalization"
                          + (f" ({c.error})" if c.error else " (free-form text)"))
    item = make_item(index, c)
    undeclared = [v for v in item.variables if v not in inputs and v not in outputs]
    _refuse_streams(c, undeclared)
    if undeclared:
        raise ShieldError(f"{_where(c)}: assumption {c.id} reads {', '.join(undeclared)}, "
                          "declared neither input nor output")
    if item.pt is None:
        raise ShieldError(f"{_where(c)}: assumption {c.id} is not a safety property: "
                          + _not_safety(c.formalization.key))
    now = _read_now(item.pt, set(outputs))
    if now:
        raise ShieldError(f"{_where(c)}: assumption {c.id} reads the output(s) "
                          f"{', '.join(sorted(now))} at the tick it is judged, so the "
                          "controller could break it and win by it: an assumption may read "
                          "outputs only at earlier ticks ('whenever ... the environment shall "
                          "at the next timepoint satisfy ...')")
    for n in ir.walk(item.pt):
        if preds.is_predicate(n) and (why := preds.refusal(n, inputs)) is not None:
            raise ShieldError(f"{_where(c)}: assumption {c.id}: {why}")
    return item


def _read_now(n: Node, outputs: set[str], past: bool = False) -> set[str]:
    """The outputs ``n`` (a pt formula) reads at the current tick: outside every ``Y`` and
    ``Z`` (``O``, ``H``, ``S`` and ``T`` read the current tick too)."""
    if n.op in ("Y", "Z"):
        past = True
    if not n.args:
        return set() if past else {v for v in ir.variables(n) if v in outputs}
    if n.op == "cmp" or n.op == "arith":
        return set() if past else {v for v in ir.variables(n) if v in outputs}
    out: set[str] = set()
    for a in n.args:
        out |= _read_now(a, outputs, past)
    return out


def _probability_bound(c: Any) -> str | None:
    """None for a requirement without ``with probability OP p`` (FRET 3.1); for one with it,
    the note that the shield enforces its property on every run, so with probability 1,
    which meets ``OP p``.

    Raises:
        ShieldError: probability 1 does not meet the bound (``<= 0.001``: a shield that
            enforces the property makes the requirement fail)."""
    req = c.entry.requirement
    prob = getattr(req, "probability", None)
    if prob is None:
        return None
    p = float(prob.value)
    holds = {"<": 1 < p, "<=": 1 <= p, ">": 1 > p, ">=": 1 >= p, "=": p == 1,
             "!=": p != 1}[prob.op]
    if not holds:
        raise ShieldError(f"{_where(c)}: {c.id} bounds the probability of its property by "
                          f"{prob.op} {prob.value}: a shield enforces the property on every "
                          "run (probability 1), which breaks that bound; leave it out of the "
                          "shield and judge it with fretc audit or fretc estimate")
    return (f"{c.id}: 'with probability {prob.op} {prob.value}' is enforced on every run "
            "(probability 1, which meets the bound): the shield may correct more than the "
            "requirement asks")


def _not_safety(key: str) -> str:
    """Why a requirement of template key ``key`` (``scope,condition,timing``) has no
    run-time enforcement, and what to write instead."""
    scope, _cond, timing = (key.split(",") + ["", "", ""])[:3]
    if timing in ("eventually", "null"):
        return ("its response is required eventually, with no bound, so no finite run "
                "shows it failed and no shield can enforce it; give a deadline (e.g. "
                "'within 1 second')")
    if timing == "finally":
        return ("'at the last timepoint' speaks of the run's end, which a shield never "
                "sees; write the obligation with a deadline instead")
    return (f"in the {scope} scope with the {timing} timing its ft_inf formula asks for "
            "something to happen eventually (a strong until), so no shield can enforce it "
            "at run time; a deadline or another scope makes it a safety property")


def _where(c: Any) -> str:
    return f"{c.entry.source}:{c.entry.line}"


def _message_groups(outputs: list[str], bindings: Bindings | None) -> list[list[str]]:
    """Output variables joined when their bindings read a common topic (union-find); a
    variable alone on its topics is a group of one (its messages are made the same way)."""
    if bindings is None:
        return []
    variables = [v for v in outputs if v in bindings.variables]
    return connected_groups(variables, lambda v: bindings.variables[v].topics)


def _components(items: list[CheckItem], groups: list[list[str]]) -> list[list[CheckItem]]:
    """Requirements grouped by shared variables and by ``groups`` (outputs of one message,
    of one twist), input order."""
    joined = connected_groups(groups, lambda g: g)  # groups that share a variable
    one = {v: k for k, gs in enumerate(joined) for g in gs for v in g}
    return connected_groups(items, lambda item: [(one[v],) if v in one else v
                                                 for v in item.variables])


def _component(items: list[CheckItem], inputs: list[str], groups: list[list[str]],
               bindings: Bindings | None, notes: list[str], integers: Sequence[str] = (),
               assumptions: Sequence[CheckItem] = (),
               twists: Sequence[list[str]] = ()) -> Component:
    """A :class:`Component` with its invariants (module docstring), its game taking
    ``assumptions``; ``twists`` every twist (the component keeps those it corrects).

    Raises :class:`fretc.shield.predicates.PredicateBudget` (a cluster too large),
    :class:`ShieldError` (a bounded output the shield cannot take, module docstring)."""
    pts = enforced_pts(items)
    apts = enforced_pts(list(assumptions))
    bounds = bounds_of(pts + apts, inputs)
    bounded = list(dict.fromkeys(b.output for b in bounds.values()))
    plain = [_without_bounds(f, bounds) for f in pts + apts]
    constants = NumericAbstraction.of(pts + apts).atoms
    _refuse_bounded(items, bounded, constants, integers, inputs)
    _refuse_shared_bounds(items, bounded, groups, bindings, inputs)
    orders, feasible = feasibility(list(bounds.values()),
                                   [a for v in bounded for a in constants.get(v, [])])
    ordered = ir.and_all(*orders)
    numeric = NumericAbstraction.of(pts + apts + [ordered])
    # (in doubles, as the shield's forms compute: a region with reals and no double in it
    # is no move of either player)
    env_inv = numeric.regions([v for v in numeric.atoms if v in inputs], doubles=True)
    ctl_inv = numeric.regions([v for v in numeric.atoms if v not in inputs], doubles=True,
                              integers=integers)
    clusters = preds.clusters(plain + [ordered], inputs)
    _refuse_clustered(items, bounded, clusters, inputs=inputs)
    _refuse_clustered(items, [v for t in twists for v in t], clusters, "in a twist")
    for cl in clusters:
        for values, why in cl.unwitnessed.items():
            cube = " & ".join(to_smv(a) if v else f"!{to_smv(a)}"
                              for a, v in zip(cl.atoms, values))
            notes.append(f"never chosen: {cube} ({why})")
    names, game_inputs = _game_names(clusters, bounds, inputs)
    for cl in clusters:
        inv = preds.substitute(cl.invariant, names)
        if cl.is_input:
            env_inv = ir.and_(env_inv, inv)
        else:
            ctl_inv = ir.and_(ctl_inv, inv)
    ctl_inv = ir.and_(ctl_inv, preds.substitute(feasible, names))
    game_pts = [preds.substitute(f, names) for f in pts]
    raw_pts: list[Node] = []
    watch = [ir.H(preds.substitute(f, names)) for f in apts]
    if watch:  # (a requirement is kept while some assumption has been broken)
        held = ir.and_all(*watch)
        raw_pts = list(game_pts)
        game_pts = [ir.or_(f, ir.not_(held)) for f in game_pts]
    try:
        atoms = game_atoms(game_pts)
    except Outside as exc:
        consts = [n for f in game_pts for n in ir.walk(f) if n.op == "cmp"
                  and not ir.variables(n)]  # (not folded: reals and doubles disagree)
        why = (f"the comparison of constants {to_smv(consts[0])} is true over the reals "
               "(FRET's) and false in doubles (a controller's), or the other way round; "
               "write it without them" if consts else str(exc))
        raise ShieldError(f"{', '.join(x.compiled.id for x in items)}: {why}") from None
    used = {v for x in [*items, *assumptions] for v in x.variables}
    messages = []
    for g in groups:
        if set(g) & used:
            group = MessageGroup([v for v in g if v in used], topics=sorted(
                {t for v in g for t in bindings.variables[v].topics} if bindings else ()),
                passed=[v for v in g if v not in used])
            mine = [a for a in atoms if _variable(a) in g]
            ctl_inv = ir.and_(ctl_inv, _message_constraint(mine, bindings, notes, group,
                                                           set(bounded) & set(g)))
            _message_model(group, mine, bindings, clusters, notes, bounded)
            messages.append(group)
    turns = [t for t in twists if set(t) & used]
    return Component(items, env_inv, ctl_inv, messages, clusters, names, game_pts,
                     game_inputs, list(assumptions), watch, raw_pts, bounds, turns)


def _game_names(clusters: Sequence[Any], bounds: dict[Node, Bound], inputs: Sequence[str]
                ) -> tuple[dict[Node, Node], list[str]]:
    """The game's propositions of the comparisons of ``clusters`` and of the ``bounds``
    (``PREFIX`` and a number each, in order), and the game's inputs: ``inputs`` and the
    propositions of the environment's clusters (a bound is the controller's)."""
    names: dict[Node, Node] = {}
    game_inputs = list(inputs)
    for cl in clusters:
        for a in cl.atoms:
            if preds.is_predicate(a) and a not in names:
                names[a] = ir.ap(f"{preds.PREFIX}{len(names)}")
                if cl.is_input:
                    game_inputs.append(ir.name_of(names[a]))
    for a in bounds:  # (the controller's atoms)
        names[a] = ir.ap(f"{preds.PREFIX}{len(names)}")
    return names, game_inputs


def _without_bounds(f: Node, bounds: dict[Node, Bound]) -> Node:
    """``f`` with each bound replaced by a boolean atom of its own (for the clusters: a
    bound is no cluster's, module docstring)."""
    if not bounds:
        return f
    return preds.substitute(f, {a: ir.ap(f"__bound_{k}") for k, a in enumerate(bounds)})


def _reader(items: list[CheckItem], v: str, inputs: Sequence[str] = ()) -> str:
    """``ID (file:line)`` of the first of ``items`` bounding ``v`` by the ``inputs``, else
    the first reading it."""
    def bounds_v(x: CheckItem) -> bool:
        return x.pt is not None and any(b.output == v
                                        for b in bounds_of([x.pt], inputs).values())

    x = next((x for x in items if bounds_v(x)), None) or next(
        (x for x in items if v in x.variables), items[0])
    return f"{x.id} ({x.location})"


def _refuse_bounded(items: list[CheckItem], bounded: list[str],
                    constants: dict[str, list[Node]], integers: Sequence[str],
                    inputs: Sequence[str] = ()) -> None:
    """Refuse a bounded output (module docstring) compared with a constant by ``=`` or
    ``!=`` (its truth values are no half-lines) or taking whole numbers.

    Raises:
        ShieldError: naming the requirement, the output and why."""
    for v in bounded:
        if v in integers:
            raise ShieldError(f"{_reader(items, v, inputs)}: {v} takes whole numbers (FRET's "
                              "export) and is bounded by the inputs: the shield gives a "
                              "bounded output the real number nearest the proposal; declare "
                              "it a real")
        for a in constants.get(v, []):
            sc = simple_comparison(a)
            if sc is not None and sc[1] in ("=", "!="):
                raise ShieldError(
                    f"{_reader(items, v, inputs)}: {v} is bounded by the inputs and compared "
                    f"by {to_smv(a)}: the truth values of = and != are no half-lines, which the "
                    "shield's bounds need; write the equality as two comparisons (<= and >=)")


def _refuse_shared_bounds(items: list[CheckItem], bounded: list[str],
                          groups: list[list[str]], bindings: Bindings | None,
                          inputs: Sequence[str] = ()) -> None:
    """Refuse a bounded output whose message field another output reads too
    (``linear_speed = abs(linear.x)`` or ``stopped`` beside ``linear_velocity =
    linear.x``): which truth values numbers give a bound is the output's alone to the game,
    and the other output's comparisons of the same number would be chosen apart from it.

    Raises:
        ShieldError: naming the requirement, both outputs and the field."""
    if bindings is None:
        return
    for v in bounded:
        if v not in bindings.variables:
            continue
        mine = _fields(bindings.variables[v].ast)
        for u in (u for g in groups if v in g for u in g if u != v):
            shared = mine & _fields(bindings.variables[u].ast)
            if shared:
                topic, path = sorted(shared)[0]
                raise ShieldError(
                    f"{_reader(items, v, inputs)}: {v} is bounded by the inputs and reads "
                    f"{topic}.{'.'.join(path)}, which the output {u} reads too "
                    f"({_at(bindings, u)}): the shield decides a bound on {v}'s number "
                    f"alone, and {u}'s comparisons of the same number apart from it; bind "
                    f"no other output to {v}'s fields (write {u}'s comparisons over {v})")


def _refuse_clustered(items: list[CheckItem], bounded: list[str],
                      clusters: list[preds.Cluster], what: str = "bounded by the inputs",
                      inputs: Sequence[str] = ()) -> None:
    """Refuse an output ``bounded`` (bounded by the inputs, or ``what`` else: of a twist)
    also compared with another output (a cluster's numbers and the bounds, or the twist's
    scaling, would both set it).

    Raises:
        ShieldError: naming the requirement, the output and the comparisons."""
    for cl in clusters:
        both = [v for v in bounded if v in cl.variables and not cl.is_input]
        if both:
            raise ShieldError(
                f"{_reader(items, both[0], inputs)}: {both[0]} is {what} and compared with "
                f"other outputs ({', '.join(to_smv(a) for a in cl.atoms)}): the shield sets a "
                "cluster's numbers together, from its own table; not supported")


def enforced_pts(items: list[CheckItem]) -> list[Node]:
    """The pt formulas of enforced requirements (each has one: :func:`plan` checked)."""
    out = []
    for x in items:
        assert x.pt is not None
        out.append(x.pt)
    return out


def _variable(atom: Node) -> str:
    if atom.op == "ap":
        return ir.name_of(atom)
    sc = simple_comparison(atom)
    assert sc is not None  # game_atoms took it
    return sc[0]


def _message_constraint(atoms: list[Node], bindings: Bindings | None, notes: list[str],
                        group: MessageGroup, bounded: Collection[str] = ()) -> Node:
    """The valuations of ``atoms`` (outputs bound to one topic) some message gives, as a
    propositional IR formula (the conjunction of the negated cubes of the others), each
    given valuation kept in ``group``; TRUE when the bindings cannot be inverted (noted).
    A group of ``bounded`` outputs without such atoms has one valuation, the empty one (any
    message: its numbers are the runtime's, written into the proposal's message)."""
    if bindings is not None and not atoms and bounded:
        group.valuations.append(({}, {}, {}))
        return ir.TRUE
    if bindings is None or not atoms:
        return ir.TRUE
    names = ", ".join(to_smv(a) for a in atoms)
    if len(atoms) > MAX_GROUP_ATOMS:
        notes.append(f"the valuations of {names} are not related: more than "
                     f"{MAX_GROUP_ATOMS} atoms of one message")
        return ir.TRUE
    excluded: list[Node] = []
    numeric = {_variable(a) for a in atoms if a.op != "ap"}
    try:
        wanted_of = [_wanted(a, bindings) for a in atoms]
        for values in itertools.product((False, True), repeat=len(atoms)):
            wanted = [(name, expr, v) for (name, expr), v in zip(wanted_of, values)]
            got = solve(wanted)[0]
            if got is None:
                cube = ir.and_all(*(a if v else ir.not_(a) for a, v in zip(atoms, values)))
                excluded.append(ir.not_(cube))
                continue
            fields = {k: v for k, v in got.items() if k[1] != AGE}
            numbers = {}
            for var in sorted(numeric):
                x = _number(bindings.variables[var].ast, fields)
                if x is not None:
                    numbers[var] = x
            group.valuations.append(({to_smv(a): v for a, v in zip(atoms, values)},
                                     fields, numbers))
    except NotWritable as exc:
        notes.append(f"the valuations of {names} are not related (a message could give "
                     f"any of them as far as the shield knows): {exc}")
        group.valuations.clear()
        return ir.TRUE
    return _balanced_and(excluded)


def _message_model(group: MessageGroup, atoms: list[Node], bindings: Bindings | None,
                   clusters: list[preds.Cluster], notes: list[str],
                   bounded: Sequence[str] = ()) -> None:
    """Give ``group`` (its valuations solved) its model (:mod:`fretc.shield.message_model`),
    or note why the forms cannot make its decided values one message."""
    if bindings is None or not group.valuations:
        return
    names = ", ".join(group.variables)
    clustered = sorted(set(group.variables) & {v for c in clusters for v in c.variables})
    if clustered:
        notes.append(f"the decided values of {names} are not made one message by the Python "
                     f"and C forms: {', '.join(clustered)} in a comparison of several "
                     "variables")
        return
    kinds = {_variable(a): ("b" if a.op == "ap" else "n") for a in atoms}
    kinds.update({v: "n" for v in bounded if v in group.variables})
    specs: dict[str, tuple[str, str | None, Any]] = {}
    for a in atoms:
        sc = simple_comparison(a)
        specs[to_smv(a)] = ((ir.name_of(a), None, None) if a.op == "ap" or sc is None
                            else (sc[0], sc[1], float(sc[2])))
    model, why = model_of(group.variables, group.passed, kinds, bindings, group.valuations,
                          specs)
    if model is None and why:
        notes.append(f"the decided values of {names} are not made one message by the Python "
                     f"and C forms (the ROS 2 node makes its messages): {why}")
    group.model = model


def _balanced_and(xs: list[Node]) -> Node:
    """The conjunction of ``xs`` as a balanced tree (a chain of 2^12 cubes is thousands of
    levels deep: no recursion, the query's pickling to the game's worker included, takes
    it)."""
    if not xs:
        return ir.TRUE
    if len(xs) == 1:
        return xs[0]
    mid = len(xs) // 2
    return ir.and_(_balanced_and(xs[:mid]), _balanced_and(xs[mid:]))


def _number(e: Expr, fields: dict[tuple[str, tuple[str, ...]], Any]) -> float | None:
    """A numeric binding's value on the message ``fields`` (unset fields read 0), for the
    forms :mod:`fretc.testing.invert` inverts; None for any other."""
    if isinstance(e, Const) and isinstance(e.value, float) and not isinstance(e.value, bool):
        return e.value
    if isinstance(e, Field) and e.path and all(isinstance(x, str) for x in e.path):
        v = fields.get((e.topic, tuple(str(x) for x in e.path)), 0.0)
        return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None
    if isinstance(e, UnaryOp) and e.op == "-":
        x = _number(e.arg, fields)
        return None if x is None else -x
    if isinstance(e, FuncCall) and e.func == "abs" and len(e.args) == 1:
        x = _number(e.args[0], fields)
        return None if x is None else abs(x)
    return None


def _wanted(atom: Node, bindings: Bindings) -> tuple[str, Expr]:
    """``(variable, expression)`` whose truth is the atom's, over the bound message."""
    if atom.op == "ap":
        name = ir.name_of(atom)
        return name, bindings.variables[name].ast
    sc = simple_comparison(atom)
    assert sc is not None
    var, op, c = sc
    expr = bindings.variables[var].ast
    return var, BinOp(expr.col, op, expr, Const(expr.col, float(c)))
