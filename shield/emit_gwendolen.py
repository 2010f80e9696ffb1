"""``fretc shield --emit gwendolen``: the Safety System as a Gwendolen agent that decides as the
shield decides, its AJPF verification environment and the properties AJPF checks on it
(Safe-ROS, Benjumea, Farrell, Dennis, FMAS 2025, Listings 2, 4 and 5: the SIF as a Gwendolen
agent, its environment and its AJPF properties; here generated from the requirements).

Design notes: ARCHITECTURE.md, `shield/emit_gwendolen.py`."""

from __future__ import annotations

import itertools
import re
from collections.abc import Sequence
from typing import Any

from fretc.common.textsafe import (gwendolen_comment, java_comment, java_string,
                                   properties_comment, properties_key, properties_value)
from fretc.shield.build import Shield
from fretc.shield.machine import Machine, evaluate
from fretc.shield.plan import ShieldError
from fretc.shield.runtime import BELIEF_LIMIT, CASES_LIMIT

__all__ = ["render_gwendolen", "AgentAtoms", "agent_atoms", "agent_name", "MAX_INPUT_ATOMS",
           "MAX_OUTPUT_ATOMS"]

#: the environment lists every input valuation: at most 2**16
MAX_INPUT_ATOMS = 16
#: the proposals are searched among the output valuations of a machine: at most 2**16
MAX_OUTPUT_ATOMS = 16

_TERM = re.compile(r"[a-z][A-Za-z0-9_]*\Z")
#: the agent's own names (its beliefs, actions and percepts), never an atom's
_RESERVED = frozenset({"mem", "decided", "assumption_broken", "tick", "proposal", "shield",
                       "publish", "v", "s", "none", "true", "false"})
_OP_WORDS = {"<=": "le", ">=": "ge", "!=": "ne", "<": "lt", ">": "gt", "=": "eq",
             "+": "plus", "-": "minus", "*": "times", "/": "div"}


def _term_of(text: str) -> str:
    """An atom's FRET/SMV text as a Gwendolen term: operators as words, a minus sign before a
    number ``m``, every other character not a letter or digit ``_``, a leading ``v_`` where the
    text does not start with a lower-case letter (``(linear_speed <= 0.15)`` ->
    ``linear_speed_le_0_15``)."""
    t = text.strip()
    while t.startswith("(") and t.endswith(")"):
        t = t[1:-1].strip()
    t = re.sub(r"(?<![A-Za-z0-9_.])-(?=\d)", "m", t)
    for op in ("<=", ">=", "!=", "<", ">", "=", "+", "-", "*", "/"):
        t = t.replace(f" {op} ", f"_{_OP_WORDS[op]}_")
    t = re.sub(r"[^A-Za-z0-9_]+", "_", t).strip("_") or "atom"
    return t if _TERM.match(t) else "v_" + t


class AgentAtoms:
    """The agent's names for the shield's atoms: ``inputs`` and ``outputs`` the atoms' FRET/SMV
    texts in the order of ``N_shield.java``'s ``INPUT_ATOMS`` and ``OUTPUT_ATOMS``; ``term``
    text -> Gwendolen term (unique, none of the agent's own names)."""

    def __init__(self, shield: Shield):
        self.inputs = list(dict.fromkeys(a.text for m in shield.machines for a in m.inputs))
        self.outputs = [a.text for m in shield.machines for a in m.outputs]
        self.term: dict[str, str] = {}
        used = set(_RESERVED)
        for text in [*self.inputs, *dict.fromkeys(self.outputs)]:
            base = _term_of(text)
            name, k = base, 2
            while name in used:
                name, k = f"{base}_{k}", k + 1
            used.add(name)
            self.term[text] = name


def agent_atoms(shield: Shield) -> AgentAtoms:
    """The agent's names for ``shield``'s atoms (:class:`AgentAtoms`)."""
    return AgentAtoms(shield)


def agent_name(shield: Shield, compiled: Sequence[Any]) -> str:
    """The agent: the component of the first enforced requirement that is a Gwendolen term,
    else ``shield_agent``."""
    by_id = {c.id: c for c in compiled}
    for r in shield.requirements:
        c = by_id.get(r.id)
        comp = c.entry.requirement.component if c is not None else ""
        if comp and _TERM.match(comp) and comp not in _RESERVED:
            return str(comp)
    return "shield_agent"


def _valuations(shield: Shield, atoms: AgentAtoms) -> list[int]:
    """The input valuations the environment gives (bit ``j`` the ``j``-th input atom): those
    whose every machine's ``env_ok`` holds (the values real numbers give the comparisons).

    Raises:
        ShieldError: more than :data:`MAX_INPUT_ATOMS` input atoms."""
    n = len(atoms.inputs)
    if n > MAX_INPUT_ATOMS:
        raise ShieldError(f"the Gwendolen form's environment lists every input valuation: "
                          f"{n} input atoms, at most {MAX_INPUT_ATOMS}")
    index = {t: j for j, t in enumerate(atoms.inputs)}
    out = []
    for v in range(1 << n):
        if all(evaluate(m.nodes, m.env_ok,
                        [(v >> index[a.text]) & 1 for a in m.inputs]
                        + [0] * (len(m.outputs) + len(m.init)))
               for m in shield.machines):
            out.append(v)
    return out


