"""The AJPF properties of the generated Gwendolen agent (``fretc shield --emit gwendolen``,
:mod:`fretc.shield.emit_gwendolen`): one per enforced requirement, stating as much of its
timing as AJPF's property language can, and the release of each stop output.

Design notes: ARCHITECTURE.md, `shield/agent_properties.py`."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from fretc.compiler import ir
from fretc.compiler.ajpf import psl_label
from fretc.compiler.expressions import Expander, SemanticsError
from fretc.compiler.ir import Node
from fretc.compiler.printers import to_smv
from fretc.shield.build import Shield

__all__ = ["agent_properties", "scoped_inputs", "MAX_RELEASE_STEPS"]

#: the release is checked by stepping the shield over the environment's reachable states: at
#: most this many steps (beyond, it is not stated, and the file says so)
MAX_RELEASE_STEPS = 200_000


class _Unstated(Exception):
    """A requirement's part that the agent's atoms do not state; the message says why."""


def _formula(node: Node, atom_of: dict[tuple[str, str], str], agent: str) -> str:
    """The AJPF text of a boolean IR formula over the shield's atoms (``atom_of``: ("ap",
    variable) or ("cmp", FRET/SMV text) -> Gwendolen term).

    Raises:
        _Unstated: an atom that is not one of the shield's, a temporal function."""
    op = node.op
    if op in ("ap", "cmp"):
        key = (op, ir.name_of(node) if op == "ap" else to_smv(node))
        if key not in atom_of:
            raise _Unstated(f"{key[1]} is not an atom of the shield")
        return f"B({agent},{atom_of[key]})"
    if op == "true":
        return "T"
    if op == "false":
        return "F"
    if op == "!":
        return f"~({_formula(node.args[0], atom_of, agent)})"
    if op == "stream":  # (its state bit is the shield's, no belief: fretc.fretish.fret_since)
        raise _Unstated(f"{node.name} is a FRET stream read by its state bit, not a formula "
                        "over the shield's atoms")
    a = [_formula(x, atom_of, agent) for x in node.args]
    if op == "&":
        return f"({a[0]} & {a[1]})"
    if op == "|":
        return f"({a[0]} || {a[1]})"
    if op == "->":
        return f"({a[0]} -> {a[1]})"
    if op == "<->":
        return f"(({a[0]} -> {a[1]}) & ({a[1]} -> {a[0]}))"
    if op == "xor":
        return f"(({a[0]} & ~({a[1]})) || (~({a[0]}) & {a[1]}))"
    raise _Unstated(f"{to_smv(node)} is not a formula over the shield's atoms (a temporal "
                    "function)")


def _timing(kind: str, r: str, ticks: int | None) -> tuple[str, str]:
    """``(formula at the trigger, what it states)`` of the timing ``kind`` with response
    ``r`` (module docstring)."""
    n = "" if ticks is None else f" {ticks} tick(s)"
    if kind == "immediately":
        return r, "exact: the response at the tick of the trigger"
    if kind == "always":
        return f"([] {r})", "exact: the response at every tick from the trigger on"
    if kind == "never":
        return f"([] ~({r}))", "exact: the response at no tick from the trigger on"
    if kind == "within":
        return (f"(<> {r})", f"the response eventually; its deadline of{n} is not stated: "
                             "AJPF's LTL cannot count ticks")
    if kind == "next":
        return (f"(<> {r})", "the response eventually; 'at the next timepoint' is not "
                             "stated: AJPF's LTL has no next operator")
    if kind == "after":
        return (f"(~({r}) & (<> {r}))", f"not at the trigger, then eventually; the{n} are "
                                        "not counted: AJPF's LTL cannot count ticks")
    if kind == "for":
        return r, (f"the response at the trigger's tick; that it holds for{n} is not "
                   "stated: AJPF's LTL cannot count ticks")
    raise _Unstated(f"the '{kind}' timing is not stated for AJPF")


def _ticks(c: Any, period: Any) -> int | None:
    """The duration of ``c``'s timing in ticks of its period (else the shield's ``period``),
    None without one."""
    from fretc.compiler.semantics import duration_ticks

    req = c.entry.requirement
    if req.timing.duration is None:
        return None
    try:
        return int(duration_ticks(req.timing.duration, c.entry.tick_period or period, []))
    except (ValueError, TypeError, SemanticsError):
        return None


