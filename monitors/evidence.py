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
   (../shared/fretish/README.md section 4), e.g. ``within k``: ``R`` somewhere in ``[t, t+k]``, vacuous when
   ``e < t+k``; ``only*`` scopes use the negated obligation.

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
from typing import Dict, List, Mapping, Optional, Tuple

import numpy as np

from fretish import ast as A

__all__ = ["EvidenceUnsupported", "Violation", "Evidence", "evaluate_requirement",
           "scope_intervals", "OBLIGATIONS"]

Interval = Tuple[int, int]


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
    violation: Optional[Violation]
    ticks: int
    first_interval: Optional[Interval] = None
    first_trigger: Optional[int] = None
    listed: List[Violation] = field(default_factory=list)


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
                    return {"=": np.equal, "!=": np.not_equal, "<": np.less,
                            "<=": np.less_equal, ">": np.greater,
                            ">=": np.greater_equal}[op](x, y)
            a, b = self.bool(e.left), self.bool(e.right)
            if op == "&":
                return a & b
            if op == "|":
                return a | b
            if op == "xor":
                return a != b
            if op == "->":
                return ~a | b
            if op == "<->":
                return a == b
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
            x, y = self.num(e.left), self.num(e.right)
            with np.errstate(all="ignore"):
                if e.op == "+":
                    return x + y
                if e.op == "-":
                    return x - y
                if e.op == "*":
                    return x * y
                if e.op == "/":
                    return np.where(y == 0, np.nan, x / np.where(y == 0, 1.0, y))
                if e.op == "mod":
                    return np.fmod(x, y)
                out = np.power(x, y)
                return np.where(np.isinf(out) & np.isfinite(x) & np.isfinite(y), np.nan, out)
        if isinstance(e, A.Call):
            name, args = e.name, e.args
            if name == "ite" and len(args) == 3:
                return np.where(self.bool(args[0]), self.num(args[1]), self.num(args[2]))
            if name in ("absReal", "absInt") and len(args) == 1:
                return np.abs(self.num(args[0]))
            if name in ("minReal", "minInt", "maxReal", "maxInt") and args:
                vals = [self.num(a) for a in args]
                out = vals[0]
                for b in vals[1:]:
                    out = np.where((b < out) if name.startswith("min") else (b > out), b, out)
                return out
            if name in ("preInt", "preReal") and len(args) == 2:
                init, x = self.num(args[0]), self.num(args[1])
                out = np.empty(n)
                if n:
                    out[0] = init[0]
                    out[1:] = x[:-1]
                return out
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
            p = self.bool(args[1])
            out = np.empty(n, np.bool_)
            if n:
                out[0] = bool(args[0].value)
                out[1:] = p[:-1]
            return out
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
def _runs(x: np.ndarray) -> List[Interval]:
    """Maximal runs of True in ``x``: [(start, end)] inclusive."""
    if not len(x):
        return []
    d = np.diff(np.concatenate(([0], x.astype(np.int8), [0])))
    starts = np.flatnonzero(d == 1)
    ends = np.flatnonzero(d == -1) - 1
    return list(zip(starts.tolist(), ends.tolist()))


def scope_intervals(kind: str, mode: Optional[np.ndarray], n: int) -> List[Interval]:
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


# --------------------------------------------------------------------------- obligations
#: The obligation of each timing, for documentation and reports: (plain, negated).
OBLIGATIONS: Dict[str, Tuple[str, str]] = {
    "immediately": ("R at t", "!R at t"),
    "next": ("R at t+1 (none if t = e)", "!R at t+1 (none if t = e)"),
    "finally": ("R at e", "!R at e"),
    "eventually": ("R somewhere in [t, e]", "!R everywhere in [t, e]"),
    "null": ("R somewhere in [t, e]", "!R everywhere in [t, e]"),
    "always": ("R everywhere in [t, e]", "!R somewhere in [t, e]"),
    "never": ("!R everywhere in [t, e]", "R somewhere in [t, e]"),
    "within": ("R somewhere in [t, t+k] (none if e < t+k)",
               "!R everywhere in [t, min(t+k, e)]"),
    "for": ("R everywhere in [t, min(t+k, e)]", "!R somewhere in [t, t+k] (none if e < t+k)"),
    "after": ("!R in [t, min(t+k, e)] and R at t+k+1 (if t+k+1 <= e)",
              "not (!R in [t, t+k] and R at t+k+1 <= e)"),
    "until": ("R everywhere from t until S holds (or to e)",
              "S nowhere in [t, j], j = first !R at or after t (or e)"),
    "before": ("S nowhere in [t, j], j = first R at or after t (or e)",
               "!R everywhere from t until S holds (or to e)"),
}


