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

Where the parts of a requirement are unknown is :mod:`fretc.monitors.unknowns`'s.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from fretc.fretish import ast as A
from fretc.monitors.interval import Evidence, Violation, scope_of, trigger_points
from fretc.monitors.unknowns import Unknowns

__all__ = ["definite_evidence"]


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
                and u.missed_known(w.trigger_tick, w.window[0], w.violation_tick,
                                   req.timing.kind, negate)):
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
