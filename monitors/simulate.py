"""FRET's simulator without NuSMV: the values of requirements at every tick of a small trace.

``fretc simulate FILE TRACE`` (FRET's LTLSIM, after FRET's manual, "Simulating
requirements"): for each requirement and each tick ``i`` of a trace of ``n`` ticks,

* ``ft[i]``: the ft formula on the suffix of the trace from ``i`` (FRET's finite-trace
  semantics: the suffix followed by FRET's absorbing state, ``LAST`` at its last tick), so
  ``ft[0]`` is the requirement's verdict on the whole trace;
* ``pt[i]``: the pt formula at ``i`` on the prefix up to ``i``, so ``pt[n-1]`` is the verdict
  again, and ``pt`` is what a runtime monitor says at each tick;
* ``parts``: the values of the requirement's parts at ``i``: its scope mode, its condition
  (the trigger), its stop condition and its response (None where a value is NaN).

Both formulas are evaluated by the reference evaluator (:mod:`fretc.compiler.evaluate`), the
oracle the monitors are tested against. A trace is a CSV (the audit's format,
:class:`fretc.logs.CsvSource`) or a timeline text (:func:`parse_timeline`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fretc.common.errors import InputError, Where
from fretc.compiler.evaluate import ft_at, pt_at, series

from fretc.monitors.expressions import ColumnExpressions, EvidenceUnsupported

__all__ = ["MAX_SIMULATED_TICKS", "Simulation", "parse_timeline", "read_trace", "simulate"]

#: The longest trace simulated (the reference evaluator is quadratic in it); audits have
#: no such bound.
MAX_SIMULATED_TICKS = 2000
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_WORDS = {"true": True, "false": False, "t": True, "f": False}


@dataclass
class Simulation:
    """One requirement over a trace of ``n`` ticks (module docstring): ``ft``, ``pt`` (bool
    per tick) and ``parts`` (part name -> bool or float per tick, None where unread)."""

    id: str
    text: str
    ft: list[bool] = field(default_factory=list)
    pt: list[bool] = field(default_factory=list)
    parts: dict[str, list[Any]] = field(default_factory=dict)

    def to_json(self) -> dict:
        """``{"id", "text", "ft": [...], "pt": [...], "parts": {...}}``."""
        return {"id": self.id, "text": self.text, "ft": self.ft, "pt": self.pt,
                "parts": self.parts}


def _fail(path: str, line: int | None, col: int | None, msg: str) -> InputError:
    at = f"{path}:{line}:{col}" if line and col else f"{path}:{line}" if line else path
    return InputError(f"{at}: {msg}", where=Where(path, line, col) if line else None)


def parse_timeline(text: str, path: str = "<timeline>") -> dict[str, list[Any]]:
    """A compact timeline: one line per variable, ``name: spec``; ``#`` starts a comment.
    ``spec`` is either the ticks at which a boolean holds, as ticks and ranges (``p: 0-3,
    7``; empty: never), or one value per tick separated by spaces (``speed: 0.0 0.2 0.6``;
    numbers, or ``true``/``false``/``1``/``0``). A line ``@ticks N`` sets the length; without
    it the length is the longest list (or the last tick named, plus one); a boolean given by
    ticks is false after its last one, a list of values must have the length.

    Returns:
        variable -> list of bool or float, all of the trace's length.

    Raises:
        InputError: a line that is not ``name: spec``, a bad tick or value, a variable given
            twice, a list of the wrong length; named ``path:line:col``.
    """
    ticks: dict[str, tuple[int, set[int]]] = {}
    values: dict[str, tuple[int, list[Any]]] = {}
    length = None
    for no, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].rstrip()
        if not line.strip():
            continue
        if line.strip().startswith("@ticks"):
            m = re.fullmatch(r"\s*@ticks\s+(\d+)\s*", line)
            if not m:
                raise _fail(path, no, 1, "write '@ticks N' (the trace's length in ticks)")
            length = int(m.group(1))
            continue
        name, sep, spec = line.partition(":")
        name = name.strip()
        if not sep or not _NAME.match(name):
            raise _fail(path, no, 1, f"expected 'variable: ticks or values', got {raw.strip()!r}")
        if name in ticks or name in values:
            raise _fail(path, no, 1, f"variable {name!r} is given twice")
        col = raw.index(":") + 2 + len(spec) - len(spec.lstrip())  # where the spec starts
        items = spec.split()
        if not items or re.fullmatch(r"[\d\s,\-]*", spec) and ("," in spec or "-" in spec
                                                             or len(items) == 1):
            ticks[name] = (no, _ticks(spec, path, no, col))
        else:
            values[name] = (no, [_value(v, path, no, col) for v in items])
    if length is None:
        length = max([len(v) for _n, v in values.values()]
                     + [max(t) + 1 for _n, t in ticks.values() if t] + [0])
    out: dict[str, list[Any]] = {}
    for name, (no, ts) in sorted(ticks.items()):
        if ts and max(ts) >= length:
            raise _fail(path, no, 1, f"{name}: tick {max(ts)} is past the trace's "
                        f"{length} ticks")
        out[name] = [i in ts for i in range(length)]
    for name, (no, vs) in sorted(values.items()):
        if len(vs) != length:
            raise _fail(path, no, 1, f"{name}: {len(vs)} values for a trace of {length} "
                        "ticks (every list has the trace's length)")
        out[name] = vs
    return out


def _ticks(spec: str, path: str, no: int, col: int) -> set[int]:
    out: set[int] = set()
    for part in (p.strip() for p in spec.split(",")):
        if not part:
            continue
        m = re.fullmatch(r"(\d+)\s*(?:-\s*(\d+))?", part)
        if not m or (m.group(2) and int(m.group(2)) < int(m.group(1))):
            raise _fail(path, no, col, f"{part!r} is not a tick or a range of ticks (e.g. "
                        "0-3, 7)")
        lo = int(m.group(1))
        hi = int(m.group(2)) if m.group(2) else lo
        if hi >= MAX_SIMULATED_TICKS:
            raise _fail(path, no, col, f"tick {hi}: a simulation has at most "
                        f"{MAX_SIMULATED_TICKS} ticks")
        out.update(range(lo, hi + 1))
    return out


def _value(v: str, path: str, no: int, col: int) -> Any:
    w = _WORDS.get(v.lower())
    if w is not None:
        return w
    try:
        return float(v)
    except ValueError:
        raise _fail(path, no, col, f"{v!r} is not a number nor true/false") from None


def read_trace(path: str) -> dict[str, list[Any]]:
    """The trace of ``path``: a ``.csv`` (the audit's CSV, :class:`fretc.logs.CsvSource`; a
    ``time`` column is ignored: ticks are rows) or any other file as a timeline text.

    Raises:
        InputError: an unreadable file or a bad trace (positioned), or more than
            :data:`MAX_SIMULATED_TICKS` ticks.
    """
    from fretc.logs import CsvSource

    if path.lower().endswith(".csv"):
        src = CsvSource(path)  # CsvError (an input error) names file:line and column
        rows = list(src.rows())
        names = [n for n in src.types if n != "time"]
        trace = {n: [r.values[n] for r in rows] for n in names}
        n = len(rows)
    else:
        try:
            text = open(path, encoding="utf-8").read()
        except (OSError, UnicodeDecodeError) as exc:
            raise InputError(f"{path}: cannot read the trace: {exc}") from None
        trace = parse_timeline(text, path)
        n = len(next(iter(trace.values()), []))
    if n > MAX_SIMULATED_TICKS:
        raise InputError(f"{path}: {n} ticks; a simulation has at most "
                         f"{MAX_SIMULATED_TICKS} (audit a longer trace with fretc audit)")
    return trace


def simulate(compiled, trace: dict[str, list[Any]]) -> Simulation:
    """The simulation (module docstring) of one compiled requirement
    (:class:`fretc.compiler.build.Compiled` with a formalization) over ``trace`` (variable ->
    values, one per tick, all of one length).

    Raises:
        InputError: a variable of the requirement missing from the trace (named with the
            requirement and the variables the trace has).
    """
    f = compiled.formalization
    missing = [v for v in f.variables if v not in trace]
    if missing:
        raise InputError(f"{compiled.id}: the trace has no {', '.join(map(repr, missing))} "
                         f"(it has {', '.join(sorted(trace)) or 'no variable'})")
    n = len(next(iter(trace.values()), []))
    rows = [{v: trace[v][i] for v in f.variables} for i in range(n)]
    sim = Simulation(compiled.id, compiled.text)
    if n == 0:
        return sim
    sim.ft = [bool(ft_at(f.ft, rows[i:])) for i in range(n)]
    if f.pt_causal:
        sim.pt = [bool(x) for x in series(f.pt, rows)]
    else:  # a future-time function inside pt: each prefix on its own
        sim.pt = [bool(pt_at(f.pt, rows[:i + 1])) for i in range(n)]
    sim.parts = _parts(compiled.requirement, trace, n)
    return sim


def _parts(req, trace: dict[str, list[Any]], n: int) -> dict[str, list[Any]]:
    """Scope mode, condition, stop condition and response at each tick."""
    cols = {k: np.asarray(v, dtype=np.bool_ if all(type(x) is bool for x in v)
                          else np.float64) for k, v in trace.items()}
    ev = ColumnExpressions(cols, n)
    out: dict[str, list[Any]] = {}
    for name, e in (("scope", req.scope.mode), ("condition", req.condition.expr),
                    ("stop", req.timing.stop), ("response", req.response)):
        if e is None:
            continue
        try:
            vals = ev.bool(e)[:n]
        except (EvidenceUnsupported, KeyError, ValueError, TypeError):
            continue
        out[name] = [None if isinstance(x, float) and math.isnan(x) else bool(x)
                     for x in vals.tolist()]
    return out