def _next_true(x: np.ndarray) -> np.ndarray:
    """``out[i]`` = smallest j >= i with x[j], else n (int32 array)."""
    n = len(x)
    idx = np.where(x, np.arange(n, dtype=np.int32), np.int32(n))
    return np.minimum.accumulate(idx[::-1])[::-1] if n else idx


class _Ints:
    """Read-only int view of an int array (numpy scalars become Python ints)."""

    __slots__ = ("a",)

    def __init__(self, a: np.ndarray):
        self.a = a

    def __getitem__(self, i: int) -> int:
        return int(self.a[i])


class _Bools(_Ints):
    __slots__ = ()

    def __getitem__(self, i: int) -> bool:
        return bool(self.a[i])


class _Checker:
    """Obligations of one timing over a trace (module docstring, point 3)."""

    def __init__(self, timing: str, negate: bool, R: np.ndarray, S: Optional[np.ndarray],
                 k: Optional[int]):
        self.timing = timing
        self.negate = negate
        # numpy arrays (not lists): a few bytes a tick, for long logs
        self.R = _Bools(R)
        self.k = k or 0
        self.nR = _Ints(_next_true(R))
        self.nNR = _Ints(_next_true(~R))
        self.nS = _Ints(_next_true(S)) if S is not None else None

    def check(self, t: int, e: int) -> Optional[Tuple[Interval, int, str]]:
        """None if the obligation of trigger ``t`` (interval end ``e``) holds, else (window,
        violation tick, reason)."""
        R, nR, nNR, k = self.R, self.nR, self.nNR, self.k
        kind = "eventually" if self.timing == "null" else self.timing
        want = not self.negate  # the value R must take where the obligation says "R"
        rname = "R" if want else "!R"
        nWant, nUnwant = (nR, nNR) if want else (nNR, nR)

        def everywhere(lo, hi):  # `want` on [lo, hi]
            bad = nUnwant[lo]
            return None if bad > hi else bad

        def somewhere(lo, hi):
            return nWant[lo] <= hi

        if kind == "immediately":
            if R[t] != want:
                return (t, t), t, f"{rname} does not hold at the trigger t={t}"
            return None
        if kind == "next":
            if t == e or R[t + 1] == want:
                return None
            return (t + 1, t + 1), t + 1, f"{rname} does not hold at t+1={t + 1}"
        if kind == "finally":
            if R[e] == want:
                return None
            return (e, e), e, f"{rname} does not hold at the interval end e={e}"
        if kind == "eventually":
            if not self.negate:
                if somewhere(t, e):
                    return None
                return (t, e), e, f"R never holds in [{t}, {e}]"
            bad = everywhere(t, e)
            if bad is None:
                return None
            return (t, e), bad, f"R holds at {bad} (only* scope: R must not hold in [{t}, {e}])"
        if kind in ("always", "never"):
            about_r = kind == "always"  # the obligation is about R (always) or !R (never)
            name = "R" if about_r else "!R"
            if not self.negate:  # `name` everywhere in [t, e]
                bad = (nNR if about_r else nR)[t]
                if bad > e:
                    return None
                return (t, e), bad, f"{name} fails at {bad} in [{t}, {e}]"
            # only* scope: the negation, "!name" somewhere in [t, e]
            if (nNR if about_r else nR)[t] <= e:
                return None
            return (t, e), e, f"{name} holds everywhere in [{t}, {e}] (only* scope)"
        if kind == "within":
            if not self.negate:
                if e < t + k or somewhere(t, t + k):
                    return None
                return (t, t + k), t + k, f"R does not hold in [{t}, {t + k}]"
            hi = min(t + k, e)
            bad = everywhere(t, hi)
            if bad is None:
                return None
            return (t, hi), bad, f"R holds at {bad} in [{t}, {hi}] (only* scope)"
        if kind == "for":
            if not self.negate:
                hi = min(t + k, e)
                bad = everywhere(t, hi)
                if bad is None:
                    return None
                return (t, hi), bad, f"R fails at {bad} in [{t}, {hi}]"
            if e < t + k or somewhere(t, t + k):
                return None
            return (t, t + k), t + k, f"!R never holds in [{t}, {t + k}] (only* scope)"
        if kind == "after":
            if not self.negate:
                hi = min(t + k, e)
                early = nR[t]
                if early <= hi:
                    return (t, hi), early, f"R holds at {early}, before t+k+1={t + k + 1}"
                if e >= t + k + 1 and not R[t + k + 1]:
                    return (t, t + k + 1), t + k + 1, f"R does not hold at t+k+1={t + k + 1}"
                return None
            # negated: violated iff e >= t+k+1, !R on [t, t+k] and R at t+k+1
            if e >= t + k + 1 and nR[t] == t + k + 1:
                return (t, t + k + 1), t + k + 1, (f"R first holds exactly at t+k+1={t + k + 1}"
                                                    " (only* scope)")
            return None
        if kind in ("until", "before"):
            nS = self.nS
            assert nS is not None
            if (kind == "until") == want:
                # `want` everywhere from t up to (not incl.) the first S, capped at e
                ks = nS[t]
                hi = min(ks - 1, e)
                if hi < t:
                    return None
                bad = everywhere(t, hi)
                if bad is None:
                    return None
                return (t, hi), bad, f"{rname} fails at {bad} before the stop condition"
            # no S in [t, j], j = first point >= t where `want` holds, capped at e
            j = min(nWant[t], e)
            s = nS[t]
            if s > j:
                return None
            return (t, j), s, (f"the stop condition holds at {s} before {rname} held "
                               f"(window [{t}, {j}])")
        raise ValueError(f"unknown timing {self.timing!r}")


