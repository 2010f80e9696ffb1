"""FRET's simulator without NuSMV: the values of requirements at every tick of a small trace.

``fretc simulate FILE TRACE`` (FRET's LTLSIM, after FRET's manual, "Simulating
requirements"): for each requirement and each tick ``i`` of a trace of ``n`` ticks,

Design notes: ARCHITECTURE.md, `monitors/simulate.py`."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any, TYPE_CHECKING

import numpy as np

from fretc.common.errors import InputError, Where
from fretc.compiler.evaluate import ft_at, pt_at, series

from fretc.monitors.expressions import ColumnExpressions, EvidenceUnsupported

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled

__all__ = ["MAX_SIMULATED_TICKS", "Simulation", "parse_timeline", "read_trace", "simulate"]

#: The longest trace simulated (the reference evaluator is quadratic in it); audits have
#: no such bound.
MAX_SIMULATED_TICKS = 2000
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_WORDS = {"true": True, "false": False, "t": True, "f": False}


@dataclass
class Simulation:
    """One requirement over a trace of ``n`` ticks (module docstring): ``ft``, ``pt`` (bool
    per tick, None where a NaN leaves it unknown) and ``parts`` (part name -> bool or float per tick, None where unread)."""

    id: str
    text: str
    ft: list[bool | None] = field(default_factory=list)
    pt: list[bool | None] = field(default_factory=list)
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
            if not 0 < length <= MAX_SIMULATED_TICKS:
                raise _fail(path, no, line.index(m.group(1)) + 1,
                            f"@ticks {_short(m.group(1))}: a simulation has 1 to "
                            f"{MAX_SIMULATED_TICKS} ticks (audit a longer trace with fretc "
                            "audit)")
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
            if len(items) > MAX_SIMULATED_TICKS:
                raise _fail(path, no, col, f"{name}: {len(items)} values; a simulation has "
                            f"at most {MAX_SIMULATED_TICKS} ticks")
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


def _short(digits: str) -> str:
    return digits if len(digits) <= 12 else f"{digits[:6]}...({len(digits)} digits)"


def _ticks(spec: str, path: str, no: int, col: int) -> set[int]:
    out: set[int] = set()
    for part in (p.strip() for p in spec.split(",")):
        if not part:
            continue
        m = re.fullmatch(r"(\d{1,12})\s*(?:-\s*(\d{1,12}))?", part)
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
        # CsvError (an input error) names file:line and column; a file past the bound is
        # read only a chunk of rows past it, never whole
        src = CsvSource(path, max_rows=MAX_SIMULATED_TICKS)
        if src.over_max_rows:
            raise InputError(f"{path}: more than {MAX_SIMULATED_TICKS} ticks; a simulation "
                             f"has at most {MAX_SIMULATED_TICKS} (audit a longer trace with "
                             "fretc audit)")
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
    if n == 0:
        raise InputError(f"{path}: the trace has no ticks: nothing to simulate (give values "
                         "or '@ticks N')")
    return trace


def simulate(compiled: Compiled, trace: dict[str, list[Any]]) -> Simulation:
    """The simulation (module docstring) of one compiled requirement
    (:class:`fretc.compiler.build.Compiled` with a formalization) over ``trace`` (variable ->
    values, one per tick, all of one length).

    Raises:
        InputError: a variable of the requirement missing from the trace (named with the
            requirement and the variables the trace has).
    """
    f = compiled.formalization
    assert f is not None  # (a compiled requirement with a formalization, as documented)
    missing = [v for v in f.variables if v not in trace]
    if missing:
        raise InputError(f"{compiled.id}: the trace has no {', '.join(map(repr, missing))} "
                         f"(it has {', '.join(sorted(trace)) or 'no variable'})")
    n = len(next(iter(trace.values()), []))
    rows = [{v: trace[v][i] for v in f.variables} for i in range(n)]
    sim = Simulation(compiled.id, compiled.text)
    if n == 0:
        return sim
    nan = np.zeros(n, np.bool_)
    for v in f.variables:
        nan |= np.array([isinstance(x, float) and math.isnan(x) for x in trace[v]], np.bool_)
    if not nan.any():
        sim.ft = [bool(ft_at(f.ft, rows[i:])) for i in range(n)]
        if f.pt_causal:
            sim.pt = [bool(x) for x in series(f.pt, rows)]
        else:  # a future-time function inside pt: each prefix on its own
            sim.pt = [bool(pt_at(f.pt, rows[:i + 1])) for i in range(n)]
    else:
        sim.ft, sim.pt = _three_valued(f, trace, nan, rows)
    sim.parts = _parts(compiled.requirement, trace, n)
    return sim


def _three_valued(f, trace: dict[str, list[Any]], nan: np.ndarray, rows: list[dict]):
    """``(ft, pt)`` of a trace with NaN values: True or False where every value the NaN
    could stand for gives it, None (unknown) where it depends on them, as the audit judges
    a NaN (docs/guide/ticks.md, "NaN"; :mod:`fretc.monitors.three_valued`, Kleene's
    three-valued logic, and :func:`fretc.monitors.completions.decide` where it leaves a
    verdict open). ``pt`` at tick i is the pt formula's reading at i; ``ft`` at i is the
    pt formula's at the last tick of the trace from i (FRET's ft verdict of a trace is its pt
    formula at the last tick: tests/semantics); both exact where no NaN is read. A pt formula
    with a future-time function inside is unknown wherever a NaN is in the trace."""
    from fretc.monitors.completions import decide
    from fretc.monitors.three_valued import kleene_values
    from fretc.monitors.vectorized import VectorizeError

    n = len(nan)
    cols = {v: np.asarray(trace[v], dtype=np.bool_ if all(type(x) is bool for x in trace[v])
                          else np.float64) for v in f.variables}

    def at_last(a: int, b: int) -> bool | None:  # the verdict over ticks a..b-1
        return decide(f.pt, {v: c[a:b] for v, c in cols.items()}, {}, b - a)[0]

    last_nan = int(np.flatnonzero(nan)[-1])
    try:
        if not f.pt_causal:
            raise VectorizeError("a future-time function inside the pt formula")
        values = kleene_values(f.pt, cols, {}, n, 0, {})
        lo, hi = values > 0, values >= 0
        pt = [bool(a) if a or not b else at_last(0, i + 1)
              for i, (a, b) in enumerate(zip(lo.tolist(), hi.tolist()))]
        ft: list[bool | None] = []
        for i in range(n):
            if i > last_nan:  # no NaN in the trace from i: exact
                ft.append(bool(ft_at(f.ft, rows[i:])))
                continue
            ft.append(at_last(i, n))
    except VectorizeError:
        first_nan = int(np.flatnonzero(nan)[0])
        pt = [bool(pt_at(f.pt, rows[:i + 1])) if i < first_nan else None for i in range(n)]
        ft = [None if i <= last_nan else bool(ft_at(f.ft, rows[i:])) for i in range(n)]
    return ft, pt


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
        if any(np.isnan(c).any() for c in cols.values() if c.dtype != np.bool_):
            out[name] = _part_three_valued(e, cols, n, out[name])
    return out


def _part_three_valued(e, cols: dict[str, np.ndarray], n: int, known: list) -> list:
    """A part's values where NaN values are read: True or False where every value a NaN
    could stand for gives it, None where it depends on them (Kleene's three-valued logic,
    :func:`fretc.monitors.three_valued.kleene_values`, on the part's pt expansion); a part
    that cannot be evaluated so is None from the first NaN on."""
    from fretc.compiler import ir
    from fretc.compiler.expressions import Expander
    from fretc.monitors.three_valued import kleene_values

    try:
        values = kleene_values(Expander("pt", ir.FTP, ir.LAST, free=True).bool(e), cols, {},
                               n, 0, {})
        lo, hi = values > 0, values >= 0
    except Exception:  # a future-time function, a call the columns cannot evaluate
        nan = np.zeros(n, np.bool_)
        for c in cols.values():
            if c.dtype != np.bool_:
                nan |= np.isnan(c)
        first = int(np.flatnonzero(nan)[0])
        return [v if i < first else None for i, v in enumerate(known)]
    return [True if a else (False if not b else None) for a, b in zip(lo.tolist(), hi.tolist())]
