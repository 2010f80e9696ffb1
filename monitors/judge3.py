"""The offline judge over a trace with unknown ticks (a gap in the log, a comparison with
NaN): the verdict every way of filling them agrees on, and evidence that lies in the ticks
read (../shared/DESIGN.md, "Damage is a gap: never evidence, never the end").

* **The verdict** is FRET's finite-trace verdict three-valued (:func:`fretc.monitors.
  completions.pt_verdict`): violated when every completion of the unknown ticks violates
  the requirement, satisfied when every one satisfies it, unknown otherwise. An invariant
  broken at a tick read is violated, whatever a gap elsewhere held; one that held on every
  tick read but has unknown ticks is unknown.
* **The evidence** of a violation is FRET's interval semantics
  (:func:`fretc.monitors.interval.evaluate_requirement`) over the ticks as sampled, keeping
  only the failed triggers that are *definite*: their scope interval's bounds, the trigger
  and the response (and stop condition) from the trigger to the tick the obligation was
  missed are all known. Where none is, the evidence is the tick from which the pt formula is
  false in every completion.
* **Triggers** counted are the definite ones (the trigger and the part of its scope
  interval up to it known: the interval's end does not make a trigger); a requirement that holds in every completion
  with no definite trigger is vacuous (a note says when a trigger may have fired in unknown
  ticks).

An expression is unknown at a tick where a variable it reads is, or (fretc's NaN rule) where
one of its comparisons reads NaN; one with a FRET temporal function is unknown from its first
unknown tick on (past-time functions) or everywhere (future-time ones), a bound that is
sound if not tight.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from fretc.fretish import ast as A
from fretc.monitors.interval import Evidence, Violation, scope_of, trigger_points
from fretc.monitors.nan import nan_ticks_of

__all__ = ["Unknowns", "expression_unknown", "definite_evidence", "possible_trigger"]

_PAST = ("persisted", "occurred", "prevOcc", "preBool", "preInt", "preReal")
_FUTURE = ("persists", "occurs", "nextOcc")
#: scopes whose interval the mode's first occurrence places (monitors/interval.py, point 1)
_FIRST_OCCURRENCE = ("before", "after", "onlyBefore", "onlyAfter")


def _names(e: A.Expr, out: set[str], calls: set[str]) -> None:
    if isinstance(e, A.Var):
        out.add(e.name)
    elif isinstance(e, A.Unary):
        _names(e.operand, out, calls)
    elif isinstance(e, A.Binary):
        _names(e.left, out, calls)
        _names(e.right, out, calls)
    elif isinstance(e, A.Call):
        calls.add(e.name)
        for a in e.args:
            _names(a, out, calls)


def expression_unknown(e: A.Expr | None, unknown: Mapping[str, np.ndarray],
                       columns: Mapping[str, np.ndarray], n: int, nan_unknown: bool
                       ) -> np.ndarray:
    """Where the FRETish expression ``e`` (a condition) is unknown over ``n`` ticks (module
    docstring); all False for None."""
    out = np.zeros(n, np.bool_)
    if e is None:
        return out
    names: set[str] = set()
    calls: set[str] = set()
    _names(e, names, calls)
    for name in names:
        m = unknown.get(name)
        if m is not None:
            out |= np.asarray(m[:n], np.bool_)
    if nan_unknown:
        out |= nan_ticks_of([e], columns, n)
    if out.any() and calls & set(_FUTURE):
        out[:] = True
    elif out.any() and calls & set(_PAST):
        out = np.logical_or.accumulate(out)
    return out


@dataclass
class Unknowns:
    """Where each part of a requirement is unknown over ``n`` ticks (bool arrays): the scope
    mode ``M``, the condition ``C``, the response ``R`` and the stop condition ``S``."""

    n: int
    M: np.ndarray
    C: np.ndarray
    R: np.ndarray
    S: np.ndarray
    ticks: np.ndarray = field(default=None)  # type: ignore[arg-type]  # any part unknown; set by of()

    @classmethod
    def of(cls, req: A.Requirement, unknown: Mapping[str, np.ndarray],
           columns: Mapping[str, np.ndarray], n: int, nan_unknown: bool) -> Unknowns:
        """The unknown ticks of ``req``'s parts (:func:`expression_unknown`)."""
        def part(e):
            return expression_unknown(e, unknown, columns, n, nan_unknown)

        u = cls(n, part(req.scope.mode), part(req.condition.expr), part(req.response),
                part(req.timing.stop))
        for p in req.condition.parts:
            u.C |= part(p.expr)
        u.ticks = u.M | u.C | u.R | u.S
        return u

    def scope_known(self, s: int, e: int, scope: str) -> bool:
        """The scope interval ``[s, e]``'s bounds are known: the mode is known from the tick
        before it to the tick after it, and from the first tick for the scopes that the
        mode's first occurrence places (``before``, ``after``, ``onlyBefore``,
        ``onlyAfter``: an unknown tick earlier could be that occurrence); any interval of
        the ``null`` scope is."""
        if scope == "null":
            return True
        lo = 0 if scope in _FIRST_OCCURRENCE else max(s - 1, 0)
        return not self.M[lo:min(e + 1, self.n - 1) + 1].any()

    def in_scope_known(self, t: int, s: int, scope: str) -> bool:
        """Tick ``t`` lies in a scope interval starting at ``s`` in every completion, whatever
        the interval's end (the trigger points of an interval need its start and the ticks
        up to ``t``, not its end): the mode known on ``[s - 1, t]`` (``in``, ``notin``,
        ``onlyIn``: ``t`` in the run that starts at ``s``), on ``[0, s]`` (``after``,
        ``onlyBefore``: the interval runs to the end of the trace from the tick the mode's
        first occurrence places) or on ``[0, t]`` (``before``, ``onlyAfter``: the interval
        starts at the first tick and ``t`` precedes its end)."""
        if scope == "null":
            return True
        if scope in ("after", "onlyBefore"):
            lo, hi = 0, s
        elif scope in ("before", "onlyAfter"):
            lo, hi = 0, t
        else:
            lo, hi = max(s - 1, 0), t
        return not self.M[lo:min(hi, self.n - 1) + 1].any()

    def trigger_known(self, t: int, s: int, cond: str) -> bool:
        """The trigger point ``t`` of the interval starting at ``s`` is one in every
        completion: the condition known at ``t`` (and at ``t - 1`` for a rising edge)."""
        if cond == "null":
            return True
        if self.C[t]:
            return False
        return cond == "holding" or t == s or not self.C[t - 1]

    def obligation_known(self, lo: int, hi: int) -> bool:
        """The response and stop condition are known on ``[lo, hi]``."""
        lo, hi = max(lo, 0), min(hi, self.n - 1)
        return hi < lo or not (self.R[lo:hi + 1].any() or self.S[lo:hi + 1].any())

    def missed_known(self, w: Violation, timing: str, negate: bool) -> bool:
        """The failed obligation ``w`` fails in every completion: for an invariant over a
        window (``always``, ``never``, ``for``, not in an ``only*`` scope) the response known
        at the tick it failed; for the others the response (and stop condition) known from
        the trigger to that tick."""
        vt = min(w.violation_tick, self.n - 1)
        if not negate and timing in ("always", "never", "for"):
            return not self.R[vt]
        return self.obligation_known(min(w.trigger_tick, w.window[0]), vt)


