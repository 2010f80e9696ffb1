"""Helpers for the audit, evidence and vectorized tests: requirements built directly from
``fretish.ast`` (no parser), compiled to generated monitor modules loaded in-process."""

from __future__ import annotations

import random
import types

import numpy as np

from fretc.compiler.build import compile_entry
from fretc.compiler.codegen import monitor_source, render_module
from fretc.fretish import ast as A
from fretc.fretish.files import RequirementEntry

KEYS = [(s, c, t) for s in A.SCOPE_KINDS for c in A.CONDITION_KINDS for t in A.TIMING_KINDS]
assert len(KEYS) == 288

_RESPONSES = {
    "r": A.Var("r"),
    "!r": A.Unary("!", A.Var("r")),
    "r | s": A.Binary("|", A.Var("r"), A.Var("s")),
    "r & c": A.Binary("&", A.Var("r"), A.Var("c")),
    "r xor m": A.Binary("xor", A.Var("r"), A.Var("m")),
    "x > 2": A.Binary(">", A.Var("x"), A.NumLit("2")),
}
_CONDITIONS = {
    "c": A.Var("c"),
    "!c": A.Unary("!", A.Var("c")),
    "c & x <= 3": A.Binary("&", A.Var("c"), A.Binary("<=", A.Var("x"), A.NumLit("3"))),
}


def requirement(scope: str, cond: str, timing: str, response: str = "r",
                condition: str = "c", n: int = 2) -> A.Requirement:
    """A requirement of template key ``scope,cond,timing`` over the variables m, c, r, s
    (and the number x), built from AST nodes."""
    sc = A.Scope(scope, A.Var("m") if scope != "null" else None)
    cd = A.Condition(cond, _CONDITIONS[condition] if cond != "null" else None)
    tm = A.Timing(timing,
                  duration=A.Duration(str(n), "ticks") if timing in A.DURATION_TIMINGS else None,
                  stop=A.Var("s") if timing in A.STOP_TIMINGS else None)
    text = f"<{scope},{cond},{timing}> {condition} {response} n={n}"
    return A.Requirement(text, scope=sc, condition=cd, component="sw", timing=tm,
                         response=_RESPONSES[response])


def compiled(req: A.Requirement, rid: str = "R", tick_period=None):
    entry = RequirementEntry(id=rid, text=req.text, source="<test>", line=1, column=1,
                             tick_period=tick_period, requirement=req)
    c = compile_entry(entry)
    assert c.error is None, c.error
    return c


def entry(rid: str, text: str, tick_period=None, source: str = "test.fret"):
    """A requirement entry as fretish.files makes them (without a file), its text parsed."""
    from types import SimpleNamespace

    from fretc.fretish import parse
    return SimpleNamespace(id=rid, text=text, source=source, line=1, column=1,
                           rationale=None, parent=None, tick_period=tick_period,
                           requirement=parse(text), error=None, extra={})


def load_source(source: str) -> types.ModuleType:
    """exec a generated monitor module's text into a fresh module named ``generated``."""
    mod = types.ModuleType("generated")
    exec(compile(source, "generated.py", "exec"), mod.__dict__)
    return mod


def load_module(compiled_list, name: str = "test_monitors") -> types.ModuleType:
    """exec the generated monitor module text into a fresh module."""
    src = render_module(compiled_list, name)
    mod = types.ModuleType(name)
    exec(compile(src, f"<{name}>", "exec"), mod.__dict__)
    return mod


def random_trace(rnd: random.Random, length: int, variables=("m", "c", "r", "s"),
                 numeric=("x",)) -> dict[str, np.ndarray]:
    cols = {v: np.array([rnd.random() < 0.5 for _ in range(length)], dtype=np.bool_)
            for v in variables}
    for v in numeric:
        cols[v] = np.array([float(rnd.randint(0, 5)) for _ in range(length)])
    return cols


def samples(cols: dict[str, np.ndarray], length: int) -> list[dict]:
    return [{k: (bool(v[i]) if v.dtype == np.bool_ else float(v[i])) for k, v in cols.items()}
            for i in range(length)]


def step_all(monitor, cols, length):
    """[pt verdict per tick], (status, status_tick) of a monitor instance."""
    out = [monitor.step(s) for s in samples(cols, length)]
    return out, (monitor.status, monitor.status_tick)


__all__ = ["KEYS", "requirement", "compiled", "load_module", "random_trace", "samples",
           "step_all", "monitor_source"]


_COMPILED: dict = {}


def compiled_of(text: str):
    """(compiled requirement ``R: text``, its monitor source), cached by text."""
    if text not in _COMPILED:
        import tempfile
        from pathlib import Path

        from fretc.compiler.build import compile_entries
        from fretc.fretish import load_requirements

        path = Path(tempfile.mkdtemp()) / "t.fret"
        path.write_text(f"R: {text}\n")
        (c,) = compile_entries(load_requirements([str(path)]))
        _COMPILED[text] = (c, monitor_source(c, 0))
    return _COMPILED[text]


def pqmx_columns(rows, names):
    """Columns of rows (p, q, m, x): booleans p, q, m and the number x; only ``names``."""
    cols = {n: np.array([r[i] for r in rows], dtype=np.bool_) for i, n in enumerate("pqm")}
    cols["x"] = np.array([r[3] for r in rows], dtype=np.float64)
    return {n: c for n, c in cols.items() if n in names}


def autopilot_export(defined: bool, inputs, requirements, psi: str, roll: str) -> dict:
    """An LMCPS-like FRET export of component Autopilot: ``inputs`` [(name, type)],
    ``requirements`` [(id, text)], and the stream variables psiAtZero (``psi``) and rollAtZero
    (``roll``) defined (``defined``), else Inputs."""
    variables = [{"component_name": "Autopilot", "variable_name": n, "idType": "Input",
                  "dataType": t} for n, t in inputs]
    for name, text in (("psiAtZero", psi), ("rollAtZero", roll)):
        variables.append({"component_name": "Autopilot", "variable_name": name,
                          "idType": "Internal" if defined else "Input", "dataType": "double",
                          "assignment": text if defined else ""})
    return {"requirements": [{"reqid": i, "fulltext": t} for i, t in requirements],
            "variables": variables}


def keyed_monitors(responses: list[str], conditions: list[str]) -> list:
    """Per template key (:data:`KEYS`): (pt formula, monitor source), the response, condition
    and duration varied with the key's index."""
    out = []
    for i, (s, c, t) in enumerate(KEYS):
        comp = compiled(requirement(s, c, t, response=responses[i % 6],
                                    condition=conditions[i % 3], n=i % 4), rid=f"K{i}")
        out.append((comp.formalization.pt, monitor_source(comp, i)))
    return out


def fret_export(requirements: dict[str, str], *variables: tuple, component: str = "ctrl"
                ) -> dict:
    """A FRET project export (FRET's JSON fields) of ``component``: ``requirements`` id ->
    FRETish text; ``variables`` as (name, idType, dataType), (name, idType, dataType,
    assignment) or (name, idType, dataType, {more fields})."""
    rows = []
    for name, kind, dtype, *more in variables:
        extra = more[0] if more and isinstance(more[0], dict) else (
            {"assignment": more[0]} if more else {})
        rows.append({"component_name": component, "variable_name": name, "idType": kind,
                     "dataType": dtype, **extra})
    return {"requirements": [{"reqid": k, "fulltext": t} for k, t in requirements.items()],
            "variables": rows}
