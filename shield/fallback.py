"""The shield's fallback: the outputs of a tick whose inputs cannot be read.

A tick whose inputs cannot be read (a NaN, a missing value, a sensor that stopped: the
forms' checks, :mod:`fretc.shield.runtime`) leaves the shield's state as it was, so the
shield cannot tell which outputs its state and the unknown inputs allow. The fallback is
outputs that need neither: a valuation of the output atoms in every machine's ``robust``
root (:mod:`fretc.shield.synthesis`), ``safe`` from every state of the winning region with
every input the environment may give. Safe-ROS's is the stop (``stopped``, ``forwarded_zero``,
``stop_requested``, zero speeds): each of R2, R3, R4, R6 holds whatever came before and
whatever the scan says.

Design notes: ARCHITECTURE.md, `shield/fallback.py`."""

from __future__ import annotations

import math
import tomllib
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from fretc.shield.machine import Machine
from fretc.shield.message_model import group_atoms, table_of
from fretc.shield.plan import ShieldError
from fretc.shield.runtime_values import as_message, nearest, term_value, term_variables

__all__ = ["fallback_of", "parse_fallback", "declared_fallback"]


def parse_fallback(text: str | None) -> dict[str, bool | float] | None:
    """``--fallback``'s text -> output variable -> value: ``"stopped, !moving, speed=0"``
    (a boolean named for true, ``!`` before it for false, ``name=number`` for a number;
    None for no text).

    Raises:
        ShieldError: a part that is none of these, or a variable named twice."""
    if text is None:
        return None
    out: dict[str, bool | float] = {}
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        if "=" in part:
            name, _eq, number = (x.strip() for x in part.partition("="))
            try:
                value: bool | float = float(number)
            except ValueError:
                raise ShieldError(f"--fallback: {part!r}: {number!r} is no number") from None
        else:
            name, value = (part[1:].strip(), False) if part.startswith("!") else (part, True)
        if not name or name in out:
            raise ShieldError(f"--fallback: {part!r}: " + ("a name is missing" if not name else
                                                          f"{name} is named twice"))
        out[name] = value
    return out


def declared_fallback(bindings_file: str | Path | None) -> dict[str, bool | float] | None:
    """The ``[shield] fallback`` table of a binding file (output variable -> true, false or
    a number), None when the file or the table is absent.

    Raises:
        ShieldError: not a table of booleans and numbers."""
    if bindings_file is None:
        return None
    doc = tomllib.loads(Path(bindings_file).read_text(encoding="utf-8"))
    table = doc.get("shield", {})
    if not isinstance(table, dict) or "fallback" not in table:
        return None
    fb = table["fallback"]
    if not isinstance(fb, dict) or not all(
            isinstance(k, str) and isinstance(v, (bool, int, float)) for k, v in fb.items()):
        raise ShieldError(f"{bindings_file}: [shield] fallback must map output variables to "
                          "true, false or a number, e.g. { stopped = true, speed = 0.0 }")
    return {k: (v if isinstance(v, bool) else float(v)) for k, v in fb.items()}


def _truth(spec: tuple[str, str | None, Any], values: dict[str, Any]) -> bool | None:
    """An output atom's truth on declared values (None when it reads an undeclared one)."""
    var, op, c = spec
    if op == "pred":
        return bool(term_value(c, values)) if term_variables(c) <= values.keys() else None
    if var not in values:
        return None
    x = values[var]
    if op is None:
        return bool(x)
    return bool({"<": x < c, "<=": x <= c, ">": x > c, ">=": x >= c, "=": x == c,
                 "!=": x != c}[op])


def _valuation(m: Machine, wanted: list[bool | None], prefer: dict[str, bool]) -> list[int]:
    """The output atoms of the path the ``robust`` root takes from its top (module
    docstring): at an output atom's node, its wanted value (declared, else preferred, else
    false) unless that branch is false; untested atoms their wanted value."""
    n_in = len(m.inputs)
    bits = [int(bool(w)) if w is not None else int(prefer.get(a.text, False))
            for w, a in zip(wanted, m.outputs)]
    n = m.robust
    while n > 1:
        var, lo, hi = m.nodes[n]
        j = var - n_in
        assert 0 <= j < len(m.outputs)  # (robust reads the output atoms only)
        first, other = (hi, lo) if bits[j] else (lo, hi)
        if first == 0:
            bits[j] = 1 - bits[j]
            first = other
        n = first
    return bits


