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
   (../shared/fretish/README.md section 4, :mod:`fretc.monitors.obligations`), e.g.
   ``within k``: ``R`` somewhere in ``[t, t+k]``, vacuous when ``e < t+k``; ``only*`` scopes
   use the negated obligation.

A requirement holds iff every trigger meets its obligation; it holds *vacuously* when there is
no scope interval or no trigger. The first violation is the earliest trigger (in tick order)
whose obligation fails; :class:`Violation` gives its scope interval, the response window
looked at and the tick at which the obligation was definitely missed.

Expressions are evaluated over numpy columns by :mod:`fretc.monitors.expressions` (one value per tick
per FRET variable) with the
same value conventions as the generated monitors (a number read as a condition is
``bool(x)``; ``/`` by zero is NaN). Every FRET temporal function is evaluated from the
"meaning" column of ``../shared/fretish/README.md`` section 6b, relative to FRET's ``Left`` /
``Right`` of the requirement's scope (:func:`endpoints`) in conditions, responses and stop
conditions, and in FRET's endpoint-free forms inside scope conditions: ``persisted`` and
``occurred`` (2 and 3 arguments), ``persists`` and ``occurs`` (2 and 3 arguments),
``prevOcc`` / ``at the previous occurrence of`` (true at an interval's first position),
``nextOcc`` / ``at the next occurrence of`` (true at its last), ``preBool`` / ``preInt`` /
``preReal`` (relative to the run's first tick), nested in any way. Future-time functions near
the end of the trace read FRET's absorbing state after it (every variable false, every
number 0; section 6's trace model), where an interval of ``notin``/``onlyIn``/``before``
reaching the end has no ``Right``. Only uninterpreted functions and free-form sentences raise
:class:`EvidenceUnsupported` (the audit then reports the monitor's verdict without interval
evidence). tests/monitors/test_evidence_functions.py checks all of this against the
generated monitors, FRET's formulas and an independent oracle on random sentences.

Cost: O(ticks + triggers) time and a few arrays of ``n`` items; the audit keeps the columns
of the requirement's own variables for this (1 byte per tick for a boolean, 8 for a number).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any

import numpy as np

from fretc.fretish import ast as A

from fretc.monitors.expressions import ColumnExpressions, EvidenceUnsupported
from fretc.monitors.obligations import OBLIGATIONS, Interval, ObligationChecker

if TYPE_CHECKING:
    from fretc.monitors.unknowns import Unknowns

__all__ = ["EvidenceUnsupported", "Violation", "Evidence", "evaluate_requirement", "verdict_of",
           "duration_of", "favoured",
           "endpoints", "scope_mode",
           "scope_intervals", "scope_of", "trace_signals", "trigger_points", "OBLIGATIONS"]

#: How many failed triggers an :class:`Evidence` lists (all are counted).
MAX_LISTED = 100


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


# --------------------------------------------------------------------------- scopes
def endpoints(kind: str, mode: np.ndarray | None, n: int) -> tuple[np.ndarray, np.ndarray]:
    """FRET's ``Left`` and ``Right`` of a scope (``../shared/fretish/README.md`` section 6b's
    table) at each of the ``n`` ticks of a finite trace: ``Left`` (a pt formula) marks the
    first position of a scope interval, ``Right`` (an ft formula, false after the last tick)
    its last position, as the temporal functions of conditions, responses and stop
    conditions see them.

    Args:
        kind: a scope kind of :data:`fretc.fretish.ast.SCOPE_KINDS`.
        mode: the mode's truth at each tick (None for ``null``).
        n: ticks (>= 1).

    Returns:
        (left, right): two bool arrays of ``n`` items.

    FRET's ``Right`` of ``notin``/``onlyIn``/``before`` has no ``LAST`` disjunct, so an
    interval of those scopes reaching the last tick has no ``Right`` (its functions look
    into the absorbing state after the trace); ``onlyAfter``'s is the end of every ``m`` run.
    """
    i = np.arange(n)
    first = i == 0
    last = i == n - 1
    if kind == "null" or mode is None:
        return first, last.copy()
    m = np.asarray(mode, dtype=np.bool_)
    prev = np.concatenate(([False], m[:-1]))           # Y m (false at 0)
    prev_z = np.concatenate(([True], m[:-1]))          # Z m (true at 0)
    nxt = np.concatenate((m[1:], [False]))             # X m (unused at the last tick)
    run_start = m & ~prev                              # m & Z !m
    run_end = m & (last | ~nxt)                        # m & (LAST | X !m)
    gap_start = ~m & prev_z                            # !m & Z m
    gap_end = ~m & ~last & nxt                         # !m & !LAST & X m
    if kind == "in":
        return run_start, run_end
    if kind in ("notin", "onlyIn"):
        return gap_start, gap_end
    if kind == "after":
        fall = ~m & prev                               # first !m & Y m
        left = np.zeros(n, np.bool_)
        if fall.any():
            left[int(np.argmax(fall))] = True
        return left, last.copy()
    if kind == "onlyAfter":
        return first, run_end
    if kind == "before":
        return first, gap_end
    if kind == "onlyBefore":
        left = np.zeros(n, np.bool_)
        if m.any():
            left[int(np.argmax(m))] = True             # m & Z !m & Z H !m
        return left, last.copy()
    raise ValueError(f"unknown scope kind {kind!r}")


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
        kind: a scope kind of :data:`fretc.fretish.ast.SCOPE_KINDS`.
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
def scope_mode(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int
               ) -> np.ndarray | None:
    """The truth of ``req``'s scope mode (or scope condition) at each of ``n`` ticks, its
    temporal functions in FRET's endpoint-free forms (``../shared/fretish/README.md``
    section 6b); None for the ``null`` scope."""
    if req.scope.kind == "null":
        return None
    assert req.scope.mode is not None  # (a scope other than null has its mode)
    return ColumnExpressions(columns, n, free=True).bool(req.scope.mode)[:n]


def scope_of(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int
             ) -> list[Interval]:
    """The scope intervals of ``req`` over ``n`` ticks (:func:`scope_intervals`), its mode
    evaluated with FRET's endpoint-free function forms (:func:`scope_mode`)."""
    return scope_intervals(req.scope.kind, scope_mode(req, columns, n), n)


def trace_signals(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
                  intervals: list[Interval] | None = None
                  ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """(response ``R``, condition ``C`` or None, stop condition ``S`` or None) at each of
    the ``n`` ticks, their temporal functions relative to FRET's ``Left``/``Right`` of the
    requirement's scope (:func:`endpoints`, from the scope mode; ``intervals`` is accepted
    for compatibility and not needed)."""
    return _signals(req, columns, n, scope_mode(req, columns, n))


def _signals(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
             mode: np.ndarray | None):
    """:func:`trace_signals` given the scope mode's truth at each tick."""
    left, right = endpoints(req.scope.kind, mode, n)
    ex = ColumnExpressions(columns, n, left, right)
    # (a formalizable requirement has a response, a condition's expression unless null, and
    # a stop condition with until and before)
    assert req.response is not None
    R = ex.bool(req.response)[:n]
    C = ex.bool(req.condition.expr)[:n] if req.condition.kind != "null" else None  # type: ignore[arg-type]
    S = ex.bool(req.timing.stop)[:n] if req.timing.kind in A.STOP_TIMINGS else None  # type: ignore[arg-type]
    return R, C, S


def trigger_points(cond: str, C: np.ndarray | None, s: int, e: int) -> list[int]:
    """The trigger points of the scope interval ``[s, e]`` (module docstring, point 2)."""
    if cond == "null":
        return [s]
    assert C is not None  # (a condition other than null has its truth)
    if cond == "holding":
        return (np.flatnonzero(C[s:e + 1]) + s).tolist()
    seg = C[s:e + 1]
    rise = seg.copy()
    rise[1:] &= ~seg[:-1]
    return (np.flatnonzero(rise) + s).tolist()


# --------------------------------------------------------------------------- entry point
def evaluate_requirement(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
                         duration_ticks: int | None = None, favour: Unknowns | None = None
                         ) -> Evidence:
    """Decide ``req`` on a trace of ``n`` ticks by FRET's interval semantics.

    Args:
        req: a parsed (not free-form) requirement.
        columns: FRET variable -> 1-D array of ``n`` values (bool or numeric).
        n: number of ticks (>= 1).
        duration_ticks: the timing's duration in ticks (``within``/``for``/``after``), as
            converted by the compiler (``Formalization.ticks``); None reads the duration's
            amount as ticks.
        favour: where the condition, response and stop condition are unknown (an object
            with bool arrays ``C``, ``R``, ``S``: :class:`fretc.monitors.unknowns.Unknowns`):
            there they take the value that meets the obligation (no trigger, the response
            the timing wants, the stop condition that ends it), so the failures left are
            those the known ticks make; None: the columns as they are.

    Returns:
        An :class:`Evidence`.

    Raises:
        EvidenceUnsupported: free-form, or an uninterpreted function.
        KeyError: a variable missing from ``columns``.
        ValueError: ``n`` < 1.
    """
    if req.freeform or req.response is None:
        raise EvidenceUnsupported("a free-form requirement has no semantics")
    if n < 1:
        raise ValueError("the interval semantics needs at least one tick")
    scope, cond, timing = req.scope.kind, req.condition.kind, req.timing.kind
    # scope conditions use FRET's endpoint-free function forms (../shared/fretish/README.md
    # section 6b); conditions, responses and stop conditions the scope's Left/Right
    mode = scope_mode(req, columns, n)
    intervals = scope_intervals(scope, mode, n)
    R, C, S = _signals(req, columns, n, mode)
    if favour is not None:
        R, C, S = favoured(req, R, C, S, favour)
    k = duration_of(req, duration_ticks)
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


def duration_of(req: A.Requirement, duration_ticks: int | None) -> int | None:
    """The timing's duration in ticks (``within``/``for``/``after``; None for the timings
    without one): ``duration_ticks`` as the compiler converted it
    (``Formalization.ticks``), or without it the duration's amount read as ticks.

    Raises:
        EvidenceUnsupported: a fractional amount without ``duration_ticks`` (a duration in
            time units with no tick period)."""
    if req.timing.kind not in A.DURATION_TIMINGS:
        return None
    if duration_ticks is not None:
        return int(duration_ticks)
    assert req.timing.duration is not None  # (a duration timing has it)
    amount = Fraction(req.timing.duration.amount)
    if amount.denominator != 1:
        raise EvidenceUnsupported("a fractional duration without a tick period")
    return int(amount)


def favoured(req: A.Requirement, R: np.ndarray, C: np.ndarray | None,
             S: np.ndarray | None, favour: Any
             ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """``R, C, S`` with their unknown ticks (``favour``) set to meet the obligation: no
    trigger; the response the timing wants (true, false for ``never``, negated in ``only*``
    scopes); the stop condition that ends an ``until`` and does not end a ``before``."""
    want = (not req.scope.kind.startswith("only")) != (req.timing.kind == "never")
    R = np.where(favour.R[:len(R)], want, R)
    if C is not None:
        C = np.where(favour.C[:len(C)], False, C)
    if S is not None:
        S = np.where(favour.S[:len(S)], req.timing.kind == "until", S)
    return R, C, S


def verdict_of(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
               duration_ticks: int | None = None) -> str:
    """FRET's verdict of ``req`` on a finite trace as a word: ``"satisfied"``,
    ``"vacuous"``, ``"violated"``, or ``"unknown"`` when the interval semantics cannot
    evaluate it (:class:`EvidenceUnsupported`: an uninterpreted function, a free-form
    sentence). Arguments and other errors as :func:`evaluate_requirement`; this is the
    :data:`fretc.check.witness.Judge` ``fretc check`` passes for its witnesses."""
    try:
        ev = evaluate_requirement(req, columns, n, duration_ticks)
    except EvidenceUnsupported:
        return "unknown"
    return "violated" if not ev.holds else ("vacuous" if ev.vacuous else "satisfied")