def _statement(c: Any, atom_of: dict[tuple[str, str], str], agent: str, period: Any
               ) -> tuple[str, str]:
    """``(property, what it states)`` of one enforced requirement ``c`` (compiled).

    Raises:
        _Unstated: what the agent's properties cannot state (module docstring)."""
    req = c.entry.requirement
    if req.scope.kind != "null":
        raise _Unstated(f"a '{req.scope.kind}' scope: the agent believes no mode")
    ex = Expander("pt", ir.TRUE, ir.TRUE)
    r = _formula(ex.bool(req.response), atom_of, agent)
    p, what = _timing(req.timing.kind or "null", r, _ticks(c, period))
    d = f"B({agent},decided)"
    if req.condition.expr is None:
        return f"(~{d} U ({d} & {p}))", what + "; the trigger: the first tick"
    cond = _formula(ex.bool(req.condition.expr), atom_of, agent)
    t = f"({d} & {cond})"
    if req.condition.kind == "holding":
        return f"[] ({t} -> {p})", what + "; the trigger: every tick of the condition"
    tp = f"({t} & {p})"
    return (f"[] (~{t} -> ({tp} R (~{t} || {tp})))",
            what + "; the trigger: each tick at which the condition becomes true")


def _variables(c: Any) -> set[str]:
    """The FRET variables ``c``'s condition and response read."""
    ex = Expander("pt", ir.TRUE, ir.TRUE)
    req = c.entry.requirement
    out: set[str] = set()
    for e in (req.condition.expr, req.response):
        if e is not None:
            try:
                out |= set(ir.variables(ex.bool(e)))
            except SemanticsError:
                pass
    return out


def scoped_inputs(shield: Shield, compiled: Sequence[Any], rids: Sequence[str],
                  input_terms: dict[str, str]) -> list[str]:
    """The input atoms (Gwendolen terms) an environment changes to check requirements
    ``rids``: those over the inputs they read and the inputs of the requirements that share an
    output with them, in the shield's order."""
    by_id = {c.id: c for c in compiled}
    reads = {r.id: _variables(by_id[r.id]) for r in shield.requirements if r.id in by_id}
    outs = set(shield.outputs)
    mine = set().union(*(reads.get(r, set()) for r in rids))
    near = {r for r, vs in reads.items() if vs & mine & outs}
    vars_ = mine | set().union(*(reads[r] for r in near))
    atom_var = {a.text: a.variable for m in shield.machines for a in m.inputs}
    return [term for text, term in input_terms.items() if atom_var.get(text) in vars_]


def agent_properties(shield: Shield, compiled: Sequence[Any], atoms: Any, agent: str,
                     props: Sequence[tuple[str, list[int], str]], valuations: Sequence[int]
                     ) -> tuple[str, dict[str, tuple[list[str], list[str]]]]:
    """The ``.psl`` text and, per property label, the input atoms its ``.ail`` changes
    (:func:`scoped_inputs`) and the proposals its environment makes (empty: every one; a
    release property: ``push`` only, module docstring)."""
    atom_of: dict[tuple[str, str], str] = {}
    for m in shield.machines:
        for a in (*m.inputs, *m.outputs):
            key = ("ap", a.variable) if a.op is None else ("cmp", a.text)
            atom_of.setdefault(key, atoms.term[a.text])
    input_terms = {t: atoms.term[t] for t in atoms.inputs}
    by_id = {c.id: c for c in compiled}
    lines = [f"# AJPF properties of the agent {agent} (fretc shield --emit gwendolen): one model",
             "# state per tick (the .ail's ajpf.transition_every_reasoning_cycle = false), where",
             "# the agent believes the tick's inputs and the outputs it decided; B(A,decided) from",
             "# its first tick on. AJPF's LTL has no next operator and cannot count ticks: what",
             "# each property leaves out is said above it. Lines starting with # are comments."]
    used: set[str] = set()
    scoped: dict[str, tuple[list[str], list[str]]] = {}
    for r in shield.requirements:
        c = by_id.get(r.id)
        if c is None:
            continue
        label = psl_label(r.id, used)
        lines.append(f"# {label}: {_one_line(c.text)}")
        try:
            formula, what = _statement(c, atom_of, agent, shield.period)
        except (_Unstated, SemanticsError) as exc:
            lines.append(f"#   not stated: {_one_line(str(exc))}")
            continue
        lines.append(f"#   {what}")
        lines.append(f"{label}: {formula}")
        scoped[label] = (scoped_inputs(shield, compiled, [r.id], input_terms), [])
    for rid, why in shield.monitored.items():
        lines.append(f"# {_one_line(rid)}: monitored only, not in the agent ({_one_line(why)})")
    lines += _releases(shield, compiled, atoms, agent, props, valuations, used, scoped,
                       input_terms)
    return "\n".join(lines) + "\n", scoped