def fallback_of(machines: Sequence[Machine], declared: dict[str, bool | float] | None,
                outputs: Sequence[str], numbers: frozenset[str], integers: Sequence[str],
                prefer: Sequence[tuple[str, bool]] = ()
                ) -> tuple[dict[str, Any] | None, list[str]]:
    """The fallback (module docstring) as the runtimes' tables hold it, ``{"outputs":
    {variable: value}, "atoms": [[0/1 per output atom] per machine]}``, or None; and notes.

    Raises:
        ShieldError: a declared fallback that names no output, gives a boolean a number or
            a number a boolean, or is not safe from every state whatever the inputs (the
            atom and the requirements named)."""
    declared = dict(declared or {})
    unknown = [v for v in declared if v not in outputs]
    if unknown:
        raise ShieldError("--fallback / [shield] fallback names " + ", ".join(unknown)
                          + ", not an output (" + ", ".join(outputs) + ")")
    for v, x in declared.items():
        if (v in numbers) == isinstance(x, bool):
            raise ShieldError(f"the fallback gives {v} {x!r}: {v} is "
                              + ("a number" if v in numbers else "a boolean"))
        if not isinstance(x, bool) and not math.isfinite(x):
            raise ShieldError(f"the fallback gives {v} {x!r}: a fallback is finite")
    pref = dict(prefer)
    values: dict[str, Any] = dict(declared)
    atoms: list[list[int]] = []
    for m in machines:
        if m.robust == 0:
            if declared:
                raise ShieldError(f"no fallback is safe for {', '.join(m.requirements)}: "
                                  "no outputs keep them from every state whatever the inputs "
                                  "(leave --fallback / [shield] fallback out)")
            return None, [f"no fallback: no outputs keep {', '.join(m.requirements)} from "
                          "every state whatever the inputs; at a tick whose inputs cannot "
                          "be read the shield gives no outputs"]
        wanted = [_truth(a.spec, declared) for a in m.outputs]
        bits = _valuation(m, wanted, pref)
        wrong = [a.text for a, w, b in zip(m.outputs, wanted, bits)
                 if w is not None and int(w) != b]
        if wrong:
            raise ShieldError(f"the fallback ({_shown(declared)}) does not keep "
                              f"{', '.join(m.requirements)} from every state whatever the "
                              f"inputs: {', '.join(wrong)} must be "
                              + ", ".join(str(bool(b)).lower() for a, w, b in
                                          zip(m.outputs, wanted, bits)
                                          if w is not None and int(w) != b))
        atoms.append(bits)
        values.update(_numbers(m, bits, declared, integers))
        values.update(_one_message(m, bits, values, declared, integers))
    return {"outputs": {v: values[v] for v in outputs if v in values}, "atoms": atoms}, []


def _one_message(m: Machine, bits: list[int], values: dict[str, Any],
                 declared: dict[str, Any], integers: Sequence[str]) -> dict[str, Any]:
    """The fallback's values of each message group of ``m`` made one message (KP-124,
    :func:`fretc.shield.runtime_values.as_message`: ``stopped`` with ``linear_speed = 0``
    beside a ``forwarded_zero`` false is a message only with another field moving), the
    outputs no requirement reads among them read from it (a declared one written into it).

    Raises:
        ShieldError: declared values no one message gives."""
    out: dict[str, Any] = {}
    texts = [a.text for a in m.outputs]
    specs = [a.spec for a in m.outputs]
    for g in m.messages:
        if g.model is None:
            continue
        table = table_of(g.model, texts, group_atoms(texts, g.valuations), specs,
                         [v for v in m.output_variables if v in integers])
        own = [v for v, _k, _t in table["reads"] if v not in table["passed"]]
        got = as_message(table, tuple(bits), specs, {v: values[v] for v in own},
                         {v: declared[v] for v in table["passed"] if v in declared})
        wrong = [f"{v}={declared[v]!r} (the message gives {got[v]!r})" for v in got
                 if v in declared and got[v] != declared[v]]
        if wrong:
            raise ShieldError("the fallback's values are no one message the bindings give: "
                              + ", ".join(wrong))
        out.update(got)
    return out


def _shown(declared: dict[str, Any]) -> str:
    return ", ".join(f"{k}={str(v).lower() if isinstance(v, bool) else v}"
                     for k, v in declared.items())


def _numbers(m: Machine, bits: list[int], declared: dict[str, Any], integers: Sequence[str]
             ) -> dict[str, Any]:
    """The output values of machine ``m``'s fallback valuation ``bits`` (module docstring)."""
    out: dict[str, Any] = {}
    texts = [a.text for a in m.outputs]
    for c in m.clusters:
        key = sum(bits[j] << k for k, j in enumerate(c["atoms"]))
        out.update({v: x for v, x in c["numbers"].get(key, {}).items() if v not in declared})
    given: dict[str, float] = {}
    for g in m.messages:
        for vals, _fields, nums in g.valuations:
            if all(vals.get(t, bits[j]) == bool(bits[j]) for j, t in enumerate(texts)
                   if t in vals):
                given.update(nums)
    bounded = {b["variable"] for b in m.bounds}
    for v in m.output_variables:
        idx = [j for j, a in enumerate(m.outputs) if a.variable == v and a.op != "pred"]
        if v in bounded and not idx and v not in declared:
            out[v] = 0.0  # (rest: its bounds read the inputs, :mod:`fretc.shield.runtime_bounds`)
        if v in declared or v in out or not idx:
            continue
        if m.outputs[idx[0]].op is None:
            out[v] = bool(bits[idx[0]])
            continue
        specs = [m.outputs[j].spec for j in idx]
        truths = [bits[j] for j in idx]
        x = given.get(v)
        if all(_truth(s, {v: 0.0}) == bool(t) for s, t in zip(specs, truths)):
            out[v] = 0.0  # (rest whenever the valuation's truths allow it)
        elif x is not None and math.isfinite(x) and all(
                _truth(s, {v: x}) == bool(t) for s, t in zip(specs, truths)) and (
                v not in integers or x == math.floor(x)):
            out[v] = x
        else:
            out[v] = nearest(specs, truths, 0.0, v in integers)
    return out
