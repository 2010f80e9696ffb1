"""Random safety requirement sets for the shield's property tests, and the checks every
shield must pass on a random run (independent of the game: brute force over the node table
for the choice, FRET's interval semantics for the verdicts).

Inputs ``a``, ``b`` (booleans) and ``m`` (a mode); outputs ``x``, ``y`` (booleans) and ``v``
(a number compared with 1 and 2). Requirements mix every scope kind, both condition kinds
and the safety timings (``immediately``, ``next``, ``within``, ``for``, ``always``,
``never``, ``until``, ``before``)."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
from hypothesis import strategies as st

from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
from fretc.monitors.interval import verdict_of
from fretc.shield.build import build_shield
from fretc.shield.machine import evaluate

INPUTS = ["a", "b", "m"]
OUTPUTS = ["x", "y", "v"]
SCOPES = ["", "in m mode ", "when not in m mode ", "after m ", "before m ", "only in m mode "]
CONDITIONS = ["", "whenever a ", "upon a ", "whenever a & b ", "upon b | x ", "if !a ",
              "whenever y "]
RESPONSES = ["x", "!x", "x & y", "x | y", "v <= 1", "v > 2", "!y -> x", "y", "v = 2"]
TIMINGS = ["immediately ", "at the next timepoint ", "within 2 ticks ", "within 3 ticks ",
           "for 2 ticks ", "always ", "never ", "until b ", "before a "]


@st.composite
def requirement_sets(draw, most: int = 3) -> str:
    """The text of a .fret file of 1 .. ``most`` requirements (module docstring)."""
    n = draw(st.integers(1, most))
    lines = []
    for k in range(n):
        scope = draw(st.sampled_from(SCOPES))
        cond = draw(st.sampled_from(CONDITIONS))
        timing = draw(st.sampled_from(TIMINGS))
        resp = draw(st.sampled_from(RESPONSES))
        lines.append(f"R{k + 1}: {scope}{cond}sw shall {timing}satisfy {resp}")
    return "\n".join(lines) + "\n"


def compile_text(text: str, folder: Path, name: str = "reqs.fret"):
    """The compiled requirements of ``text`` written to ``folder/name``."""
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return compile_entries(load_requirements([path]))


def build(compiled, **kwargs):
    """The shield of ``compiled`` over :data:`INPUTS`/:data:`OUTPUTS`, games in process."""
    return build_shield(compiled, INPUTS, OUTPUTS, fork=False, **kwargs)


@st.composite
def runs(draw, length: int = 40) -> list[tuple[dict, dict]]:
    """``length`` ticks of random inputs and random proposals."""
    out = []
    for _ in range(draw(st.integers(1, length))):
        ins = {"a": draw(st.booleans()), "b": draw(st.booleans()), "m": draw(st.booleans())}
        prop = {"x": draw(st.booleans()), "y": draw(st.booleans()),
                "v": draw(st.sampled_from([0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0]))}
        out.append((ins, prop))
    return out


def atoms_of(machine, values: dict) -> list[int]:
    """The output atoms' values (0/1) of one tick's outputs."""
    return [int(a.value(values if a.op == "pred" else values[a.variable]))
            for a in machine.outputs]


def safe(machine, state, ins: dict, outs: list[int]) -> bool:
    """The node table's ``safe`` for the input values ``ins`` and output atoms ``outs``."""
    values = ([int(a.value(ins if a.op == "pred" else ins[a.variable])) for a in machine.inputs]
              + list(outs) + list(state))
    return evaluate(machine.nodes, machine.safe, values)


def best_cost(machine, state, ins: dict, prop: list[int], weights: dict) -> int | None:
    """The least cost (changes, then preferences) of a safe output valuation, by brute force
    over every valuation; None when none is safe."""
    big = 1 << len(weights)
    best = None
    for outs in itertools.product((0, 1), repeat=len(prop)):
        if safe(machine, state, ins, list(outs)):
            c = cost(outs, prop, weights, big)
            best = c if best is None or c < best else best
    return best


def cost(outs, prop, weights: dict, big: int) -> int:
    """The cost of ``outs`` against ``prop`` (:func:`fretc.shield.machine` docstring)."""
    c = 0
    for j, (o, p) in enumerate(zip(outs, prop)):
        if o != p:
            c += big
            if j in weights:
                want, w = weights[j]
                c += (w if o != want else 0) - (w if p != want else 0)
    return c


def verdicts(compiled, trace: list[dict]) -> dict[str, str]:
    """FRET's finite-trace verdict of each requirement on ``trace`` by the interval
    semantics (the audit's judge)."""
    n = len(trace)
    cols = {k: np.array([row[k] for row in trace]) for k in trace[0]}
    return {c.id: verdict_of(c.entry.requirement, cols, n) for c in compiled}


def finite(x: float) -> bool:
    """Whether ``x`` is a finite number."""
    return math.isfinite(x)


def fault_kind(d) -> str:
    """The C runner's ``fault`` column for the Python form's decision ``d``: the first of its
    notes, ``input`` (an input unread), ``lost`` (a machine that no longer knows its state),
    ``proposal`` (a proposal replaced), or empty."""
    if not d.fault:
        return ""
    if d.fault.startswith("input "):
        return "input"
    return "lost" if d.lost else d.fault.split(" ")[0]


def csv_cell(x) -> str:
    """A value as a cell of the C runner's input CSV (``true``/``false``, or a float's
    repr: ``nan``, ``inf`` too)."""
    return ("true" if x else "false") if isinstance(x, bool) else repr(float(x))


def fret_var(name: str, kind: str, assignment: str = "", data_type: str = "boolean") -> dict:
    """One variable of a FRET project export (component ``ctrl`` of project ``P``)."""
    return {"project": "P", "component_name": "ctrl", "variable_name": name,
            "idType": kind, "dataType": data_type, "assignment": assignment}


def fret_export(tmp_path: Path, texts: list[str], variables: list[dict]) -> Path:
    """A FRET project export ``p.json`` of the requirements ``texts`` (R1, R2, ...) and
    ``variables`` (from :func:`fret_var`)."""
    import json

    path = tmp_path / "p.json"
    path.write_text(json.dumps({"requirements": [
        {"reqid": f"R{k + 1}", "project": "P", "fulltext": t} for k, t in enumerate(texts)],
        "variables": variables}), encoding="utf-8")
    return path


@st.composite
def unscoped_sets(draw, conditions: list[str], timings: list[str], responses: list[str]) -> str:
    """The text of a .fret file of 1 .. 3 requirements of no scope, from the given
    conditions, timings and responses."""
    lines = []
    for k in range(draw(st.integers(1, 3))):
        lines.append(f"R{k + 1}: {draw(st.sampled_from(conditions))}sw shall "
                     f"{draw(st.sampled_from(timings))}satisfy "
                     f"{draw(st.sampled_from(responses))}")
    return "\n".join(lines) + "\n"


def shield_or_assume(text: str, inputs: list[str], outputs: list[str]):
    """(compiled requirements, shield) of the .fret ``text``; a set the shield refuses is
    rejected as a hypothesis example (``assume(False)``)."""
    import tempfile

    from hypothesis import assume

    from fretc.shield.plan import ShieldError

    with tempfile.TemporaryDirectory() as tmp:
        compiled = compile_text(text, Path(tmp))
        try:
            shield = build_shield(compiled, inputs, outputs, fork=False)
        except ShieldError:
            assume(False)
            raise
    return compiled, shield