def _consistent(m: Machine) -> list[tuple[int, ...]]:
    """The output valuations of machine ``m`` that one message gives (its ``ctl_ok``).

    Raises:
        ShieldError: more than :data:`MAX_OUTPUT_ATOMS` output atoms."""
    n = len(m.outputs)
    if n > MAX_OUTPUT_ATOMS:
        raise ShieldError(f"the Gwendolen form's environment searches the controller's "
                          f"proposals among the output valuations: {n} output atoms in one "
                          f"component, at most {MAX_OUTPUT_ATOMS}")
    pad_in, pad_bits = [0] * len(m.inputs), [0] * len(m.init)
    return [v for v in itertools.product((0, 1), repeat=n)
            if evaluate(m.nodes, m.ctl_ok, pad_in + list(v) + pad_bits)]


def proposals(shield: Shield) -> list[tuple[str, list[int], str]]:
    """The controller's proposals in the environment: ``(name, output atoms, what)``:
    ``push`` (per machine, the valuation one message gives nearest every atom the opposite
    of the fallback's, ties to the first in binary order: the controller that always wants to
    move on) and ``stop`` (the fallback's atoms) when the shield has a fallback."""
    push: list[int] = []
    stop: list[int] | None = [] if shield.fallback is not None else None
    for k, m in enumerate(shield.machines):
        want = ([1 - b for b in shield.fallback["atoms"][k]] if shield.fallback is not None
                else [1] * len(m.outputs))
        cands = _consistent(m) or [tuple(want)]
        push += list(min(cands, key=lambda v: sum(a != b for a, b in zip(v, want))))
        if stop is not None and shield.fallback is not None:
            stop += list(shield.fallback["atoms"][k])
    out = [("push", push, "every output atom the opposite of the fallback's, as near as one "
                          "message allows")]
    if stop is not None and stop != push:
        out.append(("stop", stop, "the fallback's outputs"))
    return out


def _machine_ctx(shield: Shield, atoms: AgentAtoms) -> list[dict[str, Any]]:
    """Each machine's data for ``gwendolen_shield.java.j2``."""
    index = {t: j for j, t in enumerate(atoms.inputs)}
    out, o_start, b_start = [], 0, 0
    p = len(shield.preferences)
    for k, m in enumerate(shield.machines):
        weights = sorted(shield.weights(k).items())
        out.append({
            "inputs": [index[a.text] for a in m.inputs], "out_start": o_start,
            "n_out": len(m.outputs), "bit_start": b_start, "n_bits": len(m.init),
            "safe": m.safe, "nodes": ";".join(f"{v},{lo},{hi}" for v, lo, hi in m.nodes),
            "next": list(m.next), "assumed": list(m.assumed),
            "w_atom": [j for j, _w in weights], "w_want": [int(w[0]) for _j, w in weights],
            "w_weight": [w[1] for _j, w in weights], "big": 1 << p, "env_ok": m.env_ok,
            "fallback": (list(shield.fallback["atoms"][k]) if shield.fallback is not None
                         else None)})
        o_start += len(m.outputs)
        b_start += len(m.init)
    return out


def _bits_term(functor: str, bits: Sequence[int]) -> str:
    return f"{functor}({','.join(str(int(b)) for b in bits)})" if bits else functor


def _agent(shield: Shield, atoms: AgentAtoms, agent: str, base: str, notes: list[str]) -> str:
    """The agent's text (module docstring)."""
    n = len(atoms.outputs)
    init = [int(b) for m in shield.machines for b in m.init]
    rules = []
    for j, text in enumerate(atoms.outputs):
        pattern = ",".join("1" if k == j else "_" for k in range(n))
        rules.append(f"{atoms.term[text]} :- mem(_, v({pattern}), _);")
    rules.append(f"decided :- mem(_, v({','.join('_' for _k in range(n))}), _);")
    rules.append("assumption_broken :- mem(_, _, 1);")
    # (every text from the requirements through gwendolen_comment: one line, no control
    # character; a line break in a requirement id would start a line of the agent's code)
    com = gwendolen_comment
    head = [f"// {base}.gwen: the Safety System {com(shield.name)} as a Gwendolen agent, "
            "generated by fretc shield.",
            "// Each tick it decides with the shield's machine (its action shield/4, "
            f"{base}_shield.java),",
            "// believes the outputs and the state the machine gives, and publishes the outputs: "
            "the stop",
            "// is held and released as the Python, C and ROS 2 forms hold and release it.",
            "// Percepts: " + ", ".join(atoms.term[t] for t in atoms.inputs) + "; the "
            "controller's proposal as proposal(NAME).",
            "// Beliefs: " + ", ".join(f"{atoms.term[t]} ({com(t)})" for t in atoms.outputs)
            + ".",
            *[f"// {com(line)}" for line in notes]]
    return "\n".join([
        *head, "GWENDOLEN", f":name: {agent}", "", ":Initial Beliefs:",
        f"mem({_bits_term('s', init)}, none, 0)", "", ":Reasoning Rules:", *rules, "",
        ":Initial Goals:", "", ":Plans:",
        "+tick(Tick) : {B mem(State, Was, Broken)} <- shield(State, Out, Next, Now), "
        "-mem(State, Was, Broken), +mem(Next, Out, Now), publish(Out);", ""])


