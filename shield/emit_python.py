"""``fretc shield --emit python``: the shield as one standalone Python module.

The module is :mod:`fretc.shield.runtime`'s source (the one Python implementation of the
shield's step, standard library only) followed by the shield's tables (:func:`tables`) and
``class Shield``, whose ``step(inputs, proposed)`` returns a ``Decision(outputs, overridden,
reasons, changed)``. The same shield gives the same bytes (no time, no path, no set order).
"""

from __future__ import annotations

import ast
import inspect
import math
from typing import Any

from fretc.common.textsafe import python_doc
from fretc.shield import runtime, runtime_bounds, runtime_lost, runtime_values
from fretc.shield.build import Shield
from fretc.shield.message_model import group_atoms, table_of

__all__ = ["tables", "render_python", "load_shield"]


def tables(shield: Shield) -> dict[str, Any]:
    """The shield's tables in :mod:`fretc.shield.runtime`'s shape (plain literals: ints,
    floats, strings, None, tuples, lists, dicts)."""
    machines = []
    for k, m in enumerate(shield.machines):
        texts = [a.text for a in m.outputs]
        groups = []
        for g in m.messages:
            if not g.valuations:
                continue
            atoms = group_atoms(texts, g.valuations)
            numbers, fields = {}, {}
            for vals, flds, nums in g.valuations:
                key = sum(int(vals[texts[j]]) << i for i, j in enumerate(atoms))
                numbers[key] = dict(sorted(nums.items()))
                fields[key] = [(t, list(path), v) for (t, path), v in sorted(flds.items())]
            bounded = {b["variable"] for b in m.bounds} | {v for t in m.twists for v in t}
            groups.append({"atoms": atoms, "topics": list(g.topics),
                           "decides": [v for v in [*g.variables, *g.passed] if v in bounded],
                           "numbers": dict(sorted(numbers.items())),
                           "fields": dict(sorted(fields.items())),
                           "message": None if g.model is None else table_of(
                               g.model, texts, atoms, [a.spec for a in m.outputs],
                               [v for v in m.output_variables if v in shield.integers])})
        machines.append({
            "requirements": list(m.requirements),
            "inputs": [a.spec for a in m.inputs],
            "outputs": [a.spec for a in m.outputs],
            "integers": [v for v in m.output_variables if v in shield.integers],
            "texts": texts,
            "init": [int(b) for b in m.init],
            "nodes": [tuple(n) for n in m.nodes],
            "safe": m.safe, "next": list(m.next), "keep": list(m.keep), "ctl_ok": m.ctl_ok,
            "env_ok": m.env_ok,
            "weights": {j: (int(w), x) for j, (w, x) in sorted(shield.weights(k).items())},
            "groups": groups,
            "clusters": [{"atoms": list(c["atoms"]), "variables": list(c["variables"]),
                          "numbers": dict(sorted(c["numbers"].items()))}
                         for c in m.clusters],
            "assumptions": list(m.assumptions), "assumed": list(m.assumed),
            "bounds": [dict(b) for b in m.bounds], "twists": [list(t) for t in m.twists],
            "lookback": m.stats.get("lookback")})
    return {"name": shield.name, "digest": shield.digest, "inputs": list(shield.inputs),
            "outputs": list(shield.outputs),
            "preferences": [(t, int(v)) for t, v in shield.preferences],
            "machines": machines, "fallback": shield.fallback}


def _runtime_body() -> str:
    """:mod:`fretc.shield.runtime_values`' source, then :mod:`fretc.shield.runtime_bounds`',
    :mod:`fretc.shield.runtime_lost`'s and :mod:`fretc.shield.runtime`'s, each without its
    docstring and ``__all__``; the later ones' ``from __future__`` and their imports of the
    earlier ones left out (the four read as one module)."""
    values, bounds, lost = (runtime_values.__name__, runtime_bounds.__name__,
                            runtime_lost.__name__)
    return (_body(runtime_values) + "\n\n" + _body(runtime_bounds, (values,)) + "\n\n"
            + _body(runtime_lost, (values,)) + "\n\n"
            + _body(runtime, (values, bounds, lost)))


