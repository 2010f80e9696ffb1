"""The obligations of FRET's timings (``../shared/fretish/README.md`` section 4): from a
trigger ``t`` until its scope interval's end ``e``, e.g. ``within k``: ``R`` somewhere in
``[t, t+k]``, vacuous when ``e < t+k``; ``only*`` scopes check the negated obligation
(:data:`OBLIGATIONS`). The fate of each trigger is decided by
:mod:`fretc.monitors.interval_fates` (FRET's interval semantics,
:class:`fretc.monitors.interval.IntervalStream`); :class:`FirstEvents` answers the other
questions asked of one trigger in O(1) from next-true indexes over a trace."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

__all__ = ["OBLIGATIONS", "FirstEvents", "OneTrigger", "OpenObligation", "Interval",
           "open_reason"]

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


class FirstEvents:
    """The first tick at or after each tick where the response holds (:attr:`nR`), does not
    hold (:attr:`nNR`) and the stop condition holds (:attr:`nS`), over a whole trace: the
    questions asked of one trigger's obligation beside its fate (whether it is still open
    at a damage, :func:`fretc.audit.damage.open_reason`; the tick that met it, for a
    trial). The fates themselves are :mod:`fretc.monitors.interval_fates`'.

    Args:
        R, S: the response and stop condition at each tick (bool arrays; S None without one).
    """

    def __init__(self, R: np.ndarray, S: np.ndarray | None):
        # numpy arrays (not lists): a few bytes a tick, for long logs
        self.R = _Bools(R)
        self._S = S

    # (each next-true index, 4 bytes a tick, is made when a question first reads it)
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


@dataclass(frozen=True)
class OpenObligation:
    """A trigger whose obligation the end of the ticks read leaves undecided (a damage
    there: :func:`fretc.audit.damage.verdict_at_damage`).

    Attributes:
        trigger_tick: the trigger point ``t`` (0-based tick).
        interval: the scope interval ``(s, e)`` holding it; ``e`` is the last tick read.
        what: the obligation still open, in tick numbers (:func:`open_reason`'s words).
    """

    trigger_tick: int
    interval: Interval
    what: str


class OneTrigger:
    """What :func:`open_reason` asks of one trigger, from a stream that kept it waiting
    (:meth:`fretc.monitors.interval.IntervalStream.open_at_end`): ``first`` the first tick
    at or after it where its timing's event held (the one event a waiting trigger's rule
    reads), past the last tick where none did; every question gets that answer."""

    def __init__(self, t: int, first: int) -> None:
        self._t, self._first = t, first

    def __getitem__(self, i: int) -> int:
        assert i == self._t  # (asked of its trigger only)
        return self._first

    @property
    def nR(self) -> OneTrigger:
        """The answer for R."""
        return self

    @property
    def nNR(self) -> OneTrigger:
        """The answer for !R."""
        return self

    @property
    def nS(self) -> OneTrigger:
        """The answer for the stop condition."""
        return self


def open_reason(timing: str, negate: bool, t: int, e: int, k: int,
                chk: FirstEvents | OneTrigger) -> str | None:
    """Why the obligation of the trigger ``t`` is still open at ``e``, the last tick read
    (its interval reaching it), or None when the ticks up to ``e`` meet or miss it: the rule
    of :func:`fretc.audit.damage.open_obligations` for one trigger (``chk`` over those
    ticks, or :class:`OneTrigger`; ``k`` the duration in ticks or 0, ``negate`` an only*
    scope)."""
    want = not negate
    nWant, nUnwant = (chk.nR, chk.nNR) if want else (chk.nNR, chk.nR)
    kind = "eventually" if timing == "null" else timing
    return _open(kind, negate, want, t, e, k, chk, nWant, nUnwant)


def _open(kind: str, negate: bool, want: bool, t: int, e: int, k: int,
          chk: FirstEvents | OneTrigger, nWant, nUnwant) -> str | None:
    """Why the obligation of trigger ``t`` is open at the end ``e`` of the intact span, or
    None when it is met or missed already (FRET's obligations, :data:`OBLIGATIONS`)."""
    rname = "R" if want else "!R"
    if kind == "immediately":
        return None
    if kind == "next":
        return f"{rname} at t+1={t + 1}, past the damage" if t == e else None
    if kind == "finally":
        return f"{rname} at the end of the scope interval, which the damage hides"
    if kind == "eventually":
        if not negate and nWant[t] > e:
            return f"R has not held since the trigger t={t}"
        return None
    if kind in ("always", "never"):
        if negate:  # "!name somewhere in [t, e]" not found yet
            bad = (chk.nNR if kind == "always" else chk.nR)[t]
            return f"the only* obligation of t={t} is not met yet" if bad > e else None
        return None  # an invariant that held so far holds over the intact span
    if kind == "within":
        if e >= t + k:
            return None
        if not negate:
            return f"R not yet held in [{t}, {t + k}], whose end lies past the damage" \
                if nWant[t] > e else None
        return (f"!R must hold on [{t}, {t + k}], whose end lies past the damage"
                if nUnwant[t] > e else None)
    if kind == "for":
        if e >= t + k:
            return None
        if not negate:
            return (f"R must hold on [{t}, {t + k}], whose end lies past the damage"
                    if nUnwant[t] > e else None)
        return (f"!R not yet held in [{t}, {t + k}], whose end lies past the damage"
                if chk.nNR[t] > e else None)
    if kind == "after":
        if e >= t + k + 1:
            return None
        if chk.nR[t] <= e:  # R already held early: met (negated) or missed (plain)
            return None
        return f"R at t+k+1={t + k + 1}, past the damage"
    if kind in ("until", "before"):
        nS = chk.nS
        assert nS is not None  # (until and before have a stop condition)
        if (kind == "until") == want:
            if nS[t] > e and nUnwant[t] > e:
                return f"{rname} held from t={t} but the stop condition has not come yet"
            return None
        if nWant[t] > e and nS[t] > e:
            return f"neither {rname} nor the stop condition has held since t={t}"
        return None
    return None