def _ail(base: str, settings: Sequence[str] = ()) -> str:
    """An ``.ail`` file (a Java properties file, read by AIL's ``AILConfig``): the agent
    ``base`` and ``settings`` (lines already escaped: :func:`_ail_setting`)."""
    return "\n".join([f"mas.file = {properties_value(base + '.gwen')}",
                      "mas.builder = gwendolen.GwendolenMASBuilder",
                      f"env = {properties_value(base + '_env')}",
                      "# AJPF's model states are the ticks (the choice of each tick's percepts)",
                      "ajpf.transition_every_reasoning_cycle = false", *settings,
                      "log.warning = ajpf.MCAPLAgent", "log.format = brief", ""])


def render_gwendolen(shield: Shield, compiled: Sequence[Any], base: str) -> dict[str, str]:
    """``{file name: text}`` of the form (module docstring); ``base`` the file stem.

    Raises:
        ShieldError: more input or output atoms than the environment lists
            (:data:`MAX_INPUT_ATOMS`, :data:`MAX_OUTPUT_ATOMS`)."""
    from fretc.compiler.codegen import _env  # lazy: Jinja2 only when the form is written
    from fretc.shield.agent_properties import agent_properties

    atoms = agent_atoms(shield)
    agent = agent_name(shield, compiled)
    valuations = _valuations(shield, atoms)
    props = proposals(shield)
    psl, scoped = agent_properties(shield, compiled, atoms, agent, props, valuations)
    env = _env()
    env.filters["jstr"] = java_string  # (every text a Java file embeds: textsafe)
    env.filters["jcom"] = java_comment
    ctx = {"p": base, "name": shield.name, "agent": agent, "digest": shield.digest,
           "requirements": [r.id for r in shield.requirements],
           "input_atoms": [atoms.term[t] for t in atoms.inputs],
           "output_atoms": [atoms.term[t] for t in atoms.outputs],
           "init": [int(b) for m in shield.machines for b in m.init],
           "machines": _machine_ctx(shield, atoms), "valuations": valuations,
           "valuation_texts": [_valuation_text(v, atoms) for v in valuations],
           "proposals": props, "cases_limit": CASES_LIMIT, "belief_limit": BELIEF_LIMIT}
    files = {f"{base}.gwen": _agent(shield, atoms, agent, base, _notes(shield)),
             f"{base}_shield.java": env.get_template("gwendolen_shield.java.j2").render(**ctx),
             f"{base}_env.java": env.get_template("gwendolen_env.java.j2").render(**ctx),
             f"{base}.ail": _ail(base), f"{base}.psl": psl}
    for label, (inputs, chosen) in scoped.items():
        settings = [_ail_comment(f"{label}: the environment changes only "
                                 f"{', '.join(inputs) or 'no input'} (the others stay false)"),
                    _ail_setting(f"{base}_env.inputs", ",".join(inputs))]
        if chosen:
            settings += [_ail_comment(f"{label}: the controller proposes only "
                                      f"{', '.join(chosen)}"),
                         _ail_setting(f"{base}_env.proposals", ",".join(chosen))]
        files[f"{base}_{label}.ail"] = _ail(base, settings)
    return files


def _ail_comment(text: str) -> str:
    """One ``#`` comment line of an ``.ail`` file (a properties file: textsafe)."""
    return "# " + properties_comment(text)


def _ail_setting(key: str, value: str) -> str:
    """One ``key = value`` line of an ``.ail`` file, both escaped as ``Properties.store``
    escapes them (textsafe: no ``\\`` at its end continues the line)."""
    return f"{properties_key(key)} = {properties_value(value)}"


def _valuation_text(v: int, atoms: AgentAtoms) -> str:
    on = [atoms.term[t] for j, t in enumerate(atoms.inputs) if (v >> j) & 1]
    return "+".join(on) or "none"


def _notes(shield: Shield) -> list[str]:
    """What the agent leaves to the other forms: the numbers behind the comparisons, the
    requirements only monitored."""
    out = ["It decides the truth of every output atom; the numbers that give them are the "
           "hosts' (the Python, C and ROS 2 forms)."]
    for rid, why in shield.monitored.items():
        out.append(f"{rid}: monitored only, not in the agent ({why}).")
    return out
