"""``fretc shield --emit gwendolen``: the Safety Instrumented Function as a Gwendolen agent, its
AJPF verification environment and the properties AJPF checks on it (Safe-ROS, Benjumea,
Farrell, Dennis, FMAS 2025: Listings 2, 4 and 5, generated).

Files (``N`` the shield's name, ``A`` the agent):

* ``N.gwen``: the agent ``A`` (the component of the first enforced requirement: Safe-ROS's
  ``agilex_agent``). Each enforced requirement of the shape "[whenever|upon] C, A shall
  [timing] satisfy R", C a conjunction of boolean literals (or none) and R a conjunction of
  literals of boolean outputs, becomes plans ``+c: {guards} <- set_r, +r;``: on the belief
  (a percept, or a belief the agent added itself) that completes C, act to make each literal
  of R true (the action ``set_r``/``clear_r``) and believe it. ``never`` R makes R's
  negation hold instead (R one literal; the negation of a conjunction is a disjunction, not
  in the agent). A requirement without a condition is an initial goal; one whose condition
  is negated literals only (``whenever !i1``) holds from the start, so it gets an initial
  goal beside its plans. What has another shape (a number compared, a disjunction,
  a mode scope) is not in the agent: listed in its header, enforced by the other forms.
* ``N_env.java``: the verification environment (a ``VerificationofAutonomousSystemsEnvironment``
  as the paper's): at each perception every input variable is perceived or not by AJPF's
  boolean choice, so the model checker explores every input sequence.
* ``N.ail``: the AIL configuration (the agent, its builder, the environment).
* ``N.psl``: one property per requirement in the agent, ``[] (C -> <> R)`` over the agent's
  beliefs (``[] (C -> <> ~R)`` for ``never`` R).

**The untimed reading.** A Gwendolen agent has no clock and acts some reasoning cycles after
it perceives, so a deadline ("within 1 second", a counter in the shield's state) and even
"immediately" cannot be stated for AJPF: every property is the untimed reading the paper uses
(the response eventually follows the condition), and the files say so, requirement by
requirement. The deadlines are kept by the Python, C and ROS 2 forms, whose closed loop
``--prove`` checks with the timing.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

from fretc.compiler import ir
from fretc.compiler.ajpf import to_ajpf
from fretc.fretish import ast as A
from fretc.shield.build import Shield

__all__ = ["render_gwendolen", "agent_rules", "Rule"]

_TERM = re.compile(r"[a-z][A-Za-z0-9_]*\Z")


class Rule:
    """One requirement as the agent's plans: ``rid``, ``condition`` and ``response``
    ``[(variable, value)]`` literals, ``timing`` (FRET's key), or ``why`` it is not in the
    agent."""

    def __init__(self, rid: str, condition: list[tuple[str, bool]] | None = None,
                 response: list[tuple[str, bool]] | None = None, timing: str = "",
                 why: str = ""):
        self.rid, self.condition, self.response = rid, condition or [], response or []
        self.timing, self.why = timing, why


def _literals(e: Any) -> list[tuple[str, bool]] | None:
    """The literals of a conjunction of boolean variables and their negations, else None."""
    if isinstance(e, A.Var):
        return [(e.name, True)]
    if isinstance(e, A.Unary) and e.op == "!" and isinstance(e.operand, A.Var):
        return [(e.operand.name, False)]
    if isinstance(e, A.Binary) and e.op == "&":
        a, b = _literals(e.left), _literals(e.right)
        return None if a is None or b is None else a + b
    return None


def agent_rules(shield: Shield, compiled: Sequence[Any]) -> list[Rule]:
    """The enforced requirements of ``shield`` as :class:`Rule` (module docstring)."""
    by_id = {c.id: c for c in compiled}
    out = []
    for r in shield.requirements:
        req = by_id[r.id].entry.requirement
        if req.scope.kind != "null":
            out.append(Rule(r.id, why=f"a {req.scope.kind} scope: the agent has no mode"))
            continue
        cond = [] if req.condition.expr is None else _literals(req.condition.expr)
        resp = _literals(req.response)
        names = [v for v, _ in (cond or []) + (resp or [])]
        if cond is None or resp is None:
            out.append(Rule(r.id, why="its condition or response is not a conjunction of "
                                      "boolean variables (a number, a disjunction)"))
        elif any(v not in shield.outputs for v, _ in resp):
            out.append(Rule(r.id, why="its response reads an input"))
        elif not all(_TERM.match(v) for v in names):
            out.append(Rule(r.id, why="a variable that is not a Gwendolen term"))
        elif req.timing.kind == "never" and len(resp) != 1:
            out.append(Rule(r.id, why="'never' of a conjunction forbids a disjunction, and the "
                                      "agent's plans make literals true"))
        elif req.timing.kind == "never":  # never R: the agent makes R's negation hold
            (v, val), = resp
            out.append(Rule(r.id, cond, [(v, not val)], "never"))
        else:
            out.append(Rule(r.id, cond, resp, req.timing.kind or "null"))
    return out


def _plans(rules: list[Rule]) -> tuple[list[str], list[str]]:
    """The agent's plans and initial goals: per literal of the response, a plan that acts only
    while the literal does not hold yet (so each plan fires once per need, and the agent's
    pending intentions stay bounded for the model checker). A condition of negated
    literals only holds from the start, before any belief changes (the agent believes
    nothing yet): its plans fire on a belief's removal, which never comes when the input
    was never perceived, so an initial goal acts on it too."""
    plans, goals = [], []
    for rule in rules:
        if rule.why:
            continue
        for v, val in rule.response:
            act = f"{'set' if val else 'clear'}_{v}, {'+' if val else '-'}{v}"
            need = f"{'~B' if val else 'B'} {v}"
            if not rule.condition:
                goal = f"keep_{rule.rid.lower()}_{v} [perform]"
                goals.append(goal)
                plans.append(f"+!{goal} : {{{need}}} <- {act};")
                continue
            for k, (c, cval) in enumerate(rule.condition):
                others = [(w, b) for j, (w, b) in enumerate(rule.condition) if j != k]
                guard = ", ".join([("B " if b else "~B ") + w for w, b in others] + [need])
                plans.append(f"{'+' if cval else '-'}{c}: {{{guard}}} <- {act};")
            if not any(cval for _c, cval in rule.condition):  # (holds at the start)
                goal = f"start_{rule.rid.lower()}_{v} [perform]"
                goals.append(goal)
                guard = ", ".join([f"~B {c}" for c, _b in rule.condition] + [need])
                plans.append(f"+!{goal} : {{{guard}}} <- {act};")
    return plans, goals


def render_gwendolen(shield: Shield, compiled: Sequence[Any], base: str) -> dict[str, str]:
    """``{file name: text}`` of the form (module docstring); ``base`` the file stem."""
    rules = agent_rules(shield, compiled)
    by_id = {c.id: c for c in compiled}
    agent = next((by_id[r.id].entry.requirement.component for r in shield.requirements
                  if _TERM.match(by_id[r.id].entry.requirement.component or "")), "shield_agent")
    plans, goals = _plans(rules)
    inputs = [v for v in shield.inputs if v in shield.read and v not in shield.numbers
              and _TERM.match(v)]
    head = [f"// {base}.gwen: the Safety System {shield.name} as a Gwendolen agent, generated by",
            "// fretc shield (Safe-ROS's SIF). The untimed reading of each requirement: the agent",
            "// acts on what it perceives some reasoning cycles later; deadlines are kept by the",
            "// Python, C and ROS 2 forms of the same shield."]
    for rule in rules:
        if rule.why:
            head.append(f"// {rule.rid}: not in the agent ({rule.why}); enforced by the other "
                        "forms")
        else:
            head.append(f"// {rule.rid}: untimed reading of '{rule.timing}': the response"
                        + ("'s negation" if rule.timing == "never" else "")
                        + " eventually follows the condition")
    gwen = "\n".join(head + ["GWENDOLEN", f":name: {agent}", "", ":Initial Beliefs:", "",
                             ":Initial Goals:", *goals, "", ":Plans:", *plans]) + "\n"
    return {f"{base}.gwen": gwen,
            f"{base}_env.java": _environment(base, inputs),
            f"{base}.ail": (f"mas.file = {base}.gwen\nmas.builder = gwendolen.GwendolenMASBuilder\n"
                            f"env = {base}_env\n\nlog.warning = ajpf.MCAPLAgent\n"
                            "log.format = brief\n"),
            f"{base}.psl": _psl(rules, agent)}


def _psl(rules: list[Rule], agent: str) -> str:
    """One AJPF property per requirement in the agent (module docstring)."""
    lines = ["# AJPF properties of the generated agent: the untimed reading of each enforced",
             "# requirement (the response eventually follows the condition). Lines starting",
             "# with # are comments."]
    for rule in rules:
        if rule.why:
            lines.append(f"# {rule.rid}: not in the agent ({rule.why})")
            continue
        cond = ir.and_all(*(ir.ap(v) if b else ir.not_(ir.ap(v)) for v, b in rule.condition))
        resp = ir.and_all(*(ir.ap(v) if b else ir.not_(ir.ap(v)) for v, b in rule.response))
        phi = ir.G(ir.implies(cond, ir.F(resp))) if rule.condition else ir.F(resp)
        lines.append(f"# {rule.rid}: untimed reading of its '{rule.timing}' timing"
                     + (" (the response's negation)" if rule.timing == "never" else ""))
        lines.append(f"{re.sub(r'[^A-Za-z0-9_]', '_', rule.rid)}: {to_ajpf(phi, agent, {})}")
    return "\n".join(lines) + "\n"


def _environment(base: str, inputs: list[str]) -> str:
    """The verification environment (module docstring)."""
    percepts = "\n".join(
        f"        if (random_bool_generator.nextBoolean()) {{\n"
        f"            percepts.add(new Predicate(\"{v}\"));\n        }}" for v in inputs)
    return f"""// {base}_env.java: the AJPF verification environment of the generated agent (fretc
// shield): at each perception every input variable ({", ".join(inputs) or "none"}) is
// perceived or not by AJPF's boolean choice, so every input sequence is explored.
import java.util.HashSet;
import java.util.Set;

import ail.syntax.Message;
import ail.syntax.Predicate;
import gwendolen.mas.VerificationofAutonomousSystemsEnvironment;

public class {base}_env extends VerificationofAutonomousSystemsEnvironment {{

    @Override
    public Set<Predicate> generate_percepts() {{
        Set<Predicate> percepts = new HashSet<Predicate>();
{percepts}
        return percepts;
    }}

    @Override
    public Set<Message> generate_messages() {{
        return new HashSet<Message>();
    }}
}}
"""
