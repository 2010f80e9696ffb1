"""The obligations of FRET's timings (``../shared/fretish/README.md`` section 4): from a
trigger ``t`` until its scope interval's end ``e``, e.g. ``within k``: ``R`` somewhere in
``[t, t+k]``, vacuous when ``e < t+k``; ``only*`` scopes check the negated obligation
(:data:`OBLIGATIONS`). :class:`ObligationChecker` answers, for one trigger, whether the
obligation failed, the window it looked at and the tick at which it was definitely missed,
in O(1) per trigger from next-true indexes over the trace."""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["OBLIGATIONS", "ObligationChecker", "Interval"]

Interval = tuple[int, int]


#: The obligation of each timing, for documentation and reports: (plain, negated).
OBLIGATIONS: dict[str, tuple[str, str]] = {
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


class ObligationChecker:
    """The obligation of one timing from each trigger over a trace (module docstring).

    Args:
        timing: a timing kind of :data:`fretc.fretish.ast.TIMING_KINDS`.
        negate: an ``only*`` scope (the negated obligation is checked).
        R, S: the response and stop condition at each tick (bool arrays; S None without one).
        k: the duration in ticks (``within``/``for``/``after``).
    """

    def __init__(self, timing: str, negate: bool, R: np.ndarray, S: np.ndarray | None,
                 k: int | None):
        self.timing = timing
        self.negate = negate
        # numpy arrays (not lists): a few bytes a tick, for long logs
        self.R = _Bools(R)
        self.k = k or 0
        self._S = S

    # (each next-true index, 4 bytes a tick, is made when a timing first reads it)
    @functools.cached_property
    def nR(self) -> _Ints:
        """The first tick at or after each where R holds (n where none)."""
        return _Ints(_next_true(self.R.a))

    @functools.cached_property
    def nNR(self) -> _Ints:
        """The first tick at or after each where R does not hold (n where none)."""
        return _Ints(_next_true(~self.R.a))

    @functools.cached_property
    def nS(self) -> _Ints | None:
        """The first tick at or after each where S holds (n where none); None without S."""
        return _Ints(_next_true(self._S)) if self._S is not None else None

    def check(self, t: int, e: int) -> tuple[Interval, int, str] | None:
        """None if the obligation of trigger ``t`` (interval end ``e``) holds, else (window,
        violation tick, reason)."""
        kind = "eventually" if self.timing == "null" else self.timing
        method = _CHECKS.get(kind)
        if method is None:
            raise ValueError(f"unknown timing {self.timing!r}")
        return method(self, kind, t, e)

    @property
    def want(self) -> bool:
        """The value R must take where the obligation says "R" (False in only* scopes)."""
        return not self.negate

    @property
    def rname(self) -> str:
        """How the response is named in reasons: ``R``, or ``!R`` in only* scopes."""
        return "R" if self.want else "!R"

    def everywhere(self, lo: int, hi: int) -> int | None:
        """None when ``want`` holds on ``[lo, hi]``, else the first tick where it fails."""
        bad = (self.nNR if self.want else self.nR)[lo]
        return None if bad > hi else bad

    def somewhere(self, lo: int, hi: int) -> bool:
        """``want`` holds at some tick of ``[lo, hi]``."""
        return (self.nR if self.want else self.nNR)[lo] <= hi

    def _immediately(self, kind: str, t: int, e: int):
        if self.R[t] != self.want:
            return (t, t), t, f"{self.rname} does not hold at the trigger t={t}"
        return None

    def _next(self, kind: str, t: int, e: int):
        if t == e or self.R[t + 1] == self.want:
            return None
        return (t + 1, t + 1), t + 1, f"{self.rname} does not hold at t+1={t + 1}"

    def _finally(self, kind: str, t: int, e: int):
        if self.R[e] == self.want:
            return None
        return (e, e), e, f"{self.rname} does not hold at the interval end e={e}"

    def _eventually(self, kind: str, t: int, e: int):
        if not self.negate:
            if self.somewhere(t, e):
                return None
            return (t, e), e, f"R never holds in [{t}, {e}]"
        bad = self.everywhere(t, e)
        if bad is None:
            return None
        return (t, e), bad, f"R holds at {bad} (only* scope: R must not hold in [{t}, {e}])"

    def _always_never(self, kind: str, t: int, e: int):
        about_r = kind == "always"  # the obligation is about R (always) or !R (never)
        name = "R" if about_r else "!R"
        first_fail = (self.nNR if about_r else self.nR)[t]
        if not self.negate:  # `name` everywhere in [t, e]
            if first_fail > e:
                return None
            return (t, e), first_fail, f"{name} fails at {first_fail} in [{t}, {e}]"
        # only* scope: the negation, "!name" somewhere in [t, e]
        if first_fail <= e:
            return None
        return (t, e), e, f"{name} holds everywhere in [{t}, {e}] (only* scope)"

    def _within(self, kind: str, t: int, e: int):
        k = self.k
        if not self.negate:
            if e < t + k or self.somewhere(t, t + k):
                return None
            return (t, t + k), t + k, f"R does not hold in [{t}, {t + k}]"
        hi = min(t + k, e)
        bad = self.everywhere(t, hi)
        if bad is None:
            return None
        return (t, hi), bad, f"R holds at {bad} in [{t}, {hi}] (only* scope)"

    def _for(self, kind: str, t: int, e: int):
        k = self.k
        if not self.negate:
            hi = min(t + k, e)
            bad = self.everywhere(t, hi)
            if bad is None:
                return None
            return (t, hi), bad, f"R fails at {bad} in [{t}, {hi}]"
        if e < t + k or self.somewhere(t, t + k):
            return None
        return (t, t + k), t + k, f"!R never holds in [{t}, {t + k}] (only* scope)"

    def _after(self, kind: str, t: int, e: int):
        k = self.k
        if not self.negate:
            hi = min(t + k, e)
            early = self.nR[t]
            if early <= hi:
                return (t, hi), early, f"R holds at {early}, before t+k+1={t + k + 1}"
            if e >= t + k + 1 and not self.R[t + k + 1]:
                return (t, t + k + 1), t + k + 1, f"R does not hold at t+k+1={t + k + 1}"
            return None
        # negated: violated iff e >= t+k+1, !R on [t, t+k] and R at t+k+1
        if e >= t + k + 1 and self.nR[t] == t + k + 1:
            return (t, t + k + 1), t + k + 1, (f"R first holds exactly at t+k+1={t + k + 1}"
                                                " (only* scope)")
        return None

    def _until_before(self, kind: str, t: int, e: int):
        nS = self.nS
        assert nS is not None
        rname = self.rname
        if (kind == "until") == self.want:
            # `want` everywhere from t up to (not incl.) the first S, capped at e
            hi = min(nS[t] - 1, e)
            if hi < t:
                return None
            bad = self.everywhere(t, hi)
            if bad is None:
                return None
            return (t, hi), bad, f"{rname} fails at {bad} before the stop condition"
        # no S in [t, j], j = first point >= t where `want` holds, capped at e
        j = min((self.nR if self.want else self.nNR)[t], e)
        s = nS[t]
        if s > j:
            return None
        return (t, j), s, (f"the stop condition holds at {s} before {rname} held "
                           f"(window [{t}, {j}])")


_CHECKS = {"immediately": ObligationChecker._immediately, "next": ObligationChecker._next,
           "finally": ObligationChecker._finally, "eventually": ObligationChecker._eventually,
           "always": ObligationChecker._always_never, "never": ObligationChecker._always_never,
           "within": ObligationChecker._within, "for": ObligationChecker._for,
           "after": ObligationChecker._after, "until": ObligationChecker._until_before,
           "before": ObligationChecker._until_before}