def definite_evidence(req: A.Requirement, ev: Evidence, u: Unknowns,
                      columns: Mapping[str, np.ndarray]) -> Evidence:
    """``ev`` (the interval semantics over the ticks as sampled) with only the definite
    failed triggers listed and counted, and the definite triggers counted (module
    docstring). Its ``holds`` and ``vacuous`` are left to the caller (the three-valued
    verdict decides them)."""
    scope, cond = req.scope.kind, req.condition.kind
    negate = scope.startswith("only")
    listed: list[Violation] = []
    for w in ev.listed:
        s, e = w.interval
        if (u.scope_known(s, e, scope) and u.trigger_known(w.trigger_tick, s, cond)
                and u.missed_known(w, req.timing.kind, negate)):
            listed.append(w)
    triggers = 0
    first_trigger = None
    intervals = scope_of(req, columns, u.n)
    C = _condition(req, columns, u.n)
    for s, e in intervals:
        for t in trigger_points(cond, C, s, e):
            if u.in_scope_known(t, s, scope) and u.trigger_known(t, s, cond):
                triggers += 1
                first_trigger = t if first_trigger is None else first_trigger
    return Evidence(holds=ev.holds, vacuous=ev.vacuous, intervals=ev.intervals,
                    triggers=triggers, violations=len(listed),
                    violation=listed[0] if listed else None, ticks=ev.ticks,
                    first_interval=ev.first_interval, first_trigger=first_trigger,
                    listed=listed)


def _condition(req: A.Requirement, columns, n: int) -> np.ndarray | None:
    """The condition's truth at each tick as sampled (None without one)."""
    if req.condition.kind == "null":
        return None
    from fretc.monitors.interval import trace_signals  # the same Left/Right as the evidence

    return trace_signals(req, columns, n)[1]


def possible_trigger(u: Unknowns) -> bool:
    """Whether a trigger may have fired in unknown ticks: some tick where the scope mode or
    the condition is unknown (a requirement without either fires at each interval's start,
    which the mode decides)."""
    return bool(u.M.any() or u.C.any())
