"""FRET's stream variables in the traces fretc builds: ``fretc check``'s witnesses and
``fretc testgen``'s tests.

Design notes: ARCHITECTURE.md, `check/stream_rows.py`."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fretc.compiler.stream_code import _div, _mod, _pow, stream_columns
from fretc.fretish import ast as A
from fretc.fretish.fret_streams import FIRST_TICK, StreamSystem, stream_system

__all__ = ["TraceStreams", "trace_streams", "with_stream_inputs", "with_stream_columns",
           "value_at", "past_values", "TickTerms"]

_PRE = ("preBool", "preInt", "preReal")


@dataclass(frozen=True)
class TraceStreams:
    """The stream variables a set of requirements reads, as the traces built for it take
    them: ``systems`` (one :class:`fretc.fretish.fret_streams.StreamSystem` per component
    export, the first that computes a name computing it), ``exprs`` (each stream's
    definition, over its inputs, ``FTP`` and the streams), ``booleans`` (whether each stream
    and each input is a truth value) and ``inputs`` (the variables read from outside, in
    order)."""

    systems: tuple[StreamSystem, ...]
    exprs: dict[str, A.Expr]
    booleans: dict[str, bool]
    inputs: tuple[str, ...]


def trace_streams(items: Iterable[Any], columns: Iterable[str]) -> TraceStreams | None:
    """The :class:`TraceStreams` of the stream variables among ``columns`` (the names a
    trace's formulas read) defined by the FRET exports of ``items``
    (:class:`fretc.check.items.CheckItem`, or anything with ``compiled.entry`` or
    ``entry``); None when there is none (no FRET variables, or no stream among them)."""
    names = set(columns)
    systems: list[StreamSystem] = []
    seen: set[str] = set()
    for x in items:
        entry = getattr(getattr(x, "compiled", x), "entry", None)
        variables = tuple(getattr(entry, "variables", ()) or ())
        if not variables:
            continue
        wanted = sorted(names - seen)
        system = stream_system(variables, wanted) if wanted else None
        if system is None or not set(system.names) - seen:
            continue
        systems.append(system)
        seen.update(system.names)
    if not systems:
        return None
    exprs: dict[str, A.Expr] = {}
    booleans: dict[str, bool] = {}
    inputs: list[str] = []
    for s in systems:
        for n, e, b in zip(s.names, s.exprs, s.booleans):
            exprs.setdefault(n, e)
            booleans.setdefault(n, b)
        for n, b in zip(s.inputs, s.input_booleans):
            if n not in exprs and n not in booleans:
                booleans[n] = b
                inputs.append(n)
    return TraceStreams(tuple(systems), exprs, booleans, tuple(inputs))


def with_stream_inputs(columns: Mapping[str, str], streams: TraceStreams | None
                       ) -> dict[str, str]:
    """``columns`` (name -> ``"bool"``/``"float"``, :func:`fretc.check.witness.
    trace_columns`) with every input of ``streams`` the formulas do not read added after
    them (a trace must carry what the audit computes the streams from)."""
    out = dict(columns)
    if streams is not None:
        for n in streams.inputs:
            out.setdefault(n, "bool" if streams.booleans[n] else "float")
    return out


def with_stream_columns(rows: list[dict[str, Any]], streams: TraceStreams | None
                        ) -> list[dict[str, Any]]:
    """``rows`` (one ``{variable: value}`` per tick) with each stream's value computed from
    its inputs' values by the audit's code (:func:`fretc.compiler.stream_code.
    stream_columns`); ``rows`` themselves when there is no stream or an input is missing.
    New dicts: the rows given are not changed."""
    if streams is None or not rows:
        return rows
    out = [dict(r) for r in rows]
    n = len(rows)
    for system in streams.systems:
        if any(i not in rows[0] for i in system.inputs):
            continue
        cols = {i: np.array([r[i] for r in out], dtype=bool if b else float)
                for i, b in zip(system.inputs, system.input_booleans)}
        got = stream_columns(system, cols, n)
        for name, b in zip(system.names, system.booleans):
            if streams.exprs.get(name) is None or name not in got:
                continue
            for r, v in zip(out, got[name].tolist()):
                if name in r:
                    r[name] = bool(v) if b else float(v)
    return out


def value_at(e: A.Expr, rows: Sequence[Mapping[str, Any]], t: int) -> Any:
    """The value of the stream expression ``e`` at tick ``t`` of ``rows`` (rows holding
    every input and stream value up to ``t``), by the rules of
    :mod:`fretc.compiler.stream_code` (``/`` and ``mod`` by zero NaN). Raises KeyError for
    a variable no row holds."""
    if isinstance(e, A.Var):
        return t == 0 if e.name == FIRST_TICK else rows[t][e.name]
    if isinstance(e, A.BoolLit):
        return e.value
    if isinstance(e, A.NumLit):
        return float(e.value)
    if isinstance(e, A.Unary):
        v = value_at(e.operand, rows, t)
        return (not v) if e.op == "!" else -v
    if isinstance(e, A.Call) and e.name in _PRE:
        first = e.args[0]
        if t == 0:
            return first.value if isinstance(first, A.BoolLit) else float(
                first.value) if isinstance(first, A.NumLit) else math.nan
        return value_at(e.args[1], rows, t - 1)
    if isinstance(e, A.Call) and e.name == "ite":
        c = value_at(e.args[0], rows, t)
        return value_at(e.args[1] if c else e.args[2], rows, t)
    if isinstance(e, A.Binary):
        return _binary(e.op, value_at(e.left, rows, t), value_at(e.right, rows, t))
    raise ValueError(f"not a stream expression: {type(e).__name__}")


def past_values(streams: TraceStreams, rows: Sequence[Mapping[str, Any]]) -> tuple[Any, ...]:
    """The value of every ``pre`` of ``streams``' definitions at the tick after ``rows``
    (what a tick's query reads of the past, :class:`TickTerms`), in a fixed order."""
    t = len(rows)  # (a pre at t reads the rows before t only)
    return tuple(value_at(x, rows, t) for e in streams.exprs.values() for x in A.walk(e)
                 if isinstance(x, A.Call) and x.name in _PRE)


def _binary(op: str, a: Any, b: Any) -> Any:
    """``a op b`` on plain values (the tick code's rules)."""
    logic = {"&": lambda: a and b, "|": lambda: a or b, "xor": lambda: a != b,
             "->": lambda: (not a) or b, "<->": lambda: a == b, "=": lambda: a == b,
             "!=": lambda: a != b, "<": lambda: a < b, "<=": lambda: a <= b,
             ">": lambda: a > b, ">=": lambda: a >= b, "+": lambda: a + b,
             "-": lambda: a - b, "*": lambda: a * b}
    if op in logic:
        return logic[op]()
    return {"/": _div, "mod": _mod, "^": _pow}[op](a, b)


class TickTerms:
    """The streams' values at tick ``t`` as z3 terms (module docstring), over the tick's
    numeric variables as ``real(name)`` gives them (the caller's z3 Reals, shared with the
    comparisons it solves) and the boolean inputs' values ``letter_bool(name)`` gives (a
    bool, or None when the model's letter leaves it free: then a z3 Bool of this tick).
    ``rows``: the rows of ticks ``0 .. t-1``, stream values included (the tick's query
    reads nothing else of the past: :func:`past_values`)."""

    def __init__(self, z3: Any, streams: TraceStreams, rows: Sequence[Mapping[str, Any]],
                 real: Any, letter_bool: Any):
        self.z3 = z3
        self.streams = streams
        self.rows = rows
        self.t = len(rows)
        self.real = real
        self.letter_bool = letter_bool
        self.free_bools: dict[str, Any] = {}
        #: the divisors of the tick's ``/`` terms (z3's ``x / 0`` is a number; the audit's
        #: is NaN: the caller asks each to be non-zero)
        self.divisors: list[Any] = []
        self._memo: dict[str, Any] = {}

    def stream(self, name: str) -> Any:
        """The z3 term of stream ``name`` at this tick (None when its definition holds a
        value z3 cannot take: a NaN or infinite number read through ``pre``)."""
        if name not in self._memo:
            self._memo[name] = self.term(self.streams.exprs[name])
        return self._memo[name]

    def term(self, e: A.Expr) -> Any:
        """``e`` at this tick as a z3 term, or None (see :meth:`stream`)."""
        z3 = self.z3
        if isinstance(e, A.Var):
            return self._var(e.name)
        if isinstance(e, A.BoolLit):
            return z3.BoolVal(e.value)
        if isinstance(e, A.NumLit):
            return _constant(z3, float(e.value))
        if isinstance(e, A.Call) and e.name != "ite":  # a pre: its operand at the tick before
            return _constant(z3, value_at(e, self.rows, self.t))
        if isinstance(e, A.Call):  # ite
            c, a, b = (self.term(x) for x in e.args)
            return None if c is None or a is None or b is None else z3.If(c, a, b)
        if isinstance(e, A.Unary):
            a = self.term(e.operand)
            return None if a is None else (z3.Not(a) if e.op == "!" else -a)
        return self._binary(e)

    def _var(self, name: str) -> Any:
        z3 = self.z3
        if name == FIRST_TICK:
            return z3.BoolVal(self.t == 0)
        if name in self.streams.exprs:
            return self.stream(name)
        if not self.streams.booleans.get(name, False):
            return self.real(name)
        given = self.letter_bool(name)
        if given is not None:
            return z3.BoolVal(bool(given))
        if name not in self.free_bools:
            self.free_bools[name] = z3.Bool(f"{name}@bool")
        return self.free_bools[name]

    def _binary(self, e: A.Binary) -> Any:
        z3 = self.z3
        a, b = self.term(e.left), self.term(e.right)
        if a is None or b is None or e.op in ("mod", "^"):
            return None
        ops = {"&": lambda: z3.And(a, b), "|": lambda: z3.Or(a, b),
               "xor": lambda: z3.Xor(a, b), "->": lambda: z3.Implies(a, b),
               "<->": lambda: a == b, "=": lambda: a == b, "!=": lambda: a != b,
               "<": lambda: a < b, "<=": lambda: a <= b, ">": lambda: a > b,
               ">=": lambda: a >= b, "+": lambda: a + b, "-": lambda: a - b,
               "*": lambda: a * b, "/": lambda: a / b}
        if e.op == "/":
            self.divisors.append(b)
        return ops[e.op]()


def _constant(z3: Any, v: Any) -> Any:
    """A plain value as a z3 constant; None for a NaN or an infinite number."""
    if isinstance(v, (bool, np.bool_)):
        return z3.BoolVal(bool(v))
    if not math.isfinite(v):
        return None
    from fractions import Fraction

    q = Fraction(v)
    return z3.RealVal(f"{q.numerator}/{q.denominator}")
