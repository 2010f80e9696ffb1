"""The triggers of a probability requirement on one log as trials (FRET 3.1 reads ``with
probability OP p`` per trigger: :mod:`fretc.compiler.pctl`): each trigger of FRET's interval
semantics (:mod:`fretc.monitors.interval`) whose obligation the log decides is one trial,
satisfied or violated; the others are counted apart, never as trials of either outcome.

Design notes: ARCHITECTURE.md, `audit/trials.py`."""

from __future__ import annotations

from typing import TYPE_CHECKING
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

from fretc.fretish import ast as A
from fretc.monitors.interval import Violation, every_trigger
from fretc.monitors.unknowns import Unknowns, possible_trigger
from fretc.monitors.obligations import FirstEvents, open_reason


if TYPE_CHECKING:
    import numpy as np

__all__ = ["Trials", "trigger_trials", "trigger_outcomes", "TIMED_WINDOWS"]

#: the timings whose window from a trigger can reach past the end of a run
TIMED_WINDOWS = ("within", "for", "after", "next")


@dataclass
class Trials:
    """One requirement's triggers on one log (module docstring): ``satisfied``,
    ``violated`` (the trials), ``cut`` and ``unknown`` (no trials), and ``hidden`` (a
    trigger may have fired in unknown ticks)."""

    satisfied: int = 0
    violated: int = 0
    cut: int = 0
    unknown: int = 0
    hidden: bool = False

    @property
    def trials(self) -> int:
        """``satisfied + violated``."""
        return self.satisfied + self.violated

    def to_json(self) -> dict:
        """The audit JSON's ``trials`` object of a verdict (docs/reference/audit-json.md)."""
        return {"satisfied": self.satisfied, "violated": self.violated, "cut": self.cut,
                "unknown": self.unknown, "hidden": self.hidden}


def trigger_trials(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int, duration_ticks: int | None,
                   unknowns: Unknowns | None = None, damaged: bool = False) -> Trials:
    """The :class:`Trials` of ``req`` on a trace of ``n`` ticks (>= 1; module docstring):
    the outcomes of :func:`trigger_outcomes` counted; arguments and errors as there."""
    out = Trials(hidden=bool(unknowns is not None and possible_trigger(unknowns)))
    for _t, kind in trigger_outcomes(req, columns, n, duration_ticks, unknowns, damaged):
        setattr(out, kind, getattr(out, kind) + 1)
    return out


def trigger_outcomes(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
                     duration_ticks: int | None, unknowns: Unknowns | None = None,
                     damaged: bool = False) -> Iterator[tuple[int, str]]:
    """Each trigger of ``req`` on a trace of ``n`` ticks (>= 1) with its outcome, in tick
    order: ``(t, kind)``, ``kind`` one of ``satisfied``, ``violated``, ``cut``, ``unknown``
    (module docstring).

    Args:
        req: a parsed, not free-form requirement.
        columns: FRET variable -> 1-D array of ``n`` values (as sampled; unknown ticks hold
            any value).
        duration_ticks: the timing's duration in ticks (``Formalization.ticks``).
        unknowns: where its parts are unknown (None: every tick known).
        damaged: the trace ends where a damaged log stops being read, not where the run
            ended.

    Raises:
        fretc.monitors.interval.EvidenceUnsupported: an uninterpreted function.
        KeyError: a variable missing from ``columns``.
    """
    scope, cond, timing = req.scope.kind, req.condition.kind, req.timing.kind
    negate = scope.startswith("only")
    k = int(duration_ticks or 0) if timing in A.DURATION_TIMINGS else 0
    got = every_trigger(req, columns, n, k)
    chk = FirstEvents(got.R, got.S)
    for (s, e), points in zip(got.intervals, got.triggers):
        known_scope = unknowns is None or unknowns.scope_known(s, e, scope)
        for t in points:
            if not known_scope or (unknowns is not None
                                   and not unknowns.trigger_known(t, s, cond)):
                yield t, "unknown"
            else:
                yield t, _outcome(timing, negate, t, (s, e), k, chk, got.failed.get(t),
                                  unknowns, damaged, n)


def _outcome(timing: str, negate: bool, t: int, interval: tuple[int, int], k: int,
             chk: FirstEvents, bad: Violation | None, u: Unknowns | None, damaged: bool,
             n: int) -> str:
    """``satisfied``, ``violated``, ``cut`` or ``unknown`` for the known trigger ``t``
    (``bad``: its failed obligation, None when met)."""
    s, e = interval
    if e == n - 1 and open_reason(timing, negate, t, e, k, chk) is not None:
        if damaged:
            return "unknown"
        if timing in TIMED_WINDOWS:
            return "cut"
    if bad is not None:
        if u is None or u.missed_known(t, bad.window[0], bad.violation_tick, timing, negate):
            return "violated"
        return "unknown"
    return "satisfied" if _met_known(timing, negate, t, e, k, chk, u) else "unknown"


#: (timing, only* scope) whose obligation one tick meets: the one the checker looks for
#: holds somewhere in the window (True: the response, False: its negation)
_SOMEWHERE = {("eventually", False): True, ("null", False): True, ("within", False): True,
              ("never", True): True, ("always", True): False, ("for", True): False}


def _met_known(timing: str, negate: bool, t: int, e: int, k: int, chk: FirstEvents,
               u: Unknowns | None) -> bool:
    """A met obligation is met whatever the unknown ticks held: for the obligations one
    tick meets, that tick is known (or none was needed: the interval ended first); for the
    others the response and stop condition are known on the whole window."""
    if u is None:
        return True
    target = _SOMEWHERE.get((timing, negate))
    if target is not None:
        hi = min(t + k, e) if timing in ("within", "for") else e
        j = (chk.nR if target else chk.nNR)[t]
        if j <= hi and timing in ("within", "for") and u.stretched(t, j):
            return False  # (a gap between: the tick may lie past the duration)
        return j > hi or not u.R[j]
    hi = {"immediately": t, "next": min(t + 1, e), "within": min(t + k, e),
          "for": min(t + k, e), "after": min(t + k + 1, e)}.get(timing, e)
    return u.obligation_known(t, hi)