def _body(module: Any, inlined: tuple[str, ...] | None = None) -> str:
    """``module``'s source without its docstring and ``__all__``; with ``inlined`` (modules
    written before it into the same text) without its ``from __future__`` import and its
    imports from them."""
    src = inspect.getsource(module)
    doc = module.__doc__ or ""
    start = src.index('"""' + doc[:40])
    src = src[start + len(doc) + 6:].lstrip("\n")
    lines = src.splitlines()
    drop: list[tuple[int, int]] = []
    for node in ast.parse(src).body:  # (the __all__ statement, over all its lines)
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__"
                                                for t in node.targets):
            drop.append((node.lineno, node.end_lineno or node.lineno))
        if inlined is not None and isinstance(node, ast.ImportFrom) and (
                node.module == "__future__" or node.module in inlined):
            drop.append((node.lineno, node.end_lineno or node.lineno))
    for first, last in sorted(drop, reverse=True):
        del lines[first - 1:last]
    return "\n".join(lines).rstrip() + "\n"


def _literal(value: Any, indent: int = 0) -> str:
    """``value`` as Python source, one machine table entry per line, deterministic; a
    float no literal writes (a constant such as ``1e309``, infinite in doubles) as
    ``float('inf')``, ``float('-inf')`` or ``float('nan')``."""
    pad = " " * indent
    if isinstance(value, float) and not math.isfinite(value):
        return f"float({str(value)!r})"
    if isinstance(value, tuple):
        inner = ", ".join(_literal(v, indent) for v in value)
        return f"({inner},)" if len(value) == 1 else f"({inner})"
    if isinstance(value, dict):
        if not value:
            return "{}"
        items = [f"{pad}    {key!r}: {_literal(v, indent + 4)}," for key, v in value.items()]
        return "{\n" + "\n".join(items) + f"\n{pad}}}"
    if isinstance(value, list) and value and isinstance(value[0], (dict, tuple)):
        items = [f"{pad}    {_literal(v, indent + 4)}," for v in value]
        return "[\n" + "\n".join(items) + f"\n{pad}]"
    if isinstance(value, list):
        return "[" + ", ".join(_literal(v, indent) for v in value) + "]"
    return repr(value)


def render_python(shield: Shield, fretc_version: str = "") -> str:
    """The module's text (module docstring)."""
    reqs = "\n".join(f"  {r.id} ({r.source}): {r.text}\n    pt: {r.pt}"
                     for r in shield.requirements)
    monitored = "\n".join(f"  {k}: {v}" for k, v in shield.monitored.items()) or "  (none)"
    assumed = ("Under the assumptions of the environment (the guarantee holds while they do; "
               "Decision.broken\nnames one that breaks, and the outputs are then the "
               "fallback's):\n" + "\n".join(f"  {a.id} ({a.source}): {a.text}"
                                             for a in shield.assumptions) + "\n"
               if shield.assumptions else "")
    doc = f'''Shield {shield.name!r}, generated by fretc shield{(" " + fretc_version) if fretc_version else ""} from FRETish requirements.

Standalone: it imports only the Python standard library. Each tick, give it the inputs
(the environment's FRET variables: {", ".join(shield.inputs)}) and the controller's
proposed outputs ({", ".join(shield.outputs)}):

    shield = Shield()
    decision = shield.step(inputs, proposed)   # Decision(outputs, overridden, reasons, changed)

It returns the proposal unchanged whenever the proposal keeps every enforced requirement
winnable (minimal interference), otherwise the outputs that change the fewest output atoms
(preferences: {", ".join(("" if v else "!") + t for t, v in shield.preferences) or "none"}),
with the requirements that forced the change. The same requirements give the same bytes.

Enforced requirements (FRET's pt formula kept true at every tick):
{reqs}
Monitored only (not enforced):
{monitored}
{assumed}
Digest of requirements, choices and tables: {shield.digest}
'''
    # (the texts are the user's: a backslash or three quotes must not end or break it, nor
    # a NUL, a carriage return or a lone surrogate make the module unreadable:
    # textsafe.python_doc, which reads back as the text)
    head = '"""' + python_doc(doc) + '"""\n\n'
    body = _runtime_body()
    tail = f'''

TABLES = {_literal(tables(shield))}

#: the enforced requirements: id -> (FRETish text, source, pt formula)
REQUIREMENTS = {_literal({r.id: (r.text, r.source, r.pt) for r in shield.requirements})}


class Shield(ShieldRuntime):
    """The shield of this module's requirements (see the module docstring)."""

    def __init__(self) -> None:
        super().__init__(TABLES)
'''
    return head + body + tail


def load_shield(text: str, name: str = "fretc_shield") -> Any:
    """The ``Shield`` class of a generated module's ``text`` (executed in a fresh module
    namespace)."""
    import types

    mod = types.ModuleType(name)
    exec(compile(text, f"<{name}>", "exec"), mod.__dict__)
    return mod.Shield
