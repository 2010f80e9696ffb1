"""FRET Component Specifications for NASA's Ogma (``fretc FILE --emit ogma``).

Design notes: ARCHITECTURE.md, `compiler/ogma.py`."""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from typing import TYPE_CHECKING

from fretc.common.textsafe import one_line
from fretc.compiler import ir
from fretc.compiler.cocospec import (Contract, component_of, contracts, declared_variables,
                                     used_types)
from fretc.compiler.ir import name_of
from fretc.compiler.printers import mangle, to_smv

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled

__all__ = ["emit_ogma", "ogma_refusal"]

#: BNFC's Integer and Double tokens, and its Ident (Ogma's SMV grammar, SMV.cf)
_NUMBER = re.compile(r"[0-9]+|[0-9]+\.[0-9]+(?:e-?[0-9]+)?")
_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_']*")
_NOT_IN_SMV = {"fn": "function ({})", "call": "function ({})", "pre": "function ({})",
               "neg": "unary minus", "ite": "an if-then-else of numbers",
               "future": "future-time function ({}): the pt formula needs the future"}


def ogma_refusal(pt: ir.Node) -> str | None:
    """Why Ogma's SMV expression grammar (``ogma-language-smv``'s ``SMV.cf``) cannot read
    the pt formula ``pt``, or None when it can."""
    for x in ir.walk(pt):
        if x.op in _NOT_IN_SMV:
            return "Ogma's SMV grammar has no " + _NOT_IN_SMV[x.op].format(x.name)
        if x.op == "arith" and x.name in ("mod", "^"):
            return f"Ogma's SMV grammar has no {x.name} operator"
        if x.op == "num" and not _NUMBER.fullmatch(name_of(x)):
            return f"Ogma's SMV grammar has no literal {name_of(x)} (its Integer or Double)"
        if x.op in ("ap", "var") and not _IDENT.fullmatch(mangle(name_of(x))):
            return (f"the name {mangle(name_of(x))} is no identifier of Ogma's SMV grammar "
                    "(a letter first)")
    return None


def emit_ogma(compiled: Sequence[Compiled]) -> tuple[dict[str, str],
                                                     list[tuple[str, str, str]],
                                                     list[str]]:
    """Ogma's component specifications of ``compiled`` (``compiler.build.Compiled`` list):
    ``({file stem: JSON text}, [(stem, requirement id, why left out)], [notes])``, one file
    per component, stem ``<component>Spec`` as FRET names it (written as ``STEM.json``);
    the notes name the variables written as inputs that the glossary declares otherwise.
    Every name is the contract's Lustre name (:meth:`fretc.compiler.cocospec.Contract.
    lustre_name`): ``Other_variables``, ``ptLTL`` and ``CoCoSpecCode`` read the same names
    (``node`` is ``node_v`` in all three). Same input, same bytes."""
    out: dict[str, str] = {}
    skipped: list[tuple[str, str, str]] = []
    notes: list[str] = [f"{one_line(c.id)}: free-form, no formula and no component: left out"
                        for c in compiled if c.freeform]
    for contract in contracts(compiled):
        items = [c for c in compiled if c.requirement is not None and not c.freeform
                 and component_of(c) == contract.component]
        types, fret, inputs, outputs = declared_variables(items)
        used_types(items, types)
        reqs, variables = [], {}
        for name in inputs + outputs:
            variables[name] = types.get(name)
        lustre_of = {rid: expr for rid, _t, expr, _a in contract.guarantees}
        for c in items:
            f = c.formalization
            if f is None or c.error is not None:
                skipped.append((contract.name, c.id,
                                "free-form" if c.freeform else "not formalized"))
                continue
            why = ogma_refusal(f.pt)
            if why is not None:
                skipped.append((contract.name, c.id, why))
                continue
            for x in ir.walk(f.pt):
                if x.op in ("ap", "var") and variables.get(name_of(x)) is None:
                    variables[name_of(x)] = types[name_of(x)]
            reqs.append({"name": one_line(c.id), "fretish": c.text, "ptLTL": _pt_text(c, contract),
                         "CoCoSpecCode": lustre_of.get(c.id, ""), "PCTL": ""})
        for name in variables:
            kind = getattr(fret.get(name), "kind", "")
            if name not in inputs and name not in outputs and kind not in ("", "Input",
                                                                           "Output"):
                notes.append(f"{contract.name}: {one_line(name)} (a FRET {kind} variable) is "
                             "an Other_variables entry: the monitor reads it as an input")
        spec = {"Internal_variables": [],
                "Other_variables": [{"name": contract.lustre_name(n), "type": t or "bool"}
                                    for n, t in variables.items()],
                "Functions": [], "Requirements": reqs}
        out[contract.name] = json.dumps({contract.name: spec}, indent=2) + "\n"
    return out, skipped, notes


def _pt_text(c: Compiled, contract: Contract) -> str:
    """The requirement's pt formula as FRET prints it (``(Z FALSE)`` for FTP), its variables
    by their names in ``contract``: the text ``--emit ltl`` prints when no name is renamed."""
    f = c.formalization
    assert f is not None  # (a formalized requirement)
    names = {v: contract.lustre_name(v) for v in ir.variables(f.pt)}
    if all(mangle(v) == lustre for v, lustre in names.items()):
        return c.smv_text["pt"]
    memo: dict[int, ir.Node] = {}

    def go(n: ir.Node) -> ir.Node:
        got = memo.get(id(n))
        if got is None:
            if n.op in ("ap", "var"):
                got = ir.Node(n.op, (), names[name_of(n)])
            elif n.args:
                got = ir.Node(n.op, tuple(go(a) for a in n.args), n.name, n.lo, n.hi)
            else:
                got = n
            memo[id(n)] = got
        return got

    return to_smv(go(f.pt), "(Z FALSE)")