# --------------------------------------------------------------------------- entry point
def evaluate_requirement(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
                         duration_ticks: Optional[int] = None) -> Evidence:
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
    negate = scope.startswith("only")
    # scope conditions use FRET's endpoint-free function forms (../shared/fretish/README.md
    # section 6b): no interval start or end
    whole = _Expr(columns, n, np.full(n, -(1 << 40), np.int64), np.full(n, 1 << 40, np.int64))
    mode = whole.bool(req.scope.mode) if scope != "null" else None
    intervals = scope_intervals(scope, mode, n)
    start = np.arange(n, dtype=np.int64)
    end = np.arange(n, dtype=np.int64)
    for s, e in intervals:
        start[s:e + 1] = s
        end[s:e + 1] = e
    ex = _Expr(columns, n, start, end)
    R = ex.bool(req.response)
    C = ex.bool(req.condition.expr) if cond != "null" else None
    S = ex.bool(req.timing.stop) if timing in A.STOP_TIMINGS else None
    k = None
    if timing in A.DURATION_TIMINGS:
        if duration_ticks is not None:
            k = int(duration_ticks)
        else:
            amount = Fraction(req.timing.duration.amount)
            if amount.denominator != 1:
                raise EvidenceUnsupported("a fractional duration without a tick period")
            k = int(amount)
    checker = _Checker(timing, negate, R, S, k)
    triggers = violations = 0
    first: Optional[Violation] = None
    listed: List[Violation] = []
    first_trigger: Optional[int] = None
    for s, e in intervals:
        if cond == "null":
            points = [s]
        elif cond == "holding":
            points = (np.flatnonzero(C[s:e + 1]) + s).tolist()
        else:
            seg = C[s:e + 1]
            rise = seg.copy()
            rise[1:] &= ~seg[:-1]
            points = (np.flatnonzero(rise) + s).tolist()
        for t in points:
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
