"""FRET's interval semantics computed directly over a sampled trace: the evidence behind a
verdict, and a second opinion on it.

The monitors decide a requirement with its past-time formula; this module decides it again
from the meaning the formulas encode (``../shared/fretish/README.md`` sections 2-4; FRET's
``fretishSemantics`` manual; Giannakopoulou et al., IST 2021), without any formula code, and
says *why*:

1. **Scope intervals** (inclusive tick ranges ``[s, e]``) from the mode ``M``: ``null`` is
   the whole run; ``in`` every maximal run of ``M``; ``notin`` every maximal run of ``!M``;
   ``before`` from the start up to (not including) the first ``M`` point; ``after`` from the
   point just past the first ``M`` run to the end (none when that run reaches the end).
   ``only*`` scopes check the *complement* with the response negated: ``onlyIn`` the runs of
   ``!M``; ``onlyBefore`` from the first ``M`` point to the end; ``onlyAfter`` from the start
   to the end of the first ``M`` run.
2. **Trigger points** in each interval from the condition ``C``: ``null`` - the interval's
   first point; ``holding`` (``whenever``) - every point where ``C`` holds; ``regular`` -
   every point where ``C`` becomes true, or holds at the interval's first point.
3. **The timing's obligation** from each trigger ``t`` until the interval end ``e``
   (../shared/fretish/README.md section 4, :mod:`monitors.engines.obligations`), e.g.
   ``within k``: ``R`` somewhere in ``[t, t+k]``, vacuous when ``e < t+k``; ``only*`` scopes
   use the negated obligation.

A requirement holds iff every trigger meets its obligation; it holds *vacuously* when there is
no scope interval or no trigger. The first violation is the earliest trigger (in tick order)
whose obligation fails; :class:`Violation` gives its scope interval, the response window
looked at and the tick at which the obligation was definitely missed.

Expressions are evaluated over numpy columns (one value per tick per FRET variable) with the
same value conventions as the generated monitors (a number read as a condition is
``bool(x)``; ``/`` by zero is NaN). FRET's past/future functions ``persisted``, ``occurred``,
``persists``, ``occurs`` are evaluated relative to the scope interval (FRET's ``$Left$`` /
``$Right$``), ``preBool``/``preInt``/``preReal`` relative to the run's first tick;
``prevOcc``, ``nextOcc`` and uninterpreted functions raise :class:`EvidenceUnsupported`
(the audit then reports the monitor's verdict without interval evidence).

Cost: O(ticks + triggers) time and a few arrays of ``n`` items; the audit keeps the columns
of the requirement's own variables for this (1 byte per tick for a boolean, 8 for a number).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from collections.abc import Mapping

import numpy as np

from fretish import ast as A

from .arrays import COMPARISONS, CONNECTIVES, arith, connective, py_max, py_min, shifted
from .obligations import OBLIGATIONS, Interval, ObligationChecker

__all__ = ["EvidenceUnsupported", "Violation", "Evidence", "evaluate_requirement",
           "scope_intervals", "scope_of", "trace_signals", "trigger_points", "OBLIGATIONS"]

#: How many failed triggers an :class:`Evidence` lists (all are counted).
MAX_LISTED = 100


class EvidenceUnsupported(ValueError):
    """The requirement uses something the direct interval semantics does not evaluate
    (``prevOcc``, ``nextOcc``, an uninterpreted function, a free-form sentence)."""


@dataclass(frozen=True)
class Violation:
    """The first trigger whose obligation failed (all ticks 0-based, inclusive).

    Attributes:
        trigger_tick: the trigger point ``t``.
        interval: the scope interval ``(s, e)`` holding it.
        window: ``(lo, hi)``: the ticks the obligation was about (e.g. ``[t, t+k]`` for
            ``within k``); ``hi`` may exceed ``e`` only where FRET looks past it.
        violation_tick: the tick at which the obligation was definitely missed (for
            ``eventually`` the interval end; for ``always`` the first point where the
            response failed).
        reason: one sentence for a person, in tick numbers.
    """

    trigger_tick: int
    interval: Interval
    window: Interval
    violation_tick: int
    reason: str


@dataclass
class Evidence:
    """The interval-semantics verdict of one requirement on one trace.

    Attributes:
        holds: FRET's finite-trace verdict (equals the monitor's ``finish()``).
        vacuous: ``holds`` and there was no scope interval or no trigger.
        intervals: number of scope intervals; ``first_interval`` the first one.
        triggers: number of trigger points over all intervals.
        violations: number of triggers whose obligation failed.
        violation: the first of them, or None.
        listed: the failed triggers in order, at most :data:`MAX_LISTED` of them.
        ticks: trace length.
    """

    holds: bool
    vacuous: bool
    intervals: int
    triggers: int
    violations: int
    violation: Violation | None
    ticks: int
    first_interval: Interval | None = None
    first_trigger: int | None = None
    listed: list[Violation] = field(default_factory=list)


# --------------------------------------------------------------------------- expressions
class _Expr:
    """Evaluates fretish AST expressions over columns. ``start``/``end`` give, per tick, the
    first and last tick of the scope interval holding it (for interval-relative functions)."""

    def __init__(self, columns: Mapping[str, np.ndarray], n: int,
                 start: np.ndarray, end: np.ndarray):
        self.columns = columns
        self.n = n
        self.start = start
        self.end = end
        self.idx = np.arange(n, dtype=np.int64)

    def column(self, name: str) -> np.ndarray:
        col = self.columns.get(name)
        if col is None:
            raise KeyError(name)
        return np.asarray(col)

    def bool(self, e: A.Expr) -> np.ndarray:
        n = self.n
        if isinstance(e, A.Var):
            if e.name == "FTP":
                return self.idx == 0
            c = self.column(e.name)
            return c if c.dtype == np.bool_ else c.astype(np.bool_)
        if isinstance(e, A.BoolLit):
            return np.full(n, bool(e.value))
        if isinstance(e, A.Unary):
            if e.op == "!":
                return ~self.bool(e.operand)
            raise EvidenceUnsupported("arithmetic minus where a condition is expected")
        if isinstance(e, A.Binary):
            op = e.op
            if op in A.COMPARISON_OPS:
                x, y = self.num(e.left), self.num(e.right)
                with np.errstate(invalid="ignore"):
                    return COMPARISONS[op](x, y)
            a, b = self.bool(e.left), self.bool(e.right)
            if op in CONNECTIVES:
                return connective(op, a, b)
            raise EvidenceUnsupported(f"arithmetic '{op}' where a condition is expected")
        if isinstance(e, A.Call):
            return self.bool_call(e)
        raise EvidenceUnsupported(f"cannot evaluate {type(e).__name__}")

    def num(self, e: A.Expr) -> np.ndarray:
        n = self.n
        if isinstance(e, A.Var):
            return self.column(e.name).astype(np.float64)
        if isinstance(e, A.NumLit):
            return np.full(n, float(e.value))
        if isinstance(e, A.Unary) and e.op == "-":
            return -self.num(e.operand)
        if isinstance(e, A.Binary) and e.op in A.ARITH_OPS:
            return arith(e.op, self.num(e.left), self.num(e.right))
        if isinstance(e, A.Call):
            name, args = e.name, e.args
            if name == "ite" and len(args) == 3:
                return np.where(self.bool(args[0]), self.num(args[1]), self.num(args[2]))
            if name in ("absReal", "absInt") and len(args) == 1:
                return np.abs(self.num(args[0]))
            if name in ("minReal", "minInt", "maxReal", "maxInt") and args:
                vals = [self.num(a) for a in args]
                return py_min(vals) if name.startswith("min") else py_max(vals)
            if name in ("preInt", "preReal") and len(args) == 2:
                init, x = self.num(args[0]), self.num(args[1])
                return shifted(x, init[0] if n else None, np.float64)
        raise EvidenceUnsupported(f"cannot evaluate {type(e).__name__} as a number")

    def _int(self, a: A.Expr) -> int:
        if isinstance(a, A.NumLit) and isinstance(a.value, int) and a.value >= 0:
            return a.value
        raise EvidenceUnsupported("a temporal-function bound that is not an integer literal")

    def bool_call(self, e: A.Call) -> np.ndarray:
        name, args = e.name, e.args
        n = self.n
        if name == "ite" and len(args) == 3:
            c = self.bool(args[0])
            return (c & self.bool(args[1])) | (~c & self.bool(args[2]))
        if name == "preBool" and len(args) == 2 and isinstance(args[0], A.BoolLit):
            return shifted(self.bool(args[1]), bool(args[0].value), np.bool_)
        if name in ("persisted", "occurred", "persists", "occurs") and len(args) in (2, 3):
            if len(args) == 3 and name in ("persists", "occurs"):
                raise EvidenceUnsupported(f"{name} with three arguments")
            if len(args) == 2:
                m, k, p = 0, self._int(args[0]), self.bool(args[1])
            else:
                m, k, p = self._int(args[0]), self._int(args[1]), self.bool(args[2])
            cs = np.zeros(n + 1, np.int64)
            np.cumsum(p, out=cs[1:])
            i = self.idx

            def count(lo, hi):  # number of p in [lo, hi] (clipped to the trace)
                lo_c = np.clip(lo, 0, n)
                hi_c = np.clip(hi + 1, 0, n)
                return np.where(hi_c > lo_c, cs[hi_c] - cs[lo_c], 0)

            if name == "persisted":  # H[m,k] p & H[0,k-1] !Left
                # (in a scope condition start is -inf: H[m,k] p over the ticks that exist)
                needed = np.clip(i - m + 1, 0, n) - np.clip(i - k, 0, n)
                return (i - k >= self.start) & (count(i - k, i - m) == needed)
            if name == "occurred":  # (!Left) S[m,k] p: p in [max(start, i-k), i-m]
                return count(np.maximum(np.maximum(i - k, 0), self.start), i - m) > 0
            if name == "persists":  # G[0,k] p & G[0,k-1] !Right
                return (i + k <= self.end) & (count(i, i + k) == k + 1)
            # occurs: ((!Right) U p) & F[0,k] p
            return (count(i, self.end) > 0) & (count(i, i + k) > 0)
        raise EvidenceUnsupported(f"function {name}/{len(args)} is not evaluated by the "
                                  "interval semantics")


# --------------------------------------------------------------------------- scopes
def _runs(x: np.ndarray) -> list[Interval]:
    """Maximal runs of True in ``x``: [(start, end)] inclusive."""
    if not len(x):
        return []
    d = np.diff(np.concatenate(([0], x.astype(np.int8), [0])))
    starts = np.flatnonzero(d == 1)
    ends = np.flatnonzero(d == -1) - 1
    return list(zip(starts.tolist(), ends.tolist()))


def scope_intervals(kind: str, mode: np.ndarray | None, n: int) -> list[Interval]:
    """Scope intervals of a trace of ``n`` ticks (module docstring, point 1).

    Args:
        kind: a scope kind of :data:`fretish.ast.SCOPE_KINDS`.
        mode: the mode's truth at each tick (None for ``null``).

    Returns:
        Disjoint inclusive ``(start, end)`` tick ranges in order. For ``only*`` scopes these
        are the complement intervals in which the negated obligation is checked.
    """
    if n == 0:
        return []
    if kind == "null":
        return [(0, n - 1)]
    m = np.asarray(mode, dtype=np.bool_)
    if kind == "in":
        return _runs(m)
    if kind in ("notin", "onlyIn"):
        return _runs(~m)
    first_m = int(np.argmax(m)) if m.any() else None
    if kind == "before":
        if m[0]:
            return []
        return [(0, (first_m if first_m is not None else n) - 1)]
    if kind == "onlyBefore":
        if first_m is None:
            return []
        return [(first_m, n - 1)]
    runs = _runs(m)
    if kind == "after":
        if not runs or runs[0][1] == n - 1:
            return []
        return [(runs[0][1] + 1, n - 1)]
    if kind == "onlyAfter":
        if not runs:
            return [(0, n - 1)]
        return [(0, runs[0][1])]
    raise ValueError(f"unknown scope kind {kind!r}")


# --------------------------------------------------------------------------- the trace
def scope_of(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
             mode_start: np.ndarray, mode_end: np.ndarray) -> list[Interval]:
    """The scope intervals of ``req`` over ``n`` ticks (:func:`scope_intervals`), its mode
    evaluated with ``mode_start`` / ``mode_end`` as the interval bounds of its temporal
    functions."""
    scope = req.scope.kind
    whole = _Expr(columns, n, mode_start, mode_end)
    mode = whole.bool(req.scope.mode) if scope != "null" else None
    return scope_intervals(scope, mode, n)


def trace_signals(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
                  intervals: list[Interval]
                  ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """(response ``R``, condition ``C`` or None, stop condition ``S`` or None) at each tick,
    their temporal functions relative to the scope interval holding the tick."""
    start = np.arange(n, dtype=np.int64)
    end = np.arange(n, dtype=np.int64)
    for s, e in intervals:
        start[s:e + 1] = s
        end[s:e + 1] = e
    ex = _Expr(columns, n, start, end)
    R = ex.bool(req.response)
    C = ex.bool(req.condition.expr) if req.condition.kind != "null" else None
    S = ex.bool(req.timing.stop) if req.timing.kind in A.STOP_TIMINGS else None
    return R, C, S


def trigger_points(cond: str, C: np.ndarray | None, s: int, e: int) -> list[int]:
    """The trigger points of the scope interval ``[s, e]`` (module docstring, point 2)."""
    if cond == "null":
        return [s]
    if cond == "holding":
        return (np.flatnonzero(C[s:e + 1]) + s).tolist()
    seg = C[s:e + 1]
    rise = seg.copy()
    rise[1:] &= ~seg[:-1]
    return (np.flatnonzero(rise) + s).tolist()


# --------------------------------------------------------------------------- entry point
def evaluate_requirement(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
                         duration_ticks: int | None = None) -> Evidence:
    """Decide ``req`` on a trace of ``n`` ticks by FRET's interval semantics.

    Args:
        req: a parsed (not free-form) requirement.
        columns: FRET variable -> 1-D array of ``n`` values (bool or numeric).
        n: number of ticks (>= 1).
        duration_ticks: the timing's duration in ticks (``within``/``for``/``after``), as
            converted by the compiler (``Formalization.ticks``); None reads the duration's
            amount as ticks.

    Returns:
        An :class:`Evidence`.

    Raises:
        EvidenceUnsupported: free-form, or a function this module does not evaluate.
        KeyError: a variable missing from ``columns``.
        ValueError: ``n`` < 1.
    """
    if req.freeform or req.response is None:
        raise EvidenceUnsupported("a free-form requirement has no semantics")
    if n < 1:
        raise ValueError("the interval semantics needs at least one tick")
    scope, cond, timing = req.scope.kind, req.condition.kind, req.timing.kind
    # scope conditions use FRET's endpoint-free function forms (../shared/fretish/README.md
    # section 6b): no interval start or end
    intervals = scope_of(req, columns, n, np.full(n, -(1 << 40), np.int64),
                         np.full(n, 1 << 40, np.int64))
    R, C, S = trace_signals(req, columns, n, intervals)
    k = None
    if timing in A.DURATION_TIMINGS:
        if duration_ticks is not None:
            k = int(duration_ticks)
        else:
            amount = Fraction(req.timing.duration.amount)
            if amount.denominator != 1:
                raise EvidenceUnsupported("a fractional duration without a tick period")
            k = int(amount)
    checker = ObligationChecker(timing, scope.startswith("only"), R, S, k)
    triggers = violations = 0
    first: Violation | None = None
    listed: list[Violation] = []
    first_trigger: int | None = None
    for s, e in intervals:
        for t in trigger_points(cond, C, s, e):
            triggers += 1
            if first_trigger is None:
                first_trigger = t
            bad = checker.check(t, e)
            if bad is not None:
                violations += 1
                if len(listed) < MAX_LISTED:
                    window, vt, reason = bad
                    listed.append(Violation(t, (s, e), window, vt, reason))
                    if first is None:
                        first = listed[0]
    holds = violations == 0
    return Evidence(holds=holds, vacuous=holds and (not intervals or triggers == 0),
                    intervals=len(intervals), triggers=triggers, violations=violations,
                    violation=first, ticks=n,
                    first_interval=intervals[0] if intervals else None,
                    first_trigger=first_trigger, listed=listed)