def _one_line(text: str) -> str:
    from fretc.common.textsafe import one_line

    return one_line(text)


def _releases(shield: Shield, compiled: Sequence[Any], atoms: Any, agent: str,
              props: Sequence[tuple[str, list[int], str]], valuations: Sequence[int],
              used: set[str], scoped: dict[str, tuple[list[str], list[str]]],
              input_terms: dict[str, str]
              ) -> list[str]:
    """The release properties (module docstring) and their comments."""
    if shield.fallback is None or 0 not in valuations:
        return []
    push = props[0][1]
    quiet = " & ".join([f"~B({agent},{atoms.term[t]})" for t in atoms.inputs]
                       + [f"B({agent},proposal({props[0][0]}))"])
    out: list[str] = []
    start = 0
    for k, m in enumerate(shield.machines):
        fb = shield.fallback["atoms"][k]
        for j, a in enumerate(m.outputs):
            if a.op is not None or not fb[j] or push[start + j]:
                continue
            label = psl_label(f"release_{atoms.term[a.text]}", used)
            held = released_for_good(shield, k, j, [p for _n, p, _w in props], valuations,
                                     atoms, push)
            out.append(f"# {label}: once every input atom stays false and the controller "
                       f"keeps proposing push, {_one_line(a.text)} is eventually released "
                       "for good "
                       "(the shield's minimal interference)")
            if held is None:
                out.append(f"#   not stated: over {MAX_RELEASE_STEPS} steps to check it here")
                continue
            if not held:
                out.append("#   not stated: the shield itself may keep it (a run of the "
                           "environment after which it never ends)")
                continue
            out.append(f"{label}: [] (([] ({quiet})) -> (<> ([] ~B({agent},"
                       f"{atoms.term[a.text]}))))")
            readers = [r for r in m.requirements
                       if a.variable in _variables(next(c for c in compiled if c.id == r))]
            scoped[label] = (scoped_inputs(shield, compiled, readers, input_terms),
                             [props[0][0]])
        start += len(m.outputs)
    return out


def released_for_good(shield: Shield, k: int, j: int, proposals_: Sequence[Sequence[int]],
                      valuations: Sequence[int], atoms: Any, push: Sequence[int]
                      ) -> bool | None:
    """Whether output atom ``j`` of machine ``k`` ends false on every run from a state the
    environment reaches (every valuation of ``valuations`` and every proposal of
    ``proposals_``, global output atoms) that continues with every input atom false and the
    proposal ``push``; None past :data:`MAX_RELEASE_STEPS` steps. Stepped with
    :class:`fretc.shield.runtime.ShieldRuntime`'s own machine (its ``move`` and ``correct``)."""
    from fretc.shield.emit_python import tables
    from fretc.shield.runtime import ShieldRuntime

    rt = ShieldRuntime(tables(shield))
    mk, m = rt.machines[k], shield.machines[k]
    index = {t: i for i, t in enumerate(atoms.inputs)}
    start = sum(len(x.outputs) for x in shield.machines[:k])
    n_out = len(m.outputs)
    fb = tuple(shield.fallback["atoms"][k]) if shield.fallback is not None else None

    def ins_of(v: int) -> tuple[int, ...]:
        return tuple((v >> index[a.text]) & 1 for a in m.inputs)

    def step(s: tuple[int, ...], ins: tuple[int, ...], prop: tuple[int, ...]
             ) -> tuple[tuple[int, ...], tuple[int, ...]]:
        mk.state = s
        safe, nxt = mk.move(ins, prop)
        out = prop
        if not safe:
            out = mk.correct(ins, prop)
            nxt = mk.move(ins, out)[1]
        if fb is not None and mk._broken(ins, out):
            out = fb
        return out, nxt

    alphabet = {(ins_of(v), tuple(p[start:start + n_out])) for v in valuations
                for p in proposals_}
    seen = {mk.init}
    todo = [mk.init]
    steps = 0
    while todo:
        s = todo.pop()
        for ins, prop in sorted(alphabet):
            steps += 1
            if steps > MAX_RELEASE_STEPS:
                return None
            _o, nxt = step(s, ins, prop)
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    quiet, go = ins_of(0), tuple(push[start:start + n_out])
    for s in sorted(seen):
        path: dict[tuple[int, ...], int] = {}
        outs: list[int] = []
        while s not in path:
            path[s] = len(outs)
            o, s = step(s, quiet, go)
            outs.append(o[j])
        if any(outs[path[s]:]):  # (the cycle the run ends in)
            return False
    return True
