"""Where the parts of a requirement are unknown over a trace (:class:`Unknowns`): the ticks a
gap of the log leaves unknown and the ticks at which a comparison reads NaN, per part (the
scope mode, the condition, the response, the stop condition), and the questions the
three-valued judge asks of them (:mod:`fretc.monitors.judge3`: is a scope interval's bound,
a trigger, an obligation known in every completion?).

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
from fretc.fretish.fret_since import SINCE
from fretc.monitors.nan import nan_ticks_of

__all__ = ["Unknowns", "expression_unknown", "possible_trigger"]

_PAST = ("persisted", "occurred", "prevOcc", "preBool", "preInt", "preReal", SINCE)
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
    mode ``M``, the condition ``C``, the response ``R`` and the stop condition ``S``; and
    the gap ticks ``stretch`` (each one tick or more, how many not known; None: none)."""

    n: int
    M: np.ndarray
    C: np.ndarray
    R: np.ndarray
    S: np.ndarray
    ticks: np.ndarray = field(default=None)  # type: ignore[arg-type]  # any part unknown; set by of()
    stretch: np.ndarray | None = None

    @classmethod
    def of(cls, req: A.Requirement, unknown: Mapping[str, np.ndarray],
           columns: Mapping[str, np.ndarray], n: int, nan_unknown: bool,
           stretch: np.ndarray | None = None) -> Unknowns:
        """The unknown ticks of ``req``'s parts (:func:`expression_unknown`); ``stretch``:
        the gap ticks (bool array of ``n``, or None)."""
        def part(e):
            return expression_unknown(e, unknown, columns, n, nan_unknown)

        u = cls(n, part(req.scope.mode), part(req.condition.expr), part(req.response),
                part(req.timing.stop))
        if stretch is not None and np.any(stretch[:n]):
            u.stretch = np.asarray(stretch[:n], np.bool_)
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

    def stretched(self, lo: int, hi: int) -> bool:
        """A gap tick lies in ``[lo, hi]``: the distance between those ticks is not known."""
        return self.stretch is not None and bool(self.stretch[max(lo, 0):hi + 1].any())

    def obligation_known(self, lo: int, hi: int) -> bool:
        """The response and stop condition are known on ``[lo, hi]``."""
        lo, hi = max(lo, 0), min(hi, self.n - 1)
        return hi < lo or not (self.R[lo:hi + 1].any() or self.S[lo:hi + 1].any())

    def missed_known(self, trigger_tick: int, window_start: int, violation_tick: int,
                     timing: str, negate: bool) -> bool:
        """The obligation of the trigger at ``trigger_tick``, whose window starts at
        ``window_start`` and which failed at ``violation_tick`` (the fields of a
        :class:`fretc.monitors.interval.Violation`), fails in every completion: for an
        invariant over a window (``always``, ``never``, ``for``, not in an ``only*`` scope)
        the response known at the tick it failed (for ``for``, with no gap tick from the
        trigger to it: a gap of more ticks puts it past the duration); for the others the
        response (and stop condition) known from the trigger to that tick."""
        vt = min(violation_tick, self.n - 1)
        if not negate and timing in ("always", "never", "for"):
            if timing == "for" and self.stretched(min(trigger_tick, window_start), vt):
                return False
            return not self.R[vt]
        return self.obligation_known(min(trigger_tick, window_start), vt)


def possible_trigger(u: Unknowns) -> bool:
    """Whether a trigger may have fired in unknown ticks: some tick where the scope mode or
    the condition is unknown (a requirement without either fires at each interval's start,
    which the mode decides)."""
    return bool(u.M.any() or u.C.any())
